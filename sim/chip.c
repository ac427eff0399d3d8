/*
 * chip.c: wiring and the frame loop of the chip model (see chip.h and
 * docs/design.md, "Chip model").
 *
 * The chip holds rtps RTPs; each has threads_per_rtp thread contexts, one
 * unit group per kind (RGS, traversal, list, intersection) and a FIFO of
 * secondary packets waiting for a thread slot. One memory port (mem/memport.h)
 * serves every unit; behind it stands the model of memory.model: `fixed`
 * (every access takes memory.latency) or `hierarchy` (mem/hier.h: L1s,
 * memory interface, SDRAM, optionally the VMA over the host bus). The stack
 * spill area follows the memory image (page aligned); reads there bypass
 * the L1s, and without VMA the image up to it must fit on board. A frame starts by offering every
 * thread slot a tile (slot by slot, RTP by RTP, so consecutive tiles go to different RTPs); from
 * then on everything happens in event handlers, and the frame ends when the event queue runs dry.
 */
#define _GNU_SOURCE /* asprintf */
#include "sim/chip.h"

#include "kernel-ref/bitset.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "kernel-ref/worldcache.h"
#include "sim/modes/functional.h"
#include "sim/modes/replay.h"
#include "units/rgs.h"

static const char *const unit_names[UNIT_NKINDS] = {"rgs", "trav", "list", "isect"};
static const char *const state_names[THR_NSTATES] = {"idle", "running", "waiting_memory",
                                                     "waiting_unit"};

const cfg_unit *chip_unit_cfg(const saar_config *cfg, int kind)
{
	const cfg_unit *u[UNIT_NKINDS] = {&cfg->chip.rgs, &cfg->chip.trav, &cfg->chip.list,
	                                  &cfg->chip.isect};
	return u[kind];
}

const char *chip_unit_name(int kind)
{
	return kind >= 0 && kind < UNIT_NKINDS ? unit_names[kind] : "?";
}

const char *chip_state_name(int state)
{
	return state >= 0 && state < THR_NSTATES ? state_names[state] : "?";
}

static const struct {
	int id;
	const char *name, *unit, *desc;
} chip_counters[] = {
    {C_BOX_MISS_PACKETS, "skip.box_miss_packets", "packets",
     "packets whose rays all miss the scene box: no traversal"},
    {C_BOX_MISS_RAYS, "skip.box_miss_rays", "rays", "rays that miss the scene box"},
    {C_NODE_STEPS, "trav.node_steps", "ops", "traversal steps (kd-node reads), leaves included"},
    {C_LEAF_VISITS, "trav.leaf_visits", "ops", "leaves reached"},
    {C_EMPTY_LEAVES, "trav.empty_leaves", "ops", "empty leaves (no list or intersection op)"},
    {C_LIST_ENTRIES, "list.entries", "entries", "triangle addresses read by the list units"},
    {C_TRI_TESTS, "isect.tri_tests", "ops", "packet-triangle tests"},
    {C_RAY_TRI_TESTS, "isect.ray_tri_tests", "tests", "ray-triangle tests (active rays)"},
    {C_STACK_OVERFLOWS, "trav.stack_overflows", "pushes",
     "pushes beyond chip.stack_depth, spilled to memory"},
    {C_STACK_REFILLS, "trav.stack_refills", "pops", "spilled entries read back"},
    {C_MAX_SP, "trav.max_stack_depth", "entries", "deepest traversal stack"},
    {C_SHADE_READS, "rgs.shade_reads", "reads", "scene reads of the shader, before coalescing"},
    {C_SHADE_REQUESTS, "rgs.shade_requests", "requests",
     "shading memory requests after coalescing within a packet"},
    {C_SPAWNED, "rgs.spawned_packets", "packets", "secondary packets made by shading"},
    {C_QUEUED, "rgs.queue_samples", "packets",
     "sum over shading ops of the RTP queue length after spawning"},
    {C_MAX_QUEUE, "rgs.max_queue", "packets", "longest queue of secondary packets of one RTP"},
};

static const char *const shade_names[11] = {"shade.hits",
                                            "shade.misses",
                                            "shade.shadow_rays_made",
                                            "skip.shadow_no_light",
                                            "skip.shadow_light_behind",
                                            "skip.no_secondary",
                                            "skip.depth_cut",
                                            "shade.texel_reads",
                                            "skip.untextured_hits",
                                            "shade.shadow_occluded",
                                            "shade.shadow_lit"};

/* Issue cycles of unit kind k of RTP r so far, per instance. */
static double rtp_work(const chip *c, int r, int k)
{
	const thr_unit *u = &c->rtp[r].u[k];
	return (double)*u->busy / u->count;
}

/* Issue cycles of unit kind k so far, per instance, summed over RTPs. */
static double chip_work(const chip *c, int k)
{
	double w = 0;
	for (int r = 0; r < c->nrtp; r++)
		w += rtp_work(c, r, k);
	return w;
}

/* Cumulative demand of every resource (enum chip_res) in core cycles:
 * unit issue cycles per instance, L1 requests per port, SDRAM and host-bus
 * data-bus time (detailed and functional). Functional and detailed tiles
 * count it alike, so it is known for the whole frame. */
static void chip_demand(const chip *c, double d[RES_N])
{
	memset(d, 0, RES_N * sizeof *d);
	for (int k = 0; k < UNIT_NKINDS; k++)
		d[RES_RGS + k] = chip_work(c, k) / c->nrtp;
	hier_stats h;
	if (hier_get_stats(&c->mem, &h))
		return;
	for (int t = 0; t < MEM_NTYPES; t++)
		d[RES_L1_SHADE + t] =
		    (double)(h.reads[t] - h.bypass_reads[t]) / hier_l1_params(&c->cfg, t).ports;
	double per = (double)c->clk.period;
	d[RES_SDRAM] =
	    ((double)(h.sdram.busy_ticks + h.func_sdram_busy_ticks) - h.func_sdram_merge_ticks) /
	    per;
	d[RES_HOSTBUS] = (double)(h.hostbus.busy_ticks + h.func_hostbus_busy_ticks) / per;
}

/* A census mark at hand-out index tile of the current frame (the room
 * for every mark is made by chip_census_on). */
static void census_mark(chip *c, int tile)
{
	if (c->ncensus >= c->census_cap)
		return;
	chip_mark *m = &c->census[c->ncensus++];
	m->frame = c->frames_done;
	m->tile = tile;
	m->ticks = eng_now(c->e);
	chip_demand(c, m->dem);
}

/* A warming run's checkpoint at hand-out index tile (sim/warming.h): the
 * slot taking it is idle, every other one between two steps. */
static void warm_mark(chip *c, int tile)
{
	if (wm_is_full(c->wcap->g_light, c->wcap->g_full, tile))
		wm_put_full(c->wcap, c, c->frames_done, tile);
	double dem[RES_N];
	chip_demand(c, dem);
	wm_put_light(c->wcap, c, c->frames_done, tile, dem);
}

int chip_census_check(const saar_config *cfg, diag *d)
{
	if (chip_estimates(cfg))
		return diag_set(d, "--census", 0, 0,
		                "needs fidelity cycle or functional (a sampled frame's chunks mix "
		                "timed and functional work)");
	return 0;
}

int chip_census_on(chip *c, diag *d)
{
	if (chip_census_check(&c->cfg, d))
		return -1;
	/* marks per frame times frames: up to about 4e6 x 1e6 by the config's
	 * ranges, so counted in size_t and refused beyond an int */
	size_t per = (size_t)(c->g.ntiles + c->fid.unit_tiles - 1) / (size_t)c->fid.unit_tiles + 1,
	       cap = per * (size_t)c->cfg.frame.frames;
	if (cap > INT_MAX)
		return diag_set(d, "--census", 0, 0, "too many chunks (%zu) for one census", cap);
	c->census_cap = (int)cap;
	c->census = calloc(cap, sizeof *c->census);
	if (!c->census)
		return diag_set(d, "--census", 0, 0, "out of memory");
	return 0;
}

/* Gives thread t the RGC's next tile (its primary packet); 0 when the
 * frame has none left or the packet pool is out of memory. Timed and
 * functional processing both take tiles here. */
static int take_tile(chip *c, thr_ctx *t)
{
	int tx, ty;
	if (!rgc_next(&c->g, &tx, &ty))
		return 0;
	if (c->census && c->tiles_given % c->fid.unit_tiles == 0)
		census_mark(c, c->tiles_given);
	if (c->wcap && c->tiles_given % c->wcap->g_light == 0)
		warm_mark(c, c->tiles_given);
	c->tiles_given++;
	if (c->progress && c->tiles_given % 64 == 0)
		c->progress(c->progress_ctx, c->frames_done, c->tiles_given, c->g.ntiles);
	int tile = ty * c->g.tiles_x + tx;
	/* with a packet record the tile's packets replay their streams, in
	 * functional stretches and detailed regions alike */
	const pktrec *in = c->md.in;
	if (in && in->tile_pk[tile] >= 0) {
		c->replayed[tile] = 1;
		c->fid.replayed_tiles++;
		mode_replay_begin(in, t, in->tile_pk[tile]);
		return 1;
	}
	if (c->md.rec.out)
		mode_rec_tile(&c->md.rec, t, tile);
	else
		t->rec = -1;
	if (rgs_primary(t, tx, ty)) {
		c->oom = 1;
		return 0;
	}
	return 1;
}

/* Free thread t takes a queued secondary packet: the packet, or its
 * stream in the packet record. */
static void start_queued(thr_ctx *t, thr_qitem it)
{
	if (!it.p) {
		mode_replay_begin(((chip *)t->env->owner)->md.in, t, it.rec);
		return;
	}
	t->rec = it.rec;
	rgs_secondary(t, it.p);
}

static void on_free(thr_ctx *t)
{
	chip *c = t->env->owner;
	if (c->md.func_on) /* func_range hands out the work itself */
		return;
	thr_qitem it;
	if (rgs_dequeue(t->rtp, &it)) {
		start_queued(t, it);
		return;
	}
	/* sampled: the marks that time a measured unit are the moments its
	 * first tile is taken and the tile after it is wanted (docs/fidelity.md) */
	chip_fidelity *F = &c->fid;
	int next = c->g.next;
	if (next >= F->region_end) {
		if (F->ue_next < F->us_next) {
			chip_demand(c, &F->dem_e[F->ue_next * RES_N]);
			F->mark_e[F->ue_next++] = eng_now(c->e);
		}
		/* a region inside the frame ends here: what is in flight goes on
		 * functionally (each thread's next step, as its pending memory
		 * and unit events fire) instead of draining cycle by cycle */
		if (F->region_end < c->g.ntiles)
			mode_set_func(&c->md, 1);
		return;
	}
	if (F->us_next < F->unit_cap && F->unit_s[F->us_next] == next) {
		chip_demand(c, &F->dem_s[F->us_next * RES_N]);
		F->mark_s[F->us_next++] = eng_now(c->e);
	}
	take_tile(c, t);
}

/* posix_memalign takes any size, but the rounding keeps these blocks
 * valid for aligned_alloc too (kernel-ref/render.c's alloc64). */
static void *alloc64(size_t n)
{
	void *p = NULL;
	return posix_memalign(&p, 64, (n + 63) & ~(size_t)63) ? NULL : p;
}

static void trace_tap(void *ctx, const mem_req *r)
{
	chip *c = ctx;
	if (c->trace_err)
		return;
	mtr_rec m = {eng_ticks_to_cycles(c->clk, eng_now(c->e)), r->addr, r->bytes, r->type,
	             r->write};
	if (mtr_write(c->trace, &m, &c->trace_d))
		c->trace_err = 1;
}

int chip_trace_mem(chip *c, const char *path, diag *d)
{
	c->trace = malloc(sizeof *c->trace);
	if (!c->trace)
		return diag_set(d, "chip", 0, 0, "out of memory for the trace writer");
	if (mtr_open_write(c->trace, path, d)) {
		free(c->trace);
		c->trace = NULL;
		return -1;
	}
	c->mem.tap = trace_tap;
	c->mem.tap_ctx = c;
	return 0;
}

int chip_trace_close(chip *c, diag *d)
{
	if (!c->trace)
		return 0;
	int rc = c->trace_err ? -1 : 0;
	if (rc)
		*d = c->trace_d;
	if (mtr_close_write(c->trace, rc ? &c->trace_d : d))
		rc = -1;
	free(c->trace);
	c->trace = NULL;
	c->mem.tap = NULL;
	return rc;
}

static uint64_t *reg(chip *c, const char *name, const char *unit, const char *desc)
{
	uint64_t *p = stats_counter(&c->st, name, unit, desc);
	if (!p)
		c->oom = 1;
	return p;
}

/* Threads per RTP whose tiles the default warm-up holds at most. */
#define WARMUP_TPR 16

/* Stored warming's light grid: a checkpoint per RTP's worth of tiles
 * (the units and warm-ups of its plan are multiples of it). */
static int warm_light_grid(const saar_config *cfg)
{
	return cfg->chip.rtps;
}

/* The sampling plan's sizes from the config alone: tiles per unit and
 * per warm-up, and the units per frame; 1 when the regions would cover
 * the frame anyway (every tile simulated, as cycle). */
static int fid_plan(const saar_config *cfg, int *unit, int *warmup, long *units)
{
	int nrtp = cfg->chip.rtps, tpr = cfg->chip.threads_per_rtp, threads = nrtp * tpr;
	int N = rgc_tiles(cfg->frame.width, cfg->frame.height);
	/* a unit shorter than one tile per thread is over before any thread
	 * has finished anything: its window would be empty */
	int U = cfg->sampling.unit_tiles > threads ? cfg->sampling.unit_tiles : threads;
	/* a region takes over a full chip (packets in flight, caches warm):
	 * the warm-up refills the memory and unit queues (docs/fidelity.md).
	 * One tile per thread, but at most WARMUP_TPR per RTP: at 64 threads
	 * per RTP a 64-tile warm-up measured as well as a 256-tile one */
	int warm = nrtp * (tpr < WARMUP_TPR ? tpr : WARMUP_TPR);
	int W = cfg->sampling.warmup_tiles >= 0 ? cfg->sampling.warmup_tiles : warm;
	/* stored warming's regions start and end on its light grid */
	if (cfg->sampling.warming == CFG_WARMING_STORED) {
		int g = warm_light_grid(cfg);
		U = (U + g - 1) / g * g;
		W = (W + g - 1) / g * g;
	}
	/* n units of U tiles, at least sampling.min_units and 3 (the head,
	 * the tail and one between); when the regions would cover the frame
	 * anyway, simulate all of it */
	long n = lround((double)N * cfg->sampling.rate / U);
	if (n < cfg->sampling.min_units)
		n = cfg->sampling.min_units;
	if (n < 3)
		n = 3;
	*unit = U;
	*warmup = W;
	*units = n;
	return cfg->sampling.rate >= 1.0 || n * (long)(U + W) >= N;
}

int chip_estimates(const saar_config *cfg)
{
	int U, W;
	long n;
	return cfg->fidelity == CFG_FIDELITY_SAMPLED && !fid_plan(cfg, &U, &W, &n);
}

/* Sizes the sampling plan of one frame (the same for every frame). */
static int fid_init(chip *c)
{
	chip_fidelity *F = &c->fid;
	const saar_config *cfg = &c->cfg;
	F->mode = cfg->fidelity;
	F->region_end = c->g.ntiles;
	long n;
	int exact = fid_plan(cfg, &F->unit_tiles, &F->warmup_tiles, &n);
	size_t nf = (size_t)cfg->frame.frames;
	F->est = calloc(nf, sizeof *F->est);
	F->half = calloc(nf, sizeof *F->half);
	F->floor = calloc(nf, sizeof *F->floor);
	F->prev_rtp = calloc((size_t)c->nrtp * UNIT_NKINDS, sizeof *F->prev_rtp);
	if (!F->est || !F->half || !F->floor || !F->prev_rtp)
		return -1;
	if (F->mode != CFG_FIDELITY_SAMPLED)
		return 0;
	if (exact) {
		F->exact = 1;
		return 0;
	}
	int U = F->unit_tiles, W = F->warmup_tiles, N = c->g.ntiles;
	F->nunits = (int)n;
	/* planned units, and as many extra ones at most (sampling.hard_share) */
	size_t cap = (size_t)(cfg->sampling.hard_share > 0 ? 2 * n : n);
	F->unit_cap = (int)cap;
	F->base_s = calloc((size_t)n, sizeof *F->base_s);
	F->unit_s = calloc(cap, sizeof *F->unit_s);
	F->mark_s = calloc(cap, sizeof *F->mark_s);
	F->mark_e = calloc(cap, sizeof *F->mark_e);
	F->unit_rate = calloc(cap, sizeof *F->unit_rate);
	F->unit_pc = calloc(cap, sizeof *F->unit_pc);
	F->unit_cyc = calloc(cap, sizeof *F->unit_cyc);
	/* pieces per frame: a chunk per U tiles, one short chunk per stretch,
	 * three per region (warm-up, unit, after it) */
	F->pc_cap = N / U + 4 * (int)cap + 8;
	F->pc = calloc((size_t)F->pc_cap, sizeof *F->pc);
	F->mark_r0 = calloc(cap, sizeof *F->mark_r0);
	double **dem[2] = {&F->dem_s, &F->dem_e};
	for (int i = 0; i < 2; i++)
		if (!(*dem[i] = calloc(cap * RES_N, sizeof(double))))
			return -1;
	if (!F->base_s || !F->unit_s || !F->mark_s || !F->mark_e || !F->unit_rate || !F->mark_r0 ||
	    !F->unit_pc || !F->unit_cyc || !F->pc)
		return -1;
	/* the head region is the frame's start, the tail its end; the others
	 * systematic between them, one per period P at sampling.offset of the
	 * room left in it (P >= U + W: regions never overlap) */
	int RW = U + W, m = (int)n - 2;
	double P = (double)(N - 2 * RW) / m;
	F->base_s[0] = W;
	F->base_s[n - 1] = N - U;
	for (int k = 0; k < m; k++)
		F->base_s[k + 1] = RW + (int)((double)k * P + (P - RW) * cfg->sampling.offset) + W;
	/* an extra region at most every quarter period */
	F->gap = (int)(P / 4) > U ? (int)(P / 4) : U;
	return 0;
}

/* An idle thread context of RTP rp: slot id, chip-wide gid, its own
 * traversal stack and room for nkids children. -1 when out of memory (the
 * caller frees what was allocated). */
static int thread_init(thr_ctx *t, thr_rtp *rp, int id, int gid, int nkids)
{
	*t = (thr_ctx){.rtp = rp,
	               .env = rp->env,
	               .id = id,
	               .gid = gid,
	               .rec = -1,
	               .state = THR_IDLE,
	               .nkids = nkids};
	t->stack = alloc64(PKT_STACK_MAX * sizeof(trav_entry));
	t->kids = alloc64((size_t)nkids * sizeof(packet));
	return t->stack && t->kids ? 0 : -1;
}

static void thread_free(thr_ctx *t)
{
	free(t->stack);
	free(t->kids);
	thr_free_buffers(t);
}

chip *chip_create(const saar_config *cfg, const world *w, diag *d)
{
	if (cfg->chip.packet_w != TILE_W || cfg->chip.packet_h != TILE_H) {
		diag_set(d, "config", 0, 0,
		         "chip.packet_w x chip.packet_h = %d x %d: only %d x %d packets are "
		         "supported (kernel-ref tiles)",
		         cfg->chip.packet_w, cfg->chip.packet_h, TILE_W, TILE_H);
		return NULL;
	}
	chip *c = calloc(1, sizeof *c);
	if (!c)
		goto oom;
	c->cfg = *cfg;
	c->w = w;
	c->nrtp = cfg->chip.rtps;
	c->tpr = cfg->chip.threads_per_rtp;
	c->clk = eng_clock_mhz(cfg->chip.clock_mhz);
	stats_init(&c->st);
	c->e = eng_create((size_t)(c->nrtp * c->tpr * 4 + 64));
	size_t nf = (size_t)cfg->frame.frames;
	c->frame_cycles = calloc(nf, sizeof *c->frame_cycles);
	c->frame_port = calloc(nf, sizeof *c->frame_port);
	if (cfg->memory.model == CFG_MEM_HIERARCHY)
		c->frame_mem = calloc(nf, sizeof *c->frame_mem);
	c->spill_base = (w->m.size + 4095) & ~(uint64_t)4095;
	c->regs = w->m;
	c->regs.bytes = NULL;
	/* the memory's bytes: the image, then every slot's spill area */
	uint64_t space =
	    c->spill_base + (uint64_t)c->nrtp * (uint64_t)c->tpr * PKT_STACK_MAX * THR_SPILL_STRIDE;
	if (!c->e || !c->frame_cycles || !c->frame_port ||
	    (cfg->memory.model == CFG_MEM_HIERARCHY && !c->frame_mem) ||
	    ms_init(&c->store, w->m.bytes, w->m.size, space))
		goto oom;
	/* a memory model the config cannot build (an image too big for the
	 * board without VMA, a bad cache geometry) is the user's error: keep
	 * its message */
	int mrc;
	if (cfg->memory.model == CFG_MEM_HIERARCHY)
		mrc = mem_init_hier(&c->mem, c->e, c->clk, cfg, c->spill_base, &c->store, d);
	else if ((mrc = mem_init_fixed(&c->mem, c->e, c->clk, cfg->memory.latency, &c->store)))
		diag_set(d, "chip", 0, 0, "out of memory");
	if (mrc) {
		chip_destroy(c);
		return NULL;
	}
	if (thr_env_init(&c->env) || fb_init(&c->fb, cfg->frame.width, cfg->frame.height) ||
	    rgc_init(&c->g, cfg->frame.width, cfg->frame.height, cfg->chip.tile_order) ||
	    !(c->replayed = calloc((size_t)c->g.ntiles, 1)))
		goto oom;

	thr_env *v = &c->env;
	v->e = c->e;
	v->clk = c->clk;
	v->mem = &c->mem;
	v->m = &c->regs;
	v->stack_depth = cfg->chip.stack_depth;
	v->max_steps = 2 * (uint64_t)w->m.nnodes + 64;
	v->masked = cfg->chip.masked_packets;
	/* the datapath formats; kernel-ref's check frame stays full precision */
	if (fpfmt_init(&v->prec.trav, cfg->chip.fp.trav.exp, cfg->chip.fp.trav.mant,
	               cfg->chip.fp.round) ||
	    fpfmt_init(&v->prec.isect, cfg->chip.fp.isect.exp, cfg->chip.fp.isect.mant,
	               cfg->chip.fp.round) ||
	    fpfmt_init(&v->prec.shade, cfg->chip.fp.shade.exp, cfg->chip.fp.shade.mant,
	               cfg->chip.fp.round)) {
		diag_set(d, "config", 0, 0, "chip.fp: unsupported floating-point format");
		chip_destroy(c);
		return NULL;
	}
	v->nlights = w->v.nlights;
	v->spill_base = c->spill_base;
	v->on_free = on_free;
	v->owner = c;
	mode_sinks_init(&c->md, v);
	render_opts ro;
	render_opts_default(&ro);
	v->sc = (shade_ctx){&c->regs,      w->v.lights, w->v.nlights, cfg->shading.max_depth,
	                    ro.background, &c->fb,      NULL};
	cam_setup(&v->cam, &w->v.cam, cfg->frame.width, cfg->frame.height);

	/* counters */
	char name[64];
	for (int t = 0; t < PKT_NTYPES; t++) {
		snprintf(name, sizeof name, "packets.%s", pkt_type_name(t));
		v->c[C_PKT_PRIMARY + t] = reg(c, name, "packets", "packets that entered a thread");
		snprintf(name, sizeof name, "rays.%s", pkt_type_name(t));
		v->c[C_RAYS_PRIMARY + t] = reg(c, name, "rays", "valid rays of those packets");
	}
	for (size_t i = 0; i < sizeof chip_counters / sizeof *chip_counters; i++)
		v->c[chip_counters[i].id] =
		    reg(c, chip_counters[i].name, chip_counters[i].unit, chip_counters[i].desc);
	for (int i = 0; i < 11; i++)
		c->sh[i] = reg(c, shade_names[i], "", "kernel-ref shade_counts field");
	static const char *const mk[4] = {"reads", "read_bytes", "writes", "write_bytes"};
	for (int t = 0; t < MEM_NTYPES; t++)
		for (int k = 0; k < 4; k++) {
			snprintf(name, sizeof name, "mem.%s.%s", mem_type_name(t), mk[k]);
			c->memc[t][k] = reg(c, name, k & 1 ? "bytes" : "requests",
			                    "memory-port traffic of this requester type");
		}

	/* RTPs, units and threads */
	c->rtp = calloc((size_t)c->nrtp, sizeof *c->rtp);
	if (!c->rtp)
		goto oom;
	int nkids = w->v.nlights + 2;
	for (int r = 0; r < c->nrtp; r++) {
		thr_rtp *rp = &c->rtp[r];
		rp->env = v;
		rp->id = r;
		for (int k = 0; k < UNIT_NKINDS; k++) {
			thr_unit *u = &rp->u[k];
			if (thr_unit_init(u, c->e, c->clk, chip_unit_cfg(cfg, k),
			                  cfg->chip.masked_packets, cfg->chip.thread_sched, c->tpr))
				goto oom;
			u->on_start = thr_on_start;
			snprintf(name, sizeof name, "rtp%d.%s.ops", r, unit_names[k]);
			u->ops_n = reg(c, name, "ops", "operations issued");
			snprintf(name, sizeof name, "rtp%d.%s.busy_cycles", r, unit_names[k]);
			u->busy = reg(c, name, "cycles", "issue cycles (summed over the units)");
			snprintf(name, sizeof name, "rtp%d.%s.rays", r, unit_names[k]);
			u->rays = reg(c, name, "rays", "active rays of those operations");
			if (c->oom)
				goto oom;
		}
		for (int s = 0; s < THR_NSTATES; s++) {
			snprintf(name, sizeof name, "rtp%d.threads.%s_ps", r, state_names[s]);
			rp->occ[s] = reg(c, name, "ps", "thread time in this state, summed");
		}
		rp->t = alloc64((size_t)c->tpr * sizeof(thr_ctx));
		if (!rp->t)
			goto oom;
		memset(rp->t, 0, (size_t)c->tpr * sizeof(thr_ctx));
		rp->nt = c->tpr;
		rp->nidle = c->tpr;
		for (int i = 0; i < c->tpr; i++)
			if (thread_init(&rp->t[i], rp, i, r * c->tpr + i, nkids))
				goto oom;
	}
	c->turn = malloc((size_t)c->nrtp * (size_t)c->tpr * sizeof *c->turn);
	if (!c->turn)
		goto oom;
	for (int s = 0; s < c->tpr; s++)
		for (int r = 0; r < c->nrtp; r++)
			c->turn[s * c->nrtp + r] = &c->rtp[r].t[s];
	size_t nslots = (size_t)c->nrtp * (size_t)c->tpr;
	c->live = malloc((size_t)bits_words((int)nslots) * sizeof *c->live);
	c->park = malloc(nslots * sizeof *c->park);
	c->park_n = malloc((size_t)c->nrtp * sizeof *c->park_n);
	c->relax_n = malloc(nslots * sizeof *c->relax_n);
	if (!c->live || !c->park || !c->park_n || !c->relax_n)
		goto oom;
	if (c->oom || fid_init(c))
		goto oom;
	return c;
oom:
	chip_destroy(c);
	diag_set(d, "chip", 0, 0, "out of memory for %d RTPs x %d threads", cfg->chip.rtps,
	         cfg->chip.threads_per_rtp);
	return NULL;
}

void chip_destroy(chip *c)
{
	if (!c)
		return;
	for (int r = 0; c->rtp && r < c->nrtp; r++) {
		thr_rtp *rp = &c->rtp[r];
		for (int k = 0; k < UNIT_NKINDS; k++)
			thr_unit_free(&rp->u[k]);
		for (int i = 0; rp->t && i < rp->nt; i++)
			thread_free(&rp->t[i]);
		free(rp->t);
		free(rp->q);
	}
	free(c->rtp);
	free(c->turn);
	free(c->live);
	free(c->park);
	free(c->park_n);
	free(c->relax_n);
	rgc_free(&c->g);
	fb_free(&c->fb);
	pr_free(&c->rec);
	wc_unmap(&c->rec_map);
	free(c->rec_key);
	free(c->replayed);
	free(c->census);
	wm_close(&c->warm);
	wc_unmap(&c->warm_map);
	free(c->warm_own);
	mem_free(&c->mem);
	ms_free(&c->store);
	thr_env_free(&c->env);
	if (c->e)
		eng_destroy(c->e);
	free(c->frame_cycles);
	free(c->frame_port);
	free(c->frame_mem);
	free(c->fid.unit_s);
	free(c->fid.base_s);
	free(c->fid.mark_s);
	free(c->fid.mark_e);
	free(c->fid.est);
	free(c->fid.half);
	free(c->fid.floor);
	free(c->fid.prev_rtp);
	free(c->fid.unit_rate);
	free(c->fid.unit_pc);
	free(c->fid.unit_cyc);
	free(c->fid.pc);
	free(c->fid.mark_r0);
	free(c->fid.dem_s);
	free(c->fid.dem_e);
	if (c->trace) {
		diag d;
		chip_trace_close(c, &d);
	}
	stats_free(&c->st);
	free(c);
}

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* Copies counts kept outside the registry (memory port, shade_counts). */
static void sync_counters(chip *c)
{
	const uint64_t *sc = (const uint64_t *)&c->env.sh;
	_Static_assert(sizeof(shade_counts) == 11 * sizeof(uint64_t), "shade_counts changed");
	for (int i = 0; i < 11; i++)
		*c->sh[i] = sc[i];
	for (int t = 0; t < MEM_NTYPES; t++) {
		*c->memc[t][0] = c->mem.n.reads[t];
		*c->memc[t][1] = c->mem.n.read_bytes[t];
		*c->memc[t][2] = c->mem.n.writes[t];
		*c->memc[t][3] = c->mem.n.write_bytes[t];
	}
}

/* Cycle-level simulation of the tiles from the RGC's position up to `end`
 * (exclusive), until every packet they made is done: a frame starts by
 * offering every thread slot a tile, slot by slot and RTP by RTP. Returns
 * the ticks it took. */
static uint64_t run_region(chip *c, int end)
{
	uint64_t t0 = eng_now(c->e);
	int first = c->g.next;
	c->fid.region_end = end;
	mode_set_func(&c->md, 0);
	/* packets a functional stretch left in flight go on cycle by cycle
	 * from where they stopped (replayed ones too: sim/modes/replay.h): the
	 * region starts with a full chip, not with every thread taking a tile
	 * at once; slot by slot, RTP by RTP (the turn order) */
	int n = c->nrtp * c->tpr;
	for (int i = 0; i < n; i++)
		mode_func_to_timed(c->turn[i]);
	for (int i = 0; i < n; i++)
		if (c->turn[i]->state == THR_IDLE)
			on_free(c->turn[i]);
	eng_run(c->e, ENG_FOREVER);
	mode_set_func(&c->md, 0);
	c->fid.detailed_tiles += (uint64_t)(end - first);
	c->fid.detailed_cycles += eng_ticks_to_cycles(c->clk, eng_now(c->e) - t0);
	return eng_now(c->e) - t0;
}

/* The resource behind each regressor of the linear demand model. */
static const int lin_res[SMP_LIN] = {RES_RGS,   RES_TRAV,  RES_LIST,
                                     RES_ISECT, RES_SDRAM, RES_HOSTBUS};

const char *chip_lin_name(int i)
{
	return i >= 0 && i < SMP_LIN ? chip_res_name(lin_res[i]) : "?";
}

/* The demand of a stretch between two chip_demand snapshots, and whether
 * it is memory bound: its SDRAM or host-bus time above
 * sampling.hard_share of its busiest compute resource. */
static smp_piece piece(const chip *c, const double *a, const double *b)
{
	smp_piece p;
	memset(&p, 0, sizeof p);
	for (int r = 0; r < RES_N; r++) {
		double d = b[r] - a[r];
		if (r == RES_SDRAM)
			p.sdram = d;
		else if (r == RES_HOSTBUS)
			p.hbus = d;
		else if (d > p.comp)
			p.comp = d;
	}
	for (int i = 0; i < SMP_LIN; i++)
		p.lin[i] = b[lin_res[i]] - a[lin_res[i]];
	double hs = c->cfg.sampling.hard_share, mem = p.sdram > p.hbus ? p.sdram : p.hbus;
	p.hard = hs > 0 && mem > hs * p.comp;
	return p;
}

/* Keeps a piece of the estimated middle of the frame (chunk or region
 * piece) for the estimator; returns its stratum. */
static int account(chip_fidelity *F, smp_piece p, int middle)
{
	if (middle && smp_busiest(&p) > 0) {
		if (F->npc < F->pc_cap)
			F->pc[F->npc++] = p;
		else { /* cannot happen (pc_cap counts every piece); keep the sum */
			smp_piece *q = &F->pc[F->pc_cap - 1];
			q->comp += p.comp;
			q->sdram += p.sdram;
			q->hbus += p.hbus;
			for (int i = 0; i < SMP_LIN; i++)
				q->lin[i] += p.lin[i];
		}
	}
	return p.hard;
}

/* Gives a free thread its next packet in functional processing: a
 * secondary packet of its RTP first (as on_free does), else the next tile
 * below `end`. Returns 0 when there is nothing to give. */
static int func_give(chip *c, thr_ctx *t, int end, int *given)
{
	thr_qitem it;
	if (rgs_dequeue(t->rtp, &it)) {
		start_queued(t, it);
		return 1;
	}
	if (c->g.next >= end || !take_tile(c, t))
		return 0;
	c->fid.functional_tiles++;
	++*given;
	return 1;
}

/* Sampled: does a memory-bound chunk (hard) that ended at tile `from`
 * bring an extra region starting at `start`, before the next planned one
 * at `next`? When one is left, the last region ended at least `gap` tiles
 * before `from`, and a warm-up and unit fit before `next`. Functional
 * stretches (func_range) and stored warming's gaps alike. */
static int extra_due(const chip_fidelity *F, int hard, int from, int start, int next)
{
	return hard && F->extra_left > 0 && from - F->last_end >= F->gap &&
	       next - start >= F->warmup_tiles + F->unit_tiles;
}

/* A sampled frame's bookkeeping at its start. */
static void sampled_begin(chip_fidelity *F)
{
	F->us_next = F->ue_next = 0;
	F->npc = 0;
	F->extra_left = F->unit_cap - F->nunits;
	F->last_end = 0;
}

/* Thread slots ahead whose packet streams func_range prefetches. */
#define PREFETCH_TURNS 4

/* Takes idle slot i (turn order) of RTP r off func_range's passes. */
static void park_slot(chip *c, int i, int r)
{
	bits_clear(c->live, i);
	c->park[r * c->tpr + c->park_n[r]++] = i;
}

/* Puts RTP r's parked slots back on the passes. */
static void unpark_rtp(chip *c, int r)
{
	for (int k = 0; k < c->park_n[r]; k++)
		bits_set(c->live, c->park[r * c->tpr + k]);
	c->park_n[r] = 0;
}

/* Functional processing of tiles from the RGC's position up to `end`, with
 * the same unit code emitting into the functional sink (sim/modes/functional.h) and every thread
 * slot in use, as the detailed chip has them: each slot holds a packet, and
 * the slots take one step each in turn (a step: one unit operation and the
 * memory reads before the next), so the caches see the packets' accesses
 * interleaved as a busy chip makes them, not one packet after another (one
 * at a time, the L1s and SDRAM saw far fewer misses than the cycle model
 * at 16-64 threads: docs/fidelity.md). A slot that finishes takes a secondary packet of
 * its RTP, else the next tile. With a packet record, packets replay their
 * streams instead of running their math (sim/modes/replay.h). Memory goes
 * through the hierarchy's functional path: the data is there at once, and
 * a line a region left in flight counts as on its way (hier.c). FR_DRAIN
 * ends the range with every slot free; FR_STOP as soon as its last tile
 * is handed out, packets still in flight, or earlier for an extra region
 * (returning 1). FR_RELAX (stored warming, after a region) ends when a
 * slot wants a tile on the light-checkpoint grid (its RTP's queue empty)
 * once every slot has taken RELAX_TILES tiles since the range began: the
 * moment at which the warming run takes its checkpoints (warm_mark), with
 * the packets in flight about as far along as the warming run's are
 * (docs/fidelity.md "Stored warming"); or when the tile wanted is `end`,
 * or earlier for an extra region (returning 1), as FR_STOP. */
enum fr_mode { FR_DRAIN, FR_STOP, FR_RELAX };

/* Tiles every slot takes in a relax. One leaves the slot that finished
 * last holding a packet just begun where the warming run's slots are part
 * way through theirs, and the frame's counts come out low; two do not
 * (docs/fidelity.md "Stored warming", tests/test_warming.c
 * sponza_one_thread_pci_as_cycle). */
#define RELAX_TILES 2

static int func_range(chip *c, int end, int mode)
{
	chip_fidelity *F = &c->fid;
	/* sampled: the demand of each chunk of unit_tiles tiles (the units'
	 * size) adds to its stratum's; the chunk's busiest resource is its
	 * demand. A memory-bound chunk stops the stretch early for an extra
	 * region, when one is left, the last region ended at least `gap`
	 * tiles ago, and there is room before the next planned one. */
	int chunked = F->mode == CFG_FIDELITY_SAMPLED, given = 0, extra = 0;
	int n = c->nrtp * c->tpr;
	double d0[RES_N], d1[RES_N];
	if (chunked)
		chip_demand(c, d0);
	/* every slot on the passes; the drain parks idle ones (below) */
	memset(c->live, 0xff, (size_t)bits_words(n) * sizeof *c->live);
	if (n % 64)
		c->live[n / 64] = (1ull << (n % 64)) - 1;
	memset(c->park_n, 0, (size_t)c->nrtp * sizeof *c->park_n);
	int relaxed = 0, stop = 0;
	if (mode == FR_RELAX)
		memset(c->relax_n, 0, (size_t)n * sizeof *c->relax_n);
	mode_set_func(&c->md, 1);
	for (int busy = 1; busy && !stop && !c->oom;) {
		/* before a region: stop once the tiles are handed out and leave
		 * the packets in flight for the region to take over */
		if (mode == FR_STOP && c->g.next >= end)
			break;
		busy = 0;
		for (int i = bits_next(c->live, n, 0); i < n && !stop;
		     i = bits_next(c->live, n, i + 1)) {
			thr_ctx *t = c->turn[i];
			int r = (int)(t->rtp - c->rtp);
			if (!t->p && !t->rp) {
				if (chunked && given == F->unit_tiles) {
					chip_demand(c, d1);
					int hard = account(F, piece(c, d0, d1), 1);
					memcpy(d0, d1, sizeof d0);
					given = 0;
					if (mode != FR_DRAIN &&
					    extra_due(F, hard, c->g.next, c->g.next, end)) {
						end = c->g.next;
						extra = 1;
					}
				}
				if (mode == FR_RELAX && t->rtp->qn == 0 &&
				    ((relaxed == n && c->g.next % c->warm.g_light == 0) ||
				     c->g.next >= end)) {
					stop = 1;
					break;
				}
				int had = given;
				if (!func_give(c, t, end, &given)) {
					/* no tile is left (`end` only comes closer) and
					 * its RTP's queue is empty: until the RTP queues
					 * a packet, every visit would do nothing, so the
					 * drain's passes skip it (a 1024-thread drain
					 * spent most of its time visiting idle slots) */
					if (c->g.next >= end)
						park_slot(c, i, r);
					continue;
				}
				if (mode == FR_RELAX && given != had &&
				    ++c->relax_n[i] == RELAX_TILES)
					relaxed++;
			}
			if (t->rp) {
				/* the stream of the slot a few turns on is elsewhere
				 * in the record: start fetching it now (one turn
				 * ahead was too late to hide the host's memory
				 * latency); a step's bytes often run into the next
				 * host line: fetch that too */
				int k = i + PREFETCH_TURNS < n ? i + PREFETCH_TURNS
				                               : i + PREFETCH_TURNS - n;
				if (k < n && c->turn[k]->rp) {
					__builtin_prefetch(c->turn[k]->rp);
					__builtin_prefetch(c->turn[k]->rp + 32);
				}
			}
			busy |= mode_func_step(t);
			/* packets it queued (functional: only a step of its
			 * RTP's slots queues) bring that RTP's parked slots
			 * back: those ahead of i in this pass, the others in
			 * the next, as when every slot was visited */
			if (c->park_n[r] && t->rtp->qn > 0)
				unpark_rtp(c, r);
		}
	}
	mode_set_func(&c->md, 0);
	if (chunked) {
		chip_demand(c, d1);
		account(F, piece(c, d0, d1), 1);
	}
	return extra;
}

/* Sampled frame: detailed regions (warm-up, then one measured unit) with
 * functional stretches between them; a region takes over the packets the
 * stretch before it left in flight, and hands its own to the stretch after
 * it. The first region is the frame's start and the last its end (a chip
 * starting empty, and the final drain), both measured, not estimated.
 * Everything between is estimated (sampling.c) from the units' cycles and
 * the resource demands of every piece of it, taken per chunk of
 * unit_tiles tiles (func_range) and per region piece (warm-up, unit, what
 * finished after the unit), detailed or functional alike. The interval
 * adds sampling.bias_bound. A memory-bound functional chunk brings an
 * extra region (func_range). docs/fidelity.md. */
static void sampled_estimate(chip *c, int f, int nr, uint64_t t0);
static void sampled_region(chip *c, int j, int tail);

static void sampled_frame(chip *c, int f)
{
	chip_fidelity *F = &c->fid;
	int W = F->warmup_tiles, n = F->nunits;
	uint64_t t0 = eng_now(c->e);
	sampled_begin(F);
	int j = 0;
	for (int b = 0; b < n; j++) {
		int rs = F->base_s[b] - W;
		if (rs < c->g.next)
			rs = c->g.next;
		/* the stretch before the next planned region may stop early at a
		 * memory-bound chunk: an extra region starts there */
		int extra = c->g.next < rs && func_range(c, rs, FR_STOP);
		if (extra) {
			F->extra_left--;
			F->unit_s[j] = c->g.next + W;
		} else {
			F->unit_s[j] = F->base_s[b++];
		}
		sampled_region(c, j, b == n && !extra);
	}
	sampled_estimate(c, f, j, t0);
}

/* Region j of a sampled frame (its unit_s set): runs it and keeps its
 * pieces in order: warm-up, unit, what finished after the unit; the
 * head's first two and the tail are measured, not estimated. */
static void sampled_region(chip *c, int j, int tail)
{
	chip_fidelity *F = &c->fid;
	double r0[RES_N], r1[RES_N];
	chip_demand(c, r0);
	F->mark_r0[j] = eng_now(c->e);
	run_region(c, tail ? c->g.ntiles : F->unit_s[j] + F->unit_tiles);
	F->last_end = c->g.next;
	chip_demand(c, r1);
	const double *ds = &F->dem_s[j * RES_N], *de = &F->dem_e[j * RES_N];
	F->unit_pc[j] = piece(c, ds, de);
	F->unit_cyc[j] = (double)(F->mark_e[j] - F->mark_s[j]) / (double)c->clk.period;
	account(F, piece(c, r0, ds), j > 0 && !tail);
	account(F, F->unit_pc[j], j > 0 && !tail);
	account(F, piece(c, de, r1), !tail);
}

/* A piece of the warming run between two light checkpoints, its SDRAM
 * demand less the share m of on-board-cache hits a timed chip merges. */
static smp_piece warm_piece(chip *c, int f, int a, int b, double m)
{
	double d0[RES_N], d1[RES_N], per = (double)c->clk.period;
	uint64_t h0, h1;
	memcpy(d0, wm_demand(&c->warm, f, a, &h0), sizeof d0);
	memcpy(d1, wm_demand(&c->warm, f, b, &h1), sizeof d1);
	d0[RES_SDRAM] -= m * (double)h0 / per;
	d1[RES_SDRAM] -= m * (double)h1 / per;
	return piece(c, d0, d1);
}

/* A sampled frame with stored warming (docs/fidelity.md "Stored
 * warming"): as sampled_frame, but a gap between regions is not run: its
 * chunks' demands come from the warming run's light checkpoints and the
 * next region starts from the full checkpoint at its start
 * (wm_restore), which also adds the gap's counts. Region starts snap
 * down to the last full checkpoint (wm_full_below); a region whose start
 * falls at or before the last one's end follows it without a gap. */
static void sampled_frame_stored(chip *c, int f)
{
	chip_fidelity *F = &c->fid;
	wm *r = &c->warm;
	int N = c->g.ntiles, U = F->unit_tiles, W = F->warmup_tiles, n = F->nunits;
	uint64_t t0 = eng_now(c->e);
	sampled_begin(F);
	int j = 0, at = 0, room = W + U;
	for (int b = 0; b < n; j++) {
		int tail = b == n - 1, rs = wm_full_below(r, F->base_s[b] - W), extra = 0;
		if (!tail && (rs > at ? rs : at) + room > wm_full_below(r, F->base_s[n - 1] - W)) {
			b++; /* no room before the tail: left out */
			j--;
			continue;
		}
		if (rs > at && j > 0) {
			/* the last region's packets in flight go on functionally
			 * until none is left in a slot and those in flight are as
			 * far along as the warming run's when it takes a
			 * checkpoint (FR_RELAX): the work the chip leaves undone
			 * at the jump is then what the gap's counts hold. A
			 * timed chip holds more work in flight when a tile is
			 * wanted than the warming run does (slow packets stay
			 * longer), and jumping at once lost that work (the
			 * frame's PCI bytes came out low; docs/fidelity.md). A
			 * memory-bound chunk on the way brings an extra region
			 * there and then, as in full warming: a relax takes
			 * RELAX_TILES tiles per slot, and with many threads the
			 * gaps after it were too short for the extra regions,
			 * and the estimate lost its memory-bound units. */
			extra = func_range(c, rs, FR_RELAX);
			at = c->g.next;
		}
		if (extra) /* it stopped at a memory-bound chunk: a region follows */
			rs = at;
		else if (rs > at) {
			/* the gap [at, rs): the warming run's chunks of U tiles; a
			 * memory-bound one brings an extra region at the next full
			 * checkpoint after it, as func_range does */
			double m = hier_merge_share(&c->mem);
			wm_region_end(r, f, at);
			for (int a = at; a < rs;) {
				int e = a + U < rs ? a + U : rs;
				int hard = account(F, warm_piece(c, f, a, e, m), 1);
				int xs = wm_full_above(r, e);
				if (e - a == U && extra_due(F, hard, e, xs, rs)) {
					if (xs > e)
						account(F, warm_piece(c, f, e, xs, m), 1);
					rs = xs;
					extra = 1;
					break;
				}
				a = e;
			}
			F->functional_tiles += (uint64_t)(rs - at);
			F->replayed_tiles += (uint64_t)(rs - at);
			if (wm_restore(r, c, f, rs, m))
				c->warm_err = 1;
		} else
			rs = at;
		if (extra) {
			F->extra_left--;
			tail = 0;
		} else
			b++;
		int us = rs + W;
		if (tail && us > N - U)
			us = N - U > rs ? N - U : rs;
		F->unit_s[j] = us;
		sampled_region(c, j, tail);
		at = c->g.next;
		if (c->warm_err)
			break;
	}
	/* every tile's packets were replayed, here or in the warming run */
	memset(c->replayed, 1, (size_t)N);
	sampled_estimate(c, f, j, t0);
}

/* The estimate of a sampled frame of nr regions that started at t0 from
 * its units and pieces (sampling.c): the head and tail measured, the
 * middle estimated, plus sampling.bias_bound. */
static void sampled_estimate(chip *c, int f, int nr, uint64_t t0)
{
	chip_fidelity *F = &c->fid;
	double per = (double)c->clk.period, *cyc = F->unit_cyc;
	F->nreg = nr;
	F->region_end = c->g.ntiles;
	uint64_t t1 = eng_now(c->e);
	double ch = (double)(F->mark_e[0] - t0) / per, ct = (double)(t1 - F->mark_r0[nr - 1]) / per;
	smp_est r;
	smp_estimate(F->unit_pc + 1, cyc + 1, nr - 1, F->pc, F->npc, c->cfg.sampling.sdram_factor,
	             c->cfg.sampling.demand_model, &r);
	F->model = r.model;
	for (int u = 0; u < nr; u++) {
		double x = smp_demand(&F->unit_pc[u], &r.model);
		F->unit_rate[u] = x > 0 ? cyc[u] / x : 0;
	}
	double est = r.est, var = r.var, df = r.df;
	F->est[f] = ch + est + ct;
	/* plus a bound on the units' systematic error (sampling.bias_bound),
	 * which no spread between units shows */
	F->half[f] = isfinite(var)
	                 ? smp_t975((int)df) * sqrt(var) + c->cfg.sampling.bias_bound * est
	                 : INFINITY;
}

static const char *const res_names[RES_N] = {"rgs",   "trav",    "list",   "isect", "l1_shade",
                                             "l1_kd", "l1_list", "l1_tri", "sdram", "hostbus"};

const char *chip_res_name(int res)
{
	return res >= 0 && res < RES_N ? res_names[res] : "?";
}

const char *chip_rec_name(int state)
{
	static const char *const n[] = {"off", "replayed", "stored", "not stored"};
	return state >= 0 && state <= REC_UNSTORED ? n[state] : "?";
}

/* The packet record's key: kernel-ref's frame key for this view and size
 * (the memory image by its CRC, camera, lights, shading depth) and what
 * else changes a packet's work on the chip: the datapath formats and the
 * stack depth (spills). Thread counts, units and memory do not. */
static char *rec_key(const chip *c)
{
	const saar_config *g = &c->cfg;
	render_opts ro;
	render_opts_default(&ro);
	ro.width = g->frame.width;
	ro.height = g->frame.height;
	ro.max_depth = g->shading.max_depth;
	char *fk = wc_frame_key(c->w->cache_prog, c->w->image_crc, c->w->m.size, &c->w->v, &ro),
	     *key;
	if (!fk)
		return NULL;
	int n =
	    asprintf(&key,
	             "saarsim packet record 1\n%sfp %d %d %d %d %d %d round %d\nstack %d\n"
	             "counters %d shade %zu\n",
	             fk, g->chip.fp.trav.exp, g->chip.fp.trav.mant, g->chip.fp.isect.exp,
	             g->chip.fp.isect.mant, g->chip.fp.shade.exp, g->chip.fp.shade.mant,
	             g->chip.fp.round, g->chip.stack_depth, (int)C_NCOUNTERS, sizeof(shade_counts));
	free(fk);
	return n < 0 ? NULL : key;
}

/* Functional and sampled runs with a world cache: replay the stored
 * record of this frame, else record the first frame (rec_store). */
static void rec_open(chip *c)
{
	const world *w = c->w;
	chip_fidelity *F = &c->fid;
	if (!w->cache_dir || F->mode == CFG_FIDELITY_CYCLE ||
	    (F->mode == CFG_FIDELITY_SAMPLED && F->exact))
		return;
	double t0 = now_ms();
	c->rec_key = rec_key(c);
	if (!c->rec_key ||
	    wc_file(c->rec_file, sizeof c->rec_file, w->cache_dir, "packets", c->rec_key)) {
		free(c->rec_key);
		c->rec_key = NULL;
		return;
	}
	const void *tail;
	size_t n;
	int W = c->cfg.frame.width, H = c->cfg.frame.height;
	/* replayed where it lies in the file: no copy */
	if (wc_get_mapped(c->rec_file, c->rec_key, NULL, 0, &tail, &n, &c->rec_map) == 1 &&
	    !pr_load(&c->rec, tail, n, 0, W, H, c->g.ntiles)) {
		c->md.in = &c->rec;
		c->rec_state = REC_REPLAYED;
	} else {
		wc_unmap(&c->rec_map);
		if (!pr_init(&c->rec, W, H, c->g.ntiles)) {
			mode_record(&c->md, &c->rec);
			c->rec_state = REC_UNSTORED;
		}
	}
	c->rec_ms += now_ms() - t0;
}

/* After the recorded frame: stores the record (a failure is a warning),
 * and the frames after it replay it. */
static void rec_store(chip *c)
{
	if (!c->md.rec.out)
		return;
	double t0 = now_ms();
	mode_record(&c->md, NULL);
	void *b;
	size_t n;
	int rc = pr_serialize(&c->rec, &c->fb, &b, &n);
	pr_free(&c->rec);
	if (rc)
		return;
	diag d;
	if (wc_put(c->rec_file, c->rec_key, NULL, NULL, 0, b, n, &d))
		fprintf(stderr, "warning: %s\n", d.msg);
	else
		c->rec_state = REC_STORED;
	if (!pr_load(&c->rec, b, n, 1, c->cfg.frame.width, c->cfg.frame.height, c->g.ntiles))
		c->md.in = &c->rec;
	c->rec_ms += now_ms() - t0;
}

/* Replayed tiles take the recorded frame's pixels (a replayed packet
 * draws nothing). */
static void rec_pixels(chip *c)
{
	for (int i = 0; i < c->g.ntiles; i++)
		if (c->replayed[i]) {
			c->replayed[i] = 0;
			pr_put_tile(&c->rec, &c->fb, i % c->g.tiles_x, i / c->g.tiles_x, TILE_W,
			            TILE_H);
		}
}

const char *chip_warm_name(int state)
{
	static const char *const n[] = {"off", "loaded", "built", "not stored", "unavailable"};
	return state >= 0 && state <= WARM_UNAVAILABLE ? n[state] : "?";
}

int chip_warm_stored(const chip *c)
{
	return c->warm_state == WARM_LOADED || c->warm_state == WARM_BUILT ||
	       c->warm_state == WARM_UNSTORED;
}

/* Stored warming's grids: the light one (warm_light_grid), and one full
 * checkpoint in every 1/WM_FULL_PER_FRAME of the frame, rounded to the
 * light grid. */
static void warm_grid(const chip *c, int *gl, int *gf)
{
	*gl = warm_light_grid(&c->cfg);
	*gf = c->g.ntiles / WM_FULL_PER_FRAME / *gl * *gl;
	if (*gf < *gl)
		*gf = *gl;
}

/* The warming run's key: the packet record's (the frame) and every config
 * key functional processing reads. Left out (at their defaults): the name
 * (a label; a config file without one is named after the file), fidelity,
 * sampling and the keys only timing reads (cfg_key.timing_only), so a
 * sweep over those reuses one warming run. */
static char *warm_key(const chip *c, int gl, int gf)
{
	saar_config k = c->cfg, d;
	cfg_defaults(&d);
	memcpy(k.name, d.name, sizeof k.name);
	k.fidelity = d.fidelity;
	k.sampling = d.sampling;
	size_t nk;
	const cfg_key *keys = cfg_keys(&nk);
	for (size_t i = 0; i < nk; i++)
		if (keys[i].timing_only)
			memcpy((char *)&k + keys[i].off, (const char *)&d + keys[i].off,
			       keys[i].size);
	char *js = NULL, *key = NULL;
	size_t n = 0;
	FILE *f = open_memstream(&js, &n);
	if (!f)
		return NULL;
	jsonw w;
	jsonw_init_file(&w, f);
	cfg_write_json(&k, &w);
	if (fclose(f) || asprintf(&key, "saarsim warming 1\n%sgrid %d %d\nconfig %s\n", c->rec_key,
	                          gl, gf, js) < 0)
		key = NULL;
	free(js);
	return key;
}

/* The warming run of chip h (functional, replaying the packet record):
 * chip_run with checkpoints on the grids (sim/warming.h). take_tile takes
 * them (warm_mark) and chip_run the last of each frame, so the run steps
 * as functional mode does: stopping it at each checkpoint left slots idle
 * until the next and missed fewer L1 lines. */
static int warm_build(chip *h, int gl, int gf, void **out, size_t *n)
{
	wm_writer w;
	if (wm_writer_init(&w, h, gl, gf))
		return -1;
	h->wcap = &w;
	diag d;
	int rc =
	    chip_run(h, &d) || h->rec_state != REC_REPLAYED ? -1 : wm_writer_finish(&w, h, out, n);
	h->wcap = NULL;
	wm_writer_free(&w);
	return rc;
}

/* A functional chip like c for the record and warming runs. */
static chip *helper_chip(const chip *c, int frames)
{
	saar_config k = c->cfg;
	k.fidelity = CFG_FIDELITY_FUNCTIONAL;
	k.frame.frames = frames;
	diag d;
	return chip_create(&k, c->w, &d);
}

/* Stored warming: the checkpoints of this frame and config from the world
 * cache, else a warming run now (stored for the next run). Needs the
 * packet record; without one this run records it first, with a
 * functional chip of one frame. When impossible, full warming runs. */
static void warm_open(chip *c)
{
	if (c->cfg.sampling.warming != CFG_WARMING_STORED || !chip_estimates(&c->cfg))
		return;
	double t0 = now_ms();
	c->warm_state = WARM_UNAVAILABLE;
	if (c->rec_state == REC_UNSTORED) {
		/* make the record now: a warming run replays it */
		chip *h = helper_chip(c, 1);
		diag d;
		int ok = h && !chip_run(h, &d) && h->rec_state == REC_STORED;
		chip_destroy(h);
		mode_record(&c->md, NULL);
		pr_free(&c->rec);
		free(c->rec_key);
		c->rec_key = NULL;
		c->rec_state = REC_OFF;
		c->rec_ms += now_ms() - t0;
		rec_open(c);
		if (ok && c->rec_state == REC_REPLAYED)
			c->rec_state = REC_STORED;
		t0 = now_ms();
	}
	int gl, gf;
	warm_grid(c, &gl, &gf);
	char *key = c->md.in ? warm_key(c, gl, gf) : NULL;
	if (!key || wc_file(c->warm_file, sizeof c->warm_file, c->w->cache_dir, "warming", key)) {
		free(key);
		fprintf(stderr, "warning: sampling.warming stored needs --world-cache and a packet "
		                "record; the functional stretches run instead\n");
		return;
	}
	const void *tail;
	size_t n;
	if (wc_get_mapped(c->warm_file, key, NULL, 0, &tail, &n, &c->warm_map) == 1 &&
	    !wm_open(&c->warm, tail, n, c)) {
		c->warm_state = WARM_LOADED;
	} else {
		wc_unmap(&c->warm_map);
		chip *h = helper_chip(c, c->cfg.frame.frames);
		void *b = NULL;
		if (h && !warm_build(h, gl, gf, &b, &n)) {
			diag d;
			c->warm_state = WARM_UNSTORED;
			if (wc_put(c->warm_file, key, NULL, NULL, 0, b, n, &d))
				fprintf(stderr, "warning: %s\n", d.msg);
			else
				c->warm_state = WARM_BUILT;
			if (wm_open(&c->warm, b, n, c)) {
				free(b);
				b = NULL;
				c->warm_state = WARM_UNAVAILABLE;
			} else
				c->warm_own = b;
		} else {
			free(b);
			b = NULL;
		}
		if (!b) /* out of memory, or a cache line index past what is stored */
			fprintf(stderr, "warning: sampling.warming stored: the warming run failed; "
			                "the functional stretches run instead\n");
		chip_destroy(h);
	}
	free(key);
	c->warm_ms += now_ms() - t0;
}

/* The busiest-resource bound of frame f: the core cycles each resource
 * needs at least for the frame's work (units: the busiest RTP's issue
 * cycles per instance, since an RTP's units serve its own threads only;
 * L1s: requests / ports; SDRAM and host bus: data-bus time); the frame
 * cannot be faster than the largest. Needs the frame's snapshot.
 * (chip_demand, the sampled estimator's demand, takes the RTPs' mean
 * instead: it is summed chunk by chunk, which a maximum is not.) */
static void resource_bound(chip *c)
{
	chip_fidelity *F = &c->fid;
	double d[RES_N];
	chip_demand(c, d);
	for (int r = 0; r < RES_N; r++) {
		F->res_cycles[r] = d[r] - F->prev_dem[r];
		F->prev_dem[r] = d[r];
	}
	for (int k = 0; k < UNIT_NKINDS; k++) {
		double most = 0;
		for (int r = 0; r < c->nrtp; r++) {
			double w = rtp_work(c, r, k), *prev = &F->prev_rtp[r * UNIT_NKINDS + k];
			if (w - *prev > most)
				most = w - *prev;
			*prev = w;
		}
		F->res_cycles[RES_RGS + k] = most;
	}
	F->bound_by = 0;
	for (int r = 1; r < RES_N; r++)
		if (F->res_cycles[r] > F->res_cycles[F->bound_by])
			F->bound_by = r;
}

int chip_run(chip *c, diag *d)
{
	double t0 = now_ms();
	chip_fidelity *F = &c->fid;
	rec_open(c);
	warm_open(c);
	int stored = chip_warm_stored(c);
	for (int f = 0; f < c->cfg.frame.frames; f++) {
		if (f > 0) /* fb_init cleared it */
			fb_clear(&c->fb);
		rgc_reset(&c->g);
		c->tiles_given = 0;
		if (F->mode == CFG_FIDELITY_FUNCTIONAL)
			func_range(c, c->g.ntiles, FR_DRAIN);
		else if (stored)
			sampled_frame_stored(c, f);
		else if (chip_estimates(&c->cfg))
			sampled_frame(c, f);
		else /* cycle, and sampled at rate 1: the same event sequence */
			F->est[f] = (double)eng_ticks_to_cycles(c->clk, run_region(c, c->g.ntiles));
		if (c->warm_err)
			return diag_set(
			    d, c->warm_file, 0, 0,
			    "stored warming: a checkpoint is damaged (delete the file)");
		for (int r = 0; r < c->nrtp; r++) {
			for (int i = 0; i < c->tpr; i++)
				thr_flush(&c->rtp[r].t[i]);
			if (c->rtp[r].nidle != c->tpr || c->rtp[r].qn)
				return diag_set(d, "chip", 0, 0,
				                "internal error: frame ended with busy threads");
		}
		if (c->census)
			census_mark(c, c->g.ntiles);
		if (c->wcap) { /* a warming run: the frame's last light checkpoint */
			double dem[RES_N];
			chip_demand(c, dem);
			wm_put_light(c->wcap, c, f, c->g.ntiles, dem);
		}
		if (c->md.in)
			rec_pixels(c);
		rec_store(c);
		if (c->oom || c->env.oom || mem_failed(&c->mem))
			return diag_set(d, "chip", 0, 0, "out of memory during the frame");
		if (c->env.damaged)
			return diag_set(
			    d, "chip", 0, 0,
			    "a packet took more than %llu kd-tree steps (twice the "
			    "tree's nodes): the node data the traversal unit read loops "
			    "(damaged board memory or a wrong node address)",
			    (unsigned long long)c->env.max_steps);
		c->frame_port[f] = c->mem.n;
		if (c->frame_mem)
			hier_get_stats(&c->mem, &c->frame_mem[f]);
		resource_bound(c);
		F->floor[f] = F->res_cycles[F->bound_by];
		if (F->mode == CFG_FIDELITY_FUNCTIONAL) {
			/* no timing: the frame's cycles are the bound */
			F->est[f] = F->floor[f];
			c->frame_cycles[f] = (uint64_t)ceil(F->est[f]);
		} else {
			/* an estimate below the bound is impossible */
			if (F->est[f] < F->floor[f])
				F->est[f] = F->floor[f];
			c->frame_cycles[f] = (uint64_t)llround(F->est[f]);
		}
		c->frames_done = f + 1;
	}
	c->events = eng_events(c->e);
	sync_counters(c);
	c->sim_ms = now_ms() - t0;
	return 0;
}

uint64_t chip_cycles(const chip *c)
{
	uint64_t s = 0;
	for (int f = 0; f < c->frames_done; f++)
		s += c->frame_cycles[f];
	return s;
}

uint64_t chip_rtp_sum(const chip *c, const char *suffix)
{
	char name[64];
	uint64_t s = 0;
	for (int r = 0; r < c->nrtp; r++) {
		snprintf(name, sizeof name, "rtp%d.%s", r, suffix);
		s += stats_get(&c->st, name);
	}
	return s;
}

int chip_check_frame(chip *c, chip_check *out, diag *d)
{
	memset(out, 0, sizeof *out);
	double t0 = now_ms();
	render_opts ro;
	render_opts_default(&ro);
	ro.width = c->cfg.frame.width;
	ro.height = c->cfg.frame.height;
	ro.max_depth = c->cfg.shading.max_depth;
	ro.threads = 1;
	size_t n = (size_t)ro.width * (size_t)ro.height * 3;
	uint8_t *a = malloc(n), *b = malloc(n);
	int rc = a && b ? world_reference_rgb8(c->w, &ro, b, &out->ref, &out->cached, d)
	                : diag_set(d, "chip", 0, 0, "out of memory for the reference frame");
	if (!rc) {
		fb_to_rgb8(&c->fb, a, NULL);
		out->cmp = img_compare(a, b, ro.width, ro.height);
		out->ref_ms = out->ref.render_ms;
		/* the second reference: the same frame traced ray by ray (its
		 * own cache entry: the frame key holds single_ray) */
		render_stats sst;
		ro.single_ray = 1;
		/* ray by ray is many times slower than the packets (5 s on
		 * Conference 1024x768 on one thread); its time is reported
		 * nowhere, so it uses every core (the image does not depend
		 * on the thread count) */
		long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
		ro.threads = ncpu > 1 ? (int)(ncpu < 64 ? ncpu : 64) : 1;
		rc = world_reference_rgb8(c->w, &ro, b, &sst, &out->single_cached, d);
	}
	if (!rc) {
		out->single = img_compare(a, b, ro.width, ro.height);
		out->check_ms = now_ms() - t0;
		out->done = 1;
	}
	free(a);
	free(b);
	return rc;
}
