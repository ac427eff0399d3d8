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
	*v->c[C_BOX_MISS_RAYS] += (uint64_t)thr_pop(t->p->valid & ~enter);
	if (!enter) {
		++*v->c[C_BOX_MISS_PACKETS];
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

static uint64_t spill_addr(const thr_ctx *t, int index)
{
	return t->env->spill_base +
	       ((uint64_t)t->gid * PKT_STACK_MAX + (uint64_t)index) * THR_SPILL_STRIDE;
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
			++*v->c[C_STACK_REFILLS];
			thr_read(t, MEM_KD, spill_addr(t, idx), THR_STACK_ENTRY_BYTES);
		}
	}
	t->sp = r->sp;
	if (r->op == TRAV_DONE) {
		thr_wait_mem(t, rgs_finish);
		return;
	}
	++*v->c[C_NODE_STEPS];
	if ((uint64_t)r->sp > *v->c[C_MAX_SP])
		*v->c[C_MAX_SP] = (uint64_t)r->sp;
	if (r->pushed && r->sp - 1 >= v->stack_depth) {
		++*v->c[C_STACK_OVERFLOWS];
		thr_write(t, MEM_KD, spill_addr(t, r->sp - 1), THR_STACK_ENTRY_BYTES);
	}
	/* the node address comes from the refilled entry: read it after */
	thr_wait_mem(t, fetch_node);
}
