/*
 * test_kdtree.c: kd_build invariants (kdtree.h) on synthetic and shared
 * scenes.
 *
 * Structure: every node is reached exactly once, children come in pairs
 * (left odd, right = left + 1), splits lie strictly inside the node box,
 * leaf lists are concatenated in depth-first (left first) leaf order, and
 * the statistics match the tree. Coverage: a triangle must be in a leaf's
 * list when its exactly clipped part (double-precision Sutherland-Hodgman,
 * independent of the builder's) in the closed leaf box reaches the leaf's
 * interior, or lies flat in a face of the leaf (a planar triangle in a split
 * plane goes to both children). A triangle merely touching a leaf from
 * outside need not be listed (kdtree.c explains why).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/kdtree.h"
#include "tests/objmini.h"
#include "tests/testutil.h"

static uint32_t rng(uint64_t *st)
{
	*st = *st * 6364136223846793005ull + 1442695040888963407ull;
	return (uint32_t)(*st >> 33);
}

static float rnd(uint64_t *st)
{
	return (float)(rng(st) >> 7) * (1.0f / 16777216.0f); /* [0, 1) */
}

static void add_tri(scene *s, vec3 a, vec3 b, vec3 c)
{
	vec3 p[3] = {a, b, c};
	scene_add_triangle(s, p, NULL, NULL, 0);
}

static void finish(scene *s)
{
	diag d;
	cr_assert_eq(scene_finish(s, "test", &d), 0, "%s", d.msg);
}

static aabb tri_box(const vec3 *p)
{
	return aabb_grow(aabb_grow(aabb_grow(aabb_empty(), p[0]), p[1]), p[2]);
}

/* Bounds of triangle p clipped to the closed box b; 0 when empty. */
static int clip_tri(const vec3 *p, const aabb *b, double lo[3], double hi[3])
{
	double poly[12][3], out[12][3];
	int n = 3;
	for (int i = 0; i < 3; i++)
		for (int a = 0; a < 3; a++)
			poly[i][a] = v3_get(p[i], a);
	for (int a = 0; a < 3; a++) {
		for (int side = 0; side < 2; side++) {
			double bound = side ? v3_get(b->hi, a) : v3_get(b->lo, a);
			double sgn = side ? -1 : 1;
			int m = 0;
			for (int i = 0; i < n; i++) {
				const double *c = poly[i], *d = poly[(i + 1) % n];
				int ci = sgn * (c[a] - bound) >= 0, di = sgn * (d[a] - bound) >= 0;
				if (ci)
					memcpy(out[m++], c, sizeof out[0]);
				if (ci != di) {
					double t = (bound - c[a]) / (d[a] - c[a]);
					for (int j = 0; j < 3; j++) {
						double v = c[j] + t * (d[j] - c[j]);
						double l = c[j] < d[j] ? c[j] : d[j];
						double h = c[j] < d[j] ? d[j] : c[j];
						out[m][j] = v < l ? l : v > h ? h : v;
					}
					out[m++][a] = bound;
				}
			}
			n = m;
			if (n == 0)
				return 0;
			memcpy(poly, out, (size_t)n * sizeof poly[0]);
		}
	}
	for (int a = 0; a < 3; a++) {
		lo[a] = INFINITY;
		hi[a] = -INFINITY;
		for (int i = 0; i < n; i++) {
			lo[a] = fmin(lo[a], poly[i][a]);
			hi[a] = fmax(hi[a], poly[i][a]);
		}
	}
	return 1;
}

/* Must triangle p be listed in the leaf with box b? */
static int required(const vec3 *p, const aabb *b)
{
	aabb tb = tri_box(p);
	for (int a = 0; a < 3; a++)
		if (v3_get(tb.lo, a) > v3_get(b->hi, a) || v3_get(tb.hi, a) < v3_get(b->lo, a))
			return 0;
	double lo[3], hi[3];
	if (!clip_tri(p, b, lo, hi))
		return 0;
	/* Double rounding in the clip can leave a sliver of ~1e-17 where the
	 * exact part is a point or an edge on the leaf's face; the builder is
	 * exact-or-outward to a float ulp, so 1e-12 relative is still strict. */
	double scale = 0;
	for (int a = 0; a < 3; a++)
		scale = fmax(scale, fmax(fabs(v3_get(b->lo, a)), fabs(v3_get(b->hi, a))));
	for (int a = 0; a < 3; a++) {
		int piece_flat = hi[a] - lo[a] <= 1e-12 * scale;
		int tri_flat = v3_get(tb.lo, a) == v3_get(tb.hi, a);
		int leaf_flat = v3_get(b->lo, a) == v3_get(b->hi, a);
		if (piece_flat && !tri_flat && !leaf_flat)
			return 0; /* touches the leaf from outside */
	}
	return 1;
}

static int expected_max_depth(const kd_params *p, uint32_t ntris)
{
	if (p->max_depth)
		return p->max_depth;
	long md = lround(8.0 + 1.3 * log2((double)ntris));
	return md > 60 ? 60 : (int)md;
}

typedef struct leafinfo {
	aabb box;
	uint32_t first, count;
} leafinfo;

typedef struct item {
	uint32_t node;
	aabb box;
	int depth;
} item;

static int in_leaf(const kdtree *t, kd_node n, uint32_t tri)
{
	for (uint32_t k = 0; k < kd_count(n); k++)
		if (t->list[kd_first(n) + k] == tri)
			return 1;
	return 0;
}

static void split_box(const aabb *box, kd_node n, aabb *l, aabb *r)
{
	*l = *r = *box;
	float p = kd_split(n);
	int k = kd_axis(n);
	*(k == 0 ? &l->hi.x : k == 1 ? &l->hi.y : &l->hi.z) = p;
	*(k == 0 ? &r->lo.x : k == 1 ? &r->lo.y : &r->lo.z) = p;
}

/* Coverage by walking the tree per triangle (for big scenes). */
static void check_walk(const scene *s, const kdtree *t)
{
	item stack[130];
	for (uint32_t tri = 0; tri < s->ntris; tri++) {
		const vec3 *p = s->v + 3 * (size_t)tri;
		int sp = 0;
		stack[sp++] = (item){0, t->bounds, 0};
		while (sp > 0) {
			item it = stack[--sp];
			double lo[3], hi[3];
			if (!clip_tri(p, &it.box, lo, hi))
				continue;
			kd_node n = t->nodes[it.node];
			if (kd_is_leaf(n)) {
				if (required(p, &it.box))
					cr_assert(in_leaf(t, n, tri),
					          "triangle %u overlaps leaf %u but is not listed",
					          tri, it.node);
				continue;
			}
			aabb l, r;
			split_box(&it.box, n, &l, &r);
			stack[sp++] = (item){kd_left(n) + 1, r, it.depth + 1};
			stack[sp++] = (item){kd_left(n), l, it.depth + 1};
		}
	}
}

/* Structure, statistics and coverage; brute = every leaf x every triangle. */
static void check_tree(const scene *s, const kdtree *t, const kd_params *p, int brute)
{
	int maxd = expected_max_depth(p, s->ntris);
	cr_assert_gt(t->nnodes, 0);
	cr_assert_eq(t->nnodes % 2, 1, "root plus child pairs");
	cr_assert_eq(memcmp(&t->bounds, &s->bounds, sizeof t->bounds), 0);
	uint8_t *seen = calloc(t->nnodes, 1);
	uint32_t *stamp = calloc(s->ntris, sizeof *stamp);
	leafinfo *leaves = malloc(t->nnodes * sizeof *leaves);
	item stack[130];
	int sp = 0, deepest = 0;
	uint32_t nleaves = 0, nempty = 0, next_first = 0;
	stack[sp++] = (item){0, t->bounds, 0};
	while (sp > 0) {
		item it = stack[--sp];
		cr_assert_lt(it.node, t->nnodes);
		cr_assert(!seen[it.node], "node %u reached twice", it.node);
		seen[it.node] = 1;
		kd_node n = t->nodes[it.node];
		if (kd_is_leaf(n)) {
			uint32_t c = kd_count(n);
			cr_assert_eq(kd_first(n), next_first, "leaf lists out of leaf order");
			next_first += c;
			cr_assert_leq(next_first, t->nlist);
			for (uint32_t k = 0; k < c; k++) {
				uint32_t tri = t->list[kd_first(n) + k];
				cr_assert_lt(tri, s->ntris);
				cr_assert_neq(stamp[tri], nleaves + 1,
				              "triangle %u twice in a leaf", tri);
				stamp[tri] = nleaves + 1;
			}
			leaves[nleaves++] = (leafinfo){it.box, kd_first(n), c};
			nempty += c == 0;
			deepest = it.depth > deepest ? it.depth : deepest;
			continue;
		}
		int k = kd_axis(n);
		float x = kd_split(n);
		cr_assert(x > v3_get(it.box.lo, k) && x < v3_get(it.box.hi, k),
		          "split %g outside node %u box on axis %d", x, it.node, k);
		uint32_t left = kd_left(n);
		cr_assert_eq(left % 2, 1, "children are pairs after the root");
		cr_assert_lt(left + 1, t->nnodes);
		cr_assert_lt(it.depth + 1, 129);
		aabb l, r;
		split_box(&it.box, n, &l, &r);
		stack[sp++] = (item){left + 1, r, it.depth + 1};
		stack[sp++] = (item){left, l, it.depth + 1};
	}
	for (uint32_t i = 0; i < t->nnodes; i++)
		cr_assert(seen[i], "node %u unreachable", i);
	cr_assert_eq(next_first, t->nlist, "sum of leaf counts != nlist");
	cr_assert_eq(nleaves, t->nleaves);
	cr_assert_eq(nempty, t->nempty_leaves);
	cr_assert_eq(deepest, t->depth);
	cr_assert_leq(t->depth, maxd);
	cr_assert_eq(t->nnodes, 2 * t->nleaves - 1);
	cr_assert(isfinite(t->sah_cost) && t->sah_cost > 0);
	cr_assert_geq(t->build_ms, 0);
	if (brute) {
		for (uint32_t L = 0; L < nleaves; L++) {
			for (uint32_t k = 0; k < leaves[L].count; k++)
				stamp[t->list[leaves[L].first + k]] = ~L;
			for (uint32_t tri = 0; tri < s->ntris; tri++)
				if (required(s->v + 3 * (size_t)tri, &leaves[L].box))
					cr_assert_eq(
					    stamp[tri], ~L,
					    "triangle %u overlaps leaf %u but is not listed", tri,
					    L);
		}
	} else {
		check_walk(s, t);
	}
	free(seen);
	free(stamp);
	free(leaves);
}

/* Builds s with the default parameters (returned in p) into t. */
static void build_default(const scene *s, kd_params *p, kdtree *t)
{
	diag d;
	kd_params_default(p);
	cr_assert_eq(kd_build(t, s, p, &d), 0, "%s", d.msg);
}

static void build_check(const scene *s, const kd_params *p, int brute)
{
	kdtree t;
	diag d;
	cr_assert_eq(kd_build(&t, s, p, &d), 0, "%s", d.msg);
	check_tree(s, &t, p, brute);
	kd_free(&t);
}

static void random_soup(scene *s, uint32_t n, uint64_t seed)
{
	scene_init(s, "random");
	for (uint32_t i = 0; i < n; i++) {
		vec3 c = v3(rnd(&seed), rnd(&seed), rnd(&seed));
		float r = (i % 10 == 0) ? 0.3f : 0.03f;
		vec3 p[3];
		for (int k = 0; k < 3; k++)
			p[k] = v3_add(c, v3((rnd(&seed) - 0.5f) * r, (rnd(&seed) - 0.5f) * r,
			                    (rnd(&seed) - 0.5f) * r));
		add_tri(s, p[0], p[1], p[2]);
	}
	finish(s);
}

/* Two triangles per unit square of a g x g grid in plane `axis` = c. */
static void grid_plane(scene *s, int axis, float c, int g)
{
	for (int i = 0; i < g; i++)
		for (int j = 0; j < g; j++) {
			float q[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
			vec3 v[4];
			for (int k = 0; k < 4; k++)
				v[k] = axis == 0   ? v3(c, q[k][0], q[k][1])
				       : axis == 1 ? v3(q[k][0], c, q[k][1])
				                   : v3(q[k][0], q[k][1], c);
			add_tri(s, v[0], v[1], v[2]);
			add_tri(s, v[0], v[2], v[3]);
		}
}

Test(kdtree, params_default)
{
	kd_params p;
	kd_params_default(&p);
	cr_assert_float_eq(p.cost_trav, 1.0f, 1e-6);
	cr_assert_float_eq(p.cost_isect, 1.5f, 1e-6);
	cr_assert_eq(p.max_depth, 0);
	cr_assert_geq(p.leaf_size, 1);
	cr_assert(p.empty_bonus >= 0 && p.empty_bonus < 1);
}

Test(kdtree, bad_params_fail_with_diag)
{
	scene s;
	random_soup(&s, 10, 1);
	kd_params bad[10];
	for (int i = 0; i < 10; i++)
		kd_params_default(&bad[i]);
	bad[0].cost_isect = 0;
	bad[1].cost_trav = -1;
	bad[2].max_depth = 65;
	bad[3].leaf_size = -1;
	bad[4].empty_bonus = 1;
	bad[5].footprint = -0.001f;
	bad[6].footprint = (float)KD_FOOTPRINT_MAX * 1.5f;
	bad[7].footprint = NAN;
	bad[8].fp_angle = 2; /* wider than a half turn */
	bad[9].fp_angle = 0.01f;
	bad[9].fp_eye[1] = INFINITY;
	for (int i = 0; i < 10; i++) {
		kdtree t;
		diag d = {{0}};
		cr_assert_eq(kd_build(&t, &s, &bad[i], &d), -1, "case %d", i);
		cr_assert_neq(d.msg[0], 0);
		cr_assert_null(t.nodes);
		kd_free(&t);
	}
	scene_free(&s);
}

Test(kdtree, single_triangle)
{
	scene s;
	scene_init(&s, "one");
	add_tri(&s, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0.5f));
	finish(&s);
	kd_params p;
	kdtree t;
	build_default(&s, &p, &t);
	cr_assert_eq(t.nnodes, 1);
	cr_assert(kd_is_leaf(t.nodes[0]));
	cr_assert_eq(kd_count(t.nodes[0]), 1);
	cr_assert_eq(t.list[0], 0);
	kd_free(&t);
	p.leaf_size = 0;
	build_check(&s, &p, 1);
	scene_free(&s);
}

Test(kdtree, random_soup)
{
	scene s;
	random_soup(&s, 3000, 42);
	kd_params p;
	kd_params_default(&p);
	build_check(&s, &p, 1);
	p.leaf_size = 0;
	p.empty_bonus = 0;
	build_check(&s, &p, 1);
	p.max_depth = 5;
	build_check(&s, &p, 1);
	kd_params_default(&p);
	p.footprint = 0.01f; /* shallower tree, same coverage */
	build_check(&s, &p, 1);
	scene_free(&s);
}

/* Packet footprint (kdtree.c): n tiny triangles in a cube of side `side`
 * around c, added to s. */
static void cluster(scene *s, vec3 c, float side, int n, uint64_t seed)
{
	for (int i = 0; i < n; i++) {
		vec3 q = v3_add(c, v3((rnd(&seed) - 0.5f) * side, (rnd(&seed) - 0.5f) * side,
		                      (rnd(&seed) - 0.5f) * side));
		float e = 0.1f * side;
		add_tri(s, q, v3_add(q, v3(e, 0, 0)), v3_add(q, v3(0, e, 0.5f * e)));
	}
}

/* Over the leaves: how many list a triangle with id in [lo, hi) (return
 * value), and whether one lists ids of both [lo, hi) and [hi, hi2). */
static uint32_t leaves_listing(const kdtree *t, uint32_t lo, uint32_t hi, uint32_t hi2, int *mixed)
{
	uint32_t n = 0;
	*mixed = 0;
	for (uint32_t i = 0; i < t->nnodes; i++) {
		if (!kd_is_leaf(t->nodes[i]))
			continue;
		const uint32_t *l = t->list + kd_first(t->nodes[i]);
		uint32_t in = 0, other = 0;
		for (uint32_t k = 0; k < kd_count(t->nodes[i]); k++) {
			in += l[k] >= lo && l[k] < hi;
			other += l[k] >= hi && l[k] < hi2;
		}
		n += in > 0;
		*mixed |= in && other;
	}
	return n;
}

/* Two tiny marker triangles at opposite corners of the unit cube: the
 * scene's diagonal is about sqrt(3) whatever lies between. */
static void corners(scene *s)
{
	add_tri(s, v3(0, 0, 0), v3(0.001f, 0, 0), v3(0, 0.001f, 0));
	add_tri(s, v3(1, 1, 1), v3(0.999f, 1, 1), v3(1, 0.999f, 1));
}

/* Mistake caught: the footprint not reaching the SAH. The plain SAH cuts
 * a cluster far smaller than a packet into leaves of two or three
 * triangles (44 leaves here); under the footprint it stays in at most two
 * (the root's cut may pass through it: at that size, through or beside
 * it costs the same). */
Test(kdtree, footprint_keeps_a_cluster_smaller_than_a_packet_whole)
{
	scene s;
	scene_init(&s, "cluster");
	corners(&s);
	cluster(&s, v3(0.5f, 0.5f, 0.5f), 0.001f, 64, 5);
	finish(&s);
	kd_params p;
	kd_params_default(&p);
	kdtree t;
	diag d;
	int mixed;
	cr_assert_eq(kd_build(&t, &s, &p, &d), 0, "%s", d.msg);
	uint32_t plain = leaves_listing(&t, 2, 66, 66, &mixed);
	cr_assert_geq(plain, 16, "the plain SAH splits the cluster (%u leaves)", plain);
	kd_free(&t);
	/* grown by 0.05 * sqrt(3) per side: 170 times the cluster's side */
	p.footprint = 0.05f;
	cr_assert_eq(kd_build(&t, &s, &p, &d), 0, "%s", d.msg);
	uint32_t fp = leaves_listing(&t, 2, 66, 66, &mixed);
	cr_assert_leq(fp, 2,
	              "a packet 170 times wider than the cluster gains nothing by splitting it "
	              "(%u leaves)",
	              fp);
	kd_free(&t);
	scene_free(&s);
}

/* Mistake caught: the footprint growing the children but not the node
 * they split (the chance of a child would exceed 1, and no split of a
 * node smaller than the footprint would ever pay): two clusters half the
 * scene apart must still go to different leaves under the largest
 * footprint, which grows a box by a third of their distance on each side
 * (the mistake keeps them in one leaf there). */
Test(kdtree, footprint_still_parts_clusters_farther_apart_than_a_packet)
{
	scene s;
	scene_init(&s, "two clusters");
	corners(&s);
	cluster(&s, v3(0.25f, 0.5f, 0.5f), 0.001f, 32, 6);
	cluster(&s, v3(0.75f, 0.5f, 0.5f), 0.001f, 32, 7);
	finish(&s);
	kd_params p;
	kd_params_default(&p);
	p.footprint = (float)KD_FOOTPRINT_MAX; /* grown 0.17 per side */
	kdtree t;
	diag d;
	int mixed;
	cr_assert_eq(kd_build(&t, &s, &p, &d), 0, "%s", d.msg);
	leaves_listing(&t, 2, 34, 66, &mixed);
	cr_assert_not(mixed, "one leaf lists triangles of both clusters");
	kd_free(&t);
	scene_free(&s);
}

/* Mistake caught: the footprint taken in scene units instead of as a
 * fraction of the scene's diagonal. Scaling by 1024 is exact in floats,
 * so the same fraction must give the same tree node for node. */
Test(kdtree, footprint_is_a_fraction_of_the_scene)
{
	scene a, b;
	random_soup(&a, 2000, 11);
	scene_init(&b, "random x1024");
	for (uint32_t i = 0; i < a.ntris; i++) {
		vec3 p[3];
		for (int k = 0; k < 3; k++)
			p[k] = v3_scale(a.v[3 * (size_t)i + k], 1024.0f);
		add_tri(&b, p[0], p[1], p[2]);
	}
	finish(&b);
	kd_params p;
	kd_params_default(&p);
	p.footprint = 0.004f;
	kdtree ta, tb, plain;
	diag d;
	cr_assert_eq(kd_build(&ta, &a, &p, &d), 0, "%s", d.msg);
	cr_assert_eq(kd_build(&tb, &b, &p, &d), 0, "%s", d.msg);
	kd_params_default(&p);
	cr_assert_eq(kd_build(&plain, &a, &p, &d), 0, "%s", d.msg);
	cr_assert(ta.nnodes != plain.nnodes ||
	              memcmp(ta.nodes, plain.nodes, ta.nnodes * sizeof *ta.nodes),
	          "the footprint changed nothing here");
	cr_assert_eq(ta.nnodes, tb.nnodes);
	cr_assert_eq(ta.nlist, tb.nlist);
	cr_assert_eq(memcmp(ta.list, tb.list, ta.nlist * sizeof *ta.list), 0);
	for (uint32_t i = 0; i < ta.nnodes; i++) {
		cr_assert_eq(kd_is_leaf(ta.nodes[i]), kd_is_leaf(tb.nodes[i]), "node %u", i);
		if (!kd_is_leaf(ta.nodes[i]))
			cr_assert_eq(kd_split(ta.nodes[i]) * 1024.0f, kd_split(tb.nodes[i]),
			             "node %u", i);
	}
	kd_free(&ta);
	kd_free(&tb);
	kd_free(&plain);
	scene_free(&a);
	scene_free(&b);
}

Test(kdtree, flat_cells)
{
	/* Axis-aligned flat triangles on integer planes of all three axes, so
	 * nearly every split candidate has planar triangles lying in it. */
	scene s;
	scene_init(&s, "lattice");
	for (int c = 0; c <= 4; c++) {
		grid_plane(&s, 2, (float)c, 6);
		grid_plane(&s, 0, (float)c + 0.5f, 4);
	}
	grid_plane(&s, 1, 2.0f, 6);
	finish(&s);
	kd_params p;
	kd_params_default(&p);
	build_check(&s, &p, 1);
	p.leaf_size = 0;
	build_check(&s, &p, 1);
	scene_free(&s);
}

Test(kdtree, flat_scene)
{
	/* Every triangle in z = 0: the root box has zero extent in z. */
	scene s;
	uint64_t seed = 7;
	scene_init(&s, "flat");
	for (int i = 0; i < 1500; i++) {
		vec3 c = v3(rnd(&seed), rnd(&seed), 0);
		add_tri(&s, c, v3_add(c, v3(0.02f * rnd(&seed), 0.02f, 0)),
		        v3_add(c, v3(0.03f, 0.01f * rnd(&seed), 0)));
	}
	grid_plane(&s, 2, 0.0f, 3);
	finish(&s);
	kd_params p;
	kd_params_default(&p);
	build_check(&s, &p, 1);
	scene_free(&s);
}

Test(kdtree, tessellated_sphere)
{
	scene s;
	scene_init(&s, "sphere");
	const int nu = 48, nv = 24;
	for (int i = 0; i < nu; i++)
		for (int j = 0; j < nv; j++) {
			vec3 q[4];
			for (int k = 0; k < 4; k++) {
				float u = 2 * (float)M_PI * (float)(i + (k == 1 || k == 2)) / nu;
				float v = (float)M_PI * (float)(j + (k >= 2)) / nv;
				q[k] = v3(sinf(v) * cosf(u), cosf(v), sinf(v) * sinf(u));
			}
			add_tri(&s, q[0], q[1], q[2]);
			add_tri(&s, q[0], q[2], q[3]); /* zero-area at the poles */
		}
	finish(&s);
	kd_params p;
	kd_params_default(&p);
	build_check(&s, &p, 1);
	scene_free(&s);
}

Test(kdtree, degenerate_triangles)
{
	scene s;
	uint64_t seed = 99;
	scene_init(&s, "degenerate");
	grid_plane(&s, 2, 1.0f, 4);
	for (int i = 0; i < 400; i++) {
		vec3 a = v3(4 * rnd(&seed), 4 * rnd(&seed), 2 * rnd(&seed));
		vec3 b = v3(4 * rnd(&seed), 4 * rnd(&seed), 2 * rnd(&seed));
		switch (i % 4) {
		case 0: /* a point */
			add_tri(&s, a, a, a);
			break;
		case 1: /* a segment with a repeated corner */
			add_tri(&s, a, b, b);
			break;
		case 2: /* collinear corners */
			add_tri(&s, a, v3_scale(v3_add(a, b), 0.5f), b);
			break;
		default: /* a point on a lattice plane */
			add_tri(&s, v3(floorf(a.x), floorf(a.y), 1),
			        v3(floorf(a.x), floorf(a.y), 1), v3(floorf(a.x), floorf(a.y), 1));
		}
	}
	finish(&s);
	cr_assert_gt(s.ndegenerate, 300);
	kd_params p;
	kd_params_default(&p);
	build_check(&s, &p, 1);
	p.leaf_size = 0;
	build_check(&s, &p, 1);
	scene_free(&s);
}

Test(kdtree, duplicates_terminate)
{
	scene s;
	scene_init(&s, "dup");
	for (int i = 0; i < 1000; i++)
		add_tri(&s, v3(0, 0, 0), v3(1, 0.2f, 0), v3(0.3f, 1, 0.7f));
	finish(&s);
	kd_params p;
	kd_params_default(&p);
	p.leaf_size = 0;
	build_check(&s, &p, 1);
	scene_free(&s);

	/* Many copies of each of a few triangles, plus all-degenerate copies. */
	uint64_t seed = 5;
	scene_init(&s, "dup2");
	for (int i = 0; i < 20; i++) {
		vec3 a = v3(rnd(&seed), rnd(&seed), rnd(&seed));
		vec3 b = v3_add(a, v3(0.1f, 0, 0.05f)), c = v3_add(a, v3(0, 0.1f, 0));
		for (int k = 0; k < 50; k++)
			add_tri(&s, a, b, c);
		for (int k = 0; k < 20; k++)
			add_tri(&s, a, a, a);
	}
	finish(&s);
	build_check(&s, &p, 1);
	scene_free(&s);
}

/* A thousand random triangles in one plane, each covering part of the
 * others: SAH splits them again and again (each copy to both sides), and
 * the build took 11 s and 26 million list entries before it had a work
 * budget. Now it stops at the budget (KD_WORK_BUDGET per triangle), says
 * so in nbudget_leaves, and the tree is still correct. */
Test(kdtree, overlapping_coplanar_triangles_stay_linear)
{
	scene s;
	scene_init(&s, "coplanar");
	uint64_t seed = 11;
	const uint32_t n = 1000;
	for (uint32_t i = 0; i < n; i++) {
		vec3 p[3];
		for (int k = 0; k < 3; k++)
			p[k] = v3(rnd(&seed), rnd(&seed), 0);
		add_tri(&s, p[0], p[1], p[2]);
	}
	finish(&s);
	kd_params p;
	kdtree t;
	build_default(&s, &p, &t);
	cr_assert_leq(t.nlist, KD_WORK_BUDGET * n, "%u list entries for %u triangles", t.nlist, n);
	cr_assert_gt(t.nbudget_leaves, 0, "the budget was not reached");
	check_tree(&s, &t, &p, 0);
	kd_free(&t);
	scene_free(&s);
}

Test(kdtree, all_points_same)
{
	/* Zero surface area: the root must become a leaf. */
	scene s;
	scene_init(&s, "points");
	for (int i = 0; i < 10; i++)
		add_tri(&s, v3(1, 2, 3), v3(1, 2, 3), v3(1, 2, 3));
	finish(&s);
	kd_params p;
	kd_params_default(&p);
	build_check(&s, &p, 1);
	scene_free(&s);
}

static void shared_scene(const char *rel, int brute)
{
	char path[1024];
	SCENE_OR_SKIP(path, rel);
	scene s;
	cr_assert_eq(objmini_load(&s, path), 0, "cannot read %s", path);
	kd_params p;
	kdtree t;
	build_default(&s, &p, &t);
	check_tree(&s, &t, &p, brute);
	cr_assert_eq(t.nbudget_leaves, 0, "a real scene reached the work budget");
	/* far from it: under a tenth (kdtree.h says so) */
	cr_assert_lt(t.work, KD_WORK_BUDGET / 10 * s.ntris, "%llu references for %u triangles",
	             (unsigned long long)t.work, s.ntris);
	kd_free(&t);
	scene_free(&s);
}

Test(kdtree, cornell_box)
{
	shared_scene("cornell_box/CornellBox.obj", 1);
}

Test(kdtree, dragon_res4, .timeout = 120)
{
	shared_scene("stanford_dragon/dragon_vrip_res4.obj", 0);
}

/* Whether trees a and b are the same node for node, list for list. */
static int same_tree(const kdtree *a, const kdtree *b)
{
	return a->nnodes == b->nnodes && a->nlist == b->nlist &&
	       !memcmp(a->nodes, b->nodes, a->nnodes * sizeof *a->nodes) &&
	       !memcmp(a->list, b->list, a->nlist * sizeof *a->list);
}

/* Mistakes caught: a view's footprint (fp_angle, fp_eye) measured to
 * another point than the scene box's centre (a corner, the origin), or
 * not halved into a growth per side. The scene's box is [0,1]x[0,2]x[0,2]
 * (diagonal 3, centre (0.5,1,1)), so a packet 2^-5 wide seen from 3 away,
 * or 2^-6 wide from 6 away in any direction, grows a box by exactly what
 * the fraction 2^-6 of the diagonal does: the same tree, bit for bit. */
Test(kdtree, footprint_from_a_view_is_a_packet_at_the_scene_centre)
{
	scene s;
	uint64_t seed = 3;
	scene_init(&s, "box 1x2x2");
	add_tri(&s, v3(0, 0, 0), v3(0.01f, 0, 0), v3(0, 0.01f, 0));
	add_tri(&s, v3(1, 2, 2), v3(0.99f, 2, 2), v3(1, 1.99f, 2));
	for (int i = 0; i < 1500; i++) {
		vec3 c = v3(0.05f + 0.9f * rnd(&seed), 0.05f + 1.9f * rnd(&seed),
		            0.05f + 1.9f * rnd(&seed));
		add_tri(&s, c, v3_add(c, v3(0.01f * rnd(&seed), 0.02f, 0)),
		        v3_add(c, v3(0.02f, 0, 0.01f * rnd(&seed))));
	}
	finish(&s);
	diag d;
	kd_params p;
	kdtree plain, frac, t;
	kd_params_default(&p);
	cr_assert_eq(kd_build(&plain, &s, &p, &d), 0, "%s", d.msg);
	p.footprint = 0.015625f; /* 2^-6 of the diagonal, 0.046875 a side */
	cr_assert_eq(kd_build(&frac, &s, &p, &d), 0, "%s", d.msg);
	cr_assert_not(same_tree(&plain, &frac), "the footprint changed nothing here");
	cr_assert_float_eq(frac.fp_grow, 0.046875, 0);
	const float eyes[4][4] = {/* angle, eye */
	                          {0.03125f, 0.5f, 1, 4},
	                          {0.015625f, 6.5f, 1, 1},
	                          {0.015625f, 0.5f, -5, 1},
	                          {0.03125f, 0.5f, 1, -2}};
	for (int i = 0; i < 4; i++) {
		kd_params_default(&p);
		p.footprint = 0.1f; /* not used beside a view's */
		p.fp_angle = eyes[i][0];
		for (int k = 0; k < 3; k++)
			p.fp_eye[k] = eyes[i][1 + k];
		cr_assert_eq(kd_build(&t, &s, &p, &d), 0, "%s", d.msg);
		cr_assert_float_eq(t.fp_grow, 0.046875, 0, "eye %d: growth %g", i, t.fp_grow);
		cr_assert(same_tree(&t, &frac), "eye %d: another tree", i);
		kd_free(&t);
	}
	kd_free(&plain);
	kd_free(&frac);
	scene_free(&s);
}
