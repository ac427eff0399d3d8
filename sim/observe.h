/*
 * observe.h: seeing inside a cycle-level run (docs/observe.md).
 *
 * The timeline (--timeline FILE.json): a Chrome trace-event file (it
 * opens in the Perfetto UI and chrome://tracing) of a window of cycles:
 * per RTP one track per unit instance (each operation with its thread,
 * rays and kind), one per thread (its state spans), and a memory process
 * with the L1 misses (request to fill, one track per MSHR), the SDRAM
 * data bus and the host bus. It is made by observers only: an observer
 * sink outside the mode's sinks (sim/modes/modes.h mode_observe) that
 * notes each unit operation's kind and rays, the units' on_start (the
 * issue), the threads' state hook (thr_env.on_state) and the memory
 * system's timing observer (mem/memport.h mem_observe). The units and the
 * memory do not know it is there; with it off they pay a NULL check.
 */
#ifndef SAAR_SIM_OBSERVE_H
#define SAAR_SIM_OBSERVE_H

#include <stdint.h>
#include <stdio.h>

#include "kernel-ref/diag.h"
#include "sim/chip.h"

/* The cap on a timeline's events unless the caller gives another: about
 * 125 MB of JSON. */
#define OBS_TL_MAX_EVENTS 1000000ull

/* What to observe: the timeline (tl: the open file to write it to, NULL:
 * none; events starting in cycles [c0, c1), at most max of them) and the
 * heat maps. */
typedef struct obs_opts {
	FILE *tl;
	uint64_t c0, c1, max;
	int heat;
} obs_opts;

typedef struct obs obs;

/* Parses a cycle window "C0:C1" (either side may be empty: from the start,
 * to the end; C0 < C1) into *c0, *c1 (C1 UINT64_MAX: open). -1 with d
 * naming flag. */
int obs_parse_window(const char *flag, const char *s, uint64_t *c0, uint64_t *c1, diag *d);

/* Starts observing c's run (cycle fidelity only: -1 with d naming flag
 * otherwise). Call before chip_run, obs_finish after it. NULL with d set
 * when out of memory. */
obs *obs_start(chip *c, const obs_opts *p, const char *flag, diag *d);
/* After the run: the spans still open, the timeline's end written (the
 * caller closes its file); the observers removed from the chip. *written
 * and *dropped (may be NULL): timeline events written, and left out for
 * the cap. -1 on a write error of the timeline (errno set). */
int obs_finish(obs *o, uint64_t *written, uint64_t *dropped);

/* The heat maps' files in dir (obs_heat_names), for reserving them. */
extern const char *const obs_heat_files[];
/* Writes the heat maps into dir (every file committed into g; NULL:
 * renamed at once). -1 with d set. */
int obs_heat_write(const obs *o, const char *dir, af_group *g, diag *d);
void obs_free(obs *o);

#endif
