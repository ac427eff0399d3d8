/*
 * memport.h: the one memory-port interface every unit uses.
 *
 * A unit asks for bytes by address and requester type (the four SaarCOR L1
 * caches: shading, kd-nodes, lists, triangles; seed 002 §4.1) and gets its
 * answer as an engine event at the tick the data is ready: done(e, ctx, arg).
 * Stack spills are writes (requester KD, write flag); a write without a
 * callback is posted: it is counted and charged but nobody waits for it.
 *
 * The bytes travel with the requests (docs/memory.md, "Data"): a read
 * names where its bytes go (mem_req.data), and by the time done runs they
 * are there, as the memory system holds them at that address (the L1 line
 * on a hit, the line a miss filled from below); a write names the bytes
 * it stores. NULL: the request moves no data (trace and packet-record
 * replays, which time requests without decoding anything).
 *
 * What stands behind the port is a model behind a small vtable
 * (memport_model). This issue has one model, `fixed`: every access is ready
 * memory.latency core cycles after it is issued (no queueing, no bandwidth
 * limit). mem/hier.h adds caches, SDRAM and the VMA as a second model
 * without touching the units. The port itself counts requests and bytes per
 * requester type, whatever the model, and can pass every request to an
 * optional tap (the chip's --trace-mem writer) before the model sees it.
 */
#ifndef SAAR_MEM_MEMPORT_H
#define SAAR_MEM_MEMPORT_H

#include <stdint.h>

#include "sim/core/engine.h"

enum mem_req_type { MEM_SHADE, MEM_KD, MEM_LIST, MEM_TRI, MEM_NTYPES };
/* Ray types a request may name (mem_req.ray): kernel-ref's packet types
 * (primary, shadow, reflection, refraction). */
#define MEM_RAY_TYPES 4

typedef struct mem_req {
	uint64_t addr;
	uint32_t bytes;
	uint8_t type;  /* enum mem_req_type */
	uint8_t write; /* stack spill */
	uint16_t rtp;  /* requesting pipeline */
	/* read: where the bytes go (valid until done runs); write: the bytes
	 * stored (taken at once); NULL: no data */
	void *data;
	/* the type of the packet whose unit asks, + 1 (the L1s count their
	 * lookups and hits by it); 0: no packet's (a trace replay, a test) */
	uint8_t ray;
} mem_req;

/* What the memory system shows an observer of its timing (the timeline,
 * sim/observe.c; docs/observe.md): a span [t0, t1) in engine ticks.
 * L1 miss: a line's fetch from the miss (request below) to its fill; id
 * = the MSHR, type = the L1 (enum mem_req_type). SDRAM: one row's data
 * burst on the data bus; id = the bank, type = enum mem_obs_row. Host
 * bus: one DMA transfer; id 0, type 0. L1 lookup missed: a read's line
 * missed in its L1 at t0 = t1 (a new miss, id 0, or one merged into a
 * fetch on its way, id 1), who = the read's requester (the ctx its done
 * callback gets; the chip's timed reads pass their thread). */
enum mem_obs_kind { MEM_OBS_L1_MISS, MEM_OBS_SDRAM, MEM_OBS_HOSTBUS, MEM_OBS_L1_LOOKUP_MISS };
enum mem_obs_row { MEM_OBS_ROW_HIT, MEM_OBS_ROW_EMPTY, MEM_OBS_ROW_CONFLICT };

typedef struct mem_obs_ev {
	int kind, type, id, write;
	uint64_t t0, t1, addr;
	uint32_t bytes;
	const void *who; /* L1 lookup miss only; else NULL */
} mem_obs_ev;

/* An observer: fn(ctx, ev) at each event. Components hold a pointer to
 * it (NULL: none; one predictable branch where an event happens). */
typedef struct mem_obs {
	void (*fn)(void *ctx, const mem_obs_ev *ev);
	void *ctx;
} mem_obs;

typedef struct mem_counts {
	uint64_t reads[MEM_NTYPES], read_bytes[MEM_NTYPES];
	uint64_t writes[MEM_NTYPES], write_bytes[MEM_NTYPES];
} mem_counts;

/* A memory model: issue one request; call done (if not NULL) through the
 * engine at the tick the data is ready. */
typedef struct memport_model {
	const char *name;
	void (*access)(void *impl, const mem_req *r, eng_handler done, void *ctx, uint64_t arg);
	void (*destroy)(void *impl);
	/* The same request without time (fidelity functional/sampled,
	 * docs/fidelity.md): the functional state (caches, tag cache, VMA) and
	 * the counters move as the timed path would move them; nothing is
	 * scheduled. NULL: the model has no state (fixed). */
	void (*access_func)(void *impl, const mem_req *r);
	/* The bytes a read of r would return now, into dst: no time, no
	 * counter or state change (the shader finds the addresses of its
	 * dependent reads with it, units/rgs.c). */
	void (*peek)(void *impl, const mem_req *r, void *dst);
	/* Nonzero once the model lost data for want of host memory. */
	int (*failed)(const void *impl);
	/* Shows the model's timing events to o from now on (NULL: stop);
	 * NULL: the model has none to show (fixed). */
	void (*observe)(void *impl, const mem_obs *o);
} memport_model;

typedef struct memport {
	const memport_model *model;
	void *impl;
	mem_counts n;
	/* Observer of every request (memory traces); NULL: none. Set after the
	 * mem_init_* call, which clears it. One predictable branch per request. */
	void (*tap)(void *ctx, const mem_req *r);
	void *tap_ctx;
} memport;

struct mem_store;
/* The fixed-latency model: ready `latency` cycles of clk after the request
 * (at the next edge of clk if issued between edges). Its bytes are the
 * store's (mem/store.h; NULL: no data). */
int mem_init_fixed(memport *p, eng *e, eng_clock clk, int latency, struct mem_store *store);
void mem_free(memport *p);

/* Counts one request and shows it to the trace tap: what every access,
 * timed or functional, does first. */
static inline void mem_count(memport *p, const mem_req *r)
{
	if (r->write) {
		p->n.writes[r->type]++;
		p->n.write_bytes[r->type] += r->bytes;
	} else {
		p->n.reads[r->type]++;
		p->n.read_bytes[r->type] += r->bytes;
	}
	if (p->tap)
		p->tap(p->tap_ctx, r);
}

/* Issues one request. done may be NULL only for writes. */
static inline void mem_access(memport *p, const mem_req *r, eng_handler done, void *ctx,
                              uint64_t arg)
{
	mem_count(p, r);
	p->model->access(p->impl, r, done, ctx, arg);
}

/* Issues one request functionally (no answer event; the caller goes on at
 * once): counted like mem_access, then the model's access_func. */
static inline void mem_access_func(memport *p, const mem_req *r)
{
	mem_count(p, r);
	if (p->model->access_func)
		p->model->access_func(p->impl, r);
}

/* Peeks at the bytes a read would return now (memport_model.peek). */
static inline void mem_peek(memport *p, const mem_req *r, void *dst)
{
	p->model->peek(p->impl, r, dst);
}

/* Nonzero once the model lost data for want of host memory. */
static inline int mem_failed(const memport *p)
{
	return p->model && p->model->failed && p->model->failed(p->impl);
}

/* Shows the model's timing events (L1 misses, SDRAM bursts, host-bus
 * transfers) to o from now on; o NULL stops it. o must outlive the
 * model or be removed. Returns -1 when the model has none (fixed). */
int mem_observe(memport *p, const mem_obs *o);

const char *mem_type_name(int type); /* "shade", "kd", "list", "tri" */

#endif
