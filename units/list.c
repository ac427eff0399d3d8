/*
 * list.c: the list unit (see list.h).
 */
#include "list.h"

#include "isect.h"
#include "traversal.h"

static void done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	t->k = 0;
	t->mask = t->r.mask;
	isu_next(t);
}

static void fetched(thr_ctx *t)
{
	thr_use(t, UNIT_LIST, thr_pop(t->r.mask), done);
}

void list_leaf(thr_ctx *t)
{
	thr_env *v = t->env;
	thr_count(t, C_LEAF_VISITS, 1);
	if (t->r.leaf_count == 0) {
		thr_count(t, C_EMPTY_LEAVES, 1);
		tu_step(t);
		return;
	}
	thr_count(t, C_LIST_ENTRIES, t->r.leaf_count);
	thr_read(t, MEM_LIST, mimg_list_addr(v->m, t->r.leaf_first),
	         t->r.leaf_count * MIMG_LIST_BYTES);
	thr_wait_mem(t, fetched);
}
