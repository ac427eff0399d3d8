/*
 * test_reportcheck.c: the report's invariants (sim/reportcheck.h). Real
 * runs of every kind satisfy all of them; and each invariant can fail:
 * one figure of a real run's report spoiled at a time, as a counter that
 * stopped counting would spoil it, makes exactly that invariant (and those
 * that share the figure) fail. docs/TESTING.md ("Checks that can fail")
 * lists the mistakes also made by hand in the code.
 */
#include <string.h>

#include "sim/reportcheck.h"
#include "tests/chiptest.h"

static void cfg_small(saar_config *c, int size)
{
	cfg_defaults(c);
	c->frame.width = c->frame.height = size;
}

/* A run with the VMA (PCI traffic in frame 1), two frames, and a 2-entry
 * stack (spills and refills that bypass the L1s). */
static chip *vma_run(const world *w)
{
	saar_config c;
	cfg_small(&c, 64);
	c.memory.vma.enabled = true;
	c.frame.frames = 2;
	c.chip.stack_depth = 2;
	return tu_run_chip(w, &c);
}

static chip *plain_run(const world *w)
{
	saar_config c;
	cfg_small(&c, 64);
	c.chip.stack_depth = 2;
	return tu_run_chip(w, &c);
}

/* Every kind of run holds every invariant (tu_run_chip asserts it), and
 * the runs exercise what the invariants speak of. */
Test(reportcheck, real_runs_hold_every_invariant, .timeout = 300)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	chip *v = vma_run(&w), *p = plain_run(&w);
	rc_figs f;
	cr_assert_eq(rc_figs_get(v, &f), 0);
	cr_assert_gt(f.h.hostbus.bytes, 0, "the VMA run moves bytes over PCI");
	cr_assert_gt(f.h.bypass_reads[MEM_KD], 0, "the 2-entry stack refills");
	cr_assert_gt(f.h.vma.meta_bytes, 0);
	cr_assert_gt(f.per_frame[0].pci_util, 0);
	rc_figs_free(&f);
	chip_destroy(v);
	chip_destroy(p);
	static const char *const sets[][2] = {{"fidelity", "functional"},
	                                      {"fidelity", "sampled"},
	                                      {"memory.model", "fixed"},
	                                      {"memory.vma.tag_cache_enabled", "false"},
	                                      {"chip.masked_packets", "false"}};
	for (size_t i = 0; i < sizeof sets / sizeof *sets; i++) {
		saar_config c;
		cfg_small(&c, 96);
		c.memory.vma.enabled = i != 2;
		c.frame.frames = 2;
		char kv[128];
		diag d;
		snprintf(kv, sizeof kv, "%s=%s", sets[i][0], sets[i][1]);
		cr_assert_eq(cfg_set(&c, kv, &d), 0, "%s", d.msg);
		if (i == 1) {
			c.chip.rtps = 2; /* units of 8 tiles: rtps x threads_per_rtp */
			c.chip.threads_per_rtp = 4;
			c.sampling.rate = 0.2;
			c.sampling.min_units = 3;
			c.sampling.unit_tiles = 8;
			c.sampling.warmup_tiles = 8;
		}
		if (i == 2) { /* compute bound: a unit busy more than half the time */
			c.memory.latency = 1;
			c.chip.threads_per_rtp = 32;
			/* short pipelines of the test's own: on this 96x96 frame the
			 * calibrated latencies (docs/CALIBRATION.md) leave the units
			 * idle in the frame's tail */
			for (int k = 0; k < UNIT_NKINDS; k++)
				c.chip.unit[k].latency = 2;
		}
		chip *ch = tu_run_chip(&w, &c);
		if (i == 1)
			cr_assert(chip_estimates(&ch->cfg), "the sampled run estimates");
		if (i == 2) {
			cr_assert_eq(rc_figs_get(ch, &f), 0);
			cr_assert_gt(f.util[UNIT_ISECT], 0.5, "isect utilisation %g",
			             f.util[UNIT_ISECT]);
			rc_figs_free(&f);
		}
		chip_destroy(ch);
	}
	/* Dirty on-board lines written back (a stack spilling into a VMA on a
	 * 1 MB board), timed and functional: each write-back is an SDRAM read
	 * by the fill requester and a host-bus transfer, and the byte
	 * identities count them. Catches: identities that leave write-backs
	 * out (they were written before the VMA wrote dirty lines back, and
	 * every such run warned of three failed invariants). */
	for (int fn = 0; fn < 2; fn++) {
		saar_config c;
		cfg_small(&c, 64);
		c.memory.vma.enabled = true;
		c.memory.sdram.mb = 1;
		c.chip.stack_depth = 1;
		c.fidelity = fn ? CFG_FIDELITY_FUNCTIONAL : CFG_FIDELITY_CYCLE;
		chip *ch = tu_run_chip(&w, &c);
		hier_stats h;
		cr_assert_eq(hier_get_stats(&ch->mem, &h), 0);
		cr_assert_gt(h.vma.writebacks, 0, "%s: no dirty line written back",
		             fn ? "functional" : "cycle");
		chip_destroy(ch);
	}
	world_free(&w);
}

/* One figure spoiled: the list holds a violation naming want. */
typedef void (*spoil_fn)(rc_figs *f);

static void expect_failure(const chip *ch, spoil_fn spoil, const char *want, const char *what)
{
	rc_figs f;
	cr_assert_eq(rc_figs_get(ch, &f), 0);
	static rc_list l;
	cr_assert_eq(rc_check(&f, &l), 0, "%s: the real run already fails: %s", what, l.msg[0]);
	spoil(&f);
	int n = rc_check(&f, &l), found = 0;
	for (int i = 0; i < n && i < RC_MAX; i++)
		found |= strstr(l.msg[i], want) != NULL;
	cr_assert(found, "%s: no violation names '%s' (%d found%s%s)", what, want, n,
	          n ? "; first: " : "", n ? l.msg[0] : "");
	rc_figs_free(&f);
}

#define SPOIL(name, body)                                                                          \
	static void name(rc_figs *f)                                                               \
	{                                                                                          \
		body;                                                                              \
	}

SPOIL(frame_cycles_off, f->frame_cycles[1] += 1000)
SPOIL(fps_off, f->fps *= 1.01)
SPOIL(frame_fps_off, f->per_frame[1].fps *= 1.01)
SPOIL(frame_cycles_copy_off, f->per_frame[0].cycles += 1)
SPOIL(util_over_1, f->util[UNIT_ISECT] = 1.2)
SPOIL(rtp_util_negative, f->rtp_util[UNIT_TRAV * f->nrtp] = -0.1)
SPOIL(shares_off, f->share[0] += 0.1)
/* a state's time lost (a thread in no state for a while, or counted in
 * two): the shares, normalised by their own sum, cannot show it */
SPOIL(thread_time_off, f->thread_ps -= 1876)
SPOIL(hit_rate_over_1, f->per_frame[0].hit[MEM_KD] = 1.5)
SPOIL(sdram_util_over_1, f->steady.sdram_util = 1.3)
SPOIL(row_hit_rate_over_1, f->steady.row_hit_rate = 1.1)
SPOIL(meta_share_negative, f->per_frame[0].meta_share = -0.5)
SPOIL(pci_mb_zero, f->per_frame[0].pci_mb = 0)
SPOIL(sdram_mb_zero, f->per_frame[0].sdram_mb = 0)
SPOIL(pci_mb_off, f->per_frame[1].pci_mb += 0.5)
SPOIL(port_off, f->port.reads[MEM_TRI]++)
SPOIL(l1_hits_off, f->h.l1[MEM_KD].hits++)
SPOIL(type_steps_off, f->by_type[TC_NODE_STEPS]++)
SPOIL(type_busy_off, f->total[TC_BUSY + UNIT_ISECT]--)
SPOIL(ray_hits_off, f->h.ray_hits[PKT_SHADOW][MEM_TRI]++)
SPOIL(l1_merges_over, f->h.l1[MEM_LIST].merges = f->h.l1[MEM_LIST].misses + 1)
SPOIL(l2_fill_bytes_off, f->h.l2.fill_bytes += 1)
SPOIL(tag_fills_off, f->h.tag_cache.fills -= 1; f->h.tag_cache.fill_bytes -= f->line[HR_TAG])
SPOIL(sdram_bytes_off, f->h.sdram.read_bytes += 8)
SPOIL(sdram_not_busy, f->h.sdram.busy_ticks = 0; f->h.func_sdram_busy_ticks = 0)
SPOIL(vma_read_bytes_off, f->h.vma.read_bytes += 8)
SPOIL(l2_bytes_off, f->h.l2.bytes += 8)
SPOIL(tag_lookups_off, f->h.tag_cache.accesses++; f->h.tag_cache.hits++)
SPOIL(host_fetches_off, f->h.vma.host_fetches++)
SPOIL(fill_traffic_off, f->h.memif.bytes[MEMIF_FILL] += 128)
SPOIL(meta_traffic_off, f->h.memif.bytes[MEMIF_META] += 20)
SPOIL(data_bytes_off, f->h.vma.data_bytes += 8)
SPOIL(hostbus_bytes_zero, f->h.hostbus.bytes = 0)
SPOIL(hostbus_not_busy, f->h.hostbus.busy_ticks = 0; f->h.func_hostbus_busy_ticks = 0)
SPOIL(writeback_uncharged, f->h.vma.writeback_bytes += 128)
SPOIL(memif_kd_off, f->h.memif.bytes[MEM_KD] += 8; f->h.sdram.read_bytes += 8)

Test(reportcheck, each_invariant_can_fail, .timeout = 300)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	chip *v = vma_run(&w), *p = plain_run(&w);
	static const struct {
		spoil_fn spoil;
		const char *want, *what;
		int plain; /* on the run without the VMA */
	} cases[] = {
	    {frame_cycles_off, "the frames' cycles add up", "a frame's cycles", 0},
	    {fps_off, "fps = clock / cycles per frame", "fps", 0},
	    {frame_fps_off, "per_frame[1]: fps = clock / cycles", "a frame's fps", 0},
	    {frame_cycles_copy_off, "per_frame[0]: cycles = cycles_per_frame[0]",
	     "per_frame cycles", 0},
	    {util_over_1, "units.isect.utilisation: a rate in [0, 1]", "utilisation", 0},
	    {rtp_util_negative, "units.trav.per_rtp_utilisation[0]: a rate", "RTP utilisation", 0},
	    {shares_off, "threads: the four shares add up to 1", "thread shares", 0},
	    {thread_time_off, "threads: the states' times add up to contexts x frame time",
	     "thread state time", 1},
	    {hit_rate_over_1, "per_frame[0].hit_rate.l1.kd: a rate", "hit rate", 0},
	    {sdram_util_over_1, "steady_state.sdram_utilisation: a rate", "SDRAM utilisation", 0},
	    {row_hit_rate_over_1, "steady_state.sdram_row_hit_rate: a rate", "row hit rate", 0},
	    {meta_share_negative, "per_frame[0].meta_share: a rate", "meta-data share", 0},
	    {pci_mb_zero, "per_frame[0]: PCI busy", "PCI MB of a busy bus", 0},
	    {sdram_mb_zero, "per_frame[0]: SDRAM busy", "SDRAM MB of a busy bus", 0},
	    {pci_mb_off, "PCI MB add up", "per-frame PCI MB", 0},
	    {sdram_mb_zero, "SDRAM MB add up", "per-frame SDRAM MB", 1},
	    {port_off, "memory.tri: the port's requests = the hierarchy's", "port counts", 0},
	    {l1_hits_off, "l1.kd: hits + misses = accesses", "L1 hits", 0},
	    {l1_merges_over, "l1.list: merges <= misses", "L1 merges", 0},
	    {l2_fill_bytes_off, "vma.l2: fill_bytes = fills x line", "L2 fill bytes", 0},
	    {tag_fills_off, "vma.tag_cache: fills = misses - merges", "tag cache fills", 0},
	    {sdram_bytes_off, "sdram: bytes and accesses = the memory interface's", "SDRAM bytes",
	     0},
	    {sdram_not_busy, "sdram: busy exactly when bytes moved", "SDRAM busy time", 0},
	    {vma_read_bytes_off, "vma: read bytes = L1 fills + bypass reads", "VMA read bytes", 0},
	    {l2_bytes_off, "vma.l2: bytes looked up", "L2 bytes", 0},
	    {tag_lookups_off, "one meta-data lookup per on-board access", "tag lookups", 0},
	    {host_fetches_off, "vma: host fetches = L2 misses - merges", "host fetches", 0},
	    {fill_traffic_off, "memif.fill: bytes = the host fetches'", "fill traffic", 0},
	    {meta_traffic_off, "memif.meta: bytes = the VMA's meta-data bytes", "meta traffic", 0},
	    {data_bytes_off, "memif: data bytes + fill bytes = the VMA's data bytes", "data bytes",
	     0},
	    {hostbus_bytes_zero, "hostbus: bytes = host fetches + write-arounds", "PCI bytes", 0},
	    {hostbus_bytes_zero, "hostbus: busy exactly when bytes moved", "PCI bytes vs busy", 0},
	    {hostbus_not_busy, "hostbus: busy exactly when bytes moved", "PCI busy time", 0},
	    {writeback_uncharged, "memif.fill: bytes = the host fetches' + write-backs'",
	     "a write-back without its traffic", 0},
	    {memif_kd_off, "memif.kd: bytes = L1 fills + bypass reads + writes", "L1 to memif", 1},
	    {type_steps_off, "ray_types: kd_node_steps add up over the types", "kd steps by type",
	     1},
	    {type_busy_off, "ray_types: isect busy cycles add up", "busy cycles by type", 0},
	    {ray_hits_off, "ray_types: l1.tri's lookups and hits add up", "L1 hits by ray type", 1},
	};
	for (size_t i = 0; i < sizeof cases / sizeof *cases; i++)
		expect_failure(cases[i].plain ? p : v, cases[i].spoil, cases[i].want,
		               cases[i].what);
	chip_destroy(v);
	chip_destroy(p);
	world_free(&w);
}
