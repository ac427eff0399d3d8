/*
 * replay.h: threads replaying packets from a packet record
 * (traces/pktrec.h) instead of running their math: the same memory
 * requests, the same unit ops, the same counters, the same children
 * queued, in the same order; the chip gives replayed tiles the record's
 * pixels. Functional and timed alike (thr_env.func): a stream's unit op
 * goes through thr_use, its reads through thr_read, and where the unit
 * code waited for reads (thr_wait_mem) the stream waits too (PR_WAIT, and
 * before every op), so a detailed region replaying a packet makes the
 * same events at the same ticks as one running its math, and takes over
 * a packet a functional stretch left in flight as it is.
 */
#ifndef SAAR_UNITS_REPLAY_H
#define SAAR_UNITS_REPLAY_H

#include "thread.h"

/* Thread t (free) takes packet id of env.rec_in and runs its stream up to
 * its first unit op, as rgs_primary / rgs_secondary do. Its later steps
 * are the ops' completions (timed) or thr_step_func (functional). */
void thr_replay_begin(thr_ctx *t, int32_t id);
/* Functional: thread t takes over packet id stopped `off` bytes into its
 * stream before the next unit op of kind `kind` with `rays` rays, already
 * counted (as thr_use left it): where stored warming's checkpoint had it
 * (sim/warming.h). The caller sets its read history (raddr, rbytes), age
 * and state. */
void thr_replay_resume(thr_ctx *t, int32_t id, uint64_t off, int kind, int rays);

#endif
