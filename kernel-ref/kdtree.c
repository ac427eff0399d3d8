/*
 * kdtree.c: kd_build, the SAH kd-tree builder of kdtree.h.
 *
 * Algorithm: Wald & Havran 2006 in O(n log n). Every triangle contributes
 * events to three per-axis lists sorted by position (one planar event where
 * its box is flat on that axis, else a start and an end event). The lists
 * are sorted once at the root; a node's SAH sweep is a linear scan of its
 * three lists, and a split partitions them in linear time: triangles wholly
 * on one side keep their (still sorted) events, and only the straddling
 * triangles are clipped to each child box ("perfect splits"), get new
 * events, which are sorted (few) and merged in.
 *
 * Side rules at a split plane p on axis k (box [lo, hi] of the triangle's
 * part inside the node): hi <= p goes left, lo >= p goes right, lo < p < hi
 * goes to both (clipped), and a triangle lying IN the plane (lo == hi == p)
 * goes to BOTH children. Wald-Havran put such a planar triangle on one side
 * only (p_side), but a ray travelling inside the plane is sent to one child
 * only, so it could miss it; both sides keeps the kdtree.h invariant at the
 * cost of a few duplicate references. A triangle merely touching the plane
 * from one side (an edge or vertex on it) stays on its own side, as in
 * pbrt and Wald-Havran: a ray crossing the plane visits both children.
 *
 * Invariant (kdtree.h, checked by tests/test_kdtree.c): a triangle is in a
 * leaf's list whenever its exact part inside the leaf box reaches the
 * leaf's interior, or lies flat in a face of the leaf.
 *
 * Robustness: clipping is done in double with the new coordinate on the
 * clip axis set exactly to the plane and the others clamped to the edge,
 * and the bounds are rounded outward to float, so a triangle's box here
 * always contains its exact part inside the node (conservative: a leaf may
 * list a triangle that only comes within a float ulp of it). Nodes whose
 * box has zero surface area (a line or a point) become leaves.
 *
 * Packet footprint (params->footprint = f, 0 by default): the SAH above
 * prices a split by the chance that a ray hitting the node hits each
 * child, the ratio of their surface areas. A packet of rays is not a line:
 * with a cross-section about w wide, it meets a box whenever the box grown
 * by w/2 on every side meets the packet's middle ray, so the chance is the
 * ratio of the grown boxes' areas. Far above w that is the plain ratio;
 * near w it tends to 1 for both children, and splitting a node much
 * smaller than a packet stops paying (the packet visits both halves).
 * Scanned meshes of tiny triangles, which the plain SAH cuts into cells
 * far smaller than a primary packet, get shallower trees with fuller
 * leaves. w/2 is f times the scene box's diagonal: a property of the
 * scene, not of a view, so the tree stays view-independent (the chip's
 * tree takes 0, the model's figures). Or w is the width a primary packet
 * of a view has at the scene box's centre (params->fp_angle, the packet's
 * angle, and fp_eye): what rtref takes when it knows its view before the
 * scene loads (world.c, view_kd), KD_RTREF_FOOTPRINT otherwise.
 *
 * Memory: events live in one growable arena used as a stack (a node's
 * children overwrite its own events, right child below left child, and the
 * left subtree is built first), plus one growable scratch buffer, so there
 * is no allocation per node or per event. The build loop uses an explicit
 * work stack of at most max_depth + 2 entries. A NULL params pointer means
 * kd_params_default.
 */
#include "kernel-ref/kdtree.h"

#include <math.h>
#include <stdlib.h>
#include <time.h>

enum { EV_END = 0, EV_PLANAR = 1, EV_START = 2 };
/* Side classes; bit 0 = goes left unchanged, bit 1 = goes right unchanged. */
enum { C_LEFT = 1, C_RIGHT = 2, C_BOTH = 3, C_STRADDLE = 4 };

#define MAX_TRIS  ((1u << 30) - 1) /* triangle id shares a word with the type */
#define MAX_NODES (1u << 30)       /* child index field is 30 bits */

typedef struct event {
	float pos;
	uint32_t v; /* triangle << 2 | EV_* */
} event;

typedef struct work {
	aabb box;
	size_t off;    /* arena index of the axis-0 list; axes 1 and 2 follow */
	uint32_t n[3]; /* events per axis */
	uint32_t ntris;
	uint32_t node;
	int depth;
} work;

typedef struct builder {
	const scene *s;
	kd_params p;
	event *arena;
	size_t arena_cap;
	event *tmp;
	size_t tmp_cap;
	uint8_t *cls;    /* per triangle: side class during one split */
	float (*old)[6]; /* per triangle: box of a straddler before clipping */
	uint32_t *strad; /* straddling triangles of the current split */
	kd_node *nodes;
	uint32_t nnodes;
	size_t nodes_cap;
	uint32_t *list;
	size_t nlist, list_cap;
	double inv_root_area;
	double grow2; /* twice the footprint's growth per side, scene units */
	kdtree *t;
} builder;

void kd_params_default(kd_params *p)
{
	p->cost_trav = 1.0f;
	p->cost_isect = 1.5f;
	p->max_depth = 0;
	/* Splitting two triangles apart rarely pays at K_T/K_I = 1/1.5 and it
	 * doubles the node count of the deepest level. */
	p->leaf_size = 2;
	/* Wald-Havran's lambda = 0.8 for cutting off empty space. */
	p->empty_bonus = 0.2f;
	p->footprint = 0; /* the plain SAH: rtref sets its own (world.c, view_kd) */
	p->fp_angle = 0;
	p->fp_eye[0] = p->fp_eye[1] = p->fp_eye[2] = 0;
}

static int grow(void **ptr, size_t *cap, size_t need, size_t elem)
{
	if (need <= *cap)
		return 0;
	size_t n = *cap ? *cap : 1024;
	while (n < need)
		n *= 2;
	void *q = realloc(*ptr, n * elem);
	if (!q)
		return -1;
	*ptr = q;
	*cap = n;
	return 0;
}

static float lo_of(const aabb *b, int a)
{
	return v3_get(b->lo, a);
}

static float hi_of(const aabb *b, int a)
{
	return v3_get(b->hi, a);
}

static void v3_set(vec3 *v, int a, float x)
{
	*(a == 0 ? &v->x : a == 1 ? &v->y : &v->z) = x;
}

/* Surface area without the factor 2 (only ratios are used) of box b with
 * every extent grown by g (the packet footprint's 2 * w/2: "Packet
 * footprint" above; 0: the box itself). */
static double half_area_grown(const aabb *b, double g)
{
	double dx = (b->hi.x - b->lo.x) + g, dy = (b->hi.y - b->lo.y) + g,
	       dz = (b->hi.z - b->lo.z) + g;
	if (dx < 0 || dy < 0 || dz < 0)
		return 0;
	return dx * dy + dy * dz + dz * dx;
}

static double half_area(const aabb *b)
{
	return half_area_grown(b, 0);
}

/* Sort key: float order as unsigned order (no NaN; -0 is normalised away). */
static uint32_t key(float f)
{
	uint32_t u;
	memcpy(&u, &f, sizeof u);
	return (u & 0x80000000u) ? ~u : u | 0x80000000u;
}

/* Sorts by position; buf holds n events of scratch. LSD radix 11/11/10. */
static void sort_events(event *e, size_t n, event *buf)
{
	if (n < 64) {
		for (size_t i = 1; i < n; i++) {
			event x = e[i];
			size_t j = i;
			for (; j > 0 && e[j - 1].pos > x.pos; j--)
				e[j] = e[j - 1];
			e[j] = x;
		}
		return;
	}
	static const int shift[3] = {0, 11, 22};
	uint32_t h[3][2048];
	memset(h, 0, sizeof h);
	for (size_t i = 0; i < n; i++) {
		uint32_t k = key(e[i].pos);
		h[0][k & 2047]++;
		h[1][(k >> 11) & 2047]++;
		h[2][k >> 22]++;
	}
	event *src = e, *dst = buf;
	for (int pass = 0; pass < 3; pass++) {
		uint32_t sum = 0;
		for (int i = 0; i < 2048; i++) {
			uint32_t c = h[pass][i];
			h[pass][i] = sum;
			sum += c;
		}
		for (size_t i = 0; i < n; i++)
			dst[h[pass][(key(src[i].pos) >> shift[pass]) & 2047]++] = src[i];
		event *x = src;
		src = dst;
		dst = x;
	}
	/* Three passes leave the result in buf. */
	memcpy(e, src, n * sizeof *e);
}

static size_t merge(event *out, const event *a, size_t na, const event *b, size_t nb)
{
	size_t i = 0, j = 0, k = 0;
	while (i < na && j < nb)
		out[k++] = b[j].pos < a[i].pos ? b[j++] : a[i++];
	while (i < na)
		out[k++] = a[i++];
	while (j < nb)
		out[k++] = b[j++];
	return k;
}

/* Appends the events of triangle tri with box b[6] (lo xyz, hi xyz) to the
 * three lists; returns nothing, advances the counts. */
static void emit(event *l[3], uint32_t n[3], uint32_t tri, const float b[6])
{
	for (int a = 0; a < 3; a++) {
		float lo = b[a] + 0.0f, hi = b[3 + a] + 0.0f; /* -0 -> +0 */
		if (lo == hi) {
			l[a][n[a]++] = (event){lo, tri << 2 | EV_PLANAR};
		} else {
			l[a][n[a]++] = (event){lo, tri << 2 | EV_START};
			l[a][n[a]++] = (event){hi, tri << 2 | EV_END};
		}
	}
}

/* No NaN reaches these, so plain compares (libm fmin/fmax are calls). */
static double dmin(double a, double b)
{
	return a < b ? a : b;
}

static double dmax(double a, double b)
{
	return a > b ? a : b;
}

static float round_down(double d)
{
	float f = (float)d;
	return (double)f > d ? nextafterf(f, -INFINITY) : f;
}

static float round_up(double d)
{
	float f = (float)d;
	return (double)f < d ? nextafterf(f, INFINITY) : f;
}

/* Box of triangle p clipped to the closed box cb, intersected with old
 * (a box already known to contain the triangle's part in cb). Sutherland-
 * Hodgman in double; an empty result (possible only through rounding)
 * falls back to old & cb, which is conservative. */
static void clip_box(const vec3 *p, const aabb *cb, const float old[6], float out[6])
{
	double poly[2][10][3];
	int n = 3, cur = 0;
	for (int i = 0; i < 3; i++) {
		poly[0][i][0] = p[i].x;
		poly[0][i][1] = p[i].y;
		poly[0][i][2] = p[i].z;
	}
	for (int a = 0; a < 3 && n > 0; a++) {
		for (int side = 0; side < 2 && n > 0; side++) {
			double bound = side ? hi_of(cb, a) : lo_of(cb, a);
			double(*in)[3] = poly[cur], (*o)[3] = poly[cur ^ 1];
			int all = 1;
			for (int i = 0; i < n && all; i++)
				all = side ? in[i][a] <= bound : in[i][a] >= bound;
			if (all)
				continue;
			int m = 0;
			for (int i = 0; i < n; i++) {
				const double *c = in[i], *d = in[(i + 1) % n];
				int cin = side ? c[a] <= bound : c[a] >= bound;
				int din = side ? d[a] <= bound : d[a] >= bound;
				if (cin)
					memcpy(o[m++], c, sizeof o[0]);
				if (cin != din) {
					double t = (bound - c[a]) / (d[a] - c[a]);
					for (int j = 0; j < 3; j++) {
						double v = c[j] + t * (d[j] - c[j]);
						double lo = dmin(c[j], d[j]), hi = dmax(c[j], d[j]);
						o[m][j] = j == a ? bound : dmin(dmax(v, lo), hi);
					}
					m++;
				}
			}
			n = m;
			cur ^= 1;
		}
	}
	float cbf[6] = {cb->lo.x, cb->lo.y, cb->lo.z, cb->hi.x, cb->hi.y, cb->hi.z};
	for (int a = 0; a < 3; a++) {
		out[a] = (float)dmax(old[a], cbf[a]);
		out[3 + a] = (float)dmin(old[3 + a], cbf[3 + a]);
	}
	if (n == 0)
		return;
	double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
	for (int i = 0; i < n; i++)
		for (int a = 0; a < 3; a++) {
			lo[a] = dmin(lo[a], poly[cur][i][a]);
			hi[a] = dmax(hi[a], poly[cur][i][a]);
		}
	float c[6];
	for (int a = 0; a < 3; a++) {
		c[a] = (float)dmax(out[a], round_down(lo[a]));
		c[3 + a] = (float)dmin(out[3 + a], round_up(hi[a]));
		if (c[a] > c[3 + a])
			return; /* rounding disagreement: keep the fallback */
	}
	memcpy(out, c, sizeof c);
}

/* Best SAH split of w; returns its cost (INFINITY if none) and the
 * triangle counts of its children in *ncl, *ncr. */
static double find_split(const builder *b, const work *w, const event *ev, int *axis, float *pos,
                         uint32_t *ncl, uint32_t *ncr)
{
	double area = half_area(&w->box);
	double best = INFINITY;
	int best_k = 0;
	float best_p = 0;
	uint32_t best_cl = 0, best_cr = 0;
	if (!(area > 0))
		return best;
	/* every extent grown by the footprint (2 * w/2); g = 0: plain SAH */
	double g = b->grow2;
	double area_g = half_area_grown(&w->box, g);
	double kt = b->p.cost_trav, ki = b->p.cost_isect / area_g, keep = 1.0 - b->p.empty_bonus;
	for (int k = 0; k < 3; ev += w->n[k], k++) {
		double lo = lo_of(&w->box, k), hi = hi_of(&w->box, k);
		if (!(hi > lo))
			continue;
		double u = hi_of(&w->box, (k + 1) % 3) - lo_of(&w->box, (k + 1) % 3) + g;
		double v = hi_of(&w->box, (k + 2) % 3) - lo_of(&w->box, (k + 2) % 3) + g;
		double uv = u * v, us = u + v;
		uint32_t nl = 0, nr = w->ntris, n = w->n[k];
		for (uint32_t i = 0; i < n;) {
			float p = ev[i].pos;
			uint32_t ne = 0, np = 0, ns = 0;
			for (; i < n && ev[i].pos == p; i++) {
				uint32_t ty = ev[i].v & 3;
				ne += ty == EV_END;
				np += ty == EV_PLANAR;
				ns += ty == EV_START;
			}
			nr -= ne + np;
			if (p > lo && p < hi) {
				uint32_t cl = nl + np, cr = nr + np;
				double c = kt + ki * ((uv + (p - lo + g) * us) * cl +
				                      (uv + (hi - p + g) * us) * cr);
				if (cl == 0 || cr == 0)
					c *= keep;
				if (c < best) {
					best = c;
					best_k = k;
					best_p = p;
					best_cl = cl;
					best_cr = cr;
				}
			}
			nl += ns + np;
		}
	}
	*axis = best_k;
	*pos = best_p;
	*ncl = best_cl;
	*ncr = best_cr;
	return best;
}

/* Twice the footprint's growth per side (scene units): a packet's width
 * at the box's centre seen from the view's eye, or the fraction of the
 * box's diagonal (kdtree.c's top comment, "Packet footprint"). */
static double fp_grow2(const kd_params *p, const aabb *bx)
{
	double dx = (double)bx->hi.x - bx->lo.x, dy = (double)bx->hi.y - bx->lo.y,
	       dz = (double)bx->hi.z - bx->lo.z;
	if (!(p->fp_angle > 0))
		return 2.0 * p->footprint * sqrt(dx * dx + dy * dy + dz * dz);
	double ex = p->fp_eye[0] - 0.5 * ((double)bx->lo.x + bx->hi.x),
	       ey = p->fp_eye[1] - 0.5 * ((double)bx->lo.y + bx->hi.y),
	       ez = p->fp_eye[2] - 0.5 * ((double)bx->lo.z + bx->hi.z);
	return p->fp_angle * sqrt(ex * ex + ey * ey + ez * ez);
}

static int make_leaf(builder *b, const work *w, const event *ev)
{
	if (grow((void **)&b->list, &b->list_cap, b->nlist + w->ntris, sizeof *b->list))
		return -1;
	if (b->nlist + w->ntris > UINT32_MAX)
		return -1;
	uint32_t first = (uint32_t)b->nlist;
	for (uint32_t i = 0; i < w->n[0]; i++)
		if ((ev[i].v & 3) != EV_END)
			b->list[b->nlist++] = ev[i].v >> 2;
	b->nodes[w->node] = kd_make_leaf(first, w->ntris);
	kdtree *t = b->t;
	t->nleaves++;
	t->nempty_leaves += w->ntris == 0;
	if (w->depth > t->depth)
		t->depth = w->depth;
	t->sah_cost += b->p.cost_isect * w->ntris * half_area(&w->box) * b->inv_root_area;
	return 0;
}

/* Classifies w's triangles against the plane (k, p) into b->cls, on the
 * split axis; each triangle's last event there (END or PLANAR) sees its
 * final class. Counts per class into cnt, the straddlers into b->strad;
 * returns how many straddle. */
static uint32_t classify(builder *b, const work *w, int k, float p, uint32_t cnt[5])
{
	const event *ek = b->arena + w->off + (k > 0 ? w->n[0] : 0) + (k > 1 ? w->n[1] : 0);
	uint32_t nstrad = 0;
	for (uint32_t i = 0; i < w->n[k]; i++) {
		uint32_t tri = ek[i].v >> 2, ty = ek[i].v & 3;
		float x = ek[i].pos;
		if (ty == EV_START) {
			b->cls[tri] = x >= p ? C_RIGHT : C_STRADDLE;
			continue;
		}
		if (ty == EV_PLANAR)
			b->cls[tri] = x < p ? C_LEFT : x > p ? C_RIGHT : C_BOTH;
		else if (x <= p)
			b->cls[tri] = C_LEFT;
		if (b->cls[tri] == C_STRADDLE)
			b->strad[nstrad++] = tri;
		cnt[b->cls[tri]]++;
	}
	return nstrad;
}

/* Makes w's node an inner node at (k, p) with the children L and R (a
 * pair, right = left + 1) and pushes R, then L. */
static int push_children(builder *b, const work *w, int k, float p, work *L, work *R, work *stack,
                         int *sp)
{
	if (b->nnodes > MAX_NODES - 2 ||
	    grow((void **)&b->nodes, &b->nodes_cap, b->nnodes + 2, sizeof(kd_node)))
		return -1;
	uint32_t left = b->nnodes;
	b->nnodes += 2;
	b->nodes[w->node] = kd_make_inner(k, p, left);
	b->t->sah_cost += b->p.cost_trav * half_area(&w->box) * b->inv_root_area;
	L->node = left;
	R->node = left + 1;
	L->depth = R->depth = w->depth + 1;
	stack[(*sp)++] = *R;
	stack[(*sp)++] = *L;
	return 0;
}

/* Splits w at (k, p): pushes the right then the left child onto the stack.
 * Returns -1 when out of memory. */
static int split(builder *b, const work *w, int k, float p, work *stack, int *sp)
{
	event *ev = b->arena + w->off;
	uint32_t cnt[5] = {0};
	uint32_t nstrad = classify(b, w, k, p, cnt);
	/* Scratch: SL[3], SR[3] (at most n[a] each), NL[3], NR[3] (at most
	 * 2 nstrad each), radix buffer (2 nstrad). */
	size_t ntot = (size_t)w->n[0] + w->n[1] + w->n[2];
	if (grow((void **)&b->tmp, &b->tmp_cap, 2 * ntot + 14 * (size_t)nstrad, sizeof(event)))
		return -1;
	event *sl[3], *sr[3], *nl[3], *nr[3];
	uint32_t csl[3], csr[3], cnl[3] = {0}, cnr[3] = {0};
	event *q = b->tmp;
	for (int a = 0; a < 3; a++) {
		sl[a] = q;
		q += w->n[a];
		sr[a] = q;
		q += w->n[a];
	}
	for (int a = 0; a < 3; a++) {
		nl[a] = q;
		q += 2 * (size_t)nstrad;
		nr[a] = q;
		q += 2 * (size_t)nstrad;
	}
	event *rbuf = q;
	/* Partition the sorted lists; record straddlers' old boxes. */
	const event *e = ev;
	for (int a = 0; a < 3; e += w->n[a], a++) {
		uint32_t cl = 0, cr = 0;
		for (uint32_t i = 0; i < w->n[a]; i++) {
			uint32_t tri = e[i].v >> 2;
			uint8_t c = b->cls[tri];
			sl[a][cl] = e[i];
			sr[a][cr] = e[i];
			cl += c & 1;
			cr += (c >> 1) & 1;
			if (c == C_STRADDLE) {
				uint32_t ty = e[i].v & 3;
				if (ty != EV_END)
					b->old[tri][a] = e[i].pos;
				if (ty != EV_START)
					b->old[tri][3 + a] = e[i].pos;
			}
		}
		csl[a] = cl;
		csr[a] = cr;
	}
	/* Perfect splits: clip each straddler to both child boxes. */
	work L = *w, R = *w;
	v3_set(&L.box.hi, k, p);
	v3_set(&R.box.lo, k, p);
	for (uint32_t i = 0; i < nstrad; i++) {
		uint32_t tri = b->strad[i];
		const vec3 *v = b->s->v + 3 * (size_t)tri;
		float bl[6], br[6];
		clip_box(v, &L.box, b->old[tri], bl);
		clip_box(v, &R.box, b->old[tri], br);
		emit(nl, cnl, tri, bl);
		emit(nr, cnr, tri, br);
	}
	for (int a = 0; a < 3; a++) {
		sort_events(nl[a], cnl[a], rbuf);
		sort_events(nr[a], cnr[a], rbuf);
	}
	/* Children overwrite the parent: right lists first, then left. */
	size_t nright = 0, nleft = 0;
	for (int a = 0; a < 3; a++) {
		R.n[a] = csr[a] + cnr[a];
		L.n[a] = csl[a] + cnl[a];
		nright += R.n[a];
		nleft += L.n[a];
	}
	if (grow((void **)&b->arena, &b->arena_cap, w->off + nright + nleft, sizeof(event)))
		return -1;
	R.off = w->off;
	L.off = w->off + nright;
	event *out = b->arena + R.off;
	for (int a = 0; a < 3; a++)
		out += merge(out, sr[a], csr[a], nr[a], cnr[a]);
	for (int a = 0; a < 3; a++)
		out += merge(out, sl[a], csl[a], nl[a], cnl[a]);
	L.ntris = cnt[C_LEFT] + cnt[C_BOTH] + nstrad;
	R.ntris = cnt[C_RIGHT] + cnt[C_BOTH] + nstrad;
	return push_children(b, w, k, p, &L, &R, stack, sp);
}

static int build(builder *b, const scene *s)
{
	kdtree *t = b->t;
	uint32_t nt = s->ntris;
	b->cls = malloc(nt);
	b->old = malloc((size_t)nt * sizeof *b->old);
	b->strad = malloc((size_t)nt * sizeof *b->strad);
	size_t nev = 6 * (size_t)nt;
	if (!b->cls || !b->old || !b->strad ||
	    grow((void **)&b->arena, &b->arena_cap, nev, sizeof(event)) ||
	    grow((void **)&b->tmp, &b->tmp_cap, 2 * nt, sizeof(event)))
		return -1;
	/* Root events: count per axis first so the lists can be laid out. */
	work root = {.box = s->bounds, .off = 0, .ntris = nt, .node = 0, .depth = 0};
	/* kdtree.h KD_WORK_BUDGET: why the build has one */
	double work_left = KD_WORK_BUDGET * (double)nt;
	uint32_t np[3] = {0, 0, 0};
	for (uint32_t i = 0; i < nt; i++) {
		const vec3 *v = s->v + 3 * (size_t)i;
		for (int a = 0; a < 3; a++) {
			float x0 = v3_get(v[0], a);
			np[a] += x0 == v3_get(v[1], a) && x0 == v3_get(v[2], a);
		}
	}
	event *l[3];
	for (int a = 0; a < 3; a++) {
		root.n[a] = 2 * nt - np[a];
		l[a] = b->arena + (a > 0 ? root.n[0] : 0) + (a > 1 ? root.n[1] : 0);
	}
	uint32_t n[3] = {0, 0, 0};
	for (uint32_t i = 0; i < nt; i++) {
		const vec3 *v = s->v + 3 * (size_t)i;
		aabb tb = aabb_grow(aabb_grow(aabb_grow(aabb_empty(), v[0]), v[1]), v[2]);
		float bx[6] = {tb.lo.x, tb.lo.y, tb.lo.z, tb.hi.x, tb.hi.y, tb.hi.z};
		emit(l, n, i, bx);
	}
	for (int a = 0; a < 3; a++)
		sort_events(l[a], n[a], b->tmp);

	if (grow((void **)&b->nodes, &b->nodes_cap, 1024, sizeof(kd_node)))
		return -1;
	b->nnodes = 1;
	double ra = half_area(&s->bounds);
	b->inv_root_area = ra > 0 ? 1.0 / ra : 0.0;
	b->grow2 = fp_grow2(&b->p, &s->bounds);
	b->t->fp_grow = 0.5 * b->grow2;
	b->t->fp_angle = b->p.fp_angle;

	work stack[KD_DEPTH_MAX + 4];
	int sp = 0;
	stack[sp++] = root;
	while (sp > 0) {
		work w = stack[--sp];
		const event *ev = b->arena + w.off;
		int k = 0;
		float p = 0;
		uint32_t cl = 0, cr = 0;
		int stop = w.ntris <= (uint32_t)b->p.leaf_size || w.depth >= b->p.max_depth;
		if (!stop &&
		    find_split(b, &w, ev, &k, &p, &cl, &cr) < b->p.cost_isect * (double)w.ntris) {
			if ((double)cl + cr > work_left) {
				t->nbudget_leaves++;
				if (make_leaf(b, &w, ev))
					return -1;
			} else {
				work_left -= (double)cl + cr;
				t->work += (uint64_t)cl + cr;
				if (split(b, &w, k, p, stack, &sp))
					return -1;
			}
		} else if (make_leaf(b, &w, ev)) {
			return -1;
		}
	}
	if (ra <= 0)
		t->sah_cost = b->p.cost_isect * (double)b->nlist; /* a line or point scene */
	return 0;
}

int kd_depth_limit(int max_depth, uint32_t ntris)
{
	if (max_depth > 0)
		return max_depth;
	long md = lround(8.0 + 1.3 * log2((double)(ntris ? ntris : 1)));
	return md > 60 ? 60 : (int)md;
}

int kd_build(kdtree *t, const scene *s, const kd_params *params, diag *d)
{
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	memset(t, 0, sizeof *t);
	kd_params p;
	if (params)
		p = *params;
	else
		kd_params_default(&p);
	if (!(p.cost_trav >= 0 && isfinite(p.cost_trav)) ||
	    !(p.cost_isect > 0 && isfinite(p.cost_isect)) || p.max_depth < 0 ||
	    p.max_depth > KD_DEPTH_MAX || p.leaf_size < 0 ||
	    !(p.empty_bonus >= 0 && p.empty_bonus < 1) ||
	    !(p.footprint >= 0 && p.footprint <= (float)KD_FOOTPRINT_MAX) ||
	    !(p.fp_angle >= 0 && p.fp_angle <= (float)KD_FP_ANGLE_MAX) ||
	    (p.fp_angle > 0 &&
	     !(isfinite(p.fp_eye[0]) && isfinite(p.fp_eye[1]) && isfinite(p.fp_eye[2]))))
		return diag_set(d, "kd_build", 0, 0,
		                "bad parameters (need cost_trav >= 0, cost_isect > 0, 0 <= "
		                "max_depth <= %d, leaf_size >= 0, 0 <= empty_bonus < 1, 0 <= "
		                "footprint <= %g, 0 <= fp_angle <= %g, a finite fp_eye)",
		                KD_DEPTH_MAX, KD_FOOTPRINT_MAX, KD_FP_ANGLE_MAX);
	if (s->ntris == 0 || s->ntris > MAX_TRIS)
		return diag_set(d, s->name, 0, 0, "kd-tree needs 1 to %u triangles, scene has %u",
		                MAX_TRIS, s->ntris);
	p.max_depth = kd_depth_limit(p.max_depth, s->ntris);
	builder b = {.s = s, .p = p, .t = t};
	t->bounds = s->bounds;
	int rc = build(&b, s);
	free(b.arena);
	free(b.tmp);
	free(b.cls);
	free(b.old);
	free(b.strad);
	if (rc) {
		free(b.nodes);
		free(b.list);
		memset(t, 0, sizeof *t);
		return diag_set(d, s->name, 0, 0, "kd-tree build: out of memory or tree too large");
	}
	t->nodes = b.nodes;
	t->nnodes = b.nnodes;
	t->list = b.list;
	t->nlist = (uint32_t)b.nlist;
	clock_gettime(CLOCK_MONOTONIC, &t1);
	t->build_ms = (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) * 1e-6;
	return 0;
}

void kd_free(kdtree *t)
{
	free(t->nodes);
	free(t->list);
	memset(t, 0, sizeof *t);
}
