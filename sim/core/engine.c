/*
 * engine.c: the event queue (see engine.h for the contract).
 *
 * Two arrays. The pool holds one record per scheduled event (handler, ctx,
 * arg, generation, state); free records are chained through `next_free`. The
 * heap holds (when, seq, slot) triples, so sift operations compare keys
 * without touching the pool. Both grow by doubling; the heap never holds more
 * entries than the pool has records, so it is sized with the pool.
 *
 * Invariants: heap[i] <= heap[2i+1], heap[2i+2] by (when, seq); a record is
 * LIVE or CANCELLED exactly while one heap entry names it, and FREE
 * otherwise; `live` counts LIVE records.
 */
#include "sim/core/engine.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

enum { FREE, LIVE, CANCELLED };

typedef struct ev {
	eng_handler h;
	void *ctx;
	uint64_t arg;
	uint32_t gen; /* bumped when the record is freed: stale ids stop matching */
	uint32_t state;
	uint32_t next_free;
} ev;

typedef struct hent {
	uint64_t when, seq;
	uint32_t slot;
} hent;

struct eng {
	ev *pool;
	hent *heap;
	uint32_t cap, nheap, free_head, live;
	uint64_t now, seq, dispatched;
	int stop;
};

#define NIL UINT32_MAX

/* Links records [from, to) into the free list in index order. */
static void link_free(eng *e, uint32_t from, uint32_t to)
{
	for (uint32_t i = from; i < to; i++) {
		e->pool[i] =
		    (ev){.gen = 1, .state = FREE, .next_free = i + 1 < to ? i + 1 : e->free_head};
	}
	if (from < to)
		e->free_head = from;
}

static int grow(eng *e, uint32_t want)
{
	if (want <= e->cap)
		return 0;
	if (want > NIL / 2)
		return -1;
	ev *p = realloc(e->pool, (size_t)want * sizeof *p);
	if (!p)
		return -1;
	e->pool = p;
	hent *h = realloc(e->heap, (size_t)want * sizeof *h);
	if (!h)
		return -1; /* pool is larger but cap unchanged: still consistent */
	e->heap = h;
	link_free(e, e->cap, want);
	e->cap = want;
	return 0;
}

eng *eng_create(size_t capacity)
{
	eng *e = calloc(1, sizeof *e);
	if (!e)
		return NULL;
	e->free_head = NIL;
	uint32_t c = capacity < 64 ? 64 : capacity > NIL / 2 ? NIL / 2 : (uint32_t)capacity;
	if (grow(e, c)) {
		eng_destroy(e);
		return NULL;
	}
	return e;
}

void eng_destroy(eng *e)
{
	if (!e)
		return;
	free(e->pool);
	free(e->heap);
	free(e);
}

static int before(const hent *a, const hent *b)
{
	return a->when < b->when || (a->when == b->when && a->seq < b->seq);
}

static void sift_up(hent *h, uint32_t i)
{
	hent x = h[i];
	while (i > 0) {
		uint32_t p = (i - 1) / 2;
		if (!before(&x, &h[p]))
			break;
		h[i] = h[p];
		i = p;
	}
	h[i] = x;
}

static void sift_down(hent *h, uint32_t n, uint32_t i)
{
	hent x = h[i];
	for (;;) {
		uint32_t c = 2 * i + 1;
		if (c >= n)
			break;
		if (c + 1 < n && before(&h[c + 1], &h[c]))
			c++;
		if (!before(&h[c], &x))
			break;
		h[i] = h[c];
		i = c;
	}
	h[i] = x;
}

eng_id eng_schedule(eng *e, uint64_t when, eng_handler h, void *ctx, uint64_t arg)
{
	assert(when >= e->now && "event scheduled into the past");
	if (when < e->now)
		when = e->now;
	if (e->free_head == NIL && grow(e, e->cap * 2))
		return ENG_NONE;
	uint32_t s = e->free_head;
	ev *v = &e->pool[s];
	e->free_head = v->next_free;
	v->h = h;
	v->ctx = ctx;
	v->arg = arg;
	v->state = LIVE;
	e->heap[e->nheap] = (hent){when, e->seq++, s};
	sift_up(e->heap, e->nheap++);
	e->live++;
	return (eng_id)v->gen << 32 | s;
}

int eng_cancel(eng *e, eng_id id)
{
	uint32_t s = (uint32_t)id, gen = (uint32_t)(id >> 32);
	if (s >= e->cap || e->pool[s].gen != gen || e->pool[s].state != LIVE)
		return -1;
	e->pool[s].state = CANCELLED;
	e->live--;
	return 0;
}

static void release(eng *e, uint32_t s)
{
	ev *v = &e->pool[s];
	v->state = FREE;
	if (++v->gen == 0) /* keep ids non-zero after wrap-around */
		v->gen = 1;
	v->next_free = e->free_head;
	e->free_head = s;
}

eng_status eng_run(eng *e, uint64_t limit)
{
	e->stop = 0;
	while (e->nheap > 0) {
		hent top = e->heap[0];
		ev *v = &e->pool[top.slot];
		if (v->state == LIVE && top.when > limit)
			return ENG_LIMIT;
		e->heap[0] = e->heap[--e->nheap];
		if (e->nheap)
			sift_down(e->heap, e->nheap, 0);
		if (v->state == CANCELLED) {
			release(e, top.slot);
			continue;
		}
		/* Copy out and free before the call: the handler may schedule (and
		 * so reuse this record or move the pool) or cancel its own id. */
		eng_handler h = v->h;
		void *ctx = v->ctx;
		uint64_t arg = v->arg;
		release(e, top.slot);
		e->live--;
		e->now = top.when;
		e->dispatched++;
		h(e, ctx, arg);
		if (e->stop) {
			e->stop = 0;
			return ENG_STOPPED;
		}
	}
	return ENG_EMPTY;
}

void eng_stop(eng *e)
{
	e->stop = 1;
}

uint64_t eng_now(const eng *e)
{
	return e->now;
}

uint64_t eng_events(const eng *e)
{
	return e->dispatched;
}

size_t eng_pending(const eng *e)
{
	return e->live;
}

eng_clock eng_clock_mhz(double mhz)
{
	assert(mhz > 0);
	long long p = llround(1e6 / mhz);
	return (eng_clock){p < 1 ? 1 : (uint64_t)p};
}
