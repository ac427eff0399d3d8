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

#include "kernel-ref/atomicfile.h"
#include "sim/config.h"
#include "sim/memconfig.h"
#include "sim/report_mem.h"
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
		mem_req r = {f->next.addr, f->next.bytes, f->next.type, f->next.write, 0, NULL, 0};
		mem_access(f->mp, &r, r.write ? NULL : answered, f, 0);
		f->issued++;
		next_rec(f);
	}
	if (f->have)
		eng_schedule(e, eng_cycles_to_ticks(f->clk, f->next.cycle), feed, f, 0);
}

/* ---- the command line ---- */

typedef struct opts {
	saar_config cfg;
	cfg_origin origin; /* where each value came from (memcfg_validate names it) */
	const char *trace, *json;
	int timing;
	uint64_t image_bytes; /* reads at or above it bypass the L1s */
} opts;

/* --image-bytes' value: digits only (strtoull takes "", "-1" and " 7"), at
 * most 2^48 (no memory image is larger). 0, or -1 after the message. */
static int parse_image_bytes(const char *v, uint64_t *out)
{
	char *end;
	errno = 0;
	*out = strtoull(v, &end, 10);
	if (!*v || strspn(v, "0123456789") != strlen(v) || errno || *out > (1ull << 48)) {
		fprintf(stderr,
		        "saarsim-replay: --image-bytes: expected a byte count 0..2^48, got '%s'\n",
		        v);
		return -1;
	}
	return 0;
}

/* Reads the arguments into o (the config loaded, set and validated).
 * Returns -1 to go on, else the exit status (0 after --help). */
static int parse_args(int argc, char **argv, opts *o, diag *d)
{
	cfg_defaults(&o->cfg);
	memset(&o->origin, 0, sizeof o->origin);
	o->trace = o->json = NULL;
	o->timing = 0;
	o->image_bytes = UINT64_MAX;
	const char *cfgfile = NULL;
	int image_bytes_given = 0;
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
			if (cfgfile) {
				fprintf(
				    stderr,
				    "saarsim-replay: --config given twice (it takes one value)\n");
				return DIAG_EXIT;
			}
			cfgfile = argv[++i];
		} else if (!strcmp(a, "--set") && i + 1 < argc) {
			i++; /* applied below, once the file is read */
		} else if (!strcmp(a, "--timing")) {
			o->timing = 1;
		} else if (!strcmp(a, "--image-bytes") && i + 1 < argc) {
			if (image_bytes_given++) {
				fprintf(stderr,
				        "saarsim-replay: --image-bytes given twice (it takes one "
				        "value)\n");
				return DIAG_EXIT;
			}
			if (parse_image_bytes(argv[++i], &o->image_bytes))
				return DIAG_EXIT;
		} else if (!strcmp(a, "--json") && i + 1 < argc) {
			if (o->json) {
				fprintf(
				    stderr,
				    "saarsim-replay: --json given twice (it takes one value)\n");
				return DIAG_EXIT;
			}
			o->json = argv[++i];
		} else if (a[0] == '-' && a[1]) {
			char what[256];
			snprintf(what, sizeof what, "%s: unknown option or missing value", a);
			return usage(what);
		} else if (!o->trace) {
			o->trace = a;
		} else {
			return usage("more than one trace");
		}
	}
	if (!o->trace)
		return usage("no trace given");
	/* the file first, then every --set in order (as saarsim: a --set
	 * before --config is not undone by it) */
	if (cfgfile && cfg_load_at(&o->cfg, cfgfile, &o->origin, d))
		return fail(d);
	for (int i = 1; i < argc; i++) { /* the same walk: every option took its value */
		const char *a = argv[i];
		if (!strcmp(a, "--set") && cfg_set_at(&o->cfg, "--set", argv[i + 1], &o->origin, d))
			return fail(d);
		if (!strcmp(a, "--set") || !strcmp(a, "--config") || !strcmp(a, "--image-bytes") ||
		    !strcmp(a, "--json"))
			i++;
	}
	if (memcfg_validate(&o->cfg, &o->origin, d))
		return fail(d);
	return -1;
}

/* ---- the two replays: the figures into s, requests into *n, the last
 * cycle into *cycles; 0, or -1 with d set ---- */

/* Timed: each request issued at its trace cycle into the full hierarchy. */
static int replay_timed(const opts *o, mtr_reader *rdp, hier_stats *s, uint64_t *n,
                        uint64_t *cycles, diag *d)
{
	const saar_config *cfg = &o->cfg;
	eng *e = eng_create(1024);
	eng_clock clk = eng_clock_mhz(cfg->chip.clock_mhz);
	/* The trace carries no image size. Without --image-bytes: with the VMA
	 * every address is image; without it, whatever fits on board is
	 * (reads above it take the spill-area path past the L1s). */
	uint64_t img = o->image_bytes;
	if (img == UINT64_MAX && !cfg->memory.vma.enabled)
		img = (uint64_t)cfg->memory.sdram.mb << 20;
	if (!e)
		return diag_set(d, o->trace, 0, 0, "out of memory");
	memport mp;
	if (mem_init_hier(&mp, e, clk, cfg, img, NULL, d)) {
		eng_destroy(e);
		return -1;
	}
	/* a quarter of the tick range: room for the hierarchy's latencies */
	feeder f = {e, clk, &mp, rdp, {0}, (UINT64_MAX >> 2) / clk.period, 0, 0, 0, 0, d};
	int rc = next_rec(&f) < 0 ? -1 : 0;
	if (!rc) {
		if (f.have)
			eng_schedule(e, eng_cycles_to_ticks(clk, f.next.cycle), feed, &f, 0);
		eng_run(e, ENG_FOREVER);
		rc = f.err ? -1 : 0;
	}
	if (!rc) {
		*n = f.issued;
		*cycles = eng_now(e) / clk.period;
		hier_get_stats(&mp, s);
	}
	mem_free(&mp);
	eng_destroy(e);
	return rc;
}

/* The functional replay's state: the L1s with immediate fills, the VMA's
 * functional path or plain SDRAM byte counts behind them. */
typedef struct func_replay {
	cache l1[MEM_NTYPES];
	int nl1; /* L1s made */
	vma v;
	int use_vma, have_vma;
	/* per type, hoisted: line size (and its log2 when a power of two);
	 * all addresses below 4 GiB (the usual case) divide in 32 bits */
	uint32_t lbs[MEM_NTYPES];
	int lsh[MEM_NTYPES];
	uint64_t image_bytes, sd_read, sd_write;
} func_replay;

static int func_init(func_replay *fr, const saar_config *cfg, diag *d)
{
	for (; fr->nl1 < MEM_NTYPES; fr->nl1++) {
		cache_params cp = hier_l1_params(cfg, fr->nl1);
		char what[32];
		snprintf(what, sizeof what, "memory.l1.%s", mem_type_name(fr->nl1));
		if (cache_init(&fr->l1[fr->nl1], &cp, what, d))
			return -1;
	}
	fr->use_vma = cfg->memory.vma.enabled;
	if (fr->use_vma) {
		vma_params vp = hier_vma_params(cfg);
		if (vma_init(&fr->v, NULL, eng_clock_mhz(cfg->chip.clock_mhz), NULL, NULL,
		             (uint64_t)cfg->memory.sdram.mb << 20, &vp, NULL, d))
			return -1;
		fr->have_vma = 1;
	}
	for (int t = 0; t < MEM_NTYPES; t++) {
		fr->lbs[t] = fr->l1[t].p.line_bytes;
		fr->lsh[t] = -1;
		for (int b = 0; b < 32; b++)
			if (fr->lbs[t] == 1u << b)
				fr->lsh[t] = b;
	}
	return 0;
}

static void func_free(func_replay *fr)
{
	while (fr->nl1 > 0)
		cache_free(&fr->l1[--fr->nl1]);
	if (fr->have_vma)
		vma_free(&fr->v);
}

/* One request: a write or a spill-area read goes past the L1s; a read
 * looks up every line it touches and fills the missing ones. */
static inline void func_request(func_replay *fr, const mtr_rec *r, hier_stats *s)
{
	int t = r->type;
	uint64_t addr = r->addr;
	if (r->write) {
		s->writes[t]++;
		s->write_bytes[t] += r->bytes;
		if (fr->use_vma)
			vma_access_func(&fr->v, addr, r->bytes, 1, NULL);
		else
			fr->sd_write += r->bytes;
		return;
	}
	s->reads[t]++;
	s->read_bytes[t] += r->bytes;
	if (addr >= fr->image_bytes) {
		s->bypass_reads[t]++;
		if (fr->use_vma)
			vma_access_func(&fr->v, addr, r->bytes, 0, NULL);
		else
			fr->sd_read += r->bytes;
		return;
	}
	cache *c = &fr->l1[t];
	uint32_t lb = fr->lbs[t], bytes = r->bytes ? r->bytes : 1;
	uint64_t first, end = addr + bytes - 1, last;
	if (fr->lsh[t] >= 0) {
		first = addr >> fr->lsh[t];
		last = end >> fr->lsh[t];
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
		if (cache_try_hit(c, l, per) || cache_lookup(c, l, per, NULL, NULL) == CACHE_HIT)
			continue;
		cache_fill(c, l, NULL);
		if (fr->use_vma)
			vma_access_func(&fr->v, l * lb, lb, 0, NULL);
		else
			fr->sd_read += lb;
	}
}

/* The functional replay's figures into s, in the timed replay's form. */
static void func_stats(const func_replay *fr, const saar_config *cfg, hier_stats *s)
{
	uint64_t sd_read = fr->sd_read;
	const vma *v = &fr->v;
	for (int t = 0; t < MEM_NTYPES; t++)
		s->l1[t] = fr->l1[t].s;
	s->core_period = eng_clock_mhz(cfg->chip.clock_mhz).period;
	if (fr->use_vma) {
		s->vma_enabled = 1;
		s->vma = v->s;
		s->tag_cache = v->tag.c.s;
		s->l2 = v->l2.c.s;
		s->hostbus.bytes =
		    v->s.host_fetch_bytes + v->s.host_write_bytes + v->s.writeback_bytes;
		s->hostbus.transfers = v->s.host_fetches + v->s.host_writes + v->s.writebacks;
		/* SDRAM bytes with VMA: data (reads, fills, writes) plus meta-data;
		 * the functional path does not split reads from writes */
		sd_read = v->s.data_bytes + v->s.meta_bytes + v->s.writeback_bytes;
		s->memif.bytes[MEMIF_META] = v->s.meta_bytes;
		s->memif.reads[MEMIF_META] = v->s.meta_reads;
		s->memif.writes[MEMIF_META] = v->s.meta_writes;
	}
	s->sdram.read_bytes = sd_read;
	s->sdram.write_bytes = fr->sd_write;
}

/* Functional: every request through its L1 with immediate fills. */
static int replay_functional(const opts *o, mtr_reader *rdp, hier_stats *s, uint64_t *n,
                             uint64_t *cycles, diag *d)
{
	/* the L1s' and the VMA's state is large: on the heap */
	func_replay *fr = calloc(1, sizeof *fr);
	if (!fr)
		return diag_set(d, o->trace, 0, 0, "out of memory");
	fr->image_bytes = o->image_bytes;
	int rc = func_init(fr, &o->cfg, d);
	const mtr_rec *blk;
	int got = 0;
	while (!rc && (got = mtr_read_block(rdp, &blk, d)) > 0) {
		*n += (uint64_t)got;
		*cycles = blk[got - 1].cycle;
		for (const mtr_rec *r = blk, *rend = blk + got; r < rend; r++)
			func_request(fr, r, s);
	}
	if (!rc && got < 0)
		rc = -1;
	if (!rc)
		func_stats(fr, &o->cfg, s);
	func_free(fr);
	free(fr);
	return rc;
}

/* ---- the figures ---- */

static double pct_of(uint64_t part, uint64_t whole)
{
	return whole ? 100.0 * (double)part / (double)whole : 0.0;
}

static void print_summary(const opts *o, const hier_stats *s, uint64_t n, uint64_t cycles,
                          double secs)
{
	printf("trace %s: %llu requests, last cycle %llu, %s replay\n", o->trace,
	       (unsigned long long)n, (unsigned long long)cycles,
	       o->timing ? "timed" : "functional");
	for (int t = 0; t < MEM_NTYPES; t++) {
		const cache_stats *c = &s->l1[t];
		printf("  l1.%-5s accesses %12llu  hits %12llu  misses %10llu  hit rate %6.2f%%  "
		       "merges %8llu  fill bytes %12llu\n",
		       mem_type_name(t), (unsigned long long)c->accesses,
		       (unsigned long long)c->hits, (unsigned long long)c->misses,
		       pct_of(c->hits, c->accesses), (unsigned long long)c->merges,
		       (unsigned long long)c->fill_bytes);
	}
	if (s->vma_enabled) {
		const vma_stats *v = &s->vma;
		printf("  tag cache hit rate %6.2f%%   L2 hit rate %6.2f%%   meta-data SDRAM "
		       "accesses %llu (%.1f%% of SDRAM accesses)\n",
		       pct_of(s->tag_cache.hits, s->tag_cache.accesses),
		       pct_of(s->l2.hits, s->l2.accesses),
		       (unsigned long long)(v->meta_reads + v->meta_writes),
		       100.0 * (double)(v->meta_reads + v->meta_writes) /
		           (double)(v->meta_reads + v->meta_writes + v->data_reads +
		                    v->data_writes + (v->meta_reads + v->data_reads == 0)));
		printf("  host bus: %llu bytes in %llu transfers\n",
		       (unsigned long long)s->hostbus.bytes,
		       (unsigned long long)s->hostbus.transfers);
	}
	printf("  SDRAM bytes %llu (read %llu, write %llu)\n",
	       (unsigned long long)(s->sdram.read_bytes + s->sdram.write_bytes),
	       (unsigned long long)s->sdram.read_bytes, (unsigned long long)s->sdram.write_bytes);
	if (o->timing)
		printf("  SDRAM row hits %llu, row misses %llu, busy %.1f%%; %llu core cycles\n",
		       (unsigned long long)s->sdram.row_hits,
		       (unsigned long long)(s->sdram.row_empty + s->sdram.row_conflicts),
		       pct_of(s->sdram.busy_ticks, s->now_ticks), (unsigned long long)cycles);
	printf("  replay speed: %.1f million requests per host second (%.3f s)\n",
	       secs > 0 ? (double)n / secs / 1e6 : 0.0, secs);
}

static int write_json(const char *path, const hier_stats *s, diag *d)
{
	jsonw w;
	if (jsonw_open(&w, path, d))
		return -1;
	hier_write_json(s, &w);
	return jsonw_close(&w, d);
}

int main(int argc, char **argv)
{
	static opts o;
	diag d = {{0}};
	int ret = parse_args(argc, argv, &o, &d);
	if (ret >= 0)
		return ret;
	/* the JSON's temporary now, so a missing or unwritable folder is
	 * refused before the replay, not after it (atomicfile.h) */
	if (o.json && af_reserve(o.json, "", &d))
		return fail(&d);

	/* the clock includes opening the trace (its first read) */
	double t0 = now_s();
	/* the reader holds a block buffer of hundreds of KB: on the heap */
	mtr_reader *rdp = calloc(1, sizeof *rdp);
	if (!rdp) {
		diag_set(&d, o.trace, 0, 0, "out of memory");
		return fail(&d);
	}
	if (mtr_open_read(rdp, o.trace, &d)) {
		free(rdp);
		return fail(&d);
	}
	hier_stats s;
	memset(&s, 0, sizeof s);
	uint64_t n = 0, cycles = 0;
	ret = (o.timing ? replay_timed : replay_functional)(&o, rdp, &s, &n, &cycles, &d);
	if (!ret)
		print_summary(&o, &s, n, cycles, now_s() - t0);
	if (!ret && o.json)
		ret = write_json(o.json, &s, &d);
	mtr_close_read(rdp);
	free(rdp);
	return ret ? fail(&d) : 0;
}
