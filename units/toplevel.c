/*
 * toplevel.c: the top-level walk and the transformation unit (see
 * toplevel.h).
 */
#include "units/toplevel.h"

#include <stdlib.h>

static void next(thr_ctx *t);
static void inst_next(thr_ctx *t);

void tlu_enter(thr_ctx *t)
{
	thr_env *v = t->env;
	if (!t->tl && !(t->tl = malloc(sizeof *t->tl))) {
		v->oom = 1; /* the frame fails; the packet is shaded as missed */
		v->route.shade(t);
		return;
	}
	thr_tl *L = t->tl;
	packet *p = t->p;
	/* as tl_pkt_trace: every ray starts unhit at its bound */
	for (uint64_t m = p->valid; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		p->t[i] = p->tmax[i];
		p->tri[i] = PKT_NOHIT;
	}
	L->sp = 0;
	L->steps = 0;
	L->node[L->sp] = 0;
	L->mask[L->sp++] = p->valid;
	next(t);
}

static void node_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	thr_tl *L = t->tl;
	if (!L->leaf) {
		next(t);
		return;
	}
	if (L->n.count == 0) {
		if (L->sp + 2 > THR_TL_STACK) { /* damaged node data */
			t->env->damaged = 1;
			L->sp = 0;
			next(t);
			return;
		}
		L->node[L->sp] = L->n.first + 1;
		L->mask[L->sp++] = L->leaf;
		L->node[L->sp] = L->n.first;
		L->mask[L->sp++] = L->leaf;
		next(t);
		return;
	}
	L->k = L->n.first;
	L->end = L->n.first + L->n.count;
	inst_next(t);
}

/* The node record is in: its box against the rays (a traversal op). */
static void node_fetched(thr_ctx *t)
{
	thr_tl *L = t->tl;
	tli_node_decode(L->rec, &L->n);
	uint64_t mask = L->mask[L->sp];
	L->leaf = tl_pkt_box(&L->n.box, t->p, mask);
	if (L->steps == 1) { /* the root: its box is the scene's */
		thr_count(t, C_BOX_MISS_RAYS, (uint64_t)thr_pop(mask & ~L->leaf));
		thr_count(t, C_BOX_MISS_PACKETS, (uint64_t)!L->leaf);
	}
	thr_count(t, C_TL_STEPS, 1);
	thr_use(t, UNIT_TRAV, thr_pop(mask), node_done);
}

/* Pops the next node and reads its record, or ends the walk. */
static void next(thr_ctx *t)
{
	thr_env *v = t->env;
	thr_tl *L = t->tl;
	/* node data that loops (damaged memory) would keep the frame going */
	if (L->sp == 0 || ++L->steps > v->max_steps) {
		if (L->sp)
			v->damaged = 1;
		v->route.shade(t);
		return;
	}
	L->sp--;
	thr_read(t, MEM_KD, v->tl_nodes + (uint64_t)L->node[L->sp] * TLI_NODE_BYTES, TLI_NODE_BYTES,
	         L->rec);
	thr_wait_mem(t, node_fetched);
}

static void xformed(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	thr_tl *L = t->tl;
	/* the object's tree traces the moved rays; its addresses are the
	 * record's */
	L->wp = t->p;
	t->p = &L->q;
	t->img = &L->in.regs;
	t->env->route.object(t);
}

static void inst_tested(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	thr_tl *L = t->tl;
	if (!L->im) {
		L->k++;
		inst_next(t);
		return;
	}
	/* Schmittler et al. GH 2004: the transformation unit, one op of the
	 * entering rays */
	tl_pkt_to_object(L->in.inv, t->p, L->im, &L->q);
	thr_count(t, C_TL_INST_ENTERED, 1);
	thr_use(t, UNIT_XFORM, thr_pop(L->im), xformed);
}

static void inst_fetched(thr_ctx *t)
{
	thr_tl *L = t->tl;
	tli_inst_decode(L->rec, &L->in);
	L->im = tl_pkt_box(&L->in.box, t->p, L->leaf);
	thr_count(t, C_TL_INST_TESTS, 1);
	thr_use(t, UNIT_TRAV, thr_pop(L->leaf), inst_tested);
}

/* The leaf's next instance record, or back to the walk. */
static void inst_next(thr_ctx *t)
{
	thr_env *v = t->env;
	thr_tl *L = t->tl;
	if (L->k >= L->end) {
		next(t);
		return;
	}
	thr_read(t, MEM_KD, v->tl_insts + (uint64_t)L->k * TLI_INST_BYTES, TLI_INST_WALK_BYTES,
	         L->rec);
	thr_wait_mem(t, inst_fetched);
}

/* The map entries of the object's hits are in: into the world packet. */
static void merged(thr_ctx *t)
{
	thr_tl *L = t->tl;
	tl_pkt_merge(t->p, &L->q, L->im, L->g, L->k);
	L->k++;
	inst_next(t);
}

void tlu_finish(thr_ctx *t)
{
	thr_tl *L = t->tl;
	if (!t->img) { /* not in an object: a packet that never started */
		t->env->route.shade(t);
		return;
	}
	const mimg *o = t->img;
	t->p = L->wp;
	t->img = NULL;
	t->sp = 0;
	for (uint64_t m = L->im; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		if (L->q.tri[i] == PKT_NOHIT)
			continue;
		/* the object's triangle k is the map's entry k of the instance */
		uint64_t k = (L->q.tri[i] - o->base[MIMG_TRIS]) / MIMG_TRI_BYTES;
		thr_count(t, C_TL_MAP_READS, 1);
		thr_read(t, MEM_LIST, L->in.map + 4 * k, 4, &L->g[i]);
	}
	thr_wait_mem(t, merged);
}
