/*
 * functional.c: the functional sink (see functional.h).
 */
#include "sim/modes/functional.h"

#include "sim/modes/base.h"
#include "sim/modes/slot.h"

static void func_read(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes, void *dst)
{
	(void)s;
	mem_req r = mode_base_req(t, type, addr, bytes, 0, dst);
	mem_access_func(t->env->mem, &r);
}

static void func_write(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes,
                       const void *src)
{
	(void)s;
	mem_req r = mode_base_req(t, type, addr, bytes, 1, (void *)src);
	mem_access_func(t->env->mem, &r);
}

static void func_use(thr_sink *s, thr_ctx *t, int kind, int rays, eng_handler done)
{
	(void)s;
	/* the op's counts as its issue makes them (thread.c start), without
	 * its time */
	mode_base_use_issue(t, kind, rays, thr_unit_count(&t->rtp->u[kind], rays, 1));
	mode_slot_state *m = mode_slot(t);
	m->fnext = done;
	m->fkind = kind;
	m->frays = rays;
}

/* The driver gives the free thread its next packet. */
static void func_release(thr_sink *s, thr_ctx *t, int shaded)
{
	(void)s;
	mode_base_end(t, shaded);
}

const thr_sink_ops mode_func_ops = {
    .read = func_read,
    .write = func_write,
    .wait = mode_base_wait,
    .use = func_use,
    .count = mode_base_count,
    .count_max = mode_base_count_max,
    .shade = mode_base_shade,
    .enter = mode_base_enter,
    .spawn = mode_base_spawn,
    .release = func_release,
};

void mode_func_to_timed(thr_ctx *t)
{
	mode_slot_state *m = mode_slot(t);
	eng_handler done = m->fnext;
	if (!done)
		return;
	m->fnext = NULL;
	thr_unit *u = &t->rtp->u[m->fkind];
	thr_unit_count(u, m->frays, -1);
	thr_set(t, THR_WAIT_UNIT);
	thr_unit_request(u, t->id, t->age, m->frays, done, t, 0);
}

int mode_func_step(thr_ctx *t)
{
	mode_slot_state *m = mode_slot(t);
	eng_handler h = m->fnext;
	if (!h)
		return 0;
	m->fnext = NULL;
	h(t->env->e, t, 0);
	return 1;
}
