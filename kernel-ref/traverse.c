/*
 * traverse.c: packet kd-tree traversal and triangle tests (see packet.h),
 * plus the scalar single-ray path used to check them.
 *
 * The packet code works on groups of SIMD_W lanes (simd.h: 16 with
 * AVX-512, 8 with AVX). A group whose
 * lanes are all inactive is skipped, so masked packets cost little. All
 * segment arithmetic is written once as a lane operation and once as a
 * scalar one with the same operation order, so the two paths agree to the
 * bit.
 *
 * Reduced precision (pkt_precision): a stage whose format is not the
 * identity takes a scalar emulation (trav_plane_fp, trav_clip_fp,
 * isect_tri_fp), chosen once per packet; the packet and single-ray paths
 * call the same scalar functions, so they agree to the bit as well.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "kernel-ref/cone.h"
#include "kernel-ref/isect.h"
#include "kernel-ref/isect_v.h"
#include "kernel-ref/kdtree.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/simd.h"

/* a tree kd_build accepts fits the traversal stack */
_Static_assert(KD_DEPTH_MAX <= PKT_STACK_MAX, "kdtree.h KD_DEPTH_MAX fits packet.h PKT_STACK_MAX");

/* gamma(n) = n u / (1 - n u), u = 2^-24 (pbrt): relative error bound of n
 * chained float roundings. A split distance (split - o) * (1/d) carries
 * three roundings. */
#define GAMMA3 (3.0f * 0x1p-24f / (1.0f - 3.0f * 0x1p-24f))

#define NGROUPS (PKT_RAYS / SIMD_W)

int pkt_trav_fault = PKT_FAULT_NONE;

void pkt_precision_full(pkt_precision *pp)
{
	pp->trav = pp->isect = pp->shade = fpfmt_full();
}

/* ---- reduced-precision traversal arithmetic (scalar) ---------------------- */

/* Conservative bounds lo <= t <= hi of the exact distance t = (plane - o) / d
 * to an axis plane, computed in format f the way a reduced traversal unit
 * would: the plane and the origin are floats from memory, the difference,
 * 1/d (id, already rounded to f) and the product are each rounded to f.
 * Three roundings give |ts - t| <= gamma(3) |t| <= gamma(4) |ts|; gamma(5)
 * (g) leaves room for the float rounding of the bound itself, and lo and hi
 * are then rounded outward to f (one float ulp first, for the float
 * subtraction): the interval always holds the exact t, so a child cell's
 * segment can only grow, never lose the part where a hit lies (Vaidyanathan,
 * Akenine-Moller, Salvi 2016 do the same for box slabs). A flushed
 * difference has an absolute error below the smallest normal, hence the
 * tiny * |id| term. No bound (g infinite, 1- or 2-bit mantissas) or an
 * origin in the plane of an axis-parallel ray (NaN): the whole line. */
static inline void trav_plane_fp(const fpfmt *f, float g, float plane, float o, float id, float *lo,
                                 float *hi)
{
	float ts = fp_round(f, fp_round(f, plane - o) * id);
	if (ts != ts || g == INFINITY) {
		*lo = -INFINITY;
		*hi = INFINITY;
		return;
	}
	if (ts == INFINITY || ts == -INFINITY) {
		*lo = *hi = ts; /* d = +-0: the ray never reaches the plane */
		return;
	}
	float err = fabsf(ts) * g + fabsf(id) * fp_from_bits(f->minnorm);
	*lo = fp_round_down(f, fp_next_down(ts - err));
	*hi = fp_round_up(f, fp_next_up(ts + err));
}

/* The scene-box clip of one ray in format f: [tn, tf] contains the exact
 * box segment (each slab's entry is the smaller lower bound, its exit the
 * larger upper bound). */
static void trav_clip_fp(const fpfmt *f, float g, const aabb *b, const float o[3],
                         const float id[3], float tmax, float *tn, float *tf)
{
	const float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
	float n = 0.0f, fa = tmax;
	for (int a = 0; a < 3; a++) {
		float l0, h0, l1, h1;
		trav_plane_fp(f, g, lo[a], o[a], id[a], &l0, &h0);
		trav_plane_fp(f, g, hi[a], o[a], id[a], &l1, &h1);
		float en = fminf(l0, l1), ex = fmaxf(h0, h1);
		if (en > n)
			n = en;
		if (ex < fa)
			fa = ex;
	}
	*tn = n;
	*tf = fa;
}

/* Splits the segment [tn, tf] at a plane whose distance lies in [lo, hi]:
 * below and above child segments (as the SIMD loop and ray_step do). */
static inline void trav_cut(int pos, float tn, float tf, float lo, float hi, float *b_n, float *b_f,
                            float *a_n, float *a_f)
{
	float up = tn > lo ? tn : lo, dn = tf < hi ? tf : hi;
	*b_n = pos ? tn : up;
	*b_f = pos ? dn : tf;
	*a_n = pos ? up : tn;
	*a_f = pos ? tf : dn;
}

/* ---- setup ------------------------------------------------------------ */

/* A short loop over vectors unrolled by gcc (its rolled loop kept them in
 * memory); other compilers decide themselves. */
#if defined(__GNUC__) && !defined(__clang__)
#define TRAV_PRAGMA(x) _Pragma(#x)
#define TRAV_UNROLL(n) TRAV_PRAGMA(GCC unroll n)
#else
#define TRAV_UNROLL(n)
#endif

/* fminf/fmaxf semantics lane by lane (a NaN operand yields the other), so
 * the vector clip rounds exactly like ray_trace's scalar one. */
static inline fv fv_fmin(fv a, fv b)
{
	return fv_sel((a < b) | (b != b), a, b);
}
static inline fv fv_fmax(fv a, fv b)
{
	return fv_sel((a > b) | (b != b), a, b);
}
static inline fv sel3(iv k0, iv k1, fv x, fv y, fv z)
{
	return fv_sel(k0, x, fv_sel(k1, y, z));
}

/* One permutation for the whole packet? (each of the six lane masks mk of
 * the axis selects all or nothing): then its axes and the origins in its
 * order, for the triangle test's uniform path. */
static void uniform_perm(pkt_rayc *rc, const packet *p, const uint64_t mk[6])
{
	rc->uniform = p->valid != 0;
	for (int k = 0; k < 6; k++)
		rc->uniform &= mk[k] == 0 || mk[k] == p->valid;
	if (rc->uniform) {
		rc->ukz = mk[0] ? 0 : mk[1] ? 1 : 2;
		rc->ukx = mk[2] ? 0 : mk[3] ? 1 : 2;
		rc->uky = mk[4] ? 0 : mk[5] ? 1 : 2;
		const float *og[3] = {p->ox, p->oy, p->oz};
		memcpy(rc->okx, og[rc->ukx], sizeof rc->okx);
		memcpy(rc->oky, og[rc->uky], sizeof rc->oky);
		memcpy(rc->okz, og[rc->ukz], sizeof rc->okz);
	}
}

/* Reduced traversal: the clip to the scene box redone in the format, lane
 * by lane; returns the lanes whose segment is not empty. */
static uint64_t clip_fp(trav_state *s, const packet *p, const mimg *m)
{
	const pkt_rayc *rc = &s->rc;
	float g = fp_gamma(s->fpt, 5);
	uint64_t enter = 0;
	for (uint64_t b = p->valid; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		const float o[3] = {p->ox[i], p->oy[i], p->oz[i]};
		const float id[3] = {fp_round(s->fpt, rc->idx[i]), fp_round(s->fpt, rc->idy[i]),
		                     fp_round(s->fpt, rc->idz[i])};
		trav_clip_fp(s->fpt, g, &m->bounds, o, id, p->tmax[i], &s->cur.tn[i],
		             &s->cur.tf[i]);
		if (s->cur.tn[i] <= s->cur.tf[i])
			enter |= 1ull << i;
	}
	return enter;
}

uint64_t pkt_trav_begin(trav_state *s, packet *p, const mimg *m, trav_entry *stack, int stack_max)
{
	return pkt_trav_begin_fp(s, p, m, stack, stack_max, NULL);
}

/* trav_begin's first pass: 1/d, the best hit's start (tmax, no triangle)
 * and the clip to the scene box; returns the rays that enter it. */
static uint64_t begin_clip(trav_state *s, packet *p, const mimg *m)
{
	pkt_rayc *rc = &s->rc;
	uint64_t enter = 0;
	const fv zero = fv_set1(0.0f), one = fv_set1(1.0f);
	const fv lo[3] = {fv_set1(m->bounds.lo.x), fv_set1(m->bounds.lo.y),
	                  fv_set1(m->bounds.lo.z)};
	const fv hi[3] = {fv_set1(m->bounds.hi.x), fv_set1(m->bounds.hi.y),
	                  fv_set1(m->bounds.hi.z)};
	for (int g = 0; g < NGROUPS; g++) {
		int o = SIMD_W * g;
		unsigned gb = grp_bits(p->valid, g);
		/* invalid lanes: all-zero constants, empty segment, no hit */
		iv valid = iv_from_bits(gb);
		fv dx = fv_load(p->dx + o), dy = fv_load(p->dy + o), dz = fv_load(p->dz + o);
		fv id[3] = {fv_sel(valid, one / dx, zero), fv_sel(valid, one / dy, zero),
		            fv_sel(valid, one / dz, zero)};
		fv_store(rc->idx + o, id[0]);
		fv_store(rc->idy + o, id[1]);
		fv_store(rc->idz + o, id[2]);
		fv tmax = fv_load(p->tmax + o);
		fv_store(p->t + o, fv_sel(valid, tmax, zero));
		for (int l = 0; l < SIMD_W; l++)
			p->tri[o + l] = PKT_NOHIT;
		/* Clip to the scene box, widened by the error bound. A NaN slab
		 * distance (origin on a face, direction parallel) leaves the
		 * segment open on that axis. */
		fv org[3] = {fv_load(p->ox + o), fv_load(p->oy + o), fv_load(p->oz + o)};
		fv tn = zero, tf = tmax;
		TRAV_UNROLL(3)
		for (int a = 0; a < 3; a++) {
			fv t0 = (lo[a] - org[a]) * id[a], t1 = (hi[a] - org[a]) * id[a];
			fv n = fv_fmin(t0, t1), f = fv_fmax(t0, t1);
			n -= fv_abs(n) * fv_set1(GAMMA3);
			f += fv_abs(f) * fv_set1(GAMMA3);
			tn = fv_sel(n > tn, n, tn);
			tf = fv_sel(f < tf, f, tf);
		}
		tn = fv_sel(valid, tn, fv_set1(INFINITY));
		tf = fv_sel(valid, tf, fv_set1(-INFINITY));
		fv_store(s->cur.tn + o, tn);
		fv_store(s->cur.tf + o, tf);
		enter |= (uint64_t)(iv_bits(tn <= tf) & gb) << o;
	}
	return enter;
}

/* trav_begin's second pass: the intersection constants, Woop's
 * permutation and shear (isect_prepare) of every lane, and the
 * permutation's lane masks merged into mk. */
static void begin_shear(pkt_rayc *rc, const packet *p, uint64_t mk[6])
{
	const fv zero = fv_set1(0.0f);
	for (int g = 0; g < NGROUPS; g++) {
		int o = SIMD_W * g;
		unsigned gb = grp_bits(p->valid, g);
		iv valid = iv_from_bits(gb);
		fv dx = fv_load(p->dx + o), dy = fv_load(p->dy + o), dz = fv_load(p->dz + o);
		/* Woop's permutation, as isect_prepare: kz = dominant axis,
		 * kx, ky the next ones cyclically, swapped when d[kz] < 0 */
		fv ax = fv_abs(dx), ay = fv_abs(dy), az = fv_abs(dz);
		iv xy = ax > ay;
		iv kz0 = xy & (ax > az), kz1 = ~xy & (ay > az), kz2 = ~kz0 & ~kz1;
		fv dkz = sel3(kz0, kz1, dx, dy, dz);
		iv neg = dkz < zero;
		/* unswapped: kx = kz + 1, ky = kz + 2 (mod 3); d[kz] < 0 swaps them */
		iv kx0 = (iv)fv_sel(neg, (fv)kz1, (fv)kz2) & valid;
		iv kx1 = (iv)fv_sel(neg, (fv)kz2, (fv)kz0) & valid;
		iv ky0 = (iv)fv_sel(neg, (fv)kz2, (fv)kz1) & valid;
		iv ky1 = (iv)fv_sel(neg, (fv)kz0, (fv)kz2) & valid;
		fv dkx = sel3(kx0, kx1, dx, dy, dz), dky = sel3(ky0, ky1, dx, dy, dz);
		fv_store(rc->sx + o, fv_sel(valid, dkx / dkz, zero));
		fv_store(rc->sy + o, fv_sel(valid, dky / dkz, zero));
		/* 1 / d[kz] is the one of the three that dkz picks (an invalid
		 * lane's are all zero): five divisions, not six */
		fv_store(rc->sz + o, sel3(kz0, kz1, fv_load(rc->idx + o), fv_load(rc->idy + o),
		                          fv_load(rc->idz + o)));
		kz0 &= valid;
		kz1 &= valid;
		memcpy(rc->kz0 + o, &kz0, sizeof kz0);
		memcpy(rc->kz1 + o, &kz1, sizeof kz1);
		memcpy(rc->kx0 + o, &kx0, sizeof kx0);
		memcpy(rc->kx1 + o, &kx1, sizeof kx1);
		memcpy(rc->ky0 + o, &ky0, sizeof ky0);
		memcpy(rc->ky1 + o, &ky1, sizeof ky1);
		iv ks[6] = {kz0, kz1, kx0, kx1, ky0, ky1};
		/* this loop and the clip's unrolled: gcc's loops kept their
		 * vectors and mk in memory */
		TRAV_UNROLL(6)
		for (int k = 0; k < 6; k++)
			mk[k] |= (uint64_t)iv_bits(ks[k]) << o;
	}
}

/* pkt_trav_begin_fp in two passes over the lane groups: first 1/d, the
 * best hit's start and the clip to the scene box (the rays that enter),
 * then the intersection constants (Woop's permutation and shear). With
 * lazy set and full-precision traversal, a packet that enters nothing
 * stops after the first pass: rc's other constants are then not set, so
 * only a caller that traces nothing after a 0 (pkt_trace_with) asks for
 * it. Half the primary packets of the scanned models' views miss the box
 * (docs/PERFORMANCE.md). */
static uint64_t trav_begin(trav_state *s, packet *p, const mimg *m, trav_entry *stack,
                           int stack_max, const pkt_precision *prec, int lazy)
{
	s->fpt = prec && !prec->trav.full ? &prec->trav : NULL;
	s->fpi = prec && !prec->isect.full ? &prec->isect : NULL;
	s->stack = stack;
	s->stack_max = stack_max;
	s->sp = 0;
	s->shadow = p->type == PKT_SHADOW;
	uint64_t enter = begin_clip(s, p, m), mk[6] = {0};
	s->cur.node = 0;
	s->cur.mask = enter;
	if (lazy && !enter && !s->fpt)
		return 0;
	begin_shear(&s->rc, p, mk);
	uniform_perm(&s->rc, p, mk);
	if (s->fpt) {
		enter = clip_fp(s, p, m);
		s->cur.mask = enter;
	}
	return enter;
}

uint64_t pkt_trav_begin_fp(trav_state *s, packet *p, const mimg *m, trav_entry *stack,
                           int stack_max, const pkt_precision *prec)
{
	return trav_begin(s, p, m, stack, stack_max, prec, 0);
}

/* ---- one traversal step ------------------------------------------------ */

/* Rays of e still worth visiting: entry not beyond their best hit (an
 * occluded shadow ray has t = -inf). */
static uint64_t live_mask(const packet *p, const trav_entry *e)
{
	uint64_t live = 0;
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(e->mask, g);
		if (!gb)
			continue;
		iv keep = fv_load(e->tn + SIMD_W * g) <= fv_load(p->t + SIMD_W * g);
		live |= (uint64_t)(iv_bits(keep) & gb) << (SIMD_W * g);
	}
	return live;
}

int pkt_trav_pops(const trav_state *s, const packet *p)
{
	if (s->cur.mask)
		return 0;
	int k = 0;
	for (int sp = s->sp; sp > 0; sp--) {
		k++;
		if (live_mask(p, &s->stack[sp - 1]))
			break;
	}
	return k;
}

void pkt_trav_next(trav_state *s, packet *p, const mimg *m, trav_result *r)
{
	if (pkt_trav_pop(s, p, r))
		pkt_trav_node(s, p, mimg_nodes(m)[r->node], r);
}

int pkt_trav_pop(trav_state *s, packet *p, trav_result *r)
{
	r->pushed = r->popped = 0;
	/* cur is either fresh from a node step (its rays already filtered) or
	 * empty after a leaf: then pop until an entry has live rays. */
	while (!s->cur.mask) {
		if (s->sp == 0) {
			r->op = TRAV_DONE;
			r->mask = 0;
			r->sp = 0;
			return 0;
		}
		s->sp--;
		r->popped++;
		s->cur.mask = live_mask(p, &s->stack[s->sp]);
		if (s->cur.mask) {
			s->cur.node = s->stack[s->sp].node;
			memcpy(s->cur.tn, s->stack[s->sp].tn, sizeof s->cur.tn);
			memcpy(s->cur.tf, s->stack[s->sp].tf, sizeof s->cur.tf);
		}
	}
	r->node = s->cur.node;
	r->mask = s->cur.mask;
	return 1;
}

void pkt_trav_node(trav_state *s, packet *p, kd_node n, trav_result *r)
{
	if (kd_is_leaf(n)) {
		r->op = TRAV_LEAF;
		r->leaf_first = kd_first(n);
		r->leaf_count = kd_count(n);
		s->cur.mask = 0; /* the next call pops */
		r->sp = s->sp;
		return;
	}
	r->op = TRAV_NODE;
	int axis = kd_axis(n);
	fv split = fv_set1(kd_split(n));
	const float *org = axis == 0 ? p->ox : axis == 1 ? p->oy : p->oz;
	const float *idv = axis == 0 ? s->rc.idx : axis == 1 ? s->rc.idy : s->rc.idz;
	/* The near child is the first active ray's near side; its segments are
	 * written in place into cur, the far child's straight into the next
	 * stack slot (kept only if some ray needs it). A child also drops the
	 * rays whose best hit lies before its entry. */
	int near_below = !signbit(idv[__builtin_ctzll(s->cur.mask)]);
	if (pkt_trav_fault == PKT_FAULT_FAR_FIRST)
		near_below = !near_below;
	trav_entry *far = s->sp < s->stack_max ? &s->stack[s->sp] : &s->spare;
	uint64_t nmask = 0, fmask = 0;
	iv nb = iv_set1(near_below ? -1 : 0);
	if (s->fpt) {
		/* reduced precision: the scalar emulation, lane by lane */
		float gam = fp_gamma(s->fpt, 5), sp = kd_split(n);
		for (uint64_t b = s->cur.mask; b; b &= b - 1) {
			int i = __builtin_ctzll(b);
			float id = fp_round(s->fpt, idv[i]), lo, hi, b_n, b_f, a_n, a_f;
			trav_plane_fp(s->fpt, gam, sp, org[i], id, &lo, &hi);
			trav_cut(!signbit(id), s->cur.tn[i], s->cur.tf[i], lo, hi, &b_n, &b_f, &a_n,
			         &a_f);
			float n_n = near_below ? b_n : a_n, n_f = near_below ? b_f : a_f;
			float f_n = near_below ? a_n : b_n, f_f = near_below ? a_f : b_f;
			s->cur.tn[i] = n_n;
			s->cur.tf[i] = n_f;
			far->tn[i] = f_n;
			far->tf[i] = f_f;
			if (n_n <= n_f && n_n <= p->t[i])
				nmask |= 1ull << i;
			if (f_n <= f_f && f_n <= p->t[i])
				fmask |= 1ull << i;
		}
	}
	for (int g = 0; g < NGROUPS && !s->fpt; g++) {
		unsigned gb = grp_bits(s->cur.mask, g);
		if (!gb)
			continue;
		int o = SIMD_W * g;
		fv tn = fv_load(s->cur.tn + o), tf = fv_load(s->cur.tf + o);
		fv id = fv_load(idv + o);
		fv ts = (split - fv_load(org + o)) * id;
		fv err = fv_abs(ts) * fv_set1(GAMMA3);
		iv nan = ts != ts;
		fv lo = fv_sel(nan, fv_set1(-INFINITY), ts - err);
		fv hi = fv_sel(nan, fv_set1(INFINITY), ts + err);
		iv pos = id > fv_set1(0.0f); /* 1/d is never 0: +inf for d = +0, -inf for -0 */
		/* d >= 0: below is [tn, min(tf, hi)], above [max(tn, lo), tf]; d < 0 mirrored */
		fv b_n = fv_sel(pos, tn, fv_max(tn, lo)), b_f = fv_sel(pos, fv_min(tf, hi), tf);
		fv a_n = fv_sel(pos, fv_max(tn, lo), tn), a_f = fv_sel(pos, tf, fv_min(tf, hi));
		fv n_n = fv_sel(nb, b_n, a_n), n_f = fv_sel(nb, b_f, a_f);
		fv f_n = fv_sel(nb, a_n, b_n), f_f = fv_sel(nb, a_f, b_f);
		fv best = fv_load(p->t + o);
		fv_store(s->cur.tn + o, n_n);
		fv_store(s->cur.tf + o, n_f);
		fv_store(far->tn + o, f_n);
		fv_store(far->tf + o, f_f);
		nmask |= (uint64_t)(iv_bits((n_n <= n_f) & (n_n <= best)) & gb) << o;
		fmask |= (uint64_t)(iv_bits((f_n <= f_f) & (f_n <= best)) & gb) << o;
	}
	uint32_t left = kd_left(n);
	uint32_t nnode = near_below ? left : left + 1, fnode = near_below ? left + 1 : left;
	if (!nmask) {
		/* no ray needs the near child: continue in the far one (rare) */
		s->cur.node = fnode;
		s->cur.mask = fmask;
		memcpy(s->cur.tn, far->tn, sizeof s->cur.tn);
		memcpy(s->cur.tf, far->tf, sizeof s->cur.tf);
	} else {
		/* the stack is full only for a tree deeper than kd_build makes
		 * (damaged node data): the far child is dropped */
		if (fmask && far != &s->spare && pkt_trav_fault != PKT_FAULT_NO_FAR_PUSH) {
			far->node = fnode;
			far->mask = fmask;
			s->sp++;
			r->pushed = 1;
		}
		s->cur.node = nnode;
		s->cur.mask = nmask;
	}
	r->sp = s->sp;
}

/* ---- triangle test, SIMD_W lanes at a time ------------------------------- */

/* Updates lane i's result with a hit (t, bu, bv) on tri_addr by the hit
 * rule; returns 1 when the result changed. */
static inline int take_hit(const trav_state *s, packet *p, int i, float t, float bu, float bv,
                           uint32_t tri_addr)
{
	if (s->shadow) {
		if (t < p->tmax[i] && p->tri[i] == PKT_NOHIT) {
			p->t[i] = -INFINITY; /* occluded: every filter drops it */
			p->tri[i] = tri_addr;
			return 1;
		}
	} else if (isect_better(t, tri_addr, p->t[i], p->tri[i])) {
		p->t[i] = t;
		p->tri[i] = tri_addr;
		p->bu[i] = bu;
		p->bv[i] = bv;
		return 1;
	}
	return 0;
}

/* Reduced-precision intersection: isect_tri_fp per ray, with the ray's
 * permutation and shear exactly as isect_prepare makes them for the
 * single-ray path. */
static uint64_t isect_tri_fp_lanes(const trav_state *s, packet *p, const mimg_tri *tr,
                                   uint64_t mask, uint32_t tri_addr)
{
	const pkt_rayc *rc = &s->rc;
	uint64_t changed = 0;
	for (uint64_t b = mask; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		isect_ray ir;
		ir.kz = rc->kz0[i] ? 0 : rc->kz1[i] ? 1 : 2;
		ir.kx = rc->kx0[i] ? 0 : rc->kx1[i] ? 1 : 2;
		ir.ky = rc->ky0[i] ? 0 : rc->ky1[i] ? 1 : 2;
		ir.sx = rc->sx[i];
		ir.sy = rc->sy[i];
		ir.sz = rc->sz[i];
		float t, bu, bv;
		if (isect_tri_fp(s->fpi, &ir, v3(p->ox[i], p->oy[i], p->oz[i]), tr->v, &t, &bu,
		                 &bv) &&
		    take_hit(s, p, i, t, bu, bv, tri_addr))
			changed |= 1ull << i;
	}
	return changed;
}

uint64_t pkt_isect_tri(trav_state *s, packet *p, const mimg *m, uint64_t mask, uint32_t tri_addr)
{
	return pkt_isect_tri_v(s, p, mimg_tri_at(m, tri_addr), mask, tri_addr);
}

uint64_t pkt_isect_tri_v(trav_state *s, packet *p, const mimg_tri *tr, uint64_t mask,
                         uint32_t tri_addr)
{
	const pkt_rayc *rc = &s->rc;
	uint64_t changed = 0;
	if (s->fpi)
		return isect_tri_fp_lanes(s, p, tr, mask, tri_addr);
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(mask, g);
		if (!gb)
			continue;
		int o8 = SIMD_W * g;
		fv ox = fv_load(p->ox + o8), oy = fv_load(p->oy + o8), oz = fv_load(p->oz + o8);
		iv kz0 = iv_load(rc->kz0 + o8), kz1 = iv_load(rc->kz1 + o8);
		iv kx0 = iv_load(rc->kx0 + o8), kx1 = iv_load(rc->kx1 + o8);
		iv ky0 = iv_load(rc->ky0 + o8), ky1 = iv_load(rc->ky1 + o8);
		fv sx = fv_load(rc->sx + o8), sy = fv_load(rc->sy + o8), sz = fv_load(rc->sz + o8);
		fv vx[3], vy[3], vkz[3];
		if (rc->uniform) /* the same subtractions as below, without the selects */
			isect_v_uniform(rc, o8, tr, sx, sy, vx, vy, vkz);
		else
			for (int k = 0; k < 3; k++) {
				fv ax = fv_set1(tr->v[k][0]) - ox;
				fv ay = fv_set1(tr->v[k][1]) - oy;
				fv az = fv_set1(tr->v[k][2]) - oz;
				vkz[k] = sel3(kz0, kz1, ax, ay, az);
				vx[k] = sel3(kx0, kx1, ax, ay, az) - sx * vkz[k];
				vy[k] = sel3(ky0, ky1, ax, ay, az) - sy * vkz[k];
			}
		fv u, v, w, det, t;
		isect_v_edges(vx, vy, gb, &u, &v, &w);
		unsigned okb = isect_v_inside(u, v, w, gb, &det);
		if (!okb)
			continue;
		okb = isect_v_front(u, v, w, det, sz, vx, vy, vkz, okb, &t);
		fv bu = v / det, bv = w / det;
		for (unsigned k = okb; k; k &= k - 1) {
			int l = __builtin_ctz(k), i = o8 + l;
			if (s->shadow) {
				if (t[l] < p->tmax[i] && p->tri[i] == PKT_NOHIT) {
					p->t[i] = -INFINITY; /* occluded: every filter drops it */
					p->tri[i] = tri_addr;
					changed |= 1ull << i;
				}
			} else if (isect_better(t[l], tri_addr, p->t[i], p->tri[i])) {
				p->t[i] = t[l];
				p->tri[i] = tri_addr;
				p->bu[i] = bu[l];
				p->bv[i] = bv[l];
				changed |= 1ull << i;
			}
		}
	}
	return changed;
}

/* ---- whole traversal ----------------------------------------------------- */

uint64_t pkt_trace(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c)
{
	return pkt_trace_fp(p, m, stack, stack_max, c, NULL);
}

uint64_t pkt_trace_fp(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                      const pkt_precision *prec)
{
	return pkt_trace_cone(p, m, stack, stack_max, c, prec, 0);
}

void pkt_trace_leaf(trav_state *s, packet *p, const mimg *m, uint32_t first, uint32_t count,
                    uint64_t mask, const pkt_cone *cone, trav_counts *c, const pkt_leaf_hooks *hk)
{
	const uint32_t *lists = mimg_lists(m);
	if (hk && hk->prefetch)
		for (uint32_t k = 0; k < count; k++)
			__builtin_prefetch(mimg_tri_at(m, lists[first + k]));
	if (c) {
		c->leaf_visits++;
		c->tri_tests += count;
		c->ray_tri_tests += (uint64_t)count * (uint64_t)__builtin_popcountll(mask);
	}
	for (uint32_t k = 0; k < count && mask; k++) {
		uint32_t ta = lists[first + k];
		const mimg_tri *tr = mimg_tri_at(m, ta);
		if (cone && cone_culls_tri(cone, tr)) {
			if (c) {
				c->cone_culled++;
				c->cone_saved_ray_tests += (uint64_t)__builtin_popcountll(mask);
			}
			continue;
		}
		if (hk && hk->isect)
			hk->isect(s, p, tr, mask, ta);
		else
			pkt_isect_tri_v(s, p, tr, mask, ta);
		if (s->shadow)
			mask = pkt_shadow_open(p, mask);
	}
}

void pkt_trace_run(trav_state *s, packet *p, const mimg *m, const pkt_cone *cone, trav_counts *c)
{
	trav_result r;
	for (;;) {
		pkt_trav_next(s, p, m, &r);
		if (r.op == TRAV_DONE)
			break;
		if (c) {
			c->node_steps++;
			if ((uint64_t)r.sp > c->max_sp)
				c->max_sp = (uint64_t)r.sp;
		}
		if (r.op == TRAV_LEAF)
			pkt_trace_leaf(s, p, m, r.leaf_first, r.leaf_count, r.mask, cone, c, NULL);
	}
}

uint64_t pkt_trace_with(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                        const pkt_precision *prec, int cull, pkt_runner run)
{
	trav_state st;
	uint64_t entered = trav_begin(&st, p, m, stack, stack_max, prec, 1);
	if (!entered)
		return 0;
	pkt_cone cone;
	if (cull) /* the rays that entered the box (seed 004 §4) */
		cone_build(&cone, p, entered);
	if (!run || !run(&st, p, m, cull ? &cone : NULL, entered, c))
		pkt_trace_run(&st, p, m, cull ? &cone : NULL, c);
	return entered;
}

uint64_t pkt_trace_cone(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                        const pkt_precision *prec, int cull)
{
	return pkt_trace_with(p, m, stack, stack_max, c, prec, cull, NULL);
}

/* ---- single-ray path ------------------------------------------------------ */

/* One inner-node step of the single-ray path: moves to the near child
 * (pushing the far one when the ray needs both) and returns 1, or returns 0
 * when the ray needs neither child (the caller pops). */
typedef struct ray_entry {
	uint32_t node;
	float tn, tf;
} ray_entry;

static int ray_step(kd_node n, const float *oa, const float *id, uint32_t *node, float *tn,
                    float *tf, ray_entry *stack, int *sp, const fpfmt *ft, float g)
{
	int axis = kd_axis(n);
	float lo_, hi_;
	if (ft) {
		trav_plane_fp(ft, g, kd_split(n), oa[axis], id[axis], &lo_, &hi_);
	} else {
		float ts = (kd_split(n) - oa[axis]) * id[axis];
		float err = fabsf(ts) * GAMMA3;
		lo_ = ts - err;
		hi_ = ts + err;
		if (ts != ts) {
			lo_ = -INFINITY;
			hi_ = INFINITY;
		}
	}
	int pos = !signbit(id[axis]);
	float b_n = pos ? *tn : (*tn > lo_ ? *tn : lo_), b_f = pos ? (*tf < hi_ ? *tf : hi_) : *tf;
	float a_n = pos ? (*tn > lo_ ? *tn : lo_) : *tn, a_f = pos ? *tf : (*tf < hi_ ? *tf : hi_);
	int bin = b_n <= b_f, ain = a_n <= a_f;
	uint32_t left = kd_left(n);
	/* near child first: below when d >= 0 */
	uint32_t nn = pos ? left : left + 1, fn = pos ? left + 1 : left;
	int nin = pos ? bin : ain, fin = pos ? ain : bin;
	float nn_n = pos ? b_n : a_n, nn_f = pos ? b_f : a_f;
	float fn_n = pos ? a_n : b_n, fn_f = pos ? a_f : b_f;
	if (!nin && !fin)
		return 0;
	if (nin && fin)
		stack[(*sp)++] = (ray_entry){fn, fn_n, fn_f};
	*node = nin ? nn : fn;
	*tn = nin ? nn_n : fn_n;
	*tf = nin ? nn_f : fn_f;
	return 1;
}

/* The single-ray walk: the ray clipped to the scene box, then near child
 * first with the far one stacked; leaf() tests a leaf's list against *h
 * and returns 1 to end the walk (an occluder found). Entries that start
 * beyond the best hit are skipped. ray_trace_fp inlines it with its own
 * leaf test; ray_trace_leaves hands it another (tlflat.c). */
static inline __attribute__((always_inline)) ray_hit ray_walk(const mimg *m, vec3 o, vec3 d,
                                                              float tmax, trav_counts *c,
                                                              const fpfmt *ft, ray_leaf_fn leaf,
                                                              void *ctx)
{
	ray_hit h = {tmax, 0, 0, PKT_NOHIT, 0};
	float oa[3] = {o.x, o.y, o.z};
	float id[3] = {1.0f / d.x, 1.0f / d.y, 1.0f / d.z};
	float lo[3] = {m->bounds.lo.x, m->bounds.lo.y, m->bounds.lo.z};
	float hi[3] = {m->bounds.hi.x, m->bounds.hi.y, m->bounds.hi.z};
	float tn = 0.0f, tf = tmax, g = 0.0f;
	if (ft) {
		g = fp_gamma(ft, 5);
		for (int a = 0; a < 3; a++)
			id[a] = fp_round(ft, id[a]);
		trav_clip_fp(ft, g, &m->bounds, oa, id, tmax, &tn, &tf);
	}
	for (int a = 0; a < 3 && !ft; a++) {
		float t0 = (lo[a] - oa[a]) * id[a], t1 = (hi[a] - oa[a]) * id[a];
		float n = fminf(t0, t1), f = fmaxf(t0, t1);
		n -= fabsf(n) * GAMMA3;
		f += fabsf(f) * GAMMA3;
		if (n > tn)
			tn = n;
		if (f < tf)
			tf = f;
	}
	if (!(tn <= tf))
		return h;
	const kd_node *nodes = mimg_nodes(m);
	const uint32_t *lists = mimg_lists(m);
	ray_entry stack[PKT_STACK_MAX];
	int sp = 0;
	uint32_t node = 0;
	for (;;) {
		kd_node n = nodes[node];
		if (c)
			c->node_steps++;
		if (kd_is_leaf(n)) {
			if (c) {
				c->leaf_visits++;
				c->tri_tests += kd_count(n);
				c->ray_tri_tests += kd_count(n);
			}
			if (leaf(ctx, lists + kd_first(n), kd_count(n), &h))
				return h;
		} else {
			if (ray_step(n, oa, id, &node, &tn, &tf, stack, &sp, ft, g))
				continue;
		}
		/* pop, skipping entries that start beyond the best hit */
		do {
			if (sp == 0)
				return h;
			sp--;
		} while (stack[sp].tn > h.t);
		node = stack[sp].node;
		tn = stack[sp].tn;
		tf = stack[sp].tf;
	}
}

typedef struct ray_tris {
	const mimg *m;
	const fpfmt *fi;
	isect_ray ir;
	vec3 o;
	float tmax;
	int any_hit;
} ray_tris;

/* ray_trace_fp's leaf: the image's own triangles by the scalar test. */
static inline int ray_leaf_tris(void *ctx, const uint32_t *list, uint32_t count, ray_hit *h)
{
	const ray_tris *r = ctx;
	for (uint32_t k = 0; k < count; k++) {
		uint32_t ta = list[k];
		float t, bu, bv;
		const float(*tv)[3] = mimg_tri_at(r->m, ta)->v;
		if ((r->fi ? isect_tri_fp(r->fi, &r->ir, r->o, tv, &t, &bu, &bv)
		           : isect_tri(&r->ir, r->o, tv, &t, &bu, &bv)) &&
		    isect_take(h, t, bu, bv, ta, 0, r->any_hit, r->tmax))
			return 1;
	}
	return 0;
}

ray_hit ray_trace(const mimg *m, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c)
{
	return ray_trace_fp(m, o, d, tmax, any_hit, c, NULL);
}

ray_hit ray_trace_fp(const mimg *m, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c,
                     const pkt_precision *prec)
{
	const fpfmt *ft = prec && !prec->trav.full ? &prec->trav : NULL;
	ray_tris r = {
	    m, prec && !prec->isect.full ? &prec->isect : NULL, isect_prepare(d), o, tmax, any_hit};
	return ray_walk(m, o, d, tmax, c, ft, ray_leaf_tris, &r);
}

ray_hit ray_trace_leaves(const mimg *m, vec3 o, vec3 d, float tmax, trav_counts *c,
                         ray_leaf_fn leaf, void *ctx)
{
	return ray_walk(m, o, d, tmax, c, NULL, leaf, ctx);
}
