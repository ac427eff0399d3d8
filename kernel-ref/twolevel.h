/*
 * twolevel.h: two-level acceleration for scenes of rigid objects (seed 002
 * §6, dynamic scenes: a top-level tree over object instances, rebuilt each
 * frame, over bottom-level trees built once; Wald, Benthin, Slusallek,
 * "Distributed Interactive Ray Tracing of Dynamic Scenes", 2003).
 *
 * The instances of an AFF scene (aff.h) are its transform nodes: the
 * meshes directly under one node move together, so each node with meshes
 * is one rigid instance. Instances whose triangles are the same in their
 * own frames (a part file included ten times: Robots' 220 robot parts are
 * 22 distinct objects) share one object. tl_build gives every object a
 * kd-tree and memory image of its triangles, once. tl_frame places the
 * instances at a time: each its world matrix's inverse and its world box,
 * and a small BVH over the boxes (median splits), per frame.
 *
 * Tracing (tl_ray_trace, tl_pkt_trace) walks the BVH; at an instance the
 * rays are moved into object space (origin and direction by the inverse
 * matrix, the direction not normalised, so t is the world t) and traced in
 * the object's tree with kernel-ref's own traversal and triangle test (the
 * single-ray path or the packet path). Hits carry the triangle's address in
 * the shading image (aff_flatten_local: the scene's triangles in aff_flatten's
 * order, each in its instance's object space, the same at every time) and
 * the instance (its record's index in leaf order); the shader moves the
 * triangle's corners and normals into the world by the instance's forward
 * and normal matrices (shade.h, shade_tl). The hit rule is the single tree's (smallest
 * t, then smallest world triangle address), and an instance is traced with
 * the best t so far as its bound, so the result does not depend on the
 * order instances are visited in: the packet and single-ray paths agree
 * exactly. Against one tree over the flattened scene they agree up to the
 * rounding of the object-space test, and exactly when that tree tests in
 * object space too (tlflat.h; docs/design.md, "Two-level trees").
 */
#ifndef SAAR_KREF_TWOLEVEL_H
#define SAAR_KREF_TWOLEVEL_H

#include "kernel-ref/aff.h"
#include "kernel-ref/kdtree.h"
#include "kernel-ref/memimage.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/render.h"

/* The objects' images begin this aligned after the frame's image (tlimage.c
 * lays them out; the shading records' base, twolevel.c, must agree). */
#define TL_ALIGN 4096u

typedef struct tl_object {
	kdtree kd;
	mimg m; /* the object's triangles in its own frame */
	uint32_t ntris;
} tl_object;

typedef struct tl_inst {
	uint32_t obj;
	int32_t xform;  /* its AFF transform node (-1: the root) */
	uint32_t first; /* its triangles' indices in the flattened scene: gtri[first..] */
	double inv[12]; /* world -> object, row-major 3x4 */
	double fwd[12]; /* object -> world (the node's world matrix) */
	double nrm[9];  /* fwd's normal matrix (xform.h): the inverse transpose */
	aabb box;       /* world box, widened */
} tl_inst;

typedef struct tl_node {
	aabb box;
	uint32_t first, count; /* leaf: instances order[first..first+count); inner: count 0 */
	uint32_t left;         /* inner: children left, left + 1 */
} tl_node;

typedef struct tl_scene {
	tl_object *obj;
	uint32_t nobj;
	tl_inst *inst; /* placed per frame */
	uint32_t ninst;
	uint32_t *gtri; /* per instance, in order: the flattened scene's triangle indices */
	uint32_t *order;
	tl_node *node;
	uint32_t nnode;
	const mimg *world; /* the shading image: hit addresses name its triangles */
	/* per instance record (BVH leaf order, packet.inst): its shading
	 * transform, SHADE_XF_BYTES (fwd, then nrm); kernel-ref's shader
	 * reads them through shade (shade.h) */
	uint8_t *xf;
	shade_tl shade;
	double build_ms;      /* bottom level (tl_build) */
	double frame_ms;      /* last top level (tl_frame) */
	render_tracer tracer; /* hands tl_ray_trace / tl_pkt_trace to render_frame */
} tl_scene;

/* The bottom level: the instances of a, and one kd-tree (parameters kp)
 * per distinct object. */
int tl_build(tl_scene *t, const aff_scene *a, const kd_params *kp, diag *d);

/* The top level at time `time`: instances, their BVH and shading
 * transforms. world is the shading image (aff_flatten_local, mimg_build). */
int tl_frame(tl_scene *t, const aff_scene *a, double time, const mimg *world, diag *d);
void tl_free(tl_scene *t);

/* Closest hit (or with any_hit the first occluder) in (0, tmax). */
ray_hit tl_ray_trace(const tl_scene *t, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c);

/* A packet through the instances; returns the rays that entered the
 * scene's box. stack: as pkt_trace's. */
uint64_t tl_pkt_trace(const tl_scene *t, packet *p, trav_entry *stack, int stack_max,
                      trav_counts *c);

/* The ray (o, dir) in object space by inv (world -> object), in double,
 * rounded to float: every path that tests a triangle in its object's
 * space moves rays by this (tlflat.c too, so their tests agree bit for
 * bit). */
void tl_ray_to_object(const double inv[12], const float o[3], const float dir[3], vec3 *oo,
                      vec3 *od);

/* The pieces of tl_pkt_trace the chip's units call (units/toplevel.c),
 * so both make the same functional calls. The rays of mask whose box test
 * against b with their own bound passes: */
uint64_t tl_pkt_box(const aabb *b, const packet *p, uint64_t mask);
/* q = p with the rays of mask moved into object space by inv (world ->
 * object), q->valid = mask, each ray's bound its best t so far. */
void tl_pkt_to_object(const double inv[12], const packet *p, uint64_t mask, packet *q);
/* Takes q's hits (rays of mask) back into p by the single tree's rule; g[i]
 * names lane i's hit triangle in the world image, inst the instance
 * record (packet.inst). */
void tl_pkt_merge(packet *p, const packet *q, uint64_t mask, const uint32_t *g, uint32_t inst);

#endif
