/*
 * memif.h: the memory interface: arbitration of the miss streams onto SDRAM.
 *
 * Seed 002 §4.1: "All memory requests by the pipelines are handled by the
 * unified memory interface". Requesters are the four L1 miss streams and,
 * with the VMA, its meta-data (tag) traffic and the host-bus fills that
 * write fetched lines into SDRAM. Each requester has a FIFO queue; when the
 * SDRAM can take a new request the interface picks one queue head by policy
 * (fifo: the oldest request overall; round_robin: the next requester after
 * the last one served that has a ready request) and issues it to mem/sdram.
 *
 * "Can take a new request": the interface looks ahead of the data bus by
 * tRCD + CL, so a row hit issued now lands right behind the current
 * transfer and requests arriving meanwhile still compete. Completions are
 * engine events at the tick SDRAM returns. Requests come from a pool that
 * doubles when full (amortized; the steady state never allocates).
 */
#ifndef SAAR_MEM_MEMIF_H
#define SAAR_MEM_MEMIF_H

#include <stdint.h>

#include "mem/memport.h"
#include "mem/sdram.h"
#include "sim/core/engine.h"

enum memif_requester {
	MEMIF_SHADE = MEM_SHADE,
	MEMIF_KD = MEM_KD,
	MEMIF_LIST = MEM_LIST,
	MEMIF_TRI = MEM_TRI,
	MEMIF_META, /* VMA tags and state */
	MEMIF_FILL, /* VMA: lines fetched over the host bus, written to SDRAM */
	MEMIF_NREQ
};

/* fifo: oldest first; round_robin: by requester; frfcfs: first ready,
 * first come (the request whose data can start soonest given its bank's
 * open row and timing, ties to the oldest), over a window of
 * MEMIF_FRFCFS_WINDOW requests per requester queue. */
enum memif_policy { MEMIF_FIFO, MEMIF_ROUND_ROBIN, MEMIF_FRFCFS };
#define MEMIF_FRFCFS_WINDOW 16

/* A queued request. Items live in one pool (memif.pool, indices, MEMIF_NIL
 * ending a list) and are linked into two lists, both in submit order: their
 * requester's queue and, while inside that queue's FR-FCFS window, the
 * list of window items that go to the same SDRAM bank (so a pick looks at
 * one bank's requests at a time: mem/memif.c, pick_frfcfs). */
typedef struct memif_item {
	uint64_t seq, ready, addr;
	uint64_t row; /* addr's SDRAM row and bank, decoded once at submit */
	uint32_t bytes;
	uint16_t bank;
	uint8_t write, req;
	uint32_t qnext, qprev; /* the requester's queue */
	uint32_t bnext, bprev; /* the bank's window items */
	eng_handler done;
	void *ctx;
	uint64_t arg;
} memif_item;

#define MEMIF_NIL       UINT32_MAX
#define MEMIF_ROW_SLOTS 256 /* a power of two */

typedef struct memif_list {
	uint32_t head, tail;
} memif_list;

/* One requester's FIFO: n items, of which the first nwin (at most
 * MEMIF_FRFCFS_WINDOW) are in the window; wend is the first item after it
 * (MEMIF_NIL when every item is inside). */
typedef struct memif_queue {
	memif_list l;
	uint32_t n, nwin, wend;
} memif_queue;

typedef struct memif_stats {
	uint64_t reads[MEMIF_NREQ], writes[MEMIF_NREQ], bytes[MEMIF_NREQ];
	uint64_t queue_ticks[MEMIF_NREQ];   /* time requests waited before SDRAM took them */
	uint64_t latency_ticks[MEMIF_NREQ]; /* submit to data complete (reads) */
} memif_stats;

typedef struct memif {
	eng *e;
	sdram *sd;
	int policy;
	memif_queue q[MEMIF_NREQ];
	memif_item *pool;
	uint32_t cap, free_head;          /* pool size (doubles when full), its free list */
	memif_list bank[SDRAM_MAX_BANKS]; /* window items by SDRAM bank */
	uint64_t banks_used;              /* banks whose list is not empty */
	/* per bank: its window items by row modulo MEMIF_ROW_SLOTS (at most
	 * MEMIF_NREQ * MEMIF_FRFCFS_WINDOW each). 0 in the open row's slot
	 * says no item is a row hit, so the pick stops at the first ready
	 * request (mem/memif.c, bank_best); a slot that other rows share only
	 * makes it look further, never changes the pick. Kept as items come
	 * and go, whatever row is open: an exact count of the open row had to
	 * be walked again after every row change, three picks in four on
	 * dragon2 (docs/PERFORMANCE.md, "Target 2") */
	uint8_t rowcnt[SDRAM_MAX_BANKS][MEMIF_ROW_SLOTS];
	uint64_t queued; /* requests in all queues */
	uint64_t seq;
	int last;  /* requester served last (round robin) */
	int armed; /* a dispatch event is queued */
	uint64_t armed_at;
	uint64_t lead; /* look-ahead in ticks */
	memif_stats s;
} memif;

int memif_init(memif *m, eng *e, sdram *sd, int policy);
void memif_free(memif *m);
int memif_policy_parse(const char *s); /* "fifo" | "round_robin" | "frfcfs", -1 unknown */
/* Queues a request that becomes eligible at tick t (>= eng_now). done is
 * called (if not NULL) through the engine when its data is complete.
 * Returns -1 only when out of memory. */
int memif_submit(memif *m, uint64_t t, int requester, uint64_t addr, uint32_t bytes, int write,
                 eng_handler done, void *ctx, uint64_t arg);
const char *memif_requester_name(int r); /* shade kd list tri meta fill */

#endif
