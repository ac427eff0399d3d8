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

#include "kernel-ref/framebuf.h"
#include "kernel-ref/gridimage.h"
#include "kernel-ref/render.h"
#include "kernel-ref/tlimage.h"
#include "kernel-ref/world.h"
#include "kernel-ref/worldcache.h"
#include "mem/memport.h"
#include "mem/store.h"
#include "sim/config.h"
#include "sim/core/engine.h"
#include "sim/core/stats.h"
#include "sim/memconfig.h"
#include "sim/modes/modes.h"
#include "sim/sampling.h"
#include "traces/memtrace.h"
#include "units/rgc.h"
#include "units/thread.h"

/* The frame against two references (docs/report.md "Check"): kernel-ref's
 * packet render, which runs the very functions the chip's units call
 * (pkt_trav_next, pkt_isect_tri, shade_packet_fp), and its single-ray
 * render, whose traversal, leaf walk and triangle test are its own
 * (ray_trace): a mistake in the shared packet code changes the chip and
 * the first reference alike, and only the second sees it. docs/design.md
 * ("What the references share") lists what the three still share. */
typedef struct chip_check {
	int done;
	img_cmp cmp;      /* vs the packet render */
	render_stats ref; /* kernel-ref's counts for the same frame (packets) */
	double ref_ms;    /* host time of the reference render (when it was
	                   * rendered: a cached frame keeps its own) */
	double check_ms;  /* host time of the whole check */
	int cached;       /* the reference frame came from the world cache */
	img_cmp single;   /* vs the single-ray render */
	int single_cached;
	/* packet-record replay: reads whose bytes were not the recorded ones
	 * (chip_replay_bad); the frame then counts as DIFFERENT */
	uint64_t replay_bad;
	char replay_msg[320];
} chip_check;

/* Resources the busiest-resource bound looks at (chip_fidelity): every
 * unit kind of units/unit_table.h, every L1, SDRAM and host bus. */
enum chip_res {
	RES_UNIT,                        /* + enum unit_kind: issue cycles / (count x rtps) */
	RES_L1 = RES_UNIT + UNIT_NKINDS, /* + enum mem_req_type: L1 requests / ports */
	RES_SDRAM = RES_L1 + MEM_NTYPES, /* SDRAM data-bus time */
	RES_HOSTBUS,
	RES_N
};

/* --census: the cumulative resource demand and engine time at a chunk
 * boundary (the hand-out of a chunk's first tile, or a frame's end). */
typedef struct chip_mark {
	int frame, tile; /* tile: hand-out index; the frame's tile count at its end */
	uint64_t ticks;
	double dem[RES_N]; /* chip_demand */
} chip_mark;

/* What the fidelity modes add (docs/fidelity.md). */
typedef struct chip_fidelity {
	int mode; /* enum cfg_fidelity */
	/* sampled: per frame nunits units of unit_tiles tiles, each after
	 * warmup_tiles detailed tiles; exact when every tile is detailed */
	int unit_tiles, warmup_tiles, nunits, exact;
	int *base_s;         /* planned units' first tiles (nunits) */
	int unit_cap, nreg;  /* room for units (planned + extra); run in the last frame */
	int *unit_s;         /* first tile (hand-out index) of each unit run */
	int gap, extra_left; /* extra regions: tiles at least between, how many more */
	int last_end;        /* the last region's end tile */
	/* stored warming: the jump each frame took (sampling.jump, auto
	 * resolved: mode_sampled_frame_stored), the last frame's and the
	 * count of frames per jump, and the last frame's memory-to-compute
	 * demand ratio in the warming run */
	int jump, jump_frames[CFG_JUMP_AUTO + 1];
	double mem_ratio;
	/* this frame: the middle's pieces (chunks and region pieces) and the
	 * units' own (sampling.h; a unit's stratum is its piece's .hard) */
	smp_piece *pc, *unit_pc;
	double *unit_cyc; /* the units' cycles (unit_cap) */
	int npc, pc_cap;
	smp_model model;           /* last frame: the demand model used (docs/fidelity.md) */
	uint64_t *mark_s, *mark_e; /* ticks: unit's first tile taken, first tile after it wanted */
	/* cumulative resource demand (chip_demand, RES_N each) at each unit's
	 * two marks */
	double *dem_s, *dem_e;
	uint64_t *mark_r0;       /* ticks: each region's start */
	int us_next, ue_next;    /* next unit whose start / end mark is due */
	int region_end;          /* tiles at or after it are not handed out (this region) */
	uint64_t replayed_tiles; /* all frames: tiles whose packets were replayed */
	uint64_t detailed_tiles, functional_tiles, detailed_cycles; /* all frames */
	double *est, *half; /* per frame: cycles (estimate or measured), 95% half-width */
	/* sampled, last frame: the measured head (to the first unit's end)
	 * and tail (from the last region's start), cycles */
	double head_cyc, tail_cyc;
	double *floor; /* per frame: the busiest-resource bound (cycles can't be lower) */
	/* per frame: the same bound with each unit kind's work spread evenly
	 * over the RTPs, below any run of the same work whichever RTP each
	 * tile went to; sampled: the interval's low end (the busiest RTP of
	 * the run's own tile order can exceed the cycle run's) */
	double *even_floor;
	double *unit_rate; /* last frame: cycles per unit of demand of each unit */
	/* busiest-resource bound, last frame: cycles each resource needs */
	double res_cycles[RES_N];
	int bound_by;      /* enum chip_res */
	double even_bound; /* the bound with the units' work spread evenly over the RTPs */
	double prev_dem[RES_N];
	/* per RTP and unit kind (nrtp x UNIT_NKINDS): issue cycles per
	 * instance at the last frame's end (the bound takes the busiest RTP) */
	double *prev_rtp;
} chip_fidelity;

typedef struct chip {
	saar_config cfg;
	const world *w;
	eng *e;
	eng_clock clk;
	memport mem;
	/* the bytes the memory holds (SDRAM's; host memory's with the VMA):
	 * the memory image read in place, written pages copied (mem/store.h) */
	mem_store store;
	/* what the units know of the image: its region bases and scene box
	 * (the registers the host sets), no bytes */
	mimg regs;
	/* a two-level scene (world.tl, kernel-ref/tlimage.h): the chip's image
	 * (the flattened frame's, the objects', the map and the top level), and
	 * the host's per-frame update: the top level's bytes written to the
	 * board over the host bus (memory.hostbus) before the frame, and how
	 * long that takes on an idle bus */
	tl_image tli;
	/* a uniform grid (chip.accel grid, world.grid; kernel-ref/gridimage.h):
	 * the chip's image (the frame's, then the grid's cells, lists and
	 * macrocell flags), and the grid's header as the registers hold it
	 * (no arrays; its image is regs) */
	grid_image gimg;
	grid gregs;
	uint64_t update_bytes;
	double update_ms;
	/* a warm animation (chip_anim_update): per frame, the bytes the host
	 * wrote before it (128-byte lines that changed: all of them, and of
	 * those the top level's), their host-bus time, and the cache lines the
	 * writes made stale; frame 0's are the first update (the top level) */
	uint64_t *frame_update, *frame_update_top, *frame_stale;
	double *frame_update_ms;
	/* called before frame f > 0 of chip_run (NULL: none): a warm
	 * animation moves the world and writes the update there */
	int (*between)(struct chip *c, int f, void *ctx, diag *d);
	void *between_ctx;
	int anim_checked, anim_identical; /* frames before the last checked, identical */
	int anim_keep_stale; /* test hook: chip_anim_update leaves the caches as they are */
	stats st;
	thr_env env;
	mode_sinks md; /* the sinks the units emit into (sim/modes/modes.h) */
	thr_rtp *rtp;
	int nrtp, tpr;
	rgc g;
	framebuf fb;
	uint64_t *frame_cycles; /* per frame */
	uint64_t image_bytes;   /* the chip's memory image: the world's, with the top level's
	                         * or the grid's structures after it */
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
	chip_fidelity fid;
	/* the packet record (traces/pktrec.h): fidelity functional and
	 * sampled with a world cache replay it, or record it in their first
	 * frame (rec_state: enum chip_rec) */
	pktrec rec;
	wc_map rec_map; /* the replayed record's file, mapped */
	int rec_state;
	uint8_t *replayed; /* per tile, this frame: its packets were replayed */
	/* every thread slot in functional turn order: slot 0 of each RTP,
	 * then slot 1, ... (mode_func_range, chip_run_region) */
	thr_ctx **turn;
	/* mode_func_range's passes visit the slots whose `live` bit is set. An idle
	 * slot that found no tile left and an empty RTP queue is parked until
	 * its RTP queues a packet: bit clear, its turn index in
	 * park[r * tpr ..], park_n[r] of them for RTP r. */
	uint64_t *live;
	int *park, *park_n;
	/* stored warming's relax (mode_func_range FR_RELAX): tiles each slot took
	 * since it began */
	int *relax_n;
	char *rec_key, rec_file[1200];
	double rec_ms; /* host time loading or storing the record */
	/* stored warming (sampling.warming: stored; sim/warming.h): the
	 * checkpoints (mapped from the world cache, or built by this run and
	 * held in warm_own), warm_state: enum chip_warm */
	struct wm *warm;        /* the reader (sim/modes/stored.c makes it); NULL: none */
	struct wm_writer *wcap; /* a warming run's checkpoints are taken (on_tile) */
	/* observers a driver installs (sim/modes/stored.c), so that the chip
	 * calls the code above it without including it: a tile is about to be
	 * handed out (hand-out index tile); the chip is being destroyed.
	 * NULL: none */
	void (*on_tile)(struct chip *c, int tile);
	void (*on_destroy)(struct chip *c);
	wc_map warm_map;
	void *warm_own;
	int warm_state;
	int warm_auto; /* sampling.warming was auto (cfg holds what chip_create chose) */
	char warm_file[1200];
	double warm_ms; /* host time loading or building them */
	int warm_err;   /* a checkpoint could not be restored */
	/* --census (chip_census_on): marks at every fid.unit_tiles tiles
	 * handed out and at each frame's end; NULL: off */
	chip_mark *census;
	int ncensus, census_cap;
} chip;

enum chip_rec { REC_OFF, REC_REPLAYED, REC_STORED, REC_UNSTORED };
const char *chip_rec_name(int state);
/* Stored warming: not asked for (or every tile detailed), loaded from the
 * world cache, built by this run (and stored, or not), or asked for but
 * impossible (no world cache or packet record): full warming ran. */
enum chip_warm { WARM_OFF, WARM_LOADED, WARM_BUILT, WARM_UNSTORED, WARM_UNAVAILABLE };
const char *chip_warm_name(int state);
/* Whether c's sampled frames run from stored checkpoints (loaded, built
 * or built but not stored), not from functional stretches. */
int chip_warm_stored(const chip *c);

/* cfg must already be validated; w stays owned by the caller and must
 * outlive the chip. Fails (diag) on an unsupported config or out of memory. */
chip *chip_create(const saar_config *cfg, const world *w, diag *d);
void chip_destroy(chip *c);
/* Records every memory request into path (traces/memtrace.h) from now on;
 * chip_trace_close writes the end record. The caller makes it atomic (tmp
 * path + rename); messages name the file `name` (the user's path), or path
 * when name is NULL. */
int chip_trace_mem(chip *c, const char *path, const char *name, diag *d);
int chip_trace_close(chip *c, diag *d);
/* Keeps a census from now on: the resource demand (chip_demand's
 * resources) and cycles of every chunk of fid.unit_tiles tiles in hand-out
 * order, the units' size (docs/fidelity.md, "Census"). Cycle and
 * functional modes only: a sampled frame's chunks mix timed and functional
 * work. Fails (diag) in sampled mode or out of memory. */
int chip_census_on(chip *c, diag *d);
/* Does a run of cfg estimate its cycles (sampled with a plan that leaves
 * tiles to functional processing, not every tile detailed)? From the
 * config alone, as chip_create plans it. */
int chip_estimates(const saar_config *cfg);
/* The census's condition from the config alone (before the world loads):
 * fails (diag) when the run would estimate its cycles. */
int chip_census_check(const saar_config *cfg, diag *d);
/* Simulates cfg.frame.frames frames (the frame buffer holds the last;
 * sim/modes/frame.c). */
int chip_run(chip *c, diag *d);
/* A warm animation of a two-level scene (issue 33 item 4): the world was
 * moved to the next frame's time (world_set_time); the chip's image is
 * brought to it by writing the 128-byte lines that changed (the top level;
 * the moved instances' world-space triangle and shading records), each
 * dropped from every cache that held it, counted as frame f's update with
 * its host-bus time. Caches, the VMA's state and SDRAM rows stay warm.
 * The camera and lights are the frame's. -1 (diag) when the image's layout
 * changed (no warm update possible). */
int chip_anim_update(chip *c, int f, diag *d);
/* Renders the same frame with kernel-ref (render_frame, 1 host thread),
 * with packets and with single rays (each from the world cache when it
 * has it), and compares the 8-bit images into c's check. */
int chip_check_frame(chip *c, chip_check *out, diag *d);

/* The reads a packet-record replay made that returned other bytes than
 * the recorded ones (sim/modes/replay.h), all frames, and the first one
 * described in msg (one line, no newline). 0: none. */
uint64_t chip_replay_bad(const chip *c, char *msg, size_t n);

/* ---- for the mode drivers (sim/modes/) ---- */

/* Cumulative demand of every resource (enum chip_res) in core cycles. */
void chip_demand(const chip *c, double d[RES_N]);
/* The demand of a stretch between two chip_demand snapshots, and whether
 * it is memory bound (sampling.h). */
smp_piece chip_piece(const chip *c, const double *a, const double *b);
/* The timed dispatcher: cycle-level simulation of the tiles from the
 * RGC's position up to `end` (exclusive) until every packet they made is
 * done; packets a functional stretch left in flight go on from where they
 * stopped. Returns the ticks it took. */
uint64_t chip_run_region(chip *c, int end);
/* Gives thread t the RGC's next tile (its primary packet, or its stream
 * in the replayed record); 0 when none is left or out of memory. */
int chip_take_tile(chip *c, thr_ctx *t);
/* Free thread t takes a queued secondary packet (or its stream). */
void chip_start_queued(thr_ctx *t, thr_qitem it);
/* A census mark at hand-out index tile of the current frame. */
void chip_census_mark(chip *c, int tile);
/* The frame's busiest-resource bound into fid.res_cycles / bound_by. */
void chip_resource_bound(chip *c);
/* Copies counts kept outside the registry into it. */
void chip_sync_counters(chip *c);
/* Stored warming's grids: light checkpoints every *gl tiles, full ones
 * about every *gf. */
void chip_warm_grid(const chip *c, int *gl, int *gf);
double chip_now_ms(void); /* host time, ms */
/* The frame goes on from hand-out index tile, the next packet entering a
 * thread taking age next_age (stored warming's restore). */
void chip_resume_at(chip *c, int tile, uint64_t next_age);

/* Totals over frames, for reports. */
uint64_t chip_cycles(const chip *c);
/* Sum of a per-RTP counter "rtp<i>.<suffix>" over all RTPs. */
uint64_t chip_rtp_sum(const chip *c, const char *suffix);

/* Name of an enum chip_res ("trav", "l1_kd", "sdram", "hostbus", ...). */
const char *chip_res_name(int res);
/* Name of the linear demand model's regressor i (sampling.h SMP_LIN): the
 * chip resource it is ("rgs", ..., "sdram", "hostbus"). */
const char *chip_lin_name(int i);
/* unit_table[kind].name: "rgs", "trav", "list", "isect" */
const char *chip_unit_name(int kind);
/* The config of unit kind `kind` (enum unit_kind): chip.<name>.* */
const cfg_unit *chip_unit_cfg(const saar_config *cfg, int kind);
const char *chip_state_name(int state); /* "idle", "running", "waiting_memory", "waiting_unit" */

#endif
