/*
 * engine.c: the event queue (see engine.h for the contract).
 *
 * Two queues, both ordered by (when, seq); a pop takes the smaller of
 * their firsts, so events run in (when, seq) order whichever holds them.
 *
 * The wheel holds the near future: ENG_SLOTS slots of ENG_SLOT_TICKS
 * ticks each, covering the ENG_SLOTS * ENG_SLOT_TICKS ticks from the
 * start of the slot of eng_now (about 2200 cycles of a 533 MHz core).
 * A slot is a list of event records sorted by (when, seq); since a new
 * event's sequence number is larger than any queued one's, it goes after
 * every queued event of its tick, mostly at the slot's tail (a slot spans
 * about one core cycle, so it rarely holds more than one tick). A bitmask
 * of the slots that hold events finds the first one from eng_now's slot
 * on, wrapping round. Every queued event lies at or after eng_now and was
 * inside the window when queued, so the slots from eng_now's on, in
 * order, hold the wheel's events in (when, seq) order. Records come from
 * a pool (indices; a free list) that doubles when full.
 *
 * Events further away go to a binary min-heap of records (the overflow;
 * few events are that far ahead). The sequence number doubles as the
 * event's id: it is never reused, so an id is stale once its event ran or
 * was cancelled. Both queues keep a cancelled record (h == NULL) until it
 * comes first; `cancelled` counts those still queued, `dropped` those
 * taken out. Live events and dispatched ones are worked out from these
 * and the sequence number when asked (eng_pending, eng_events), so
 * scheduling and dispatching keep no count of their own.
 *
 * Why a wheel (docs/PERFORMANCE.md, "Profile"): the heap alone spent about
 * a fifth of cycle mode's instructions sinking and refilling its root,
 * log n levels of (when, seq) comparisons per event, where a slot takes an
 * event in a few instructions.
 */
#include "sim/core/engine.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define ENG_SLOT_BITS  10 /* a slot spans 1024 ticks (ps) */
#define ENG_SLOT_TICKS ((uint64_t)1 << ENG_SLOT_BITS)
#define ENG_SLOTS      4096 /* a power of two, a multiple of 64 */
#define ENG_WORDS      (ENG_SLOTS / 64)
#define ENG_NIL        UINT32_MAX

typedef struct hent {
	uint64_t when, seq;
	eng_handler h; /* NULL: cancelled, dropped when it comes first */
	void *ctx;
	uint64_t arg;
} hent;

/* A wheel record: an event and the next of its slot (or of the free
 * list). */
typedef struct wrec {
	hent ev;
	uint32_t next;
} wrec;

struct eng {
	struct eng_head hd; /* first: eng_now (engine.h) reads it */
	/* the wheel */
	wrec *pool;
	uint32_t pcap, pfree; /* records, the first free one */
	uint32_t wn;          /* events in the wheel */
	uint32_t head[ENG_SLOTS], tail[ENG_SLOTS];
	uint64_t used[ENG_WORDS]; /* slots that hold events */
	/* the overflow heap: heap[i] <= heap[2i+1], heap[2i+2] by (when, seq) */
	hent *heap;
	uint32_t cap, n;
	uint64_t seq;       /* the next event's; seq - 1 events were queued */
	uint64_t cancelled; /* cancelled records still queued */
	uint64_t dropped;   /* cancelled records taken out */
	int stop;
};

#define MAX_CAP (UINT32_MAX / 2)

static int grow_heap(eng *e, uint32_t want)
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

/* Pool records [pcap, want) join the free list. */
static int grow_pool(eng *e, uint32_t want)
{
	if (want <= e->pcap)
		return 0;
	if (want > MAX_CAP)
		return -1;
	wrec *p = realloc(e->pool, (size_t)want * sizeof *p);
	if (!p)
		return -1;
	e->pool = p;
	for (uint32_t i = want; i-- > e->pcap;) {
		p[i].next = e->pfree;
		e->pfree = i;
	}
	e->pcap = want;
	return 0;
}

eng *eng_create(size_t capacity)
{
	eng *e = calloc(1, sizeof *e);
	if (!e)
		return NULL;
	e->seq = 1; /* ids are sequence numbers; 0 is ENG_NONE */
	e->pfree = ENG_NIL;
	memset(e->head, 0xff, sizeof e->head);
	memset(e->tail, 0xff, sizeof e->tail);
	uint32_t c = capacity < 64 ? 64 : capacity > MAX_CAP ? MAX_CAP : (uint32_t)capacity;
	if (grow_pool(e, c) || grow_heap(e, 64)) {
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
	free(e->pool);
	free(e);
}

static int before(const hent *a, const hent *b)
{
	return a->when < b->when || (a->when == b->when && a->seq < b->seq);
}

/* ---- the overflow heap ---- */

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

/* Takes out the root: the last entry sinks from there. */
static void heap_pop(eng *e)
{
	hent *h = e->heap;
	uint32_t n = --e->n, i = 0;
	if (!n)
		return;
	hent x = h[n];
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

/* ---- the wheel ---- */

static uint32_t slot_of(uint64_t when)
{
	return (uint32_t)(when >> ENG_SLOT_BITS) & (ENG_SLOTS - 1);
}

/* The first slot from s on (wrapping round) that holds events; the
 * wheel must hold one. */
static uint32_t first_used(const eng *e, uint32_t s)
{
	uint32_t w = s / 64;
	uint64_t m = e->used[w] & (~(uint64_t)0 << (s % 64));
	while (!m) {
		w = (w + 1) % ENG_WORDS;
		m = e->used[w];
	}
	return w * 64 + (uint32_t)__builtin_ctzll(m);
}

/* Links pool record i (its event set) into its slot, after every event of
 * the slot at or before its tick (its sequence number is the largest). */
static inline void wheel_link(eng *e, uint32_t i)
{
	wrec *p = e->pool;
	uint64_t when = p[i].ev.when;
	uint32_t s = slot_of(when);
	uint64_t *u = &e->used[s / 64], bit = (uint64_t)1 << (s % 64);
	/* An empty slot (its bit clear; its tail is stale then) and an
	 * append to a used one take the same path, without a branch on which
	 * it is: whether a slot holds events is as good as random to the
	 * host's branch predictor. Empty, the record compares with itself and
	 * links from the slot's head; used, from the slot's tail. */
	uint32_t em = (uint32_t)(*u >> (s % 64) & 1) - 1; /* all ones: empty */
	uint32_t t = (i & em) | (e->tail[s] & ~em);
	if (p[t].ev.when <= when) {
		e->head[s] = (i & em) | (e->head[s] & ~em);
		p[t].next = i; /* empty: p[i].next, set just below */
		p[i].next = ENG_NIL;
		e->tail[s] = i;
		*u |= bit;
	} else { /* an earlier tick than the slot's last: walk (the tail stops it) */
		uint32_t prev = ENG_NIL, c = e->head[s];
		while (p[c].ev.when <= when) {
			prev = c;
			c = p[c].next;
		}
		p[i].next = c;
		if (prev == ENG_NIL)
			e->head[s] = i;
		else
			p[prev].next = i;
	}
	e->wn++;
}

/* eng_schedule's rare cases, out of line: an event past the wheel's
 * window (into the heap), or a full pool. It takes the event's parts, not
 * a record: a record built by eng_schedule cost every call a stack frame. */
static __attribute__((noinline)) eng_id schedule_slow(eng *e, uint64_t when, eng_handler h,
                                                      void *ctx, uint64_t arg, int far)
{
	hent x = {when, e->seq, h, ctx, arg};
	if (far) {
		if (e->n == e->cap && grow_heap(e, e->cap * 2))
			return ENG_NONE;
		e->heap[e->n] = x;
		sift_up(e->heap, e->n++);
	} else {
		if (grow_pool(e, e->pcap * 2))
			return ENG_NONE;
		uint32_t i = e->pfree;
		e->pfree = e->pool[i].next;
		e->pool[i].ev = x;
		wheel_link(e, i);
	}
	e->seq++;
	return (eng_id)x.seq;
}

/* eng_schedule, and with idle_behind set eng_schedule_or_idle: the new
 * event is counted, not queued, when the last event queued for its tick
 * is h(ctx) (the slot's last record is its last event by (when, seq): one
 * for another tick says no; the overflow heap's events for a tick run
 * before the wheel's, which were queued after them). */
static inline __attribute__((always_inline)) eng_id
schedule_in(eng *e, uint64_t when, eng_handler h, void *ctx, uint64_t arg, int idle_behind)
{
	assert(when >= e->hd.now && "event scheduled into the past");
	if (when < e->hd.now)
		when = e->hd.now;
	uint64_t seq = e->seq;
	/* the window: the ENG_SLOTS slots from the start of eng_now's */
	uint64_t base = e->hd.now & ~(ENG_SLOT_TICKS - 1);
	int far = when - base >= ENG_SLOTS * ENG_SLOT_TICKS;
	if (__builtin_expect(far || e->pfree == ENG_NIL, 0))
		return schedule_slow(e, when, h, ctx, arg, far);
	if (idle_behind) {
		uint32_t s = slot_of(when);
		if (e->used[s / 64] >> (s % 64) & 1) { /* else its tail is stale */
			const hent *t = &e->pool[e->tail[s]].ev;
			if (t->when == when && t->h == h && t->ctx == ctx) {
				e->seq = seq + 1; /* counted as dispatched: seq - 1 - queued */
				return (eng_id)seq;
			}
		}
	}
	uint32_t i = e->pfree;
	wrec *r = &e->pool[i];
	e->pfree = r->next;
	r->ev = (hent){when, seq, h, ctx, arg};
	wheel_link(e, i);
	e->seq = seq + 1;
	return (eng_id)seq;
}

eng_id eng_schedule(eng *e, uint64_t when, eng_handler h, void *ctx, uint64_t arg)
{
	return schedule_in(e, when, h, ctx, arg, 0);
}

eng_id eng_schedule_or_idle(eng *e, uint64_t when, eng_handler h, void *ctx, uint64_t arg)
{
	return schedule_in(e, when, h, ctx, arg, 1);
}

/* O(n) in the queued events: the simulator never cancels (the tests do).
 * The wheel's queued records are those of its used slots' lists (a free
 * record keeps the sequence number of the event it held). */
int eng_cancel(eng *e, eng_id id)
{
	hent *x = NULL;
	for (uint32_t i = 0; i < e->n && !x; i++)
		if (e->heap[i].seq == id)
			x = &e->heap[i];
	for (uint32_t s = 0; s < ENG_SLOTS && !x && id; s++) {
		if (!(e->used[s / 64] >> (s % 64) & 1))
			continue;
		for (uint32_t i = e->head[s]; i != ENG_NIL && !x; i = e->pool[i].next)
			if (e->pool[i].ev.seq == id)
				x = &e->pool[i].ev;
	}
	if (!x || !x->h)
		return -1;
	x->h = NULL;
	e->cancelled++;
	return 0;
}

eng_status eng_run(eng *e, uint64_t limit)
{
	e->stop = 0;
	for (;;) {
		/* the first event: the wheel's or the overflow's, by (when, seq);
		 * a wheel record (nearly every event) stays in hand, with its
		 * index, for its removal below (a separate pop read the slot's
		 * head again) */
		eng_handler h;
		void *ctx;
		uint64_t arg, when;
		uint32_t s = 0, i = 0;
		wrec *r = NULL;
		if (e->wn) {
			s = first_used(e, slot_of(e->hd.now));
			i = e->head[s];
			r = &e->pool[i];
			if (e->n && before(&e->heap[0], &r->ev))
				r = NULL;
		} else if (!e->n) {
			return ENG_EMPTY;
		}
		const hent *top = r ? &r->ev : &e->heap[0];
		h = top->h;
		when = top->when;
		if (h && when > limit)
			return ENG_LIMIT;
		/* copy out, then take it out: the handler may schedule (and so
		 * move the heap or the pool) or cancel */
		ctx = top->ctx;
		arg = top->arg;
		if (r) { /* out of its slot, into the free list */
			/* the slot's bit cleared when it empties, without a branch
			 * (see wheel_link: its tail is not reset) */
			uint32_t next = r->next;
			e->head[s] = next;
			e->used[s / 64] &= ~((uint64_t)(next == ENG_NIL) << (s % 64));
			r->next = e->pfree;
			e->pfree = i;
			e->wn--;
		} else {
			heap_pop(e);
		}
		if (!h) { /* cancelled: not run, counted or timed */
			e->cancelled--;
			e->dropped++;
			continue;
		}
		e->hd.now = when;
		h(e, ctx, arg);
		if (e->stop) {
			e->stop = 0;
			return ENG_STOPPED;
		}
	}
}

void eng_stop(eng *e)
{
	e->stop = 1;
}

uint64_t eng_events(const eng *e)
{
	/* every event queued is still queued, was dropped, or ran */
	return e->seq - 1 - e->wn - e->n - e->dropped;
}

size_t eng_pending(const eng *e)
{
	return (size_t)(e->wn + e->n - e->cancelled);
}

eng_clock eng_clock_mhz(double mhz)
{
	assert(mhz > 0);
	long long p = llround(1e6 / mhz);
	uint64_t period = p < 1 ? 1 : (uint64_t)p;
	return (eng_clock){period, fastdiv_of(period).inv};
}
