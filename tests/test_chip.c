/*
 * test_chip.c: the chip model: unit timing (one op through an idle unit,
 * N ops through one unit, several units, masked packets, the order the
 * waiting policies serve in), the image equal to kernel-ref's on the
 * embedded scene and every shared view for several thread and RTP counts,
 * kernel-ref's traversal counts, stack overflow spilling, determinism, and
 * the memory port.
 */
#include <string.h>

#include "kernel-ref/view.h"
#include "mem/memport.h"
#include "tests/chiptest.h"
#include "units/thread.h"

/* ---- unit timing ---- */

static uint64_t done_at[64];
static int ndone;

static void on_done(eng *e, void *ctx, uint64_t arg)
{
	(void)ctx;
	done_at[arg] = eng_now(e);
	ndone++;
}

static void one_unit(int count, int width, int latency, int masked, int n, int rays, eng_clock clk)
{
	eng *e = eng_create(0);
	thr_unit u;
	unit_params up = {count, width, latency, masked, UNIT_SCHED_ROUND_ROBIN};
	cr_assert_eq(thr_unit_init(&u, e, clk, &up, 64), 0);
	ndone = 0;
	for (int k = 0; k < n; k++)
		thr_unit_request(&u, k, (uint64_t)k, rays, on_done, NULL, (uint64_t)k);
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(ndone, n);
	cr_assert_eq(*u.ops_n, (uint64_t)n);
	thr_unit_free(&u);
	eng_destroy(e);
}

Test(chip, one_packet_through_idle_unit_takes_issue_plus_latency)
{
	eng_clock clk = eng_clock_mhz(500); /* 2000 ps */
	/* 13 active rays, width 4: ceil(13/4) = 4 issue cycles, + 10 latency */
	one_unit(1, 4, 10, 0, 1, 13, clk);
	cr_assert_eq(done_at[0], 14 * 2000ull);
	/* masked packets always cost 64 rays: 16 issue cycles */
	one_unit(1, 4, 10, 1, 1, 13, clk);
	cr_assert_eq(done_at[0], 26 * 2000ull);
}

Test(chip, n_packets_through_one_unit_take_predicted_cycles)
{
	eng_clock clk = eng_clock_mhz(533);
	int n = 10, w = 16, lat = 8, issue = 64 / w;
	one_unit(1, w, lat, 1, n, 64, clk);
	/* pipelined: op k issues at k*issue, completes issue + lat later */
	for (int k = 0; k < n; k++)
		cr_assert_eq(done_at[k], (uint64_t)((k + 1) * issue + lat) * clk.period, "op %d",
		             k);
	/* two units of the kind: pairs issue together */
	one_unit(2, w, lat, 1, n, 64, clk);
	for (int k = 0; k < n; k++)
		cr_assert_eq(done_at[k], (uint64_t)((k / 2 + 1) * issue + lat) * clk.period,
		             "op %d", k);
}

/* ---- waiting policies ---- */

static int served[300], nserved;

static void on_served(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)ctx;
	served[nserved++] = (int)arg;
}

/* Requests ids[0..n) at once from one busy single-instance unit (the first
 * starts at once, the rest wait) and returns the order they issued in. */
static void serve_batch(thr_unit *u, eng *e, const int *ids, const uint64_t *age, int n)
{
	nserved = 0;
	for (int k = 0; k < n; k++)
		thr_unit_request(u, ids[k], age[ids[k]], 64, on_served, NULL, (uint64_t)ids[k]);
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(nserved, n);
}

/* The waiters are kept in a bitset (round robin) or a heap (oldest first);
 * both must serve what a scan over every waiter picks: round robin the
 * first id after the one served last, wrapping round; oldest first the
 * smallest (age, id). 200 ids span four bitset words. */
Test(chip, waiting_policies_serve_in_their_order)
{
	enum { N = 200 };
	int ids[N];
	uint64_t age[N];
	uint32_t x = 12345;
	for (int i = 0; i < N; i++) {
		ids[i] = i;
		x = x * 1103515245u + 12345u;
		age[i] = (x >> 16) % 40; /* many equal ages: ties go to the smaller id */
	}
	for (int i = N - 1; i > 0; i--) { /* requested in a shuffled order */
		x = x * 1103515245u + 12345u;
		int j = (int)((x >> 8) % (uint32_t)(i + 1)), t = ids[i];
		ids[i] = ids[j];
		ids[j] = t;
	}
	eng_clock clk = eng_clock_mhz(500);
	for (int sched = 0; sched < 2; sched++) {
		eng *e = eng_create(0);
		thr_unit u;
		unit_params up = {1, 64, 0, 1,
		                  sched ? UNIT_SCHED_OLDEST_FIRST : UNIT_SCHED_ROUND_ROBIN};
		cr_assert_eq(thr_unit_init(&u, e, clk, &up, N), 0);
		/* two batches on the same unit: the second, smaller, finds the
		 * waiter set the first emptied (its first request starts at
		 * once and sets the round-robin position itself) */
		for (int b = 0; b < 2; b++) {
			int n = b ? 77 : N, *want = malloc(sizeof(int) * (size_t)n);
			const int *req = b ? ids + 50 : ids;
			int *left = malloc(sizeof(int) * (size_t)n), nl = n - 1;
			/* the first request finds the unit idle and starts at once */
			want[0] = req[0];
			int rr = req[0];
			memcpy(left, req + 1, sizeof(int) * (size_t)nl);
			for (int k = 1; k < n; k++) {
				int best = 0;
				for (int i = 1; i < nl; i++) {
					int a = left[i], c = left[best];
					if (sched ? age[a] < age[c] || (age[a] == age[c] && a < c)
					          : (a - rr - 1 + 2 * N) % N <
					                (c - rr - 1 + 2 * N) % N)
						best = i;
				}
				want[k] = rr = left[best];
				left[best] = left[--nl];
			}
			serve_batch(&u, e, req, age, n);
			for (int k = 0; k < n; k++)
				cr_assert_eq(served[k], want[k], "policy %d batch %d: op %d", sched,
				             b, k);
			free(want);
			free(left);
		}
		thr_unit_free(&u);
		eng_destroy(e);
	}
}

Test(chip, fixed_memory_answers_after_latency_and_counts)
{
	eng *e = eng_create(0);
	eng_clock clk = eng_clock_mhz(500);
	memport m;
	cr_assert_eq(mem_init_fixed(&m, e, clk, 20, NULL), 0);
	mem_req r = {4096, 36, MEM_TRI, 0, 0, NULL, 0};
	ndone = 0;
	mem_access(&m, &r, on_done, NULL, 0);
	mem_req wr = {8192, 524, MEM_KD, 1, 0, NULL, 0};
	mem_access(&m, &wr, NULL, NULL, 0);
	eng_run(e, ENG_FOREVER);
	cr_assert_eq(ndone, 1);
	cr_assert_eq(done_at[0], 20 * 2000ull);
	cr_assert_eq(m.n.reads[MEM_TRI], 1);
	cr_assert_eq(m.n.read_bytes[MEM_TRI], 36);
	cr_assert_eq(m.n.writes[MEM_KD], 1);
	cr_assert_eq(m.n.write_bytes[MEM_KD], 524);
	mem_free(&m);
	eng_destroy(e);
}

/* ---- whole frames ---- */

static void small_cfg(saar_config *c, int size)
{
	cfg_defaults(c);
	c->frame.width = c->frame.height = size;
}

/* kernel-ref's 8-bit frame and stats */
static uint8_t *reference(const world *w, const saar_config *c, render_stats *st)
{
	return tu_reference(w, c, st);
}

static void assert_same_image(const chip *ch, const uint8_t *ref, const char *what)
{
	int n = ch->cfg.frame.width * ch->cfg.frame.height * 3;
	uint8_t *a = malloc((size_t)n);
	fb_to_rgb8(&ch->fb, a, NULL);
	img_cmp cmp = img_compare(a, ref, ch->cfg.frame.width, ch->cfg.frame.height);
	cr_assert(cmp.identical, "%s: %llu pixels differ from kernel-ref (PSNR %.2f)", what,
	          (unsigned long long)cmp.differing_pixels, cmp.psnr);
	free(a);
}

/* threads_per_rtp 1, 4, 32 x rtps 1, 4: every image equals kernel-ref's
 * (so more threads never change it), and the functional counts agree. */
static void image_matrix(const world *w, const char *what)
{
	saar_config c;
	small_cfg(&c, 128);
	render_stats st;
	uint8_t *ref = reference(w, &c, &st);
	static const int threads[] = {1, 4, 32}, rtps[] = {1, 4};
	for (int a = 0; a < 3; a++)
		for (int b = 0; b < 2; b++) {
			c.chip.threads_per_rtp = threads[a];
			c.chip.rtps = rtps[b];
			chip *ch = tu_run_chip(w, &c);
			char lbl[256];
			snprintf(lbl, sizeof lbl, "%s, %d threads x %d RTPs", what, threads[a],
			         rtps[b]);
			assert_same_image(ch, ref, lbl);
			cr_assert_eq(stats_get(&ch->st, "trav.node_steps"), st.trav.node_steps,
			             "%s", lbl);
			cr_assert_eq(stats_get(&ch->st, "trav.leaf_visits"), st.trav.leaf_visits,
			             "%s", lbl);
			for (int t = 0; t < PKT_NTYPES; t++) {
				char nm[64];
				snprintf(nm, sizeof nm, "rays.%s", pkt_type_name(t));
				cr_assert_eq(stats_get(&ch->st, nm), st.rays[t], "%s: %s", lbl, nm);
			}
			cr_assert_eq(stats_get(&ch->st, "skip.box_miss_packets"),
			             st.box_miss_packets);
			cr_assert_gt(chip_cycles(ch), 0);
			chip_destroy(ch);
		}
	free(ref);
}

Test(chip, image_identical_embedded_any_threads_and_rtps)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	image_matrix(&w, "embedded");
	world_free(&w);
}

static void view_test(const char *name)
{
	char views[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	world w;
	tu_load_world(&w, NULL, views, name);
	image_matrix(&w, name);
	world_free(&w);
}

#define VIEW_TEST(n)                                                                               \
	Test(chip_views, n, .timeout = 600)                                                        \
	{                                                                                          \
		view_test(#n);                                                                     \
	}
VIEW_TEST(cornell)
VIEW_TEST(teapot)
VIEW_TEST(dragon4)
VIEW_TEST(dragon3)
VIEW_TEST(dragon2)
VIEW_TEST(bunny)
VIEW_TEST(sponza)
VIEW_TEST(conference)
VIEW_TEST(robots)
VIEW_TEST(sibenik)

Test(chip_views, every_view_has_a_test)
{
	static const char *const covered[] = {"cornell", "teapot", "dragon4", "dragon3",
	                                      "dragon2", "bunny",  "sponza",  "conference",
	                                      "robots",  "sibenik"};
	char views[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	char names[64][VIEW_NAME_MAX];
	diag d;
	int n = view_list(views, names, 64, &d);
	cr_assert_gt(n, 0, "%s", d.msg);
	for (int k = 0; k < n; k++) {
		int ok = 0;
		for (size_t i = 0; i < sizeof covered / sizeof *covered; i++)
			ok |= !strcmp(names[k], covered[i]);
		cr_assert(ok, "view %s of views.yaml has no chip test", names[k]);
	}
}

Test(chip, stack_overflow_spills_and_keeps_the_image)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	small_cfg(&c, 64);
	c.chip.stack_depth = 2; /* below the tree depth: cfg_validate would refuse it */
	c.chip.rtps = c.chip.threads_per_rtp = 1; /* nothing hides the refill latency */
	render_stats st;
	uint8_t *ref = reference(&w, &c, &st);
	chip *ch = tu_run_chip(&w, &c);
	assert_same_image(ch, ref, "stack depth 2");
	uint64_t ov = stats_get(&ch->st, "trav.stack_overflows");
	cr_assert_gt(ov, 0, "no overflow with a 2-entry stack");
	cr_assert_gt(stats_get(&ch->st, "trav.stack_refills"), 0);
	cr_assert_eq(stats_get(&ch->st, "mem.kd.writes"), ov);
	cr_assert_eq(stats_get(&ch->st, "mem.kd.write_bytes"), ov * THR_STACK_ENTRY_BYTES);
	/* a deep stack never spills, and refills cost time a single thread cannot hide */
	c.chip.stack_depth = 64;
	chip *deep = tu_run_chip(&w, &c);
	cr_assert_eq(stats_get(&deep->st, "trav.stack_overflows"), 0);
	cr_assert_gt(chip_cycles(ch), chip_cycles(deep));
	chip_destroy(deep);
	chip_destroy(ch);
	free(ref);
	world_free(&w);
}

/* The mistake: a traversal that never pushes the far child (rays that
 * need it lose their hits there). The chip and kernel-ref's packet render
 * both step through pkt_trav_next, so they make it alike and the packet
 * comparison still says identical; the single-ray render traverses on its
 * own and must see it. Without the fault both say identical. */
Test(chip, wrong_packet_traversal_is_caught_by_the_single_ray_reference)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	small_cfg(&c, 64);
	for (int fault = 0; fault < 2; fault++) {
		pkt_trav_fault = fault ? PKT_FAULT_NO_FAR_PUSH : PKT_FAULT_NONE;
		chip *ch = tu_run_chip(&w, &c);
		chip_check k;
		diag d;
		cr_assert_eq(chip_check_frame(ch, &k, &d), 0, "%s", d.msg);
		cr_assert(k.cmp.identical, "fault %d: the packet render makes the same mistake",
		          fault);
		if (fault)
			cr_assert_gt(k.single.differing_pixels, 100,
			             "a lost far child went unseen (%llu pixels differ)",
			             (unsigned long long)k.single.differing_pixels);
		else
			cr_assert(k.single.identical,
			          "%llu pixels differ from the single-ray render",
			          (unsigned long long)k.single.differing_pixels);
		chip_destroy(ch);
	}
	pkt_trav_fault = PKT_FAULT_NONE;
	world_free(&w);
}

Test(chip, deterministic_cycles_and_counters)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	small_cfg(&c, 96);
	c.chip.thread_sched = CFG_SCHED_OLDEST_FIRST;
	c.chip.tile_order = CFG_TILES_MORTON;
	c.frame.frames = 2;
	chip *a = tu_run_chip(&w, &c), *b = tu_run_chip(&w, &c);
	cr_assert_eq(a->frame_cycles[0], b->frame_cycles[0]);
	cr_assert_eq(a->frame_cycles[1], b->frame_cycles[1]);
	cr_assert_eq(a->st.n, b->st.n);
	for (size_t i = 0; i < a->st.n; i++)
		cr_assert_eq(*a->st.e[i].value, *b->st.e[i].value, "%s", a->st.e[i].name);
	chip_destroy(a);
	chip_destroy(b);
	world_free(&w);
}

Test(chip, units_and_threads_account_for_all_time)
{
	world w;
	tu_load_world(&w, NULL, NULL, NULL);
	saar_config c;
	small_cfg(&c, 64);
	c.chip.masked_packets = false;
	chip *ch = tu_run_chip(&w, &c);
	uint64_t cyc = chip_cycles(ch), tot = 0;
	const char *st[] = {"threads.idle_ps", "threads.running_ps", "threads.waiting_memory_ps",
	                    "threads.waiting_unit_ps"};
	for (int s = 0; s < 4; s++)
		tot += chip_rtp_sum(ch, st[s]);
	cr_assert_eq(tot, cyc * ch->clk.period * (uint64_t)(ch->nrtp * ch->tpr));
	/* one trav op per kd step, one isect op per triangle test */
	cr_assert_eq(chip_rtp_sum(ch, "trav.ops"), stats_get(&ch->st, "trav.node_steps"));
	cr_assert_eq(chip_rtp_sum(ch, "isect.ops"), stats_get(&ch->st, "isect.tri_tests"));
	cr_assert_eq(stats_get(&ch->st, "mem.kd.reads"), stats_get(&ch->st, "trav.node_steps"));
	cr_assert_eq(stats_get(&ch->st, "mem.tri.reads"), stats_get(&ch->st, "isect.tri_tests"));
	cr_assert_leq(chip_rtp_sum(ch, "trav.busy_cycles"), cyc * (uint64_t)ch->nrtp);
	chip_destroy(ch);
	world_free(&w);
}
