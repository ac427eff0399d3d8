/*
 * gridtrav.h: the pieces of the grid's packet traversal (gridtrav.c) that
 * its step-by-step form (gridwalk.c, the chip's grid unit) shares, so
 * both make the same decisions by the same code. Internal to the grid:
 * only gridtrav.c and gridwalk.c include it.
 */
#ifndef SAAR_KREF_GRIDTRAV_H
#define SAAR_KREF_GRIDTRAV_H

#include "kernel-ref/grid.h"

#define GRID_GAMMA3    (3.0f * 0x1p-24f / (1.0f - 3.0f * 0x1p-24f))
#define GRID_T_WIDEN   1e-5 /* relative slack on a hit's t when deciding to stop */
#define GRID_MAX_SLOPE 1e4  /* a ray steeper than this to the slices goes alone (DDA) */
#define GRID_MBOX_BITS 10

/* The per-packet mailbox (§2.3): the triangle addresses a packet has
 * tested, in a small open-addressed set. A full set stops recording (the
 * repeated tests are then merely redundant). */
typedef struct grid_mbox {
	uint32_t slot[1u << GRID_MBOX_BITS];
	uint32_t used;
} grid_mbox;

/* One frustum's rays in the slice frame: k along the major axis (flipped
 * so it grows along the rays), u and v across; a ray is at
 * u = au + (k - kref) su, v = av + (k - kref) sv, and at k = ok + t dk.
 * kref is the smallest origin's k: every ray point has k >= kref, where
 * min(a + (k - kref) s) >= min a + (k - kref) min s (the frustum's lower
 * planes; the upper likewise). For primary rays (one origin) the planes
 * pass through the eye: the exact frustum. */
typedef struct grid_frustum {
	int ax[3]; /* grid axes of k, u, v */
	int flip;  /* k runs against the grid axis */
	double ok[PKT_RAYS], dk[PKT_RAYS], kin[PKT_RAYS], kout[PKT_RAYS];
	double amin[2], amax[2], smin[2], smax[2];
	double k0, k1; /* first and last slice coordinate of any ray */
	double kref;
} grid_frustum;

int grid_mbox_seen(grid_mbox *b, uint32_t addr);
/* 1 when g mailboxes and addr was already tested for this ray or packet
 * (counted into *skips, optional): the triangle is skipped. Every walk of
 * a cell's list asks this before a test. */
int grid_mbox_skip(const grid *g, grid_mbox *b, uint32_t addr, uint64_t *skips);
/* The ray clipped to the scene box, exactly as ray_trace clips it. */
int grid_clip_box(const grid *g, vec3 o, vec3 d, float tmax, float *tn, float *tf);
int grid_clampi(double x, int n);
/* Sets up f for the rays in mask; returns the rays it cannot hold. */
uint64_t grid_frustum_setup(const grid *g, const packet *p, const trav_state *s, uint64_t mask,
                            grid_frustum *f);
/* The cells [lo, hi] across axis j the frustum overlaps between slice
 * coordinates ka and kb, divided by div; 0 when none is in the grid. */
int grid_frustum_span(const grid *g, const grid_frustum *f, int j, double ka, double kb, int div,
                      int *lo, int *hi);
uint32_t grid_slice_cell(const grid *g, const grid_frustum *f, int ks, int u, int v);
/* Frustum culling (§2.3): 1 when no ray of f can hit t. */
int grid_frustum_culls(const grid *g, const grid_frustum *f, const mimg_tri *t);
/* The rays of live still unfinished after the slice ending at kend. */
uint64_t grid_still_live(const grid *g, const grid_frustum *f, const packet *p, uint64_t live,
                         double kend);
/* 1 when the rays of mask start within one cell of each other. */
int grid_one_origin(const grid *g, const packet *p, uint64_t mask);
/* The lanes of sub-packet q of side `side`. */
uint64_t grid_sub_lanes(int side, int q);

#endif
