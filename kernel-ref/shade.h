/*
 * shade.h: the fixed SaarCOR shader and secondary-ray generation (the RGS's
 * second job), shared by kernel-ref and the chip model.
 *
 * Extended Phong: ambient (SHADE_AMBIENT * Ka * texture) + per visible
 * point light (Kd * texture * N.L + Ks * (R.V)^Ns), with an optional image
 * texture (map_Kd) and bump map; hard shadows; mirror reflection and
 * refraction up to max_depth. A hit splits its weight w into local
 * w * (1 - reflect - transmit), reflected w * reflect and refracted
 * w * transmit (total internal reflection sends the refracted share to the
 * mirror direction).
 *
 * Secondary rays are self-contained (pixel, weight): a shadow ray carries
 * the contribution it adds when it reaches its light unoccluded; reflection
 * and refraction rays carry their weight. They are grouped in packets per
 * parent packet and per type: one shadow packet per light, one reflection
 * and one refraction packet, each made only when it has a ray. What is
 * skipped is counted (shade_counts).
 *
 * Scene data is read through a reader (shade_reader): kernel-ref's reads
 * the memory image (and with a non-NULL log records every read: address,
 * bytes, region); the chip model's hands out the bytes its memory system
 * returns for those addresses (units/rgs.c). Either way the shader decodes
 * only what the reader gives it, in the same order.
 */
#ifndef SAAR_KREF_SHADE_H
#define SAAR_KREF_SHADE_H

#include "kernel-ref/drt.h"
#include "kernel-ref/fpfmt.h"
#include "kernel-ref/framebuf.h"
#include "kernel-ref/memimage.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/view.h"

#define SHADE_AMBIENT 0.15f

/* Frame-buffer adds kept instead of made (shade_ctx.defer): at most one
 * per ray of a packet (its background or ambient term). */
typedef struct shade_add {
	uint32_t pixel;
	float r, g, b;
} shade_add;
typedef struct shade_adds {
	uint32_t n;
	shade_add e[PKT_RAYS];
} shade_adds;

/* Two-level scenes (twolevel.h, docs/design.md "The chip on two-level
 * scenes"): the image's triangle and shading records are in each
 * instance's object space, and every hit carries its instance (packet.inst).
 * The shader reads the instance's shading transform, SHADE_XF_BYTES at
 * base + inst * stride: the forward matrix (object -> world, 12 doubles,
 * row-major 3x4) and the normal matrix (its inverse transpose, 9 doubles,
 * xform.h), in SHADE_XF_READS reads after the material; it moves
 * the triangle's corners and shading normals into the world with them.
 * bytes (kernel-ref's reader only) holds the records from base on, size
 * bytes; the chip's reader reads them from its memory. */
#define SHADE_XF_BYTES 168u
#define SHADE_XF_READS 4
enum shade_fault {
	SHADE_FAULT_NONE,
	SHADE_FAULT_NO_NORMAL_XF,
	SHADE_FAULT_LEAN_NO_TEXTURE,
	SHADE_FAULT_LEAN_NO_CLAMP,
	SHADE_FAULT_LEAN_MEMO_TEXTURED,
	SHADE_FAULT_LEAN_ONE_WEIGHT
};
extern int shade_fault; /* shade.c: planted mistakes, tests only */
typedef struct shade_tl {
	uint64_t base;   /* the first instance's shading transform */
	uint32_t stride; /* bytes from one instance's to the next */
	const uint8_t *bytes;
	uint64_t size;
} shade_tl;

typedef struct shade_ctx {
	const mimg *m; /* the region bases (the bytes come from the reader) */
	const light *lights;
	int nlights;
	int max_depth; /* reflection/refraction generations after the primary hit */
	vec3 background;
	framebuf *fb;
	/* non-NULL: shade_packet* keeps its frame-buffer adds here (emptied
	 * first) instead of making them; shade_adds_apply makes them */
	shade_adds *defer;
	/* distribution effects (drt.h): area-light points and glossy
	 * reflection from the packet's sample; NULL: point lights, mirrors */
	const drt_shade *drt;
	/* two-level scenes: the instances' shading transforms; NULL: a single
	 * tree, records in world space */
	const shade_tl *tl;
} shade_ctx;

/* Where the shader's scene data comes from: read(ctx, addr, bytes, region)
 * returns the `bytes` (at most 64) bytes at addr, valid until the next
 * call; region is the enum mimg_region the address lies in. */
typedef struct shade_reader {
	const void *(*read)(void *ctx, uint64_t addr, uint32_t bytes, int region);
	void *ctx;
} shade_reader;

typedef struct shade_read {
	uint64_t addr;
	uint32_t bytes;
	uint32_t region; /* enum mimg_region */
} shade_read;

typedef struct shade_log {
	shade_read *e;
	uint32_t n, cap;
	uint32_t dropped; /* reads beyond cap (never with SHADE_LOG_CAP) */
} shade_log;

/* Upper bound of reads for one packet: per ray a triangle record, a shading
 * record, a material, per texture a header and 3 texels, and on a
 * two-level scene its instance's shading transform. */
#define SHADE_LOG_CAP (PKT_RAYS * (3 + SHADE_XF_READS + 2 * 4))

typedef struct shade_counts {
	uint64_t hits, misses;     /* rays shaded */
	uint64_t shadow_rays_made; /* shadow rays put into packets */
	uint64_t
	    shadow_skip_nolight; /* hits that would have cast shadow rays had there been lights */
	uint64_t shadow_skip_facing; /* light behind the surface: no ray needed */
	uint64_t secondary_skip;  /* shaded packets that spawned no reflection/refraction packet */
	uint64_t depth_cut;       /* reflect/refract rays not made: max_depth reached */
	uint64_t texel_reads;     /* texels read (map_Kd and bump) */
	uint64_t untextured_hits; /* hits on untextured materials: no texel reads */
	uint64_t shadow_hits, shadow_lit; /* shadow rays occluded / reaching the light */
} shade_counts;

/* Shades a traced primary/reflection/refraction packet: adds misses'
 * background and each hit's ambient term to the frame buffer, and writes
 * the child packets into out[0..max_out) (max_out >= nlights + 2).
 * Returns how many it made. */
int shade_packet(const shade_ctx *c, const packet *p, packet *out, int max_out, shade_log *log,
                 shade_counts *cnt);

/* The same at reduced shading precision fp (NULL or the identity format:
 * exactly shade_packet). Rounds the colour terms, the shading normal, the
 * weights and the secondary directions to fp; never the spawn point (its
 * robust offset needs the float error bound), so it changes the image, not
 * correctness. */
int shade_packet_fp(const shade_ctx *c, const fpfmt *fp, const packet *p, packet *out, int max_out,
                    shade_log *log, shade_counts *cnt);

/* The same with the scene's bytes from reader rd (the memory image's
 * reader is what shade_packet_fp passes). The reads, in order, per hit:
 * triangle record, shading record, material, on a two-level scene the
 * instance's shading transform (shade_tl); per texture lookup its header
 * and texel (map_Kd once, bump map three times). */
int shade_packet_rd(const shade_ctx *c, const fpfmt *fp, const shade_reader *rd, const packet *p,
                    packet *out, int max_out, shade_counts *cnt);

/* Makes the frame-buffer adds d kept. */
void shade_adds_apply(const shade_adds *d, framebuf *fb);

/* Finishes a traced shadow packet: unoccluded rays add their contribution. */
void shade_shadow_done(const shade_ctx *c, const packet *p, shade_counts *cnt);

#endif
