/*
 * spd.h: procedural benchmark scenes after Eric Haines' Standard Procedural
 * Databases (IEEE CG&A 1987; the SPD package): balls (sphereflake), tetra
 * (Sierpinski tetrahedron), mount (fractal mountain with glass spheres),
 * rings (rings of tori), plus the Cornell box and a billiard table (after
 * the benchmark of seed 000, Boulos et al.). Written by us from the
 * published descriptions, tessellated into triangles, each with its
 * standard view and lights (docs/spd.md gives the formulas and counts).
 *
 * Selected as --scene spd:NAME[:SIZE[:TESS]]: SIZE is the recursion level
 * (the SPD "size factor"), TESS the segments around each tessellated sphere
 * or torus. Every generator is deterministic (its own fixed-seed LCG) and
 * every closed object is an edge-manifold mesh with exactly shared
 * vertices, so rays cannot leak between its triangles.
 */
#ifndef SAAR_KREF_SPD_H
#define SAAR_KREF_SPD_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/scene.h"
#include "kernel-ref/view.h"

#define SPD_PREFIX "spd:"

#include <string.h>

/* Does path name a procedural scene ("spd:...") rather than a file? */
static inline int spd_is(const char *path)
{
	return path && strncmp(path, SPD_PREFIX, strlen(SPD_PREFIX)) == 0;
}

/* Builds the scene named by spec ("spd:balls:3", "spd:tetra:6:..."), and its
 * standard view into v (may be NULL). -1 with diag on an unknown name or a
 * size out of range. */
int spd_generate(scene *s, view *v, const char *spec, diag *d);

/* Triangle count the generator will produce, or 0 for a bad spec (lets
 * users dial a size before generating, and lets tests check the formula). */
uint64_t spd_triangles(const char *spec);

/* A closed UV sphere (nu segments around, nu/2 rings; 2 nu (nu/2 - 1)
 * triangles) with smooth normals, for generators and stress tests. */
void spd_add_sphere(scene *s, vec3 c, float r, int nu, uint32_t mat);

#endif
