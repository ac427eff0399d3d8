/*
 * gridtrav.c: traversal of the uniform grid (grid.h): packets slice by
 * slice through their bounding frustum (seed 003 §2.2-2.4), single rays
 * by a 3D DDA (Amanatides and Woo 1987).
 *
 * Exactness. Both paths use kernel-ref's triangle test and hit rule
 * (isect.h: smallest t, ties to the smaller triangle address), so the
 * result is the kd path's when every triangle that could beat or tie the
 * final hit has been tested. Three margins of grid.eps cells (about a
 * thousandth of a cell) make sure of that despite rounding: a triangle is
 * referenced in every cell its box widened by eps touches (grid.c), a
 * frustum's cells in a slice are those of its overlap box widened by eps,
 * and a ray stops only when its hit lies more than eps before the far
 * boundary of what it has visited (the slice's far plane, or the DDA
 * cell's exit), with the hit's t widened by 1e-5 relative. Stopping in a
 * cell on a hit beyond the cell's far boundary would miss a nearer
 * triangle in the next cell (GRID_FAULT_EARLY_STOP shows it).
 *
 * Ties at shared edges need nothing more: the watertight test gives each
 * triangle the same answer whatever cell it is tested from, and the hit
 * rule does not depend on the order of the tests.
 */
#include <math.h>
#include <string.h>

#include "kernel-ref/grid.h"
#include "kernel-ref/gridtrav.h"
#include "kernel-ref/isect.h"

int grid_fault = GRID_FAULT_NONE;

int grid_mbox_skip(const grid *g, grid_mbox *b, uint32_t addr, uint64_t *skips)
{
	if (!g->p.mailbox || !grid_mbox_seen(b, addr))
		return 0;
	if (skips)
		(*skips)++;
	return 1;
}

/* 1 when addr was already tested; records it otherwise. */
int grid_mbox_seen(grid_mbox *b, uint32_t addr)
{
	uint32_t key = addr + 1, mask = (1u << GRID_MBOX_BITS) - 1;
	uint32_t h = (key * 2654435761u) >> (32 - GRID_MBOX_BITS);
	for (;; h = (h + 1) & mask) {
		if (b->slot[h] == key)
			return 1;
		if (b->slot[h] == 0)
			break;
	}
	if (b->used < (3u << GRID_MBOX_BITS) / 4) {
		b->slot[h] = key;
		b->used++;
	}
	return 0;
}

/* The ray clipped to the scene box, exactly as ray_trace clips it. */
int grid_clip_box(const grid *g, vec3 o, vec3 d, float tmax, float *tn, float *tf)
{
	const aabb *b = &g->m->bounds;
	float oa[3] = {o.x, o.y, o.z}, id[3] = {1.0f / d.x, 1.0f / d.y, 1.0f / d.z};
	float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
	*tn = 0.0f;
	*tf = tmax;
	for (int a = 0; a < 3; a++) {
		float t0 = (lo[a] - oa[a]) * id[a], t1 = (hi[a] - oa[a]) * id[a];
		float n = fminf(t0, t1), f = fmaxf(t0, t1);
		n -= fabsf(n) * GRID_GAMMA3;
		f += fabsf(f) * GRID_GAMMA3;
		if (n > *tn)
			*tn = n;
		if (f < *tf)
			*tf = f;
	}
	return *tn <= *tf;
}

int grid_clampi(double x, int n)
{
	return x < 0 ? 0 : x >= n ? n - 1 : (int)x;
}

/* Tests a cell's triangles against one ray; 1 when an any-hit ray is done. */
static int dda_cell(const grid *g, uint32_t c, const isect_ray *ir, vec3 o, int any_hit, float tmax,
                    ray_hit *h, grid_mbox *mb, grid_counts *gc)
{
	for (uint32_t k = g->first[c]; k < g->first[c + 1]; k++) {
		uint32_t ta = g->refs[k];
		if (grid_mbox_skip(g, mb, ta, gc ? &gc->mailbox_skips : NULL))
			continue;
		if (gc) {
			gc->tri_tests++;
			gc->ray_tri_tests++;
		}
		float t, bu, bv;
		if (isect_tri(ir, o, mimg_tri_at(g->m, ta)->v, &t, &bu, &bv) &&
		    isect_take(h, t, bu, bv, ta, 0, any_hit, tmax))
			return 1;
	}
	return 0;
}

ray_hit grid_ray_trace(const grid *g, vec3 o, vec3 d, float tmax, int any_hit, grid_counts *gc)
{
	ray_hit h = {tmax, 0, 0, PKT_NOHIT, 0};
	float tn, tf;
	if (!g->m->ntris || !grid_clip_box(g, o, d, tmax, &tn, &tf))
		return h;
	isect_ray ir = isect_prepare(d);
	double go[3], gd[3], oa[3] = {o.x, o.y, o.z}, da[3] = {d.x, d.y, d.z}, gmax = 0;
	int cell[3], step[3];
	double tnext[3], tdelta[3];
	for (int a = 0; a < 3; a++) {
		go[a] = (oa[a] - g->lo[a]) * g->scale[a];
		gd[a] = da[a] * g->scale[a];
		gmax = fmax(gmax, fabs(gd[a]));
		cell[a] = grid_clampi(floor(go[a] + tn * gd[a]), g->n[a]);
		step[a] = gd[a] > 0 ? 1 : gd[a] < 0 ? -1 : 0;
		tdelta[a] = step[a] ? 1.0 / fabs(gd[a]) : INFINITY;
		tnext[a] = step[a] ? ((cell[a] + (step[a] > 0)) - go[a]) / gd[a] : INFINITY;
	}
	double eps_t = g->eps / gmax;
	static _Thread_local grid_mbox mb;
	memset(&mb, 0, sizeof mb);
	for (;;) {
		if (gc) {
			gc->slices++;
			gc->cells++;
		}
		uint32_t c = grid_cell(g, cell[0], cell[1], cell[2]);
		if (dda_cell(g, c, &ir, o, any_hit, tmax, &h, &mb, gc))
			return h;
		int a = tnext[0] < tnext[1] ? (tnext[0] < tnext[2] ? 0 : 2)
		                            : (tnext[1] < tnext[2] ? 1 : 2);
		double texit = tnext[a];
		/* done when the segment or the best hit ends before the exit */
		double tend =
		    fmin((double)tf, h.tri == PKT_NOHIT ? INFINITY : h.t * (1 + GRID_T_WIDEN));
		if (grid_fault == GRID_FAULT_EARLY_STOP && h.tri != PKT_NOHIT)
			return h;
		if (tend < texit - eps_t)
			return h;
		cell[a] += step[a];
		if (cell[a] < 0 || cell[a] >= g->n[a])
			return h;
		tnext[a] += tdelta[a];
	}
}

/* ---- packets: slice traversal ---------------------------------------- */

/* Sets up f for the rays in mask; returns the rays it cannot hold (the
 * wrong sign along k, or too steep), which go alone. */
uint64_t grid_frustum_setup(const grid *g, const packet *p, const trav_state *s, uint64_t mask,
                            grid_frustum *f)
{
	int first = __builtin_ctzll(mask);
	double d0[3] = {p->dx[first] * g->scale[0], p->dy[first] * g->scale[1],
	                p->dz[first] * g->scale[2]};
	int k = fabs(d0[0]) > fabs(d0[1]) ? (fabs(d0[0]) > fabs(d0[2]) ? 0 : 2)
	                                  : (fabs(d0[1]) > fabs(d0[2]) ? 1 : 2);
	f->ax[0] = k;
	f->ax[1] = (k + 1) % 3;
	f->ax[2] = (k + 2) % 3;
	f->flip = d0[k] < 0;
	uint64_t alone = 0;
	f->k0 = INFINITY;
	f->k1 = -INFINITY;
	for (int j = 0; j < 2; j++) {
		f->amin[j] = f->smin[j] = INFINITY;
		f->amax[j] = f->smax[j] = -INFINITY;
	}
	double w[2][PKT_RAYS], sl[2][PKT_RAYS];
	f->kref = INFINITY;
	for (uint64_t b = mask; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		double o[3] = {p->ox[i], p->oy[i], p->oz[i]}, d[3] = {p->dx[i], p->dy[i], p->dz[i]};
		double go[3], gd[3];
		for (int a = 0; a < 3; a++) {
			go[a] = (o[a] - g->lo[a]) * g->scale[a];
			gd[a] = d[a] * g->scale[a];
		}
		double ok = f->flip ? g->n[k] - go[k] : go[k], dk = f->flip ? -gd[k] : gd[k];
		double su = gd[f->ax[1]] / dk, sv = gd[f->ax[2]] / dk;
		if (!(dk > 0) || !(fabs(su) < GRID_MAX_SLOPE) || !(fabs(sv) < GRID_MAX_SLOPE)) {
			alone |= 1ull << i;
			continue;
		}
		w[0][i] = go[f->ax[1]];
		w[1][i] = go[f->ax[2]];
		sl[0][i] = su;
		sl[1][i] = sv;
		f->ok[i] = ok;
		f->dk[i] = dk;
		f->kin[i] = ok + s->cur.tn[i] * dk;
		f->kout[i] = ok + s->cur.tf[i] * dk;
		f->k0 = fmin(f->k0, f->kin[i]);
		f->k1 = fmax(f->k1, f->kout[i]);
		f->kref = fmin(f->kref, ok);
	}
	for (uint64_t b = mask & ~alone; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		for (int j = 0; j < 2; j++) {
			double a0 = w[j][i] + (f->kref - f->ok[i]) * sl[j][i];
			f->amin[j] = fmin(f->amin[j], a0);
			f->amax[j] = fmax(f->amax[j], a0);
			f->smin[j] = fmin(f->smin[j], sl[j][i]);
			f->smax[j] = fmax(f->smax[j], sl[j][i]);
		}
	}
	return alone;
}

/* The cells [lo, hi] across axis j (0: u, 1: v) the frustum overlaps
 * between slice coordinates ka and kb (0 <= ka <= kb), widened by eps and
 * divided by div (1, or M for macrocells). 0 when none is in the grid. */
int grid_frustum_span(const grid *g, const grid_frustum *f, int j, double ka, double kb, int div,
                      int *lo, int *hi)
{
	if (grid_fault == GRID_FAULT_NARROW_FRUSTUM)
		kb = ka; /* the mistake: the slice's entry plane only */
	/* no ray has a point before kref */
	ka = fmax(ka - f->kref, 0.0);
	kb = fmax(kb - f->kref, 0.0);
	double l = fmin(f->amin[j] + ka * f->smin[j], f->amin[j] + kb * f->smin[j]) - g->eps;
	double h = fmax(f->amax[j] + ka * f->smax[j], f->amax[j] + kb * f->smax[j]) + g->eps;
	int n = g->n[f->ax[1 + j]];
	if (h < 0 || l >= n)
		return 0;
	*lo = grid_clampi(floor(l), n) / div;
	*hi = grid_clampi(floor(h), n) / div;
	return 1;
}

/* Grid coordinates of slice coordinate ks, across coordinates u, v. */
uint32_t grid_slice_cell(const grid *g, const grid_frustum *f, int ks, int u, int v)
{
	int c[3];
	c[f->ax[0]] = f->flip ? g->n[f->ax[0]] - 1 - ks : ks;
	c[f->ax[1]] = u;
	c[f->ax[2]] = v;
	return grid_cell(g, c[0], c[1], c[2]);
}

/* 1 when the M slices from ks hold nothing the frustum overlaps: every
 * macrocell they touch is empty (§2.4), so they can be skipped. */
static int macro_empty(const grid *g, const grid_frustum *f, int ks)
{
	int m = g->p.macro, ul, uh, vl, vh, nk = g->n[f->ax[0]];
	if (!grid_frustum_span(g, f, 0, ks, ks + m, m, &ul, &uh) ||
	    !grid_frustum_span(g, f, 1, ks, ks + m, m, &vl, &vh))
		return 1;
	/* the fine cells ks .. ks + M - 1 along k, in grid order, lie in one
	 * or (flipped, when M does not divide n) two blocks */
	int last = ks + m - 1 < nk ? ks + m - 1 : nk - 1;
	int fa = f->flip ? nk - 1 - last : ks, fb = f->flip ? nk - 1 - ks : last;
	int c[3];
	for (int kb = fa / m; kb <= fb / m; kb++)
		for (int u = ul; u <= uh; u++)
			for (int v = vl; v <= vh; v++) {
				c[f->ax[0]] = kb;
				c[f->ax[1]] = u;
				c[f->ax[2]] = v;
				if (g->macro[(c[2] * g->mn[1] + c[1]) * g->mn[0] + c[0]])
					return 0;
			}
	return 1;
}

/* Frustum culling (§2.3): 1 when the triangle lies wholly outside one of
 * the frustum's four bounding planes (by more than eps), so no ray of the
 * frustum can hit it. Every ray keeps u >= amin + k smin, u <= amax +
 * k smax (and so for v) at k >= 0 (k counted from kref); the planes are
 * lines in (k, u), so a triangle whose three vertices lie beyond one of
 * them lies beyond it whole. A vertex before kref keeps the triangle. The seed culls with the four
 * corner rays' edge tests; the bounding planes are the same frustum, and exact for any packet. */
int grid_frustum_culls(const grid *g, const grid_frustum *f, const mimg_tri *t)
{
	double k[3], w[2][3];
	for (int i = 0; i < 3; i++) {
		double gk = (t->v[i][f->ax[0]] - g->lo[f->ax[0]]) * g->scale[f->ax[0]];
		k[i] = (f->flip ? g->n[f->ax[0]] - gk : gk) - f->kref;
		if (k[i] < 0)
			return 0;
		for (int j = 0; j < 2; j++)
			w[j][i] =
			    (t->v[i][f->ax[1 + j]] - g->lo[f->ax[1 + j]]) * g->scale[f->ax[1 + j]];
	}
	for (int j = 0; j < 2; j++) {
		int below = 1, above = 1;
		for (int i = 0; i < 3; i++) {
			below &= w[j][i] < f->amin[j] + k[i] * f->smin[j] - g->eps;
			above &= w[j][i] > f->amax[j] + k[i] * f->smax[j] + g->eps;
		}
		if (below || above)
			return 1;
	}
	return 0;
}

/* Tests the rays in live against every triangle of one cell. */
static void slice_cell_test(const grid *g, trav_state *s, packet *p, const grid_frustum *f,
                            uint32_t c, uint64_t live, grid_mbox *mb, grid_counts *gc)
{
	for (uint32_t k = g->first[c]; k < g->first[c + 1]; k++) {
		uint32_t ta = g->refs[k];
		if (grid_mbox_skip(g, mb, ta, gc ? &gc->mailbox_skips : NULL))
			continue;
		const mimg_tri *tr = mimg_tri_at(g->m, ta);
		/* a culled triangle stays culled: the frustum does not change,
		 * so the mailbox may keep it */
		if (g->p.cull && grid_frustum_culls(g, f, tr)) {
			if (gc)
				gc->culled++;
			continue;
		}
		if (gc) {
			gc->tri_tests++;
			gc->ray_tri_tests += (uint64_t)__builtin_popcountll(live);
		}
		pkt_isect_tri_v(s, p, tr, live, ta);
	}
}

/* The rays of live still unfinished after the slice ending at kend: their
 * segment and best hit reach past kend - eps. */
uint64_t grid_still_live(const grid *g, const grid_frustum *f, const packet *p, uint64_t live,
                         double kend)
{
	uint64_t r = 0;
	for (uint64_t b = live; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		double t = p->tri[i] == PKT_NOHIT ? INFINITY : (double)p->t[i] * (1 + GRID_T_WIDEN);
		if (p->t[i] == -INFINITY)
			continue; /* an occluded shadow ray */
		if (grid_fault == GRID_FAULT_EARLY_STOP && p->tri[i] != PKT_NOHIT)
			continue;
		double k = fmin(f->kout[i], f->ok[i] + t * f->dk[i]);
		if (k >= kend - g->eps)
			r |= 1ull << i;
	}
	return r;
}

/* One frustum of rays (mask) slice by slice. */
static void frustum_trace(const grid *g, trav_state *s, packet *p, const grid_frustum *f,
                          uint64_t live, grid_counts *gc)
{
	int nk = g->n[f->ax[0]], m = g->macro ? g->p.macro : 0;
	int ks = grid_clampi(floor(f->k0 - g->eps), nk),
	    kl = grid_clampi(floor(f->k1 + g->eps), nk);
	static _Thread_local grid_mbox mb;
	memset(&mb, 0, sizeof mb);
	for (; ks <= kl && live; ks++) {
		if (m && ks % m == 0 && macro_empty(g, f, ks)) {
			if (gc)
				gc->macro_skips++;
			ks += m - 1;
			live = grid_still_live(g, f, p, live, ks + 1);
			continue;
		}
		if (gc)
			gc->slices++;
		int ul, uh, vl, vh;
		if (grid_frustum_span(g, f, 0, ks, ks + 1, 1, &ul, &uh) &&
		    grid_frustum_span(g, f, 1, ks, ks + 1, 1, &vl, &vh))
			for (int u = ul; u <= uh; u++)
				for (int v = vl; v <= vh; v++) {
					if (gc)
						gc->cells++;
					slice_cell_test(g, s, p, f, grid_slice_cell(g, f, ks, u, v),
					                live, &mb, gc);
				}
		live = grid_still_live(g, f, p, live, ks + 1);
	}
}

/* A ray of the packet alone, by the DDA, into its lane. */
static void ray_alone(const grid *g, packet *p, int i, grid_counts *gc)
{
	ray_hit h =
	    grid_ray_trace(g, v3(p->ox[i], p->oy[i], p->oz[i]), v3(p->dx[i], p->dy[i], p->dz[i]),
	                   p->tmax[i], p->type == PKT_SHADOW, gc);
	if (gc)
		gc->dda_rays++;
	/* the packet path's form: an occluded shadow ray has t = -inf */
	p->t[i] = p->type == PKT_SHADOW && h.tri != PKT_NOHIT ? -INFINITY : h.t;
	p->tri[i] = h.tri;
	p->bu[i] = h.bu;
	p->bv[i] = h.bv;
}

/* 1 when the rays of mask start within one cell of each other (primary
 * rays: one eye). A frustum over rays from scattered origins (shadow rays
 * from a packet's hit points towards a light) spans far more cells than
 * its rays cross (seed 003 §4.7: secondary packets lose the frustum's
 * coherence), so those rays go one by one through the DDA. */
int grid_one_origin(const grid *g, const packet *p, uint64_t mask)
{
	int f = __builtin_ctzll(mask);
	for (uint64_t b = mask; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		if (fabs(((double)p->ox[i] - p->ox[f]) * g->scale[0]) > 1 ||
		    fabs(((double)p->oy[i] - p->oy[f]) * g->scale[1]) > 1 ||
		    fabs(((double)p->oz[i] - p->oz[f]) * g->scale[2]) > 1)
			return 0;
	}
	return 1;
}

/* The lanes of sub-packet q of side `side` (lane = row * 8 + column). */
uint64_t grid_sub_lanes(int side, int q)
{
	uint64_t r = 0;
	int per = 8 / side, qx = q % per, qy = q / per;
	for (int y = 0; y < side; y++)
		for (int x = 0; x < side; x++)
			r |= 1ull << ((qy * side + y) * 8 + qx * side + x);
	return r;
}

uint64_t grid_pkt_trace(const grid *g, packet *p, trav_entry *stack, int stack_max, grid_counts *gc)
{
	trav_state s;
	/* the rays' test constants, results reset, segments clipped to the
	 * scene box: exactly as for the kd-tree */
	uint64_t entered = pkt_trav_begin(&s, p, g->m, stack, stack_max);
	if (!g->m->ntris)
		return entered;
	int side = g->p.packet;
	if (side <= 1) {
		for (uint64_t b = entered; b; b &= b - 1)
			ray_alone(g, p, __builtin_ctzll(b), gc);
		return entered;
	}
	int nsub = (8 / side) * (8 / side);
	for (int q = 0; q < nsub; q++) {
		uint64_t mask = entered & grid_sub_lanes(side, q);
		if (!mask)
			continue;
		if (!grid_one_origin(g, p, mask)) {
			for (uint64_t b = mask; b; b &= b - 1)
				ray_alone(g, p, __builtin_ctzll(b), gc);
			continue;
		}
		grid_frustum f;
		uint64_t alone = grid_frustum_setup(g, p, &s, mask, &f);
		for (uint64_t b = alone; b; b &= b - 1)
			ray_alone(g, p, __builtin_ctzll(b), gc);
		if (mask & ~alone)
			frustum_trace(g, &s, p, &f, mask & ~alone, gc);
	}
	return entered;
}
