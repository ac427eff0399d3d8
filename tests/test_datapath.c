/*
 * test_datapath.c: the bytes travel (issue 29, docs/memory.md "Data").
 * The chip decodes nodes, list entries, triangles, spilled stack entries
 * and shading records from what its reads return, so damage to the board's
 * memory (never to the host's scene, which kernel-ref renders the check
 * frame from), to a cache line, or a unit asking for the wrong address
 * must change the chip's frame, and the per-frame check must say
 * DIFFERENT; undamaged, every mode and memory path renders kernel-ref's
 * frame. Each damaged case passes only if the bytes do travel: with the
 * units reading the host's image instead, the frames stay identical.
 */
#include <string.h>

#include "kernel-ref/camera.h"
#include "sim/report.h"
#include "tests/chiptest.h"

static const char *const modes[] = {"cycle", "functional", "sampled"};

/* The embedded room at size x size through config changes `sets` (each
 * "key=value"), in fidelity mode. */
static void cfg_for(saar_config *c, int size, const char *mode, const char *const *sets, int n)
{
	cfg_defaults(c);
	c->frame.width = c->frame.height = size;
	/* few threads: a sampled frame of 256 tiles is sampled, not exact */
	c->chip.rtps = 1;
	c->chip.threads_per_rtp = 4;
	/* full warming: the sampled runs here record and replay in their own
	 * stretches (auto would choose stored warming with the cache, whose
	 * record a helper chip makes from the undamaged board) */
	c->sampling.warming = CFG_WARMING_FULL;
	diag d;
	char kv[128];
	snprintf(kv, sizeof kv, "fidelity=%s", mode);
	cr_assert_eq(cfg_set(c, kv, &d), 0, "%s", d.msg);
	for (int i = 0; i < n; i++)
		cr_assert_eq(cfg_set(c, sets[i], &d), 0, "%s: %s", sets[i], d.msg);
}

/* The address of the triangle the middle pixel sees. */
static uint32_t visible_tri(const world *w, int size)
{
	cam_frame cf;
	cam_setup(&cf, &w->v.cam, size, size);
	packet *p = aligned_alloc(64, (sizeof(packet) + 63) / 64 * 64);
	trav_entry *st = aligned_alloc(64, (PKT_STACK_MAX * sizeof(trav_entry) + 63) / 64 * 64);
	cam_primary_packet(&cf, size / 2 / TILE_W, size / 2 / TILE_H, p);
	pkt_trace(p, &w->m, st, PKT_STACK_MAX, NULL);
	uint32_t ta = p->tri[0];
	free(p);
	free(st);
	cr_assert_neq(ta, PKT_NOHIT, "the middle of the frame shows no triangle");
	return ta;
}

/* Runs the chip, checks its frame against kernel-ref's and returns whether
 * they are identical; the text report must say so, and its invariants
 * hold (damaged data changes the frame, never the accounting). */
static int frame_identical(chip *ch, const world *w)
{
	diag d;
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	tu_assert_report_ok(ch);
	chip_check k;
	cr_assert_eq(chip_check_frame(ch, &k, &d), 0, "%s", d.msg);
	char *txt = NULL;
	size_t n = 0;
	FILE *f = open_memstream(&txt, &n);
	report_info ri = {ch, w, &k, 0, 0, NULL, 0, NULL};
	report_text(f, &ri);
	fclose(f);
	cr_assert(strstr(txt, k.cmp.identical ? "check vs kernel-ref: packets identical"
	                                      : "check vs kernel-ref: packets DIFFERENT"),
	          "%s", txt);
	free(txt);
	return k.cmp.identical;
}

static chip *make_chip(const world *w, const saar_config *c)
{
	diag d;
	chip *ch = chip_create(c, w, &d);
	cr_assert(ch, "%s", d.msg);
	return ch;
}

/* Damages triangle ta in the chip's memory: all three corners at the
 * first one, so it covers nothing. */
static void flatten_tri(chip *ch, uint32_t ta)
{
	mimg_tri t;
	ms_read(&ch->store, ta, sizeof t, &t);
	memcpy(t.v[1], t.v[0], sizeof t.v[0]);
	memcpy(t.v[2], t.v[0], sizeof t.v[0]);
	cr_assert_eq(ms_write(&ch->store, ta, sizeof t, &t), 0);
}

/* (a), and (c) with the VMA on a small board: one visible triangle
 * damaged in the board's (or host) memory changes the frame in every
 * mode; kernel-ref's copy stays as it was, and without the damage the
 * frame is kernel-ref's. */
static void damaged_triangle(const char *const *sets, int n)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	uint32_t ta = visible_tri(&w, 128);
	mimg_tri before;
	memcpy(&before, w.m.bytes + ta, sizeof before);
	char blind[64] = "";
	for (int m = 0; m < 3; m++) {
		saar_config c;
		cfg_for(&c, 128, modes[m], sets, n);
		chip *ok = make_chip(&w, &c);
		cr_assert(frame_identical(ok, &w), "%s: undamaged", modes[m]);
		chip_destroy(ok);
		chip *ch = make_chip(&w, &c);
		flatten_tri(ch, ta);
		if (frame_identical(ch, &w))
			strcat(strcat(blind, " "), modes[m]);
		cr_assert_eq(memcmp(w.m.bytes + ta, &before, sizeof before), 0,
		             "the host's image changed");
		chip_destroy(ch);
	}
	cr_assert_str_empty(blind, "the damaged triangle is not seen in:%s", blind);
	world_free(&w);
}

Test(datapath, damaged_triangle_in_board_memory_changes_the_frame, .timeout = 300)
{
	damaged_triangle(NULL, 0);
}

Test(datapath, damaged_triangle_in_host_memory_changes_the_frame_through_the_vma, .timeout = 300)
{
	static const char *const on_vma[] = {"memory.vma.enabled=true", "memory.sdram.mb=1"};
	damaged_triangle(on_vma, 2);
}

/* The packet record (docs/fidelity.md "The packet record"): a functional
 * or sampled run with a world cache records its frame while it runs the
 * math, through the recording sink around the functional one, so its
 * units decode what their reads return as without a record: one visible
 * triangle damaged in board memory changes the recording run's frame, and
 * the record keeps that frame and the checksums of the damaged bytes, so
 * a run replaying it on an undamaged board shows a frame other than
 * kernel-ref's too, and says its reads returned other bytes than the
 * recording's. Catches: a recording run whose units see the host's image
 * instead of the board's bytes (both frames would be kernel-ref's). */
Test(datapath, damaged_triangle_changes_the_recording_run_and_its_record, .timeout = 300)
{
	static const char *const rec_modes[] = {"functional", "sampled"};
	for (int m = 0; m < 2; m++) {
		char dir[64];
		tu_tmpdir(dir, sizeof dir);
		world w;
		tu_load_world_cached(&w, NULL, NULL, NULL, dir);
		uint32_t ta = visible_tri(&w, 128);
		saar_config c;
		cfg_for(&c, 128, rec_modes[m], NULL, 0);
		chip *ch = make_chip(&w, &c);
		flatten_tri(ch, ta);
		cr_assert_not(frame_identical(ch, &w), "%s: the recording run did not see it",
		              rec_modes[m]);
		cr_assert_eq(ch->rec_state, REC_STORED, "%s: %s", rec_modes[m],
		             chip_rec_name(ch->rec_state));
		chip_destroy(ch);
		ch = make_chip(&w, &c);
		cr_assert_not(frame_identical(ch, &w), "%s: the replayed record lost it",
		              rec_modes[m]);
		cr_assert_eq(ch->rec_state, REC_REPLAYED, "%s: %s", rec_modes[m],
		             chip_rec_name(ch->rec_state));
		cr_assert_gt(ch->fid.replayed_tiles, 0, "%s", rec_modes[m]);
		char msg[320];
		cr_assert_gt(chip_replay_bad(ch, msg, sizeof msg), 0, "%s", rec_modes[m]);
		chip_destroy(ch);
		world_free(&w);
	}
}

/* A 128x128 frame of the embedded room in mode `mode` (functional or
 * sampled) recorded into a fresh world cache, so that the next chip of
 * config *c on *w replays it; returns the recording run's record state. */
static int record_frame(const char *mode, world *w, saar_config *c)
{
	char dir[64];
	tu_tmpdir(dir, sizeof dir);
	tu_load_world_cached(w, NULL, NULL, NULL, dir);
	cfg_for(c, 128, mode, NULL, 0);
	chip *ch = make_chip(w, c);
	cr_assert(frame_identical(ch, w), "%s: the recording run", mode);
	int rec = ch->rec_state;
	chip_destroy(ch);
	return rec;
}

/* A run replaying a packet record runs no math, but its reads carry
 * their bytes and the record holds each recorded read's checksum
 * (traces/pktrec.h pr_sum): a replayed read that returns other bytes is
 * reported by the frame's check. Records an undamaged frame, then replays
 * it in functional and sampled mode (functional stretches and timed
 * regions) with `spoil` applied to the replaying chip only; the check must
 * say DIFFERENT and name a read of the given type (and address, unless
 * 0). Undamaged, the replay is kernel-ref's frame with no bad read. */
static void replay_sees(void (*spoil_fn)(chip *ch, uint64_t arg), uint64_t arg, const char *type,
                        uint64_t addr)
{
	static const char *const rec_modes[] = {"functional", "sampled"};
	char blind[64] = "";
	for (int m = 0; m < 2; m++) {
		world w;
		saar_config c;
		cr_assert_eq(record_frame(rec_modes[m], &w, &c), REC_STORED);
		char msg[320];
		chip *ch = make_chip(&w, &c);
		cr_assert(frame_identical(ch, &w), "%s: an undamaged replay", rec_modes[m]);
		cr_assert_eq(ch->rec_state, REC_REPLAYED);
		cr_assert_eq(chip_replay_bad(ch, msg, sizeof msg), 0, "%s: %s", rec_modes[m], msg);
		chip_destroy(ch);
		ch = make_chip(&w, &c);
		spoil_fn(ch, arg);
		int same = frame_identical(ch, &w);
		cr_assert_eq(ch->rec_state, REC_REPLAYED);
		cr_assert_eq(ch->fid.replayed_tiles, (uint64_t)ch->g.ntiles, "%s", rec_modes[m]);
		if (same || !chip_replay_bad(ch, msg, sizeof msg)) {
			strcat(strcat(blind, " "), rec_modes[m]);
		} else {
			/* one line naming the packet, its tile and the read */
			char want[64];
			snprintf(want, sizeof want, "(%s)", type);
			cr_assert(strstr(msg, "packet-record replay") && strstr(msg, " of tile ") &&
			              strstr(msg, want) && !strchr(msg, '\n'),
			          "%s: %s", rec_modes[m], msg);
			snprintf(want, sizeof want, "at 0x%llx (", (unsigned long long)addr);
			cr_assert(!addr || strstr(msg, want), "%s: %s", rec_modes[m], msg);
		}
		chip_destroy(ch);
		world_free(&w);
	}
	cr_assert_str_empty(blind, "the replaying run did not see it in:%s", blind);
}

static void flatten(chip *ch, uint64_t ta)
{
	flatten_tri(ch, (uint32_t)ta);
}

/* Issue 29: a visible triangle damaged in the board memory of a run that
 * replays a packet record (the record made from an undamaged board). The
 * replayed tile used to take the recorded frame's pixels and the check
 * said identical. Catches: replay comparing no checksums (tests/mutants
 * 28), replayed reads carrying no bytes, a record without checksums. */
Test(datapath, damaged_triangle_in_a_replaying_runs_board_memory_is_caught, .timeout = 300)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	uint32_t ta = visible_tri(&w, 128);
	world_free(&w);
	replay_sees(flatten, ta, "tri", ta);
}

static void next_tri(chip *ch, uint64_t arg)
{
	(void)arg;
	ch->env.mutant = THR_MUT_REPLAY_NEXT_TRI;
}

/* A replay that asks for the wrong address (a test hook: every triangle
 * record read at the next one's) reads other bytes than were recorded,
 * and the check says so. Catches: the same mistakes as above, for an
 * address the replay decodes wrongly rather than damaged data. */
Test(datapath, wrong_replayed_address_is_caught, .timeout = 300)
{
	replay_sees(next_tri, 0, "tri", 0);
}

/* Every replayed read is checked: at once in a functional run (sim/
 * modes/replay.c read_checked), and in a sampled run's detailed regions
 * (timed) once the thread's reads are in. With every triangle record read
 * at the next one's address, all but a few of the run's triangle reads (a
 * checksum passes a wrong read with odds 2^-16) are reported. Catches:
 * the timed check dropped, which wrong_replayed_address_is_caught does
 * not see (a sampled run's functional stretches still flag the frame),
 * and the functional one. */
Test(datapath, every_replayed_read_is_checked_timed_and_functional, .timeout = 300)
{
	static const char *const rec_modes[] = {"functional", "sampled"};
	for (int m = 0; m < 2; m++) {
		world w;
		saar_config c;
		record_frame(rec_modes[m], &w, &c);
		chip *ch = make_chip(&w, &c);
		next_tri(ch, 0);
		cr_assert_not(frame_identical(ch, &w), "%s", rec_modes[m]);
		cr_assert_eq(ch->rec_state, REC_REPLAYED, "%s", rec_modes[m]);
		hier_stats h;
		cr_assert_eq(hier_get_stats(&ch->mem, &h), 0);
		char msg[320];
		uint64_t bad = chip_replay_bad(ch, msg, sizeof msg), tri = h.reads[MEM_TRI];
		cr_assert_gt(tri, 0, "%s", rec_modes[m]);
		cr_assert(bad <= tri && bad >= tri - tri / 100,
		          "%s: %llu of %llu triangle reads reported", rec_modes[m],
		          (unsigned long long)bad, (unsigned long long)tri);
		chip_destroy(ch);
		world_free(&w);
	}
}

/* The shader's records travel too: the material of the visible triangle
 * made black in board memory changes the frame in every mode. */
Test(datapath, damaged_material_changes_the_frame, .timeout = 300)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	uint32_t ta = visible_tri(&w, 64);
	const mimg_shade *sh = mimg_shade_at(&w.m, mimg_tri_index(&w.m, ta));
	uint64_t ma = mimg_mat_addr(&w.m, sh->mat);
	char blind[64] = "";
	for (int m = 0; m < 3; m++) {
		saar_config c;
		cfg_for(&c, 64, modes[m], NULL, 0);
		chip *ch = make_chip(&w, &c);
		mimg_mat mt;
		ms_read(&ch->store, ma, sizeof mt, &mt);
		memset(mt.kd, 0, sizeof mt.kd);
		memset(mt.ka, 0, sizeof mt.ka);
		memset(mt.ks, 0, sizeof mt.ks);
		cr_assert_eq(ms_write(&ch->store, ma, sizeof mt, &mt), 0);
		if (frame_identical(ch, &w))
			strcat(strcat(blind, " "), modes[m]);
		chip_destroy(ch);
	}
	cr_assert_str_empty(blind, "the black material is not seen in:%s", blind);
	world_free(&w);
}

/* (b) A traversal unit that asks for the wrong node (each node's sibling)
 * decodes the wrong node and renders another frame, in every mode. */
Test(datapath, wrong_node_address_changes_the_frame, .timeout = 300)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	char blind[64] = "";
	for (int m = 0; m < 3; m++) {
		saar_config c;
		cfg_for(&c, 128, modes[m], NULL, 0);
		chip *ch = make_chip(&w, &c);
		ch->env.mutant = THR_MUT_KD_SIBLING;
		if (frame_identical(ch, &w))
			strcat(strcat(blind, " "), modes[m]);
		chip_destroy(ch);
	}
	cr_assert_str_empty(blind, "the wrong nodes are not seen in:%s", blind);
	world_free(&w);
}

/* Node data that loops (here the root's children made the root itself,
 * in board memory) would keep a packet, and the frame, stepping for ever
 * (a wrong node address did: make mutate hung on it): the traversal unit
 * ends such a packet after twice the tree's nodes in steps and the frame
 * fails with one message, in every mode. */
Test(datapath, looping_node_data_fails_the_frame)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	for (int m = 0; m < 3; m++) {
		saar_config c;
		cfg_for(&c, 64, modes[m], NULL, 0);
		chip *ch = make_chip(&w, &c);
		kd_node root;
		uint64_t a = mimg_node_addr(&w.m, 0);
		ms_read(&ch->store, a, sizeof root, &root);
		cr_assert(!kd_is_leaf(root), "the root is a leaf");
		root.b &= 3; /* left child 0: the root again, and so is its pair */
		cr_assert_eq(ms_write(&ch->store, a, sizeof root, &root), 0);
		diag d = {{0}};
		cr_assert_eq(chip_run(ch, &d), -1, "%s: the frame ended", modes[m]);
		cr_assert(strstr(d.msg, "kd-tree steps") && strstr(d.msg, "loops"), "%s: %s",
		          modes[m], d.msg);
		chip_destroy(ch);
	}
	world_free(&w);
}

/* Cache lines hold their bytes: once the first frame has filled them,
 * zeroing every line of the triangle cache (or, through the VMA, the
 * on-board lines of triangle records) in the middle of the second frame
 * changes it: hits hand out the line's bytes, not memory's. (Zeroed
 * kd-nodes would send the traversal round the root for ever, as they
 * would the chip.) */
typedef struct spoil {
	chip *ch;
	int l2; /* spoil the on-board cache instead of the L1 */
	int done;
} spoil;

static void spoil_lines(void *ctx, int frame, int tiles_done, int tiles)
{
	(void)tiles;
	spoil *s = ctx;
	if (frame != 1 || tiles_done < 64 || s->done)
		return;
	cache *l1[MEM_NTYPES], *tag, *l2;
	hier_caches(&s->ch->mem, l1, &tag, &l2);
	cache *k = s->l2 ? l2 : l1[MEM_TRI];
	const mimg *m = &s->ch->w->m;
	uint64_t lo = m->base[MIMG_TRIS], hi = lo + m->len[MIMG_TRIS];
	for (uint32_t i = 0; i < k->nsets * k->p.ways; i++) {
		uint64_t a = k->way[i].tag * k->p.line_bytes;
		uint8_t *d = k->way[i].tag != CACHE_INVALID ? cache_data_at(k, i) : NULL;
		if (d && a >= lo && a < hi)
			memset(d, 0, k->p.line_bytes);
	}
	s->done = 1;
}

static void spoiled_cache(int l2)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	static const char *const sets[] = {"memory.vma.enabled=true", "frame.frames=2"};
	saar_config c;
	cfg_for(&c, 128, "cycle", l2 ? sets : sets + 1, l2 ? 2 : 1);
	chip *ch = make_chip(&w, &c);
	spoil s = {ch, l2, 0};
	ch->progress = spoil_lines;
	ch->progress_ctx = &s;
	cr_assert_not(frame_identical(ch, &w));
	cr_assert(s.done);
	chip_destroy(ch);
	world_free(&w);
}

Test(datapath, spoiled_l1_lines_change_the_frame)
{
	spoiled_cache(0);
}

Test(datapath, spoiled_on_board_lines_change_the_frame)
{
	spoiled_cache(1);
}

/* (d) Stack spills: with one on-chip entry every deeper entry goes to
 * memory and comes back from it. Undamaged: kernel-ref's frame, through
 * SDRAM and through the VMA on a small board (where spilled lines are
 * evicted dirty and written back: without the write-back they were
 * lost); damaged on their way (each entry's ray mask zeroed as it is
 * written): another frame. */
static void drop_mask(void *ctx, mem_store *s, uint64_t addr, uint32_t bytes)
{
	(void)ctx;
	(void)bytes;
	static const uint8_t zero[8];
	s->on_write = NULL; /* not for the hook's own write */
	ms_write(s, addr + 4, 8, zero);
	s->on_write = drop_mask;
}

Test(datapath, spills_travel_through_memory, .timeout = 300)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	static const char *const sets[][3] = {
	    {"chip.stack_depth=1"},
	    {"chip.stack_depth=1", "memory.vma.enabled=true", "memory.sdram.mb=1"}};
	char blind[128] = "";
	for (int v = 0; v < 2; v++)
		for (int m = 0; m < 3; m++) {
			saar_config c;
			cfg_for(&c, 128, modes[m], sets[v], v ? 3 : 1);
			c.chip.rtps = 4;
			c.chip.threads_per_rtp = 16;
			chip *ch = make_chip(&w, &c);
			cr_assert(frame_identical(ch, &w), "%s, vma %d", modes[m], v);
			cr_assert_gt(stats_get(&ch->st, "trav.stack_refills"), 0);
			if (v) {
				hier_stats h;
				hier_get_stats(&ch->mem, &h);
				cr_assert_gt(h.vma.writebacks, 0, "%s: no dirty line evicted",
				             modes[m]);
			}
			chip_destroy(ch);
			ch = make_chip(&w, &c);
			ch->store.on_write = drop_mask;
			if (frame_identical(ch, &w))
				strcat(strcat(blind, v ? " vma-" : " "), modes[m]);
			chip_destroy(ch);
		}
	cr_assert_str_empty(blind, "the damaged spills are not seen in:%s", blind);
	world_free(&w);
}

/* The shader's results stand when the bytes its reads returned are those
 * it found them with; decoding the returned bytes every time instead
 * changes nothing: the same frame and every counter. */
Test(datapath, shading_decoded_from_returned_bytes_is_the_same)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	cfg_for(&c, 64, "cycle", NULL, 0);
	chip *a = tu_run_chip(&w, &c), *b = make_chip(&w, &c);
	b->env.shade_redecode = 1;
	cr_assert(frame_identical(b, &w));
	cr_assert_eq(chip_cycles(a), chip_cycles(b));
	for (size_t i = 0; i < a->st.n; i++)
		cr_assert_eq(*a->st.e[i].value, *b->st.e[i].value, "%s", a->st.e[i].name);
	chip_destroy(a);
	chip_destroy(b);
	world_free(&w);
}

TestSuite(datapath, .timeout = 120);
