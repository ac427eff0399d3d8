/*
 * thread.c: pipelined units with waiting queues, thread state accounting
 * and the packet pool (see thread.h). What a thread's operations do is
 * its sink's (units/sink.h, sim/modes/).
 */
#include "units/thread.h"

#include "kernel-ref/bitset.h"

#include <stdlib.h>
#include <string.h>

/* ======================== pipelined units ======================== */

int thr_unit_init(thr_unit *u, eng *e, eng_clock clk, const unit_params *p, int max_waiters)
{
	memset(u, 0, sizeof *u);
	u->e = e;
	u->clk = clk;
	u->count = p->count > 0 ? p->count : 1;
	u->width = p->width > 0 ? p->width : 1;
	u->latency = p->latency > 0 ? p->latency : 0;
	u->masked = p->masked;
	u->sched = p->sched;
	u->maxw = max_waiters;
	u->rr = max_waiters - 1;
	u->ops_n = &u->own[0];
	u->busy = &u->own[1];
	u->rays = &u->own[2];
	for (int r = 0; r <= THR_SCALAR_OP; r++)
		u->issue[r] = (uint32_t)thr_unit_issue_div(u, r);
	u->free_at = calloc((size_t)u->count, sizeof *u->free_at);
	u->ops = calloc((size_t)max_waiters, sizeof *u->ops);
	u->wait = calloc((size_t)max_waiters, sizeof *u->wait);
	u->wbits = calloc((size_t)bits_words(max_waiters), sizeof *u->wbits);
	return u->free_at && u->ops && u->wait && u->wbits ? 0 : -1;
}

uint64_t thr_unit_host_bytes(int count, int max_waiters)
{
	thr_unit *u = NULL;
	return (uint64_t)(count > 0 ? count : 1) * sizeof *u->free_at +
	       (uint64_t)max_waiters * (sizeof *u->ops + sizeof *u->wait) +
	       (uint64_t)bits_words(max_waiters) * sizeof *u->wbits;
}

void thr_unit_free(thr_unit *u)
{
	free(u->free_at);
	free(u->ops);
	free(u->wait);
	free(u->wbits);
	memset(u, 0, sizeof *u);
}

/* Instance inst takes op now. Always inlined: gcc had kept it a call from
 * every unit request. */
static inline __attribute__((always_inline)) void start(thr_unit *u, int inst, const thr_op *op)
{
	uint64_t t0 = eng_next_edge(u->clk, eng_now(u->e));
	uint64_t issue = thr_unit_count(u, op->rays, 1);
	u->free_at[inst] = t0 + eng_cycles_to_ticks(u->clk, issue);
	if (u->on_start)
		u->on_start(op->ctx, op->arg);
	eng_schedule(u->e, t0 + eng_cycles_to_ticks(u->clk, issue + (uint64_t)u->latency), op->done,
	             op->ctx, op->arg);
}

/* The instance free earliest; *when = its free tick. */
static int first_free(const thr_unit *u, uint64_t *when)
{
	int best = 0;
	for (int i = 1; i < u->count; i++)
		if (u->free_at[i] < u->free_at[best])
			best = i;
	*when = u->free_at[best];
	return best;
}

static void wake(eng *e, void *ctx, uint64_t arg);

static void arm(thr_unit *u)
{
	uint64_t when;
	first_free(u, &when);
	uint64_t now = eng_now(u->e);
	u->wake_pending = 1;
	eng_schedule(u->e, when > now ? when : now, wake, u, 0);
}

/* The waiters, kept so that the policy's next one is found without a scan
 * over every waiting thread (with a thousand threads per RTP that scan was
 * a quarter of the host time): round robin keeps them as a bitset of ids
 * and serves the first id after the one served last; oldest first keeps
 * them in a binary heap on (age, id). Either serves exactly the waiter the
 * plain scan over them would. */
static int older(const thr_unit *u, int a, int b)
{
	uint64_t x = u->ops[a].age, y = u->ops[b].age;
	return x < y || (x == y && a < b);
}

static void heap_push(thr_unit *u, int id)
{
	int i = u->nwait;
	while (i > 0) {
		int parent = (i - 1) / 2;
		if (!older(u, id, u->wait[parent]))
			break;
		u->wait[i] = u->wait[parent];
		i = parent;
	}
	u->wait[i] = id;
}

/* Removes and returns the heap's oldest waiter (nwait not yet lowered). */
static int heap_pop(thr_unit *u)
{
	int top = u->wait[0], n = u->nwait - 1, last = u->wait[n], i = 0;
	for (;;) {
		int c = 2 * i + 1;
		if (c >= n)
			break;
		if (c + 1 < n && older(u, u->wait[c + 1], u->wait[c]))
			c++;
		if (!older(u, u->wait[c], last))
			break;
		u->wait[i] = u->wait[c];
		i = c;
	}
	u->wait[i] = last;
	return top;
}

/* The first waiting id after rr, wrapping round (rr itself last). */
static int rr_pop(thr_unit *u)
{
	int id = bits_next(u->wbits, u->maxw, u->rr + 1);
	if (id == u->maxw)
		id = bits_next(u->wbits, u->maxw, 0);
	bits_clear(u->wbits, id); /* a member: nwait > 0 */
	return id;
}

/* Removes and returns the waiter the policy serves next. */
static int pick(thr_unit *u)
{
	return u->sched == UNIT_SCHED_OLDEST_FIRST ? heap_pop(u) : rr_pop(u);
}

static void wake(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_unit *u = ctx;
	u->wake_pending = 0;
	uint64_t now = eng_now(u->e), when;
	while (u->nwait > 0) {
		int inst = first_free(u, &when);
		if (when > now)
			break;
		int id = pick(u);
		u->nwait--;
		u->rr = id;
		thr_op op = u->ops[id];
		start(u, inst, &op);
	}
	if (u->nwait > 0)
		arm(u);
}

void thr_unit_request(thr_unit *u, int id, uint64_t age, int rays, eng_handler done, void *ctx,
                      uint64_t arg)
{
	thr_op op = {age, rays, done, ctx, arg};
	if (u->nwait == 0) {
		uint64_t when;
		int inst = first_free(u, &when);
		if (when <= eng_now(u->e)) {
			u->rr = id;
			start(u, inst, &op);
			return;
		}
	}
	u->ops[id] = op;
	if (u->sched == UNIT_SCHED_OLDEST_FIRST)
		heap_push(u, id);
	else
		bits_set(u->wbits, id);
	u->nwait++;
	if (!u->wake_pending)
		arm(u);
}

/* ======================== environment ======================== */

#define POOL_CHUNK 64

int thr_env_init(thr_env *v)
{
	memset(v, 0, sizeof *v);
	pkt_precision_full(&v->prec);
	v->hkey = malloc(THR_HASH_SLOTS * sizeof *v->hkey);
	v->hgen = calloc(THR_HASH_SLOTS, sizeof *v->hgen);
	v->hidx = malloc(THR_HASH_SLOTS * sizeof *v->hidx);
	return v->hkey && v->hgen && v->hidx ? 0 : -1;
}

void thr_env_free(thr_env *v)
{
	for (int i = 0; i < v->nchunks; i++)
		free(v->chunks[i]);
	free(v->chunks);
	free(v->freel);
	free(v->hkey);
	free(v->hgen);
	free(v->hidx);
	memset(v, 0, sizeof *v);
}

packet *thr_pkt_alloc(thr_env *v)
{
	if (v->nfree == 0) {
		packet **ch = realloc(v->chunks, (size_t)(v->nchunks + 1) * sizeof *ch);
		if (!ch)
			return NULL;
		v->chunks = ch;
		void *mem = NULL;
		if (posix_memalign(&mem, 64, (POOL_CHUNK * sizeof(packet) + 63) & ~(size_t)63))
			return NULL;
		packet *blk = mem;
		ch[v->nchunks++] = blk;
		if (v->capfree < v->nchunks * POOL_CHUNK) {
			int cap = v->nchunks * POOL_CHUNK * 2;
			packet **fl = realloc(v->freel, (size_t)cap * sizeof *fl);
			if (!fl)
				return NULL;
			v->freel = fl;
			v->capfree = cap;
		}
		for (int i = POOL_CHUNK - 1; i >= 0; i--)
			v->freel[v->nfree++] = &blk[i];
	}
	return v->freel[--v->nfree];
}

void thr_pkt_free(thr_env *v, packet *p)
{
	v->freel[v->nfree++] = p;
}

/* ======================== threads ======================== */

void thr_free_buffers(thr_ctx *t)
{
	free(t->list);
	free(t->spill_in);
	free(t->tl);
	t->tl = NULL;
	free(t->grid);
	t->grid = NULL;
	if (t->sh) {
		free(t->sh->peek);
		free(t->sh->got);
		free(t->sh->rd);
		free(t->sh);
	}
	t->list = NULL;
	t->spill_in = NULL;
	t->sh = NULL;
}

uint64_t thr_rays(const packet *p)
{
	return (uint64_t)thr_pop(p->valid);
}

void thr_on_start(void *ctx, uint64_t arg)
{
	(void)arg;
	thr_set(ctx, THR_RUN);
}
