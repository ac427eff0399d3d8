/*
 * intersection.c: the intersection unit (see intersection.h).
 */
#include "units/intersection.h"

static void done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	packet *p = t->p;
	/* the record as read, named by the list entry that addressed it */
	uint32_t ta = t->list[t->k];
	thr_count(t, C_TRI_TESTS, 1);
	thr_count(t, C_RAY_TRI_TESTS, (uint64_t)thr_pop(t->mask));
	pkt_isect_tri_v(&t->ts, p, &t->tri, t->mask, ta);
	if (t->ts.shadow)
		for (uint64_t b = t->mask; b; b &= b - 1) {
			int i = __builtin_ctzll(b);
			if (p->tri[i] != PKT_NOHIT)
				t->mask &= ~(1ull << i);
		}
	t->k++;
	isu_next(t);
}

/* The triangle-cone test is done (chip.cone_cull): a triangle outside
 * the packet's cone is skipped for every ray, else the rays test it. */
static void cone_tested(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	if (cone_culls_tri(&t->cone, &t->tri)) {
		thr_count(t, C_CONE_CULLED, 1);
		thr_count(t, C_CONE_SAVED, (uint64_t)thr_pop(t->mask));
		t->k++;
		isu_next(t);
		return;
	}
	thr_use(t, UNIT_ISECT, thr_pop(t->mask), done);
}

static void fetched(thr_ctx *t)
{
	if (t->env->cone_cull) {
		/* seed 004 §4: one cone-sphere test for the packet, a few dot
		 * products like one ray's triangle test: a packet-level op */
		thr_count(t, C_CONE_TESTS, 1);
		thr_use(t, UNIT_ISECT, THR_SCALAR_OP, cone_tested);
		return;
	}
	thr_use(t, UNIT_ISECT, thr_pop(t->mask), done);
}

void isu_next(thr_ctx *t)
{
	if (t->k >= t->r.leaf_count || !t->mask) {
		t->env->route.traverse(t);
		return;
	}
	thr_read(t, MEM_TRI, t->list[t->k], MIMG_TRI_BYTES, &t->tri);
	thr_wait_mem(t, fetched);
}
