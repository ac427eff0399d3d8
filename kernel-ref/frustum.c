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
#include <stddef.h>

#include "kernel-ref/cone.h"
#include "kernel-ref/isect_v.h"
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
	int one; /* one origin (olo = ohi on every axis): fru_plane's short way */
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

#if SIMD_W == 8 && defined(__AVX__)
/* the lanes' smaller (most 0) or larger (most 1) of a and b */
static inline __m128 m128_ext(__m128 a, __m128 b, int most)
{
	return most ? _mm_max_ps(a, b) : _mm_min_ps(a, b);
}
#endif

/* The smallest (most 0) or largest (most 1) lane of v (no NaN lanes): a
 * reduction tree with AVX-512, or with AVX the halves, then the quarters,
 * then the last pair; else lane by lane. */
static inline float fv_hext(fv v, int most)
{
#if SIMD_W == 16 && defined(__AVX512F__)
	__m512 x;
	memcpy(&x, &v, sizeof x);
	return most ? _mm512_reduce_max_ps(x) : _mm512_reduce_min_ps(x);
#elif SIMD_W == 8 && defined(__AVX__)
	__m256 x;
	memcpy(&x, &v, sizeof x);
	__m128 h = m128_ext(_mm256_castps256_ps128(x), _mm256_extractf128_ps(x, 1), most);
	h = m128_ext(h, _mm_movehl_ps(h, h), most);
	h = m128_ext(h, _mm_movehdup_ps(h), most);
	return _mm_cvtss_f32(h);
#else
	float a = v[0];
	for (int l = 1; l < SIMD_W; l++)
		a = (most ? v[l] > a : v[l] < a) ? v[l] : a;
	return a;
#endif
}
static inline float fv_hmin(fv v)
{
	return fv_hext(v, 0);
}
static inline float fv_hmax(fv v)
{
	return fv_hext(v, 1);
}

#define FRU_RANGES 6 /* in one pass (fru_setup) */

/* A short loop over vectors unrolled by gcc (its rolled loop kept them in
 * memory); other compilers decide themselves. */
#if defined(__GNUC__) && !defined(__clang__)
#define FRU_PRAGMA(x) _Pragma(#x)
#define FRU_UNROLL(n) FRU_PRAGMA(GCC unroll n)
#else
#define FRU_UNROLL(n)
#endif

/* Smallest and largest x[j][i] over the lanes i of mask, for j <
 * FRU_RANGES, in one pass over the lane groups; returns nonzero when one
 * is NaN (the bounds are then meaningless). A group with all lanes in
 * mask needs no selects. Which zero a range of +0 and -0 ends on does not
 * matter: the bounds only decide shortcuts (file comment), by value. */
static unsigned lane_ranges(const float *const *x, uint64_t mask, float *lo, float *hi)
{
	const fv pinf = fv_set1(INFINITY), ninf = fv_set1(-INFINITY);
	fv mn[FRU_RANGES], mx[FRU_RANGES];
	FRU_UNROLL(6)
	for (int j = 0; j < FRU_RANGES; j++) {
		mn[j] = pinf;
		mx[j] = ninf;
	}
	unsigned nan = 0;
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(mask, g);
		if (!gb)
			continue;
		iv on = iv_from_bits(gb);
		FRU_UNROLL(6)
		for (int j = 0; j < FRU_RANGES; j++) {
			fv v = fv_load(x[j] + SIMD_W * g), vl = v, vh = v;
			if (gb != SIMD_MASK) {
				vl = fv_sel(on, v, pinf);
				vh = fv_sel(on, v, ninf);
			}
			nan |= iv_bits(v != v) & gb;
			mn[j] = fv_min(mn[j], vl);
			mx[j] = fv_max(mx[j], vh);
		}
	}
	FRU_UNROLL(6)
	for (int j = 0; j < FRU_RANGES; j++) {
		lo[j] = fv_hmin(mn[j]);
		hi[j] = fv_hmax(mx[j]);
	}
	return nan;
}

/* The smallest entry and the largest exit distance of e's rays in mask
 * (lane_ranges' two of the four that are used). */
static void seg_bounds(const trav_entry *e, uint64_t mask, float *tn, float *tf)
{
	const fv pinf = fv_set1(INFINITY), ninf = fv_set1(-INFINITY);
	fv mn = pinf, mx = ninf;
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(mask, g);
		if (!gb)
			continue;
		fv n = fv_load(e->tn + SIMD_W * g), f = fv_load(e->tf + SIMD_W * g);
		if (gb != SIMD_MASK) {
			iv on = iv_from_bits(gb);
			n = fv_sel(on, n, pinf);
			f = fv_sel(on, f, ninf);
		}
		mn = fv_min(mn, n);
		mx = fv_max(mx, f);
	}
	*tn = fv_hmin(mn);
	*tf = fv_hmax(mx);
}

/* Fills b from the state pkt_trav_begin_fp left; 0 when no axis can take
 * the packet step (or a ray has a NaN origin or direction). */
static int fru_setup(fru_box *b, const trav_state *s, const packet *p, uint64_t entered)
{
	const float *id[3] = {s->rc.idx, s->rc.idy, s->rc.idz};
	const float *x[FRU_RANGES] = {s->rc.idx, s->rc.idy, s->rc.idz, p->ox, p->oy, p->oz};
	float lo[FRU_RANGES], hi[FRU_RANGES];
	unsigned nan = lane_ranges(x, entered, lo, hi);
	int any = 0;
	b->one = 1;
	for (int a = 0; a < 3; a++) {
		b->idlo[a] = lo[a];
		b->idhi[a] = hi[a];
		b->olo[a] = lo[3 + a];
		b->ohi[a] = hi[3 + a];
		b->pos[a] = b->idlo[a] > 0.0f;
		b->ok[a] =
		    b->pos[a] ? b->idhi[a] < INFINITY : b->idhi[a] < 0.0f && b->idlo[a] > -INFINITY;
		any |= b->ok[a];
		b->one &= b->olo[a] == b->ohi[a];
		if (fru_fault == FRU_FAULT_ONE_DIRECTION) {
			int first = __builtin_ctzll(entered);
			b->idlo[a] = b->idhi[a] = id[a][first];
		}
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
	float tl, th;
	if (b->one) { /* clo = chi: the four products are two */
		float c = split - b->olo[axis];
		float p0 = c * b->idlo[axis], p1 = c * b->idhi[axis];
		tl = mn2(p0, p1);
		th = mx2(p0, p1);
	} else {
		float clo = split - b->ohi[axis], chi = split - b->olo[axis];
		float p0 = clo * b->idlo[axis], p1 = clo * b->idhi[axis];
		float p2 = chi * b->idlo[axis], p3 = chi * b->idhi[axis];
		tl = mn2(mn2(p0, p1), mn2(p2, p3));
		th = mx2(mx2(p0, p1), mx2(p2, p3));
	}
	if (!(fabsf(tl) < INFINITY && fabsf(th) < INFINITY)) {
		*lo = -INFINITY;
		*hi = INFINITY;
		return;
	}
	*lo = tl - fabsf(tl) * FRU_MARGIN;
	*hi = th + fabsf(th) * FRU_MARGIN;
}

/* traverse.c's gamma(3): the per-ray widening of a split distance */
#define FRU_GAMMA3 (3.0f * 0x1p-24f / (1.0f - 3.0f * 0x1p-24f))

/* The walk's own state (fru_walk). The segments [tn_i, tf_i] of the node
 * being worked on and of each stack entry live in buffers that change
 * hands instead of being copied: a pop or a step into the far child only
 * (pkt_trav_pop's and pkt_trav_node's copies of 512 bytes) swaps the
 * current buffer with the entry's. The buffers are the caller's stack
 * entries, the state's cur and its spare (the far child's scratch when
 * the stack is full, as in pkt_trav_node). */
typedef struct fru_entry {
	uint32_t node;
	uint64_t mask;
	trav_entry *seg; /* this slot's buffer: its tn and tf */
	float bt, bf;    /* bounds of the entry's segments */
} fru_entry;

typedef struct fru_walker {
	const fru_box *b;
	trav_state *s; /* the rays' constants (rc), shadow flag and buffers */
	packet *p;
	fru_entry stk[PKT_STACK_MAX];
	int sp;
	int nseg; /* stk[0 .. nseg-1] have their buffers (fru_step gives them) */
	uint32_t node;
	uint64_t mask;
	trav_entry *cur, *spare; /* the current node's segments; the scratch */
	float tn, tf;            /* bounds of the current segments */
} fru_walker;

static inline void swap_seg(trav_entry **a, trav_entry **b)
{
	trav_entry *t = *a;
	*a = *b;
	*b = t;
}

/* Rays of an entry still worth visiting: those whose entry distance is
 * not beyond their best hit (traverse.c's live_mask). Every lane group is
 * compared, active or not (a branch per group, taken at random with
 * sparse masks, cost more than the compares; fru_lanes likewise). */
static uint64_t fru_live(const packet *p, const trav_entry *seg, uint64_t mask)
{
	if (fru_fault == FRU_FAULT_POP_ALL)
		return mask;
	uint64_t live = 0;
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(mask, g);
		iv keep = fv_load(seg->tn + SIMD_W * g) <= fv_load(p->t + SIMD_W * g);
		live |= (uint64_t)(iv_bits(keep) & gb) << (SIMD_W * g);
	}
	return live;
}

/* pkt_trav_pop: pops until an entry has live rays; 0 when none is left.
 * The popped entry's buffer becomes the current one (no copy), and its
 * bounds the current bounds (a popped entry's rays are a subset). */
static int fru_pop(fru_walker *w)
{
	if (w->mask)
		return 1;
	for (;;) {
		if (w->sp == 0)
			return 0;
		fru_entry *e = &w->stk[--w->sp];
		w->mask = fru_live(w->p, e->seg, e->mask);
		if (w->mask)
			break;
	}
	fru_entry *e = &w->stk[w->sp];
	w->node = e->node;
	w->tn = e->bt;
	w->tf = e->bf;
	if (fru_fault != FRU_FAULT_STALE_SEGMENTS)
		swap_seg(&w->cur, &e->seg);
	return 1;
}

/* pkt_trav_node's full-precision lane arithmetic for the rays of w->mask
 * on the inner node n, near child below when near_below: the near
 * child's segments written in place, the far child's into far; returns
 * the near child's live rays and sets *fmask to the far child's. Where
 * every ray's 1/d on the axis has one sign (uni) both signs give the
 * near child [tn, min(tf, hi)] and the far one [max(tn, lo), tf] (the
 * per-lane selects, resolved once): the same values, fewer operations. */
static uint64_t fru_lanes(fru_walker *w, kd_node n, int near_below, int uni, trav_entry *far,
                          uint64_t *fmask)
{
	int axis = kd_axis(n);
	const packet *p = w->p;
	const float *org = axis == 0 ? p->ox : axis == 1 ? p->oy : p->oz;
	const float *idv = axis == 0 ? w->s->rc.idx : axis == 1 ? w->s->rc.idy : w->s->rc.idz;
	fv split = fv_set1(kd_split(n));
	iv nb = iv_set1(near_below ? -1 : 0);
	uint64_t nm = 0, fm = 0;
	if (uni && split[0] == split[0]) {
		/* every 1/d finite and of one sign, every origin and the split
		 * finite (fru_setup): no distance is NaN, and a ray of the mask
		 * enters its node no later than its best hit (fru_live at each
		 * pop, the far test below at each step), which the near child
		 * keeps */
		for (int g = 0; g < NGROUPS; g++) {
			unsigned gb = grp_bits(w->mask, g);
			int o = SIMD_W * g;
			fv tn = fv_load(w->cur->tn + o), tf = fv_load(w->cur->tf + o);
			fv ts = (split - fv_load(org + o)) * fv_load(idv + o);
			fv err = fv_abs(ts) * fv_set1(FRU_GAMMA3);
			fv n_f = fv_min(tf, ts + err), f_n = fv_max(tn, ts - err);
			fv_store(w->cur->tf + o, n_f);
			fv_store(far->tn + o, f_n);
			fv_store(far->tf + o, tf);
			fv best = fv_load(p->t + o);
			nm |= (uint64_t)(iv_bits(tn <= n_f) & gb) << o;
			fm |= (uint64_t)(iv_bits((f_n <= tf) & (f_n <= best)) & gb) << o;
		}
		*fmask = fm;
		return nm;
	}
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(w->mask, g);
		int o = SIMD_W * g;
		fv tn = fv_load(w->cur->tn + o), tf = fv_load(w->cur->tf + o);
		fv id = fv_load(idv + o);
		fv ts = (split - fv_load(org + o)) * id;
		fv err = fv_abs(ts) * fv_set1(FRU_GAMMA3);
		iv nan = ts != ts;
		fv lo = fv_sel(nan, fv_set1(-INFINITY), ts - err);
		fv hi = fv_sel(nan, fv_set1(INFINITY), ts + err);
		fv n_n, n_f, f_n, f_f;
		if (uni) {
			n_n = tn;
			n_f = fv_min(tf, hi);
			f_n = fv_max(tn, lo);
			f_f = tf;
		} else {
			iv pos = id > fv_set1(0.0f);
			fv b_n = fv_sel(pos, tn, fv_max(tn, lo)),
			   b_f = fv_sel(pos, fv_min(tf, hi), tf);
			fv a_n = fv_sel(pos, fv_max(tn, lo), tn),
			   a_f = fv_sel(pos, tf, fv_min(tf, hi));
			n_n = fv_sel(nb, b_n, a_n), n_f = fv_sel(nb, b_f, a_f);
			f_n = fv_sel(nb, a_n, b_n), f_f = fv_sel(nb, a_f, b_f);
			fv_store(w->cur->tn + o, n_n);
		}
		fv best = fv_load(p->t + o);
		fv_store(w->cur->tf + o, n_f);
		fv_store(far->tn + o, f_n);
		fv_store(far->tf + o, f_f);
		nm |= (uint64_t)(iv_bits((n_n <= n_f) & (n_n <= best)) & gb) << o;
		fm |= (uint64_t)(iv_bits((f_n <= f_f) & (f_n <= best)) & gb) << o;
	}
	*fmask = fm;
	return nm;
}

/* One inner-node step on n: pkt_trav_node with the packet shortcut. When
 * the plane's distances [lo, hi] lie beyond every segment (lo > tf: the
 * near child only) or before it (hi < tn: the far child only), the
 * per-lane step would leave every segment and the mask as they are (file
 * comment), so only the node changes. Otherwise the lanes step
 * (fru_lanes): the near child next, the far child pushed when some ray
 * needs it, or entered when no ray needs the near one. Either way the
 * bounds follow the child without a pass over the lanes: the near
 * child's segments lie within [tn, min(tf, hi)], the far child's within
 * [max(tn, lo), tf]. Returns the far child's node when it was pushed,
 * else UINT32_MAX. */
static uint32_t fru_step(fru_walker *w, kd_node n)
{
	const fru_box *b = w->b;
	int axis = kd_axis(n);
	float lo = -INFINITY, hi = INFINITY;
	if (b->ok[axis])
		fru_plane(b, axis, kd_split(n), &lo, &hi);
	uint32_t left = kd_left(n), near = b->pos[axis] ? left : left + 1;
	uint32_t far = b->pos[axis] ? left + 1 : left;
	if (lo > w->tf) { /* the near child only */
		w->node = near;
		return UINT32_MAX;
	}
	if (hi < w->tn) { /* the far child only */
		w->node = fru_fault == FRU_FAULT_ALWAYS_NEAR ? near : far;
		return UINT32_MAX;
	}
	/* one sign on the axis: the near side is the packet's; else, as
	 * pkt_trav_node, the first active ray's */
	const float *idv = axis == 0 ? w->s->rc.idx : axis == 1 ? w->s->rc.idy : w->s->rc.idz;
	int near_below = b->ok[axis] ? b->pos[axis] : !signbit(idv[__builtin_ctzll(w->mask)]);
	uint32_t nnode = near_below ? left : left + 1, fnode = near_below ? left + 1 : left;
	int room = w->sp < w->s->stack_max;
	if (room && w->sp == w->nseg) /* the stack's first use of this slot */
		w->stk[w->nseg++].seg = &w->s->stack[w->sp];
	trav_entry *fseg = room ? w->stk[w->sp].seg : w->spare;
	uint64_t fmask, nmask = fru_lanes(w, n, near_below, b->ok[axis], fseg, &fmask);
	float ftn = mx2(w->tn, lo), ntf = mn2(w->tf, hi), otf = w->tf;
	uint32_t pushed = UINT32_MAX;
	if (!nmask) { /* no ray needs the near child: continue in the far one (rare) */
		w->node = fnode;
		w->mask = fmask;
		swap_seg(&w->cur, room ? &w->stk[w->sp].seg : &w->spare);
	} else {
		if (fmask && room) { /* a full stack (damaged tree) drops the far child */
			fru_entry *e = &w->stk[w->sp++];
			e->node = fnode;
			e->mask = fmask;
			e->bt = ftn;
			e->bf = otf;
			pushed = fnode;
		}
		w->node = nnode;
		w->mask = nmask;
	}
	if (w->node == near)
		w->tf = ntf;
	else
		w->tn = ftn;
	return pushed;
}

/* pkt_isect_tri_v for a packet whose rays share one axis permutation
 * (pkt_rayc.uniform, full precision), the same operations in the same
 * order: the barycentrics' divisions are left to the lanes whose hit is
 * taken (a division is correctly rounded, in a lane or alone), which the
 * packet test spends on every lane of a group with a candidate. With the
 * image m (non-NULL), a triangle whose hit is taken has its shading
 * record fetched ahead for the shader. */
static inline void fru_isect_in(trav_state *s, packet *p, const mimg_tri *tr, uint64_t mask,
                                uint32_t tri_addr, const mimg *m)
{
	int took = 0;
	const pkt_rayc *rc = &s->rc;
	for (int g = 0; g < NGROUPS; g++) {
		unsigned gb = grp_bits(mask, g);
		if (!gb)
			continue;
		int o = SIMD_W * g;
		fv sx = fv_load(rc->sx + o), sy = fv_load(rc->sy + o);
		fv vx[3], vy[3], vkz[3], u, v, w;
		isect_v_uniform(rc, o, tr, sx, sy, vx, vy, vkz);
		isect_v_edges(vx, vy, gb, &u, &v, &w);
		fv det, t;
		unsigned okb = isect_v_inside(u, v, w, gb, &det);
		if (!okb)
			continue;
		okb = isect_v_front(u, v, w, det, fv_load(rc->sz + o), vx, vy, vkz, okb, &t);
		for (unsigned k = okb; k; k &= k - 1) {
			int l = __builtin_ctz(k), i = o + l;
			if (s->shadow) {
				if (t[l] < p->tmax[i] && p->tri[i] == PKT_NOHIT) {
					p->t[i] = -INFINITY; /* occluded: every filter drops it */
					p->tri[i] = tri_addr;
				}
			} else if (isect_better(t[l], tri_addr, p->t[i], p->tri[i])) {
				took = 1;
				p->t[i] = t[l];
				p->tri[i] = tri_addr;
				p->bu[i] = fru_fault == FRU_FAULT_BARY_SWAP ? w[l] / det[l]
				                                            : v[l] / det[l];
				p->bv[i] = w[l] / det[l];
			}
		}
	}
	/* the shader reads the hit triangle's shading record: fetched ahead */
	if (m && took) {
		uint64_t a = mimg_shade_addr(m, mimg_tri_index(m, tri_addr));
		if (a < m->size)
			__builtin_prefetch(m->bytes + a);
	}
}

/* fru_isect_in as pkt_trace_leaf's hook (with cone culling), which has
 * no image at hand for the shading record's fetch. */
static void fru_isect(trav_state *s, packet *p, const mimg_tri *tr, uint64_t mask,
                      uint32_t tri_addr)
{
	fru_isect_in(s, p, tr, mask, tri_addr, NULL);
}

int fru_tri_path = FRU_TRI_AUTO;

/* Up to SIMD_W of a leaf's triangles, one per lane: each corner's
 * coordinates in the packet's axis permutation (pkt_rayc's ukx, uky,
 * ukz); the lanes past the chunk's last triangle are off (on). */
typedef struct fru_tris {
	fv x[3], y[3], z[3];
	uint32_t addr[SIMD_W];
	unsigned on; /* the lanes holding a triangle of the chunk */
} fru_tris;

/* fru_gather lane by lane, the lanes that are off holding list[0]. */
static void fru_gather_lanes(fru_tris *g, const pkt_rayc *rc, const mimg *m, const uint32_t *list,
                             int n)
{
	float b[9][SIMD_W];
	for (int l = 0; l < SIMD_W; l++) {
		uint32_t a = list[l < n ? l : 0];
		const mimg_tri *tr = mimg_tri_at(m, a);
		g->addr[l] = a;
		for (int k = 0; k < 3; k++) {
			b[k][l] = tr->v[k][rc->ukx];
			b[3 + k][l] = tr->v[k][rc->uky];
			b[6 + k][l] = tr->v[k][rc->ukz];
		}
	}
	for (int k = 0; k < 3; k++) {
		g->x[k] = fv_load(b[k]);
		g->y[k] = fv_load(b[3 + k]);
		g->z[k] = fv_load(b[6 + k]);
	}
}

/* The triangles list[0 .. n-1] (0 < n <= SIMD_W) into g's lanes: with
 * AVX-512 or AVX2 nine gathers from the image, the addresses being the
 * gathers' byte offsets (an image of up to 2 GB: the offsets are signed),
 * the lanes that are off zero; else lane by lane (dragon2's primary frame
 * took 52 ms with the lanes filled one by one, 49 with the gathers:
 * docs/PERFORMANCE.md, session 46). */
_Static_assert(offsetof(mimg_tri, v) == 0 && sizeof(mimg_tri) == 9 * sizeof(float),
               "fru_gather reads corner k's axis a at byte 4 * (3k + a) of a triangle's "
               "record, which starts at its address (mimg_tri_at)");

static void fru_gather(fru_tris *g, const pkt_rayc *rc, const mimg *m, const uint32_t *list, int n)
{
	g->on = n == SIMD_W ? SIMD_MASK : (1u << n) - 1u;
	const int ax[3] = {rc->ukx, rc->uky, rc->ukz};
	fv *dst[3] = {g->x, g->y, g->z};
	if (m->size > (uint64_t)INT32_MAX) {
		fru_gather_lanes(g, rc, m, list, n);
		return;
	}
#if SIMD_W == 16 && defined(__AVX512F__)
	__mmask16 on = (__mmask16)g->on;
	__m512i idx = _mm512_maskz_loadu_epi32(on, list);
	_mm512_storeu_si512(g->addr, idx);
	FRU_UNROLL(9)
	for (int c = 0; c < 9; c++) { /* corner c % 3, axis ax[c / 3] */
		__m512 v = _mm512_mask_i32gather_ps(_mm512_setzero_ps(), on, idx,
		                                    m->bytes + 4 * (3 * (c % 3) + ax[c / 3]), 1);
		memcpy(&dst[c / 3][c % 3], &v, sizeof v);
	}
#elif SIMD_W == 8 && defined(__AVX2__)
	iv onv = iv_from_bits(g->on);
	__m256i idx, msk;
	for (int l = 0; l < SIMD_W; l++)
		g->addr[l] = l < n ? list[l] : 0;
	memcpy(&idx, g->addr, sizeof idx);
	memcpy(&msk, &onv, sizeof msk);
	FRU_UNROLL(9)
	for (int c = 0; c < 9; c++) {
		const float *base = (const float *)(m->bytes + 4 * (3 * (c % 3) + ax[c / 3]));
		__m256 v = _mm256_mask_i32gather_ps(_mm256_setzero_ps(), base, idx,
		                                    _mm256_castsi256_ps(msk), 1);
		memcpy(&dst[c / 3][c % 3], &v, sizeof v);
	}
#else
	(void)ax;
	(void)dst;
	fru_gather_lanes(g, rc, m, list, n);
#endif
}

/* Ray i against g's triangles, lane by lane: for each (ray, triangle)
 * pair the functions fru_isect_in runs (isect_v_shear, as
 * isect_v_uniform calls it, isect_v_edges, isect_v_inside and
 * isect_v_front), with the ray's constants broadcast and the triangles'
 * corners in the lanes, so the same floats. Returns
 * the lanes hit in front of the origin, with their t, edge functions v,
 * w and determinant. */
static inline unsigned fru_ray_tris(const pkt_rayc *rc, int i, const fru_tris *g, fv *t, fv *v,
                                    fv *w, fv *det)
{
	fv okx = fv_set1(rc->okx[i]), oky = fv_set1(rc->oky[i]), okz = fv_set1(rc->okz[i]);
	fv sx = fv_set1(rc->sx[i]), sy = fv_set1(rc->sy[i]);
	fv vx[3], vy[3], vkz[3], u;
	FRU_UNROLL(3)
	for (int k = 0; k < 3; k++)
		isect_v_shear(g->x[k], g->y[k], g->z[k], okx, oky, okz, sx, sy, &vx[k], &vy[k],
		              &vkz[k]);
	isect_v_edges(vx, vy, g->on, &u, v, w);
	unsigned okb = isect_v_inside(u, *v, *w, g->on, det);
	if (!okb)
		return 0;
	return isect_v_front(u, *v, *w, *det, fv_set1(rc->sz[i]), vx, vy, vkz, okb, t);
}

/* Ray i's hits okb on g's triangles taken as fru_isect_in takes them:
 * a shadow ray records its first occluder in the leaf's order (the
 * lowest lane: the per-triangle loop stops a ray at its first); any other
 * ray the best hit by isect_better, a total order, so whichever order the
 * lanes are taken in, with its barycentrics divided once. Returns the
 * lane bit of the taken hit of a non-shadow ray, else 0. */
static inline unsigned fru_take_tris(const trav_state *s, packet *p, int i, const fru_tris *g,
                                     unsigned okb, fv t, fv v, fv w, fv det)
{
	if (s->shadow) {
		okb &= iv_bits(t < fv_set1(p->tmax[i]));
		if (okb && p->tri[i] == PKT_NOHIT) {
			int l = fru_fault == FRU_FAULT_TRI_SHADOW_LAST ? 31 - __builtin_clz(okb)
			                                               : __builtin_ctz(okb);
			p->t[i] = -INFINITY; /* occluded: every filter drops it */
			p->tri[i] = g->addr[l];
		}
		return 0;
	}
	int b = -1;
	for (unsigned k = okb; k; k &= k - 1) {
		int l = __builtin_ctz(k);
		if (isect_better(t[l], g->addr[l], p->t[i], p->tri[i])) {
			p->t[i] = t[l];
			p->tri[i] = g->addr[l];
			b = l;
		}
	}
	if (b < 0)
		return 0;
	p->bu[i] = fru_fault == FRU_FAULT_BARY_SWAP ? w[b] / det[b] : v[b] / det[b];
	p->bv[i] = w[b] / det[b];
	return 1u << b;
}

/* fru_leaf's test of the leaf's triangles list[0 .. count-1] for the few
 * rays of mask: triangle-parallel, each ray against SIMD_W triangles at
 * once (fru_ray_tris), where the per-triangle loop spends a lane group
 * on each triangle for each group with an active ray, most of its lanes
 * idle. The same hits (fru_take_tris); a shadow ray occluded in one
 * chunk of triangles is not tested against the next. */
static void fru_leaf_tris(trav_state *s, packet *p, const mimg *m, const uint32_t *list,
                          uint32_t count, uint64_t mask)
{
	uint32_t step = fru_fault == FRU_FAULT_TRI_ONE_CHUNK ? count : SIMD_W;
	for (uint32_t j0 = 0; j0 < count && mask; j0 += step) {
		fru_tris g;
		fru_gather(&g, &s->rc, m, list + j0,
		           count - j0 < SIMD_W ? (int)(count - j0) : SIMD_W);
		unsigned took = 0;
		for (uint64_t r = mask; r; r &= r - 1) {
			int i = __builtin_ctzll(r);
			fv t, v, w, det;
			unsigned okb = fru_ray_tris(&s->rc, i, &g, &t, &v, &w, &det);
			if (okb)
				took |= fru_take_tris(s, p, i, &g, okb, t, v, w, det);
		}
		if (s->shadow) /* an occluded shadow ray stops */
			mask = pkt_shadow_open(p, mask);
		/* the shader reads the hit triangles' shading records: fetched ahead */
		for (; took; took &= took - 1) {
			uint64_t a =
			    mimg_shade_addr(m, mimg_tri_index(m, g.addr[__builtin_ctz(took)]));
			if (a < m->size)
				__builtin_prefetch(m->bytes + a);
		}
	}
}

/* Whether fru_leaf tests a leaf of count triangles for the rays of mask
 * (rays of them) triangle-parallel: where that takes fewer SIMD_W-lane
 * tests, counting a chunk's gathers as one more test (one per ray and
 * one for the gathers for each chunk of SIMD_W triangles), than the
 * per-triangle loop (one per triangle for each lane group with an
 * active ray); fru_tri_path as tests set it. A leaf of one triangle
 * never gains. */
static inline int fru_tri_parallel(uint32_t count, uint64_t mask, int rays)
{
	if (fru_tri_path != FRU_TRI_AUTO)
		return fru_tri_path == FRU_TRI_ALWAYS;
	uint32_t chunks = (count + SIMD_W - 1) / SIMD_W, cost = ((uint32_t)rays + 1) * chunks;
	if (count < 2 || cost >= count * NGROUPS) /* dense: no need to count groups */
		return 0;
	uint32_t groups = 0;
	for (int g = 0; g < NGROUPS; g++)
		groups += grp_bits(mask, g) != 0;
	return cost < count * groups;
}

/* The leaf counts of a walk (trav_counts' fields), kept in locals. */
typedef struct fru_counts {
	uint64_t leaves, tris, ray_tris;
} fru_counts;

/* pkt_trace_leaf for rays of one permutation without cone culling: the
 * same tests in the same order, so the same hits and counts (into k),
 * with fru_isect called directly, or for a sparse packet the same tests
 * triangle-parallel (fru_tri_parallel, fru_leaf_tris); the leaf's
 * triangles fetched ahead. */
static void fru_leaf(trav_state *s, packet *p, const mimg *m, uint32_t first, uint32_t count,
                     uint64_t mask, fru_counts *k)
{
	const uint32_t *lists = mimg_lists(m) + first;
	for (uint32_t j = 0; j < count; j++)
		__builtin_prefetch(mimg_tri_at(m, lists[j]));
	k->leaves++;
	k->tris += count;
	int rays = __builtin_popcountll(mask);
	k->ray_tris += (uint64_t)count * (uint64_t)rays;
	if (fru_tri_parallel(count, mask, rays)) {
		fru_leaf_tris(s, p, m, lists, count, mask);
		return;
	}
	for (uint32_t j = 0; j < count && mask; j++) {
		fru_isect_in(s, p, mimg_tri_at(m, lists[j]), mask, lists[j], m);
		if (s->shadow) /* an occluded shadow ray stops */
			mask = pkt_shadow_open(p, mask);
	}
}

/* pkt_trace_run with the packet shortcut (fru_step), the same pops
 * (fru_pop) and leaves, so the same counts; the segments change hands
 * instead of being copied (fru_walker). The next node's data is fetched
 * ahead: an inner node's children while its lanes step, a pushed far
 * child's node, a leaf's triangles before the first is tested (the
 * scenes' trees and triangles are far larger than the caches). */
static void fru_walk(const fru_box *b, trav_state *s, packet *p, const mimg *m,
                     const pkt_cone *cone, trav_counts *c)
{
	const kd_node *nodes = mimg_nodes(m);
	fru_walker wk; /* stk's entries are set as the stack grows (fru_step) */
	fru_walker *w = &wk;
	w->b = b;
	w->s = s;
	w->p = p;
	w->sp = w->nseg = 0;
	w->cur = &s->cur;
	w->spare = &s->spare;
	w->node = s->cur.node;
	w->mask = s->cur.mask;
	seg_bounds(&s->cur, w->mask, &w->tn, &w->tf);
	/* the counts kept here during the walk (a counter in memory, read
	 * and written at every step, held it up) */
	uint64_t steps = 0;
	int max_sp = 0;
	fru_counts leaf = {0, 0, 0};
	while (fru_pop(w)) {
		kd_node n = nodes[w->node];
		if (kd_is_leaf(n)) {
			/* rays of one permutation take fru_isect (fru_leaf where
			 * no cone culls), their triangles fetched ahead */
			pkt_leaf_hooks hk = {fru_isect, 1};
			if (!cone && s->rc.uniform)
				fru_leaf(s, p, m, kd_first(n), kd_count(n), w->mask, &leaf);
			else
				pkt_trace_leaf(s, p, m, kd_first(n), kd_count(n), w->mask, cone, c,
				               s->rc.uniform ? &hk : NULL);
			w->mask = 0; /* pop next */
		} else {
			__builtin_prefetch(&nodes[kd_left(n)]);
			uint32_t pushed = fru_step(w, n);
			if (pushed != UINT32_MAX)
				__builtin_prefetch(&nodes[pushed]);
		}
		steps++; /* as pkt_trace_run: the depth after the step */
		max_sp = w->sp > max_sp ? w->sp : max_sp;
	}
	if (c) {
		c->node_steps += steps;
		c->leaf_visits += leaf.leaves;
		c->tri_tests += leaf.tris;
		c->ray_tri_tests += leaf.ray_tris;
		c->max_sp = (uint64_t)max_sp > c->max_sp ? (uint64_t)max_sp : c->max_sp;
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
