/*
 * frame.c: the frame loop (chip.h chip_run): per frame, the driver of the
 * run's mode: the timed dispatcher (chip_run_region) for cycle, the
 * functional driver (mode_func_range) for functional, the sampled drivers
 * (sampled.h) for sampled; then the frame's figures.
 */
#include <math.h>

#include "sim/chip.h"
#include "sim/modes/sampled.h"
#include "sim/modes/stored.h"
#include "sim/warming.h"

int chip_run(chip *c, diag *d)
{
	double t0 = chip_now_ms();
	chip_fidelity *F = &c->fid;
	mode_rec_open(c);
	mode_warm_open(c);
	int stored = chip_warm_stored(c);
	for (int f = 0; f < c->cfg.frame.frames; f++) {
		if (f > 0 && c->between && c->between(c, f, c->between_ctx, d))
			return -1; /* a warm animation's next frame (chip_anim_update) */
		if (f > 0)         /* fb_init cleared it */
			fb_clear(&c->fb);
		rgc_reset(&c->g);
		c->tiles_given = 0;
		if (F->mode == CFG_FIDELITY_FUNCTIONAL)
			mode_func_range(c, c->g.ntiles, FR_DRAIN);
		else if (stored)
			mode_sampled_frame_stored(c, f);
		else if (chip_estimates(&c->cfg))
			mode_sampled_frame(c, f);
		else /* cycle, and sampled at rate 1: the same event sequence */
			F->est[f] =
			    (double)eng_ticks_to_cycles(c->clk, chip_run_region(c, c->g.ntiles));
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
			chip_census_mark(c, c->g.ntiles);
		if (c->wcap) { /* a warming run: the frame's last light checkpoint */
			double dem[RES_N];
			chip_demand(c, dem);
			wm_put_light(c->wcap, c, f, c->g.ntiles, dem);
		}
		if (c->md.in)
			mode_rec_pixels(c);
		mode_rec_store(c);
		if (c->oom || c->env.oom || mem_failed(&c->mem))
			return diag_set(d, "chip", 0, 0, "out of memory during the frame");
		if (c->env.damaged && c->env.grid)
			return diag_set(d, "chip", 0, 0,
			                "the grid the grid traversal unit read is damaged: a cell "
			                "range past the cell lists, or a packet's walk longer than "
			                "%llu steps (damaged board memory or a wrong address)",
			                (unsigned long long)c->env.max_steps);
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
		chip_resource_bound(c);
		F->floor[f] = F->res_cycles[F->bound_by];
		F->even_floor[f] = F->even_bound;
		if (F->mode == CFG_FIDELITY_FUNCTIONAL) {
			/* no timing: the frame's cycles are the bound, in whole
			 * cycles (the estimate too: the report's fidelity figures
			 * are then the headline's) */
			F->est[f] = ceil(F->floor[f]);
			c->frame_cycles[f] = (uint64_t)F->est[f];
		} else {
			/* an estimate below the bound is impossible */
			if (F->est[f] < F->floor[f])
				F->est[f] = F->floor[f];
			c->frame_cycles[f] = (uint64_t)llround(F->est[f]);
		}
		c->frames_done = f + 1;
	}
	c->events = eng_events(c->e);
	chip_sync_counters(c);
	c->sim_ms = chip_now_ms() - t0;
	return 0;
}
