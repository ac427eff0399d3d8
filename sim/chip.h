/*
 * chip.h: the SaarCOR chip model: RTPs, units, threads, memory port and the
 * event engine wired together; runs frames and owns the frame buffer.
 *
 * Build: chip_create (allocates everything: thread contexts, stacks, unit
 * queues, the memory model of memory.model; registers the stats),
 * optionally chip_trace_mem, then chip_run (frame.frames frames of the same
 * view; the memory model is never reset between frames, so caches, tag
 * cache and VMA stay warm and a snapshot of the memory counters is taken
 * after every frame for per-frame figures), then
 * read the results (cycles per frame, the stats registry, the frame buffer)
 * and optionally chip_check (kernel-ref renders the same frame; the 8-bit
 * images are compared). The hot path never allocates except to grow the
 * packet pool and the per-RTP queues of secondary packets (amortised, only
 * while they reach their high-water mark).
 */
#ifndef SAAR_SIM_CHIP_H
#define SAAR_SIM_CHIP_H

#include <stdint.h>

#include "config.h"
#include "engine.h"
#include "framebuf.h"
#include "hier.h"
#include "memport.h"
#include "memtrace.h"
#include "render.h"
#include "rgc.h"
#include "stats.h"
#include "thread.h"
#include "world.h"

typedef struct chip_check {
	int done;
	img_cmp cmp;
	render_stats ref; /* kernel-ref's counts for the same frame */
	double ref_ms;    /* host time of the reference render */
} chip_check;

typedef struct chip {
	saar_config cfg;
	const world *w;
	eng *e;
	eng_clock clk;
	memport mem;
	stats st;
	thr_env env;
	thr_rtp *rtp;
	int nrtp, tpr;
	rgc g;
	framebuf fb;
	uint64_t *frame_cycles; /* per frame */
	uint64_t spill_base;    /* stack spills live at and above it (after the image) */
	/* cumulative counters at the end of each frame: frame f's own figures
	 * are the difference to frame f-1 */
	mem_counts *frame_port;
	hier_stats *frame_mem; /* NULL with memory.model fixed */
	mtr_writer *trace;     /* --trace-mem, NULL: off */
	int trace_err;
	diag trace_d;
	int frames_done;
	uint64_t events; /* engine events dispatched */
	double sim_ms;   /* host time in chip_run */
	int tiles_given; /* in the current frame */
	int oom;
	uint64_t *sh[11]; /* shade_counts mirrored into the registry */
	uint64_t *memc[MEM_NTYPES][4];
	/* optional progress callback: called every 64 tiles handed out */
	void (*progress)(void *ctx, int frame, int tiles_done, int tiles);
	void *progress_ctx;
} chip;

/* cfg must already be validated; w stays owned by the caller and must
 * outlive the chip. Fails (diag) on an unsupported config or out of memory. */
chip *chip_create(const saar_config *cfg, const world *w, diag *d);
void chip_destroy(chip *c);
/* Records every memory request into path (traces/memtrace.h) from now on;
 * chip_trace_close writes the end record. The caller makes it atomic (tmp
 * path + rename). */
int chip_trace_mem(chip *c, const char *path, diag *d);
int chip_trace_close(chip *c, diag *d);
/* Simulates cfg.frame.frames frames (the frame buffer holds the last). */
int chip_run(chip *c, diag *d);
/* Renders the same frame with kernel-ref (render_frame, 1 host thread) and
 * compares the 8-bit images into c's check. */
int chip_check_frame(chip *c, chip_check *out, diag *d);

/* Totals over frames, for reports. */
uint64_t chip_cycles(const chip *c);
/* Sum of a per-RTP counter "rtp<i>.<suffix>" over all RTPs. */
uint64_t chip_rtp_sum(const chip *c, const char *suffix);

const char *chip_unit_name(int kind);   /* "rgs", "trav", "list", "isect" */
const char *chip_state_name(int state); /* "idle", "running", "waiting_memory", "waiting_unit" */

#endif
