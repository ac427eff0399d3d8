/*
 * functional.h: the functional sink (units/sink.h; docs/fidelity.md):
 * memory goes through mem_access_func (the data is there at once, nothing
 * to wait for), a unit op is counted as its issue would count it but
 * takes no time, and its done handler becomes the thread's next step
 * (sim/modes/slot.h fnext), which mode_func_step runs. A freed thread waits for
 * the driver (sim/modes/sampled.c mode_func_range) to give it work.
 */
#ifndef SAAR_SIM_MODES_FUNCTIONAL_H
#define SAAR_SIM_MODES_FUNCTIONAL_H

#include "units/thread.h"

extern const thr_sink_ops mode_func_ops;

/* Runs the thread's next step (up to its next unit op); 0 if it has none
 * (its packet is done). The driver interleaves threads' steps, so a
 * packet's thousands of steps never nest on the C stack. */
int mode_func_step(thr_ctx *t);
/* A thread stopped before its next unit op (slot.h fnext set) requests that op
 * from its unit for real: the op's functional counts are taken back and
 * the unit will count it when it issues. How a sampled region takes over
 * packets in flight without a cold start. */
void mode_func_to_timed(thr_ctx *t);

#endif
