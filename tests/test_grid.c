/*
 * test_grid.c: the uniform grid and its coherent traversal
 * (kernel-ref/grid.c, gridtrav.c; seed 003) against the kd-tree: the same
 * frames exactly, on the embedded scene, procedural scenes, a shared view
 * and the animated Robots; mailboxing and macrocells change the counts,
 * never the image.
 */
#include "kernel-ref/grid.h"
#include "tests/testutil.h"

/* A frame of w with options o (tracer tr: NULL for the kd-tree) as 8-bit
 * RGB (malloc'd); its counts into st. */
static uint8_t *grid_image(const world *w, render_opts o, const render_tracer *tr, render_stats *st)
{
	framebuf fb;
	diag d = {{0}};
	o.tracer = tr;
	cr_assert_eq(fb_init(&fb, o.width, o.height), 0);
	cr_assert_eq(render_frame(&w->m, &w->v, &o, &fb, st, &d), 0, "%s", d.msg);
	uint8_t *rgb = malloc((size_t)o.width * (size_t)o.height * 3);
	cr_assert(rgb);
	fb_to_rgb8(&fb, rgb, NULL);
	fb_free(&fb);
	return rgb;
}

static size_t grid_differ(const uint8_t *a, const uint8_t *b, int w, int h)
{
	size_t n = 0;
	for (size_t i = 0; i < (size_t)w * (size_t)h; i++)
		n += memcmp(a + 3 * i, b + 3 * i, 3) != 0;
	return n;
}

/* The grid's frames of world w under every traversal variant (packets of
 * 8x8 and 4x4, single rays; mailbox, macrocells, culling on and off) against
 * the kd-tree's packet frame: the number of pixels the worst differs in. */
static size_t grid_variants_differ(const world *w, int size)
{
	render_opts o;
	render_opts_default(&o);
	o.width = o.height = size;
	render_stats st;
	uint8_t *kd = grid_image(w, o, NULL, &st);
	/* packet side, mailbox, macrocell side, frustum culling */
	static const int var[][4] = {{8, 1, 6, 1}, {4, 1, 6, 1}, {1, 1, 6, 1}, {8, 0, 6, 1},
	                             {8, 1, 0, 1}, {8, 1, 2, 1}, {8, 1, 6, 0}};
	size_t worst = 0;
	for (size_t k = 0; k < sizeof var / sizeof *var; k++) {
		grid_params gp;
		grid_params_default(&gp);
		gp.packet = var[k][0];
		gp.mailbox = var[k][1];
		gp.macro = var[k][2];
		gp.cull = var[k][3];
		grid g;
		diag d = {{0}};
		cr_assert_eq(grid_build(&g, &w->m, &gp, &d), 0, "%s", d.msg);
		uint8_t *gi = grid_image(w, o, &g.tracer, &st);
		size_t n = grid_differ(kd, gi, size, size);
		if (n > worst)
			worst = n;
		free(gi);
		grid_free(&g);
	}
	free(kd);
	return worst;
}

static void grid_load(world *w, const char *path)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = path;
	diag d = {{0}};
	cr_assert_eq(world_load(w, &o, &d), 0, "%s", d.msg);
}

/* Mistakes caught: a ray that stops in a cell on a hit beyond the cell's
 * far boundary (GRID_FAULT_EARLY_STOP), a slice's cells taken from the
 * frustum at its entry plane only (GRID_FAULT_NARROW_FRUSTUM); both are
 * planted here and must change the frame, so the equality is not
 * vacuous. (The grid.eps margins are a safeguard against rounding: with
 * them dropped these frames still match, so no test here claims them.) */
Test(grid, frames_equal_kd_embedded_and_spd, .timeout = 120)
{
	static const char *scenes[] = {NULL, "spd:balls:2", "spd:tetra:4", "spd:rings:2",
	                               "spd:mount:3"};
	size_t planted[3] = {0};
	for (size_t k = 0; k < sizeof scenes / sizeof *scenes; k++) {
		world w;
		grid_load(&w, scenes[k]);
		size_t n = grid_variants_differ(&w, 64);
		cr_assert_eq(n, 0, "%s: the grid's frame differs from the kd-tree's in %zu pixels",
		             scenes[k] ? scenes[k] : "embedded", n);
		for (int f = GRID_FAULT_EARLY_STOP; f <= GRID_FAULT_NARROW_FRUSTUM; f++) {
			grid_fault = f;
			planted[f] += grid_variants_differ(&w, 64);
			grid_fault = GRID_FAULT_NONE;
		}
		world_free(&w);
	}
	cr_assert(planted[GRID_FAULT_EARLY_STOP] > 0, "stopping on a hit beyond the cell not seen");
	cr_assert(planted[GRID_FAULT_NARROW_FRUSTUM] > 0, "a frustum too narrow not seen");
}

/* A shared view (the conference room: long thin triangles, many cells per
 * triangle) at a small size. Mistake: as above, on real geometry. */
Test(grid, frames_equal_kd_shared_view, .timeout = 300)
{
	char views[1024], sc[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	SCENE_OR_SKIP(sc, "conference_69k/conference.obj.gz");
	world_opts o;
	world_opts_default(&o);
	o.views = views;
	o.view = "conference";
	world w;
	diag d = {{0}};
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	size_t n = grid_variants_differ(&w, 48);
	cr_assert_eq(n, 0, "conference: the grid's frame differs in %zu pixels", n);
	world_free(&w);
}

/* Mailboxing, macrocells and frustum culling change the work, not the
 * frame. Mistakes: a mailbox that never skips (or a flag ignored),
 * macrocells never skipped (their flags all set, or the layer never
 * consulted), culling that never culls. */
Test(grid, mailbox_and_macrocells_change_counts, .timeout = 60)
{
	world w;
	grid_load(&w, "spd:balls:2");
	render_opts o;
	render_opts_default(&o);
	o.width = o.height = 64;
	grid_params gp;
	grid_params_default(&gp);
	grid g;
	diag d = {{0}};
	render_stats on, off;
	cr_assert_eq(grid_build(&g, &w.m, &gp, &d), 0, "%s", d.msg);
	uint8_t *a = grid_image(&w, o, &g.tracer, &on);
	grid_free(&g);
	gp.mailbox = 0;
	cr_assert_eq(grid_build(&g, &w.m, &gp, &d), 0, "%s", d.msg);
	uint8_t *b = grid_image(&w, o, &g.tracer, &off);
	grid_free(&g);
	cr_assert_eq(grid_differ(a, b, 64, 64), 0);
	cr_assert(on.trav.tri_tests < off.trav.tri_tests,
	          "mailbox: %llu triangle tests, without: %llu",
	          (unsigned long long)on.trav.tri_tests, (unsigned long long)off.trav.tri_tests);
	cr_assert_eq(on.trav.node_steps, off.trav.node_steps, "the mailbox changed the slices");
	gp.mailbox = 1;
	gp.macro = 0;
	cr_assert_eq(grid_build(&g, &w.m, &gp, &d), 0, "%s", d.msg);
	free(b);
	b = grid_image(&w, o, &g.tracer, &off);
	grid_free(&g);
	cr_assert_eq(grid_differ(a, b, 64, 64), 0);
	cr_assert(on.trav.node_steps < off.trav.node_steps,
	          "macrocells: %llu slice steps, without: %llu",
	          (unsigned long long)on.trav.node_steps, (unsigned long long)off.trav.node_steps);
	gp.macro = 6;
	gp.cull = 0;
	cr_assert_eq(grid_build(&g, &w.m, &gp, &d), 0, "%s", d.msg);
	free(b);
	b = grid_image(&w, o, &g.tracer, &off);
	grid_free(&g);
	cr_assert_eq(grid_differ(a, b, 64, 64), 0);
	cr_assert(on.trav.ray_tri_tests < off.trav.ray_tri_tests,
	          "culling: %llu ray-triangle tests, without: %llu",
	          (unsigned long long)on.trav.ray_tri_tests,
	          (unsigned long long)off.trav.ray_tri_tests);
	free(a);
	free(b);
	world_free(&w);
}

/* The lambda heuristic (seed 003 §3): about lambda N cells, nearly cubic.
 * Mistakes: the cube root left out, the volume of the wrong box, the
 * resolution not following lambda. */
Test(grid, resolution_follows_lambda)
{
	world w;
	grid_load(&w, "spd:balls:3"); /* a near-cubic box */
	for (double lambda = 1; lambda <= 16; lambda *= 4) {
		grid_params gp;
		grid_params_default(&gp);
		gp.lambda = lambda;
		grid g;
		diag d = {{0}};
		cr_assert_eq(grid_build(&g, &w.m, &gp, &d), 0, "%s", d.msg);
		double cells = (double)g.n[0] * g.n[1] * g.n[2], want = lambda * w.m.ntris;
		cr_assert(cells > 0.5 * want && cells <= 1.01 * want,
		          "lambda %g: %g cells for %u triangles", lambda, cells, w.m.ntris);
		for (int a = 0; a < 3; a++) {
			double side = 1.0 / g.scale[a], side0 = 1.0 / g.scale[0];
			cr_assert(side < 1.5 * side0 && side > side0 / 1.5, "cells not cubic");
		}
		grid_free(&g);
	}
	world_free(&w);
}

/* The animated Robots: the grid rebuilt with every frame's world gives the
 * kd-tree's frame. Mistake: the grid not rebuilt (world_set_time leaving
 * the first frame's grid: robots in the wrong places, lists naming a freed
 * image). */
Test(grid, robots_frames_equal_kd, .timeout = 300)
{
	char aff[1024];
	SCENE_OR_SKIP(aff, "bart_robots_aff/aff/Robot.aff");
	world_opts o;
	world_opts_default(&o);
	o.scene = aff;
	o.accel = WORLD_ACCEL_GRID;
	world w;
	diag d = {{0}};
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	cr_assert(w.grid);
	render_opts ro;
	render_opts_default(&ro);
	ro.width = 64;
	ro.height = 48;
	render_stats st;
	const double ts[] = {0, 12.5, 30};
	for (int k = 0; k < 3; k++) {
		if (k)
			cr_assert_eq(world_set_time(&w, &o, ts[k], &d), 0, "%s", d.msg);
		cr_assert_eq(w.grid->m, &w.m);
		uint8_t *kd = grid_image(&w, ro, NULL, &st);
		uint8_t *gi = grid_image(&w, ro, &w.grid->tracer, &st);
		size_t n = grid_differ(kd, gi, ro.width, ro.height);
		cr_assert_eq(n, 0, "t=%g: the grid's frame differs in %zu pixels", ts[k], n);
		free(kd);
		free(gi);
	}
	world_free(&w);
}

/* rtref --accel grid traces the grid (the stats say so, with other
 * counts) and writes the kd-tree's image; bad values are one line and
 * status 2; saarsim takes it (and chip.accel grid). Mistake: the flag parsed but the kd-tree
 * traced. */
Test(grid, rtref_flag, .timeout = 60)
{
	char dir[128];
	tu_tmpdir(dir, sizeof dir);
	char args[600];
	snprintf(args, sizeof args, "--size 32x32 --out %s/k.ppm --stats %s/k.json", dir, dir);
	cr_assert_eq(tu_prog(dir, "rtref", args), 0);
	snprintf(args, sizeof args, "--size 32x32 --accel grid --out %s/g.ppm --stats %s/g.json",
	         dir, dir);
	cr_assert_eq(tu_prog(dir, "rtref", args), 0);
	char *gs = tu_slurp(dir, "g.json"), *ks = tu_slurp(dir, "k.json");
	cr_assert(strstr(gs, "\"accel\": \"grid\"") || strstr(gs, "\"accel\":\"grid\""),
	          "stats without accel grid");
	cr_assert(strstr(gs, "\"grid\""));
	char *gn = strstr(gs, "\"kd_node_visits\""), *kn = strstr(ks, "\"kd_node_visits\"");
	cr_assert(gn && kn && strncmp(gn, kn, 32), "the same counts with --accel grid");
	snprintf(args, sizeof args, "cmp -s %s/g.ppm %s/k.ppm", dir, dir);
	cr_assert_eq(tu_run(args), 0, "the grid's image differs");
	cr_assert_eq(tu_prog(dir, "rtref", "--accel octree"), 2);
	tu_one_line(dir, "rtref", "--accel");
	cr_assert_eq(tu_prog(dir, "rtref", "--accel grid --grid-packet 3"), 2);
	cr_assert_eq(tu_prog(dir, "rtref", "--accel grid --cone-cull"), 2);
	/* the chip's grid unit (issue 34 item 4): saarsim takes it, and
	 * refuses what kernel-ref's grid tracer cannot check */
	cr_assert_eq(tu_prog(dir, "saarsim", "--accel grid --size 8x8"), 0);
	cr_assert_eq(tu_prog(dir, "saarsim", "--set chip.accel=grid --size 8x8"), 0);
	cr_assert_eq(tu_prog(dir, "saarsim", "--accel grid --size 8x8 --set chip.cone_cull=true"),
	             2);
	cr_assert_eq(tu_prog(dir, "saarsim", "--set chip.accel=octree --size 8x8"), 2);
	tu_one_line(dir, "saarsim", "chip.accel");
}

/* scripts/accel-doc.py (make accel's writer) on runs that are not there:
 * one line naming the file, status 2, no document. Mistake: a missing run
 * written as an empty table or a traceback. */
Test(grid, accel_doc_bad_input, .timeout = 60)
{
	char dir[128], cmd[1200];
	tu_tmpdir(dir, sizeof dir);
	const char *r = getenv("SAAR_ROOT");
	snprintf(cmd, sizeof cmd,
	         "python3 %s/scripts/accel-doc.py %s/none %s/A.md 8x8 cornell 0 cornell 32x32 "
	         ">%s/out 2>%s/err",
	         r && *r ? r : ".", dir, dir, dir, dir);
	cr_assert_eq(tu_run(cmd), 2);
	tu_one_line(dir, "accel-doc", "cornell-kd.json");
	cr_assert(!tu_exists(dir, "A.md"), "a document written from no runs");
}
