/*
 * engine.c: the event queue (see engine.h for the contract).
 *
 * One array, a binary min-heap of event records ordered by (when, seq);
 * each record carries its handler, context and argument, so the heap is
 * all there is (no side pool to allocate from and free to). It grows by
 * doubling. The sequence number doubles as the event's id: it is never
 * reused, so an id is stale once its event ran or was cancelled.
 *
 * The running event keeps its root slot while its handler runs (`hole`):
 * the first event the handler schedules takes that slot and sinks from the
 * root, one heap operation where a pop and a push take two; if the
 * handler schedules nothing, the slot is refilled from the last entry after
 * it returns. Either way the heap pops in (when, seq) order, and since no
 * two records share a sequence number the order of events is the same as
 * with any other priority queue.
 *
 * Invariants: heap[i] <= heap[2i+1], heap[2i+2] by (when, seq) for the
 * entries present (with `hole` set, heap[0] is vacant and counts as
 * smallest); a record with h == NULL is cancelled; `live` counts the
 * records with a handler.
 */
#include "sim/core/engine.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

typedef struct hent {
	uint64_t when, seq;
	eng_handler h; /* NULL: cancelled, dropped when it reaches the root */
	void *ctx;
	uint64_t arg;
} hent;

struct eng {
	struct eng_head hd; /* first: eng_now (engine.h) reads it */
	hent *heap;
	uint32_t cap, n; /* slots, entries (with `hole`, heap[0] is one, vacant) */
	int hole;        /* the running event's root slot is still taken */
	size_t live;
	uint64_t seq, dispatched;
	int stop;
};

#define MAX_CAP (UINT32_MAX / 2)

static int grow(eng *e, uint32_t want)
{
	if (want <= e->cap)
		return 0;
	if (want > MAX_CAP)
		return -1;
	hent *h = realloc(e->heap, (size_t)want * sizeof *h);
	if (!h)
		return -1;
	e->heap = h;
	e->cap = want;
	return 0;
}

eng *eng_create(size_t capacity)
{
	eng *e = calloc(1, sizeof *e);
	if (!e)
		return NULL;
	e->seq = 1; /* ids are sequence numbers; 0 is ENG_NONE */
	uint32_t c = capacity < 64 ? 64 : capacity > MAX_CAP ? MAX_CAP : (uint32_t)capacity;
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
	free(e->heap);
	free(e);
}

static int before(const hent *a, const hent *b)
{
	return a->when < b->when || (a->when == b->when && a->seq < b->seq);
}

/* Puts x into the vacant root of heap[0..n): the vacancy moves down to a
 * leaf along the smaller children (one comparison a level), then x rises
 * from there (the last entry, which refills the root, is mostly late: it
 * rises little). */
static void fill_root(hent *h, uint32_t n, const hent *x)
{
	uint32_t i = 0;
	for (;;) {
		uint32_t c = 2 * i + 1;
		if (c >= n)
			break;
		if (c + 1 < n && before(&h[c + 1], &h[c]))
			c++;
		h[i] = h[c];
		i = c;
	}
	while (i > 0) {
		uint32_t p = (i - 1) / 2;
		if (!before(x, &h[p]))
			break;
		h[i] = h[p];
		i = p;
	}
	h[i] = *x;
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

/* Puts x into the vacant root of heap[0..n), sinking it while a child
 * comes before it (an event scheduled by a handler is often among the
 * next few: it stops early). */
static void sink_root(hent *h, uint32_t n, const hent *x)
{
	uint32_t i = 0;
	for (;;) {
		uint32_t c = 2 * i + 1;
		if (c >= n)
			break;
		if (c + 1 < n && before(&h[c + 1], &h[c]))
			c++;
		if (!before(&h[c], x))
			break;
		h[i] = h[c];
		i = c;
	}
	h[i] = *x;
}

/* Takes out the root (vacant or not): the last entry fills it. */
static void drop_root(eng *e)
{
	e->hole = 0;
	if (--e->n)
		fill_root(e->heap, e->n, &e->heap[e->n]);
}

eng_id eng_schedule(eng *e, uint64_t when, eng_handler h, void *ctx, uint64_t arg)
{
	assert(when >= e->hd.now && "event scheduled into the past");
	if (when < e->hd.now)
		when = e->hd.now;
	hent x = {when, e->seq, h, ctx, arg};
	if (e->hole) {
		e->hole = 0;
		sink_root(e->heap, e->n, &x);
	} else {
		if (e->n == e->cap && grow(e, e->cap * 2))
			return ENG_NONE;
		e->heap[e->n] = x;
		sift_up(e->heap, e->n++);
	}
	e->seq++;
	e->live++;
	return (eng_id)x.seq;
}

/* O(n) in the queued events: the simulator never cancels (the tests do). */
int eng_cancel(eng *e, eng_id id)
{
	for (uint32_t i = e->hole ? 1 : 0; i < e->n; i++) {
		if (e->heap[i].seq == id) {
			if (!e->heap[i].h)
				return -1;
			e->heap[i].h = NULL;
			e->live--;
			return 0;
		}
	}
	return -1;
}

eng_status eng_run(eng *e, uint64_t limit)
{
	e->stop = 0;
	while (e->n > 0) {
		const hent *top = &e->heap[0];
		if (!top->h) {
			drop_root(e); /* cancelled: not run, counted or timed */
			continue;
		}
		if (top->when > limit)
			return ENG_LIMIT;
		/* Copy out before the call: the handler may schedule (and so take
		 * the root slot or move the heap) or cancel. */
		eng_handler h = top->h;
		void *ctx = top->ctx;
		uint64_t arg = top->arg;
		e->hd.now = top->when;
		e->live--;
		e->dispatched++;
		e->hole = 1;
		h(e, ctx, arg);
		if (e->hole)
			drop_root(e);
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
