/*
 * tlflat.h: the reference for two-level trees: ONE kd-tree over the scene
 * flattened at the frame's time (world space, rebuilt per frame), whose
 * leaves test each triangle in its object's space, as the two-level trees
 * do.
 *
 * Why: a two-level tree (twolevel.h) tests triangles in object space, a
 * tree over the flattened scene in world space. The two are the same
 * surface but not the same floating-point test, so their images differ at
 * a few edge pixels (11 of 19,200 on Robots at t = 0) and cannot be
 * compared exactly. This tracer keeps what the two-level trees replace (a
 * single tree over every triangle where they sit at the time) and takes
 * from them only the triangle test: the ray moved into the triangle's
 * object by tl_ray_to_object, then kernel-ref's scalar test against the
 * object's own vertices. Its hits must then equal the two-level trees'
 * exactly, pixel for pixel (tests/test_twolevel.c); a wrong top level, a
 * wrong instance box, a bottom-level tree that loses a triangle or an
 * instance visited out of turn all show.
 *
 * It walks the flat tree with kernel-ref's single-ray walk
 * (ray_trace_leaves), which accepts a hit in any leaf and skips only
 * subtrees that start beyond the best hit, so a triangle's world copy
 * being rounded differently from its object-space test cannot lose it.
 * Hits name the triangle in the two-level shading image and the instance
 * record, as the two-level trees' hits do, so the shading is theirs.
 */
#ifndef SAAR_KREF_TLFLAT_H
#define SAAR_KREF_TLFLAT_H

#include "kernel-ref/twolevel.h"

typedef struct tl_flat {
	const tl_scene *t;
	const mimg *flat; /* the tree over the flattened scene (world_load without --two-level) */
	uint32_t *rec;    /* per flattened triangle: its instance's record (BVH leaf order) */
	uint32_t *local;  /* per flattened triangle: its address in its object's image */
	render_tracer tracer;
} tl_flat;

/* For the frame t is placed at (tl_frame) and flat, the image of the scene
 * flattened at the same time (aff_flatten order, the order of t's shading
 * image). Call again after each tl_frame: the records move. */
int tl_flat_init(tl_flat *f, const tl_scene *t, const mimg *flat, diag *d);
void tl_flat_free(tl_flat *f);

/* Closest hit (any_hit: the first occluder) in (0, tmax), by the single
 * tree's rule; tri is the hit's address in t's shading image. */
ray_hit tl_flat_ray(const tl_flat *f, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c);

#endif
