/*
 * replay.h: threads replaying packets from a packet record
 * (traces/pktrec.h) instead of running their math: a stream is decoded
 * into the very operations the units emitted when it was recorded
 * (units/sink.h), into whatever sink runs (timed or functional): the same
 * memory requests, unit ops, counters and children queued, in the same
 * order; the chip gives replayed tiles the record's pixels. Where the unit
 * code waited for reads (thr_wait_mem) the stream waits too (PR_WAIT, and
 * before every op), so a detailed region replaying a packet makes the
 * same events at the same ticks as one running its math, and takes over
 * a packet a functional stretch left in flight as it is.
 *
 * A replayed read carries its bytes (into the slot's buffer): once they
 * are in, their checksum is compared with the record's (pr_sum). A read
 * that returned other bytes than the recorded one (damaged board memory,
 * a wrong address, a fault on the data's way) is counted in the chip's
 * mode_rbad, the first one described, and its tile takes no pixels from
 * the record: the frame's check says DIFFERENT (docs/fidelity.md, "What
 * replay checks"). Spilled stack entries are not checked: replayed spills
 * write no bytes.
 */
#ifndef SAAR_SIM_MODES_REPLAY_H
#define SAAR_SIM_MODES_REPLAY_H

#include "sim/modes/slot.h"
#include "traces/pktrec.h"
#include "units/rgs.h"
#include "units/thread.h"

/* Thread t (free) takes packet id of record r and runs its stream up to
 * its first unit op, as rgs_primary / rgs_secondary do. Its later steps
 * are the ops' completions (timed) or mode_func_step (functional). */
void mode_replay_begin(const pktrec *r, thr_ctx *t, int32_t id);

/* Frees slot m's replay buffers (mode_sinks_free). */
void mode_replay_free(mode_slot_state *m);

/* Where a functional thread slot is between two steps, as stored
 * warming's checkpoints keep it (sim/warming.h): idle (rec -1), or
 * replaying packet rec stopped `off` bytes into its stream before its
 * next unit op (of `kind`, `rays` rays, already counted, as thr_use left
 * it), with the packet's read history and age. A fixed layout: it is
 * stored as it is. */
typedef struct mode_replay_state {
	int32_t rec;
	int16_t kind, rays;
	uint64_t off, age;
	uint64_t raddr[MEM_NTYPES];
	uint32_t rbytes[MEM_NTYPES];
	/* the packet's type (thr_ctx.ptype): what its later work counts
	 * under by ray type (a restored slot kept the type of the packet it
	 * ran before) */
	int32_t ptype;
} mode_replay_state;

/* Thread t's state (functional, between steps); -1 when it cannot be
 * kept: it runs a packet's math, or it is in the middle of a step. */
int mode_replay_save(const thr_ctx *t, mode_replay_state *s);
/* Thread t (no read outstanding, no event pending) takes state s of
 * record r; -1 when s does not fit r (t is then left idle). */
int mode_replay_restore(const pktrec *r, thr_ctx *t, const mode_replay_state *s);

/* RTP r's queue of secondary packets as checkpoints keep it: the streams'
 * ids, oldest first, 4 bytes each into out (room for rgs_queue_len); -1
 * when an item is a packet running its math, not a stream. */
int mode_queue_save(const thr_rtp *r, void *out);
/* RTP r's queue becomes the n streams ids (4 bytes each) of record rec,
 * counting nothing; -1 when one is not in rec (the queue is left as it
 * was) or out of memory. */
int mode_queue_restore(const pktrec *rec, thr_rtp *r, const void *ids, int n);

#endif
