/*
 * gridtrav.c: the grid traversal unit (see gridtrav.h).
 */
#include "units/gridtrav.h"
#include "units/list.h"
#include "units/traversal.h"

#include <stdlib.h>

#include "kernel-ref/gridimage.h"
#include "kernel-ref/gridwalk.h"

/* A thread's grid walk: the walk, its current ask and the bytes of a
 * flag or a cell's range as read. */
typedef struct thr_grid {
	grid_walk w;
	grid_ask a;
	uint8_t b[8];
} thr_grid;

static void next(thr_ctx *t);

static void stepped(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	next(ctx);
}

/* The walk is over: its slice steps are the traversal steps (as rtref's
 * node_steps), then shading. */
static void end(thr_ctx *t)
{
	thr_count(t, C_NODE_STEPS, t->grid->w.c.slices);
	if (t->grid->w.bad)
		t->env->damaged = 1;
	t->sp = 0;
	t->env->route.finish(t);
}

void gtu_begin(thr_ctx *t)
{
	thr_env *v = t->env;
	if (!t->grid && !(t->grid = malloc(sizeof *t->grid))) {
		v->oom = 1; /* the frame fails; the packet is shaded as missed */
		t->env->route.finish(t);
		return;
	}
	uint64_t enter = tu_enter(t, 1);
	if (!enter)
		return;
	grid_walk_begin(&t->grid->w, v->grid, &t->ts, t->p, enter);
	next(t);
}

static void flag_in(thr_ctx *t)
{
	thr_grid *G = t->grid;
	grid_walk_flag(&G->w, G->b[0]);
	thr_use(t, UNIT_TRAV, thr_pop(G->a.mask), stepped);
}

static void cell_in(thr_ctx *t)
{
	thr_grid *G = t->grid;
	uint32_t first, endi;
	gimg_cell_decode(G->b, &first, &endi);
	/* a range past the lists (damaged memory): no entries, the frame fails */
	if (endi > t->env->grid_nrefs || first > endi) {
		G->w.bad = 1;
		first = endi = 0;
	}
	grid_walk_cell(&G->w, first, endi);
	thr_count(t, C_LEAF_VISITS, 1);
	if (first == endi)
		thr_count(t, C_EMPTY_LEAVES, 1);
	thr_use(t, UNIT_TRAV, thr_pop(G->a.mask), stepped);
}

static void list_in(thr_ctx *t)
{
	thr_grid *G = t->grid;
	grid_walk_list(&G->w, t->list);
	thr_use(t, UNIT_LIST, thr_pop(G->a.mask), stepped);
}

static void tri_in(thr_ctx *t)
{
	thr_grid *G = t->grid;
	int n = grid_walk_tri(&G->w, &t->tri);
	if (!n) { /* culled by the frustum (§2.3): a packet-level test */
		thr_use(t, UNIT_ISECT, THR_SCALAR_OP, stepped);
		return;
	}
	thr_count(t, C_TRI_TESTS, 1);
	thr_count(t, C_RAY_TRI_TESTS, (uint64_t)n);
	thr_use(t, UNIT_ISECT, n, stepped);
}

/* The walk's next ask as a read, then the unit's op. */
static void next(thr_ctx *t)
{
	thr_env *v = t->env;
	thr_grid *G = t->grid;
	grid_ask *a = &G->a;
	/* a walk that never ends (damaged memory) would keep the frame going */
	if (++t->steps > v->max_steps) {
		v->damaged = 1;
		t->sp = 0;
		t->env->route.finish(t);
		return;
	}
	switch (grid_walk_next(&G->w, a)) {
	case GW_FLAG:
		thr_read(t, MEM_KD, v->grid_macro + a->index, GIMG_FLAG_BYTES, G->b);
		thr_wait_mem(t, flag_in);
		return;
	case GW_CELL:
		thr_read(t, MEM_KD, v->grid_cells + (uint64_t)a->index * GIMG_CELL_BYTES,
		         2 * GIMG_CELL_BYTES, G->b);
		thr_wait_mem(t, cell_in);
		return;
	case GW_LIST:
		if (list_room(t, a->count)) {
			v->oom = 1;
			end(t);
			return;
		}
		thr_count(t, C_LIST_ENTRIES, a->count);
		uint64_t first = a->first + (v->mutant == THR_MUT_GRID_LIST_NEXT); /* test hook */
		thr_read(t, MEM_LIST, v->grid_refs + first * GIMG_REF_BYTES,
		         a->count * GIMG_REF_BYTES, t->list);
		thr_wait_mem(t, list_in);
		return;
	case GW_TRI:
		thr_read(t, MEM_TRI, a->addr, MIMG_TRI_BYTES, &t->tri);
		thr_wait_mem(t, tri_in);
		return;
	default:
		end(t);
	}
}
