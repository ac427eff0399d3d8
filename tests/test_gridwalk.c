/*
 * test_gridwalk.c: the grid traversal step by step (kernel-ref/gridwalk.c,
 * the chip's grid unit's state machine) against grid_pkt_trace: every
 * packet of whole frames (primary, shadow and secondary; frusta and rays
 * alone) traced both ways must give the same lanes and the same counts.
 */
#include "kernel-ref/gridwalk.h"
#include "tests/testutil.h"

/* The tracer under test: each packet traced by grid_pkt_trace and, on a
 * copy, by the walk; differences counted. */
typedef struct gw_check {
	const grid *g;
	uint64_t packets, lanes_differ, counts_differ;
	grid_counts a, b; /* totals of grid_pkt_trace and the walk */
} gw_check;

static ray_hit gw_ray(const void *ctx, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c)
{
	const gw_check *k = ctx;
	return k->g->tracer.ray(k->g, o, d, tmax, any_hit, c);
}

static uint64_t gw_packet(const void *ctx, packet *p, trav_entry *stack, int stack_max,
                          trav_counts *c)
{
	gw_check *k = (gw_check *)ctx; /* render_frame runs on one thread here */
	static packet q;
	q = *p;
	grid_counts a = {0}, b = {0};
	uint64_t ea = grid_pkt_trace(k->g, p, stack, stack_max, &a);
	uint64_t eb = grid_walk_trace(k->g, &q, stack, stack_max, &b);
	k->packets++;
	if (p->valid != q.valid) /* mistake: the walk drops or adds rays */
		k->lanes_differ++;
	for (int i = 0; i < PKT_RAYS; i++)
		if ((p->valid >> i & 1) &&
		    (memcmp(&p->t[i], &q.t[i], sizeof p->t[i]) || p->tri[i] != q.tri[i] ||
		     p->bu[i] != q.bu[i] || p->bv[i] != q.bv[i]))
			k->lanes_differ++;
	if (ea != eb || memcmp(&a, &b, sizeof a))
		k->counts_differ++;
#define ADD(f)                                                                                     \
	k->a.f += a.f;                                                                             \
	k->b.f += b.f
	ADD(slices);
	ADD(macro_skips);
	ADD(cells);
	ADD(tri_tests);
	ADD(mailbox_skips);
	ADD(culled);
	ADD(dda_rays);
#undef ADD
	grid_counts_add(c, &a);
	return ea;
}

/* Frames of w under the traversal variants, both ways; the totals of the
 * differences into out. */
static void gw_frames(const world *w, int size, gw_check *out)
{
	static const int var[][4] = {{8, 1, 6, 1}, {4, 1, 6, 1}, {1, 1, 6, 1}, {8, 0, 6, 1},
	                             {8, 1, 0, 1}, {8, 1, 2, 1}, {8, 1, 6, 0}};
	for (size_t v = 0; v < sizeof var / sizeof *var; v++) {
		grid_params gp;
		grid_params_default(&gp);
		gp.packet = var[v][0];
		gp.mailbox = var[v][1];
		gp.macro = var[v][2];
		gp.cull = var[v][3];
		grid g;
		diag d = {{0}};
		cr_assert_eq(grid_build(&g, &w->m, &gp, &d), 0, "%s", d.msg);
		gw_check k = {.g = &g};
		render_tracer tr = {&k, gw_ray, gw_packet, NULL};
		render_opts o;
		render_opts_default(&o);
		o.width = o.height = size;
		o.threads = 1;
		o.tracer = &tr;
		framebuf fb;
		render_stats st;
		cr_assert_eq(fb_init(&fb, size, size), 0);
		cr_assert_eq(render_frame(&w->m, &w->v, &o, &fb, &st, &d), 0, "%s", d.msg);
		fb_free(&fb);
		grid_free(&g);
		out->packets += k.packets;
		out->lanes_differ += k.lanes_differ;
		out->counts_differ += k.counts_differ;
#define ADD(f)                                                                                     \
	out->a.f += k.a.f;                                                                         \
	out->b.f += k.b.f
		ADD(slices);
		ADD(macro_skips);
		ADD(cells);
		ADD(tri_tests);
		ADD(mailbox_skips);
		ADD(culled);
		ADD(dda_rays);
#undef ADD
	}
}

/* Mistakes caught (each planted in gridwalk.c and seen failing here): a
 * mailbox the walk never consults (tests and counts grow), flags read
 * for the wrong block or a set flag taken as clear (cells skipped: other
 * hits), the DDA's next cell along the wrong axis, a ray alone whose
 * occluder does not end it (counts), the frustum's live rays not narrowed
 * after a slice. The scenes make every kind of work happen (the
 * totals are checked non-zero), so the equality is not vacuous. */
Test(gridwalk, equals_grid_pkt_trace, .timeout = 240)
{
	static const char *scenes[] = {NULL, "spd:balls:2", "spd:rings:2", "spd:tetra:4"};
	gw_check t = {0};
	for (size_t s = 0; s < sizeof scenes / sizeof *scenes; s++) {
		world_opts o;
		world_opts_default(&o);
		o.scene = scenes[s];
		world w;
		diag d = {{0}};
		cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
		gw_frames(&w, 48, &t);
		world_free(&w);
	}
	cr_assert_gt(t.packets, 0);
	cr_assert_eq(t.lanes_differ, 0, "%llu lanes differ", (unsigned long long)t.lanes_differ);
	cr_assert_eq(t.counts_differ, 0,
	             "%llu packets' counts differ (cells %llu vs %llu, tests %llu vs %llu, mailbox "
	             "%llu vs %llu, macro %llu vs %llu)",
	             (unsigned long long)t.counts_differ, (unsigned long long)t.a.cells,
	             (unsigned long long)t.b.cells, (unsigned long long)t.a.tri_tests,
	             (unsigned long long)t.b.tri_tests, (unsigned long long)t.a.mailbox_skips,
	             (unsigned long long)t.b.mailbox_skips, (unsigned long long)t.a.macro_skips,
	             (unsigned long long)t.b.macro_skips);
	/* every kind of work happened */
	cr_assert_gt(t.a.macro_skips, 0);
	cr_assert_gt(t.a.mailbox_skips, 0);
	cr_assert_gt(t.a.culled, 0);
	cr_assert_gt(t.a.dda_rays, 0);
}
