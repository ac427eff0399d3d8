/*
 * sampled.c: the functional and sampled drivers (see sampled.h; docs/fidelity.md).
 */
#include "sim/modes/sampled.h"

#include "kernel-ref/bitset.h"

#include <math.h>
#include <string.h>

#include "sim/modes/functional.h"
#include "sim/warming.h"
#include "units/rgs.h"

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
		chip_start_queued(t, it);
		return 1;
	}
	if (c->g.next >= end || !chip_take_tile(c, t))
		return 0;
	c->fid.functional_tiles++;
	++*given;
	return 1;
}

/* Sampled: does a memory-bound chunk (hard) that ended at tile `from`
 * bring an extra region starting at `start`, before the next planned one
 * at `next`? When one is left, the last region ended at least `gap` tiles
 * before `from`, and a warm-up and unit fit before `next`. Functional
 * stretches (mode_func_range) and stored warming's gaps alike. */
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

/* Thread slots ahead whose packet streams mode_func_range prefetches. */
#define PREFETCH_TURNS 4

/* Takes idle slot i (turn order) of RTP r off mode_func_range's passes. */
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

/* Tiles every slot takes in a relax. One leaves the slot that finished
 * last holding a packet just begun where the warming run's slots are part
 * way through theirs, and the frame's counts come out low; two do not
 * (docs/fidelity.md "Stored warming", tests/test_warming.c
 * sponza_one_thread_pci_as_cycle). */
#define RELAX_TILES 2

int mode_func_range(chip *c, int end, int mode)
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
	/* a warming run with done records: every count goes to its packet's
	 * tile (wm_attr) */
	wm_writer *wa = c->wcap && c->wcap->done ? c->wcap : NULL;
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
			int r = t->rtp->id; /* its index in c->rtp */
			if (!t->p && !mode_slot(t)->rp) {
				if (chunked && given == F->unit_tiles) {
					chip_demand(c, d1);
					int hard = account(F, chip_piece(c, d0, d1), 1);
					memcpy(d0, d1, sizeof d0);
					given = 0;
					if (mode != FR_DRAIN &&
					    extra_due(F, hard, c->g.next, c->g.next, end)) {
						end = c->g.next;
						extra = 1;
					}
				}
				if (mode == FR_RELAX && t->rtp->qn == 0 &&
				    ((relaxed == n && c->g.next % c->warm->g_light == 0) ||
				     c->g.next >= end)) {
					stop = 1;
					break;
				}
				int had = given;
				int ok = func_give(c, t, end, &given);
				if (wa && ok) {
					if (given != had)
						wm_attr_take(wa, c, mode_slot(t)->rec,
						             c->tiles_given - 1);
					wm_attr(wa, c, mode_slot(t)->rec);
				}
				if (!ok) {
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
			if (mode_slot(t)->rp) {
				/* the stream of the slot a few turns on is elsewhere
				 * in the record: start fetching it now (one turn
				 * ahead was too late to hide the host's memory
				 * latency); a step's bytes often run into the next
				 * host line: fetch that too */
				int k = i + PREFETCH_TURNS < n ? i + PREFETCH_TURNS
				                               : i + PREFETCH_TURNS - n;
				const uint8_t *rp = k < n ? mode_slot(c->turn[k])->rp : NULL;
				if (rp) {
					__builtin_prefetch(rp);
					__builtin_prefetch(rp + 32);
				}
			}
			int32_t rec = mode_slot(t)->rec;
			busy |= mode_func_step(t);
			if (wa)
				wm_attr(wa, c, rec);
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
		account(F, chip_piece(c, d0, d1), 1);
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
 * unit_tiles tiles (mode_func_range) and per region piece (warm-up, unit, what
 * finished after the unit), detailed or functional alike. The interval
 * adds sampling.bias_bound. A memory-bound functional chunk brings an
 * extra region (mode_func_range). docs/fidelity.md. */
static void sampled_estimate(chip *c, int f, int nr, uint64_t t0);
static void sampled_region(chip *c, int j, int tail);

void mode_sampled_frame(chip *c, int f)
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
		int extra = c->g.next < rs && mode_func_range(c, rs, FR_STOP);
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
	chip_run_region(c, tail ? c->g.ntiles : F->unit_s[j] + F->unit_tiles);
	F->last_end = c->g.next;
	chip_demand(c, r1);
	const double *ds = &F->dem_s[j * RES_N], *de = &F->dem_e[j * RES_N];
	F->unit_pc[j] = chip_piece(c, ds, de);
	F->unit_cyc[j] = (double)(F->mark_e[j] - F->mark_s[j]) / (double)c->clk.period;
	account(F, chip_piece(c, r0, ds), j > 0 && !tail);
	account(F, F->unit_pc[j], j > 0 && !tail);
	account(F, chip_piece(c, de, r1), !tail);
}

/* The warming run's demand at the light checkpoint at tile (done: of the
 * tiles before it, wm_demand_done), its SDRAM demand less the share m of
 * on-board-cache hits a timed chip merges. */
static void warm_dem(chip *c, int f, int tile, double m, int done, double *d)
{
	uint64_t h;
	memcpy(d, done ? wm_demand_done(c->warm, f, tile, &h) : wm_demand(c->warm, f, tile, &h),
	       RES_N * sizeof *d);
	d[RES_SDRAM] -= m * (double)h / (double)c->clk.period;
}

/* A piece of the warming run between two light checkpoints, its SDRAM
 * demand less the share m of on-board-cache hits a timed chip merges. */
static smp_piece warm_piece(chip *c, int f, int a, int b, double m)
{
	double d0[RES_N], d1[RES_N];
	warm_dem(c, f, a, m, 0, d0);
	warm_dem(c, f, b, m, 0, d1);
	return chip_piece(c, d0, d1);
}

/* Whether the stretch between a region that ended at tile `at` and the
 * next one at full checkpoint rs drains (sampling.jump): drain, when the
 * warming run had finished every packet of the tiles before `at` by rs
 * (else the restored slots would hold packets the drain finished, counted
 * twice); mixed, as drain but not next to memory-bound work: after a
 * region whose last U tiles, or before one whose U tiles before rs, the
 * warming run calls memory bound. There a relax usually runs into the
 * next region, which then starts from a chip that ran the frame, and
 * restored regions measured the frame worse (docs/fidelity.md "Stored
 * warming"). */
static int warm_done_by(chip *c, int f, int at, int x);

/* sampling.jump, auto as this frame resolved it (frame_jump) */
static int jump_of(const chip *c)
{
	int jump = c->cfg.sampling.jump;
	return jump == CFG_JUMP_AUTO ? c->fid.jump : jump;
}

static int jump_drains(chip *c, int f, int at, int rs)
{
	int jump = jump_of(c), U = c->fid.unit_tiles;
	if (jump == CFG_JUMP_RELAX || !warm_done_by(c, f, at, rs))
		return 0;
	if (jump == CFG_JUMP_DRAIN || jump == CFG_JUMP_SKIP)
		return 1;
	double m = hier_merge_share(&c->mem);
	return !(at - U >= 0 && warm_piece(c, f, at - U, at, m).hard) &&
	       !(rs - U >= at && warm_piece(c, f, rs - U, rs, m).hard);
}

/* Whether the warming run had finished every packet of the tiles before
 * `at` by the light checkpoint at x: a skip asks the oldest tile in flight
 * there (it keeps no done records), a drain its done records. */
static int warm_done_by(chip *c, int f, int at, int x)
{
	if (jump_of(c) == CFG_JUMP_SKIP)
		return wm_oldest(c->warm, f, x) >= at;
	return wm_done_by(c->warm, f, at, x);
}

int mode_warm_hard(chip *c, int f, int a, int b)
{
	return warm_piece(c, f, a, b, hier_merge_share(&c->mem)).hard;
}

int mode_jump_drains(chip *c, int f, int at, int rs)
{
	return jump_drains(c, f, at, rs);
}

/* After a drain that ended at tile `at`, before the next region at rs:
 * an extra region at the first full checkpoint x that ends a memory-bound
 * chunk of U tiles (the warming run's) where extra_due lets one start and
 * the warming run had finished the tiles before `at` (jump_drains): where
 * the relax would have met it. Returns the next region's start, *extra
 * set when it is an extra one. */
static int drained_extra(chip *c, int f, int at, int rs, double m, int *extra)
{
	int U = c->fid.unit_tiles;
	for (int x = wm_full_above(c->warm, at + 1); x < rs; x = wm_full_above(c->warm, x + 1))
		if (x - U >= at && warm_done_by(c, f, at, x) &&
		    extra_due(&c->fid, warm_piece(c, f, x - U, x, m).hard, x, x, rs)) {
			*extra = 1;
			return x;
		}
	return rs;
}

/* Where, in the warming run's demand, the gap after a drain starts (into
 * from): its demand at the light checkpoint rs_last where the chip last
 * took its state (the chip's demand then dem_rs), plus what the chip did
 * since, up to the drain (its demand d0 then, less dem_rs). From one
 * restore to the next the estimate so counts the warming run's demand of
 * the work in all, the timed regions in it their own, and the drain none
 * of its own: a drain runs a region's last packets with no new tile handed
 * out, in L1s they share with fewer packets than in a chip that runs on,
 * and reads less SDRAM for the same work (Conference 1024x768 at 32
 * threads per RTP: 12% less than the warming run in the memory-bound
 * regions; counted, it made the estimates fast: docs/fidelity.md "A
 * drain's demand"). The estimate then needs no done record (the warming
 * run's work of the tiles before the drain's end, which the drained
 * work's share would be taken from); the counters still do (wm_restore
 * after wm_region_end). */
static void drain_from(chip *c, int f, int rs_last, const double *dem_rs, const double *d0,
                       double *from)
{
	warm_dem(c, f, rs_last, hier_merge_share(&c->mem), 0, from);
	for (int k = 0; k < RES_N; k++)
		from[k] += d0[k] - dem_rs[k];
}

/* The gap [at, *rs): the warming run's chunks of U tiles into the
 * estimate. After a relax (from NULL) a memory-bound one brings an extra
 * region at the next full checkpoint after it, as mode_func_range does
 * (*rs moves there, *extra set). After a drain the first chunk starts from
 * `from` (drain_from), not from the light checkpoint at `at`: it holds
 * the rest of the work of the timed chip's packets in flight at the
 * region's end. */
static void gap_chunks(chip *c, int f, int at, int *rs, double m, const double *from, int *extra)
{
	chip_fidelity *F = &c->fid;
	int U = F->unit_tiles;
	for (int a = at; a < *rs;) {
		int e = a + U < *rs ? a + U : *rs;
		smp_piece p = warm_piece(c, f, a, e, m);
		if (a == at && from) {
			double d1[RES_N];
			warm_dem(c, f, e, m, 0, d1);
			p = chip_piece(c, from, d1);
		}
		int hard = account(F, p, 1), xs = wm_full_above(c->warm, e);
		if (!from && e - a == U && extra_due(F, hard, e, xs, *rs)) {
			if (xs > e)
				account(F, warm_piece(c, f, e, xs, m), 1);
			*rs = xs;
			*extra = 1;
			return;
		}
		a = e;
	}
}

/* The warming run's memory-to-compute demand ratio over frame f: the
 * memory time (SDRAM or host bus, the larger) of its chunks of U tiles
 * over their compute time (the busiest unit or L1 port), each summed over
 * the frame's whole chunks. */
static double frame_mem_ratio(chip *c, int f)
{
	int N = c->g.ntiles, U = c->fid.unit_tiles;
	double m = hier_merge_share(&c->mem), mem = 0, comp = 0;
	for (int a = 0; a + U <= N; a += U) {
		smp_piece p = warm_piece(c, f, a, a + U, m);
		mem += p.sdram > p.hbus ? p.sdram : p.hbus;
		comp += p.comp;
	}
	return comp > 0 ? mem / comp : mem > 0 ? INFINITY : 0;
}

/* The jump frame f takes (sampling.jump; docs/fidelity.md "`sampling.jump:
 * auto`"): auto relaxes a frame whose memory demand is at least
 * sampling.auto_ratio times its compute demand and skips any other. A
 * skip restores every region, so its estimate rests on the warming run's
 * demand of the gaps, whose SDRAM time runs below a timed chip's where
 * memory bound; in a frame that is memory bound nearly throughout, the
 * relaxes run into the next regions (slow packets), and the timed chip
 * measures more of the frame (dragon3 at 16 threads per RTP: 38% of its
 * tiles against 29%, fps +1.2% against +2.0%). Elsewhere a skip is as
 * accurate and 1.4 to 2 times faster. */
static int frame_jump(chip *c, int f)
{
	chip_fidelity *F = &c->fid;
	F->mem_ratio = frame_mem_ratio(c, f);
	int jump = c->cfg.sampling.jump;
	if (jump == CFG_JUMP_AUTO)
		jump = F->mem_ratio >= c->cfg.sampling.auto_ratio ? CFG_JUMP_RELAX : CFG_JUMP_SKIP;
	F->jump_frames[jump]++;
	return jump;
}

/* A sampled frame with stored warming (docs/fidelity.md "Stored
 * warming"): as mode_sampled_frame, but a gap between regions is not run: its
 * chunks' demands come from the warming run's light checkpoints and the
 * next region starts from the full checkpoint at its start
 * (wm_restore), which also adds the gap's counts. Region starts snap
 * down to the last full checkpoint (wm_full_below); a region whose start
 * falls at or before the last one's end follows it without a gap. */
void mode_sampled_frame_stored(chip *c, int f)
{
	chip_fidelity *F = &c->fid;
	wm *r = c->warm;
	int N = c->g.ntiles, U = F->unit_tiles, W = F->warmup_tiles, n = F->nunits;
	uint64_t t0 = eng_now(c->e);
	sampled_begin(F);
	int j = 0, at = 0, room = W + U;
	/* where the chip last took the warming run's state (the frame's start
	 * before the first restore): the tile and the chip's demand then, from
	 * which the gap after a drain starts (drain_from) */
	int rs_last = 0;
	F->jump = frame_jump(c, f);
	double dem_rs[RES_N];
	chip_demand(c, dem_rs);
	wm_mark(r, c);
	for (int b = 0; b < n; j++) {
		int tail = b == n - 1, rs = wm_full_below(r, F->base_s[b] - W), extra = 0;
		if (!tail && (rs > at ? rs : at) + room > wm_full_below(r, F->base_s[n - 1] - W)) {
			b++; /* no room before the tail: left out */
			j--;
			continue;
		}
		int drained = 0, skipped = 0;
		double from[RES_N];
		if (rs > at && j > 0) {
			at = c->g.next;
			int drains = jump_drains(c, f, at, rs);
			if (drains && jump_of(c) == CFG_JUMP_SKIP) {
				/* no functional step: the chip's work since its last
				 * restore, the region's packets in flight half done
				 * among it, gives way to the warming run's counts
				 * (wm_skip, below) and the estimate is the drain's,
				 * whose own steps it never counted (drain_from) */
				double d0[RES_N];
				chip_demand(c, d0);
				drain_from(c, f, rs_last, dem_rs, d0, from);
				drained = skipped = 1;
			} else if (drains) {
				/* the region's packets in flight finish functionally,
				 * no tile handed out: the chip has then done every
				 * tile before `at`, and the jump adds the work of the
				 * tiles from there on, as the warming run split its
				 * counts by tile (wm_region_end, wm_demand_done). The
				 * gap's first chunk holds the drained work (drain_from,
				 * below) */
				double d0[RES_N];
				int npc = F->npc;
				chip_demand(c, d0);
				mode_func_range(c, at, FR_DRAIN);
				drain_from(c, f, rs_last, dem_rs, d0, from);
				F->npc = npc;
				drained = 1;
			} else {
				/* the last region's packets in flight go on
				 * functionally until none is left in a slot and those
				 * in flight are as far along as the warming run's when
				 * it takes a checkpoint (FR_RELAX): the work the chip
				 * leaves undone at the jump is then what the gap's
				 * counts hold. A timed chip holds more work in flight
				 * when a tile is wanted than the warming run does
				 * (slow packets stay longer), and jumping at once lost
				 * that work (the frame's PCI bytes came out low;
				 * docs/fidelity.md). A memory-bound chunk on the way
				 * brings an extra region there and then, as in full
				 * warming: a relax takes RELAX_TILES tiles per slot,
				 * and with many threads the gaps after it were too
				 * short for the extra regions, and the estimate lost
				 * its memory-bound units. */
				extra = mode_func_range(c, rs, FR_RELAX);
				at = c->g.next;
			}
		}
		if (extra) /* it stopped at a memory-bound chunk: a region follows */
			rs = at;
		else if (rs > at) {
			double m = hier_merge_share(&c->mem);
			if (skipped)
				wm_skip(r, c, f, rs_last);
			else
				wm_region_end(r, f, at, drained);
			if (drained)
				rs = drained_extra(c, f, at, rs, m, &extra);
			gap_chunks(c, f, at, &rs, m, drained ? from : NULL, &extra);
			F->functional_tiles += (uint64_t)(rs - at);
			F->replayed_tiles += (uint64_t)(rs - at);
			if (wm_restore(r, c, f, rs, m))
				c->warm_err = 1;
			rs_last = rs;
			chip_demand(c, dem_rs);
			wm_mark(r, c);
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
	/* every tile's packets were replayed, here or in the warming run (2:
	 * and a read returned other bytes than recorded, replay.h) */
	for (int i = 0; i < N; i++)
		if (!c->replayed[i])
			c->replayed[i] = 1;
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
	/* the units that sample the middle: those after the head's (unit 0,
	 * from an empty chip) and before the tail's. The tail's unit lies in
	 * the measured tail (ct holds its cycles), at the same place in every
	 * replica, and in stored warming it runs from the last full checkpoint
	 * to the frame's end, several units long: taken as a sample of the
	 * middle it pulled every replica's ratio towards the frame's end (on
	 * Conference 1024x768, whose last tiles run at 1.48 cycles per demand
	 * against the middle's 1.30, about -1% fps at every offset;
	 * docs/fidelity.md "The estimator"). It joins only when the middle
	 * has fewer than two units of its own. */
	int nm = nr - 2 >= 2 ? nr - 2 : nr - 1;
	smp_est r;
	smp_estimate(F->unit_pc + 1, cyc + 1, nm, F->pc, F->npc, c->cfg.sampling.sdram_factor,
	             c->cfg.sampling.overlap, c->cfg.sampling.demand_model, &r);
	F->model = r.model;
	for (int u = 0; u < nr; u++) {
		double x = smp_demand(&F->unit_pc[u], &r.model);
		F->unit_rate[u] = x > 0 ? cyc[u] / x : 0;
	}
	double est = r.est, var = r.var, df = r.df;
	F->head_cyc = ch;
	F->tail_cyc = ct;
	F->est[f] = ch + est + ct;
	/* plus a bound on the units' systematic error (sampling.bias_bound),
	 * which no spread between units shows */
	F->half[f] = isfinite(var)
	                 ? smp_t975((int)df) * sqrt(var) + c->cfg.sampling.bias_bound * est
	                 : INFINITY;
}
