/*
 * sink.h: where the units' operations go (docs/design-modes.md).
 *
 * A unit (traversal, list, intersection, RGS) does its math on the bytes
 * its reads returned, and everything it does to the rest of the chip is
 * one of the operations below, emitted into the environment's sink
 * (thr_env.sink): memory reads and writes, a wait for the reads so far, an
 * operation at a pipelined unit, counter updates, the packet entering a
 * thread, children spawned, and the end of the packet. What an operation
 * costs is the sink's business, not the unit's: the timed sink (sim/modes/
 * timed.c) sends reads through the timed memory path and queues unit ops
 * for their issue cycles; the functional sink (sim/modes/functional.c)
 * makes the data there at once and counts an op without its time; the
 * recording sink (sim/modes/record.c) writes each operation into the
 * packet record (traces/pktrec.h) and passes it on to the sink it wraps.
 * Replay (sim/modes/replay.c) decodes a stored packet stream into the same
 * operations. So no unit file asks which mode runs.
 *
 * A sink is a table of operations (thr_sink_ops) and, for a sink that
 * wraps another (recording, an observer), the one it passes them to
 * (inner). The unit-facing calls (thr_read, thr_use, thr_count, ... in
 * units/thread.h) are one indirect call each.
 */
#ifndef SAAR_UNITS_SINK_H
#define SAAR_UNITS_SINK_H

#include <stdint.h>

#include "kernel-ref/packet.h"
#include "kernel-ref/shade.h"
#include "sim/core/engine.h"

struct thr_ctx;
struct thr_sink;

typedef struct thr_sink_ops {
	/* A read of `bytes` at addr of memory type `type` into dst (NULL: no
	 * data wanted, a replayed read); a posted write from src (NULL: no
	 * data). */
	void (*read)(struct thr_sink *s, struct thr_ctx *t, int type, uint64_t addr, uint32_t bytes,
	             void *dst);
	void (*write)(struct thr_sink *s, struct thr_ctx *t, int type, uint64_t addr,
	              uint32_t bytes, const void *src);
	/* Wait for the reads so far: 0 when none is outstanding (the caller
	 * goes on itself), 1 when cont(t) runs once they are in. */
	int (*wait)(struct thr_sink *s, struct thr_ctx *t, void (*cont)(struct thr_ctx *t));
	/* An op of `rays` rays at the thread's unit of kind `kind`; done runs
	 * when it completes (timed) or as the thread's next step
	 * (functional). */
	void (*use)(struct thr_sink *s, struct thr_ctx *t, int kind, int rays, eng_handler done);
	/* counter id (enum thr_counter) += n; raised to at least v (a
	 * maximum) */
	void (*count)(struct thr_sink *s, struct thr_ctx *t, int id, uint64_t n);
	void (*count_max)(struct thr_sink *s, struct thr_ctx *t, int id, uint64_t v);
	/* shading's counts (kernel-ref shade_counts) += add */
	void (*shade)(struct thr_sink *s, struct thr_ctx *t, const shade_counts *add);
	/* a packet of `type` with `rays` valid rays enters the thread */
	void (*enter)(struct thr_sink *s, struct thr_ctx *t, int type, uint64_t rays);
	/* n children join the thread's RTP queue: the packets kids[0..n)
	 * (copied), or (kids NULL) replayed streams ids[0..n); ids NULL: not
	 * recorded. -1 when one was lost (out of memory). */
	int (*spawn)(struct thr_sink *s, struct thr_ctx *t, int n, const packet *kids,
	             const int32_t *ids);
	/* The packet is done and the thread free; shaded: it was a shading
	 * op, whose children are queued (the queue is sampled, and idle
	 * threads may take them). */
	void (*release)(struct thr_sink *s, struct thr_ctx *t, int shaded);
} thr_sink_ops;

typedef struct thr_sink {
	const thr_sink_ops *op;
	struct thr_sink *inner; /* a wrapping sink passes its operations on to it */
} thr_sink;

#endif
