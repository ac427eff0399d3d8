/*
 * chip.c: wiring and the timed dispatcher of the chip model (see chip.h
 * and docs/design.md, "Chip model"). The frame loop and the functional
 * and sampled drivers are in sim/modes/ (frame.c, sampled.c, stored.c),
 * and so are the sinks the units emit into (docs/design-modes.md).
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
#include "mem/cache.h"
#include "mem/hier.h"
#include "sim/memconfig.h"
#include "sim/modes/functional.h"
#include "sim/modes/replay.h"
#include "sim/modes/slot.h"
#include "units/gridtrav.h"
#include "units/intersection.h"
#include "units/list.h"
#include "units/rgs.h"
#include "units/toplevel.h"
#include "units/traversal.h"

/* ---- the unit kinds (units/unit_table.h) and the pipeline ----
 *
 * Every per-kind list here derives from unit_table: names, config,
 * counters, resources. The pipeline's order (seed 002 §4.1) is this
 * route, set in every thread's environment when the chip is wired: a
 * packet (after ray generation, or a queued secondary one) enters
 * traversal; a leaf goes to the list unit, its entries to intersection,
 * which resumes traversal; a finished traversal goes to the RGS for
 * shading. */
static const unit_route pipeline = {
    .enter = tu_begin,
    .leaf = list_leaf,
    .triangles = isu_next,
    .traverse = tu_step,
    .finish = rgs_finish,
};

/* A two-level scene (issue 33; units/toplevel.h): a packet walks the top
 * level first; at an instance the transformation unit hands it to the
 * object's traversal, whose end goes back to the top level; the walk's
 * end goes to the RGS. */
static const unit_route pipeline_two_level = {
    .enter = tlu_enter,
    .leaf = list_leaf,
    .triangles = isu_next,
    .traverse = tu_step,
    .finish = tlu_finish,
    .object = tu_begin_object,
    .shade = rgs_finish,
};

/* A uniform grid (issue 34; units/gridtrav.h): a packet's walk through the
 * grid unit does its cells, lists and triangles itself (with the list and
 * intersection unit kinds' ops); its end goes to the RGS. */
static const unit_route pipeline_grid = {
    .enter = gtu_begin,
    .traverse = gtu_begin,
    .finish = rgs_finish,
};

static const char *const state_names[THR_NSTATES] = {"idle", "running", "waiting_memory",
                                                     "waiting_unit"};

const cfg_unit *chip_unit_cfg(const saar_config *cfg, int kind)
{
	return &cfg->chip.unit[kind];
}

const char *chip_unit_name(int kind)
{
	return unit_name(kind);
}

/* The parameters of unit kind k's instances from the config: the builder's
 * part, so that units/ reads no config schema. */
static unit_params unit_params_of(const saar_config *cfg, int k)
{
	const cfg_unit *u = &cfg->chip.unit[k];
	return (unit_params){u->count, u->width, u->latency, cfg->chip.masked_packets,
	                     cfg->chip.thread_sched == CFG_SCHED_OLDEST_FIRST
	                         ? UNIT_SCHED_OLDEST_FIRST
	                         : UNIT_SCHED_ROUND_ROBIN};
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
    {C_CONE_PACKETS, "cone.packets", "packets", "enclosing cones built (chip.cone_cull)"},
    {C_CONE_TESTS, "cone.tests", "ops", "triangle-cone tests (chip.cone_cull)"},
    {C_CONE_CULLED, "cone.culled", "ops", "packet-triangle tests the cone saved"},
    {C_CONE_SAVED, "cone.saved_ray_tests", "tests", "ray-triangle tests the cone saved"},
    {C_TL_STEPS, "toplevel.node_steps", "ops", "two-level scenes: top-level (BVH) node steps"},
    {C_TL_INST_TESTS, "toplevel.instance_tests", "ops", "instance box tests"},
    {C_TL_INST_ENTERED, "xform.instances", "ops",
     "instances entered: packets moved into object space by the transformation unit"},
    {C_TL_MAP_READS, "toplevel.map_reads", "reads", "object-space hits named through the map"},
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
void chip_demand(const chip *c, double d[RES_N])
{
	memset(d, 0, RES_N * sizeof *d);
	for (int k = 0; k < UNIT_NKINDS; k++)
		d[RES_UNIT + k] = chip_work(c, k) / c->nrtp;
	hier_stats h;
	if (hier_get_stats(&c->mem, &h))
		return;
	for (int t = 0; t < MEM_NTYPES; t++)
		d[RES_L1 + t] = (double)(h.reads[t] - h.bypass_reads[t]) /
		                (uint32_t)memcfg_l1_ports(&c->cfg, t);
	double per = (double)c->clk.period;
	d[RES_SDRAM] =
	    ((double)(h.sdram.busy_ticks + h.func_sdram_busy_ticks) - h.func_sdram_merge_ticks) /
	    per;
	d[RES_HOSTBUS] = (double)(h.hostbus.busy_ticks + h.func_hostbus_busy_ticks) / per;
}

/* A census mark at hand-out index tile of the current frame (the room
 * for every mark is made by chip_census_on). */
void chip_census_mark(chip *c, int tile)
{
	if (c->ncensus >= c->census_cap)
		return;
	chip_mark *m = &c->census[c->ncensus++];
	m->frame = c->frames_done;
	m->tile = tile;
	m->ticks = eng_now(c->e);
	chip_demand(c, m->dem);
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
int chip_take_tile(chip *c, thr_ctx *t)
{
	int tx, ty;
	if (!rgc_next(&c->g, &tx, &ty))
		return 0;
	if (c->census && c->tiles_given % c->fid.unit_tiles == 0)
		chip_census_mark(c, c->tiles_given);
	if (c->on_tile)
		c->on_tile(c, c->tiles_given);
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
		mode_slot(t)->rec = -1;
	if (rgs_primary(t, tx, ty)) {
		c->oom = 1;
		return 0;
	}
	return 1;
}

void chip_resume_at(chip *c, int tile, uint64_t next_age)
{
	c->g.next = tile;
	c->tiles_given = tile;
	c->env.next_age = next_age;
}

/* Free thread t takes a queued secondary packet: the packet, or its
 * stream in the packet record. */
void chip_start_queued(thr_ctx *t, thr_qitem it)
{
	if (!it.p) {
		mode_replay_begin(((chip *)t->env->owner)->md.in, t, it.rec);
		return;
	}
	mode_slot(t)->rec = it.rec;
	rgs_secondary(t, it.p);
}

static void on_free(thr_ctx *t)
{
	chip *c = t->env->owner;
	if (c->md.func_on) /* the functional driver (mode_func_range) hands out the work itself */
		return;
	thr_qitem it;
	if (rgs_dequeue(t->rtp, &it)) {
		chip_start_queued(t, it);
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
	chip_take_tile(c, t);
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

int chip_trace_mem(chip *c, const char *path, const char *name, diag *d)
{
	c->trace = malloc(sizeof *c->trace);
	if (!c->trace)
		return diag_set(d, "chip", 0, 0, "out of memory for the trace writer");
	if (mtr_open_write_as(c->trace, path, name ? name : path, d)) {
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
	F->even_floor = calloc(nf, sizeof *F->even_floor);
	F->prev_rtp = calloc((size_t)c->nrtp * UNIT_NKINDS, sizeof *F->prev_rtp);
	if (!F->est || !F->half || !F->floor || !F->even_floor || !F->prev_rtp)
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
	*t = (thr_ctx){
	    .rtp = rp, .env = rp->env, .id = id, .gid = gid, .state = THR_IDLE, .nkids = nkids};
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

/* The chip's frame, engine, per-frame figures and the memory's bytes (the
 * image, then every slot's spill area); -1 when out of memory. */
/* The stack spill area's bytes: room for PKT_STACK_MAX entries of every
 * thread slot, after spill_base (thr_spill_addr). */
static uint64_t spill_area(const chip *c)
{
	return (uint64_t)c->nrtp * (uint64_t)c->tpr * PKT_STACK_MAX * THR_SPILL_STRIDE;
}

static int chip_base(chip *c, const saar_config *cfg, const world *w)
{
	c->cfg = *cfg;
	c->w = w;
	/* sampling.warming auto (the default): stored warming whenever the
	 * world cache can hold the frame's checkpoints (a folder in use), which
	 * leaves a sampled run only its regions to simulate (docs/fidelity.md
	 * "Stored warming"); full warming otherwise. Every other mode and
	 * warming ignores the key: they keep full, as before auto. */
	if (cfg->sampling.warming == CFG_WARMING_AUTO) {
		c->warm_auto = 1;
		c->cfg.sampling.warming = CFG_WARMING_STORED;
		if (!w->cache_dir || !chip_estimates(&c->cfg)) /* (every tile detailed: none) */
			c->cfg.sampling.warming = CFG_WARMING_FULL;
	}
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
	const uint8_t *image = w->m.bytes;
	uint64_t image_size = w->m.size;
	if (w->tl) { /* the objects, the map and the top level after the frame's image */
		diag td;
		if (tli_build(&c->tli, w->tl, &w->m, &td))
			return -1;
		image = c->tli.bytes;
		image_size = c->tli.size;
	} else if (w->grid) { /* the grid's cells, lists and flags after it */
		diag gd;
		if (gimg_build(&c->gimg, w->grid, &w->m, &gd))
			return -1;
		image = c->gimg.bytes;
		image_size = c->gimg.size;
	}
	c->image_bytes = image_size;
	c->spill_base = (image_size + 4095) & ~(uint64_t)4095;
	c->regs = w->m;
	c->regs.bytes = NULL;
	uint64_t space = c->spill_base + spill_area(c);
	if (!c->e || !c->frame_cycles || !c->frame_port ||
	    (cfg->memory.model == CFG_MEM_HIERARCHY && !c->frame_mem) ||
	    ms_init(&c->store, image, image_size, space))
		return -1;
	return 0;
}

/* A two-level scene's per-frame update (issue 33): the host rebuilt the
 * top level (kernel-ref tl_frame) and writes it, the BVH's nodes and the
 * instance records with their transforms, to the board in one DMA
 * transfer over the host bus (memory.hostbus; seed 002 §4.2: the board
 * sits on PCI). Its bytes and its time on an idle bus are the frame's
 * update; the objects' trees were written once, before the first frame.
 * The frame's simulated cycles start after it (not included). */
static int chip_update(chip *c, diag *d)
{
	if (!c->w->tl)
		return 0;
	hbus_params hp;
	hbus h;
	hier_hbus_params(&c->cfg, &hp);
	if (hbus_init(&h, &hp, d))
		return -1;
	c->update_bytes = c->tli.top_bytes;
	c->update_ms = (double)hbus_duration(&h, (uint32_t)c->update_bytes) * 1e-9;
	size_t nf = (size_t)c->cfg.frame.frames;
	c->frame_update = calloc(nf, sizeof *c->frame_update);
	c->frame_update_top = calloc(nf, sizeof *c->frame_update_top);
	c->frame_stale = calloc(nf, sizeof *c->frame_stale);
	c->frame_update_ms = calloc(nf, sizeof *c->frame_update_ms);
	if (!c->frame_update || !c->frame_update_top || !c->frame_stale || !c->frame_update_ms)
		return diag_set(d, "chip", 0, 0, "out of memory");
	c->frame_update[0] = c->frame_update_top[0] = c->update_bytes;
	c->frame_update_ms[0] = c->update_ms;
	return 0;
}

#define ANIM_LINE 128u /* the update's unit: the VMA's line (MIMG_ALIGN) */

/* Line [a, a + n) changed: dropped from every cache (hierarchy). */
static uint64_t anim_stale(chip *c, uint64_t a, uint64_t n)
{
	if (!hier_is(&c->mem) || c->anim_keep_stale)
		return 0;
	cache *l1[MEM_NTYPES], *tag, *l2;
	hier_caches(&c->mem, l1, &tag, &l2);
	uint64_t k = 0;
	for (int t = 0; t < MEM_NTYPES; t++)
		k += cache_invalidate(l1[t], a, n);
	if (l2)
		k += cache_invalidate(l2, a, n);
	return k;
}

int chip_anim_update(chip *c, int f, diag *d)
{
	const world *w = c->w;
	tl_image n;
	if (!w->tl || tli_build(&n, w->tl, &w->m, d))
		return w->tl ? -1 : diag_set(d, "chip", 0, 0, "a warm animation needs --two-level");
	tl_image *o = &c->tli;
	int same = n.size == o->size && n.top_base == o->top_base && n.map_base == o->map_base;
	for (uint32_t k = 0; same && k < w->tl->nobj; k++)
		same = n.obj_base[k] == o->obj_base[k];
	if (!same) {
		tli_free(&n);
		return diag_set(
		    d, "chip", 0, 0,
		    "the two-level image's layout changed between frames: no warm update");
	}
	uint64_t bytes = 0, top = 0, stale = 0;
	for (uint64_t a = 0; a < n.size; a += ANIM_LINE) {
		uint64_t len = n.size - a < ANIM_LINE ? n.size - a : ANIM_LINE;
		if (!memcmp(o->bytes + a, n.bytes + a, len))
			continue;
		/* the store reads the image in place: the line is written */
		memcpy(o->bytes + a, n.bytes + a, len);
		bytes += len;
		top += a >= o->top_base ? len : 0;
		stale += anim_stale(c, a, len);
	}
	tli_free(&n);
	hbus_params hp;
	hbus h;
	hier_hbus_params(&c->cfg, &hp);
	if (hbus_init(&h, &hp, d))
		return -1;
	c->frame_update[f] = bytes;
	c->frame_update_top[f] = top;
	c->frame_stale[f] = stale;
	c->frame_update_ms[f] = (double)hbus_duration(&h, (uint32_t)bytes) * 1e-9;
	/* the frame's registers: region bases (unchanged), camera and lights */
	c->regs = w->m;
	c->regs.bytes = NULL;
	thr_env *v = &c->env;
	cam_setup_view(&v->cam, &w->v, c->cfg.frame.width, c->cfg.frame.height);
	v->sc.lights = w->v.lights;
	v->sc.nlights = w->v.nlights;
	v->nlights = w->v.nlights;
	return 0;
}

/* The memory model of memory.model behind the port. A model the config
 * cannot build (an image too big for the board without VMA, a bad cache
 * geometry) is the user's error: its message is kept. */
static int chip_memory(chip *c, diag *d)
{
	const saar_config *cfg = &c->cfg;
	int mrc;
	/* Without the VMA the chip's memory is on board: the image, and the
	 * stack spill area after it when a stack shallower than kernel-ref's
	 * can spill (every thread slot has room for PKT_STACK_MAX entries,
	 * thr_spill_addr). A spill past the board had been served as rows the
	 * board does not have, without a word. */
	uint64_t board = (uint64_t)cfg->memory.sdram.mb << 20, area = spill_area(c);
	/* and its addresses are the chip's: 32 bits (docs/memory-map.md) */
	if (cfg->chip.stack_depth < PKT_STACK_MAX && c->spill_base + area > ((uint64_t)1 << 32))
		return diag_set(
		    d, "config", 0, 0,
		    "the stack spill area (%d RTPs x %d threads x %d entries of %u bytes = "
		    "%.1f GB) ends past the chip's 32-bit addresses with chip.stack_depth "
		    "%d < %d: use fewer RTPs or threads, or raise chip.stack_depth",
		    c->nrtp, c->tpr, PKT_STACK_MAX, THR_SPILL_STRIDE, (double)area / (1 << 30),
		    (int)cfg->chip.stack_depth, PKT_STACK_MAX);
	if (cfg->memory.model == CFG_MEM_HIERARCHY && !cfg->memory.vma.enabled &&
	    cfg->chip.stack_depth < PKT_STACK_MAX && c->spill_base <= board &&
	    c->spill_base + area > board)
		return diag_set(
		    d, "config", 0, 0,
		    "the stack spill area (%d RTPs x %d threads x %d entries of %u bytes = "
		    "%.1f MB, after the %.1f MB image) does not fit in on-board memory "
		    "(memory.sdram.mb = %d) with chip.stack_depth %d < %d: raise "
		    "memory.sdram.mb or chip.stack_depth, use fewer threads, or enable the "
		    "virtual memory architecture (memory.vma.enabled: true)",
		    c->nrtp, c->tpr, PKT_STACK_MAX, THR_SPILL_STRIDE, (double)area / (1 << 20),
		    (double)c->spill_base / (1 << 20), (int)cfg->memory.sdram.mb,
		    (int)cfg->chip.stack_depth, PKT_STACK_MAX);
	if (cfg->memory.model == CFG_MEM_HIERARCHY)
		mrc = mem_init_hier(&c->mem, c->e, c->clk, cfg, c->spill_base, &c->store, d);
	else if ((mrc = mem_init_fixed(&c->mem, c->e, c->clk, cfg->memory.latency, &c->store)))
		diag_set(d, "chip", 0, 0, "out of memory");
	return mrc;
}

/* The units' shared environment: memory, registers, datapath formats,
 * shading, camera and the pipeline's route. -1 (diag) on an unsupported
 * floating-point format. */
static int chip_env(chip *c, diag *d)
{
	const saar_config *cfg = &c->cfg;
	const world *w = c->w;
	thr_env *v = &c->env;
	v->e = c->e;
	v->clk = c->clk;
	v->mem = &c->mem;
	v->m = &c->regs;
	v->stack_depth = cfg->chip.stack_depth;
	v->max_steps = 2 * (uint64_t)w->m.nnodes + 64;
	v->masked = cfg->chip.masked_packets;
	v->cone_cull = cfg->chip.cone_cull;
	/* the datapath formats; kernel-ref's check frame stays full precision */
	if (fpfmt_init(&v->prec.trav, cfg->chip.fp.trav.exp, cfg->chip.fp.trav.mant,
	               cfg->chip.fp.round) ||
	    fpfmt_init(&v->prec.isect, cfg->chip.fp.isect.exp, cfg->chip.fp.isect.mant,
	               cfg->chip.fp.round) ||
	    fpfmt_init(&v->prec.shade, cfg->chip.fp.shade.exp, cfg->chip.fp.shade.mant,
	               cfg->chip.fp.round))
		return diag_set(d, "config", 0, 0, "chip.fp: unsupported floating-point format");
	v->nlights = w->v.nlights;
	v->spill_base = c->spill_base;
	v->route = pipeline;
	if (w->tl) {
		v->route = pipeline_two_level;
		v->two_level = 1;
		v->tl_nodes = c->tli.top_base;
		v->tl_insts = c->tli.inst_base;
		uint64_t n = c->tli.max_nodes > w->tl->nnode ? c->tli.max_nodes : w->tl->nnode;
		v->max_steps = 2 * (n > w->m.nnodes ? n : w->m.nnodes) + 64;
	} else if (w->grid) {
		const grid *g = w->grid;
		v->route = pipeline_grid;
		c->gregs = *g;
		c->gregs.m = &c->regs;
		c->gregs.first = c->gregs.refs = NULL;
		c->gregs.macro = NULL;
		v->grid = &c->gregs;
		v->grid_cells = c->gimg.cells_base;
		v->grid_refs = c->gimg.refs_base;
		v->grid_macro = c->gimg.macro_base;
		v->grid_nrefs = g->nrefs;
		/* a packet asks at most, per frustum (16 of 4x4) and per ray
		 * alone (64), for every flag, cell, range and entry once */
		uint64_t cells = (uint64_t)g->n[0] * (uint64_t)g->n[1] * (uint64_t)g->n[2],
		         flags = (uint64_t)g->mn[0] * (uint64_t)g->mn[1] * (uint64_t)g->mn[2];
		v->max_steps = 80 * (2 * cells + (uint64_t)g->nrefs + flags) + 64;
	}
	v->on_free = on_free;
	v->owner = c;
	if (mode_sinks_init(&c->md, v, c->nrtp * c->tpr, c->replayed))
		return diag_set(d, "chip", 0, 0, "out of memory for %d RTPs x %d threads",
		                cfg->chip.rtps, cfg->chip.threads_per_rtp);
	render_opts ro;
	render_opts_default(&ro);
	v->sc = (shade_ctx){&c->regs,      w->v.lights, w->v.nlights, cfg->shading.max_depth,
	                    ro.background, &c->fb,      NULL,         NULL,
	                    NULL};
	if (w->tl) /* object-space records, moved back by the instance records */
		v->sc.tl = &c->tli.shade;
	cam_setup_view(&v->cam, &w->v, cfg->frame.width, cfg->frame.height);
	if (!drt_is_off(&w->v.drt)) { /* distribution effects (kernel-ref/drt.h) */
		drt_shade_setup(&v->drt, &w->v.drt, w->v.cam.up, (uint32_t)cfg->frame.width);
		v->sc.drt = &v->drt;
	}
	return 0;
}

/* The counters split by packet type (enum thr_type_counter):
 * type.<type>.trav.node_steps ... type.<type>.<unit>.busy_cycles/rays. */
static void chip_type_counters_reg(chip *c)
{
	static const struct {
		int id;
		const char *name, *unit, *desc;
	} tc[] = {
	    {TC_NODE_STEPS, "trav.node_steps", "ops", "traversal steps of packets of this type"},
	    {TC_LEAF_VISITS, "trav.leaf_visits", "ops", "leaves reached by packets of this type"},
	    {TC_LIST_ENTRIES, "list.entries", "entries", "list entries read for this type"},
	    {TC_TRI_TESTS, "isect.tri_tests", "ops", "packet-triangle tests of this type"},
	    {TC_RAY_TRI_TESTS, "isect.ray_tri_tests", "tests", "ray-triangle tests of this type"},
	};
	char name[96];
	for (int t = 0; t < PKT_NTYPES; t++) {
		uint64_t **ct = c->env.ct[t];
		for (size_t i = 0; i < sizeof tc / sizeof *tc; i++) {
			snprintf(name, sizeof name, "type.%s.%s", pkt_type_name(t), tc[i].name);
			ct[tc[i].id] = reg(c, name, tc[i].unit, tc[i].desc);
		}
		for (int k = 0; k < UNIT_NKINDS; k++) {
			snprintf(name, sizeof name, "type.%s.%s.busy_cycles", pkt_type_name(t),
			         unit_table[k].name);
			ct[TC_BUSY + k] = reg(c, name, "cycles", "issue cycles of this type's ops");
			snprintf(name, sizeof name, "type.%s.%s.rays", pkt_type_name(t),
			         unit_table[k].name);
			ct[TC_RAYS + k] = reg(c, name, "rays", "active rays of this type's ops");
		}
	}
}

/* The chip-wide counters: packets and rays by type, the units' counters
 * (enum thr_counter), shade_counts and the memory port's traffic. */
static void chip_counters_reg(chip *c)
{
	thr_env *v = &c->env;
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
	chip_type_counters_reg(c);
}

/* RTP r's units, one group per kind of unit_table, with their counters
 * rtp<r>.<name>.ops/busy_cycles/rays. -1 when out of memory. */
static int rtp_units(chip *c, thr_rtp *rp)
{
	char name[64];
	for (int k = 0; k < UNIT_NKINDS; k++) {
		thr_unit *u = &rp->u[k];
		unit_params p = unit_params_of(&c->cfg, k);
		if (thr_unit_init(u, c->e, c->clk, &p, c->tpr))
			return -1;
		u->on_start = thr_on_start;
		const char *un = unit_table[k].name;
		snprintf(name, sizeof name, "rtp%d.%s.ops", rp->id, un);
		u->ops_n = reg(c, name, "ops", "operations issued");
		snprintf(name, sizeof name, "rtp%d.%s.busy_cycles", rp->id, un);
		u->busy = reg(c, name, "cycles", "issue cycles (summed over the units)");
		snprintf(name, sizeof name, "rtp%d.%s.rays", rp->id, un);
		u->rays = reg(c, name, "rays", "active rays of those operations");
		if (c->oom)
			return -1;
	}
	return 0;
}

/* The RTPs: units, thread-state counters and thread contexts. -1 when out
 * of memory. */
static int chip_rtps(chip *c)
{
	char name[64];
	c->rtp = calloc((size_t)c->nrtp, sizeof *c->rtp);
	if (!c->rtp)
		return -1;
	int nkids = c->w->v.nlights + 2;
	for (int r = 0; r < c->nrtp; r++) {
		thr_rtp *rp = &c->rtp[r];
		rp->env = &c->env;
		rp->id = r;
		if (rtp_units(c, rp))
			return -1;
		for (int s = 0; s < THR_NSTATES; s++) {
			snprintf(name, sizeof name, "rtp%d.threads.%s_ps", r, state_names[s]);
			rp->occ[s] = reg(c, name, "ps", "thread time in this state, summed");
		}
		rp->t = alloc64((size_t)c->tpr * sizeof(thr_ctx));
		if (!rp->t)
			return -1;
		memset(rp->t, 0, (size_t)c->tpr * sizeof(thr_ctx));
		rp->nt = c->tpr;
		rp->nidle = c->tpr;
		for (int i = 0; i < c->tpr; i++)
			if (thread_init(&rp->t[i], rp, i, r * c->tpr + i, nkids))
				return -1;
	}
	return 0;
}

/* Functional processing's turn order (slot 0 of each RTP, then slot 1,
 * ...) and its live and parked sets. -1 when out of memory. */
static int chip_turns(chip *c)
{
	c->turn = malloc((size_t)c->nrtp * (size_t)c->tpr * sizeof *c->turn);
	if (!c->turn)
		return -1;
	for (int s = 0; s < c->tpr; s++)
		for (int r = 0; r < c->nrtp; r++)
			c->turn[s * c->nrtp + r] = &c->rtp[r].t[s];
	size_t nslots = (size_t)c->nrtp * (size_t)c->tpr;
	c->live = malloc((size_t)bits_words((int)nslots) * sizeof *c->live);
	c->park = malloc(nslots * sizeof *c->park);
	c->park_n = malloc((size_t)c->nrtp * sizeof *c->park_n);
	c->relax_n = malloc(nslots * sizeof *c->relax_n);
	return c->live && c->park && c->park_n && c->relax_n ? 0 : -1;
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
	if (!c || chip_base(c, cfg, w))
		goto oom;
	if (chip_memory(c, d) || chip_update(c, d)) {
		chip_destroy(c);
		return NULL;
	}
	int order = cfg->chip.tile_order == CFG_TILES_MORTON ? RGC_MORTON : RGC_SCANLINE;
	if (thr_env_init(&c->env) || fb_init(&c->fb, cfg->frame.width, cfg->frame.height) ||
	    rgc_init(&c->g, cfg->frame.width, cfg->frame.height, order) ||
	    !(c->replayed = calloc((size_t)c->g.ntiles, 1)))
		goto oom;
	if (chip_env(c, d)) {
		chip_destroy(c);
		return NULL;
	}
	chip_counters_reg(c);
	if (chip_rtps(c) || chip_turns(c) || c->oom || fid_init(c))
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
	tli_free(&c->tli);
	gimg_free(&c->gimg);
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
	if (c->on_destroy)
		c->on_destroy(c);
	wc_unmap(&c->warm_map);
	free(c->warm_own);
	mem_free(&c->mem);
	ms_free(&c->store);
	mode_sinks_free(&c->md);
	thr_env_free(&c->env);
	if (c->e)
		eng_destroy(c->e);
	free(c->frame_cycles);
	free(c->frame_update);
	free(c->frame_update_top);
	free(c->frame_stale);
	free(c->frame_update_ms);
	free(c->frame_port);
	free(c->frame_mem);
	free(c->fid.unit_s);
	free(c->fid.base_s);
	free(c->fid.mark_s);
	free(c->fid.mark_e);
	free(c->fid.est);
	free(c->fid.half);
	free(c->fid.floor);
	free(c->fid.even_floor);
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

double chip_now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* Copies counts kept outside the registry (memory port, shade_counts). */
void chip_sync_counters(chip *c)
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
uint64_t chip_run_region(chip *c, int end)
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

/* The resource behind regressor i of the linear demand model: every unit
 * kind, then SDRAM and host bus. */
_Static_assert(SMP_LIN == UNIT_NKINDS + 2, "sampling.h SMP_LIN: the unit kinds, SDRAM, host bus");
_Static_assert(SMP_COMP == RES_SDRAM - RES_UNIT, "sampling.h SMP_COMP: the unit kinds, the L1s");
static int lin_res(int i)
{
	return i < UNIT_NKINDS ? RES_UNIT + i : i == UNIT_NKINDS ? RES_SDRAM : RES_HOSTBUS;
}

const char *chip_lin_name(int i)
{
	return i >= 0 && i < SMP_LIN ? chip_res_name(lin_res(i)) : "?";
}

/* The demand of a stretch between two chip_demand snapshots, and whether
 * it is memory bound: its SDRAM or host-bus time above
 * sampling.hard_share of its busiest compute resource. */
smp_piece chip_piece(const chip *c, const double *a, const double *b)
{
	smp_piece p;
	memset(&p, 0, sizeof p);
	for (int r = 0; r < RES_N; r++) {
		double d = b[r] - a[r];
		if (r == RES_SDRAM)
			p.sdram = d;
		else if (r == RES_HOSTBUS)
			p.hbus = d;
		else {
			p.res[r - RES_UNIT] = d;
			if (d > p.comp)
				p.comp = d;
		}
	}
	for (int i = 0; i < SMP_LIN; i++)
		p.lin[i] = b[lin_res(i)] - a[lin_res(i)];
	double hs = c->cfg.sampling.hard_share, mem = p.sdram > p.hbus ? p.sdram : p.hbus;
	p.hard = hs > 0 && mem > hs * p.comp;
	return p;
}

/* The resources after the unit kinds' (whose names are the kinds'). */
static const char *const res_names[RES_N - RES_L1] = {"l1_shade", "l1_kd", "l1_list",
                                                      "l1_tri",   "sdram", "hostbus"};

const char *chip_res_name(int res)
{
	if (res >= RES_UNIT && res < RES_L1)
		return unit_name(res - RES_UNIT);
	return res >= RES_L1 && res < RES_N ? res_names[res - RES_L1] : "?";
}

const char *chip_rec_name(int state)
{
	static const char *const n[] = {"off", "replayed", "stored", "not stored"};
	return state >= 0 && state <= REC_UNSTORED ? n[state] : "?";
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
 * checkpoint in every 1/CFG_WARM_FULL_PER_FRAME of the frame, rounded to the
 * light grid. */
void chip_warm_grid(const chip *c, int *gl, int *gf)
{
	*gl = warm_light_grid(&c->cfg);
	*gf = c->g.ntiles / CFG_WARM_FULL_PER_FRAME / *gl * *gl;
	if (*gf < *gl)
		*gf = *gl;
}

/* The busiest-resource bound of frame f: the core cycles each resource
 * needs at least for the frame's work (units: the busiest RTP's issue
 * cycles per instance, since an RTP's units serve its own threads only;
 * L1s: requests / ports; SDRAM and host bus: data-bus time); the frame
 * cannot be faster than the largest. Needs the frame's snapshot.
 * (chip_demand, the sampled estimator's demand, takes the RTPs' mean
 * instead: it is summed chunk by chunk, which a maximum is not.) */
void chip_resource_bound(chip *c)
{
	chip_fidelity *F = &c->fid;
	double d[RES_N];
	chip_demand(c, d);
	F->even_bound = 0;
	for (int r = 0; r < RES_N; r++) {
		F->res_cycles[r] = d[r] - F->prev_dem[r];
		F->prev_dem[r] = d[r];
		if (F->res_cycles[r] > F->even_bound) /* units: spread evenly (chip_demand) */
			F->even_bound = F->res_cycles[r];
	}
	for (int k = 0; k < UNIT_NKINDS; k++) {
		double most = 0;
		for (int r = 0; r < c->nrtp; r++) {
			double w = rtp_work(c, r, k), *prev = &F->prev_rtp[r * UNIT_NKINDS + k];
			if (w - *prev > most)
				most = w - *prev;
			*prev = w;
		}
		F->res_cycles[RES_UNIT + k] = most;
	}
	F->bound_by = 0;
	for (int r = 1; r < RES_N; r++)
		if (F->res_cycles[r] > F->res_cycles[F->bound_by])
			F->bound_by = r;
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

uint64_t chip_replay_bad(const chip *c, char *msg, size_t n)
{
	const mode_rbad *b = &c->md.bad;
	if (!b->n)
		return 0;
	int tx = b->tile >= 0 ? b->tile % c->g.tiles_x : -1,
	    ty = b->tile >= 0 ? b->tile / c->g.tiles_x : -1;
	snprintf(msg, n,
	         "packet-record replay: %llu read%s returned other bytes than recorded; the "
	         "first: packet %d of tile %d (%d,%d) read %u bytes at 0x%llx (%s): checksum "
	         "%04x, recorded %04x",
	         (unsigned long long)b->n, b->n == 1 ? "" : "s", (int)b->pk, (int)b->tile, tx, ty,
	         (unsigned)b->bytes, (unsigned long long)b->addr, mem_type_name(b->type),
	         (unsigned)b->got, (unsigned)b->want);
	return b->n;
}

int chip_check_frame(chip *c, chip_check *out, diag *d)
{
	memset(out, 0, sizeof *out);
	double t0 = chip_now_ms();
	render_opts ro;
	render_opts_default(&ro);
	ro.width = c->cfg.frame.width;
	ro.height = c->cfg.frame.height;
	ro.max_depth = c->cfg.shading.max_depth;
	ro.threads = 1;
	ro.cone_cull = c->cfg.chip.cone_cull;
	if (c->w->tl) /* a two-level scene: kernel-ref traces the same trees */
		ro.tracer = &c->w->tl->tracer;
	if (c->w->grid) /* a grid: kernel-ref traces the same grid */
		ro.tracer = &c->w->grid->tracer;
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
		/* a replayed read that returned other bytes than recorded: the
		 * frame is not the one memory holds, whatever its pixels */
		out->replay_bad = chip_replay_bad(c, out->replay_msg, sizeof out->replay_msg);
		if (out->replay_bad)
			out->cmp.identical = out->single.identical = 0;
		out->check_ms = chip_now_ms() - t0;
		out->done = 1;
	}
	free(a);
	free(b);
	return rc;
}
