/*
 * stress.h: the numerical stress cases (issue 7): each builds a hard scene
 * in code, traces it with kernel-ref and counts what must stay zero.
 *
 *   leaked      rays that pass through a closed surface
 *   acne        shadow rays from the lit side of a lone convex mesh that are
 *               occluded (only their own surface could occlude them)
 *   disagree    hits that differ from a double-precision reference by more
 *               than a true tie (a hit within rounding of an edge)
 *   mismatch    packet path != single-ray path, or results that change
 *               with the thread count
 *
 * The fast variants run in `make test` (tests/test_stress.c); `make stress`
 * runs larger ones and writes docs/NUMERICS.md (kernel-ref/stress_main.c).
 */
#ifndef SAAR_KREF_STRESS_H
#define SAAR_KREF_STRESS_H

#include <stdint.h>

#include "kernel-ref/packet.h"

/* which counts a case measures (the table shows the others as "-") */
enum { ST_LEAK = 1, ST_ACNE = 2, ST_DISAGREE = 4, ST_MISMATCH = 8 };

typedef struct stress_result {
	char name[96];
	uint64_t rays;
	uint64_t leaked, acne, disagree, ties, mismatch;
	double ms;
	unsigned measured; /* ST_* bits */
} stress_result;

/* A closed sphere of radius `scale` centred at (offset, offset/2, -offset/3),
 * seen from inside and from outside at res x res; rays continued past every
 * hit must hit again. */
stress_result stress_sphere(double scale, double offset, int res);

/* The same with traversal and intersection in reduced formats (prec NULL:
 * full precision, exactly stress_sphere). Packet and single-ray paths run
 * the same formats, so mismatch must stay zero too. */
stress_result stress_sphere_fp(double scale, double offset, int res, const pkt_precision *prec);

/* The SPD tetra scene (closed tetrahedra, spd.h) scaled by `scale` and
 * moved by `offset`, seen from its standard view: every ray continued past
 * an entry must hit again. A ray is judged only when its continuation
 * origin (rounded to float) lies inside the tetrahedron it entered, checked
 * in double: far from the origin, rounding can move it outside. */
stress_result stress_spd_tetra(double scale, double offset, int res);

/* The same sphere, lit from outside with nothing else in the scene: every
 * occluded shadow ray is a self-intersection. */
stress_result stress_acne(double scale, double offset, int res);

/* Rays aimed exactly at the shared vertex of a fan and along the shared
 * edges of a strip (grid of unit squares); every ray must hit. */
stress_result stress_vertices_edges(int n);

/* A flat scene: n x n unit squares in the plane z = 0, rays straight down
 * with direction components exactly +0 and -0, from origins on grid lines
 * (that is, on kd split planes); every ray must hit. */
stress_result stress_flat_axis_parallel(int n);

/* Degenerate (zero area, collinear), sliver, duplicate and coplanar
 * overlapping triangles, a very deep tree and grazing rays: packet ==
 * single ray, and 1 == 2 == 5 threads, bit for bit. */
stress_result stress_degenerate(int res);

/* Random rays against random triangles compared with a double-precision
 * test: disagreements are counted apart when the double result lies within
 * rounding of an edge (ties). */
stress_result stress_random(uint64_t n, uint32_t seed);

#endif
