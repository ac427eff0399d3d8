/*
 * list.c: the list unit (see list.h).
 */
#include "units/list.h"

#include <stdlib.h>

static void done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	t->k = 0;
	t->mask = t->r.mask;
	t->env->route.triangles(t);
}

static void fetched(thr_ctx *t)
{
	thr_use(t, UNIT_LIST, thr_pop(t->r.mask), done);
}

int list_room(thr_ctx *t, uint32_t n)
{
	if (n <= t->list_cap)
		return 0;
	uint32_t cap = t->list_cap ? t->list_cap : 64;
	while (cap < n)
		cap = cap > UINT32_MAX / 2 ? n : 2 * cap;
	uint32_t *l = realloc(t->list, (size_t)cap * sizeof *l);
	if (!l)
		return -1;
	t->list = l;
	t->list_cap = cap;
	return 0;
}

void list_leaf(thr_ctx *t)
{
	thr_env *v = t->env;
	thr_count(t, C_LEAF_VISITS, 1);
	if (t->r.leaf_count == 0) {
		thr_count(t, C_EMPTY_LEAVES, 1);
		v->route.traverse(t);
		return;
	}
	if (list_room(t, t->r.leaf_count)) {
		v->oom = 1; /* the frame fails */
		v->route.traverse(t);
		return;
	}
	/* the entries (triangle addresses) as the read returns them */
	thr_count(t, C_LIST_ENTRIES, t->r.leaf_count);
	thr_read(t, MEM_LIST, mimg_list_addr(thr_img(t), t->r.leaf_first),
	         t->r.leaf_count * MIMG_LIST_BYTES, t->list);
	thr_wait_mem(t, fetched);
}
