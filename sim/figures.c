/*
 * figures.c: the derived figures (see figures.h).
 *
 * Memory figures per frame come from the cumulative snapshots chip_run takes
 * after every frame (chip.frame_port, chip.frame_mem): a span of frames is
 * the difference of two snapshots, so per-frame, steady-state and whole-run
 * figures are computed the same way and always add up.
 */
#include "sim/figures.h"

#include <stdio.h>
#include <string.h>

static double ratio(double a, double b)
{
	return b > 0 ? a / b : 0.0;
}

static uint64_t get(const chip *c, const char *name)
{
	return stats_get(&c->st, name);
}

/* Issue cycles of unit kind over the chip (rtp < 0) or one RTP. */
static uint64_t unit_busy(const chip *c, int kind, int rtp)
{
	char name[64];
	if (rtp >= 0) {
		snprintf(name, sizeof name, "rtp%d.%s.busy_cycles", rtp, chip_unit_name(kind));
		return get(c, name);
	}
	snprintf(name, sizeof name, "%s.busy_cycles", chip_unit_name(kind));
	return chip_rtp_sum(c, name);
}

double fig_util(const chip *c, int kind, int rtp)
{
	int units = chip_unit_cfg(&c->cfg, kind)->count * (rtp < 0 ? c->nrtp : 1);
	return ratio((double)unit_busy(c, kind, rtp), (double)chip_cycles(c) * units);
}

double fig_fps(const chip *c)
{
	double cyc = ratio((double)chip_cycles(c), c->frames_done);
	return ratio(c->cfg.chip.clock_mhz * 1e6, cyc);
}

uint64_t fig_thread_ps(const chip *c, uint64_t ps[THR_NSTATES])
{
	char name[64];
	uint64_t tot = 0;
	for (int s = 0; s < THR_NSTATES; s++) {
		snprintf(name, sizeof name, "threads.%s_ps", chip_state_name(s));
		tot += ps[s] = chip_rtp_sum(c, name);
	}
	return tot;
}

int fig_thread_shares(const chip *c, double share[THR_NSTATES])
{
	uint64_t ps[THR_NSTATES];
	double tot = (double)fig_thread_ps(c, ps);
	for (int s = 0; s < THR_NSTATES; s++)
		share[s] = tot > 0 ? (double)ps[s] / tot : 0;
	return tot > 0;
}

/* ---- memory figures over a span of frames ---- */

#define MB (1024.0 * 1024.0) /* MB = 2^20 bytes, as memory.sdram.mb */

static const char *const hr_names[HR_N] = {"shade", "kd", "list", "tri", "tag_cache", "l2"};

const char *fig_hit_name(int slot)
{
	return slot >= 0 && slot < HR_N ? hr_names[slot] : "?";
}

/* A cache's hit rate between snapshots a and b; with est (a sampled
 * frame) its hits as a timed cache would count them (cache_timed_hits;
 * *share: the merge share used). -1 without accesses. */
static double span_hit_rate(const cache_stats *a, const cache_stats *b, int est, double *share)
{
	double h = (double)(b->hits - a->hits), r = 0;
	if (est)
		h = cache_timed_hits(a, b, &r);
	if (share)
		*share = r;
	uint64_t acc = b->accesses - a->accesses;
	return acc ? h / (double)acc : -1.0;
}

void fig_span(const chip *c, int f0, int f1, memfig *m)
{
	static const hier_stats zero_h;
	static const mem_counts zero_p;
	memset(m, 0, sizeof *m);
	int n = f1 - f0;
	m->first = f0 + 1;
	m->last = f1;
	uint64_t cyc = 0;
	for (int f = f0; f < f1; f++)
		cyc += c->frame_cycles[f];
	m->cycles = ratio((double)cyc, n);
	m->fps = ratio(c->cfg.chip.clock_mhz * 1e6, m->cycles);
	for (int k = 0; k < HR_N; k++)
		m->hit[k] = -1.0;
	/* -1 (null, "-" in the text) where there is nothing to measure: the
	 * fixed model has no SDRAM, a span with no engine time (functional)
	 * no bus time */
	m->meta_share = m->row_hit_rate = m->sdram_util = m->pci_util = -1;
	if (!c->frame_mem) {
		const mem_counts *a = f0 ? &c->frame_port[f0 - 1] : &zero_p,
		                 *b = &c->frame_port[f1 - 1];
		uint64_t bytes = 0;
		for (int t = 0; t < MEM_NTYPES; t++)
			bytes += b->read_bytes[t] - a->read_bytes[t] + b->write_bytes[t] -
			         a->write_bytes[t];
		m->sdram_mb = (double)bytes / MB / n;
		return;
	}
	const hier_stats *a = f0 ? &c->frame_mem[f0 - 1] : &zero_h, *b = &c->frame_mem[f1 - 1];
	uint64_t sd =
	    b->sdram.read_bytes + b->sdram.write_bytes - a->sdram.read_bytes - a->sdram.write_bytes;
	m->sdram_mb = (double)sd / MB / n;
	m->pci_mb = (double)(b->hostbus.bytes - a->hostbus.bytes) / MB / n;
	int est = chip_estimates(&c->cfg);
	for (int t = 0; t < MEM_NTYPES; t++)
		m->hit[t] = span_hit_rate(&a->l1[t], &b->l1[t], est, NULL);
	if (b->vma_enabled) {
		double share;
		m->hit[HR_TAG] = span_hit_rate(&a->tag_cache, &b->tag_cache, est, NULL);
		m->hit[HR_L2] = span_hit_rate(&a->l2, &b->l2, est, &share);
		/* an on-board cache hit reads SDRAM; the accesses a timed chip
		 * merges into a PCI fetch in flight do not (sampled) */
		double acc = (double)(b->l2.accesses - a->l2.accesses);
		double fh = (double)(b->l2.func_hits - a->l2.func_hits);
		if (est && acc > 0)
			m->sdram_mb -=
			    fh * share * (double)(b->l2.bytes - a->l2.bytes) / acc / MB / n;
	}
	uint64_t meta = 0, all = 0;
	for (int r = 0; r < MEMIF_NREQ; r++) {
		uint64_t x =
		    b->memif.reads[r] + b->memif.writes[r] - a->memif.reads[r] - a->memif.writes[r];
		all += x;
		if (r == MEMIF_META)
			meta = x;
	}
	/* -1 (null, an empty CSV field) when no access was made: a share of
	 * nothing is not 0% */
	m->meta_share = all ? (double)meta / (double)all : -1;
	uint64_t rh = b->sdram.row_hits - a->sdram.row_hits;
	uint64_t rows = rh + b->sdram.row_empty - a->sdram.row_empty + b->sdram.row_conflicts -
	                a->sdram.row_conflicts;
	m->row_hit_rate = rows ? (double)rh / (double)rows : -1;
	double ticks = (double)(b->now_ticks - a->now_ticks);
	if (ticks <= 0)
		return;
	/* with the busy time of regions a skip handed over (hier_params.h) */
	m->sdram_util = ratio((double)(b->sdram.busy_ticks + b->skipped_sdram_busy_ticks -
	                               a->sdram.busy_ticks - a->skipped_sdram_busy_ticks),
	                      ticks);
	m->pci_util = ratio((double)(b->hostbus.busy_ticks + b->skipped_hostbus_busy_ticks -
	                             a->hostbus.busy_ticks - a->skipped_hostbus_busy_ticks),
	                    ticks);
}

/* frames 2..N, or frame 1 alone (report.h) */
void fig_steady_state(const chip *c, memfig *m)
{
	fig_span(c, c->frames_done > 1 ? 1 : 0, c->frames_done, m);
}
