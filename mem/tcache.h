/*
 * tcache.h: the timed cache component: a cache (mem/cache.h) with its
 * MSHRs' wait lists, the FIFO of requests refused for lack of an MSHR,
 * the MSHRs' line buffers and an access port. One component serves every
 * timed cache of the chip: the four L1s (mem/hier.c; seed 002 §4.1), the
 * VMA's tag cache and its on-board L2 (mem/vma.c; §4.2).
 *
 * The component does not know what waits: a waiter is an opaque pointer
 * (an L1 read, a VMA piece) the user gets back when the line fills or an
 * MSHR frees. Time stays with the user, which fetches the line below and
 * calls back:
 *
 *   tcache_lookup   hit, or a miss that hangs `who` on the line's MSHR
 *                   (new: the user fetches the line; merged: it is on its
 *                   way), or CACHE_MSHR_FULL (nothing changed: the user
 *                   parks `who` with tcache_stall)
 *   tcache_take     the line arrived: its waiters, taken off the MSHR
 *                   before cache_fill frees it; tcache_pop hands them out
 *                   (newest first, the order they were always served in)
 *   tcache_resume   after a fill: the parked requests, oldest first, while
 *                   MSHRs are free; the user's retry says whether the
 *                   request got through (it leaves) or was refused again
 *                   (it stays at the head, and resuming stops)
 *
 * Waiter records come from a free list that grows in chunks: the steady
 * state never allocates.
 */
#ifndef SAAR_MEM_TCACHE_H
#define SAAR_MEM_TCACHE_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "mem/cache.h"
#include "sim/core/engine.h"

typedef struct tc_wait tc_wait;
struct tc_wait {
	void *who;      /* the user's request */
	uint64_t since; /* stall FIFO: when it was parked */
	tc_wait *next;
};

typedef struct tcache {
	cache c;
	tc_wait **wait;              /* per MSHR: its line's waiters, newest first */
	tc_wait *stall, *stall_tail; /* refused for lack of an MSHR, oldest first */
	uint8_t *mbuf;               /* per MSHR: the line on its way (TC_MBUF) */
	uint64_t port_cycle;         /* tcache_port: the cycle being filled */
	uint32_t port_used;          /* accesses accepted in it */
	int oom;                     /* a waiter found no record (it is lost) */
	tc_wait *free_w;
	void *chunks;
} tcache;

enum {
	TC_DATA = 1, /* the cache holds line data (cache_data_on) */
	TC_MBUF = 2, /* a line buffer per MSHR (fills arriving with their bytes) */
};

/* cache_init(p) plus the lists; flags TC_*. Errors name `what`. */
int tcache_init(tcache *t, const cache_params *p, int flags, const char *what, diag *d);
void tcache_free(tcache *t);

/* A waiter record from the free list (tcache_wait_grow: the list is
 * empty; NULL and oom set when out of memory). */
tc_wait *tcache_wait_grow(tcache *t);
static inline tc_wait *tcache_wait_alloc(tcache *t)
{
	tc_wait *w = t->free_w;
	if (__builtin_expect(!w, 0))
		return tcache_wait_grow(t);
	t->free_w = w->next;
	return w;
}

/* One access to one line: cache_lookup, and on a miss (new or merged) who
 * joins the line's MSHR (*mshr its index; *slot the way on a hit). Inline,
 * like tcache_take and tcache_resume: every L1 read and fill runs them. */
static inline cache_result tcache_lookup(tcache *t, uint64_t line, uint32_t bytes, void *who,
                                         int *mshr, uint32_t *slot)
{
	int m = -1;
	cache_result r = cache_lookup(&t->c, line, bytes, &m, slot);
	if (r == CACHE_MISS_NEW || r == CACHE_MISS_MERGED) {
		tc_wait *w = tcache_wait_alloc(t);
		if (w) {
			*w = (tc_wait){who, 0, t->wait[m]};
			t->wait[m] = w;
		}
		if (mshr)
			*mshr = m;
	}
	return r;
}
/* Parks who at the tail of the stall FIFO (since: when, for its wait). */
static inline void tcache_stall(tcache *t, void *who, uint64_t since)
{
	tc_wait *w = tcache_wait_alloc(t);
	if (!w)
		return;
	*w = (tc_wait){who, since, NULL};
	if (t->stall_tail)
		t->stall_tail->next = w;
	else
		t->stall = w;
	t->stall_tail = w;
}
/* Detaches the waiters of line (NULL if it has no MSHR); *mshr gets the
 * MSHR (-1: none) whose buffer holds the line. Call before the fill
 * (cache_fill_mshr with that MSHR: the MSHRs are searched once). */
static inline tc_wait *tcache_take(tcache *t, uint64_t line, int *mshr)
{
	int m = cache_mshr_find(&t->c, line);
	if (mshr)
		*mshr = m;
	if (m < 0)
		return NULL;
	tc_wait *w = t->wait[m];
	t->wait[m] = NULL;
	return w;
}
/* The next waiter of a taken list (NULL at its end); frees its record. */
static inline void *tcache_pop(tcache *t, tc_wait **list)
{
	tc_wait *w = *list;
	if (!w)
		return NULL;
	*list = w->next;
	w->next = t->free_w;
	t->free_w = w;
	return w->who;
}
/* A parked request's wait for an MSHR at tick now: none when it is resumed
 * before the tick it was parked for (its port slot). */
static inline uint64_t tc_waited(uint64_t since, uint64_t now)
{
	return now > since ? now - since : 0;
}
/* Retries the parked requests while an MSHR is free: retry(ctx, who,
 * waited, now) returns 0 when who got through (it leaves the FIFO), 1 when
 * refused again (it stays at the head; resuming stops); waited is its wait
 * for an MSHR so far. A request parked for its port slot may be resumed by
 * a fill before that slot: its wait is then none (tc_waited), not below
 * zero. (It is looked up at the fill, before its slot: a known
 * approximation, docs/memory.md "MSHRs"; looking it up at its slot moves
 * Conference 1024x768's cycles by 0.04-0.06%.) */
typedef int (*tc_retry)(void *ctx, void *who, uint64_t waited, uint64_t now);
static inline void tcache_resume(tcache *t, uint64_t now, tc_retry retry, void *ctx)
{
	while (t->stall && cache_mshr_free(&t->c)) {
		tc_wait *w = t->stall;
		if (retry(ctx, w->who, tc_waited(w->since, now), now))
			break; /* stays at the head */
		t->stall = w->next;
		if (!t->stall)
			t->stall_tail = NULL;
		w->next = t->free_w;
		t->free_w = w;
	}
}

/* The access port: p.ports accesses per cycle of clock clk, in arrival
 * order. Returns the tick at which an access arriving at `now` starts (the
 * start of the first cycle with a free port). */
static inline uint64_t tcache_port(tcache *t, uint64_t now, eng_clock clk)
{
	uint64_t period = clk.period;
	uint64_t cyc = eng_div_period(clk, now + period - 1);
	if (cyc > t->port_cycle) {
		t->port_cycle = cyc;
		t->port_used = 0;
	}
	if (t->port_used == t->c.p.ports) {
		t->port_cycle++;
		t->port_used = 0;
	}
	t->port_used++;
	return t->port_cycle * period;
}

#endif
