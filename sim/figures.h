/*
 * figures.h: the figures derived from a run's counters that both the
 * report (sim/report.c) and its invariants (sim/reportcheck.c) read:
 * memory figures over a span of frames, fps, unit utilisation and the
 * threads' state shares. One place computes them, so what is checked is
 * what is printed (docs/report.md).
 */
#ifndef SAAR_SIM_FIGURES_H
#define SAAR_SIM_FIGURES_H

#include "sim/chip.h"

/* Memory figures over a span of frames (the report's steady_state and
 * per_frame fields; docs/report.md). In a sampled frame the hit rates
 * and SDRAM MB are estimates (docs/fidelity.md "Sampled"). */
enum { HR_TAG = MEM_NTYPES, HR_L2, HR_N }; /* hit-rate slots: the four L1s, tag cache, L2 */

typedef struct memfig {
	int first, last;     /* frames first..last (1-based, inclusive) */
	double cycles, fps;  /* mean core cycles per frame, fps at the clock */
	double sdram_mb;     /* per frame; fixed model: bytes through the memory port */
	double pci_mb;       /* per frame; 0 without VMA */
	double hit[HR_N];    /* hits / accesses over the span; -1: no such cache or no access */
	double meta_share;   /* meta-data share of SDRAM accesses */
	double row_hit_rate; /* SDRAM row hits / (hits + empty + conflicts) */
	double sdram_util;   /* SDRAM data bus busy / elapsed time */
	double pci_util;     /* host bus busy / elapsed time */
} memfig;

/* The steady state: the mean of frames 2..N when there are several (the
 * first frame warms the caches and the VMA), else frame 1. */
void fig_steady_state(const chip *c, memfig *m);
/* The figures of frames f0..f1-1 (0-based; per_frame is f, f + 1). */
void fig_span(const chip *c, int f0, int f1, memfig *m);
/* The report's fps: clock / mean cycles per frame. */
double fig_fps(const chip *c);
/* Utilisation of unit kind k (UNIT_*): issue cycles / (cycles x units of
 * the kind), over the chip (rtp < 0) or one RTP. */
double fig_util(const chip *c, int kind, int rtp);
/* The thread contexts' time in each state (threads.<state>_ps over the
 * RTPs) into ps; returns their sum. */
uint64_t fig_thread_ps(const chip *c, uint64_t ps[THR_NSTATES]);
/* The thread states' shares of threads x time (THR_NSTATES of them);
 * returns 0 (shares all 0) when no thread time was timed (functional). */
int fig_thread_shares(const chip *c, double share[THR_NSTATES]);
/* The report's name of hit-rate slot i (HR_*): "shade" ... "tag_cache", "l2". */
const char *fig_hit_name(int slot);

#endif
