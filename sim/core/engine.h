/*
 * engine.h: the discrete-event engine that drives the chip model.
 *
 * Units never tick: they schedule a handler at the tick their work completes
 * and the engine jumps from one event to the next, so idle hardware costs
 * nothing (ARCHITECTURE.md, "Speed targets").
 *
 * Time. One tick is one picosecond. A clock domain is a period in ticks,
 * period = round(1e6 / MHz): 533 MHz -> 1876 ps (533.05 MHz, +0.009%),
 * 133 MHz -> 7519 ps (132.997 MHz, -0.002%). Rounding to whole picoseconds
 * errs by at most 0.5 ps per period, i.e. < 0.03% up to 1 GHz, and keeps all
 * arithmetic integer and exact. Every domain has an edge at tick 0 (all
 * clocks start in phase).
 *
 * Order. Events run by (when, sequence): the sequence number counts calls to
 * eng_schedule, so events for the same tick run in the order they were
 * scheduled (FIFO). With a deterministic model the dispatch order is
 * therefore a pure function of the schedule calls: runs are reproducible.
 *
 * Cost. Events of the near future (about 4.2 million ticks from eng_now's)
 * go into a wheel of slots of 1024 ticks, each a list sorted by (when,
 * sequence), with a bitmask of the slots in use: eng_schedule and each
 * dispatch take a few steps whatever the number of queued events. Events
 * further ahead go into a binary min-heap (O(log n)); a dispatch takes the
 * first of the two (engine.c). Both grow by doubling, so steady state never
 * mallocs. eng_cancel is O(n) (see below).
 *
 * Same-tick events. A handler may schedule an event for eng_now(): it runs in
 * the same eng_run, after every event already queued for that tick (its
 * sequence number is larger). Scheduling before eng_now() is a bug: it
 * asserts in debug builds and is clamped to eng_now() under NDEBUG.
 *
 * Cancellation is lazy (like Redis' AE_DELETED_EVENT_ID): eng_cancel finds
 * the record (a scan of the queue: the simulator itself never cancels) and
 * marks it; it is dropped when it reaches the top, without running, counting,
 * or advancing time. An id names one scheduling: once the event ran or was
 * cancelled, the id is stale and eng_cancel on it is a no-op (an id is the
 * event's sequence number, never reused).
 */
#ifndef SAAR_SIM_ENGINE_H
#define SAAR_SIM_ENGINE_H

#include <stddef.h>
#include <stdint.h>

#include "sim/core/fastdiv.h"

typedef struct eng eng;
typedef void (*eng_handler)(eng *e, void *ctx, uint64_t arg);

/* Identifies one scheduled event; 0 is never a valid id. */
typedef uint64_t eng_id;
#define ENG_NONE    ((eng_id)0)
#define ENG_FOREVER UINT64_MAX /* eng_run limit: no limit */

/* Why eng_run returned. */
typedef enum eng_status {
	ENG_EMPTY,   /* no live event left */
	ENG_LIMIT,   /* the next event lies after the limit (it stays queued) */
	ENG_STOPPED, /* a handler called eng_stop */
} eng_status;

/* Capacity is a hint for the number of events queued at once (0 is fine).
 * Returns NULL when out of memory. */
eng *eng_create(size_t capacity);
void eng_destroy(eng *e);

/* Queues handler(e, ctx, arg) at tick `when`. Returns its id, or ENG_NONE
 * when the queue cannot grow (out of memory). */
eng_id eng_schedule(eng *e, uint64_t when, eng_handler h, void *ctx, uint64_t arg);
/* Returns 0 if the event was pending and is now cancelled, -1 if the id is
 * stale (already ran, already cancelled) or was never issued. */
int eng_cancel(eng *e, eng_id id);

/* eng_schedule for a caller that knows the event would do nothing if it
 * ran right after another h(ctx) of the same tick (mem/memif.c: a dispatch
 * right behind another): when the last event queued for `when` is h(ctx),
 * the new one is counted, not queued. It takes its sequence number, as
 * eng_schedule would, and counts as dispatched at once, so the events
 * after it keep their order and eng_events, once eng_run has run to the
 * end, is what it would have been. Otherwise (or when `when` is past the
 * wheel's near future) it is eng_schedule. */
eng_id eng_schedule_or_idle(eng *e, uint64_t when, eng_handler h, void *ctx, uint64_t arg);

/* Dispatches events in (when, sequence) order while when <= limit. Returns
 * when the queue holds no live event, the next one is after limit, or a
 * handler called eng_stop (the current handler finishes first; the rest stay
 * queued for the next eng_run). eng_now() stays at the last dispatched
 * event: it never jumps to the limit. */
eng_status eng_run(eng *e, uint64_t limit);
/* Makes the running eng_run return after the current handler. Outside a
 * handler it has no effect (eng_run clears the flag when it starts). */
void eng_stop(eng *e);

/* The first member of struct eng (engine.c), read by the inline eng_now: it
 * is called for nearly every event, from other files. */
struct eng_head {
	uint64_t now; /* tick of the event being/last dispatched */
};
static inline uint64_t eng_now(const eng *e)
{
	return ((const struct eng_head *)(const void *)e)->now;
}

uint64_t eng_events(const eng *e); /* events dispatched so far (not cancelled ones) */
size_t eng_pending(const eng *e);  /* live events queued */

/* ---- clock domains ---- */

typedef struct eng_clock {
	uint64_t period; /* ticks (ps) per cycle, >= 1 */
	/* t / period by a multiplication (sim/core/fastdiv.h), worked out by
	 * eng_clock_mhz; inv 0 (a clock made otherwise) divides */
	uint64_t inv;
} eng_clock;

/* The domain of a clock of mhz MHz: period = round(1e6 / mhz) ps, at least 1.
 * mhz must be > 0. */
eng_clock eng_clock_mhz(double mhz);

/* t / c.period */
static inline uint64_t eng_div_period(eng_clock c, uint64_t t)
{
	return fastdiv_div((fastdiv){c.period, c.inv}, t);
}

static inline uint64_t eng_cycles_to_ticks(eng_clock c, uint64_t cycles)
{
	return cycles * c.period;
}
/* Whole cycles of c that have completed by tick t (rounds down). */
static inline uint64_t eng_ticks_to_cycles(eng_clock c, uint64_t t)
{
	return eng_div_period(c, t);
}
/* The first tick >= t that is an edge of c (edges at multiples of period). */
static inline uint64_t eng_next_edge(eng_clock c, uint64_t t)
{
	uint64_t r = t - eng_div_period(c, t) * c.period;
	return r ? t + (c.period - r) : t;
}
/* The tick n cycles of c from now: the next edge of c at or after eng_now,
 * plus n periods. This is how a unit says "done in `latency` core cycles"
 * and memory says "at the next SDRAM edge" (n = 0). */
static inline uint64_t eng_after_cycles(const eng *e, eng_clock c, uint64_t n)
{
	return eng_next_edge(c, eng_now(e)) + eng_cycles_to_ticks(c, n);
}

#endif
