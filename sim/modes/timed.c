/*
 * timed.c: the timed sink (see timed.h).
 */
#include "sim/modes/timed.h"

#include "sim/modes/base.h"
#include "units/rgs.h"

/* A read arrived; the last one continues the thread. */
static void mem_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	if (--t->pending == 0 && t->cont) {
		void (*c)(thr_ctx *) = t->cont;
		t->cont = NULL;
		c(t);
	}
}

static void timed_read(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes, void *dst)
{
	(void)s;
	mem_req r = mode_base_req(t, type, addr, bytes, 0, dst);
	t->pending++;
	mem_access(t->env->mem, &r, mem_done, t, 0);
}

static void timed_write(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes,
                        const void *src)
{
	(void)s;
	mem_req r = mode_base_req(t, type, addr, bytes, 1, (void *)src);
	mem_access(t->env->mem, &r, NULL, NULL, 0);
}

static void timed_use(thr_sink *s, thr_ctx *t, int kind, int rays, eng_handler done)
{
	(void)s;
	mode_base_use(t, kind, rays);
	thr_set(t, THR_WAIT_UNIT);
	thr_unit_request(&t->rtp->u[kind], t->id, t->age, rays, done, t, 0);
}

/* The thread asks for new work; after a shading op, the RTP's idle
 * threads may take the children it queued. */
static void timed_release(thr_sink *s, thr_ctx *t, int shaded)
{
	(void)s;
	thr_rtp *r = t->rtp;
	mode_base_end(t, shaded);
	t->env->on_free(t);
	if (shaded)
		rgs_dispatch(r);
}

const thr_sink_ops mode_timed_ops = {
    .read = timed_read,
    .write = timed_write,
    .wait = mode_base_wait,
    .use = timed_use,
    .count = mode_base_count,
    .count_max = mode_base_count_max,
    .shade = mode_base_shade,
    .enter = mode_base_enter,
    .spawn = mode_base_spawn,
    .release = timed_release,
};
