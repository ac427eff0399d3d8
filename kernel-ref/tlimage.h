/*
 * tlimage.h: the chip's memory image of a two-level scene (twolevel.h;
 * docs/memory-map.md, "Two-level scenes").
 *
 * The shading image (memimage.h; the scene flattened in its instances' own
 * frames, aff_flatten_local) comes first: the shader reads its triangle
 * and shading records, materials and textures at the same addresses as
 * for a single tree, and moves a hit's records into the world by its
 * instance record's shading transform (shade.h, shade_tl). After it, on
 * 4 KB boundaries:
 *
 *  - every object's image (its kd-nodes, lists and triangle records, as
 *    mimg_build laid them out) moved to its offset, the list entries
 *    (triangle addresses) moved with it; built once with the objects;
 *  - the triangle map: per instance, in instance order, the world image's
 *    triangle address of each of its object's triangles (4 bytes each):
 *    where a hit in object space is named for the shader;
 *  - the top level (written per frame, the host's update): the BVH's nodes
 *    (TLI_NODE_BYTES each) then the instance records (TLI_INST_BYTES each)
 *    in the BVH's leaf order, so a leaf's instances are consecutive (a
 *    hit's packet.inst is its record's index). The walk reads a record's
 *    first TLI_INST_WALK_BYTES; the shader its forward and normal
 *    matrices after them.
 *
 * Records are little-endian as the host is; tli_node / tli_inst are their
 * decoded forms, tli_*_decode the units' decoders of the bytes a read
 * returned.
 */
#ifndef SAAR_KREF_TLIMAGE_H
#define SAAR_KREF_TLIMAGE_H

#include <stdint.h>

#include "kernel-ref/twolevel.h"

#define TLI_NODE_BYTES 32u /* box (6 floats), left or first (4), count (4; 0: inner) */
/* an instance record: the walk's part (inverse: 12 doubles, world box,
 * object box, 4 bases), then the shader's (forward and normal matrices) */
#define TLI_INST_WALK_BYTES 160u
#define TLI_INST_BYTES      (TLI_INST_WALK_BYTES + SHADE_XF_BYTES)
#define TLI_ALIGN           TL_ALIGN

typedef struct tli_node {
	aabb box;
	uint32_t first; /* leaf: first instance record; inner: left child (right = left + 1) */
	uint32_t count; /* leaf: instance records; 0: inner */
} tli_node;

typedef struct tli_inst {
	double inv[12]; /* world -> object, row-major 3x4 */
	aabb box;       /* world box */
	mimg regs;      /* the object's region bases and box (no bytes) */
	uint64_t map;   /* its first triangle map entry */
} tli_inst;

typedef struct tl_image {
	uint8_t *bytes;
	uint64_t size;
	uint64_t *obj_base; /* per object: where its image starts */
	uint64_t map_base;  /* the triangle map */
	uint64_t top_base;  /* the top level: nodes, then instance records */
	uint64_t top_bytes; /* the top level's size: the per-frame update */
	uint64_t inst_base; /* the instance records */
	uint32_t max_nodes; /* the largest object's kd-nodes */
	shade_tl shade;     /* the shader's view of the records (shade_ctx.tl) */
} tl_image;

/* The image of t's frame (tl_frame) over the frame's flattened image
 * world: everything, the top level included. -1 (diag) when out of memory. */
int tli_build(tl_image *im, const tl_scene *t, const mimg *world, diag *d);
/* Rewrites the top level for t's current frame (the host's update);
 * returns its bytes. */
uint64_t tli_write_top(tl_image *im, const tl_scene *t);
void tli_free(tl_image *im);
/* The size tli_build's image would have (nothing allocated). */
uint64_t tli_size(const tl_scene *t, const mimg *world);

void tli_node_decode(const uint8_t *b, tli_node *n);
void tli_inst_decode(const uint8_t *b, tli_inst *in);

#endif
