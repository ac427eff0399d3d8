/*
 * replay.c: saarsim-replay, runs a memory trace (traces/memtrace.h) through
 * any cache/VMA configuration without simulating the units.
 *
 *   saarsim-replay [--config FILE] [--set key=value]... [--timing]
 *                  [--image-bytes N] [--json FILE] TRACE.gz
 *
 * Default (functional): every request goes through its L1 (mem/cache) with
 * immediate fills; L1 misses go to SDRAM, or with memory.vma.enabled through
 * the VMA's tag cache and L2 (vma_access_func). Hit rates, bytes at every
 * level and requests per host second; fast enough for cache-size and
 * line-size sweeps. --timing instead issues each request at its trace cycle
 * into the full timed hierarchy (mem/hier.c) and also reports the cycles.
 * Reads at or above --image-bytes (the chip's stack-spill area) bypass the
 * L1s, as in the chip. Bad input: one line on stderr, exit 2.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sim/memconfig.h"
#include "sim/report_mem.h"
#include "sim/config.h"
#include "traces/memtrace.h"

static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define USAGE                                                                                      \
	"saarsim-replay [--config FILE] [--set key=value]... [--timing] [--image-bytes N] "        \
	"[--json FILE] TRACE.gz"

/* Bad command line: one line, what is wrong and the usage. */
static int usage(const char *what)
{
	fprintf(stderr, "saarsim-replay: %s (usage: " USAGE ")\n", what);
	return DIAG_EXIT;
}

static int fail(const diag *d)
{
	fprintf(stderr, "saarsim-replay: %s\n", d->msg);
	return DIAG_EXIT;
}

/* ---- timed replay: a feeder event issues the requests of each cycle ---- */

typedef struct feeder {
	eng *e;
	eng_clock clk;
	memport *mp;
	mtr_reader *rd;
	mtr_rec next;
	uint64_t max_cycle; /* beyond it the engine's picosecond ticks overflow */
	int have, err;
	uint64_t issued, answered;
	diag *d;
} feeder;

static void answered(eng *e, void *ctx, uint64_t arg)
{
	((feeder *)ctx)->answered++;
}

/* The next record into f->next: 1, 0 at the end, -1 on an error (also a
 * cycle the engine cannot represent). */
static int next_rec(feeder *f)
{
	int rc = mtr_read(f->rd, &f->next, f->d);
	if (rc == 1 && f->next.cycle > f->max_cycle)
		rc = diag_set(f->d, f->rd->path, 0, 0,
		              "record %llu (counting from 1) is at cycle %llu, beyond the %llu "
		              "a timed replay at %g MHz can represent",
		              (unsigned long long)(f->rd->n - (f->rd->have - f->rd->next)),
		              (unsigned long long)f->next.cycle, (unsigned long long)f->max_cycle,
		              1e6 / (double)f->clk.period);
	f->have = rc == 1;
	f->err |= rc < 0;
	return rc;
}

static void feed(eng *e, void *ctx, uint64_t arg)
{
	feeder *f = ctx;
	uint64_t cyc = eng_now(e) / f->clk.period;
	while (f->have && f->next.cycle <= cyc) {
		mem_req r = {f->next.addr, f->next.bytes, f->next.type, f->next.write, 0, NULL};
		mem_access(f->mp, &r, r.write ? NULL : answered, f, 0);
		f->issued++;
		next_rec(f);
	}
	if (f->have)
		eng_schedule(e, eng_cycles_to_ticks(f->clk, f->next.cycle), feed, f, 0);
}

int main(int argc, char **argv)
{
	saar_config cfg;
	diag d = {{0}};
	cfg_defaults(&cfg);
	const char *trace = NULL, *json = NULL;
	int timing = 0;
	uint64_t image_bytes = UINT64_MAX;
	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
			printf("usage: " USAGE "\n"
			       "  replays a memory trace (saarsim --trace-mem) through the caches, "
			       "SDRAM and VMA\n"
			       "  of a config: functional by default, --timing issues each request "
			       "at its cycle\n"
			       "  --image-bytes N: reads at or above N bypass the L1s (the chip's "
			       "stack spills)\n"
			       "  --json FILE: the figures as JSON\n");
			return 0;
		}
		if (!strcmp(a, "--config") && i + 1 < argc) {
			if (cfg_load(&cfg, argv[++i], &d))
				return fail(&d);
		} else if (!strcmp(a, "--set") && i + 1 < argc) {
			if (cfg_set(&cfg, argv[++i], &d))
				return fail(&d);
		} else if (!strcmp(a, "--timing")) {
			timing = 1;
		} else if (!strcmp(a, "--image-bytes") && i + 1 < argc) {
			/* a byte count: digits only (strtoull takes "", "-1" and
			 * " 7"), at most 2^48 (no memory image is larger) */
			const char *v = argv[++i];
			char *end;
			errno = 0;
			image_bytes = strtoull(v, &end, 10);
			if (!*v || strspn(v, "0123456789") != strlen(v) || errno ||
			    image_bytes > (1ull << 48)) {
				fprintf(
				    stderr,
				    "saarsim-replay: --image-bytes: expected a byte count 0..2^48, "
				    "got '%s'\n",
				    v);
				return DIAG_EXIT;
			}
		} else if (!strcmp(a, "--json") && i + 1 < argc) {
			json = argv[++i];
		} else if (a[0] == '-' && a[1]) {
			char what[256];
			snprintf(what, sizeof what, "%s: unknown option or missing value", a);
			return usage(what);
		} else if (!trace) {
			trace = a;
		} else {
			return usage("more than one trace");
		}
	}
	if (!trace)
		return usage("no trace given");
	if (cfg_validate(&cfg, &d))
		return fail(&d);

	/* the clock includes opening the trace (its first read) */
	double t0 = now_s();
	/* the reader holds a block buffer of hundreds of KB: on the heap */
	mtr_reader *rdp = calloc(1, sizeof *rdp);
	if (!rdp) {
		diag_set(&d, trace, 0, 0, "out of memory");
		return fail(&d);
	}
	if (mtr_open_read(rdp, trace, &d)) {
		free(rdp);
		return fail(&d);
	}
	/* from here every way out (goto out) frees what it holds */
	int ret = DIAG_EXIT;
	eng *e = NULL;
	memport mp;
	int have_mp = 0, nl1 = 0, have_vma = 0;
	cache l1[MEM_NTYPES];
	vma v;

	hier_stats s;
	memset(&s, 0, sizeof s);
	uint64_t n = 0, cycles = 0;
	if (timing) {
		e = eng_create(1024);
		eng_clock clk = eng_clock_mhz(cfg.chip.clock_mhz);
		/* The trace carries no image size. Without --image-bytes: with the VMA
		 * every address is image; without it, whatever fits on board is
		 * (reads above it take the spill-area path past the L1s). */
		uint64_t img = image_bytes;
		if (img == UINT64_MAX && !cfg.memory.vma.enabled)
			img = (uint64_t)cfg.memory.sdram.mb << 20;
		if (!e) {
			diag_set(&d, trace, 0, 0, "out of memory");
			goto out;
		}
		if (mem_init_hier(&mp, e, clk, &cfg, img, NULL, &d))
			goto out;
		have_mp = 1;
		/* a quarter of the tick range: room for the hierarchy's latencies */
		feeder f = {e, clk, &mp, rdp, {0}, (UINT64_MAX >> 2) / clk.period, 0, 0, 0, 0, &d};
		if (next_rec(&f) < 0)
			goto out;
		if (f.have)
			eng_schedule(e, eng_cycles_to_ticks(clk, f.next.cycle), feed, &f, 0);
		eng_run(e, ENG_FOREVER);
		if (f.err)
			goto out;
		n = f.issued;
		cycles = eng_now(e) / clk.period;
		hier_get_stats(&mp, &s);
	} else {
		for (; nl1 < MEM_NTYPES; nl1++) {
			cache_params cp = hier_l1_params(&cfg, nl1);
			char what[32];
			snprintf(what, sizeof what, "memory.l1.%s", mem_type_name(nl1));
			if (cache_init(&l1[nl1], &cp, what, &d))
				goto out;
		}
		int use_vma = cfg.memory.vma.enabled;
		if (use_vma) {
			vma_params vp = hier_vma_params(&cfg);
			if (vma_init(&v, NULL, eng_clock_mhz(cfg.chip.clock_mhz), NULL, NULL,
			             (uint64_t)cfg.memory.sdram.mb << 20, &vp, NULL, &d))
				goto out;
			have_vma = 1;
		}
		uint64_t sd_read = 0, sd_write = 0;
		/* per type, hoisted: line size (and its log2 when a power of two);
		 * all addresses below 4 GiB (the usual case) divide in 32 bits */
		uint32_t lbs[MEM_NTYPES];
		int lsh[MEM_NTYPES];
		for (int t = 0; t < MEM_NTYPES; t++) {
			lbs[t] = l1[t].p.line_bytes;
			lsh[t] = -1;
			for (int b = 0; b < 32; b++)
				if (lbs[t] == 1u << b)
					lsh[t] = b;
		}
		const mtr_rec *blk;
		int rc;
		while ((rc = mtr_read_block(rdp, &blk, &d)) > 0) {
			n += (uint64_t)rc;
			cycles = blk[rc - 1].cycle;
			for (const mtr_rec *r = blk, *rend = blk + rc; r < rend; r++) {
				int t = r->type;
				uint64_t addr = r->addr;
				if (r->write) {
					s.writes[t]++;
					s.write_bytes[t] += r->bytes;
					if (use_vma)
						vma_access_func(&v, addr, r->bytes, 1, NULL);
					else
						sd_write += r->bytes;
					continue;
				}
				s.reads[t]++;
				s.read_bytes[t] += r->bytes;
				if (addr >= image_bytes) {
					s.bypass_reads[t]++;
					if (use_vma)
						vma_access_func(&v, addr, r->bytes, 0, NULL);
					else
						sd_read += r->bytes;
					continue;
				}
				cache *c = &l1[t];
				uint32_t lb = lbs[t], bytes = r->bytes ? r->bytes : 1;
				uint64_t first, end = addr + bytes - 1, last;
				if (lsh[t] >= 0) {
					first = addr >> lsh[t];
					last = end >> lsh[t];
				} else if (end <= UINT32_MAX) {
					first = (uint32_t)addr / lb;
					last = (uint32_t)end / lb;
				} else {
					first = addr / lb;
					last = end / lb;
				}
				/* one line (the common case): bytes counted as asked;
				 * several: a whole line each, as before */
				uint32_t per = first == last ? bytes : lb;
				for (uint64_t l = first; l <= last; l++) {
					if (cache_try_hit(c, l, per) ||
					    cache_lookup(c, l, per, NULL, NULL) == CACHE_HIT)
						continue;
					cache_fill(c, l, NULL);
					if (use_vma)
						vma_access_func(&v, l * lb, lb, 0, NULL);
					else
						sd_read += lb;
				}
			}
		}
		if (rc < 0)
			goto out;
		for (int t = 0; t < MEM_NTYPES; t++)
			s.l1[t] = l1[t].s;
		s.core_period = eng_clock_mhz(cfg.chip.clock_mhz).period;
		if (use_vma) {
			s.vma_enabled = 1;
			s.vma = v.s;
			s.tag_cache = v.tag.c.s;
			s.l2 = v.l2.c.s;
			s.hostbus.bytes =
			    v.s.host_fetch_bytes + v.s.host_write_bytes + v.s.writeback_bytes;
			s.hostbus.transfers = v.s.host_fetches + v.s.host_writes + v.s.writebacks;
			/* SDRAM bytes with VMA: data (reads, fills, writes) plus meta-data;
			 * the functional path does not split reads from writes */
			sd_read = v.s.data_bytes + v.s.meta_bytes + v.s.writeback_bytes;
			s.memif.bytes[MEMIF_META] = v.s.meta_bytes;
			s.memif.reads[MEMIF_META] = v.s.meta_reads;
			s.memif.writes[MEMIF_META] = v.s.meta_writes;
		}
		s.sdram.read_bytes = sd_read;
		s.sdram.write_bytes = sd_write;
	}
	double secs = now_s() - t0;

	printf("trace %s: %llu requests, last cycle %llu, %s replay\n", trace,
	       (unsigned long long)n, (unsigned long long)cycles, timing ? "timed" : "functional");
	for (int t = 0; t < MEM_NTYPES; t++) {
		const cache_stats *c = &s.l1[t];
		printf("  l1.%-5s accesses %12llu  hits %12llu  misses %10llu  hit rate %6.2f%%  "
		       "merges %8llu  fill bytes %12llu\n",
		       mem_type_name(t), (unsigned long long)c->accesses,
		       (unsigned long long)c->hits, (unsigned long long)c->misses,
		       c->accesses ? 100.0 * (double)c->hits / (double)c->accesses : 0.0,
		       (unsigned long long)c->merges, (unsigned long long)c->fill_bytes);
	}
	if (s.vma_enabled) {
		printf(
		    "  tag cache hit rate %6.2f%%   L2 hit rate %6.2f%%   meta-data SDRAM accesses "
		    "%llu (%.1f%% of SDRAM accesses)\n",
		    s.tag_cache.accesses
		        ? 100.0 * (double)s.tag_cache.hits / (double)s.tag_cache.accesses
		        : 0.0,
		    s.l2.accesses ? 100.0 * (double)s.l2.hits / (double)s.l2.accesses : 0.0,
		    (unsigned long long)(s.vma.meta_reads + s.vma.meta_writes),
		    100.0 * (double)(s.vma.meta_reads + s.vma.meta_writes) /
		        (double)(s.vma.meta_reads + s.vma.meta_writes + s.vma.data_reads +
		                 s.vma.data_writes + (s.vma.meta_reads + s.vma.data_reads == 0)));
		printf("  host bus: %llu bytes in %llu transfers\n",
		       (unsigned long long)s.hostbus.bytes,
		       (unsigned long long)s.hostbus.transfers);
	}
	printf("  SDRAM bytes %llu (read %llu, write %llu)\n",
	       (unsigned long long)(s.sdram.read_bytes + s.sdram.write_bytes),
	       (unsigned long long)s.sdram.read_bytes, (unsigned long long)s.sdram.write_bytes);
	if (timing)
		printf("  SDRAM row hits %llu, row misses %llu, busy %.1f%%; %llu core cycles\n",
		       (unsigned long long)s.sdram.row_hits,
		       (unsigned long long)(s.sdram.row_empty + s.sdram.row_conflicts),
		       s.now_ticks ? 100.0 * (double)s.sdram.busy_ticks / (double)s.now_ticks : 0.0,
		       (unsigned long long)cycles);
	printf("  replay speed: %.1f million requests per host second (%.3f s)\n",
	       secs > 0 ? (double)n / secs / 1e6 : 0.0, secs);
	if (json) {
		jsonw w;
		if (jsonw_open(&w, json, &d))
			goto out;
		hier_write_json(&s, &w);
		if (jsonw_close(&w, &d))
			goto out;
	}
	ret = 0;
out:
	if (ret)
		fail(&d);
	if (have_mp)
		mem_free(&mp);
	if (e)
		eng_destroy(e);
	while (nl1 > 0)
		cache_free(&l1[--nl1]);
	if (have_vma)
		vma_free(&v);
	mtr_close_read(rdp);
	free(rdp);
	return ret;
}
