/*
 * unit_table.h: the unit kinds of one RTP, described once.
 *
 * An RTP (SaarCOR seed 002 §4.1) has one group of pipelined units per
 * kind: ray generation and shading, traversal, list, intersection. Every
 * list the simulator keeps per kind is derived from unit_table[]: the
 * config keys chip.<name>.count/width/latency with their defaults, ranges
 * and provenance (sim/config.c), the chip's counters rtp<i>.<name>.* and
 * the report's units.<name> (sim/chip.c, sim/report.c), the resources of
 * the busiest-resource bound and the sampled estimator's linear model
 * (sim/chip.h enum chip_res, sim/sampling.h SMP_LIN), the unit-op codes of
 * packet records (traces/pktrec.h PR_USE + kind). docs/extending.md
 * walks through adding a kind.
 *
 * This header includes nothing but the C library: every layer may take it
 * (units/ itself, traces/, sim/), and no include circle can pass through
 * it.
 */
#ifndef SAAR_UNITS_UNIT_TABLE_H
#define SAAR_UNITS_UNIT_TABLE_H

#include <stdint.h>

/* The unit kinds, in table order (the order of every derived list, the
 * report's included). */
enum unit_kind { UNIT_RGS, UNIT_TRAV, UNIT_LIST, UNIT_ISECT, UNIT_XFORM, UNIT_NKINDS };

/* Which waiting thread a free unit serves next (chip.thread_sched). */
enum unit_sched { UNIT_SCHED_ROUND_ROBIN, UNIT_SCHED_OLDEST_FIRST };

/* The parameters of one unit kind's instances in an RTP (units/thread.h
 * thr_unit): `count` identical pipelined units of issue width `width`
 * rays/cycle and `latency` cycles; masked: an op costs all 64 rays of the
 * packet; sched: enum unit_sched. Filled by the chip's builder from the
 * config (sim/chip.c): units/ reads no config schema. */
typedef struct unit_params {
	int count, width, latency;
	int masked, sched;
} unit_params;

/* One parameter of a kind as the config offers it: default, inclusive
 * range, whether the value is published (seed 002) and where it comes
 * from or why it is assumed; timing: only timing reads it (functional
 * processing does the same with any value). */
typedef struct unit_param_desc {
	int def, min, max;
	int published, timing;
	const char *source;
	int calibrated; /* fitted by scripts/calibrate.sh (docs/CALIBRATION.md) */
} unit_param_desc;

typedef struct unit_desc {
	/* "trav": config section chip.<name>, counters rtp<i>.<name>.*,
	 * report units.<name>, the bound's resource <name> */
	const char *name;
	/* "traversal": the config keys' descriptions ("number of traversal
	 * units per RTP") */
	const char *what;
	unit_param_desc count, width, latency;
	/* the memory requester type (mem/memport.h enum mem_req_type) whose
	 * reads this unit's stage waits for: the report's stall cycles of the
	 * unit are that type's; -1: it reads nothing of its own */
	int mem;
} unit_desc;

extern const unit_desc unit_table[UNIT_NKINDS];

/* The kind's name ("trav"), "?" out of range; the kind named `name`, -1. */
const char *unit_name(int kind);
int unit_find(const char *name);

/* ---- routing (set when the chip is wired) ----
 *
 * The pipeline's order is not written as calls between unit files: a unit
 * hands a thread on through its environment's route (thr_env.route,
 * units/thread.h), which the chip's wiring fills (sim/chip.c). So no unit
 * file includes another's header, and a new unit is placed in the
 * pipeline by changing a line of the wiring. */
struct thr_ctx;
typedef void (*unit_step)(struct thr_ctx *t);
typedef struct unit_route {
	unit_step enter;     /* a packet enters the ray-tracing core (traversal) */
	unit_step leaf;      /* traversal reached a leaf (list unit) */
	unit_step triangles; /* the leaf's entries are in (intersection) */
	unit_step traverse;  /* the next traversal step (after a leaf's triangles) */
	unit_step finish;    /* traversal is over (shading, in the RGS) */
	/* two-level scenes (units/toplevel.c, which takes enter and finish):
	 * the packet moved into an instance's object space enters its tree
	 * (traversal), and the top level's walk is over (shading) */
	unit_step object;
	unit_step shade;
} unit_route;

#endif
