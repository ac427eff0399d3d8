/*
 * grid.h: a uniform grid over the frame's triangles, rebuilt every frame,
 * and its coherent traversal (seed 003: Wald, Ize, Kensler, Knoll, Parker,
 * "Ray Tracing Animated Scenes using Coherent Grid Traversal", SIGGRAPH
 * 2006).
 *
 * Build (grid.c, §3): N_a = d_a (lambda N / V)^(1/3) cells along each axis
 * of the scene box (d its diagonal, V its volume, N the triangles, lambda
 * = 5 by default), each triangle referenced in every cell its bounding box
 * overlaps (widened by grid.eps cells, see below), in one counting pass and
 * one filling pass into flat arrays; plus a macrocell layer (§2.4): one
 * flag per block of M x M x M cells, set when any of them is occupied.
 * The cell lists hold triangle record addresses of the memory image the
 * grid was built from, as the kd-tree's leaf lists do.
 *
 * Traversal (gridtrav.c): packets slice by slice through their bounding
 * frustum (§2.2-2.3) with per-packet mailboxing, skipping empty macrocell
 * slices (§2.4); single rays by a 3D DDA (Amanatides and Woo). Both use
 * kernel-ref's triangle test and hit rule (isect.h), and a ray stops only
 * once its best hit lies before the far boundary of everything visited
 * (by more than the error margin), so it has tested every triangle that
 * could beat or tie that hit: the result is the kd path's exactly
 * (docs/design.md, "Uniform grid").
 */
#ifndef SAAR_KREF_GRID_H
#define SAAR_KREF_GRID_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/jsonw.h"
#include "kernel-ref/memimage.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/render.h"

#define GRID_MAX_RES  1024       /* cells along one axis */
#define GRID_MAX_REFS (1u << 27) /* triangle references (512 MB): coarser beyond */

typedef struct grid_params {
	double lambda; /* cells per triangle (§3); default 5 */
	int macro;     /* macrocell side M in cells (§2.4; default 6); 0: none */
	int packet;    /* packet side traced as one frustum: 8 (default), 4, or 1 (3D DDA) */
	int mailbox;   /* 1 (default): a packet tests a triangle once */
	int cull;      /* 1 (default): frustum culling of triangles (§2.3) */
} grid_params;

void grid_params_default(grid_params *p);

/* What one traversal did (Table 4 of seed 003 counts cells and tests). */
typedef struct grid_counts {
	uint64_t slices;        /* slice steps of a frustum (DDA: cell steps) */
	uint64_t macro_skips;   /* macrocell slices skipped as empty */
	uint64_t cells;         /* cells visited (overlapped by a frustum, or by a ray) */
	uint64_t tri_tests;     /* triangle tests (one per packet and triangle) */
	uint64_t ray_tri_tests; /* ray-triangle tests */
	uint64_t mailbox_skips; /* triangle tests saved by the mailbox */
	uint64_t culled;        /* triangles culled outside a frustum (§2.3) */
	uint64_t dda_rays;      /* packet rays traced alone (sign or slope apart from the packet) */
} grid_counts;

typedef struct grid {
	grid_params p;
	const mimg *m;   /* the image whose triangles the lists name */
	int n[3];        /* cells per axis */
	double lo[3];    /* grid box corner */
	double scale[3]; /* cells per world unit */
	double eps;      /* error margin, in cells */
	uint32_t *first; /* cell c's references: refs[first[c] .. first[c + 1]) */
	uint32_t *refs;  /* triangle record addresses */
	uint32_t nrefs;
	int mn[3];       /* macrocells per axis */
	uint8_t *macro;  /* 1: some cell of the block holds a triangle */
	double build_ms; /* the last grid_build */
	render_tracer tracer;
} grid;

/* Builds g over m's triangles (g keeps m: it must outlive g). Rebuilding
 * an existing grid reuses nothing (call grid_free first). */
int grid_build(grid *g, const mimg *m, const grid_params *p, diag *d);
void grid_free(grid *g);

static inline uint32_t grid_cell(const grid *g, int x, int y, int z)
{
	return ((uint32_t)z * (uint32_t)g->n[1] + (uint32_t)y) * (uint32_t)g->n[0] + (uint32_t)x;
}

/* Closest hit (any_hit: an occluder) in (0, tmax) by a 3D DDA. */
ray_hit grid_ray_trace(const grid *g, vec3 o, vec3 d, float tmax, int any_hit, grid_counts *c);

/* A packet: frusta of p.packet x p.packet rays slice by slice (or each ray
 * by the DDA for p.packet 1). Returns the rays that entered the scene box. */
uint64_t grid_pkt_trace(const grid *g, packet *p, trav_entry *stack, int stack_max, grid_counts *c);

/* Mistakes made on purpose, so tests can show their checks catch them
 * (as pkt_trav_fault; only tests set it, in their own process):
 *   GRID_FAULT_EARLY_STOP: a ray stops at the first slice or cell where it
 *     has a hit, even when the hit lies beyond the far boundary (a nearer
 *     triangle in the next cell is missed: a wrong image).
 *   GRID_FAULT_NARROW_FRUSTUM: a slice's cells are taken from the frustum
 *     at the slice's entry plane only (rays leave it inside the slice). */
enum grid_fault_kind { GRID_FAULT_NONE, GRID_FAULT_EARLY_STOP, GRID_FAULT_NARROW_FRUSTUM };
extern int grid_fault;

/* grid_counts as render_frame's trav_counts: node_steps = slices,
 * leaf_visits = cells, tri_tests, ray_tri_tests. */
void grid_counts_add(trav_counts *t, const grid_counts *c);

/* The grid's fields as both reports give them (rtref's stats, saarsim's
 * report; the caller opens and closes the object): resolution, lambda,
 * macro, packet, mailbox, cull, references. */
void grid_json_fields(jsonw *j, const grid *g);

#endif
