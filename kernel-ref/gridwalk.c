/*
 * gridwalk.c: the grid's packet traversal step by step (see gridwalk.h).
 *
 * The walk is grid_pkt_trace (gridtrav.c) with its loops unrolled into
 * phases, using the same pieces (gridtrav.h): sub-packets of p.packet
 * squared rays; per sub-packet first the rays that go alone (the 3D DDA of
 * grid_ray_trace), then the frustum slice by slice (seed 003 §2.2), a
 * macrocell slice skipped when every flag it touches is clear (§2.4),
 * each cell's list through the per-packet mailbox (§2.3) and frustum
 * culling. Where the loops read g->macro, g->first, g->refs or a
 * triangle, the walk stops with an ask instead.
 */
#include "kernel-ref/gridwalk.h"

#include <math.h>
#include <string.h>

enum {
	P_SUB,      /* the next sub-packet */
	P_ALONE,    /* the next ray alone, or the frustum */
	P_DDA_CELL, /* a ray's cell: its list */
	P_DDA_NEXT, /* a ray's step to the next cell */
	P_SLICE,    /* the next slice of the frustum */
	P_MACRO,    /* the next macrocell flag of a slice of M */
	P_BODY,     /* a slice not skipped: its cells */
	P_SCELL,    /* the next cell of the slice */
	P_SEND,     /* the slice is done */
	P_LIST,     /* waiting for the cell's range */
	P_LASK,     /* the cell's range is in: its entries to read */
	P_LWAIT,    /* waiting for the entries */
	P_ENTRY,    /* the next entry of the cell */
	P_FLAGGED,  /* waiting for a flag */
};

void grid_walk_begin(grid_walk *w, const grid *g, trav_state *s, packet *p, uint64_t entered)
{
	w->g = g;
	w->s = s;
	w->p = p;
	memset(&w->c, 0, sizeof w->c);
	w->bad = 0;
	w->entered = entered;
	w->side = g->p.packet;
	w->nsub = w->side <= 1 ? 1 : (8 / w->side) * (8 / w->side);
	w->q = 0;
	w->alone = w->fmask = 0;
	w->m = g->p.macro > 0 ? g->p.macro : 0;
	/* no triangles: nothing to visit (as grid_pkt_trace) */
	w->phase = g->m->ntris ? P_SUB : -1;
}

/* Starts ray i alone (grid_ray_trace's set-up); 0 when it misses the box. */
static int dda_start(grid_walk *w, int i)
{
	const grid *g = w->g;
	packet *p = w->p;
	vec3 o = v3(p->ox[i], p->oy[i], p->oz[i]), d = v3(p->dx[i], p->dy[i], p->dz[i]);
	w->ray = i;
	w->dda = 1;
	w->o = o;
	w->tmax = p->tmax[i];
	w->any_hit = p->type == PKT_SHADOW;
	w->h = (ray_hit){w->tmax, 0, 0, PKT_NOHIT, 0};
	float tn;
	if (!grid_clip_box(g, o, d, w->tmax, &tn, &w->tf))
		return 0;
	w->ir = isect_prepare(d);
	double oa[3] = {o.x, o.y, o.z}, da[3] = {d.x, d.y, d.z}, gmax = 0;
	for (int a = 0; a < 3; a++) {
		double go = (oa[a] - g->lo[a]) * g->scale[a], gd = da[a] * g->scale[a];
		gmax = fmax(gmax, fabs(gd));
		w->cell[a] = grid_clampi(floor(go + tn * gd), g->n[a]);
		w->step[a] = gd > 0 ? 1 : gd < 0 ? -1 : 0;
		w->tdelta[a] = w->step[a] ? 1.0 / fabs(gd) : INFINITY;
		w->tnext[a] = w->step[a] ? ((w->cell[a] + (w->step[a] > 0)) - go) / gd : INFINITY;
	}
	w->eps_t = g->eps / gmax;
	memset(&w->mb, 0, sizeof w->mb);
	return 1;
}

/* Ray w->ray is done: its lane in the packet path's form (ray_alone). */
static void dda_end(grid_walk *w)
{
	packet *p = w->p;
	int i = w->ray;
	w->c.dda_rays++;
	p->t[i] = p->type == PKT_SHADOW && w->h.tri != PKT_NOHIT ? -INFINITY : w->h.t;
	p->tri[i] = w->h.tri;
	p->bu[i] = w->h.bu;
	p->bv[i] = w->h.bv;
	w->phase = P_ALONE;
}

/* grid_ray_trace's step after a cell: on to the next, or the ray is done. */
static void dda_next(grid_walk *w)
{
	const grid *g = w->g;
	int a = w->tnext[0] < w->tnext[1] ? (w->tnext[0] < w->tnext[2] ? 0 : 2)
	                                  : (w->tnext[1] < w->tnext[2] ? 1 : 2);
	double texit = w->tnext[a];
	double tend =
	    fmin((double)w->tf, w->h.tri == PKT_NOHIT ? INFINITY : w->h.t * (1 + GRID_T_WIDEN));
	if ((grid_fault == GRID_FAULT_EARLY_STOP && w->h.tri != PKT_NOHIT) ||
	    tend < texit - w->eps_t) {
		dda_end(w);
		return;
	}
	w->cell[a] += w->step[a];
	if (w->cell[a] < 0 || w->cell[a] >= g->n[a]) {
		dda_end(w);
		return;
	}
	w->tnext[a] += w->tdelta[a];
	w->phase = P_DDA_CELL;
}

/* The next sub-packet: its rays alone and its frustum (grid_pkt_trace). */
static int sub_next(grid_walk *w)
{
	const grid *g = w->g;
	if (w->q >= w->nsub)
		return 0;
	int q = w->q++;
	if (w->side <= 1) {
		w->alone = w->entered;
		w->fmask = 0;
		return 1;
	}
	uint64_t mask = w->entered & grid_sub_lanes(w->side, q);
	w->alone = w->fmask = 0;
	if (!mask)
		return 1;
	if (!grid_one_origin(g, w->p, mask)) {
		w->alone = mask;
		return 1;
	}
	w->alone = grid_frustum_setup(g, w->p, w->s, mask, &w->f);
	w->fmask = mask & ~w->alone;
	return 1;
}

/* The frustum's first slice (frustum_trace). */
static void frustum_start(grid_walk *w)
{
	const grid *g = w->g;
	int nk = g->n[w->f.ax[0]];
	w->ks = grid_clampi(floor(w->f.k0 - g->eps), nk);
	w->kl = grid_clampi(floor(w->f.k1 + g->eps), nk);
	w->live = w->fmask;
	w->fmask = 0;
	w->dda = 0;
	memset(&w->mb, 0, sizeof w->mb);
	w->phase = P_SLICE;
}

/* Slice ks starts a block of M: the flags it must look at (macro_empty);
 * 0 when the frustum overlaps none (the slices are empty). */
static int macro_start(grid_walk *w)
{
	const grid *g = w->g;
	const grid_frustum *f = &w->f;
	int m = w->m, ks = w->ks, nk = g->n[f->ax[0]];
	if (!grid_frustum_span(g, f, 0, ks, ks + m, m, &w->mul, &w->muh) ||
	    !grid_frustum_span(g, f, 1, ks, ks + m, m, &w->mvl, &w->mvh))
		return 0;
	int last = ks + m - 1 < nk ? ks + m - 1 : nk - 1;
	int fa = f->flip ? nk - 1 - last : ks, fb = f->flip ? nk - 1 - ks : last;
	w->kb = fa / m;
	w->kbe = fb / m;
	w->mu = w->mul;
	w->mv = w->mvl;
	return 1;
}

/* The macrocell slices from ks are empty: skipped (frustum_trace). */
static void macro_skip(grid_walk *w)
{
	w->c.macro_skips++;
	w->ks += w->m - 1;
	w->live = grid_still_live(w->g, &w->f, w->p, w->live, w->ks + 1);
	w->ks++;
	w->phase = P_SLICE;
}

/* The next flag to read, or (none left) the skip. */
static int macro_ask(grid_walk *w, grid_ask *a)
{
	const grid *g = w->g;
	if (w->kb > w->kbe) {
		macro_skip(w);
		return 0;
	}
	int c[3];
	c[w->f.ax[0]] = w->kb;
	c[w->f.ax[1]] = w->mu;
	c[w->f.ax[2]] = w->mv;
	a->op = GW_FLAG;
	a->index = (uint32_t)((c[2] * g->mn[1] + c[1]) * g->mn[0] + c[0]);
	/* the order of macro_empty's loops: k block, u, v */
	if (++w->mv > w->mvh) {
		w->mv = w->mvl;
		if (++w->mu > w->muh) {
			w->mu = w->mul;
			w->kb++;
		}
	}
	w->phase = P_FLAGGED;
	return 1;
}

/* A slice not skipped: its cells (frustum_trace's body). */
static void body_start(grid_walk *w)
{
	w->c.slices++;
	if (grid_frustum_span(w->g, &w->f, 0, w->ks, w->ks + 1, 1, &w->ul, &w->uh) &&
	    grid_frustum_span(w->g, &w->f, 1, w->ks, w->ks + 1, 1, &w->vl, &w->vh)) {
		w->u = w->ul;
		w->v = w->vl;
		w->phase = P_SCELL;
	} else
		w->phase = P_SEND;
}

/* The next list entry the mailbox does not hold: a triangle to read. */
static int entry_ask(grid_walk *w, grid_ask *a)
{
	while (w->k < w->n) {
		uint32_t ta = w->list[w->k++];
		if (grid_mbox_skip(w->g, &w->mb, ta, &w->c.mailbox_skips))
			continue;
		w->ta = ta;
		a->op = GW_TRI;
		a->addr = ta;
		return 1;
	}
	w->phase = w->after;
	return 0;
}

/* One phase: 1 with an ask in a, 0 when the walk went on by itself. */
static int step(grid_walk *w, grid_ask *a)
{
	switch (w->phase) {
	case P_SUB:
		if (!sub_next(w)) {
			w->phase = -1;
			return 0;
		}
		w->phase = P_ALONE;
		return 0;
	case P_ALONE:
		if (w->alone) {
			int i = __builtin_ctzll(w->alone);
			w->alone &= w->alone - 1;
			if (dda_start(w, i))
				w->phase = P_DDA_CELL;
			else
				dda_end(w);
		} else if (w->fmask)
			frustum_start(w);
		else
			w->phase = P_SUB;
		return 0;
	case P_DDA_CELL:
		w->c.slices++;
		w->c.cells++;
		a->op = GW_CELL;
		a->index = grid_cell(w->g, w->cell[0], w->cell[1], w->cell[2]);
		w->after = P_DDA_NEXT;
		w->phase = P_LIST;
		return 1;
	case P_DDA_NEXT:
		dda_next(w);
		return 0;
	case P_SLICE:
		if (!(w->ks <= w->kl && w->live))
			w->phase = P_SUB;
		else if (w->m && w->ks % w->m == 0) {
			if (macro_start(w))
				w->phase = P_MACRO;
			else
				macro_skip(w);
		} else
			body_start(w);
		return 0;
	case P_MACRO:
		return macro_ask(w, a);
	case P_BODY:
		body_start(w);
		return 0;
	case P_SCELL:
		if (w->u > w->uh) {
			w->phase = P_SEND;
			return 0;
		}
		w->c.cells++;
		a->op = GW_CELL;
		a->index = grid_slice_cell(w->g, &w->f, w->ks, w->u, w->v);
		if (++w->v > w->vh) {
			w->v = w->vl;
			w->u++;
		}
		w->after = P_SCELL;
		w->phase = P_LIST;
		return 1;
	case P_SEND:
		w->live = grid_still_live(w->g, &w->f, w->p, w->live, w->ks + 1);
		w->ks++;
		w->phase = P_SLICE;
		return 0;
	case P_LASK:
		if (!w->n) {
			w->phase = w->after;
			return 0;
		}
		a->op = GW_LIST;
		a->first = w->lfirst;
		a->count = w->n;
		w->phase = P_LWAIT;
		return 1;
	case P_ENTRY:
		return entry_ask(w, a);
	default:
		return 0;
	}
}

int grid_walk_next(grid_walk *w, grid_ask *a)
{
	memset(a, 0, sizeof *a);
	for (;;) {
		/* the end, or an ask left unanswered (a caller's mistake):
		 * the walk stops rather than go on without the data */
		if (w->phase < 0 || w->phase == P_LIST || w->phase == P_LWAIT ||
		    w->phase == P_FLAGGED) {
			a->op = GW_DONE;
			return GW_DONE;
		}
		if (step(w, a)) {
			a->dda = w->dda;
			a->mask = w->dda ? 1ull << w->ray : w->live;
			return a->op;
		}
	}
}

void grid_walk_flag(grid_walk *w, uint8_t flag)
{
	/* a set flag: the slice's cells; else the next flag */
	w->phase = flag ? P_BODY : P_MACRO;
}

void grid_walk_cell(grid_walk *w, uint32_t first, uint32_t end)
{
	if (end < first) { /* damaged offsets: no entries */
		w->bad = 1;
		end = first;
	}
	w->list = NULL;
	w->k = 0;
	w->n = end - first;
	w->lfirst = first;
	w->phase = P_LASK;
}

void grid_walk_list(grid_walk *w, const uint32_t *entries)
{
	w->list = entries;
	w->phase = P_ENTRY;
}

int grid_walk_tri(grid_walk *w, const mimg_tri *tri)
{
	packet *p = w->p;
	if (w->dda) { /* the ray alone: dda_cell's test */
		w->c.tri_tests++;
		w->c.ray_tri_tests++;
		float t, bu, bv;
		if (isect_tri(&w->ir, w->o, tri->v, &t, &bu, &bv) &&
		    isect_take(&w->h, t, bu, bv, w->ta, 0, w->any_hit, w->tmax))
			dda_end(w); /* an occluder: the ray is done */
		return 1;
	}
	/* a culled triangle stays culled (the frustum does not change) */
	if (w->g->p.cull && grid_frustum_culls(w->g, &w->f, tri)) {
		w->c.culled++;
		return 0;
	}
	int n = __builtin_popcountll(w->live);
	w->c.tri_tests++;
	w->c.ray_tri_tests += (uint64_t)n;
	pkt_isect_tri_v(w->s, p, tri, w->live, w->ta);
	return n;
}

uint64_t grid_walk_trace(const grid *g, packet *p, trav_entry *stack, int stack_max, grid_counts *c)
{
	trav_state s;
	uint64_t entered = pkt_trav_begin(&s, p, g->m, stack, stack_max);
	static _Thread_local grid_walk w;
	grid_walk_begin(&w, g, &s, p, entered);
	grid_ask a;
	while (grid_walk_next(&w, &a) != GW_DONE) {
		switch (a.op) {
		case GW_FLAG:
			grid_walk_flag(&w, g->macro[a.index]);
			break;
		case GW_CELL:
			grid_walk_cell(&w, g->first[a.index], g->first[a.index + 1]);
			break;
		case GW_LIST:
			grid_walk_list(&w, g->refs + a.first);
			break;
		case GW_TRI:
			grid_walk_tri(&w, mimg_tri_at(g->m, a.addr));
			break;
		}
	}
	if (c) {
		c->slices += w.c.slices;
		c->macro_skips += w.c.macro_skips;
		c->cells += w.c.cells;
		c->tri_tests += w.c.tri_tests;
		c->ray_tri_tests += w.c.ray_tri_tests;
		c->mailbox_skips += w.c.mailbox_skips;
		c->culled += w.c.culled;
		c->dda_rays += w.c.dda_rays;
	}
	return entered;
}
