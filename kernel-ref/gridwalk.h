/*
 * gridwalk.h: the grid's packet traversal (grid_pkt_trace, gridtrav.c)
 * step by step, for the chip's grid traversal unit (units/gridtrav.c), as
 * pkt_trav_node / pkt_trav_pop are the kd-tree's (packet.h).
 *
 * The walk makes exactly grid_pkt_trace's decisions and counts, but it
 * never reads the grid's arrays or the image's bytes: each time it needs
 * data it stops and says what (grid_walk_next fills a grid_ask), and the
 * caller reads it (from memory, on the chip) and hands it back by the
 * answer named for the ask:
 *
 *   GW_FLAG: the macrocell flag of block `index` (one byte): grid_walk_flag
 *   GW_CELL: cell `index`'s list range (its two list offsets): grid_walk_cell
 *   GW_LIST: `count` list entries from entry `first`: grid_walk_list
 *   GW_TRI:  the triangle record at `addr`: grid_walk_tri
 *   GW_DONE: the packet is traced (its lanes hold the hits)
 *
 * Rays a frustum cannot hold (origins apart, a sign or slope apart, seed
 * 003 §4.7) go alone by the 3D DDA in the same walk: the asks are the
 * same (`dda` says which), the test is the single ray's.
 * grid_walk_trace answers from a built grid on the host: the check that
 * the walk is grid_pkt_trace (tests/test_gridwalk.c).
 */
#ifndef SAAR_KREF_GRIDWALK_H
#define SAAR_KREF_GRIDWALK_H

#include "kernel-ref/gridtrav.h"
#include "kernel-ref/isect.h"

enum grid_walk_op { GW_DONE, GW_FLAG, GW_CELL, GW_LIST, GW_TRI };

typedef struct grid_ask {
	int op;
	int dda;               /* 1: for a ray traced alone (the DDA) */
	uint32_t index;        /* GW_FLAG: macrocell; GW_CELL: cell */
	uint32_t first, count; /* GW_LIST: the cell's entries (list index) */
	uint32_t addr;         /* GW_TRI: triangle record address */
	uint64_t mask;         /* the rays the step works for */
} grid_ask;

typedef struct grid_walk {
	const grid *g; /* its header only: n, lo, scale, eps, p, mn, m's box and ntris */
	trav_state *s;
	packet *p;
	grid_counts c;
	int phase, after; /* where the walk is; where a cell's list returns to */
	int bad;          /* the answers were impossible (damaged memory) */
	uint64_t entered, alone, fmask, live;
	int side, nsub, q;
	/* the frustum and its slices */
	grid_frustum f;
	int ks, kl, m;
	int kb, kbe, mul, muh, mvl, mvh, mu, mv; /* a macrocell slice's flags */
	int ul, uh, vl, vh, u, v;                /* a slice's cells */
	/* the current cell's list */
	const uint32_t *list;
	uint32_t n, k, ta, lfirst;
	/* a ray alone (the DDA) */
	int dda, ray, any_hit; /* dda: the walk is at a ray alone */
	isect_ray ir;
	vec3 o;
	float tmax, tf;
	ray_hit h;
	int cell[3], step[3];
	double tnext[3], tdelta[3], eps_t;
	grid_mbox mb;
} grid_walk;

/* Starts the walk of packet p after pkt_trav_begin (s, which returned
 * entered). g needs only its header (the chip's has no arrays). */
void grid_walk_begin(grid_walk *w, const grid *g, trav_state *s, packet *p, uint64_t entered);
/* The next thing the walk needs (a->op), or GW_DONE. */
int grid_walk_next(grid_walk *w, grid_ask *a);
void grid_walk_flag(grid_walk *w, uint8_t flag);
void grid_walk_cell(grid_walk *w, uint32_t first, uint32_t end);
/* entries must stay valid until the cell's triangles are done (the next
 * GW_CELL or GW_FLAG or GW_DONE). */
void grid_walk_list(grid_walk *w, const uint32_t *entries);
/* The triangle is tested (or culled, §2.3); returns the rays tested, 0
 * when culled: the size of the intersection op. */
int grid_walk_tri(grid_walk *w, const mimg_tri *tri);

/* The walk answered from g's arrays and image: grid_pkt_trace's result
 * and counts. */
uint64_t grid_walk_trace(const grid *g, packet *p, trav_entry *stack, int stack_max,
                         grid_counts *c);

#endif
