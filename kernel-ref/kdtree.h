/*
 * kdtree.h: SAH kd-tree over a scene, built in O(n log n) with a sorted
 * event sweep (Wald & Havran 2006, "On building fast kd-trees for ray
 * tracing, and on doing that in O(N log N)").
 *
 * The node is the 8-byte SaarCOR/pbrt node that the chip reads from memory:
 *
 *   word a (32 bits)                    word b (32 bits)
 *   inner: split position (float bits)  [31..2] index of the left child | [1..0] axis 0,1,2
 *   leaf:  first list entry index       [31..2] triangle count          | [1..0] 3
 *
 * The right child of an inner node is always left + 1 (children stored as
 * a pair), so one index serves both. Points exactly on a split plane belong
 * to both children: a triangle lying in the plane is put on both sides
 * ("flat cells"), so traversal may send a ray to either.
 *
 * Invariant: every triangle that overlaps a leaf's region (its clipped
 * bounding box intersects the region with positive or zero extent) is in
 * that leaf's list. The node array starts with the root at index 0.
 */
#ifndef SAAR_KREF_KDTREE_H
#define SAAR_KREF_KDTREE_H

#include <stdint.h>
#include <string.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/scene.h"

typedef struct kd_params {
	float cost_trav;   /* SAH cost of one traversal step (K_T) */
	float cost_isect;  /* SAH cost of one triangle test (K_I) */
	int max_depth;     /* hard depth limit; 0 = 8 + 1.3 log2(n) */
	int leaf_size;     /* stop splitting at or below this many triangles */
	float empty_bonus; /* in [0,1): SAH discount for cutting off empty space */
	float footprint;   /* packet footprint, a fraction of the scene box's
	                    * diagonal: the SAH grows every box by it on each side
	                    * (kdtree.c, "Packet footprint"); 0 = the plain SAH */
	/* a view's packet instead (fp_angle > 0): the growth per side is
	 * fp_angle / 2 times the distance from fp_eye to the scene box's
	 * centre, half the width there of a packet fp_angle wide (radians)
	 * seen from fp_eye; footprint is not used then */
	float fp_angle;
	float fp_eye[3];
} kd_params;

typedef struct kd_node {
	uint32_t a, b;
} kd_node;

typedef struct kdtree {
	kd_node *nodes;
	uint32_t nnodes;
	uint32_t *list; /* triangle indices of all leaves, leaf after leaf */
	uint32_t nlist;
	aabb bounds; /* the scene box the root stands for */
	/* build statistics */
	uint32_t nleaves, nempty_leaves;
	/* leaves made because the build's work budget ran out
	 * (KD_WORK_BUDGET: heavily overlapping triangles); 0 on real scenes */
	uint32_t nbudget_leaves;
	uint64_t work;   /* triangle references the splits spent (KD_WORK_BUDGET) */
	int depth;       /* deepest leaf */
	double sah_cost; /* expected cost of the whole tree */
	double fp_grow;  /* the packet footprint's growth per side, scene units */
	float fp_angle;  /* kd_params.fp_angle it was built with (0: none) */
	double build_ms; /* host wall time of kd_build */
} kdtree;

/* The build's work budget, per triangle: a split of a node into children
 * of cl and cr triangles spends cl + cr (its events are partitioned, and
 * the children's lists and sweeps cost that again). SAH keeps splitting
 * where many triangles overlap (a few thousand coplanar ones covering each
 * other: each split copies most of them to both sides, and the sweep still
 * finds a slightly cheaper split), so the work and the lists grow
 * exponentially with depth: a thousand such triangles took 11 s and 26
 * million list entries (100 MB), four thousand minutes and gigabytes.
 * Once a split would overdraw the budget it is not made and the node
 * becomes a leaf (counted in kdtree.nbudget_leaves), and so do the nodes
 * after it: the build stays linear in the triangles, deterministic, and
 * the tree correct (poorer where it was cut). Real scenes spend well
 * under a tenth of it (kdtree.work; tests/test_kdtree.c checks the shared
 * scenes it builds), so their trees are the same with and without it. A
 * per-subtree budget (split in proportion to the children's counts) was
 * tried first and changed real trees even at 8192 per triangle, where a
 * dense patch of a scene duplicates many triangles over a few levels. */
#define KD_WORK_BUDGET 1024.0

/* The ranges the kd parameters take from the command line (--kd-*) and
 * from configs (kdtree.*): one definition for both. */
#define KD_COST_MIN      0.001
#define KD_COST_MAX      1000.0
#define KD_DEPTH_MAX     64 /* the traversal stack's PKT_STACK_MAX */
#define KD_LEAF_MIN      1
#define KD_LEAF_MAX      1024
#define KD_BONUS_MAX     0.99
#define KD_FOOTPRINT_MAX 0.1

/* rtref's own footprint where it has no view to take it from (the chip's
 * tree, kdtree.footprint, keeps 0): measured against 0, 0.0005, 0.0015
 * and 0.002 on the shared views in docs/PERFORMANCE.md ("Target 1:
 * session 46"); the one that makes no view slower. With a view known
 * before the scene loads rtref takes its packet's footprint instead
 * (world_opts.fp_packet, kernel-ref.md). */
#define KD_RTREF_FOOTPRINT 0.001f
#define KD_FP_ANGLE_MAX    1.0 /* radians: a packet of a 180-degree view */

void kd_params_default(kd_params *p);

/* The depth limit a build of ntris triangles uses: max_depth, or with 0
 * (automatic) 8 + 1.3 log2(ntris), at most 60. */
int kd_depth_limit(int max_depth, uint32_t ntris);

/* Builds the tree. Fails (diag, -1) only on bad parameters or out of
 * memory; any valid scene builds. */
int kd_build(kdtree *t, const scene *s, const kd_params *p, diag *d);
void kd_free(kdtree *t);

static inline int kd_is_leaf(kd_node n)
{
	return (n.b & 3u) == 3u;
}
static inline int kd_axis(kd_node n)
{
	return (int)(n.b & 3u);
}
static inline uint32_t kd_left(kd_node n)
{
	return n.b >> 2;
}
static inline uint32_t kd_count(kd_node n)
{
	return n.b >> 2;
}
static inline uint32_t kd_first(kd_node n)
{
	return n.a;
}
static inline float kd_split(kd_node n)
{
	float f;
	memcpy(&f, &n.a, sizeof f);
	return f;
}
static inline kd_node kd_make_inner(int axis, float split, uint32_t left)
{
	kd_node n;
	memcpy(&n.a, &split, sizeof split);
	n.b = (left << 2) | (uint32_t)axis;
	return n;
}
static inline kd_node kd_make_leaf(uint32_t first, uint32_t count)
{
	return (kd_node){first, (count << 2) | 3u};
}

#endif
