/*
 * modes.h: the chip's sinks and which of them the units emit into
 * (units/sink.h; docs/design-modes.md). The base sink is the timed one
 * (cycle-level simulation, a sampled frame's detailed regions) or the
 * functional one (fidelity functional, the stretches between regions,
 * stored warming's relax); while a packet record is made, the recording
 * sink wraps the base and thr_env.sink points at it. Replay needs no sink
 * of its own: it feeds the record's streams into the one that runs
 * (replay.h). An observer sink, when set, wraps whatever runs: units ->
 * observer -> recording -> base.
 */
#ifndef SAAR_SIM_MODES_MODES_H
#define SAAR_SIM_MODES_MODES_H

#include "sim/modes/record.h"
#include "sim/modes/slot.h"
#include "traces/pktrec.h"
#include "units/thread.h"

typedef struct mode_sinks {
	thr_env *env;
	mode_slot_state *slot; /* per thread slot (thr_env.modes) */
	thr_sink timed, func;  /* the base sinks */
	mode_rec rec;          /* wraps the base while rec.out is set */
	thr_sink *obs;         /* an observer outside them all, NULL */
	const pktrec *in;      /* the record whose streams replay, NULL */
	int func_on;           /* the base sink is the functional one */
	int nslots;
	mode_rbad bad; /* what replay found (slot.h) */
} mode_sinks;

/* Sinks for env v and its nslots thread slots; the timed one runs,
 * nothing is recorded; replay's findings mark tiles[] (ntiles, the
 * chip's). -1 when out of memory. */
int mode_sinks_init(mode_sinks *m, thr_env *v, int nslots, uint8_t *tiles);
void mode_sinks_free(mode_sinks *m);
/* The base sink becomes the functional (on) or the timed one; a record
 * being made goes on through the new base. */
void mode_set_func(mode_sinks *m, int on);
/* Records into out from now on (out NULL: stops recording). */
void mode_record(mode_sinks *m, pktrec *out);
/* Puts obs (a wrapping sink: it passes every operation on to obs->inner,
 * which this sets) outside the others from now on; NULL removes it. For
 * tracing, checks and tests (docs/extending.md). */
void mode_observe(mode_sinks *m, thr_sink *obs);

#endif
