/*
 * test_fidelity.c: the fidelity modes (issue 6, docs/fidelity.md). Every
 * mode renders kernel-ref's image; sampled at rate 1 is cycle, event for
 * event; functional moves exactly cycle's memory-port and L1 traffic (hits
 * within cycle's merged misses + 3% of accesses, SDRAM bytes within 10%)
 * and does exactly its unit operations, and its fps bound is never below
 * the true fps; sampled intervals shrink with more units, cover the true
 * value on replicas, never go below the bound, and follow the host bus on
 * a PCI-bound frame; regions take over packets in flight with every
 * operation counted once; memory-bound chunks get their own stratum and
 * extra units; the SDRAM factor is fitted to the units' law and, on
 * Conference, narrows the interval and the error; sampled hit rates and
 * SDRAM MB count merges as cycle does. Scenes: the embedded
 * one, SPD balls through the VMA, and Conference when the shared scenes
 * are there.
 */
#include <math.h>
#include <string.h>

#include "mem/hier.h"
#include "sim/report.h"
#include "tests/chiptest.h"

static void cfg_mode(saar_config *c, int size, int mode)
{
	cfg_defaults(c);
	c->frame.width = c->frame.height = size;
	c->fidelity = mode;
	/* The regime these tests' tolerances were measured in: intersection
	 * 4 and traversal 16 lanes, tRP 3 (the defaults before the second
	 * calibration). The estimator is tested here, not the defaults: its
	 * accuracy at the shipped defaults is docs/FIDELITY.md's (make bench),
	 * and a calibration that moves the defaults must not move a test's
	 * premise (Conference SDRAM-bound in places, 10 units off by < 15%). */
	c->chip.unit[UNIT_ISECT].width = 4;
	c->chip.unit[UNIT_TRAV].width = 16;
	c->memory.sdram.trp = 3;
}

/* The embedded scene at 256x256 with threads_per_rtp threads per RTP, in
 * fidelity mode `mode`. */
static void embedded(world *w, saar_config *c, int mode, int threads_per_rtp)
{
	tu_load_world(w, NULL, NULL, NULL);
	cfg_mode(c, 256, mode);
	c->chip.threads_per_rtp = threads_per_rtp;
}

/* SPD balls at size x size through a VMA with 1 MB on board (the image
 * does not fit: every line comes over PCI once), in cycle mode. */
static void balls_vma(world *w, saar_config *c, int size)
{
	tu_load_world(w, "spd:balls:2", NULL, NULL);
	cfg_mode(c, size, CFG_FIDELITY_CYCLE);
	c->memory.vma.enabled = true;
	c->memory.sdram.mb = 1;
}

Test(fidelity, every_mode_renders_the_reference_image)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	static const int modes[] = {CFG_FIDELITY_CYCLE, CFG_FIDELITY_FUNCTIONAL,
	                            CFG_FIDELITY_SAMPLED};
	for (int m = 0; m < 3; m++)
		for (int tpr = 1; tpr <= 16; tpr *= 16) {
			saar_config c;
			cfg_mode(&c, 128, modes[m]);
			c.chip.threads_per_rtp = tpr;
			c.sampling.rate = 0.2;
			c.sampling.unit_tiles = 8;
			c.sampling.warmup_tiles = 8;
			c.sampling.min_units = 3; /* room for functional tiles at 64 threads */
			chip *ch = tu_run_chip(&w, &c);
			char what[64];
			snprintf(what, sizeof what, "fidelity %s, %d threads",
			         cfg_enum_name(&c, "fidelity"), tpr);
			tu_assert_identical(ch, what);
			if (modes[m] == CFG_FIDELITY_SAMPLED) {
				cr_assert_gt(ch->fid.functional_tiles, 0, "%s: nothing functional",
				             what);
				cr_assert_gt(ch->fid.detailed_tiles, 0, "%s: nothing detailed",
				             what);
			}
			chip_destroy(ch);
		}
	world_free(&w);
}

/* A sampled region takes over packets a functional stretch left in
 * flight, and hands its own back: every unit operation and memory request
 * is still counted exactly once, as cycle counts them. */
Test(fidelity, sampled_counts_every_operation_once)
{
	world w;
	saar_config c;
	embedded(&w, &c, CFG_FIDELITY_CYCLE, 16);
	chip *x = tu_run_chip(&w, &c);
	c.fidelity = CFG_FIDELITY_SAMPLED;
	c.sampling.rate = 0.1;
	c.sampling.min_units = 3;
	chip *y = tu_run_chip(&w, &c);
	cr_assert(!y->fid.exact);
	cr_assert_gt(y->fid.functional_tiles, 0);
	tu_assert_identical(y, "sampled, 16 threads");
	static const char *const sfx[] = {"rgs.ops",   "trav.ops",          "list.ops",
	                                  "isect.ops", "isect.busy_cycles", "trav.rays"};
	for (int k = 0; k < 6; k++)
		cr_assert_eq(chip_rtp_sum(x, sfx[k]), chip_rtp_sum(y, sfx[k]), "%s: %llu vs %llu",
		             sfx[k], (unsigned long long)chip_rtp_sum(x, sfx[k]),
		             (unsigned long long)chip_rtp_sum(y, sfx[k]));
	cr_assert_eq(memcmp(&x->mem.n, &y->mem.n, sizeof x->mem.n), 0, "memory-port counts differ");
	chip_destroy(x);
	chip_destroy(y);
	world_free(&w);
}

/* Two frames, so the warm second frame is covered too. */
Test(fidelity, sampled_at_rate_one_is_cycle)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config a, b;
	cfg_mode(&a, 128, CFG_FIDELITY_CYCLE);
	a.frame.frames = 2;
	b = a;
	b.fidelity = CFG_FIDELITY_SAMPLED;
	b.sampling.rate = 1.0;
	chip *x = tu_run_chip(&w, &a), *y = tu_run_chip(&w, &b);
	cr_assert(y->fid.exact);
	for (int f = 0; f < 2; f++)
		cr_assert_eq(
		    x->frame_cycles[f], y->frame_cycles[f], "frame %d: %llu vs %llu cycles", f,
		    (unsigned long long)x->frame_cycles[f], (unsigned long long)y->frame_cycles[f]);
	cr_assert_eq(x->events, y->events);
	cr_assert_eq(x->st.n, y->st.n);
	for (size_t i = 0; i < x->st.n; i++)
		cr_assert_eq(*x->st.e[i].value, *y->st.e[i].value, "counter %s differs",
		             x->st.e[i].name);
	hier_stats hx, hy;
	hier_get_stats(&x->mem, &hx);
	hier_get_stats(&y->mem, &hy);
	hx.now_ticks = hy.now_ticks = 0;
	cr_assert_eq(memcmp(&hx, &hy, sizeof hx), 0, "hierarchy counters differ");
	cr_assert_eq(y->fid.functional_tiles, 0);
	chip_destroy(x);
	chip_destroy(y);
	world_free(&w);
}

/* Accesses and bytes are exact; hits differ by MSHR merges (a merged miss
 * in cycle is a hit in functional, whose fills are immediate) and by the
 * order of the requests (functional runs packet after packet, cycle
 * interleaves its threads): within merges + 20% of accesses. */
static void assert_same_traffic(const world *w, saar_config *c, const char *what)
{
	c->fidelity = CFG_FIDELITY_CYCLE;
	chip *x = tu_run_chip(w, c);
	c->fidelity = CFG_FIDELITY_FUNCTIONAL;
	chip *y = tu_run_chip(w, c);
	tu_assert_identical(y, what);
	cr_assert_eq(memcmp(&x->mem.n, &y->mem.n, sizeof x->mem.n), 0,
	             "%s: memory-port counts differ", what);
	hier_stats hx, hy;
	hier_get_stats(&x->mem, &hx);
	hier_get_stats(&y->mem, &hy);
	for (int t = 0; t < MEM_NTYPES; t++) {
		const cache_stats *a = &hx.l1[t], *b = &hy.l1[t];
		cr_assert_eq(a->accesses, b->accesses, "%s: L1 %s accesses %llu vs %llu", what,
		             mem_type_name(t), (unsigned long long)a->accesses,
		             (unsigned long long)b->accesses);
		cr_assert_eq(a->bytes, b->bytes, "%s: L1 %s bytes", what, mem_type_name(t));
		cr_assert_eq(hx.reads[t], hy.reads[t]);
		cr_assert_eq(hx.bypass_reads[t], hy.bypass_reads[t]);
		cr_assert_eq(b->merges, 0, "%s: functional merged a miss", what);
		/* functional keeps every thread slot busy and interleaves their
		 * steps, so LRU victims are close to cycle's (one packet at a time,
		 * kd hits of balls through the VMA were 13% of accesses off) */
		double tol = (double)a->merges + 0.03 * (double)a->accesses;
		cr_assert_leq(fabs((double)a->hits - (double)b->hits), tol,
		              "%s: L1 %s hits %llu vs %llu (merges %llu)", what, mem_type_name(t),
		              (unsigned long long)a->hits, (unsigned long long)b->hits,
		              (unsigned long long)a->merges);
	}
	double sx = (double)(hx.sdram.read_bytes + hx.sdram.write_bytes),
	       sy = (double)(hy.sdram.read_bytes + hy.sdram.write_bytes);
	cr_assert_leq(fabs(sx - sy), 0.1 * sx, "%s: SDRAM bytes %g vs %g", what, sx, sy);
	/* the same unit operations, so the same issue cycles */
	static const char *const sfx[] = {"rgs.ops", "trav.busy_cycles", "isect.busy_cycles",
	                                  "list.rays"};
	for (int k = 0; k < 4; k++)
		cr_assert_eq(chip_rtp_sum(x, sfx[k]), chip_rtp_sum(y, sfx[k]), "%s: %s", what,
		             sfx[k]);
	cr_assert_eq(stats_get(&x->st, "isect.tri_tests"), stats_get(&y->st, "isect.tri_tests"));
	/* a bound: never slower than the timed chip */
	cr_assert_leq(y->frame_cycles[0], x->frame_cycles[0], "%s: bound %llu > true %llu", what,
	              (unsigned long long)y->frame_cycles[0],
	              (unsigned long long)x->frame_cycles[0]);
	/* ... nor faster than any RTP's own units allow (an RTP's units serve
	 * its threads only: the bound once took the RTPs' mean, and a busier
	 * RTP's utilisation came out above 100%) */
	for (int r = 0; r < y->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++) {
			const thr_unit *u = &y->rtp[r].u[k];
			cr_assert_leq((double)*u->busy / u->count, (double)y->frame_cycles[0],
			              "%s: RTP %d %s busier than the bound", what, r,
			              chip_unit_name(k));
		}
	cr_assert_eq(y->fid.detailed_tiles, 0);
	cr_assert_eq(hy.func_sdram_merge_ticks, 0, "%s: no timed access, no merge share", what);
	chip_destroy(x);
	chip_destroy(y);
}

Test(fidelity, functional_traffic_equals_cycle)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	cfg_mode(&c, 128, CFG_FIDELITY_CYCLE);
	assert_same_traffic(&w, &c, "embedded 128, std");
	c.chip.threads_per_rtp = 64;
	c.chip.stack_depth = 4; /* spills: writes and bypass reads */
	assert_same_traffic(&w, &c, "embedded 128, 64 threads, stack 4");
	world_free(&w);

	balls_vma(&w, &c, 96);
	assert_same_traffic(&w, &c, "balls through the VMA");
	world_free(&w);
}

static double half_width(const world *w, double rate, double *est, double *truth)
{
	saar_config c;
	cfg_mode(&c, 256, CFG_FIDELITY_SAMPLED);
	c.chip.threads_per_rtp = 4; /* units of 16 tiles: 6 or 26 of them */
	c.sampling.rate = rate;
	c.sampling.min_units = 3;
	chip *ch = tu_run_chip(w, &c);
	cr_assert(!ch->fid.exact);
	double h = ch->fid.half[0];
	*est = ch->fid.est[0];
	chip_destroy(ch);
	if (truth) {
		c.fidelity = CFG_FIDELITY_CYCLE;
		ch = tu_run_chip(w, &c);
		*truth = (double)ch->frame_cycles[0];
		chip_destroy(ch);
	}
	return h;
}

Test(fidelity, intervals_shrink_with_more_samples)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	double e1, e4, truth;
	double h1 = half_width(&w, 0.1, &e1, NULL), h4 = half_width(&w, 0.4, &e4, &truth);
	cr_assert_lt(h4, h1, "half-width at rate 0.4 (%g) not below rate 0.1 (%g)", h4, h1);
	cr_assert(isfinite(h1) && h1 > 0);
	/* 26 units: near the truth (the benchmark measures how near) */
	cr_assert_lt(fabs(e4 - truth), 0.1 * truth, "estimate %g vs true %g", e4, truth);
	world_free(&w);
}

/* c's true cycles of frame 0, from a cycle run; leaves c sampled. */
static double truth_then_sampled(const world *w, saar_config *c)
{
	c->fidelity = CFG_FIDELITY_CYCLE;
	chip *x = tu_run_chip(w, c);
	double t = (double)x->frame_cycles[0];
	chip_destroy(x);
	c->fidelity = CFG_FIDELITY_SAMPLED;
	return t;
}

/* One sampled run of c (at its sampling.offset) against the true cycles:
 * the estimate's error and interval half-width, whether it covers, and
 * the demand model it used; logged, the chip gone. */
typedef struct replica {
	double err, half, k;
	int covered, exact, linear, nreg;
	double p; /* the p-norm model's exponent, 0 for the others */
} replica;

static replica run_replica(const world *w, const saar_config *c, double truth)
{
	chip *y = tu_run_chip(w, c);
	replica r = {y->fid.est[0] - truth, y->fid.half[0],      y->fid.model.k, 0,
	             y->fid.exact,          y->fid.model.linear, y->fid.nreg,    y->fid.model.p};
	r.covered = fabs(r.err) <= r.half;
	cr_log_info("offset %.2f: %+.2f%% +- %.2f%% (%d units, demand %s, k %.2f, p %.2f)",
	            c->sampling.offset, 100 * r.err / truth, 100 * r.half / truth, r.nreg,
	            r.linear  ? "linear"
	            : r.p > 0 ? "pnorm"
	                      : "max",
	            r.k, r.p);
	chip_destroy(y);
	return r;
}

/* Replicas at five sampling offsets of one frame (the embedded scene,
 * 4 threads per RTP, ten units each): the interval covers the true cycles
 * on at least four, and every estimate is within 15% (measured: -10% to
 * +5%; ten units see a frame coarsely). */
Test(fidelity, interval_covers_small_cases)
{
	world w;
	saar_config c;
	embedded(&w, &c, CFG_FIDELITY_CYCLE, 4);
	double truth = truth_then_sampled(&w, &c);
	c.sampling.rate = 0.15; /* default units and warm-ups */
	int covered = 0;
	for (int k = 0; k < 5; k++) {
		c.sampling.offset = 0.1 + 0.2 * k;
		replica r = run_replica(&w, &c, truth);
		cr_assert(!r.exact);
		covered += r.covered;
		cr_assert_leq(fabs(r.err), 0.15 * truth, "offset %.1f: %g off the truth %g +- %g",
		              c.sampling.offset, r.err, truth, r.half);
	}
	cr_assert_geq(covered, 4, "interval covered the truth on %d of 5 replicas", covered);
	world_free(&w);
}

/* The billiard table with distribution ray tracing (configs/drt-views.yaml,
 * 16 samples per pixel) at 512x384, standard config, 16 threads per RTP:
 * loads it into w, returns its true cycles (a cycle run) and
 * leaves c set for sampled runs at rate 0.05 with full warming. */
static double billiard_sampled(world *w, saar_config *c)
{
	tu_load_world(w, NULL, "configs/drt-views.yaml", "billiard-drt");
	cr_assert_eq(w->v.drt.spp, 16);
	cfg_defaults(c);
	c->frame.width = 512;
	c->frame.height = 384;
	c->chip.threads_per_rtp = 16;
	double truth = truth_then_sampled(w, c);
	c->sampling.rate = 0.05;
	c->sampling.warming = CFG_WARMING_FULL;
	return truth;
}

/* Mistake: an interval that takes the fitted SDRAM factor k and overlap g
 * as known. On the billiard table with distribution ray tracing (16
 * samples per pixel, 512x384, the shipped defaults) the eight units of
 * rate 0.05 hold little SDRAM time, so k and g are barely told apart, yet
 * applied to the rows where the balls and their reflections make SDRAM
 * time approach compute: at offset 0.7 the fit took k 3.98 and g 1, the
 * estimate ran 27% slow and its interval (+-9%) missed the truth, as did
 * offset 0.5's (-9.6%, +-5%). The interval now also spans the estimates
 * of every k and g the units cannot rule out (sampling.c, param_var):
 * it covers the truth at both offsets. */
Test(fidelity, interval_covers_an_unknown_sdram_factor, .timeout = 300)
{
	world w;
	saar_config c;
	double truth = billiard_sampled(&w, &c);
	c.sampling.demand_model = CFG_DEMAND_MAX; /* auto takes pnorm here */
	for (int k = 0; k < 2; k++) {
		c.sampling.offset = 0.5 + 0.2 * k;
		replica r = run_replica(&w, &c, truth);
		cr_assert(!r.exact && !r.linear && !(r.p > 0));
		cr_assert(r.covered, "offset %.1f: %+.1f%% off the truth, interval +-%.1f%%",
		          c.sampling.offset, 100 * r.err / truth, 100 * r.half / truth);
	}
	world_free(&w);
}

/* The p-norm model on the same frame (sampling.demand_model pnorm): the
 * billiard table's rows run above their busiest resource where two units
 * are alike (shading and intersection in the rows above the balls: 1.2 to
 * 1.6 cycles per cycle of the busiest at 64 samples per pixel, by a
 * census), which no SDRAM factor or overlap describes; the max model's
 * estimates at offsets 0.5 and 0.7 ran 10% and 27% slow. With the p-norm
 * of every resource the estimate is within 2% (measured: -1.5% and
 * +0.3%) and the interval narrower than the max model's. Catches the
 * norm taken over the busiest resource alone (the max model again), a
 * resource left out of it, and a fit that keeps the wrong p. */
Test(fidelity, pnorm_estimates_the_billiard_table, .timeout = 300)
{
	world w;
	saar_config c;
	double truth = billiard_sampled(&w, &c);
	for (int k = 0; k < 2; k++) {
		c.sampling.offset = 0.5 + 0.2 * k;
		c.sampling.demand_model = CFG_DEMAND_MAX;
		replica m = run_replica(&w, &c, truth);
		c.sampling.demand_model = CFG_DEMAND_AUTO;
		replica a = run_replica(&w, &c, truth);
		cr_assert(a.p > 0, "offset %.1f: auto did not take the p-norm model",
		          c.sampling.offset);
		c.sampling.demand_model = CFG_DEMAND_PNORM;
		replica r = run_replica(&w, &c, truth);
		cr_assert(!r.exact && r.p > 0, "offset %.1f: no p-norm model", c.sampling.offset);
		cr_assert(r.covered && fabs(r.err) <= 0.02 * truth,
		          "offset %.1f: %+.1f%% off the truth, interval +-%.1f%%",
		          c.sampling.offset, 100 * r.err / truth, 100 * r.half / truth);
		cr_assert_lt(r.half, m.half,
		             "offset %.1f: interval +-%.1f%%, the max model's +-%.1f%%",
		             c.sampling.offset, 100 * r.half / truth, 100 * m.half / truth);
	}
	world_free(&w);
}

/* The middle's pieces (chunks, region pieces) of stratum `hard`. */
static int pieces(const chip_fidelity *F, int hard)
{
	int n = 0;
	for (int i = 0; i < F->npc; i++)
		n += F->pc[i].hard == hard;
	return n;
}

/* Memory-bound chunks form their own stratum and bring extra regions; with
 * sampling.hard_share 0 there is one stratum and only the planned units. */
Test(fidelity, memory_bound_chunks_get_extra_units)
{
	world w;
	saar_config c;
	embedded(&w, &c, CFG_FIDELITY_SAMPLED, 4);
	c.sampling.rate = 0.1;
	chip *y = tu_run_chip(&w, &c);
	int hard = 0;
	for (int u = 0; u < y->fid.nreg; u++)
		hard += y->fid.unit_pc[u].hard;
	cr_log_info("%d planned units, %d run, %d memory bound", y->fid.nunits, y->fid.nreg, hard);
	cr_assert_gt(y->fid.nreg, y->fid.nunits, "no extra region");
	cr_assert_leq(y->fid.nreg, 2 * y->fid.nunits);
	cr_assert_gt(hard, 0, "no memory-bound unit");
	cr_assert_gt(pieces(&y->fid, 1), 0, "no memory-bound chunk");
	chip_destroy(y);
	c.sampling.hard_share = 0;
	y = tu_run_chip(&w, &c);
	cr_assert_eq(y->fid.nreg, y->fid.nunits);
	cr_assert_eq(pieces(&y->fid, 1), 0);
	cr_assert_gt(pieces(&y->fid, 0), 0);
	for (int u = 0; u < y->fid.nreg; u++)
		cr_assert_eq(y->fid.unit_pc[u].hard, 0);
	chip_destroy(y);
	world_free(&w);
}

/* The middle of the frame is estimated from the units between the head's
 * and the tail's. Named mistake: taking the tail region's unit as a
 * sample of the middle too. Its cycles are already in the measured tail,
 * it sits at the frame's end in every replica and (stored warming) runs
 * from the last checkpoint to the end, several units long: on Conference
 * 1024x768 it pulled every offset's estimate about 1% slow
 * (docs/fidelity.md "The estimator"). The estimate must be the head and
 * tail as measured plus the estimator over units 1 .. nreg - 2 alone. */
Test(fidelity, tail_unit_is_not_a_sample_of_the_middle)
{
	world w;
	saar_config c;
	embedded(&w, &c, CFG_FIDELITY_SAMPLED, 4);
	c.sampling.rate = 0.1;
	chip *y = tu_run_chip(&w, &c);
	const chip_fidelity *F = &y->fid;
	int nr = F->nreg;
	cr_assert_geq(nr, 4, "premise: two units or more in the middle (%d regions)", nr);
	cr_assert_gt(F->est[0], F->floor[0], "premise: the estimate is not the bound");
	smp_est mid, with_tail;
	smp_estimate(F->unit_pc + 1, F->unit_cyc + 1, nr - 2, F->pc, F->npc,
	             c.sampling.sdram_factor, c.sampling.overlap, c.sampling.demand_model, &mid);
	smp_estimate(F->unit_pc + 1, F->unit_cyc + 1, nr - 1, F->pc, F->npc,
	             c.sampling.sdram_factor, c.sampling.overlap, c.sampling.demand_model,
	             &with_tail);
	double want = F->head_cyc + mid.est + F->tail_cyc;
	cr_log_info("%d regions: estimate %.1f, middle's units %.1f, with the tail's %.1f", nr,
	            F->est[0], want, F->head_cyc + with_tail.est + F->tail_cyc);
	cr_assert_gt(fabs(with_tail.est - mid.est), 1e-3 * mid.est,
	             "premise: the tail unit moves the estimate (test could not tell)");
	cr_assert_leq(fabs(F->est[0] - want), 1e-9 * want,
	              "estimate %.3f, not head + middle's units + tail %.3f", F->est[0], want);
	chip_destroy(y);
	world_free(&w);
}

Test(fidelity, config_and_cli)
{
	saar_config c;
	cfg_defaults(&c);
	diag d;
	cr_assert_eq(cfg_set(&c, "fidelity=functional", &d), 0, "%s", d.msg);
	cr_assert_eq(c.fidelity, CFG_FIDELITY_FUNCTIONAL);
	cr_assert_eq(cfg_set(&c, "sampling.rate=0.25", &d), 0, "%s", d.msg);
	cr_assert_float_eq(c.sampling.rate, 0.25, 1e-12);
	cr_assert_neq(cfg_set(&c, "sampling.rate=0", &d), 0);
	cr_assert_neq(cfg_set(&c, "fidelity=fast", &d), 0);
	char cmd[512];
	snprintf(cmd, sizeof cmd, "%s/saarsim --fidelity bogus --size 16x16 >/dev/null 2>&1",
	         tu_bin_dir());
	cr_assert_eq(tu_run(cmd), 2);
	char dir[256];
	tu_tmpdir(dir, sizeof dir);
	cr_assert_eq(tu_prog(dir, "saarsim",
	                     "--fidelity sampled --sample-rate 0.3 --unit-tiles 2 "
	                     "--warmup-tiles 2 --size 64x64"),
	             0, "%s", tu_slurp(dir, "err"));
	cr_assert(strstr(tu_slurp(dir, "out"), "fidelity sampled: "),
	          "sampled summary line missing");
}

/* The estimate never claims a frame faster than its busiest-resource
 * bound, and the bound never exceeds the truth. */
Test(fidelity, estimate_respects_the_bound)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	for (int tpr = 1; tpr <= 16; tpr *= 4) {
		saar_config c;
		cfg_mode(&c, 256, CFG_FIDELITY_CYCLE);
		c.chip.threads_per_rtp = tpr;
		chip *x = tu_run_chip(&w, &c);
		double truth = (double)x->frame_cycles[0];
		cr_assert_leq(x->fid.floor[0], truth, "tpr %d: bound %g above the truth %g", tpr,
		              x->fid.floor[0], truth);
		chip_destroy(x);
		c.fidelity = CFG_FIDELITY_SAMPLED;
		c.sampling.rate = 0.05;
		c.sampling.min_units = 3;
		c.sampling.unit_tiles = 8;
		c.sampling.warmup_tiles = 8;
		chip *y = tu_run_chip(&w, &c);
		cr_assert(!y->fid.exact);
		cr_assert_geq(y->fid.est[0], y->fid.floor[0], "tpr %d: estimate %g below bound %g",
		              tpr, y->fid.est[0], y->fid.floor[0]);
		chip_destroy(y);
	}
	world_free(&w);
}

/* A frame bound by the host bus (a scene through a tiny VMA): the demand
 * the estimate scales includes PCI time, so the estimate follows the bus.
 * (Scaling the busiest unit kind's work alone was 5x off on such frames.) */
Test(fidelity, pci_bound_frame_follows_the_bus)
{
	world w;
	saar_config c;
	balls_vma(&w, &c, 256);
	chip *x = tu_run_chip(&w, &c);
	double truth = (double)x->frame_cycles[0];
	cr_assert_eq(x->fid.bound_by, RES_HOSTBUS, "bound by %s, not the host bus",
	             chip_res_name(x->fid.bound_by));
	chip_destroy(x);
	c.fidelity = CFG_FIDELITY_SAMPLED;
	c.sampling.rate = 0.1;
	c.sampling.min_units = 3;
	c.sampling.unit_tiles = 64;
	c.sampling.warmup_tiles = 128;
	chip *y = tu_run_chip(&w, &c);
	cr_assert(!y->fid.exact);
	double est = y->fid.est[0], h = y->fid.half[0];
	cr_log_info("PCI-bound: true %.0f, estimate %.0f +- %.0f", truth, est, h);
	cr_assert_lt(fabs(est - truth), 0.1 * truth, "estimate %g vs true %g", est, truth);
	chip_destroy(y);
	world_free(&w);
}

/* The SDRAM factor fit on units made to a known law: cycles =
 * max(compute, k x SDRAM) with +-1% noise give back k; units whose cycles
 * follow compute alone give 1, however much SDRAM they use; host-bus time
 * is never scaled. */
Test(fidelity, sdram_factor_fits_the_units_law)
{
	enum { N = 24 };
	smp_piece u[N];
	double cyc[N];
	for (int law = 0; law < 3; law++) {
		double k = law == 0 ? 1.5 : law == 1 ? 2.3 : 1.0;
		for (int j = 0; j < N; j++) {
			double noise = 1.0 + 0.01 * ((j * 7) % 5 - 2) / 2.0;
			/* laws 0 and 1: SDRAM time up to 1.5x compute; law 2 (compute
			 * alone): up to 0.9x, cycles ignoring it */
			u[j] = (smp_piece){.comp = 1000.0,
			                   .sdram = 100.0 + (law < 2 ? 60.0 : 35.0) * j};
			double x = u[j].comp > k * u[j].sdram ? u[j].comp : k * u[j].sdram;
			cyc[j] = (law < 2 ? x : u[j].comp) * noise;
		}
		double got = smp_fit_sdram_factor(u, cyc, N);
		cr_assert(fabs(got - k) <= 0.04, "law k = %.2f: fitted %.2f", k, got);
	}
	for (int j = 0; j < N; j++) { /* PCI-bound units: the host bus sets the pace */
		u[j] = (smp_piece){
		    .comp = 500.0, .sdram = 200.0 + 10.0 * j, .hbus = 800.0 + 100.0 * j};
		cyc[j] = 1.1 * u[j].hbus;
	}
	cr_assert_float_eq(smp_fit_sdram_factor(u, cyc, N), 1.0, 1e-9);
	/* PCI-bound units beside SDRAM-bound ones under k = 1.5: a factor that
	 * also scaled the host bus would fit neither group (alone, every unit
	 * PCI-bound, one ratio absorbs any common scale) */
	for (int j = 0; j < N; j++) {
		int pci = j % 2;
		u[j] = (smp_piece){.comp = 500.0,
		                   .sdram = pci ? 100.0 : 400.0 + 20.0 * j,
		                   .hbus = pci ? 900.0 + 50.0 * j : 0.0};
		double x = pci ? u[j].hbus : 1.5 * u[j].sdram;
		cyc[j] = x > u[j].comp ? x : u[j].comp;
	}
	double mixed = smp_fit_sdram_factor(u, cyc, N);
	cr_assert(fabs(mixed - 1.5) <= 0.04, "PCI- and SDRAM-bound units: fitted %.2f", mixed);
}

/* The max model's overlap share g (smp_fit_max): units whose cycles are
 * max(compute, k x SDRAM) + g x min(compute, k x SDRAM) give back k and
 * g; units on the busiest resource alone give back g = 0 (the smallest
 * that fits); a given k or g stays as given. Catches the overlap term
 * left out of the demand, taken on the larger time instead of the
 * smaller, or fitted to the first g instead of the best. */
Test(fidelity, overlap_fits_the_units_law)
{
	enum { N = 24 };
	smp_piece u[N];
	double cyc[N];
	const double laws[][2] = {{1.3, 0.3}, {1.0, 0.5}, {1.5, 0.0}};
	for (int l = 0; l < 3; l++) {
		double k = laws[l][0], g = laws[l][1];
		for (int j = 0; j < N; j++) {
			double noise = 1.0 + 0.01 * ((j * 7) % 5 - 2) / 2.0;
			/* SDRAM time from a fifth of compute to twice it */
			u[j] = (smp_piece){.comp = 1000.0, .sdram = 200.0 + 80.0 * j};
			double s = k * u[j].sdram, hi = s > u[j].comp ? s : u[j].comp,
			       lo = s < u[j].comp ? s : u[j].comp;
			cyc[j] = (hi + g * lo) * noise;
		}
		double fk, fg;
		smp_fit_max(u, cyc, N, 0, -1, &fk, &fg);
		cr_assert(fabs(fk - k) <= 0.04 && fabs(fg - g) <= 0.04,
		          "law k = %.2f, g = %.2f: fitted k = %.2f, g = %.2f", k, g, fk, fg);
		smp_fit_max(u, cyc, N, 2.0, -1, &fk, &fg);
		cr_assert_float_eq(fk, 2.0, 1e-12, "a given k is kept");
		smp_fit_max(u, cyc, N, 0, 0.25, &fk, &fg);
		cr_assert_float_eq(fg, 0.25, 1e-12, "a given g is kept");
		smp_model m = {0, k, {0}, g, 0};
		cr_assert(fabs(smp_demand(&u[N - 1], &m) - cyc[N - 1]) < 0.02 * cyc[N - 1],
		          "the demand under the law is the law's cycles");
	}
}

/* A piece of compute resources res (the rest 0), SDRAM and host-bus time. */
static smp_piece res_piece(double rgs, double isect, double mem, double host)
{
	smp_piece p = {.sdram = mem, .hbus = host};
	p.res[0] = rgs;
	p.res[3] = isect;
	p.res[4] = 0.4 * isect; /* a third, smaller resource */
	p.comp = rgs > isect ? rgs : isect;
	return p;
}

/* The p-norm model (smp_demand, smp_fit_p): the demand is the p-norm of
 * every compute resource, SDRAM and host-bus time; units whose cycles
 * follow one p give it back, units on their busiest resource alone give
 * p = infinity (the plain busiest resource). Catches a resource left
 * out of the norm (SDRAM, host bus, or all but the busiest), the fit
 * keeping the first p or the smallest instead of the best, and a tie
 * settled away from the busiest resource. */
Test(fidelity, pnorm_fits_the_units_law)
{
	smp_model two = {0, 1, {0}, 0, 2};
	smp_piece a = res_piece(0, 0, 3, 4), b = res_piece(5, 5, 0, 0);
	cr_assert_float_eq(smp_demand(&a, &two), 5.0, 1e-9, "SDRAM and host bus in the norm");
	cr_assert_float_eq(smp_demand(&b, &two), sqrt(50 + 4), 1e-9, "every compute resource");
	enum { N = 16 };
	smp_piece u[N];
	double cyc[N];
	const double laws[] = {1.5, 2.0, 3.0, 0};
	for (int l = 0; l < 4; l++) {
		smp_model law = {0, 1, {0}, 0, laws[l]};
		for (int j = 0; j < N; j++) {
			double noise = 1.0 + 0.004 * ((j * 7) % 5 - 2);
			/* shading from a fifth of intersection to twice it, a little SDRAM */
			u[j] = res_piece(200.0 + 120.0 * j, 1000.0, 50.0 + 10.0 * j, 0);
			cyc[j] = smp_demand(&u[j], &law) * noise;
		}
		smp_model f = smp_fit_p(u, cyc, N);
		if (laws[l] > 0)
			cr_assert(fabs(f.p - laws[l]) <= 0.1 + 1e-9, "law p = %.1f: fitted %.2f",
			          laws[l], f.p);
		else
			cr_assert(isinf(f.p), "busiest resource alone: fitted p = %.2f", f.p);
	}
}

/* The p-norm model's interval carries p's uncertainty (sampling.c
 * param_var): units whose resources are never alike (shading a tenth of
 * intersection or less) cannot tell p = 3 from infinity, but a middle
 * whose chunks have the two alike is 1.3 times as long at p = 3. The
 * interval must span that, whatever p the fit kept. Catches p taken as
 * known (the interval only the units' 1% spread), and the term left out
 * when the fit keeps infinity. */
Test(fidelity, pnorm_interval_spans_what_the_units_cannot_rule_out)
{
	enum { N = 12, M = 40 };
	smp_piece u[N], pc[M];
	double cyc[N];
	for (int j = 0; j < N; j++) {
		double noise = 1.0 + 0.01 * ((j * 7) % 5 - 2);
		u[j] = res_piece(10.0 * j, 1000.0, 0, 0);
		cyc[j] = 1000.0 * noise;
	}
	for (int i = 0; i < M; i++)
		pc[i] = i < N ? u[i] : res_piece(1000.0, 1000.0, 0, 0);
	smp_est r;
	smp_estimate(u, cyc, N, pc, M, 0, -1, CFG_DEMAND_PNORM, &r);
	smp_model three = {0, 1, {0}, 0, 3};
	double at3 = 0;
	for (int i = 0; i < M; i++)
		at3 += smp_demand(&pc[i], &three);
	double half = smp_t975((int)r.df) * sqrt(r.var);
	cr_log_info("p %.2f: estimate %.0f +- %.0f; at p = 3: %.0f", r.model.p, r.est, half, at3);
	cr_assert_gt(at3, 1.15 * r.est, "the test's premise: p = 3 gives another middle");
	cr_assert_geq(r.est + half, 0.95 * at3, "interval %.0f +- %.0f, p = 3 gives %.0f", r.est,
	              half, at3);
}

/* Loads a shared view (the test skips when the shared scenes are absent)
 * and sets c to the defaults at width x height in cycle mode. */
static void shared_view(world *w, saar_config *c, const char *vname, int width, int height)
{
	char views[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	tu_load_world(w, NULL, views, vname);
	cfg_mode(c, 0, CFG_FIDELITY_CYCLE);
	c->frame.width = width;
	c->frame.height = height;
}

/* On Conference (standard config, 16 threads) a sizeable share of the
 * frame is near its SDRAM bound: the fitted factor is well above 1, and
 * the estimate is closer to cycle's, with a narrower interval, than with
 * the factor held at 1 (sampling.sdram_factor), at each of three offsets. */
Test(fidelity, sdram_factor_tightens_conference, .timeout = 300)
{
	world w;
	saar_config c;
	shared_view(&w, &c, "conference", 1024, 768);
	double truth = truth_then_sampled(&w, &c);
	c.sampling.rate = 0.1;
	c.sampling.demand_model = CFG_DEMAND_MAX;
	double err[2] = {0, 0}, half[2] = {0, 0};
	for (int o = 0; o < 3; o++) {
		c.sampling.offset = 0.25 + 0.25 * o;
		for (int fixed = 0; fixed < 2; fixed++) {
			c.sampling.sdram_factor = fixed;
			replica r = run_replica(&w, &c, truth);
			if (!fixed)
				cr_assert(r.k > 1.2 && r.k < 2.0, "k %.2f", r.k);
			cr_assert(r.covered, "offset %.2f: outside the interval",
			          c.sampling.offset);
			err[fixed] += fabs(r.err);
			half[fixed] += r.half;
		}
	}
	cr_assert_lt(err[0], err[1], "fitted k: summed error %g, k = 1: %g", err[0], err[1]);
	cr_assert_lt(half[0], half[1], "fitted k: summed half-width %g, k = 1: %g", half[0],
	             half[1]);
	world_free(&w);
}

/* Mistake: the fitted k and g's uncertainty taken from every value of
 * their grid instead of those the units cannot rule out (the joint
 * region of param_var): every interval would widen, also where the
 * units pin k and g down, and no coverage test would see it. On
 * Conference at 1024x768 (16 threads, rate 0.1) the interval with k and g
 * fitted is at most a quarter wider than with the same values given
 * (sampling.sdram_factor, sampling.overlap: nothing fitted, no term). */
Test(fidelity, fitted_k_widens_little_where_the_units_pin_it, .timeout = 300)
{
	world w;
	saar_config c;
	shared_view(&w, &c, "conference", 1024, 768);
	c.fidelity = CFG_FIDELITY_SAMPLED;
	c.sampling.rate = 0.1;
	c.sampling.demand_model = CFG_DEMAND_MAX;
	chip *y = tu_run_chip(&w, &c);
	double k = y->fid.model.k, g = y->fid.model.g, fitted = y->fid.half[0];
	chip_destroy(y);
	c.sampling.sdram_factor = k;
	c.sampling.overlap = g;
	y = tu_run_chip(&w, &c);
	double given = y->fid.half[0];
	chip_destroy(y);
	cr_log_info("k %.2f, g %.2f: half-width %.0f fitted, %.0f given", k, g, fitted, given);
	cr_assert(given > 0 && fitted >= given, "fitted %g, given %g", fitted, given);
	cr_assert_leq(fitted, 1.25 * given, "fitted k and g: half-width %g, given: %g", fitted,
	              given);
	world_free(&w);
}

/* The linear model's fit on units made to a known law: cycles = sum(beta x
 * lin) with +-1% noise give back beta; a regressor that is zero in every
 * unit (the host bus without VMA) gets 0; a law that would need a negative
 * coefficient gets none. */
Test(fidelity, linear_demand_fits_the_units_law)
{
	enum { N = 40 };
	smp_piece u[N];
	double cyc[N], beta[SMP_LIN];
	const double law[SMP_LIN] = {0.3, 3.5, 20.0, 2.0, 1.2, 0};
	for (int j = 0; j < N; j++) {
		memset(&u[j], 0, sizeof u[j]);
		for (int i = 0; i < 5; i++) /* regressors that vary apart */
			u[j].lin[i] = 100.0 + 50.0 * ((j * (2 * i + 3) + i) % 11);
		double y = 0;
		for (int i = 0; i < SMP_LIN; i++)
			y += law[i] * u[j].lin[i];
		cyc[j] = y * (1.0 + 0.01 * ((j * 7) % 5 - 2) / 2.0);
	}
	cr_assert_eq(smp_fit_linear(u, cyc, N, beta), 5);
	for (int i = 0; i < SMP_LIN; i++)
		cr_assert(fabs(beta[i] - law[i]) <= 0.05 * law[3], "beta[%d] %.3f, law %.3f", i,
		          beta[i], law[i]);
	smp_model m = {1, 1, {0}, 0, 0};
	memcpy(m.beta, beta, sizeof beta);
	cr_assert(fabs(smp_demand(&u[0], &m) - cyc[0]) < 0.02 * cyc[0]);
	/* cycles that fall as SDRAM time grows: its coefficient is dropped */
	for (int j = 0; j < N; j++)
		cyc[j] = 2.0 * u[j].lin[1] + 3.0 * u[j].lin[3] - 0.5 * u[j].lin[4];
	int kept = smp_fit_linear(u, cyc, N, beta);
	cr_assert(kept >= 1 && kept < 5, "kept %d", kept);
	for (int i = 0; i < SMP_LIN; i++)
		cr_assert_geq(beta[i], 0, "beta[%d] = %g", i, beta[i]);
	cr_assert_eq(beta[4], 0);
}

/* One thread per RTP: a packet's operations and memory waits follow one
 * another, cycles add up rather than follow the busiest resource. With 30
 * units or more, auto picks the linear model there, and on five replicas
 * of the embedded frame its estimates are nearer cycle's than the max
 * model's (sampling.demand_model = max), its interval covering the truth
 * on at least four. */
Test(fidelity, linear_demand_for_one_thread, .timeout = 300)
{
	world w;
	saar_config c;
	embedded(&w, &c, CFG_FIDELITY_CYCLE, 1);
	double truth = truth_then_sampled(&w, &c);
	c.sampling.rate = 0.15;
	double err[2] = {0, 0};
	int covered = 0;
	for (int k = 0; k < 5; k++) {
		c.sampling.offset = 0.1 + 0.2 * k;
		for (int m = 0; m < 2; m++) {
			c.sampling.demand_model = m ? CFG_DEMAND_MAX : CFG_DEMAND_AUTO;
			replica r = run_replica(&w, &c, truth);
			err[m] += fabs(r.err);
			if (m)
				continue;
			cr_assert(r.linear, "offset %.1f: auto did not pick linear",
			          c.sampling.offset);
			covered += r.covered;
		}
	}
	cr_assert_lt(err[0], err[1], "linear: summed error %g, max: %g", err[0], err[1]);
	cr_assert_geq(covered, 4, "interval covered the truth on %d of 5 replicas", covered);
	world_free(&w);
}

/* A small frame at one thread (BART robots, 256x192, ~37 units of 4
 * tiles): a regressor nonzero in only a unit or two let the linear fit
 * match them exactly, and the interval missed the truth on three of five
 * replicas. Judged by its leave-one-out error, the linear model is taken
 * only where it predicts, and its interval is widened by it: at least four
 * of five cover. */
Test(fidelity, small_frame_one_thread_intervals_cover, .timeout = 300)
{
	world w;
	saar_config c;
	shared_view(&w, &c, "robots", 256, 192);
	c.chip.threads_per_rtp = 1;
	double truth = truth_then_sampled(&w, &c);
	c.sampling.rate = 0.2;
	int covered = 0;
	for (int k = 0; k < 5; k++) {
		c.sampling.offset = 0.1 + 0.2 * k;
		covered += run_replica(&w, &c, truth).covered;
	}
	cr_assert_geq(covered, 4, "interval covered the truth on %d of 5 replicas", covered);
	world_free(&w);
}

/* Sampled hit rates: a functional hit may be an access the timed chip
 * merges into a fill in flight (a miss there); the estimate splits those
 * off by the detailed regions' merge share (cache_timed_hits). Through the
 * VMA, where PCI fetches are long and merges many, the tag cache's and
 * on-board cache's estimates must land near cycle's and much nearer than
 * the counts taken as they are; so must SDRAM MB (a merged access reads
 * no SDRAM). */
Test(fidelity, sampled_hit_rates_count_merges_as_cycle_does)
{
	world w;
	saar_config c;
	balls_vma(&w, &c, 192);
	c.chip.threads_per_rtp = 4;
	chip *x = tu_run_chip(&w, &c);
	c.fidelity = CFG_FIDELITY_SAMPLED;
	c.sampling.rate = 0.2;
	chip *y = tu_run_chip(&w, &c);
	cr_assert(!y->fid.exact);
	memfig mx, my;
	fig_steady_state(x, &mx);
	fig_steady_state(y, &my);
	hier_stats hy;
	hier_get_stats(&y->mem, &hy);
	const cache_stats *raw[2] = {&hy.tag_cache, &hy.l2};
	for (int k = 0; k < 2; k++) {
		double truth = mx.hit[HR_TAG + k], est = my.hit[HR_TAG + k];
		double counted = (double)raw[k]->hits / (double)raw[k]->accesses;
		cr_log_info("%s: cycle %.4f sampled %.4f counted %.4f", k ? "l2" : "tag", truth,
		            est, counted);
		cr_assert_lt(fabs(est - truth), 0.03, "%s: %.4f vs cycle %.4f", k ? "l2" : "tag",
		             est, truth);
		cr_assert_lt(fabs(est - truth), 0.5 * fabs(counted - truth));
	}
	double sd_counted =
	    (double)(hy.sdram.read_bytes + hy.sdram.write_bytes) / (1024.0 * 1024.0);
	cr_log_info("sdram: cycle %.4f sampled %.4f counted %.4f", mx.sdram_mb, my.sdram_mb,
	            sd_counted);
	cr_assert_lt(fabs(my.sdram_mb - mx.sdram_mb), fabs(sd_counted - mx.sdram_mb));
	/* the same for the SDRAM demand the estimate works from: the data-bus
	 * time of the functional reads so split off is not counted */
	double per = (double)y->clk.period, sx = x->fid.res_cycles[RES_SDRAM],
	       sy = y->fid.res_cycles[RES_SDRAM], merged = hy.func_sdram_merge_ticks / per;
	cr_log_info("sdram demand: cycle %.0f sampled %.0f (%.0f merged)", sx, sy, merged);
	cr_assert_gt(merged, 0);
	cr_assert_lt(fabs(sy - sx), fabs(sy + merged - sx));
	chip_destroy(x);
	chip_destroy(y);
	world_free(&w);
}

/* Mistake: the interval's low end held at sampled mode's floor, the
 * busiest RTP's work in the sampled run. Functional stretches hand tiles
 * to other RTPs than the cycle run does, so that RTP may hold more work
 * than any RTP of the cycle run: the Cornell box at 1024x768, 32 threads
 * per RTP, bound by intersection, gave a floor of 477,136 cycles against
 * the cycle run's 475,712, the estimate was clamped to it (0.3% slow), and
 * the report's interval [477,136, 487,131] lay wholly above the truth. The
 * low end now stops at the bound of the work spread evenly over the RTPs
 * (474,078 there), below any run of the same work: the report's interval
 * covers the truth at both offsets. */
Test(fidelity, interval_low_end_allows_another_tile_order, .timeout = 300)
{
	world w;
	saar_config c;
	shared_view(&w, &c, "cornell", 1024, 768);
	c.chip.threads_per_rtp = 32;
	double truth = truth_then_sampled(&w, &c);
	char dir[256], path[300];
	tu_tmpdir(dir, sizeof dir);
	snprintf(path, sizeof path, "%s/r.json", dir);
	for (int k = 0; k < 2; k++) {
		c.sampling.offset = 0.1 + 0.8 * k;
		chip *y = tu_run_chip(&w, &c);
		cr_assert(!y->fid.exact);
		cr_assert_leq(y->fid.even_floor[0], truth,
		              "offset %.1f: even bound %.0f, truth %.0f", c.sampling.offset,
		              y->fid.even_floor[0], truth);
		report_info ri = {.c = y, .w = &w};
		diag d;
		cr_assert_eq(report_json(path, &ri, &d), 0, "%s", d.msg);
		const char *s = tu_slurp(dir, "r.json");
		double lo = tu_json_nth(s, "cycles_ci95", 0), hi = tu_json_nth(s, "cycles_ci95", 1);
		cr_assert(lo <= truth && truth <= hi,
		          "offset %.1f: interval [%.0f, %.0f], truth %.0f", c.sampling.offset, lo,
		          hi, truth);
		chip_destroy(y);
	}
	unlink(path);
	rmdir(dir);
	world_free(&w);
}
