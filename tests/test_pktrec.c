/*
 * test_pktrec.c: the packet record (traces/pktrec.h, sim/modes/replay.h). A
 * functional or sampled run with a world cache records its frame; the
 * next run with the cache replays it and must be the run without a
 * record, figure for figure: every counter, the memory and cache counts,
 * the estimate and its interval, the frame. Replays into other thread
 * counts and memory systems than the recording's, through the VMA, and
 * over several frames; a damaged, foreign or old-format record is
 * recorded again, never replayed. (What a replay checks of its reads'
 * bytes is tested in test_datapath.c.)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim/modes/replay.h"
#include "tests/chiptest.h"

/* Loads the scene (NULL: the embedded room) with a world cache in dir
 * (NULL: none). */
static void load(world *w, const char *path, const char *dir)
{
	tu_load_world_cached(w, path, NULL, NULL, dir);
}

static void same_cache(const cache_stats *a, const cache_stats *b, const char *what)
{
	cr_assert_eq(memcmp(a, b, sizeof *a), 0,
	             "%s: accesses %llu/%llu hits %llu/%llu merges %llu/%llu", what,
	             (unsigned long long)a->accesses, (unsigned long long)b->accesses,
	             (unsigned long long)a->hits, (unsigned long long)b->hits,
	             (unsigned long long)a->merges, (unsigned long long)b->merges);
}

/* Everything a report prints from the run, equal in a and b. */
static void same_run(chip *a, chip *b, const char *what)
{
	cr_assert_eq(a->frames_done, b->frames_done);
	for (int f = 0; f < a->frames_done; f++) {
		cr_assert_eq(a->frame_cycles[f], b->frame_cycles[f],
		             "%s: frame %d cycles %llu vs %llu", what, f,
		             (unsigned long long)a->frame_cycles[f],
		             (unsigned long long)b->frame_cycles[f]);
		cr_assert(a->fid.half[f] == b->fid.half[f], "%s: interval", what);
		cr_assert_eq(memcmp(&a->frame_port[f], &b->frame_port[f], sizeof(mem_counts)), 0,
		             "%s: memory-port counts", what);
	}
	cr_assert_eq(a->st.n, b->st.n);
	for (size_t i = 0; i < a->st.n; i++)
		cr_assert_eq(*a->st.e[i].value, *b->st.e[i].value, "%s: %s %llu vs %llu", what,
		             a->st.e[i].name, (unsigned long long)*a->st.e[i].value,
		             (unsigned long long)*b->st.e[i].value);
	hier_stats x, y;
	if (!hier_get_stats(&a->mem, &x)) {
		cr_assert_eq(hier_get_stats(&b->mem, &y), 0);
		for (int t = 0; t < MEM_NTYPES; t++)
			same_cache(&x.l1[t], &y.l1[t], what);
		same_cache(&x.tag_cache, &y.tag_cache, what);
		same_cache(&x.l2, &y.l2, what);
		cr_assert_eq(memcmp(&x.sdram, &y.sdram, sizeof x.sdram), 0, "%s: SDRAM", what);
		cr_assert_eq(memcmp(&x.hostbus, &y.hostbus, sizeof x.hostbus), 0, "%s: host bus",
		             what);
		cr_assert_eq(x.func_sdram_busy_ticks, y.func_sdram_busy_ticks, "%s", what);
		cr_assert(x.func_sdram_merge_ticks == y.func_sdram_merge_ticks, "%s", what);
	}
	size_t n = (size_t)a->fb.w * (size_t)a->fb.h * 3;
	cr_assert_eq(memcmp(a->fb.acc, b->fb.acc, n * sizeof *a->fb.acc), 0, "%s: frames differ",
	             what);
}

/* Runs c on w_plain (no cache) and twice on w_cached: the first run
 * records (unless a record is there), the second replays; both equal the
 * plain run. Returns the replaying run's replayed tiles. */
static uint64_t record_then_replay(const world *plain, const world *cached, const saar_config *c,
                                   const char *what)
{
	chip *ref = tu_run_chip(plain, c);
	cr_assert_eq(ref->rec_state, REC_OFF);
	chip *rec = tu_run_chip(cached, c);
	cr_assert_neq(rec->rec_state, REC_OFF, "%s: no record", what);
	same_run(ref, rec, what);
	chip *rep = tu_run_chip(cached, c);
	cr_assert_eq(rep->rec_state, REC_REPLAYED, "%s: %s", what, chip_rec_name(rep->rec_state));
	same_run(ref, rep, what);
	uint64_t n = rep->fid.replayed_tiles;
	cr_assert_gt(n, 0, "%s: nothing replayed", what);
	char msg[320];
	cr_assert_eq(chip_replay_bad(rep, msg, sizeof msg), 0, "%s: %s", what, msg);
	tu_assert_identical(rep, what);
	chip_destroy(ref);
	chip_destroy(rec);
	chip_destroy(rep);
	return n;
}

/* The embedded room without and with a world cache in a fresh folder dir,
 * and a functional config of size x size. */
static void embedded(world *plain, world *cached, char *dir, size_t ndir, saar_config *c, int size)
{
	tu_tmpdir(dir, ndir);
	load(plain, NULL, NULL);
	load(cached, NULL, dir);
	cfg_defaults(c);
	c->frame.width = c->frame.height = size;
	c->fidelity = CFG_FIDELITY_FUNCTIONAL;
}

/* The frame's tiles under config c. */
static uint64_t tiles_of(const saar_config *c)
{
	return (uint64_t)(c->frame.width / c->chip.packet_w) *
	       (uint64_t)(c->frame.height / c->chip.packet_h);
}

Test(pktrec, replay_equals_the_math)
{
	char dir[64];
	world plain, cached;
	saar_config c;
	embedded(&plain, &cached, dir, sizeof dir, &c, 128);
	c.chip.threads_per_rtp = 4;
	uint64_t n = record_then_replay(&plain, &cached, &c, "functional");
	cr_assert_eq(n, tiles_of(&c), "functional replays every tile (%llu), not %llu",
	             (unsigned long long)tiles_of(&c), (unsigned long long)n);
	/* sampled: recorded at 4 threads per RTP, replayed at 4 and at 1;
	 * the detailed regions replay too (timed), taking over the packets
	 * the functional stretches left in flight */
	c.frame.width = c.frame.height = 256;
	c.fidelity = CFG_FIDELITY_SAMPLED;
	c.sampling.warming = CFG_WARMING_FULL; /* replay in the stretches (auto: stored) */
	c.sampling.rate = 0.1;
	n = record_then_replay(&plain, &cached, &c, "sampled, 4 threads per RTP");
	cr_assert_eq(n, tiles_of(&c),
	             "sampled replays every tile (%llu), detailed ones too, not %llu",
	             (unsigned long long)tiles_of(&c), (unsigned long long)n);
	c.chip.threads_per_rtp = 1;
	chip *ref = tu_run_chip(&plain, &c);
	chip *rep = tu_run_chip(&cached, &c);
	cr_assert_eq(rep->rec_state, REC_REPLAYED);
	cr_assert(!ref->fid.exact && rep->fid.replayed_tiles > 0, "nothing sampled");
	same_run(ref, rep, "sampled, 1 thread per RTP");
	tu_assert_identical(rep, "sampled, 1 thread per RTP");
	chip_destroy(ref);
	chip_destroy(rep);
	world_free(&plain);
	world_free(&cached);
}

Test(pktrec, timed_replay_waits_where_the_math_waits)
{
	/* a 2-entry stack: traversal spills and reads entries back, and waits
	 * for them before it reads the next node or shades (PR_WAIT): a
	 * detailed region replaying the stream must wait there too, or its
	 * reads and cycles would differ from the math's */
	char dir[64];
	world plain, cached;
	saar_config c;
	embedded(&plain, &cached, dir, sizeof dir, &c, 128);
	c.chip.threads_per_rtp = 2;
	c.chip.stack_depth = 2;
	c.fidelity = CFG_FIDELITY_SAMPLED;
	c.sampling.warming = CFG_WARMING_FULL; /* replay in the stretches (auto: stored) */
	c.sampling.rate = 0.3;
	record_then_replay(&plain, &cached, &c, "sampled, 2-entry stack");
	chip *rep = tu_run_chip(&cached, &c);
	cr_assert_eq(rep->rec_state, REC_REPLAYED);
	cr_assert_gt(stats_get(&rep->st, "trav.stack_refills"), 0, "no stack refills to wait for");
	cr_assert_gt(rep->fid.detailed_tiles, 0, "no detailed region");
	chip_destroy(rep);
	world_free(&plain);
	world_free(&cached);
}

Test(pktrec, replay_through_the_vma_and_frames)
{
	/* balls through a VMA with 1 MB on board: host-bus fetches, tag cache */
	char dir[64];
	tu_tmpdir(dir, sizeof dir);
	world plain, cached;
	load(&plain, "spd:balls:2", NULL);
	load(&cached, "spd:balls:2", dir);
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = 128;
	c.memory.vma.enabled = true;
	c.memory.sdram.mb = 1;
	c.fidelity = CFG_FIDELITY_SAMPLED;
	c.sampling.warming = CFG_WARMING_FULL; /* replay in the stretches (auto: stored) */
	c.sampling.rate = 0.2;
	c.chip.threads_per_rtp = 2;
	record_then_replay(&plain, &cached, &c, "sampled through the VMA");
	/* two frames: the recording run replays its own record in frame 2 */
	char dir2[64];
	tu_tmpdir(dir2, sizeof dir2);
	world cached2;
	load(&cached2, "spd:balls:2", dir2);
	c.frame.frames = 2;
	chip *ref = tu_run_chip(&plain, &c);
	chip *rec = tu_run_chip(&cached2, &c);
	cr_assert_eq(rec->rec_state, REC_STORED);
	cr_assert_gt(rec->fid.replayed_tiles, 0, "frame 2 replays frame 1's record");
	same_run(ref, rec, "two frames");
	chip_destroy(ref);
	chip_destroy(rec);
	world_free(&plain);
	world_free(&cached);
	world_free(&cached2);
}

/* The one packets-*.bin file in dir. */
static void record_file(const char *dir, char *out, size_t n)
{
	cr_assert_eq(tu_find_files(dir, "packets-", out, n), 1, "one record in %s", dir);
}

Test(pktrec, damaged_or_foreign_records_are_not_replayed)
{
	char dir[64], file[512];
	world plain, cached;
	saar_config c;
	embedded(&plain, &cached, dir, sizeof dir, &c, 64);
	chip *ref = tu_run_chip(&plain, &c);
	chip_destroy(tu_run_chip(&cached, &c));
	record_file(dir, file, sizeof file);
	/* a flipped byte in the middle: the CRC fails, the run records anew */
	struct stat st;
	cr_assert_eq(stat(file, &st), 0);
	long size = (long)st.st_size;
	tu_flip_byte(file, size / 2, 0x5a);
	chip *again = tu_run_chip(&cached, &c);
	cr_assert_eq(again->rec_state, REC_STORED, "damaged: %s", chip_rec_name(again->rec_state));
	same_run(ref, again, "after a damaged record");
	chip_destroy(again);
	/* truncated */
	cr_assert_eq(truncate(file, size / 3), 0);
	again = tu_run_chip(&cached, &c);
	cr_assert_eq(again->rec_state, REC_STORED, "truncated");
	chip_destroy(again);
	/* another datapath (a different key): its own record */
	c.chip.fp.isect.mant = 16;
	chip *fp = tu_run_chip(&cached, &c);
	cr_assert_eq(fp->rec_state, REC_STORED, "another datapath replayed a foreign record");
	chip_destroy(fp);
	/* cycle mode neither records nor replays */
	c.fidelity = CFG_FIDELITY_CYCLE;
	chip *cy = tu_run_chip(&cached, &c);
	cr_assert_eq(cy->rec_state, REC_OFF);
	chip_destroy(cy);
	chip_destroy(ref);
	world_free(&plain);
	world_free(&cached);
}

/* A record of the previous format (version "PKR2": reads without their
 * checksums) under the current key must not be replayed: its streams
 * would decode wrongly. pr_load refuses it, and the run records its frame
 * anew, figure for figure the run without a record. Catches: a format
 * change without a new version (the old record replayed with its
 * arguments read as checksums). */
Test(pktrec, old_version_record_is_recorded_anew)
{
	char dir[64];
	world plain, cached;
	saar_config c;
	embedded(&plain, &cached, dir, sizeof dir, &c, 64);
	chip *ref = tu_run_chip(&plain, &c);
	chip *rec = tu_run_chip(&cached, &c);
	cr_assert_eq(rec->rec_state, REC_STORED);
	void *tail = NULL;
	size_t n = 0;
	cr_assert_eq(wc_get(rec->rec_file, rec->rec_key, NULL, 0, &tail, &n), 1);
	/* the stored form loads; with the old magic it does not */
	pktrec r;
	void *copy = malloc(n);
	cr_assert(copy);
	memcpy(copy, tail, n);
	cr_assert_eq(pr_load(&r, copy, n, 1, 64, 64, rec->g.ntiles), 0);
	pr_free(&r);
	static const uint32_t pkr2 = 0x32524b50; /* "PKR2" */
	memcpy(tail, &pkr2, 4);
	copy = malloc(n);
	cr_assert(copy);
	memcpy(copy, tail, n);
	cr_assert_eq(pr_load(&r, copy, n, 1, 64, 64, rec->g.ntiles), -1, "PKR2 loaded");
	/* stored under the current key, CRC and all: recorded anew */
	diag d;
	cr_assert_eq(wc_put(rec->rec_file, rec->rec_key, NULL, NULL, 0, tail, n, &d), 0, "%s",
	             d.msg);
	free(tail);
	chip *again = tu_run_chip(&cached, &c);
	cr_assert_eq(again->rec_state, REC_STORED, "an old record: %s",
	             chip_rec_name(again->rec_state));
	same_run(ref, again, "after an old record");
	chip *rep = tu_run_chip(&cached, &c);
	cr_assert_eq(rep->rec_state, REC_REPLAYED, "the new record: %s",
	             chip_rec_name(rep->rec_state));
	same_run(ref, rep, "the new record");
	chip_destroy(ref);
	chip_destroy(rec);
	chip_destroy(again);
	chip_destroy(rep);
	world_free(&plain);
	world_free(&cached);
}

/* Cone culling changes the packets' work (cone tests, culled triangles,
 * the intersection unit's ops): a record made with it on is not replayed
 * with it off, nor the reverse; each setting records its own and its
 * replay is figure for figure the run without a world cache. On the
 * billiard table with its distribution effects, functional. Catches the
 * record's key without chip.cone_cull (a culling record replayed for a
 * run without culling reported 3244 cones with cone_cull false). */
Test(pktrec, cone_culling_records_its_own)
{
	char dir[64];
	tu_tmpdir(dir, sizeof dir);
	world plain, cached;
	tu_load_world(&plain, NULL, "configs/drt-views.yaml", "billiard-drt");
	tu_load_world_cached(&cached, NULL, "configs/drt-views.yaml", "billiard-drt", dir);
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = 32;
	c.frame.height = 24;
	c.fidelity = CFG_FIDELITY_FUNCTIONAL;
	for (int k = 0; k < 2; k++) {
		c.chip.cone_cull = k == 0; /* on first: its record is there for off */
		chip *ref = tu_run_chip(&plain, &c), *rec = tu_run_chip(&cached, &c);
		cr_assert_eq(rec->rec_state, REC_STORED, "cone_cull %d: %s", k == 0,
		             chip_rec_name(rec->rec_state));
		same_run(ref, rec, k == 0 ? "culling, recorded" : "no culling, recorded");
		chip *rep = tu_run_chip(&cached, &c);
		cr_assert_eq(rep->rec_state, REC_REPLAYED, "%s", chip_rec_name(rep->rec_state));
		same_run(ref, rep, k == 0 ? "culling, replayed" : "no culling, replayed");
		cr_assert_eq(stats_get(&rep->st, "cone.tests") > 0, k == 0,
		             "cone tests with cone_cull %d", k == 0);
		chip_destroy(ref);
		chip_destroy(rec);
		chip_destroy(rep);
	}
	world_free(&plain);
	world_free(&cached);
}
