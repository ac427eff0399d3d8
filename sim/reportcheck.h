/*
 * reportcheck.h: the invariants a run's report must satisfy, checked on
 * every run (docs/report.md "Invariants").
 *
 * A report is a pile of derived figures; a counter that stops counting
 * (the audit of issue 29 found "PCI 0.00 MB/frame" beside "PCI busy
 * 99.7%") leaves it plausible at a glance. rc_check holds the figures
 * against identities that follow from how the memory system moves bytes
 * (mem/hier.c, mem/vma.c): every cache's hits + misses = accesses, its
 * fills = the misses not merged, the bytes each level asks for = the bytes
 * the level below delivers, SDRAM bytes = the memory interface's, host-bus
 * bytes = the VMA's fetches and write-arounds; a bus that was busy moved
 * bytes; rates and shares lie in [0, 1]; fps = clock / cycles per frame;
 * per-frame figures add up to the totals; the figures split by ray type
 * (ray_types) add up to the totals they split. saarsim prints one
 * "warning: report invariant failed: ..." line per violation and lists
 * them in the JSON report (invariants_failed); every test that runs the
 * chip asserts there are none.
 *
 * The figures are first copied into an rc_figs by the functions that write
 * the report (fig_span, fig_util, ...), so what is checked is what
 * is reported, and a test can spoil one figure and see its invariant fail.
 */
#ifndef SAAR_SIM_REPORTCHECK_H
#define SAAR_SIM_REPORTCHECK_H

#include "sim/chip.h"
#include "sim/figures.h"

#define RC_MAX 64 /* violations kept (rc_list.n counts all of them) */

typedef struct rc_list {
	int n;                 /* violations found */
	char msg[RC_MAX][256]; /* the first RC_MAX: "what: rule (the numbers)" */
} rc_list;

/* The report's figures the invariants look at. */
typedef struct rc_figs {
	int frames, nrtp;
	int hierarchy, vma;       /* memory.model hierarchy; its VMA on */
	int estimated;            /* sampled and estimated: per-frame SDRAM MB is an estimate */
	int exact_fills;          /* no stored warming: every new miss fills exactly once */
	double clock_mhz, fps;    /* chip.clock_mhz, the report's fps */
	uint64_t cycles;          /* cycles (sum of cycles_per_frame) */
	uint64_t *frame_cycles;   /* cycles_per_frame */
	memfig *per_frame;        /* per_frame */
	memfig steady;            /* steady_state */
	mem_counts port;          /* the memory port's counts (memory.shade ... tri) */
	hier_stats h;             /* memory.hierarchy (hierarchy only) */
	uint32_t line[HR_N];      /* line bytes: the L1s, tag cache, L2 */
	double util[UNIT_NKINDS]; /* units.*.utilisation */
	double *rtp_util;         /* units.*.per_rtp_utilisation: [kind * nrtp + rtp] */
	int threads_timed;
	double share[THR_NSTATES]; /* threads.* */
	/* the states' times summed (threads.*_ps over the RTPs) and, where
	 * every cycle was simulated (cycle; sampled with every tile
	 * detailed), what they must add up to: contexts x the frames' time
	 * (0: not checked) */
	uint64_t thread_ps, thread_ps_want;
	/* ray_types (issue 32): the per-type counters summed over the types,
	 * and the totals they split (traversal.*, the units' busy cycles and
	 * rays summed over the RTPs) */
	uint64_t by_type[TC_NCOUNTERS], total[TC_NCOUNTERS];
} rc_figs;

/* Copies c's report figures into f (rc_figs_free releases it); -1 when out
 * of memory. */
int rc_figs_get(const chip *c, rc_figs *f);
void rc_figs_free(rc_figs *f);
/* Lists the invariants f violates into out; returns how many. */
int rc_check(const rc_figs *f, rc_list *out);
/* Both: c's report against every invariant (out of memory counts as a
 * violation). */
int report_check(const chip *c, rc_list *out);

#endif
