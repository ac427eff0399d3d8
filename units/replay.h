/*
 * replay.h: threads replaying packets from a packet record
 * (traces/pktrec.h) instead of running their math: the same memory
 * requests through the functional path, the same unit ops counted, the
 * same counters, the same children queued; the chip gives replayed
 * tiles the record's pixels. Functional processing only (thr_env.func).
 * A detailed region needs real packets: thr_replay_rebuild turns a
 * replayed packet in flight back into one, its rays and traversal state
 * rebuilt by running its math silently (no requests, counts or ages)
 * through the steps already replayed, so the region takes over the
 * same packets as without a record.
 */
#ifndef SAAR_UNITS_REPLAY_H
#define SAAR_UNITS_REPLAY_H

#include "thread.h"

/* Thread t (free) takes packet id of env.rec_in and runs its stream up to
 * its first unit op, as rgs_primary / rgs_secondary do. */
void thr_replay_begin(thr_ctx *t, int32_t id);
/* Runs the replayed packet's next step (up to its next unit op, or its
 * end); 0 if the thread replays nothing. */
int thr_replay_step(thr_ctx *t);
/* Thread t replaying a packet gets the real packet at the same step, its
 * next unit op pending (fnext), as functional processing leaves it;
 * queued replayed packets of RTP r become real ones. s: a scratch thread
 * (its own stack and children) for rebuilding parents. -1 when out of
 * memory. */
int thr_replay_rebuild(thr_ctx *t, thr_ctx *s);
int thr_replay_rebuild_queue(thr_rtp *r, thr_ctx *s);

#endif
