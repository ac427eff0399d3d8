/*
 * timed.h: the timed sink (units/sink.h): reads and writes go through the
 * memory port's timed path (mem_access: caches, MSHRs, SDRAM, VMA as
 * events), a unit op waits for its unit and takes its issue cycles and
 * latency (thr_unit_request), and a freed thread asks the chip for work
 * (thr_env.on_free). Cycle-level simulation and a sampled frame's
 * detailed regions run on it.
 */
#ifndef SAAR_SIM_MODES_TIMED_H
#define SAAR_SIM_MODES_TIMED_H

#include "units/thread.h"

extern const thr_sink_ops mode_timed_ops;

#endif
