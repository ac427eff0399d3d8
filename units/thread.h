/*
 * thread.h: thread contexts, pipelined units and how threads share them.
 *
 * A thread is one packet in flight on one RTP (SaarCOR seed 002 §4.4: "each
 * packet of rays forms a thread"): the packet, its traversal state and
 * stack, where it is in its life (ray generation, traversal, list,
 * intersection, shading) and what it is doing right now (enum thr_state).
 * A thread has at most one thing outstanding: memory reads, or one
 * operation queued at or running in a unit. While it waits, other threads
 * use the units: that is all the latency hiding there is.
 *
 * A unit kind of one RTP (thr_unit) is `count` identical pipelined units
 * with issue width `width` rays/cycle and latency `latency` cycles. An op of
 * r rays (r = 64 when chip.masked_packets, else the active rays) issues for
 * ceil(r / width) cycles and completes `latency` cycles after its issue
 * cycles end: done = start + issue + latency. The unit accepts the next op
 * when the issue cycles end (pipelined). When every instance is busy the
 * request waits; when one frees, the pick policy (round robin over thread
 * ids, or oldest packet first) chooses among the waiting threads. All of it
 * is events: an idle unit schedules nothing.
 *
 * What a unit's operations cost (memory reads, unit ops, the packet's
 * end) is the environment's sink's (units/sink.h, sim/modes/): the unit
 * files emit them through thr_read, thr_use, ... below and never ask which
 * mode runs. The unit pipelines' timing (thr_unit) lives here; the
 * functional work is done by
 * kernel-ref calls (packet.h, shade.h) in exactly kernel-ref's order, on
 * the bytes the thread's reads returned (kd-nodes, list entries, triangle
 * records, spilled stack entries, shading records): a unit never looks at
 * the host's copy of the scene (thr_env.m has the region bases and the
 * scene box, the registers the host sets, and no bytes).
 */
#ifndef SAAR_UNITS_THREAD_H
#define SAAR_UNITS_THREAD_H

#include <stdint.h>

#include "kernel-ref/camera.h"
#include "kernel-ref/cone.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/shade.h"
#include "kernel-ref/tlimage.h"
#include "mem/memport.h"
#include "sim/core/engine.h"
#include "units/sink.h"
#include "units/unit_table.h"

/* Unit kinds (enum unit_kind), their parameters and routing: unit_table.h. */
enum thr_state { THR_IDLE, THR_RUN, THR_WAIT_MEM, THR_WAIT_UNIT, THR_NSTATES };

/* Bytes of one hardware traversal stack entry: node index (4), ray mask
 * (8), per-ray entry and exit distance (64 x 2 x 4). Spills move this much. */
#define THR_STACK_ENTRY_BYTES 524u
#define THR_SPILL_STRIDE      1024u
#define THR_HASH_SLOTS        2048u /* shading read de-duplication, > 2 x SHADE_LOG_CAP */

/* Test hooks (thr_env.mutant): a unit that asks for the wrong address,
 * which data-carrying memory must turn into a wrong image. */
enum thr_mutant {
	THR_MUT_NONE,
	THR_MUT_KD_SIBLING, /* the traversal unit reads a node's sibling instead */
	/* packet-record replay (sim/modes/replay.c) reads each triangle
	 * record at the next one's address: the replay's checksums must see it */
	THR_MUT_REPLAY_NEXT_TRI,
	/* the grid unit reads a cell's list one entry further on */
	THR_MUT_GRID_LIST_NEXT,
};

/* ---- pipelined units ---- */

/* The `rays` of a packet-level op: one computation for the whole packet
 * (the cone test of seed 004, units/intersection.c), one issue cycle and
 * counted as one ray whether or not packets are masked. */
#define THR_SCALAR_OP (PKT_RAYS + 1)
/* The rays an op of `rays` counts (a packet-level op: one). */
static inline int thr_op_rays(int rays)
{
	return rays == THR_SCALAR_OP ? 1 : rays;
}

typedef struct thr_op {
	uint64_t age;
	int rays;
	eng_handler done;
	void *ctx;
	uint64_t arg;
} thr_op;

typedef struct thr_unit {
	eng *e;
	eng_clock clk;
	int count, width, latency, masked, sched;
	uint64_t *free_at;      /* per instance: tick it accepts the next op */
	thr_op *ops;            /* per requester id: its waiting op */
	int *wait, nwait, maxw; /* oldest first: a heap of waiting ids on (age, id) */
	uint64_t *wbits;        /* round robin: waiting ids (bitset.h) */
	int rr;                 /* round robin: id served last */
	int wake_pending;
	/* called when an op issues (the requester stops waiting) */
	void (*on_start)(void *ctx, uint64_t arg);
	uint64_t *ops_n, *busy, *rays; /* counters; point at own[] if unregistered */
	uint64_t own[3];
	/* issue cycles by active rays (thr_unit_issue), computed once: every
	 * op, timed or functional, needs it, and a division per op showed in
	 * functional runs' profiles */
	uint32_t issue[THR_SCALAR_OP + 1];
} thr_unit;

/* count/width/latency, masked (charge 64 rays per op) and sched (enum
 * unit_sched) from p; max_waiters: requester ids are 0..max_waiters-1. */
int thr_unit_init(thr_unit *u, eng *e, eng_clock clk, const unit_params *p, int max_waiters);
void thr_unit_free(thr_unit *u);
/* Host bytes thr_unit_init allocates for count instances and max_waiters
 * requesters (the run's memory estimate, sim/hostmem.c). */
uint64_t thr_unit_host_bytes(int count, int max_waiters);
/* Issue cycles of an op with `rays` active rays. Inline, division and
 * all: as a call, the rare division made every op's counting (thr_unit_count,
 * the functional sink's use) save and restore registers. */
static inline uint64_t thr_unit_issue_div(const thr_unit *u, int rays)
{
	if (rays == THR_SCALAR_OP)
		return 1;
	int r = u->masked ? PKT_RAYS : rays;
	uint64_t c = ((uint64_t)r + (uint64_t)u->width - 1) / (uint64_t)u->width;
	return c ? c : 1;
}
static inline uint64_t thr_unit_issue(const thr_unit *u, int rays)
{
	return rays >= 0 && rays <= THR_SCALAR_OP ? u->issue[rays] : thr_unit_issue_div(u, rays);
}
/* Counts (sign 1) or takes back (sign -1) one op of `rays` rays at u:
 * ops, issue cycles, rays. The one place an op's counts are made: at
 * issue (thread.c), in a functional op, and taken back when a functional
 * op becomes a timed one (sim/modes/functional.c). Returns the issue
 * cycles. */
static inline uint64_t thr_unit_count(thr_unit *u, int rays, int sign)
{
	uint64_t issue = thr_unit_issue(u, rays), s = (uint64_t)(int64_t)sign;
	*u->ops_n += s;
	*u->busy += s * issue;
	*u->rays += s * (uint64_t)thr_op_rays(rays);
	return issue;
}
/* Requests one op for requester id (at most one outstanding per id). done
 * runs at issue start + issue cycles + latency. */
void thr_unit_request(thr_unit *u, int id, uint64_t age, int rays, eng_handler done, void *ctx,
                      uint64_t arg);

/* ---- chip-wide environment shared by the units ---- */

/* Counters every unit file may bump (registered by the chip, sim/chip.c). */
enum thr_counter {
	C_PKT_PRIMARY, /* + type: packets entering a thread, by packet type */
	C_RAYS_PRIMARY = C_PKT_PRIMARY + PKT_NTYPES,
	C_BOX_MISS_PACKETS = C_RAYS_PRIMARY + PKT_NTYPES,
	C_BOX_MISS_RAYS,
	C_NODE_STEPS,
	C_LEAF_VISITS,
	C_EMPTY_LEAVES,
	C_LIST_ENTRIES,
	C_TRI_TESTS,
	C_RAY_TRI_TESTS,
	C_STACK_OVERFLOWS,
	C_STACK_REFILLS,
	C_MAX_SP,
	C_SHADE_READS,
	C_SHADE_REQUESTS,
	C_SPAWNED,
	C_QUEUED,
	C_MAX_QUEUE,
	C_CONE_PACKETS,    /* cone culling (chip.cone_cull): cones built, */
	C_CONE_TESTS,      /* triangle-cone tests, */
	C_CONE_CULLED,     /* triangles culled for the whole packet, */
	C_CONE_SAVED,      /* and the ray-triangle tests they saved */
	C_TL_STEPS,        /* two-level scenes: top-level node steps, */
	C_TL_INST_TESTS,   /* instance box tests, */
	C_TL_INST_ENTERED, /* instances entered (transformation ops), */
	C_TL_MAP_READS,    /* hits named through the triangle map */
	C_NCOUNTERS
};
_Static_assert(C_NCOUNTERS <= 32, "packet records (pktrec.h) hold 32 counters");

/* Counters split by the type of the packet that made them (seed 000 §3
 * groups packets by ray type; issue 32): kd steps, leaves, list entries
 * and triangle tests, and each unit kind's issue cycles and op rays. They
 * are not thr_counters (a packet record holds 32 of those): the sinks
 * derive them where they count the totals, from the type of the thread's
 * packet (thr_ctx.ptype), so a replayed record splits them as the
 * recording run did. */
enum thr_type_counter {
	TC_NODE_STEPS,
	TC_LEAF_VISITS,
	TC_LIST_ENTRIES,
	TC_TRI_TESTS,
	TC_RAY_TRI_TESTS,
	TC_BUSY,                         /* + kind: issue cycles of the kind's ops */
	TC_RAYS = TC_BUSY + UNIT_NKINDS, /* + kind: active rays of the kind's ops */
	TC_NCOUNTERS = TC_RAYS + UNIT_NKINDS
};

struct thr_ctx;
struct thr_rtp;

/* A thread's walk of a two-level scene's top level (units/toplevel.c):
 * its stack of (node, rays), the leaf's instance records, the record and
 * node as read, the packet moved into the object's space and the world
 * packet it came from, the map entries its hits read. Allocated at the
 * thread's first two-level packet. */
#define THR_TL_STACK 64
typedef struct thr_tl {
	uint32_t node[THR_TL_STACK];
	uint64_t mask[THR_TL_STACK];
	int sp;
	uint32_t k, end;   /* the leaf's records [k, end) */
	uint64_t leaf, im; /* rays in the leaf; rays entering the instance */
	uint8_t rec[TLI_INST_BYTES];
	tli_node n;
	tli_inst in;
	packet q;
	packet *wp;
	uint32_t g[PKT_RAYS];
	uint64_t steps;
} thr_tl;

/* One distinct shading read of a packet: its address, size and place in
 * the thread's shading buffers. */
typedef struct thr_shread {
	uint64_t addr;
	uint32_t bytes, off;
} thr_shread;

/* A thread's shading (units/rgs.c): the reads a pass of the shader made,
 * the bytes it was given (peek: what memory held when it asked) and those
 * the reads returned (got), its outputs until they are made. Allocated at
 * the thread's first shading; the buffers grow to the largest packet. */
typedef struct thr_shade {
	uint8_t *peek, *got;
	uint32_t used, cap;
	thr_shread *rd;
	uint32_t n, capn;
	uint32_t issued;  /* reads [0, issued) are requested */
	uint32_t reads;   /* reads of the pass before coalescing */
	int delivered;    /* the pass reads the returned bytes */
	int round;        /* passes so far */
	shade_counts cnt; /* the pass's counts */
	shade_adds adds;  /* the pass's frame-buffer adds */
} thr_shade;

typedef struct thr_env {
	eng *e;
	eng_clock clk;
	memport *mem;
	const mimg *m; /* region bases and scene box; bytes NULL (the chip's) */
	shade_ctx sc;
	cam_frame cam;
	drt_shade drt; /* distribution effects (sc.drt points here when on) */
	int stack_depth, masked, nlights;
	int cone_cull; /* chip.cone_cull: packets cull leaf triangles outside their cone */
	/* a packet that takes more traversal steps than this has looped on
	 * damaged node data (a correct walk visits each node at most once):
	 * it is ended and the frame fails (damaged) */
	uint64_t max_steps;
	int damaged;
	/* where the units' operations go (units/sink.h): the mode's sink, set
	 * by the driver (sim/modes/); the units never ask which mode runs */
	thr_sink *sink;
	/* what the mode drivers and sinks keep per thread slot (sim/modes/
	 * slot.h), opaque to the units */
	void *modes;
	pkt_precision prec; /* datapath formats (chip.fp); full = the SIMD path */
	uint64_t spill_base;
	uint64_t next_age;
	uint64_t *c[C_NCOUNTERS];
	uint64_t *ct[PKT_NTYPES][TC_NCOUNTERS]; /* enum thr_type_counter, by packet type */
	shade_counts sh;
	/* the pipeline's order: where a unit hands a thread on (set by the
	 * chip's wiring, unit_table.h) */
	unit_route route;
	/* an observer of the threads' states (the timeline and heat maps,
	 * sim/observe.c): called at each change before it is made (t->state
	 * and t->since are the old state's); NULL: none */
	void (*on_state)(void *ctx, struct thr_ctx *t, int to);
	void *state_ctx;
	/* a thread became free: give it work (set by the chip) */
	void (*on_free)(struct thr_ctx *t);
	void *owner;
	/* packet pool: chunks, free list */
	packet **chunks;
	int nchunks;
	packet **freel;
	int nfree, capfree;
	/* shading scratch: the de-duplication table of one pass's reads
	 * (key, stamp, index of the read) */
	uint64_t *hkey;
	uint32_t *hgen, *hidx, gen;
	int oom; /* a thread's buffer found no memory: the frame fails */
	/* a two-level scene (kernel-ref/tlimage.h): its top level's nodes and
	 * instance records (the registers the host sets per frame); 0: none */
	int two_level;
	uint64_t tl_nodes, tl_insts;
	/* a uniform grid (chip.accel grid; kernel-ref/gridimage.h): its header
	 * (the registers: resolution, box, scale, margin, parameters; no
	 * arrays) and the bases of its cells' list offsets, cell lists and
	 * macrocell flags; grid NULL: the kd-tree */
	const struct grid *grid;
	uint64_t grid_cells, grid_refs, grid_macro;
	uint32_t grid_nrefs;
	/* test hooks: enum thr_mutant; shading decoded again from the
	 * delivered bytes even when they equal those it found (units/rgs.c) */
	int mutant, shade_redecode;
} thr_env;

int thr_env_init(thr_env *v);
void thr_env_free(thr_env *v);
packet *thr_pkt_alloc(thr_env *v); /* NULL when out of memory */
void thr_pkt_free(thr_env *v, packet *p);

/* ---- threads ---- */

typedef struct thr_ctx {
	trav_state ts;
	trav_result r;
	struct thr_rtp *rtp;
	thr_env *env;
	int id, gid; /* index in the RTP, and chip-wide */
	int state;
	uint64_t since; /* tick of the last state change */
	packet *p;
	int ptype;         /* the packet's type (enum pkt_type), set as it enters */
	uint64_t age;      /* packet sequence number: smaller = older */
	trav_entry *stack; /* functional stack (PKT_STACK_MAX entries) */
	int sp;            /* stack depth after the last step */
	uint64_t mask;     /* intersection: rays still testing this leaf */
	uint32_t k;        /* intersection: next leaf entry */
	int pending;       /* outstanding memory reads */
	void (*cont)(struct thr_ctx *t);
	/* what the reads returned: the node, the leaf's list entries, the
	 * triangle record, the spilled stack entries read back (packed,
	 * THR_STACK_ENTRY_BYTES each by stack index; allocated at the first
	 * refill), the shading records */
	kd_node node;
	mimg_tri tri;
	uint32_t *list, list_cap;
	uint8_t *spill_in;
	int backed, rlo,
	    rhi; /* stack entries [backed, sp) read back this step; [rlo, rhi) in flight */
	thr_shade *sh;
	packet *kids; /* shade_packet's output */
	int nkids, made;
	uint64_t steps; /* traversal steps of the current packet (thr_env.max_steps) */
	pkt_cone cone;  /* the packet's enclosing cone (chip.cone_cull) */
	/* the image traversal, list and intersection read: NULL the scene's
	 * (thr_env.m); inside an instance of a two-level scene its object's
	 * (units/toplevel.c) */
	const mimg *img;
	struct thr_tl *tl;     /* a two-level scene's walk (units/toplevel.c) */
	struct thr_grid *grid; /* a grid walk (units/gridtrav.c), allocated at the first */
} thr_ctx;

/* The image the thread's traversal reads now. */
static inline const mimg *thr_img(const thr_ctx *t)
{
	return t->img ? t->img : t->env->m;
}

/* A queued secondary packet: the packet, or (p NULL) a replayed stream. */
typedef struct thr_qitem {
	packet *p;
	int32_t rec;
} thr_qitem;

typedef struct thr_rtp {
	thr_env *env;
	int id;
	thr_unit u[UNIT_NKINDS];
	thr_ctx *t;
	int nt, nidle;
	/* secondary packets waiting for a thread slot (FIFO ring) */
	thr_qitem *q;
	int qhead, qn, qcap;
	uint64_t *occ[THR_NSTATES]; /* ticks spent in each state, summed over threads */
} thr_rtp;

/* Adds the time since the last change to the occupancy counters. */
static inline void thr_flush(thr_ctx *t)
{
	uint64_t now = eng_now(t->env->e);
	*t->rtp->occ[t->state] += now - t->since;
	t->since = now;
}
/* The thread's state becomes `state` (the observer told first, the time
 * in the old one counted). Inline: a timed op changes it three times. */
static inline void thr_set(thr_ctx *t, int state)
{
	if (state == t->state)
		return;
	if (t->env->on_state)
		t->env->on_state(t->env->state_ctx, t, state);
	thr_flush(t);
	if (t->state == THR_IDLE)
		t->rtp->nidle--;
	if (state == THR_IDLE)
		t->rtp->nidle++;
	t->state = state;
}
/* Frees the thread's data buffers (chip_destroy). */
void thr_free_buffers(thr_ctx *t);
/* The valid rays of a packet. */
uint64_t thr_rays(const packet *p);
/* thr_unit.on_start for units used by threads: the thread runs. */
void thr_on_start(void *ctx, uint64_t arg);

static inline int thr_pop(uint64_t m)
{
	return __builtin_popcountll(m);
}

/* Where traversal stack entry `index` of thread t spills: every thread slot
 * has its own area after the memory image (chip.c). */
static inline uint64_t thr_spill_addr(const thr_ctx *t, uint64_t index)
{
	return t->env->spill_base + ((uint64_t)t->gid * PKT_STACK_MAX + index) * THR_SPILL_STRIDE;
}

/* ---- the units' operations, into the environment's sink (units/sink.h) ---- */

/* Issues a read for the thread; thr_wait_mem continues when all are in,
 * the bytes in dst (NULL: none wanted, a replayed read). */
static inline void thr_read(thr_ctx *t, int type, uint64_t addr, uint32_t bytes, void *dst)
{
	thr_sink *s = t->env->sink;
	s->op->read(s, t, type, addr, bytes, dst);
}

/* A posted write (stack spill) of src (NULL: no data, a replayed write). */
static inline void thr_write(thr_ctx *t, int type, uint64_t addr, uint32_t bytes, const void *src)
{
	thr_sink *s = t->env->sink;
	s->op->write(s, t, type, addr, bytes, src);
}

/* As thr_wait_mem, but with no read outstanding it returns 0 instead of
 * calling cont (the caller goes on itself); 1: cont runs when they are in. */
static inline int thr_park_mem(thr_ctx *t, void (*cont)(thr_ctx *t))
{
	thr_sink *s = t->env->sink;
	return s->op->wait(s, t, cont);
}

/* Calls cont(t) once every read issued so far has arrived (at once if none). */
static inline void thr_wait_mem(thr_ctx *t, void (*cont)(thr_ctx *t))
{
	if (!thr_park_mem(t, cont))
		cont(t);
}

/* Queues an op of the thread's `rays` rays at unit kind `kind`. */
static inline void thr_use(thr_ctx *t, int kind, int rays, eng_handler done)
{
	thr_sink *s = t->env->sink;
	s->op->use(s, t, kind, rays, done);
}

/* Adds n to counter id (enum thr_counter) for the thread's packet. */
static inline void thr_count(thr_ctx *t, int id, uint64_t n)
{
	thr_sink *s = t->env->sink;
	s->op->count(s, t, id, n);
}

/* Raises counter id (a maximum: trav.max_stack_depth) to v. */
static inline void thr_count_max(thr_ctx *t, int id, uint64_t v)
{
	thr_sink *s = t->env->sink;
	s->op->count_max(s, t, id, v);
}

/* Adds what shading counted (kernel-ref shade_counts). */
static inline void thr_shade_count(thr_ctx *t, const shade_counts *add)
{
	thr_sink *s = t->env->sink;
	s->op->shade(s, t, add);
}

/* A packet of `type` with `rays` valid rays enters thread t. */
static inline void thr_enter(thr_ctx *t, int type, uint64_t rays)
{
	thr_sink *s = t->env->sink;
	s->op->enter(s, t, type, rays);
}

/* Queues n children at the thread's RTP (units/sink.h spawn). */
static inline int thr_spawn(thr_ctx *t, int n, const packet *kids, const int32_t *ids)
{
	thr_sink *s = t->env->sink;
	return s->op->spawn(s, t, n, kids, ids);
}

/* The packet is done (a replayed one: its stream): back to the pool; the
 * thread is free for new work. */
static inline void thr_release(thr_ctx *t)
{
	thr_sink *s = t->env->sink;
	s->op->release(s, t, 0);
}

/* As thr_release after a shading op whose children thr_spawn queued. */
static inline void thr_release_shaded(thr_ctx *t)
{
	thr_sink *s = t->env->sink;
	s->op->release(s, t, 1);
}

#endif
