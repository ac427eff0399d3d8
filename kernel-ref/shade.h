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
 * All scene data is read from the memory image; with a non-NULL log every
 * read (address, bytes, region) is recorded so the chip model can send it
 * through its shading cache.
 */
#ifndef SAAR_KREF_SHADE_H
#define SAAR_KREF_SHADE_H

#include "fpfmt.h"
#include "framebuf.h"
#include "memimage.h"
#include "packet.h"
#include "view.h"

#define SHADE_AMBIENT 0.15f

typedef struct shade_ctx {
	const mimg *m;
	const light *lights;
	int nlights;
	int max_depth; /* reflection/refraction generations after the primary hit */
	vec3 background;
	framebuf *fb;
} shade_ctx;

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
 * record, a material, and per texture a header and 3 texels. */
#define SHADE_LOG_CAP (PKT_RAYS * (3 + 2 * 4))

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

/* Finishes a traced shadow packet: unoccluded rays add their contribution. */
void shade_shadow_done(const shade_ctx *c, const packet *p, shade_counts *cnt);

#endif
