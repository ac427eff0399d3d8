/*
 * test_engine.c: the event engine (sim/core/engine.h): order, FIFO ties,
 * determinism, cancellation, same-tick scheduling, clock domains, pool
 * growth, run limits and stop.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sim/core/engine.h"
#include "tests/testutil.h"

/* What handlers record: (tick, arg) of every dispatch, in order. */
typedef struct rec {
	uint64_t t[64], arg[64];
	size_t n;
} rec;

static void log_ev(eng *e, void *ctx, uint64_t arg)
{
	rec *r = ctx;
	cr_assert_lt(r->n, 64);
	r->t[r->n] = eng_now(e);
	r->arg[r->n++] = arg;
}

static eng *mk(size_t cap)
{
	eng *e = eng_create(cap);
	cr_assert(e);
	return e;
}

Test(engine, orders_by_time)
{
	eng *e = mk(0);
	rec r = {0};
	uint64_t when[] = {30, 10, 20, 5, 25};
	for (int i = 0; i < 5; i++)
		cr_assert_neq(eng_schedule(e, when[i], log_ev, &r, when[i]), ENG_NONE);
	cr_assert_eq(eng_pending(e), 5);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY);
	uint64_t want[] = {5, 10, 20, 25, 30};
	cr_assert_eq(r.n, 5);
	for (int i = 0; i < 5; i++) {
		cr_assert_eq(r.t[i], want[i]);
		cr_assert_eq(r.arg[i], want[i]);
	}
	cr_assert_eq(eng_now(e), 30);
	cr_assert_eq(eng_events(e), 5);
	cr_assert_eq(eng_pending(e), 0);
	eng_destroy(e);
}

Test(engine, same_tick_runs_fifo)
{
	eng *e = mk(0);
	rec r = {0};
	/* interleave tick-7 events with earlier and later ones */
	for (uint64_t i = 0; i < 8; i++) {
		eng_schedule(e, 7, log_ev, &r, i);
		eng_schedule(e, i % 2 ? 3 : 9, log_ev, &r, 100 + i);
	}
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(r.n, 16);
	for (size_t i = 0; i < 4; i++)
		cr_assert_eq(r.arg[i], 100 + 2 * i + 1); /* tick 3, in schedule order */
	for (size_t i = 0; i < 8; i++)
		cr_assert_eq(r.arg[4 + i], i); /* tick 7 */
	for (size_t i = 0; i < 4; i++)
		cr_assert_eq(r.arg[12 + i], 100 + 2 * i); /* tick 9 */
	eng_destroy(e);
}

/* A little model: each event appends itself to a trace and, driven by an
 * LCG in the context, schedules up to two more, often at equal ticks. */
typedef struct chain {
	uint64_t rng, trace[4096];
	size_t n;
} chain;

static uint64_t lcg(uint64_t *s)
{
	*s = *s * 6364136223846793005ull + 1442695040888963407ull;
	return *s >> 33;
}

static void chain_ev(eng *e, void *ctx, uint64_t arg)
{
	chain *c = ctx;
	if (c->n < 4096)
		c->trace[c->n++] = eng_now(e) << 20 | arg;
	if (c->n < 3000)
		for (int k = 0; k < 2; k++)
			eng_schedule(e, eng_now(e) + lcg(&c->rng) % 4, chain_ev, c,
			             lcg(&c->rng) % 1000);
}

static void run_chain(chain *c)
{
	eng *e = mk(4);
	c->rng = 42;
	c->n = 0;
	for (uint64_t i = 0; i < 10; i++)
		eng_schedule(e, lcg(&c->rng) % 3, chain_ev, c, i);
	eng_run(e, ENG_FOREVER);
	eng_destroy(e);
}

Test(engine, deterministic)
{
	static chain a, b;
	run_chain(&a);
	run_chain(&b);
	cr_assert_gt(a.n, 1000);
	cr_assert_eq(a.n, b.n);
	cr_assert(!memcmp(a.trace, b.trace, a.n * sizeof a.trace[0]));
	for (size_t i = 1; i < a.n; i++)
		cr_assert_geq(a.trace[i] >> 20, a.trace[i - 1] >> 20);
}

/* Mistake: a queue that loses the order of (time, scheduling order), e.g.
 * an event of a tick already queued put before that tick's earlier
 * events, or a later tick before an earlier one. Handlers schedule up to three events
 * each, at their own tick and at ticks shared with queued events; every
 * event must run in the order of (tick, the count of schedule calls before
 * it), which the test keeps itself. */
typedef struct ordmodel {
	uint64_t rng, next;       /* LCG state; schedule calls so far */
	int spread;               /* steps near and far (ord_step) */
	uint64_t when[6000];      /* tick of each scheduled event, by label */
	uint64_t ran[6000], nran; /* labels in the order they ran */
} ordmodel;

/* The tick step of a scheduled event: 0, 5 or 10 ticks; with spread,
 * also steps inside one slot of the engine's wheel but at another tick
 * (700: an event queued behind a later one of its slot), steps across
 * slots, near the end of the wheel's window and past it (the overflow
 * heap: 4.5e6 and 1e9 ticks). */
static uint64_t ord_step(ordmodel *o)
{
	static const uint64_t far[] = {0, 5, 700, 1500, 4000000, 4500000, 1000000000};
	uint64_t r = lcg(&o->rng);
	if (!o->spread || r % 2)
		return r / 2 % 3 * 5;
	return far[r / 2 % (sizeof far / sizeof far[0])];
}

static void ord_ev(eng *e, void *ctx, uint64_t arg)
{
	ordmodel *o = ctx;
	cr_assert_eq(eng_now(e), o->when[arg]);
	o->ran[o->nran++] = arg;
	int k = o->spread ? 1 : (int)(lcg(&o->rng) % 4); /* spread: 20 long chains */
	for (int j = 0; j < k && o->next < 6000; j++) {
		uint64_t t = eng_now(e) + ord_step(o);
		o->when[o->next] = t;
		eng_schedule(e, t, ord_ev, o, o->next++);
	}
}

static void ord_run(int spread)
{
	static ordmodel o;
	memset(&o, 0, sizeof o);
	o.rng = 9;
	o.spread = spread;
	eng *e = mk(0);
	for (; o.next < 20; o.next++) {
		o.when[o.next] = spread && o.next % 3 ? ord_step(&o) : lcg(&o.rng) % 4 * 5;
		eng_schedule(e, o.when[o.next], ord_ev, &o, o.next);
	}
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(o.nran, o.next);
	cr_assert_gt(o.nran, 1000);
	for (uint64_t i = 1; i < o.nran; i++) {
		uint64_t a = o.ran[i - 1], b = o.ran[i];
		cr_assert(o.when[a] < o.when[b] || (o.when[a] == o.when[b] && a < b),
		          "event %llu (tick %llu) ran before %llu (tick %llu)",
		          (unsigned long long)a, (unsigned long long)o.when[a],
		          (unsigned long long)b, (unsigned long long)o.when[b]);
	}
	eng_destroy(e);
}

Test(engine, events_scheduled_by_handlers_run_in_time_then_schedule_order)
{
	ord_run(0);
}

/* Mistake: the wheel appends an event at its slot's tail although the slot
 * holds a later tick, searches its slots from the wrong one, or a pop takes
 * the wheel's first event without comparing it with the overflow heap's
 * (or the other way round): events then run out of (tick, schedule order).
 * Steps reach within a slot, across slots, and past the wheel's window. */
Test(engine, near_and_far_events_run_in_time_then_schedule_order)
{
	ord_run(1);
}

Test(engine, cancel)
{
	eng *e = mk(0);
	rec r = {0};
	eng_id a = eng_schedule(e, 10, log_ev, &r, 1);
	eng_id b = eng_schedule(e, 20, log_ev, &r, 2);
	eng_id c = eng_schedule(e, 30, log_ev, &r, 3);
	cr_assert(a && b && c && a != b && b != c);
	cr_assert_eq(eng_cancel(e, b), 0);
	cr_assert_eq(eng_cancel(e, b), -1, "second cancel is a no-op");
	cr_assert_eq(eng_cancel(e, ENG_NONE), -1);
	cr_assert_eq(eng_cancel(e, (eng_id)1 << 32 | 999999), -1, "never issued");
	cr_assert_eq(eng_pending(e), 2);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY);
	cr_assert_eq(r.n, 2);
	cr_assert_eq(r.arg[0], 1);
	cr_assert_eq(r.arg[1], 3);
	cr_assert_eq(eng_events(e), 2, "cancelled events are not counted");
	cr_assert_eq(eng_cancel(e, a), -1, "already ran");
	/* A stale id must not cancel the event that reuses its record. */
	eng_id d = eng_schedule(e, 40, log_ev, &r, 4);
	cr_assert_neq(d, a);
	cr_assert_eq(eng_cancel(e, a), -1);
	cr_assert_eq(eng_cancel(e, c), -1);
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(r.n, 3);
	cr_assert_eq(r.arg[2], 4);
	eng_destroy(e);
}

/* At tick 10: schedules arg+1 for "now" and cancels the id in ctx->victim. */
typedef struct nowctx {
	rec r;
	eng_id victim;
} nowctx;

static void at_now(eng *e, void *ctx, uint64_t arg)
{
	nowctx *x = ctx;
	log_ev(e, &x->r, arg);
	if (arg == 1) {
		eng_schedule(e, eng_now(e), at_now, x, 99);
		cr_assert_eq(eng_cancel(e, x->victim), 0);
	}
}

Test(engine, schedule_for_current_tick_runs_after_queued_ones)
{
	eng *e = mk(0);
	nowctx x = {0};
	eng_schedule(e, 10, at_now, &x, 1);
	eng_schedule(e, 10, at_now, &x, 2);
	x.victim = eng_schedule(e, 10, at_now, &x, 3);
	eng_schedule(e, 11, at_now, &x, 4);
	cr_assert_eq(eng_run(e, 10), ENG_LIMIT, "the limit is inclusive; 11 is after it");
	cr_assert_eq(x.r.n, 3);
	cr_assert_eq(x.r.arg[0], 1);
	cr_assert_eq(x.r.arg[1], 2);
	cr_assert_eq(x.r.arg[2], 99);
	cr_assert_eq(x.r.t[2], 10);
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(x.r.arg[3], 4);
	eng_destroy(e);
}

Test(engine, clock_domains)
{
	eng_clock core = eng_clock_mhz(533), sdram = eng_clock_mhz(133);
	cr_assert_eq(core.period, 1876);  /* 1e6/533 = 1876.17 */
	cr_assert_eq(sdram.period, 7519); /* 1e6/133 = 7518.80 */
	cr_assert_eq(eng_clock_mhz(1000).period, 1000);
	cr_assert_eq(eng_clock_mhz(1e7).period, 1, "never a zero period");
	cr_assert_eq(eng_cycles_to_ticks(core, 0), 0);
	cr_assert_eq(eng_cycles_to_ticks(core, 533), 533 * 1876);
	cr_assert_eq(eng_ticks_to_cycles(core, 1875), 0);
	cr_assert_eq(eng_ticks_to_cycles(core, 1876), 1);
	/* next edge: t itself on an edge, else the following multiple */
	cr_assert_eq(eng_next_edge(core, 0), 0);
	cr_assert_eq(eng_next_edge(core, 1), 1876);
	cr_assert_eq(eng_next_edge(core, 1876), 1876);
	cr_assert_eq(eng_next_edge(core, 1877), 2 * 1876);
	cr_assert_eq(eng_next_edge(sdram, 3 * 7519 + 1), 4 * 7519);
	/* a core event at cycle 5 waits for the SDRAM edge after it */
	uint64_t t = eng_cycles_to_ticks(core, 5); /* 9380 */
	cr_assert_eq(eng_next_edge(sdram, t), 2 * 7519);
	/* One simulated second of each clock is within 0.03% of its frequency. */
	uint64_t sec = 1000000000000ull;
	cr_assert_lt(llabs((long long)(sec / core.period) - 533000000), 533000000 / 3000);
	cr_assert_lt(llabs((long long)(sec / sdram.period) - 133000000), 133000000 / 3000);
}

typedef struct after {
	eng_clock c;
	uint64_t seen;
} after;

static void after_ev(eng *e, void *ctx, uint64_t arg)
{
	after *a = ctx;
	if (arg == 0) /* at tick 100 (mid-cycle): 3 cycles after the next edge */
		eng_schedule(e, eng_after_cycles(e, a->c, 3), after_ev, a, 1);
	else
		a->seen = eng_now(e);
}

Test(engine, after_cycles_aligns_to_edge)
{
	eng *e = mk(0);
	after a = {eng_clock_mhz(533), 0};
	eng_schedule(e, 100, after_ev, &a, 0);
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(a.seen, 1876 + 3 * 1876);
	eng_destroy(e);
}

static void count_ev(eng *e, void *ctx, uint64_t arg)
{
	uint64_t *last = ctx;
	cr_assert_geq(eng_now(e), last[0]);
	last[0] = eng_now(e);
	last[1]++;
}

Test(engine, pool_grows_to_1e5_events)
{
	eng *e = mk(1); /* start tiny: forces many doublings */
	uint64_t rng = 7, last[2] = {0, 0};
	const int n = 100000;
	for (int i = 0; i < n; i++)
		cr_assert_neq(eng_schedule(e, lcg(&rng) % 50000, count_ev, last, (uint64_t)i),
		              ENG_NONE);
	cr_assert_eq(eng_pending(e), (size_t)n);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY);
	cr_assert_eq(last[1], (uint64_t)n);
	cr_assert_eq(eng_events(e), (uint64_t)n);
	/* steady state: the pool is reused, a second wave needs no growth */
	for (int i = 0; i < n; i++)
		eng_schedule(e, eng_now(e) + (uint64_t)(i % 100), count_ev, last, 0);
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(last[1], 2 * (uint64_t)n);
	eng_destroy(e);
}

static void stop_ev(eng *e, void *ctx, uint64_t arg)
{
	log_ev(e, ctx, arg);
	if (arg == 20)
		eng_stop(e);
}

Test(engine, run_limit_and_stop)
{
	eng *e = mk(0);
	rec r = {0};
	for (uint64_t t = 10; t <= 50; t += 10)
		eng_schedule(e, t, stop_ev, &r, t);
	cr_assert_eq(eng_run(e, 15), ENG_LIMIT);
	cr_assert_eq(r.n, 1);
	cr_assert_eq(eng_now(e), 10, "now stays at the last event, not the limit");
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_STOPPED);
	cr_assert_eq(r.n, 2);
	cr_assert_eq(eng_now(e), 20);
	cr_assert_eq(eng_pending(e), 3);
	eng_stop(e); /* outside a run: no effect */
	cr_assert_eq(eng_run(e, 40), ENG_LIMIT);
	cr_assert_eq(r.n, 4);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY);
	cr_assert_eq(r.n, 5);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY, "empty queue returns at once");
	eng_destroy(e);
}

/* sim/core/fastdiv.h against the division instruction. The mistakes it
 * catches: dropping the correction step (the estimate is one short for
 * about half the dividends), an inverse rounded the other way (2^64 / d
 * rounded up overshoots by one just below multiples of d), and the
 * overflow at t near 2^64. Divisors: the clocks' periods, the L1 line and
 * set counts, small numbers, powers of two and their neighbours, the
 * largest; dividends: around multiples of d and the ends of the range. */
Test(engine, fastdiv_matches_division)
{
	uint64_t ds[] = {1,
	                 2,
	                 3,
	                 7,
	                 36,
	                 455,
	                 1024,
	                 1876,
	                 7519,
	                 1000000,
	                 1u << 31,
	                 (1ull << 32) + 1,
	                 UINT64_MAX / 3,
	                 UINT64_MAX};
	uint64_t x = 88172645463325252ull; /* xorshift64 */
	for (size_t i = 0; i < sizeof ds / sizeof ds[0]; i++) {
		uint64_t d = ds[i];
		fastdiv f = fastdiv_of(d);
		for (int k = 0; k < 20000; k++) {
			x ^= x << 13, x ^= x >> 7, x ^= x << 17;
			uint64_t ts[] = {x,
			                 x >> (k % 64),
			                 (x % 1000) * d,
			                 (x % 1000) * d - 1,
			                 UINT64_MAX - (uint64_t)k,
			                 (uint64_t)k};
			for (size_t j = 0; j < sizeof ts / sizeof ts[0]; j++) {
				uint64_t t = ts[j];
				cr_assert_eq(fastdiv_div(f, t), t / d, "%llu / %llu",
				             (unsigned long long)t, (unsigned long long)d);
				cr_assert_eq(fastdiv_mod(f, t), t % d);
			}
		}
	}
	/* a clock made without eng_clock_mhz (inv 0) still divides */
	eng_clock c = {1876, 0};
	cr_assert_eq(eng_next_edge(c, 1877), 2 * 1876);
	cr_assert_eq(eng_ticks_to_cycles(eng_clock_mhz(533), UINT64_MAX), UINT64_MAX / 1876);
}

/* A slot that emptied keeps its last record's index as a stale tail, and
 * the freed record keeps its event: eng_schedule_or_idle must take the
 * slot's bit, not that record, for whether an event of the tick is still
 * queued. Mistake caught: the stale record compared without the bit (or
 * the bit tested after it), so an event scheduled for the tick of the one
 * that just ran, the same handler on the same context, is counted idle
 * and never runs. */
Test(engine, schedule_or_idle_after_the_slot_emptied_queues)
{
	eng *e = mk(0);
	rec r = {0};
	eng_schedule(e, 300, log_ev, &r, 1);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY);
	eng_schedule_or_idle(e, 300, log_ev, &r, 2); /* the slot is empty now: queued */
	cr_assert_eq(eng_pending(e), 1);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY);
	cr_assert_eq(r.n, 2);
	cr_assert_eq(r.arg[1], 2);
	cr_assert_eq(eng_events(e), 2);
	eng_destroy(e);
}

/* A second handler, to tell handlers apart. */
static void log_ev2(eng *e, void *ctx, uint64_t arg)
{
	log_ev(e, ctx, arg + 1000);
}

/* eng_schedule_or_idle counts the new event instead of queueing it only
 * when the last event queued for its tick is the same handler on the same
 * context. Mistakes caught: the slot's last record taken for the tick's
 * without comparing its tick (a wheel slot spans 1024 ticks: an event at
 * tick 100 would swallow one for tick 200), or without comparing the
 * handler or the context; and an idle event not counted (eng_events) or
 * shifting the order of later same-tick events. */
Test(engine, schedule_or_idle_counts_only_behind_the_same_event)
{
	eng *e = mk(0);
	rec r = {0}, r2 = {0};
	eng_schedule(e, 100, log_ev, &r, 1);
	eng_schedule(e, 300, log_ev, &r, 2);
	eng_schedule(e, 300, log_ev, &r, 3);
	eng_schedule_or_idle(e, 200, log_ev, &r, 4);  /* slot's last is tick 100: queued */
	eng_schedule_or_idle(e, 300, log_ev, &r, 5);  /* behind (log_ev, r) at 300: idle */
	eng_schedule_or_idle(e, 300, log_ev, &r, 6);  /* still behind it: idle */
	eng_schedule_or_idle(e, 300, log_ev, &r2, 7); /* another context: queued */
	eng_schedule_or_idle(e, 300, log_ev, &r, 8);  /* behind r2's: queued */
	eng_schedule_or_idle(e, 300, log_ev2, &r, 9); /* another handler: queued */
	eng_schedule_or_idle(e, 400, log_ev, &r, 10); /* nothing at 400: queued */
	eng_schedule(e, 300, log_ev, &r, 11);         /* after the idle ones, in order */
	cr_assert_eq(eng_pending(e), 9);
	cr_assert_eq(eng_run(e, ENG_FOREVER), ENG_EMPTY);
	uint64_t want[] = {1, 4, 2, 3, 8, 1009, 11, 10};
	cr_assert_eq(r.n, 8);
	for (int i = 0; i < 8; i++)
		cr_assert_eq(r.arg[i], want[i], "event %d: %llu", i, (unsigned long long)r.arg[i]);
	cr_assert_eq(r2.n, 1);
	cr_assert_eq(r2.arg[0], 7);
	cr_assert_eq(eng_events(e), 11, "the two idle events count as dispatched");
	eng_destroy(e);
}
