/*
 * report_mem.c: the hierarchy stats as JSON (see report_mem.h). Ratios
 * (hit rates, utilisation, bandwidth) are derived here from the counters.
 */
#include "sim/report_mem.h"

static double ratio(uint64_t a, uint64_t b)
{
	return b ? (double)a / (double)b : 0.0;
}

/* Key k: v, or null when there is nothing to measure. */
static void knum_null_if(jsonw *w, const char *k, double v, int none)
{
	if (none) {
		jsonw_key(w, k);
		jsonw_null(w);
	} else {
		jsonw_knum(w, k, v);
	}
}

static void cache_json(jsonw *w, const char *key, const cache_stats *c)
{
	jsonw_key(w, key);
	jsonw_obj_begin(w);
	jsonw_kuint(w, "accesses", c->accesses);
	jsonw_kuint(w, "hits", c->hits);
	jsonw_kuint(w, "misses", c->misses);
	jsonw_knum(w, "hit_rate", ratio(c->hits, c->accesses));
	jsonw_kuint(w, "mshr_merges", c->merges);
	jsonw_kuint(w, "mshr_full", c->mshr_full);
	jsonw_kuint(w, "bytes", c->bytes);
	jsonw_kuint(w, "fills", c->fills);
	jsonw_kuint(w, "fill_bytes", c->fill_bytes);
	jsonw_kuint(w, "evictions", c->evictions);
	jsonw_obj_end(w);
}

void hier_write_json(const hier_stats *s, jsonw *w)
{
	double secs = (double)s->now_ticks * 1e-12;
	jsonw_obj_begin(w);
	jsonw_kstr(w, "model", "hierarchy");
	jsonw_kbool(w, "vma_enabled", s->vma_enabled);
	jsonw_knum(w, "elapsed_s", secs);

	jsonw_key(w, "l1");
	jsonw_obj_begin(w);
	for (int t = 0; t < MEM_NTYPES; t++) {
		jsonw_key(w, mem_type_name(t));
		jsonw_obj_begin(w);
		jsonw_kuint(w, "reads", s->reads[t]);
		jsonw_kuint(w, "read_bytes", s->read_bytes[t]);
		jsonw_kuint(w, "writes", s->writes[t]);
		jsonw_kuint(w, "write_bytes", s->write_bytes[t]);
		jsonw_kuint(w, "bypass_reads", s->bypass_reads[t]);
		jsonw_kuint(w, "wait_cycles", s->wait_cycles[t]);
		jsonw_kuint(w, "mshr_stall_cycles", s->mshr_stall_cycles[t]);
		cache_json(w, "cache", &s->l1[t]);
		jsonw_obj_end(w);
	}
	jsonw_obj_end(w);

	uint64_t meta = s->memif.reads[MEMIF_META] + s->memif.writes[MEMIF_META], all = 0;
	jsonw_key(w, "memif");
	jsonw_obj_begin(w);
	for (int r = 0; r < MEMIF_NREQ; r++) {
		all += s->memif.reads[r] + s->memif.writes[r];
		jsonw_key(w, memif_requester_name(r));
		jsonw_obj_begin(w);
		jsonw_kuint(w, "reads", s->memif.reads[r]);
		jsonw_kuint(w, "writes", s->memif.writes[r]);
		jsonw_kuint(w, "bytes", s->memif.bytes[r]);
		jsonw_kuint(w, "queue_cycles", s->memif.queue_ticks[r] / s->core_period);
		jsonw_obj_end(w);
	}
	jsonw_obj_end(w);

	const sdram_stats *d = &s->sdram;
	uint64_t rows = d->row_hits + d->row_empty + d->row_conflicts;
	jsonw_key(w, "sdram");
	jsonw_obj_begin(w);
	jsonw_kuint(w, "reads", d->reads);
	jsonw_kuint(w, "writes", d->writes);
	jsonw_kuint(w, "read_bytes", d->read_bytes);
	jsonw_kuint(w, "write_bytes", d->write_bytes);
	jsonw_kuint(w, "bytes", d->read_bytes + d->write_bytes);
	jsonw_kuint(w, "meta_accesses", meta);
	jsonw_kuint(w, "data_accesses", all - meta);
	/* null where there is nothing to share or time (a functional run's
	 * SDRAM has no rows opened, no bus time) */
	knum_null_if(w, "meta_share", ratio(meta, all), !all);
	jsonw_kuint(w, "row_hits", d->row_hits);
	jsonw_kuint(w, "row_empty", d->row_empty);
	jsonw_kuint(w, "row_conflicts", d->row_conflicts);
	knum_null_if(w, "row_hit_rate", ratio(d->row_hits, rows), !rows);
	/* a skip's regions were on the bus too (skipped_*: hier_params.h) */
	uint64_t sbusy = d->busy_ticks + s->skipped_sdram_busy_ticks;
	jsonw_kuint(w, "busy_ns", sbusy / 1000);
	knum_null_if(w, "utilization", ratio(sbusy, s->now_ticks), !s->now_ticks);
	double run_s = s->run_ticks ? (double)s->run_ticks * 1e-12 : secs;
	jsonw_knum(w, "bandwidth_gb_s",
	           run_s > 0 ? (double)(d->read_bytes + d->write_bytes) / run_s / 1e9 : 0.0);
	jsonw_knum(w, "peak_gb_s", s->sdram_peak_bytes_per_s / 1e9);
	jsonw_obj_end(w);

	if (s->vma_enabled) {
		const vma_stats *v = &s->vma;
		jsonw_key(w, "vma");
		jsonw_obj_begin(w);
		cache_json(w, "tag_cache", &s->tag_cache);
		cache_json(w, "l2", &s->l2);
		jsonw_kuint(w, "meta_reads", v->meta_reads);
		jsonw_kuint(w, "meta_writes", v->meta_writes);
		jsonw_kuint(w, "meta_bytes", v->meta_bytes);
		jsonw_kuint(w, "data_reads", v->data_reads);
		jsonw_kuint(w, "data_writes", v->data_writes);
		jsonw_kuint(w, "data_bytes", v->data_bytes);
		jsonw_kuint(w, "host_fetches", v->host_fetches);
		jsonw_kuint(w, "host_fetch_bytes", v->host_fetch_bytes);
		jsonw_kuint(w, "host_writes", v->host_writes);
		jsonw_kuint(w, "host_write_bytes", v->host_write_bytes);
		jsonw_kuint(w, "writebacks", v->writebacks);
		jsonw_kuint(w, "writeback_bytes", v->writeback_bytes);
		jsonw_kuint(w, "mshr_stall_cycles", v->stall_ticks / s->core_period);
		jsonw_obj_end(w);
		const hbus_stats *b = &s->hostbus;
		jsonw_key(w, "hostbus");
		jsonw_obj_begin(w);
		jsonw_kuint(w, "transfers", b->transfers);
		jsonw_kuint(w, "bytes", b->bytes);
		uint64_t hbusy = b->busy_ticks + s->skipped_hostbus_busy_ticks;
		jsonw_kuint(w, "busy_ns", hbusy / 1000);
		knum_null_if(w, "utilization", ratio(hbusy, s->now_ticks), !s->now_ticks);
		jsonw_knum(w, "peak_mb_s", s->hostbus_peak_bytes_per_s / 1e6);
		jsonw_obj_end(w);
	}
	jsonw_obj_end(w);
}
