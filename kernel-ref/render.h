/*
 * render.h: the reference packet tracer (kernel-ref): a whole frame, tile
 * by tile, on host threads with dynamic load balancing.
 *
 * Each 8x8 tile is one primary packet; its secondary packets are traced
 * depth first on the same host thread, and every ray adds into pixels of
 * its own tile, so tiles never share frame-buffer words. Combined with the
 * fixed-point frame buffer this makes the image bit-identical for any
 * thread count.
 */
#ifndef SAAR_KREF_RENDER_H
#define SAAR_KREF_RENDER_H

#include "kernel-ref/camera.h"
#include "kernel-ref/framebuf.h"
#include "kernel-ref/memimage.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/shade.h"
#include "kernel-ref/view.h"

/* Another tracer for the frame's rays, in place of the image's own kd-tree
 * (the two-level trees of twolevel.h): its hits name triangles of the
 * image render_frame is given, which the shader reads as usual. Full
 * precision only (render_opts.prec is not passed on). */
typedef struct render_tracer {
	const void *ctx;
	ray_hit (*ray)(const void *ctx, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c);
	uint64_t (*packet)(const void *ctx, packet *p, trav_entry *stack, int stack_max,
	                   trav_counts *c);
	/* non-NULL: the image's records are in object space and hits carry
	 * their instance; the shader moves them with these (shade_ctx.tl) */
	const shade_tl *shade;
} render_tracer;

typedef struct render_opts {
	int width, height;
	int threads;    /* host threads, >= 1 */
	int max_depth;  /* reflection/refraction depth */
	int shadows;    /* 0: primary rays only (no shadow packets) */
	int single_ray; /* trace with the scalar single-ray path instead of packets */
	vec3 background;
	/* Reduced precision per stage (NULL: full precision, the reference).
	 * Must outlive render_frame. */
	const pkt_precision *prec;
	const render_tracer *tracer; /* NULL: the image's kd-tree */
	/* cull leaf triangles outside each packet's enclosing cone (cone.h,
	 * seed 004); the image is the same, the work less */
	int cone_cull;
	/* trace coherent packets of the image's kd-tree by the packet interval
	 * walk (frustum.h; rtref's default): the same image, kernel-ref's own
	 * work counts. 0 (render_opts_default): the per-lane traversal the chip
	 * steps through, whose counts the chip's must equal. */
	int frustum;
} render_opts;

typedef struct render_stats {
	uint64_t rays[PKT_NTYPES], packets[PKT_NTYPES];
	uint64_t box_miss_packets; /* packets whose rays all missed the scene box: no traversal */
	uint64_t box_miss_rays;
	trav_counts trav;
	/* trav split by the type of the packet that made the counts (seed 000
	 * §3 groups packets by ray type); max_sp stays 0 here */
	trav_counts trav_type[PKT_NTYPES];
	shade_counts shade;
	double trace_ms;  /* host time inside traversal + intersection, summed over threads */
	double render_ms; /* wall time of the whole frame (rays, tracing, shading) */
} render_stats;

void render_opts_default(render_opts *o);

/* Renders v's camera into fb (already sized to width x height). */
int render_frame(const mimg *m, const view *v, const render_opts *o, framebuf *fb, render_stats *st,
                 diag *d);

const char *pkt_type_name(int type);

#endif
