/*
 * frustum.c: the per-lane packet traversal with a packet-wide shortcut
 * (see frustum.h).
 *
 * Why the shortcut is exact. For ray i with 1/d of the packet's sign on
 * the split axis, the per-lane step (traverse.c, pkt_trav_node) makes the
 * near child [tn_i, min(tf_i, hi_i)] and the far child [max(tn_i, lo_i),
 * tf_i], where [lo_i, hi_i] is ts_i = (split - o_i) * (1/d_i) widened by
 * gamma(3) |ts_i|, so lo_i <= hi_i. If lo_i > tf_i the far segment is empty
 * and the near one is [tn_i, tf_i] unchanged (min picks tf_i, bit for
 * bit); if hi_i < tn_i the near one is empty and the far one unchanged.
 * The mask stays the same too: a ray in the current mask already has
 * tn_i <= tf_i and tn_i <= its best hit, which does not change between
 * two leaves. So when LO > TF or HI < TN for bounds LO <= every lo_i,
 * HI >= every hi_i, TN <= every tn_i, TF >= every tf_i, only the node
 * changes.
 *
 * The bounds. With o_i in [olo, ohi] and 1/d_i in [idlo, idhi] (one
 * sign), ts_i lies between the smallest and the largest of the four
 * corner products, since a rounded subtraction and a rounded product are
 * monotone in each operand; widening by four times gamma(3) covers the
 * per-ray widening and its rounding. The segment bounds start as the
 * rays' extremes after the scene-box clip and follow each step: the near
 * child's segments lie within [TN, min(TF, HI)], the far child's within
 * [max(TN, LO), TF] (any axis: the parent's [TN, TF]); a stack entry
 * keeps its bounds, and popping only drops rays.
 */
#include "kernel-ref/frustum.h"

#include <math.h>

#include "kernel-ref/cone.h"
#include "kernel-ref/kdtree.h"
#include "kernel-ref/simd.h"

#define NGROUPS (PKT_RAYS / SIMD_W)

/* Four times traverse.c's gamma(3): the per-ray widening plus room for
 * the rounding of the widened bounds. */
#define FRU_MARGIN (4.0f * 3.0f * 0x1p-24f / (1.0f - 3.0f * 0x1p-24f))

int fru_fault = FRU_FAULT_NONE;

/* The packet's bounds: origin and 1/d intervals per axis; pos[a]: every
 * ray's 1/d is positive on axis a (the near child is the one below), ok[a]:
 * the rays' 1/d on axis a are finite and of one sign (else every step on
 * that axis is per lane). */
typedef struct fru_box {
	float olo[3], ohi[3];
	float idlo[3], idhi[3];
	int pos[3], ok[3];
	/* one origin (olo = ohi): the rays' directions lie in [dlo, dhi],
	 * each component at most dmax in size (fru_tri_missed) */
	int one;
	float dlo[3], dhi[3], dmax;
} fru_box;

/* min and max of two floats that are not NaN (no libm call) */
static inline float mn2(float a, float b)
{
	return a < b ? a : b;
}
static inline float mx2(float a, float b)
{
	return a > b ? a : b;
}

/* Smallest and largest x over the lanes of mask; returns nonzero when x
 * is NaN in one of them (the bounds are then meaningless). A group with
 * all lanes in mask needs no selects. */
static unsigned lane_range(const float *x, uint64_t mask, float *lo, float *hi)
{
	const fv pinf = fv_set1(INFINITY), ninf = fv_set1(-INFINITY);
	fv mn = pinf, mx = ninf;
	unsigned nan = 0;
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(mask, g);
		if (!gb)
			continue;
		fv v = fv_load(x + SIMD_W * g), vl = v, vh = v;
		if (gb != SIMD_MASK) {
			iv on = iv_from_bits(gb);
			vl = fv_sel(on, v, pinf);
			vh = fv_sel(on, v, ninf);
		}
		nan |= iv_bits(v != v) & gb;
		mn = fv_min(mn, vl);
		mx = fv_max(mx, vh);
	}
	float a = INFINITY, b = -INFINITY;
	for (int l = 0; l < SIMD_W; l++) {
		a = mn[l] < a ? mn[l] : a;
		b = mx[l] > b ? mx[l] : b;
	}
	*lo = a;
	*hi = b;
	return nan;
}

/* Fills b from the state pkt_trav_begin_fp left; 0 when no axis can take
 * the packet step (or a ray has a NaN origin or direction). */
static int fru_setup(fru_box *b, const trav_state *s, const packet *p, uint64_t entered)
{
	const float *id[3] = {s->rc.idx, s->rc.idy, s->rc.idz};
	const float *org[3] = {p->ox, p->oy, p->oz};
	unsigned nan = 0;
	int any = 0;
	for (int a = 0; a < 3; a++) {
		nan |= lane_range(id[a], entered, &b->idlo[a], &b->idhi[a]);
		nan |= lane_range(org[a], entered, &b->olo[a], &b->ohi[a]);
		b->pos[a] = b->idlo[a] > 0.0f;
		b->ok[a] =
		    b->pos[a] ? b->idhi[a] < INFINITY : b->idhi[a] < 0.0f && b->idlo[a] > -INFINITY;
		any |= b->ok[a];
		if (fru_fault == FRU_FAULT_ONE_DIRECTION) {
			int first = __builtin_ctzll(entered);
			b->idlo[a] = b->idhi[a] = id[a][first];
		}
	}
	const float *dir[3] = {p->dx, p->dy, p->dz};
	b->one = 1;
	b->dmax = 0.0f;
	for (int a = 0; a < 3; a++) {
		nan |= lane_range(dir[a], entered, &b->dlo[a], &b->dhi[a]);
		b->one &= b->olo[a] == b->ohi[a];
		b->dmax = mx2(b->dmax, mx2(fabsf(b->dlo[a]), fabsf(b->dhi[a])));
	}
	return nan == 0 && any;
}

/* The shortcut applies (full precision, no planted fault, the packet's
 * box set up into b). */
static int fru_applies(fru_box *b, const trav_state *s, const packet *p, uint64_t entered)
{
	return entered && !s->fpt && !s->fpi && pkt_trav_fault == PKT_FAULT_NONE &&
	       s->stack_max <= PKT_STACK_MAX && fru_setup(b, s, p, entered);
}

int fru_coherent(const trav_state *s, const packet *p, uint64_t entered)
{
	fru_box b;
	return fru_applies(&b, s, p, entered);
}

/* [lo, hi] holding every ray's widened distance to the plane split on the
 * axis (the whole line if a bound overflows). */
static void fru_plane(const fru_box *b, int axis, float split, float *lo, float *hi)
{
	float clo = split - b->ohi[axis], chi = split - b->olo[axis];
	float p0 = clo * b->idlo[axis], p1 = clo * b->idhi[axis];
	float p2 = chi * b->idlo[axis], p3 = chi * b->idhi[axis];
	float tl = mn2(mn2(p0, p1), mn2(p2, p3)), th = mx2(mx2(p0, p1), mx2(p2, p3));
	if (!(fabsf(tl) < INFINITY && fabsf(th) < INFINITY)) {
		*lo = -INFINITY;
		*hi = INFINITY;
		return;
	}
	*lo = tl - fabsf(tl) * FRU_MARGIN;
	*hi = th + fabsf(th) * FRU_MARGIN;
}

/* Triangle culling for a packet from one origin (Reshetov et al. 2005 §3
 * cull a leaf's triangles by the packet's frustum): 1 when no ray of the
 * packet can hit t. With the corners relative to the origin, ray d passes
 * inside the triangle only if the three triple products d . (a_k x
 * a_k+1) do not have both signs; over the box of the rays' directions each
 * product's range is an interval sum. If one edge's products are above
 * +margin for every ray and another's below -margin, every ray's Woop
 * test (isect.h) sees two edge functions of opposite sign and rejects:
 * they are these products over d[kz] (one factor for all three), computed
 * with an error within a few float roundings of |a_k|_1 |a_k+1|_1, far
 * inside margin = 1e-4 |a_k|_1 |a_k+1|_1 dmax (also above the rounding of
 * this test itself). So skipping t changes no hit. */
static int fru_tri_missed(const void *ctx, const mimg_tri *t)
{
	const fru_box *b = ctx;
	float a[3][3], l1[3];
	for (int k = 0; k < 3; k++) {
		for (int j = 0; j < 3; j++)
			a[k][j] = t->v[k][j] - b->olo[j];
		l1[k] = fabsf(a[k][0]) + fabsf(a[k][1]) + fabsf(a[k][2]);
	}
	int pos = 0, neg = 0;
	for (int e = 0; e < 3; e++) {
		const float *u = a[e], *v = a[(e + 1) % 3];
		float n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
		              u[0] * v[1] - u[1] * v[0]};
		float lo = 0.0f, hi = 0.0f;
		for (int j = 0; j < 3; j++) {
			float x = n[j] * b->dlo[j], y = n[j] * b->dhi[j];
			lo += mn2(x, y);
			hi += mx2(x, y);
		}
		float margin = 1e-4f * l1[e] * l1[(e + 1) % 3] * b->dmax;
		pos |= lo > margin;
		neg |= hi < -margin;
	}
	if (fru_fault == FRU_FAULT_CULL_ONE_SIGN)
		return neg;
	return pos && neg;
}

/* The per-lane step with its packet shortcut, on the inner node n whose
 * rays' segments lie within [*tn, *tf]. When the plane's distances [lo,
 * hi] lie beyond every segment (lo > tf: the near child only) or before
 * it (hi < tn: the far child only), the per-lane step would leave every
 * segment and the mask as they are (file comment), so only the node
 * changes. Otherwise pkt_trav_node steps lane by lane. Either way the
 * bounds follow the child without a pass over the lanes: the near child's
 * segments are [tn_i, min(tf_i, hi_i)], within [tn, min(tf, hi)], the far
 * child's within [max(tn, lo), tf]; bt, bf: the far child's, if pushed. */
static void fru_step(const fru_box *b, trav_state *s, packet *p, kd_node n, float *tn, float *tf,
                     float *bt, float *bf)
{
	int axis = kd_axis(n);
	float lo = -INFINITY, hi = INFINITY;
	if (b->ok[axis])
		fru_plane(b, axis, kd_split(n), &lo, &hi);
	uint32_t left = kd_left(n), near = b->pos[axis] ? left : left + 1;
	uint32_t far = b->pos[axis] ? left + 1 : left;
	if (lo > *tf) { /* the near child only */
		s->cur.node = near;
		return;
	}
	if (hi < *tn) { /* the far child only */
		s->cur.node = fru_fault == FRU_FAULT_ALWAYS_NEAR ? near : far;
		return;
	}
	trav_result r;
	pkt_trav_node(s, p, n, &r);
	float ftn = mx2(*tn, lo), ntf = mn2(*tf, hi);
	if (r.pushed) {
		*bt = ftn;
		*bf = *tf;
	}
	if (s->cur.node == near)
		*tf = ntf;
	else
		*tn = ftn;
}

/* pkt_trace_run with the packet shortcut (fru_step); pops and leaves as
 * pkt_trace_run, so the counts are the same. bt[k], bf[k]: the segment
 * bounds of stack slot k. */
static void fru_walk(const fru_box *b, trav_state *s, packet *p, const mimg *m,
                     const pkt_cone *cone, trav_counts *c)
{
	const kd_node *nodes = mimg_nodes(m);
	float bt[PKT_STACK_MAX], bf[PKT_STACK_MAX], tn, tf, lo, hi;
	lane_range(s->cur.tn, s->cur.mask, &tn, &hi);
	lane_range(s->cur.tf, s->cur.mask, &lo, &tf);
	trav_result r;
	while (pkt_trav_pop(s, p, &r)) {
		if (r.popped) { /* a popped entry's rays are a subset: its bounds hold */
			tn = bt[s->sp];
			tf = bf[s->sp];
		}
		kd_node n = nodes[r.node];
		if (kd_is_leaf(n)) {
			/* triangle culling pays when many rays would test */
			int many = b->one && __builtin_popcountll(r.mask) >= 16;
			pkt_skip sk = {fru_tri_missed, b};
			pkt_trace_leaf(s, p, m, kd_first(n), kd_count(n), r.mask, cone, c,
			               many ? &sk : NULL);
			s->cur.mask = 0; /* pop next */
		} else
			fru_step(b, s, p, n, &tn, &tf, &bt[s->sp], &bf[s->sp]);
		if (c) { /* as pkt_trace_run: the depth after the step */
			c->node_steps++;
			c->max_sp = (uint64_t)s->sp > c->max_sp ? (uint64_t)s->sp : c->max_sp;
		}
	}
}

/* pkt_trace_with's run: the shortcut where it applies (full precision,
 * no planted fault, the packet's box set up), else 0: the per-lane loop. */
static int fru_run(trav_state *s, packet *p, const mimg *m, const struct pkt_cone *cone,
                   uint64_t entered, trav_counts *c)
{
	fru_box b;
	if (!fru_applies(&b, s, p, entered))
		return 0;
	fru_walk(&b, s, p, m, cone, c);
	return 1;
}

uint64_t fru_trace(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                   const pkt_precision *prec, int cull)
{
	return pkt_trace_with(p, m, stack, stack_max, c, prec, cull, fru_run);
}
