/*
 * memimage.h: the flat host memory image the chip reads (docs/memory-map.md).
 *
 * One byte array holding every piece of scene data at a documented address,
 * in regions: kd-nodes (8 B), triangle-address lists (4 B entries holding
 * the byte address of a triangle record), triangle records (36 B: three
 * vertices of 3 floats), shading records (64 B: three normals, three
 * texcoords, material id), materials (64 B), texture headers and texels
 * (RGBA8). The reference tracer reads the scene only through this image and
 * the chip model's memory system serves exactly these addresses, so every
 * read has an address here. All multi-byte values are little-endian host
 * floats and integers; every region starts on a 128-byte boundary (the VMA
 * line size) so regions never share a cache line.
 */
#ifndef SAAR_KREF_MEMIMAGE_H
#define SAAR_KREF_MEMIMAGE_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/kdtree.h"
#include "kernel-ref/scene.h"

enum mimg_region {
	MIMG_HEADER,
	MIMG_NODES,
	MIMG_LISTS,
	MIMG_TRIS,
	MIMG_SHADE,
	MIMG_MATS,
	MIMG_TEXHDR,
	MIMG_TEXELS,
	MIMG_NREGIONS
};

#define MIMG_NODE_BYTES   8u
#define MIMG_LIST_BYTES   4u
#define MIMG_TRI_BYTES    36u
#define MIMG_SHADE_BYTES  64u
#define MIMG_MAT_BYTES    64u
#define MIMG_TEXHDR_BYTES 16u
#define MIMG_ALIGN        128u

/* x rounded up to a multiple of a (> 0): the regions' and the appended
 * images' bases (memimage.c, tlimage.c, gridimage.c, twolevel.c). */
static inline uint64_t mimg_align_up(uint64_t x, uint64_t a)
{
	return (x + a - 1) / a * a;
}
/* The triangle region starts on a multiple of this, the least common
 * multiple of MIMG_ALIGN and MIMG_TRI_BYTES: the triangle cache's 36-byte
 * lines are numbered address / 36, so only a region starting on a multiple
 * of 36 puts each record in one line (from a 128-byte boundary alone every
 * record straddled two, and each triangle fetch cost two L1 lines). 1152
 * is also a multiple of 72, 144 and 288, and of every power of two up to
 * 128, the other line sizes a config may give the triangle cache. */
#define MIMG_TRI_ALIGN 1152u

/* Triangle record (36 bytes). */
typedef struct mimg_tri {
	float v[3][3];
} mimg_tri;

/* Shading record (64 bytes), one per triangle, same index. */
typedef struct mimg_shade {
	float n[3][3];  /* corner normals */
	float uv[3][2]; /* corner texcoords */
	uint32_t mat;   /* material index */
} mimg_shade;

/* Material record (64 bytes). Emission (MTL Ke) is not stored: the fixed
 * SaarCOR shader has no emissive term. */
typedef struct mimg_mat {
	float kd[3], ks[3], ka[3];
	float ns, ni, transmit, reflect;
	int16_t tex_kd, tex_bump; /* texture header index, or -1 */
	float bump_scale;
	uint32_t pad;
} mimg_mat;

/* Texture header (16 bytes). */
typedef struct mimg_texhdr {
	uint32_t w, h;
	uint32_t texel_addr; /* byte address of texel (0,0), row-major RGBA8 */
	uint32_t reserved;
} mimg_texhdr;

typedef struct mimg {
	uint8_t *bytes;
	uint64_t size;
	uint64_t base[MIMG_NREGIONS];
	uint64_t len[MIMG_NREGIONS];
	uint32_t nnodes, nlist, ntris, nmats, ntexs;
	aabb bounds; /* scene box (the kd-tree root's region) */
} mimg;

int mimg_build(mimg *m, const scene *s, const kdtree *t, diag *d);
void mimg_free(mimg *m);
const char *mimg_region_name(int region);

static inline uint64_t mimg_node_addr(const mimg *m, uint32_t i)
{
	return m->base[MIMG_NODES] + (uint64_t)MIMG_NODE_BYTES * i;
}
static inline uint64_t mimg_list_addr(const mimg *m, uint32_t k)
{
	return m->base[MIMG_LISTS] + (uint64_t)MIMG_LIST_BYTES * k;
}
static inline uint64_t mimg_tri_addr(const mimg *m, uint32_t tri)
{
	return m->base[MIMG_TRIS] + (uint64_t)MIMG_TRI_BYTES * tri;
}
static inline uint64_t mimg_shade_addr(const mimg *m, uint32_t tri)
{
	return m->base[MIMG_SHADE] + (uint64_t)MIMG_SHADE_BYTES * tri;
}
static inline uint64_t mimg_mat_addr(const mimg *m, uint32_t mat)
{
	return m->base[MIMG_MATS] + (uint64_t)MIMG_MAT_BYTES * mat;
}
static inline uint32_t mimg_tri_index(const mimg *m, uint32_t tri_addr)
{
	return (uint32_t)((tri_addr - m->base[MIMG_TRIS]) / MIMG_TRI_BYTES);
}
static inline const kd_node *mimg_nodes(const mimg *m)
{
	return (const kd_node *)(m->bytes + m->base[MIMG_NODES]);
}
static inline const uint32_t *mimg_lists(const mimg *m)
{
	return (const uint32_t *)(m->bytes + m->base[MIMG_LISTS]);
}
static inline const mimg_shade *mimg_shade_at(const mimg *m, uint32_t tri)
{
	return (const mimg_shade *)(m->bytes + mimg_shade_addr(m, tri));
}
static inline const mimg_mat *mimg_mat_at(const mimg *m, uint32_t mat)
{
	return (const mimg_mat *)(m->bytes + mimg_mat_addr(m, mat));
}
static inline const mimg_texhdr *mimg_texhdr_at(const mimg *m, uint32_t tex)
{
	return (const mimg_texhdr *)(m->bytes + m->base[MIMG_TEXHDR] +
	                             (uint64_t)MIMG_TEXHDR_BYTES * tex);
}
static inline const mimg_tri *mimg_tri_at(const mimg *m, uint32_t tri_addr)
{
	return (const mimg_tri *)(m->bytes + tri_addr);
}

#endif
