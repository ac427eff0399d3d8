/*
 * traversal.c: the traversal unit (see traversal.h).
 */
#include "traversal.h"

#include "list.h"
#include "rgs.h"

void tu_begin(thr_ctx *t)
{
	thr_env *v = t->env;
	uint64_t enter = pkt_trav_begin_fp(&t->ts, t->p, v->m, t->stack, PKT_STACK_MAX, &v->prec);
	t->sp = 0;
	thr_count(t, C_BOX_MISS_RAYS, (uint64_t)thr_pop(t->p->valid & ~enter));
	if (!enter) {
		thr_count(t, C_BOX_MISS_PACKETS, 1);
		rgs_finish(t);
		return;
	}
	tu_step(t);
}

static void done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	if (t->r.op == TRAV_LEAF)
		list_leaf(t);
	else
		tu_step(t);
}

static void fetched(thr_ctx *t)
{
	thr_use(t, UNIT_TRAV, thr_pop(t->r.mask), done);
}

static void fetch_node(thr_ctx *t)
{
	thr_read(t, MEM_KD, mimg_node_addr(t->env->m, t->r.node), MIMG_NODE_BYTES);
	thr_wait_mem(t, fetched);
}

void tu_step(thr_ctx *t)
{
	thr_env *v = t->env;
	trav_result *r = &t->r;
	int sp0 = t->sp;
	pkt_trav_next(&t->ts, t->p, v->m, r);
	/* popped entries that lived in memory come back first */
	for (int k = 0; k < r->popped; k++) {
		int idx = sp0 - 1 - k;
		if (idx >= v->stack_depth) {
			thr_count(t, C_STACK_REFILLS, 1);
			thr_read(t, MEM_KD, thr_spill_addr(t, (uint64_t)idx),
			         THR_STACK_ENTRY_BYTES);
		}
	}
	t->sp = r->sp;
	if (r->op == TRAV_DONE) {
		thr_wait_mem(t, rgs_finish);
		return;
	}
	thr_count(t, C_NODE_STEPS, 1);
	thr_count_max(t, C_MAX_SP, (uint64_t)r->sp);
	if (r->pushed && r->sp - 1 >= v->stack_depth) {
		thr_count(t, C_STACK_OVERFLOWS, 1);
		thr_write(t, MEM_KD, thr_spill_addr(t, (uint64_t)(r->sp - 1)),
		          THR_STACK_ENTRY_BYTES);
	}
	/* the node address comes from the refilled entry: read it after */
	thr_wait_mem(t, fetch_node);
}
