/*
 * base.h: what the timed and the functional sink do alike (units/sink.h):
 * counters, shading's counts, a packet entering a thread, children joining
 * the RTP queue, the wait for reads, and the packet's end. The two differ
 * only in the time things take (timed.c, functional.c).
 */
#ifndef SAAR_SIM_MODES_BASE_H
#define SAAR_SIM_MODES_BASE_H

#include "units/thread.h"

/* Counts into thr_env.c and, for the counters split by packet type, into
 * thr_env.ct of the thread's packet type. */
void mode_base_count(thr_sink *s, thr_ctx *t, int id, uint64_t n);
/* The per-type issue cycles and op rays of an op of `rays` rays at the
 * thread's unit of kind `kind` (the timed and functional sinks' use; the
 * totals are the unit's own, thr_unit_count). */
void mode_base_use(thr_ctx *t, int kind, int rays);
/* As mode_base_use, with the op's issue cycles (thr_unit_issue) known. */
static inline void mode_base_use_issue(thr_ctx *t, int kind, int rays, uint64_t issue)
{
	uint64_t *const *ct = t->env->ct[t->ptype];
	*ct[TC_BUSY + kind] += issue;
	*ct[TC_RAYS + kind] += (uint64_t)thr_op_rays(rays);
}
void mode_base_count_max(thr_sink *s, thr_ctx *t, int id, uint64_t v);
void mode_base_shade(thr_sink *s, thr_ctx *t, const shade_counts *add);
void mode_base_enter(thr_sink *s, thr_ctx *t, int type, uint64_t rays);
int mode_base_spawn(thr_sink *s, thr_ctx *t, int n, const packet *kids, const int32_t *ids);
int mode_base_wait(thr_sink *s, thr_ctx *t, void (*cont)(thr_ctx *t));
/* The packet's end without handing out new work: after a shading op the
 * RTP queue is sampled (C_QUEUED); the packet goes back to the pool and
 * the thread is idle. */
void mode_base_end(thr_ctx *t, int shaded);

/* Thread t's request to memory type `type` (mem/memport.h): its RTP is
 * the port, its packet type (+1) the ray type, data the bytes' source or
 * destination. */
static inline mem_req mode_base_req(const thr_ctx *t, int type, uint64_t addr, uint32_t bytes,
                                    int write, void *data)
{
	return (mem_req){.addr = addr,
	                 .bytes = bytes,
	                 .type = (uint8_t)type,
	                 .write = (uint8_t)write,
	                 .rtp = (uint16_t)t->rtp->id,
	                 .data = data,
	                 .ray = (uint8_t)(t->ptype + 1)};
}

#endif
