/*
 * reportcheck.c: the report's invariants (see reportcheck.h and
 * docs/report.md "Invariants").
 *
 * Byte identities hold exactly (integers); derived figures (fps, MB, rates)
 * are compared with a relative tolerance of 1e-9, far below any rounding
 * a report prints and far above double rounding.
 */
#include "sim/reportcheck.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "units/thread.h"

#define MB   (1024.0 * 1024.0)
#define U(x) ((unsigned long long)(x))

static void fail(rc_list *o, const char *fmt, ...)
{
	if (o->n < RC_MAX) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(o->msg[o->n], sizeof o->msg[0], fmt, ap);
		va_end(ap);
	}
	o->n++;
}

static int near(double a, double b)
{
	return fabs(a - b) <= 1e-9 * fmax(fabs(a), fabs(b)) + 1e-12;
}

/* A rate or share: in [0, 1], or -1 where the report writes null. */
static void rate(rc_list *o, const char *what, double v, int null_ok)
{
	if (null_ok && v == -1)
		return;
	if (!(v >= -1e-12 && v <= 1 + 1e-12))
		fail(o, "%s: a rate in [0, 1] (is %.9g)", what, v);
}

static const char *const cache_name[HR_N] = {"l1.shade", "l1.kd",         "l1.list",
                                             "l1.tri",   "vma.tag_cache", "vma.l2"};

static void cache_rules(rc_list *o, const char *what, const cache_stats *s, uint32_t line,
                        int exact)
{
	if (s->hits + s->misses != s->accesses)
		fail(o, "%s: hits + misses = accesses (%llu + %llu != %llu)", what, U(s->hits),
		     U(s->misses), U(s->accesses));
	if (s->merges > s->misses)
		fail(o, "%s: merges <= misses (%llu > %llu)", what, U(s->merges), U(s->misses));
	if (s->fill_bytes != s->fills * line)
		fail(o, "%s: fill_bytes = fills x line (%llu != %llu x %u)", what, U(s->fill_bytes),
		     U(s->fills), line);
	uint64_t fetched = s->misses >= s->merges ? s->misses - s->merges : 0;
	if (exact ? s->fills != fetched : s->fills > fetched)
		fail(o, "%s: fills %s misses - merges (%llu, %llu - %llu)", what,
		     exact ? "=" : "<=", U(s->fills), U(s->misses), U(s->merges));
}

/* A span's figures (per_frame[i] or steady_state). */
static void span_rules(rc_list *o, const rc_figs *f, const char *what, const memfig *m)
{
	char w[96];
	if (!near(m->fps, m->cycles > 0 ? f->clock_mhz * 1e6 / m->cycles : 0))
		fail(o, "%s: fps = clock / cycles (%.9g, %g MHz / %.9g)", what, m->fps,
		     f->clock_mhz, m->cycles);
	for (int k = 0; k < HR_N; k++) {
		snprintf(w, sizeof w, "%s.hit_rate.%s", what, cache_name[k]);
		rate(o, w, m->hit[k], 1);
	}
	snprintf(w, sizeof w, "%s.meta_share", what);
	rate(o, w, m->meta_share, 1);
	snprintf(w, sizeof w, "%s.sdram_row_hit_rate", what);
	rate(o, w, m->row_hit_rate, 1);
	snprintf(w, sizeof w, "%s.sdram_utilisation", what);
	rate(o, w, m->sdram_util, 1);
	snprintf(w, sizeof w, "%s.pci_utilisation", what);
	rate(o, w, m->pci_util, 1);
	/* a busy bus moved bytes (the audit's "PCI 0.00 MB/frame, busy 99.7%") */
	if (m->sdram_util > 0 && !(m->sdram_mb > 0))
		fail(o, "%s: SDRAM busy (%.1f%%) moved bytes (%.6g MB)", what, 100 * m->sdram_util,
		     m->sdram_mb);
	if (m->pci_util > 0 && !(m->pci_mb > 0))
		fail(o, "%s: PCI busy (%.1f%%) moved bytes (%.6g MB)", what, 100 * m->pci_util,
		     m->pci_mb);
}

/* Bytes the L1 of type t asked of the level below: line fills, reads that
 * bypass it (stack refills, one entry each) and posted writes. */
static uint64_t l1_below_read(const hier_stats *h, int t)
{
	return h->l1[t].fill_bytes + h->bypass_reads[t] * THR_STACK_ENTRY_BYTES;
}

static void memory_rules(rc_list *o, const rc_figs *f)
{
	const hier_stats *h = &f->h;
	const mem_counts *p = &f->port;
	for (int t = 0; t < MEM_NTYPES; t++)
		if (p->reads[t] != h->reads[t] || p->read_bytes[t] != h->read_bytes[t] ||
		    p->writes[t] != h->writes[t] || p->write_bytes[t] != h->write_bytes[t])
			fail(o,
			     "memory.%s: the port's requests = the hierarchy's (reads %llu/%llu, "
			     "bytes %llu/%llu, writes %llu/%llu)",
			     mem_type_name(t), U(p->reads[t]), U(h->reads[t]), U(p->read_bytes[t]),
			     U(h->read_bytes[t]), U(p->writes[t]), U(h->writes[t]));
	for (int t = 0; t < MEM_NTYPES; t++)
		cache_rules(o, cache_name[t], &h->l1[t], f->line[t], f->exact_fills);
	uint64_t mi_bytes = 0, mi_acc = 0;
	for (int r = 0; r < MEMIF_NREQ; r++) {
		mi_bytes += h->memif.bytes[r];
		mi_acc += h->memif.reads[r] + h->memif.writes[r];
	}
	uint64_t sd_bytes = h->sdram.read_bytes + h->sdram.write_bytes;
	if (sd_bytes != mi_bytes || h->sdram.reads + h->sdram.writes != mi_acc)
		fail(o,
		     "sdram: bytes and accesses = the memory interface's (%llu/%llu bytes, "
		     "%llu/%llu "
		     "accesses)",
		     U(sd_bytes), U(mi_bytes), U(h->sdram.reads + h->sdram.writes), U(mi_acc));
	if ((h->sdram.busy_ticks + h->func_sdram_busy_ticks > 0) != (sd_bytes > 0))
		fail(o, "sdram: busy exactly when bytes moved (busy %llu ps, %llu bytes)",
		     U(h->sdram.busy_ticks + h->func_sdram_busy_ticks), U(sd_bytes));
	if (!f->vma) {
		for (int t = 0; t < MEM_NTYPES; t++) {
			uint64_t want = l1_below_read(h, t) + h->write_bytes[t];
			if (h->memif.bytes[t] != want)
				fail(o,
				     "memif.%s: bytes = L1 fills + bypass reads + writes (%llu != "
				     "%llu + "
				     "%llu + %llu)",
				     mem_type_name(t), U(h->memif.bytes[t]), U(h->l1[t].fill_bytes),
				     U(h->bypass_reads[t] * THR_STACK_ENTRY_BYTES),
				     U(h->write_bytes[t]));
		}
		return;
	}
	const vma_stats *v = &h->vma;
	cache_rules(o, cache_name[HR_TAG], &h->tag_cache, f->line[HR_TAG], f->exact_fills);
	cache_rules(o, cache_name[HR_L2], &h->l2, f->line[HR_L2], f->exact_fills);
	uint64_t asked = 0, written = 0, l1data = 0;
	for (int t = 0; t < MEM_NTYPES; t++) {
		asked += l1_below_read(h, t);
		written += h->write_bytes[t];
		l1data += h->memif.bytes[t];
	}
	if (v->read_bytes != asked || v->write_bytes != written)
		fail(o,
		     "vma: read bytes = L1 fills + bypass reads, write bytes = writes (%llu/%llu, "
		     "%llu/%llu)",
		     U(v->read_bytes), U(asked), U(v->write_bytes), U(written));
	if (h->l2.bytes != v->read_bytes)
		fail(o, "vma.l2: bytes looked up = the VMA's read bytes (%llu != %llu)",
		     U(h->l2.bytes), U(v->read_bytes));
	if (f->line[HR_TAG] && h->tag_cache.accesses != h->l2.accesses)
		fail(o, "vma.tag_cache: one meta-data lookup per on-board access (%llu != %llu)",
		     U(h->tag_cache.accesses), U(h->l2.accesses));
	uint64_t fetched = h->l2.misses - h->l2.merges;
	if (v->host_fetches != fetched || v->host_fetch_bytes != fetched * f->line[HR_L2])
		fail(o,
		     "vma: host fetches = L2 misses - merges, of a line each (%llu, %llu bytes; "
		     "%llu)",
		     U(v->host_fetches), U(v->host_fetch_bytes), U(fetched));
	/* a dirty line written back when evicted is read from SDRAM by the
	 * fill requester and crosses the host bus (docs/memory.md, VMA) */
	if (h->memif.bytes[MEMIF_FILL] != v->host_fetch_bytes + v->writeback_bytes)
		fail(o,
		     "memif.fill: bytes = the host fetches' + write-backs' (%llu != %llu + %llu)",
		     U(h->memif.bytes[MEMIF_FILL]), U(v->host_fetch_bytes), U(v->writeback_bytes));
	if (h->memif.bytes[MEMIF_META] != v->meta_bytes)
		fail(o, "memif.meta: bytes = the VMA's meta-data bytes (%llu != %llu)",
		     U(h->memif.bytes[MEMIF_META]), U(v->meta_bytes));
	if (l1data + h->memif.bytes[MEMIF_FILL] != v->data_bytes + v->writeback_bytes)
		fail(o,
		     "memif: data bytes + fill bytes = the VMA's data bytes + write-backs (%llu + "
		     "%llu != %llu + %llu)",
		     U(l1data), U(h->memif.bytes[MEMIF_FILL]), U(v->data_bytes),
		     U(v->writeback_bytes));
	uint64_t hb = v->host_fetch_bytes + v->host_write_bytes + v->writeback_bytes;
	if (h->hostbus.bytes != hb)
		fail(o,
		     "hostbus: bytes = host fetches + write-arounds + write-backs (%llu != %llu + "
		     "%llu + %llu)",
		     U(h->hostbus.bytes), U(v->host_fetch_bytes), U(v->host_write_bytes),
		     U(v->writeback_bytes));
	if ((h->hostbus.busy_ticks + h->func_hostbus_busy_ticks > 0) != (h->hostbus.bytes > 0))
		fail(o, "hostbus: busy exactly when bytes moved (busy %llu ps, %llu bytes)",
		     U(h->hostbus.busy_ticks + h->func_hostbus_busy_ticks), U(h->hostbus.bytes));
}

/* ray_types: every counter split by packet type adds up over the types
 * to the total it splits (a count made under the wrong type still adds
 * up; tests/test_drt.c compares the split with kernel-ref's), and with
 * caches, each L1's lookups and hits by ray type add up to its own. */
static void ray_type_rules(rc_list *o, const rc_figs *f)
{
	static const char *const what[TC_BUSY] = {"kd_node_steps", "leaf_visits", "list_entries",
	                                          "triangle_tests", "ray_triangle_tests"};
	for (int i = 0; i < TC_NCOUNTERS; i++) {
		char w[64];
		if (i < TC_BUSY)
			snprintf(w, sizeof w, "%s", what[i]);
		else
			snprintf(w, sizeof w, "%s %s", chip_unit_name((i - TC_BUSY) % UNIT_NKINDS),
			         i < TC_RAYS ? "busy cycles" : "op rays");
		if (f->by_type[i] != f->total[i])
			fail(o, "ray_types: %s add up over the types to the total (%llu != %llu)",
			     w, U(f->by_type[i]), U(f->total[i]));
	}
	if (!f->hierarchy)
		return;
	for (int t = 0; t < MEM_NTYPES; t++) {
		uint64_t lk = 0, hit = 0;
		for (int r = 0; r < MEM_RAY_TYPES; r++) {
			lk += f->h.ray_lookups[r][t];
			hit += f->h.ray_hits[r][t];
		}
		if (lk != f->h.l1[t].accesses || hit != f->h.l1[t].hits)
			fail(o,
			     "ray_types: %s's lookups and hits add up over the ray types to the "
			     "L1's (%llu, %llu != %llu, %llu)",
			     cache_name[t], U(lk), U(hit), U(f->h.l1[t].accesses),
			     U(f->h.l1[t].hits));
	}
}

int rc_check(const rc_figs *f, rc_list *o)
{
	memset(o, 0, sizeof *o);
	uint64_t sum = 0;
	for (int i = 0; i < f->frames; i++)
		sum += f->frame_cycles[i];
	if (sum != f->cycles)
		fail(o, "cycles: the frames' cycles add up to the total (%llu != %llu)", U(sum),
		     U(f->cycles));
	if (!near(f->fps, f->cycles ? f->clock_mhz * 1e6 * f->frames / (double)f->cycles : 0))
		fail(o, "fps = clock / cycles per frame (%.9g, %g MHz x %d / %llu)", f->fps,
		     f->clock_mhz, f->frames, U(f->cycles));
	for (int k = 0; k < UNIT_NKINDS; k++) {
		char w[64];
		snprintf(w, sizeof w, "units.%s.utilisation", chip_unit_name(k));
		rate(o, w, f->util[k], 0);
		for (int r = 0; r < f->nrtp; r++) {
			snprintf(w, sizeof w, "units.%s.per_rtp_utilisation[%d]", chip_unit_name(k),
			         r);
			rate(o, w, f->rtp_util[k * f->nrtp + r], 0);
		}
	}
	if (f->threads_timed) {
		double s = 0;
		for (int k = 0; k < THR_NSTATES; k++) {
			char w[64];
			snprintf(w, sizeof w, "threads.%s", chip_state_name(k));
			rate(o, w, f->share[k], 0);
			s += f->share[k];
		}
		if (!near(s, 1))
			fail(o, "threads: the four shares add up to 1 (%.9g)", s);
	}
	/* the shares are the states' times over their own sum, so the sum
	 * above cannot fail: the times themselves must fill every context's
	 * whole frame time (each context is in one state at a time) */
	if (f->thread_ps_want && f->thread_ps != f->thread_ps_want)
		fail(o,
		     "threads: the states' times add up to contexts x frame time (%llu ps != %llu)",
		     U(f->thread_ps), U(f->thread_ps_want));
	double sd = 0, pci = 0;
	for (int i = 0; i < f->frames; i++) {
		char w[32];
		snprintf(w, sizeof w, "per_frame[%d]", i);
		span_rules(o, f, w, &f->per_frame[i]);
		if (f->per_frame[i].cycles != (double)f->frame_cycles[i])
			fail(o, "%s: cycles = cycles_per_frame[%d] (%.9g != %llu)", w, i,
			     f->per_frame[i].cycles, U(f->frame_cycles[i]));
		sd += f->per_frame[i].sdram_mb;
		pci += f->per_frame[i].pci_mb;
	}
	span_rules(o, f, "steady_state", &f->steady);
	/* per-frame MB add up to the run's bytes (a sampled frame's SDRAM MB
	 * is an estimate, not a count) */
	uint64_t bytes = 0;
	if (f->hierarchy)
		bytes = f->h.sdram.read_bytes + f->h.sdram.write_bytes;
	else
		for (int t = 0; t < MEM_NTYPES; t++)
			bytes += f->port.read_bytes[t] + f->port.write_bytes[t];
	if (!f->estimated && !near(sd, (double)bytes / MB))
		fail(o, "per_frame: SDRAM MB add up to the run's bytes (%.9g != %llu / 2^20)", sd,
		     U(bytes));
	if (f->hierarchy && !near(pci, (double)f->h.hostbus.bytes / MB))
		fail(o, "per_frame: PCI MB add up to the host bus's bytes (%.9g != %llu / 2^20)",
		     pci, U(f->h.hostbus.bytes));
	if (f->hierarchy)
		memory_rules(o, f);
	ray_type_rules(o, f);
	return o->n;
}

/* The per-type counters summed over the types, and their totals. */
static void ray_type_figs(const chip *c, rc_figs *f)
{
	for (int t = 0; t < PKT_NTYPES; t++)
		for (int i = 0; i < TC_NCOUNTERS; i++)
			f->by_type[i] += *c->env.ct[t][i];
	f->total[TC_NODE_STEPS] = *c->env.c[C_NODE_STEPS];
	f->total[TC_LEAF_VISITS] = *c->env.c[C_LEAF_VISITS];
	f->total[TC_LIST_ENTRIES] = *c->env.c[C_LIST_ENTRIES];
	f->total[TC_TRI_TESTS] = *c->env.c[C_TRI_TESTS];
	f->total[TC_RAY_TRI_TESTS] = *c->env.c[C_RAY_TRI_TESTS];
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++) {
			f->total[TC_BUSY + k] += *c->rtp[r].u[k].busy;
			f->total[TC_RAYS + k] += *c->rtp[r].u[k].rays;
		}
}

int rc_figs_get(const chip *c, rc_figs *f)
{
	memset(f, 0, sizeof *f);
	f->frames = c->frames_done;
	f->nrtp = c->nrtp;
	f->frame_cycles = calloc((size_t)f->frames + 1, sizeof *f->frame_cycles);
	f->per_frame = calloc((size_t)f->frames + 1, sizeof *f->per_frame);
	f->rtp_util = calloc((size_t)UNIT_NKINDS * (size_t)f->nrtp, sizeof *f->rtp_util);
	if (!f->frame_cycles || !f->per_frame || !f->rtp_util) {
		rc_figs_free(f);
		return -1;
	}
	f->hierarchy = !hier_get_stats(&c->mem, &f->h);
	f->vma = f->hierarchy && f->h.vma_enabled;
	f->estimated = chip_estimates(&c->cfg);
	f->exact_fills = c->warm_state == WARM_OFF;
	f->clock_mhz = c->cfg.chip.clock_mhz;
	f->fps = fig_fps(c);
	f->cycles = chip_cycles(c);
	for (int i = 0; i < f->frames; i++) {
		f->frame_cycles[i] = c->frame_cycles[i];
		fig_span(c, i, i + 1, &f->per_frame[i]);
	}
	fig_steady_state(c, &f->steady);
	f->port = c->mem.n;
	for (int t = 0; t < MEM_NTYPES; t++)
		f->line[t] = hier_l1_params(&c->cfg, t).line_bytes;
	if (f->vma) {
		vma_params vp = hier_vma_params(&c->cfg);
		f->line[HR_TAG] = vp.tag_cache_enabled ? vp.ways * VMA_META_BYTES_PER_LINE : 0;
		f->line[HR_L2] = vp.line;
	}
	for (int k = 0; k < UNIT_NKINDS; k++) {
		f->util[k] = fig_util(c, k, -1);
		for (int r = 0; r < f->nrtp; r++)
			f->rtp_util[k * f->nrtp + r] = fig_util(c, k, r);
	}
	f->threads_timed = fig_thread_shares(c, f->share);
	uint64_t ps[THR_NSTATES];
	f->thread_ps = fig_thread_ps(c, ps);
	f->thread_ps_want = c->cfg.fidelity != CFG_FIDELITY_FUNCTIONAL && !chip_estimates(&c->cfg)
	                        ? chip_cycles(c) * c->clk.period * (uint64_t)(c->nrtp * c->tpr)
	                        : 0;
	ray_type_figs(c, f);
	return 0;
}

void rc_figs_free(rc_figs *f)
{
	free(f->frame_cycles);
	free(f->per_frame);
	free(f->rtp_util);
	memset(f, 0, sizeof *f);
}

int report_check(const chip *c, rc_list *out)
{
	rc_figs f;
	if (rc_figs_get(c, &f)) {
		memset(out, 0, sizeof *out);
		fail(out, "report invariants: out of memory for the figures");
		return out->n;
	}
	int n = rc_check(&f, out);
	rc_figs_free(&f);
	return n;
}
