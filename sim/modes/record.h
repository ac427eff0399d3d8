/*
 * record.h: the recording sink (units/sink.h; traces/pktrec.h): every
 * operation a packet emits goes into its stream in the packet record, and
 * on to the sink it wraps (timed or functional, whichever runs), so a
 * frame is recorded in whatever mode draws it. Reads are stored as
 * address differences per memory type, stack spills by entry index, a
 * wait for reads only where one falls between requests (a unit op waits
 * anyway: PR_WAIT), a maximum only when it rises, and every read with
 * the checksum of its bytes (pr_sum). Replay (replay.c) turns
 * a stream back into the same operations.
 */
#ifndef SAAR_SIM_MODES_RECORD_H
#define SAAR_SIM_MODES_RECORD_H

#include "traces/pktrec.h"
#include "units/thread.h"

typedef struct mode_rec {
	thr_sink s;  /* s.inner: the sink it passes everything on to */
	pktrec *out; /* the record being made */
	/* the bytes of the read being recorded, for its checksum */
	uint8_t *buf;
	uint32_t cap;
} mode_rec;

extern const thr_sink_ops mode_rec_ops;

/* Thread t begins the primary packet of tile: its stream (-1 when the
 * record is out of memory; recording then stops). */
void mode_rec_tile(mode_rec *m, thr_ctx *t, int tile);

#endif
