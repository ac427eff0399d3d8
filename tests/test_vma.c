/*
 * test_vma.c: the hierarchy model behind the memory port, with and without
 * the VMA: every read is answered; a working set larger than on-board memory
 * moves lines over PCI, one that fits moves 0 bytes on its second pass;
 * disabling the tag cache raises meta-data SDRAM accesses; every fetched
 * line is written on board with its meta-data record; counters are
 * consistent (hits + misses = accesses, bytes add up across levels); an
 * image too large for on-board memory without VMA is a clear error.
 */
#include <string.h>

#include "mem/hier_level.h"
#include "sim/config.h"
#include "sim/memconfig.h"
#include "sim/report_mem.h"
#include "tests/testutil.h"

typedef struct drv {
	eng *e;
	memport *mp;
	eng_clock clk;
	uint64_t issued, answered, n, base, span, stride;
	int per_cycle, type;
	uint32_t bytes;
	uint64_t last_done;
} drv;

static void answered(eng *e, void *ctx, uint64_t arg)
{
	drv *d = ctx;
	d->answered++;
	d->last_done = eng_now(e);
}

/* Issues per_cycle reads every core cycle: a strided sweep over span. */
static void issue(eng *e, void *ctx, uint64_t arg)
{
	drv *d = ctx;
	for (int k = 0; k < d->per_cycle && d->issued < d->n; k++, d->issued++) {
		uint64_t a = d->base + (d->issued * d->stride) % d->span;
		mem_req r = {a, d->bytes, (uint8_t)d->type, 0, 0, NULL, 0};
		mem_access(d->mp, &r, answered, d, 0);
	}
	if (d->issued < d->n)
		eng_schedule(e, eng_now(e) + d->clk.period, issue, d, 0);
}

static void run_pass(drv *d, uint64_t n)
{
	d->n += n;
	eng_schedule(d->e, eng_next_edge(d->clk, eng_now(d->e)), issue, d, 0);
	eng_run(d->e, ENG_FOREVER);
	cr_assert_eq(d->answered, d->issued, "every read answered");
}

static void setup(saar_config *c, int use_vma, int sdram_mb)
{
	cfg_defaults(c);
	c->memory.model = CFG_MEM_HIERARCHY;
	c->memory.vma.enabled = use_vma;
	c->memory.sdram.mb = sdram_mb;
}

static void check_consistent(const hier_stats *s)
{
	for (int t = 0; t < MEM_NTYPES; t++)
		cr_assert_eq(s->l1[t].hits + s->l1[t].misses, s->l1[t].accesses);
	uint64_t reads = 0, bytes = 0;
	for (int r = 0; r < MEMIF_NREQ; r++) {
		reads += s->memif.reads[r];
		bytes += s->memif.bytes[r];
	}
	/* every memif request reached SDRAM, and the bytes add up */
	cr_assert_eq(reads, s->sdram.reads);
	cr_assert_eq(bytes, s->sdram.read_bytes + s->sdram.write_bytes);
	cr_assert_eq(s->sdram.row_hits + s->sdram.row_empty + s->sdram.row_conflicts > 0, 1);
	if (s->vma_enabled) {
		cr_assert_eq(s->l2.hits + s->l2.misses, s->l2.accesses);
		cr_assert_eq(s->vma.host_fetch_bytes + s->vma.host_write_bytes +
		                 s->vma.writeback_bytes,
		             s->hostbus.bytes);
		cr_assert_eq(s->vma.meta_reads + s->vma.meta_writes,
		             s->memif.reads[MEMIF_META] + s->memif.writes[MEMIF_META]);
		cr_assert_eq(s->vma.meta_bytes, s->memif.bytes[MEMIF_META]);
		cr_assert_eq(s->l2.fills, s->vma.host_fetches);
	}
}

Test(hier, no_vma_bytes_add_up)
{
	saar_config c;
	setup(&c, 0, 64);
	eng *e = eng_create(64);
	eng_clock clk = eng_clock_mhz(533);
	memport mp;
	diag d;
	cr_assert_eq(mem_init_hier(&mp, e, clk, &c, 8 << 20, NULL, &d), 0, "%s", d.msg);
	drv v = {e, &mp, clk, 0, 0, 0, 0, 1 << 20, 36, 4, MEM_TRI, 36, 0};
	run_pass(&v, 100000);
	hier_stats s;
	cr_assert_eq(hier_get_stats(&mp, &s), 0);
	check_consistent(&s);
	/* 1 MB of 36-byte triangles, 100000 reads: 3.6 MB > 144 KB: misses */
	cr_assert_gt(s.l1[MEM_TRI].misses, 0);
	cr_assert_eq(s.l1[MEM_TRI].fill_bytes, s.memif.bytes[MEMIF_TRI]);
	cr_assert_eq(s.l1[MEM_TRI].fills, s.memif.reads[MEMIF_TRI]);
	cr_assert_eq(s.reads[MEM_TRI], 100000);
	cr_assert_gt(s.wait_cycles[MEM_TRI], 100000 * 2 - 1);
	/* JSON is well formed enough to contain the keys */
	char *buf = NULL;
	size_t len = 0;
	FILE *f = open_memstream(&buf, &len);
	jsonw w;
	jsonw_init_file(&w, f);
	hier_write_json(&s, &w);
	fclose(f);
	cr_assert(strstr(buf, "\"row_hit_rate\"") && strstr(buf, "\"tri\""), "%s", buf);
	free(buf);
	mem_free(&mp);
	eng_destroy(e);
}

Test(hier, image_too_large_without_vma)
{
	saar_config c;
	setup(&c, 0, 1);
	eng *e = eng_create(4);
	memport mp;
	diag d;
	cr_assert_neq(mem_init_hier(&mp, e, eng_clock_mhz(533), &c, 3 << 20, NULL, &d), 0);
	cr_assert(strstr(d.msg, "saarcor-vma.yaml"), "%s", d.msg);
	eng_destroy(e);
}

Test(hier, hit_latency_exact)
{
	saar_config c;
	setup(&c, 0, 64);
	/* a value of the test's own, not the config's default (which the
	 * calibration may move) */
	c.memory.l1.kd.hit_latency = 3;
	eng *e = eng_create(16);
	eng_clock clk = eng_clock_mhz(533);
	memport mp;
	diag d;
	cr_assert_eq(mem_init_hier(&mp, e, clk, &c, 1 << 20, NULL, &d), 0, "%s", d.msg);
	drv v = {e, &mp, clk, 0, 0, 0, 0, 64, 8, 1, MEM_KD, 8, 0};
	run_pass(&v, 1); /* a miss */
	uint64_t t0 = eng_now(e) + clk.period * 10;
	t0 = eng_next_edge(clk, t0);
	eng_schedule(e, t0, issue, &v, 0);
	v.n = 2;
	v.base = 0;
	v.stride = 0;
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(v.last_done, t0 + 3 * clk.period, "hit in hit_latency cycles");
	mem_free(&mp);
	eng_destroy(e);
}

static hier_stats vma_run(int tag_cache, int sdram_mb, uint64_t span, int passes,
                          uint64_t *pci_per_pass)
{
	saar_config c;
	setup(&c, 1, sdram_mb);
	c.memory.vma.tag_cache_enabled = tag_cache;
	c.memory.vma.tag_cache_kb = 4; /* small: meta-data misses show */
	eng *e = eng_create(64);
	eng_clock clk = eng_clock_mhz(533);
	memport mp;
	diag d;
	cr_assert_eq(mem_init_hier(&mp, e, clk, &c, 64 << 20, NULL, &d), 0, "%s", d.msg);
	/* 64-byte shading records: each L1 miss is an 8-byte line */
	drv v = {e, &mp, clk, 0, 0, 0, 4096, span, 64, 2, MEM_SHADE, 8, 0};
	hier_stats s;
	uint64_t prev = 0;
	for (int p = 0; p < passes; p++) {
		run_pass(&v, span / 64);
		hier_get_stats(&mp, &s);
		if (pci_per_pass)
			pci_per_pass[p] = s.hostbus.bytes - prev;
		prev = s.hostbus.bytes;
	}
	check_consistent(&s);
	mem_free(&mp);
	eng_destroy(e);
	return s;
}

Test(vma, larger_than_board_uses_pci)
{
	uint64_t pci[2];
	/* 3 MB swept twice through 1 MB on board: the second pass misses again */
	hier_stats s = vma_run(1, 1, 3 << 20, 2, pci);
	cr_assert_gt(pci[0], 0);
	cr_assert_gt(pci[1], 0);
	cr_assert_gt(s.vma.host_fetches, (3u << 20) / 128);
	cr_assert_gt(s.memif.reads[MEMIF_META] + s.memif.writes[MEMIF_META], 0);
}

Test(vma, fitting_set_second_pass_no_pci)
{
	uint64_t pci[2];
	/* 512 KB twice through 1 MB on board (the 64 KB shading L1 cannot hold
	 * it, so the second pass reaches the L2 and hits there) */
	hier_stats s = vma_run(1, 1, 512 << 10, 2, pci);
	cr_assert_eq(pci[0], (512u << 10), "first pass fetches every line once");
	cr_assert_eq(pci[1], 0, "second pass: %llu bytes over PCI", (unsigned long long)pci[1]);
	cr_assert_gt(s.l2.hits, 0);
}

Test(vma, no_tag_cache_more_meta_accesses)
{
	hier_stats with = vma_run(1, 1, 512 << 10, 2, NULL);
	hier_stats without = vma_run(0, 1, 512 << 10, 2, NULL);
	uint64_t mw = with.memif.reads[MEMIF_META], mo = without.memif.reads[MEMIF_META];
	cr_assert_gt(mo, mw, "meta reads: %llu without vs %llu with tag cache",
	             (unsigned long long)mo, (unsigned long long)mw);
	cr_assert_eq(without.tag_cache.accesses, 0);
	cr_assert_gt(with.tag_cache.hits, 0);
}

/* Mistake: a line fetched over PCI is not written into the on-board
 * memory (the FILL write is dropped), or its meta-data record is not
 * updated: later reads of it would find it missing. Every host fetch
 * writes its line (FILL) and its set's record (META) through the memory
 * interface. */
Test(vma, fetched_lines_are_written_on_board)
{
	saar_config c;
	setup(&c, 1, 1);
	hier_stats s = vma_run(1, 1, 512 << 10, 2, NULL);
	uint64_t f = s.vma.host_fetches;
	cr_assert_gt(f, 0);
	cr_assert_eq(s.memif.writes[MEMIF_FILL], f, "%llu FILL writes for %llu fetches",
	             (unsigned long long)s.memif.writes[MEMIF_FILL], (unsigned long long)f);
	cr_assert_eq(s.memif.bytes[MEMIF_FILL], f * (uint64_t)c.memory.vma.line);
	cr_assert_eq(s.memif.writes[MEMIF_META], f, "%llu META writes for %llu fetches",
	             (unsigned long long)s.memif.writes[MEMIF_META], (unsigned long long)f);
	cr_assert_eq(s.vma.meta_writes, f);
}

static void vma_answered(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	(*(int *)ctx)++;
}

/* A VMA hierarchy over a 1 MB board with unhashed sets and a 4 KB image
 * (the reads above it bypass the L1s), for tests that place lines in
 * chosen on-board sets. */
typedef struct vma_rig {
	eng *e;
	memport mp;
	hier *h;
	int done;
} vma_rig;

static void vma_rig_init(vma_rig *r)
{
	saar_config c;
	setup(&c, 1, 1);
	c.memory.vma.hash = CFG_HASH_NONE;
	hier_params hp;
	diag d;
	cr_assert_eq(memcfg_hier(&c, &hp, &d), 0, "%s", d.msg);
	r->e = eng_create(64);
	cr_assert_eq(hier_init(&r->mp, r->e, eng_clock_mhz(533), &hp, 4096, NULL, &d), 0, "%s",
	             d.msg);
	r->h = r->mp.impl;
	r->done = 0;
}

/* One access of kd line `line` (a posted write, or a read), timed or
 * functional, run to its end. */
static void vma_rig_access(vma_rig *r, uint64_t line, int write, int timed)
{
	mem_req q = {line * r->h->v.p.line, 8, MEM_KD, (uint8_t)write, 0, NULL, 0};
	if (!timed)
		mem_access_func(&r->mp, &q);
	else
		mem_access(&r->mp, &q, write ? NULL : vma_answered, &r->done, 0);
	eng_run(r->e, ENG_FOREVER);
}

static void vma_rig_free(vma_rig *r)
{
	mem_free(&r->mp);
	eng_destroy(r->e);
}

/* A write into an on-board line is a use of it for the replacement, as a
 * read's hit is: four lines A-D fill one on-board set (A the least
 * recent), A is written (dirty), a fifth line E of the set is read: the
 * victim is B, not the line just written, so nothing is written back.
 * Timed and functional alike. Catches the write leaving the line's
 * recency as it was (A evicted at once and written back over PCI). */
Test(vma, a_write_is_a_use_of_its_line)
{
	for (int timed = 0; timed < 2; timed++) {
		vma_rig r;
		vma_rig_init(&r);
		uint64_t ns = r.h->v.l2.c.nsets, A = 1000;
		uint64_t seq[] = {A, A + ns, A + 2 * ns, A + 3 * ns, A, A + 4 * ns};
		for (int k = 0; k < 6; k++)
			vma_rig_access(&r, seq[k], k == 4, timed);
		hier_stats s;
		cr_assert_eq(hier_get_stats(&r.mp, &s), 0);
		cr_assert_eq(s.vma.host_fetches, 5, "%s: five lines fetched",
		             timed ? "timed" : "functional");
		cr_assert_eq(s.vma.writebacks, 0, "%s: the line just written was evicted",
		             timed ? "timed" : "functional");
		vma_rig_free(&r);
	}
}

/* A spill write reads its set's meta-data record like any on-board access
 * (§4.2) and writes it back when it dirties its line: line A is read (its
 * record now in the tag cache), written (clean to dirty: one record
 * write, no read), written again (already dirty: nothing), and line B of
 * another set, never read, is written around the board (its record read
 * from SDRAM, none written). Timed and functional alike, and the memory
 * interface's meta traffic is the VMA's. Catches writes that take no
 * meta-data at all (the model until session 61). */
Test(vma, a_write_reads_and_writes_meta_data)
{
	for (int timed = 0; timed < 2; timed++) {
		vma_rig r;
		vma_rig_init(&r);
		uint64_t A = 1000;
		const char *what = timed ? "timed" : "functional";
		/* read A, write A, write A, write B; the meta counts after each */
		uint64_t seq[] = {A, A, A, A + 1}, reads[4], writes[4];
		for (int k = 0; k < 4; k++) {
			vma_rig_access(&r, seq[k], k > 0, timed);
			hier_stats s;
			cr_assert_eq(hier_get_stats(&r.mp, &s), 0);
			reads[k] = s.vma.meta_reads;
			writes[k] = s.vma.meta_writes;
			if (timed)
				cr_assert_eq(s.memif.bytes[MEMIF_META], s.vma.meta_bytes,
				             "memif meta bytes = the VMA's, after access %d", k);
		}
		cr_assert_eq(reads[1], reads[0], "%s: A's record is in the tag cache", what);
		cr_assert_eq(writes[1], writes[0] + 1, "%s: A made dirty: its record written",
		             what);
		cr_assert_eq(reads[2] - reads[1] + writes[2] - writes[1], 0,
		             "%s: A already dirty: no meta-data traffic", what);
		cr_assert_eq(reads[3], reads[2] + 1, "%s: B's record read from SDRAM", what);
		cr_assert_eq(writes[3], writes[2], "%s: B written around: no record write", what);
		vma_rig_free(&r);
	}
}
