/*
 * cone.h: an enclosing cone of a packet's rays and the test that culls a
 * triangle for the whole packet (seed 004, Szécsi, "The Hierarchical Ray
 * Engine", §4: "enclosing infinite cones of rays are described by an
 * origin, a direction and an opening angle"; a primitive whose enclosing
 * sphere the cone misses is skipped by every ray of the tile).
 *
 * Construction. Seed 004 §4 grows the cone ray by ray (widen the angle,
 * then slide the apex back along a generator). Here, a simpler
 * conservative cone of the same kind: the axis is the mean of the rays'
 * unit directions, the half angle the largest angle between it and a
 * ray's direction, and the apex sits on the axis behind the origins'
 * centroid so far that the ball holding every origin lies inside the cone
 * (distance R / sin(phi)). A cone is a convex set closed under adding its
 * directions, so each ray, origin inside and direction within phi of the
 * axis, stays inside for every t >= 0. A packet whose directions spread
 * beyond CONE_MAX_PHI gets no cone (`all`): it culls nothing.
 *
 * Test. A sphere (centre v, radius r) seen from the apex at distance d
 * spans the angles theta +- asin(r / d) from the axis; the cone holds the
 * angles up to phi, so the sphere lies outside exactly when theta - asin(r
 * / d) > phi. Everything is done in double with a margin (CONE_MARGIN
 * radians), so a triangle culled is one no ray of the packet can hit, with
 * float rays and the watertight test alike: culling never changes the
 * image (tests/test_drt.c), only the work.
 *
 * kd nodes. SaarCOR's packet traversal (traverse.c) enters a node only
 * when some active ray's segment crosses it, and such a ray lies in the
 * cone, so the cone would cull no node the traversal visits: only
 * triangles are tested (a leaf's triangles are only known to lie in the
 * leaf, not to meet a ray).
 */
#ifndef SAAR_KERNEL_REF_CONE_H
#define SAAR_KERNEL_REF_CONE_H

#include <stdint.h>

#include "kernel-ref/memimage.h"
#include "kernel-ref/packet.h"

#define CONE_MAX_PHI 1.2  /* radians (about 69 degrees): wider cones cull nothing */
#define CONE_MARGIN  1e-4 /* radians added to the cone's half angle in the test */

typedef struct pkt_cone {
	double a[3], x[3]; /* apex, unit axis */
	double phi;        /* half opening angle, radians */
	int all;           /* no useful cone: every triangle is tested */
} pkt_cone;

/* The enclosing cone of p's rays in mask. */
void cone_build(pkt_cone *c, const packet *p, uint64_t mask);
/* 1 when no ray inside c can meet triangle t (its bounding sphere lies
 * outside the cone): the packet skips its test. */
int cone_culls_tri(const pkt_cone *c, const mimg_tri *t);

/* pkt_trace_fp (packet.h) with cull set: the packet's cone is built from
 * the rays that enter the scene box, and each leaf triangle it culls is
 * skipped (counted in c's cone_* fields). cull 0: pkt_trace_fp. */
uint64_t pkt_trace_cone(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                        const pkt_precision *prec, int cull);

#endif
