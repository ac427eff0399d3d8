/*
 * test_memsys_chip.c: the memory hierarchy wired into the chip (issue 4):
 * the default config renders kernel-ref's image through the hierarchy;
 * a scene larger than on-board memory renders the same image through the
 * VMA with PCI traffic, or is refused without it; disabling the tag cache
 * raises meta-data traffic; a warm static second frame moves nothing over
 * PCI; the counters add up across levels; per-frame snapshots cover the
 * run; a frame's cycles and read latency grow with the CAS latency; the
 * PCI bytes are the on-board cache's line fills, timed and functional.
 * Scenes: the embedded one and SPD balls (1.3 MB image, larger than a
 * 1 MB board).
 */
#include <string.h>

#include "mem/hier.h"
#include "tests/chiptest.h"

static void cfg_small(saar_config *c, int size)
{
	cfg_defaults(c);
	c->frame.width = c->frame.height = size;
}

static void cfg_vma(saar_config *c, int size, int mb)
{
	cfg_small(c, size);
	c->memory.vma.enabled = true;
	c->memory.sdram.mb = mb;
}

static hier_stats stats_of(const chip *ch)
{
	hier_stats s;
	cr_assert_eq(hier_get_stats(&ch->mem, &s), 0, "not a hierarchy");
	return s;
}

static uint64_t meta_accesses(const hier_stats *s)
{
	return s->memif.reads[MEMIF_META] + s->memif.writes[MEMIF_META];
}

/* hits + misses = accesses (lines) for every cache; the port's counts equal
 * the hierarchy's; without VMA each L1's fill bytes are what its requester
 * asked of the memory interface; memif bytes = SDRAM bytes; with VMA the
 * host bus carries the fetched lines plus the write-around bytes. */
static void assert_consistent(const chip *ch)
{
	hier_stats s = stats_of(ch);
	for (int t = 0; t < MEM_NTYPES; t++) {
		const cache_stats *c = &s.l1[t];
		cr_assert_eq(c->hits + c->misses, c->accesses, "l1 %s", mem_type_name(t));
		cr_assert_eq(c->fills * hier_l1_params(&ch->cfg, t).line_bytes, c->fill_bytes);
		cr_assert_eq(s.reads[t], ch->mem.n.reads[t]);
		cr_assert_eq(s.read_bytes[t], ch->mem.n.read_bytes[t]);
		cr_assert_eq(s.writes[t], ch->mem.n.writes[t]);
		/* spills (writes, bypassing reads) add their own bytes */
		if (!s.vma_enabled && !s.writes[t] && !s.bypass_reads[t])
			cr_assert_eq(c->fill_bytes, s.memif.bytes[t], "l1 %s fill bytes vs memif",
			             mem_type_name(t));
		else if (!s.vma_enabled)
			cr_assert_geq(s.memif.bytes[t], c->fill_bytes + s.write_bytes[t]);
	}
	uint64_t mi = 0;
	for (int r = 0; r < MEMIF_NREQ; r++)
		mi += s.memif.bytes[r];
	cr_assert_eq(mi, s.sdram.read_bytes + s.sdram.write_bytes, "memif vs SDRAM bytes");
	if (s.vma_enabled) {
		cr_assert_eq(s.tag_cache.hits + s.tag_cache.misses, s.tag_cache.accesses);
		cr_assert_eq(s.l2.hits + s.l2.misses, s.l2.accesses);
		cr_assert_eq(s.vma.meta_bytes, s.memif.bytes[MEMIF_META]);
		cr_assert_eq(s.hostbus.bytes,
		             s.vma.host_fetches * (uint64_t)ch->cfg.memory.vma.line +
		                 s.vma.host_write_bytes + s.vma.writeback_bytes);
	}
	/* the last per-frame snapshot is the whole run */
	const hier_stats *last = &ch->frame_mem[ch->frames_done - 1];
	cr_assert_eq(last->sdram.read_bytes, s.sdram.read_bytes);
	cr_assert_eq(last->l1[MEM_KD].accesses, s.l1[MEM_KD].accesses);
}

TestSuite(memsys_chip, .timeout = 600);

Test(memsys_chip, default_is_hierarchy_and_identical_embedded)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	cfg_small(&c, 128);
	cr_assert_eq(c.memory.model, CFG_MEM_HIERARCHY);
	chip *ch = tu_run_chip(&w, &c);
	cr_assert(hier_is(&ch->mem));
	tu_assert_identical(ch, "embedded, hierarchy");
	hier_stats s = stats_of(ch);
	cr_assert_gt(s.sdram.read_bytes, 0);
	cr_assert_eq(s.vma_enabled, 0);
	assert_consistent(ch);
	/* a triangle fetch is one 36-byte record, one triangle-cache line
	 * (the triangle region starts on a multiple of 36; when it did not,
	 * every fetch touched two lines) */
	cr_assert_eq(s.l1[MEM_TRI].accesses, s.reads[MEM_TRI], "tri lines %llu per %llu fetches",
	             (unsigned long long)s.l1[MEM_TRI].accesses,
	             (unsigned long long)s.reads[MEM_TRI]);
	chip_destroy(ch);
	world_free(&w);
}

Test(memsys_chip, conference_128_identical_with_hierarchy)
{
	char views[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	world w;
	tu_load_world(&w, NULL, views, "conference");
	saar_config c;
	cfg_small(&c, 128);
	chip *ch = tu_run_chip(&w, &c);
	tu_assert_identical(ch, "conference, hierarchy");
	assert_consistent(ch);
	chip_destroy(ch);
	world_free(&w);
}

Test(memsys_chip, image_larger_than_board_needs_vma)
{
	world w;
	tu_load_world(&w, "spd:balls:2", NULL, NULL);
	cr_assert_gt(w.m.size, 1u << 20, "the scene must not fit a 1 MB board");
	saar_config c;
	cfg_small(&c, 32);
	c.memory.sdram.mb = 1;
	diag d;
	chip *ch = chip_create(&c, &w, &d);
	cr_assert_null(ch);
	cr_assert(strstr(d.msg, "configs/saarcor-vma.yaml"), "%s", d.msg);
	cr_assert_null(strchr(d.msg, '\n'));
	world_free(&w);
}

Test(memsys_chip, vma_renders_identical_image_with_pci_traffic)
{
	world w;
	tu_load_world(&w, "spd:balls:2", NULL, NULL);
	saar_config c;
	cfg_vma(&c, 64, 1);
	chip *ch = tu_run_chip(&w, &c);
	tu_assert_identical(ch, "balls through the VMA");
	hier_stats s = stats_of(ch);
	cr_assert_gt(s.hostbus.bytes, 0, "no PCI traffic");
	cr_assert_gt(s.vma.host_fetches, 0);
	cr_assert_gt(meta_accesses(&s), 0);
	assert_consistent(ch);
	chip_destroy(ch);
	world_free(&w);
}

Test(memsys_chip, no_tag_cache_raises_meta_data_accesses)
{
	world w;
	tu_load_world(&w, "spd:balls:2", NULL, NULL);
	saar_config c;
	cfg_vma(&c, 32, 1);
	chip *with = tu_run_chip(&w, &c);
	c.memory.vma.tag_cache_enabled = false;
	chip *without = tu_run_chip(&w, &c);
	hier_stats a = stats_of(with), b = stats_of(without);
	cr_assert_gt(meta_accesses(&b), meta_accesses(&a), "meta %llu without vs %llu with",
	             (unsigned long long)meta_accesses(&b), (unsigned long long)meta_accesses(&a));
	cr_assert_eq(b.tag_cache.hits, 0);
	tu_assert_identical(without, "no tag cache");
	assert_consistent(without);
	chip_destroy(with);
	chip_destroy(without);
	world_free(&w);
}

Test(memsys_chip, warm_second_frame_moves_nothing_over_pci)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	cfg_vma(&c, 64, 64); /* 64 MB board, 0.4 MB scene */
	c.frame.frames = 2;
	chip *ch = tu_run_chip(&w, &c);
	cr_assert_eq(ch->frames_done, 2);
	const hier_stats *f1 = &ch->frame_mem[0], *f2 = &ch->frame_mem[1];
	cr_assert_gt(f1->hostbus.bytes, 0, "the first frame fetches the scene");
	cr_assert_eq(f2->hostbus.bytes, f1->hostbus.bytes, "frame 2 moved %llu PCI bytes",
	             (unsigned long long)(f2->hostbus.bytes - f1->hostbus.bytes));
	/* warm caches: frame 2 misses less and finishes sooner */
	cr_assert_lt(f2->l1[MEM_KD].misses - f1->l1[MEM_KD].misses, f1->l1[MEM_KD].misses);
	cr_assert_lt(ch->frame_cycles[1], ch->frame_cycles[0]);
	tu_assert_identical(ch, "second frame");
	assert_consistent(ch);
	chip_destroy(ch);
	world_free(&w);
}

Test(memsys_chip, fixed_model_still_available)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	cfg_small(&c, 64);
	c.memory.model = CFG_MEM_FIXED;
	chip *ch = tu_run_chip(&w, &c);
	cr_assert_not(hier_is(&ch->mem));
	cr_assert_null(ch->frame_mem);
	tu_assert_identical(ch, "fixed model");
	chip_destroy(ch);
	world_free(&w);
}

/* Mistake: the SDRAM ignores the CAS latency (memory.sdram.cl): CL taken
 * as 0, or a read's data coming with its column command. On the embedded
 * room at CL 2, 5 and 9 SDRAM cycles, a frame's cycles must grow with CL,
 * and so must the memory interface's mean read latency (submit to data),
 * by at least the CL step: every read waits CL once more (measured: 18.6,
 * 23.9, 31.1 SDRAM cycles; reads that skip CL grow by under one cycle). */
Test(memsys_chip, frame_cycles_grow_with_cas_latency)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	cfg_small(&c, 32);
	static const int cl[] = {2, 5, 9};
	uint64_t cyc[3];
	double lat[3];
	for (int i = 0; i < 3; i++) {
		c.memory.sdram.cl = cl[i];
		chip *ch = tu_run_chip(&w, &c);
		cyc[i] = chip_cycles(ch);
		hier_stats s = stats_of(ch);
		uint64_t ticks = 0, reads = 0;
		for (int r = 0; r < MEMIF_NREQ; r++) {
			ticks += s.memif.latency_ticks[r];
			reads += s.memif.reads[r];
		}
		cr_assert_gt(reads, 1000);
		/* in SDRAM cycles */
		lat[i] = (double)ticks / (double)reads /
		         (double)eng_clock_mhz(c.memory.sdram.clock_mhz).period;
		chip_destroy(ch);
	}
	for (int i = 1; i < 3; i++) {
		cr_assert_gt(cyc[i], cyc[i - 1], "CL %d: %llu cycles, CL %d: %llu", cl[i],
		             (unsigned long long)cyc[i], cl[i - 1], (unsigned long long)cyc[i - 1]);
		cr_assert_geq(lat[i] - lat[i - 1], cl[i] - cl[i - 1],
		              "mean read latency %.2f SDRAM cycles at CL %d, %.2f at CL %d", lat[i],
		              cl[i], lat[i - 1], cl[i - 1]);
	}
	world_free(&w);
}

/* Mistake: the PCI bytes are not counted (the host bus, or the VMA's
 * functional walk, moves lines without adding their bytes), so a run
 * through the VMA reports 0 PCI MB while the bus was busy. Through a
 * 1 MB board, timed and functional: the bus is busy, and its bytes are
 * exactly the lines fetched into the on-board cache (its fills) times the
 * line size, plus the bytes written around it. */
Test(memsys_chip, pci_bytes_are_the_fetched_lines)
{
	world w;
	tu_load_world(&w, "spd:balls:2", NULL, NULL);
	for (int f = 0; f < 2; f++) {
		saar_config c;
		cfg_vma(&c, 32, 1);
		c.fidelity = f ? CFG_FIDELITY_FUNCTIONAL : CFG_FIDELITY_CYCLE;
		const char *mode = f ? "functional" : "cycle";
		chip *ch = tu_run_chip(&w, &c);
		hier_stats s = stats_of(ch);
		uint64_t busy = f ? s.func_hostbus_busy_ticks : s.hostbus.busy_ticks;
		cr_assert_gt(busy, 0, "%s: the host bus was never busy", mode);
		cr_assert_gt(s.l2.fills, 0, "%s", mode);
		cr_assert_eq(s.hostbus.bytes,
		             s.l2.fills * (uint64_t)c.memory.vma.line + s.vma.host_write_bytes,
		             "%s: %llu PCI bytes for %llu line fills of %d bytes", mode,
		             (unsigned long long)s.hostbus.bytes, (unsigned long long)s.l2.fills,
		             c.memory.vma.line);
		chip_destroy(ch);
	}
	world_free(&w);
}
