/*
 * test_chip_grid.c: the chip on a uniform grid (issue 34 item 4;
 * units/gridtrav.h, kernel-ref/gridimage.h): every frame is kernel-ref's
 * grid frame, the grid unit's counts are kernel-ref's, and it reads the
 * grid from its memory only.
 */
#include "kernel-ref/gridimage.h"
#include "sim/memconfig.h"
#include "tests/chiptest.h"

/* A world with a grid of parameters gp (NULL: the defaults). */
static void load_grid(world *w, const char *path, const char *views, const char *vname,
                      const grid_params *gp)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = path;
	o.views = views;
	o.view = vname;
	o.accel = WORLD_ACCEL_GRID;
	if (gp)
		o.gp = *gp;
	diag d;
	cr_assert_eq(world_load(w, &o, &d), 0, "%s", d.msg);
	cr_assert(w->grid, "no grid");
}

/* tu_cfg_small's chip walking the grid. */
static void cfg_small(saar_config *c, int size, const char *mode, int with_vma)
{
	tu_cfg_small(c, size, mode, with_vma);
	c->chip.accel = CFG_ACCEL_GRID;
}

/* kernel-ref's grid frame's counts (one thread: the frame's packets). */
static render_stats ref_counts(const world *w, int size)
{
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = size;
	ro.threads = 1;
	ro.tracer = &w->grid->tracer;
	framebuf fb;
	cr_assert_eq(fb_init(&fb, size, size), 0);
	render_stats st;
	diag d;
	cr_assert_eq(render_frame(&w->m, &w->v, &ro, &fb, &st, &d), 0, "%s", d.msg);
	fb_free(&fb);
	return st;
}

/* The chip's counts are kernel-ref's grid counts: slice steps, cells,
 * packet- and ray-triangle tests. */
static void assert_counts(chip *ch, const world *w, int size, const char *what)
{
	render_stats st = ref_counts(w, size);
	uint64_t steps = stats_get(&ch->st, "trav.node_steps"),
	         cells = stats_get(&ch->st, "trav.leaf_visits"),
	         tests = stats_get(&ch->st, "isect.tri_tests"),
	         rays = stats_get(&ch->st, "isect.ray_tri_tests");
	cr_assert(steps == st.trav.node_steps && cells == st.trav.leaf_visits &&
	              tests == st.trav.tri_tests && rays == st.trav.ray_tri_tests,
	          "%s: chip slices %llu cells %llu tests %llu ray tests %llu; kernel-ref %llu %llu "
	          "%llu %llu",
	          what, (unsigned long long)steps, (unsigned long long)cells,
	          (unsigned long long)tests, (unsigned long long)rays,
	          (unsigned long long)st.trav.node_steps, (unsigned long long)st.trav.leaf_visits,
	          (unsigned long long)st.trav.tri_tests, (unsigned long long)st.trav.ray_tri_tests);
}

/* Every frame, in cycle and functional fidelity, with and without the
 * VMA, and under the traversal variants (mailbox off, no macrocells,
 * packets of 4x4, single rays) is kernel-ref's grid frame, with its
 * counts (a variant without the mailbox: the mailbox's effect on the
 * tests is the chip's as kernel-ref's). Mistakes caught (each planted in
 * units/gridtrav.c and seen failing): a triangle culled by the frustum
 * counted as a test (counts), a macrocell flag read but taken as clear
 * (the frame), the slice steps not counted (counts). */
Test(chip_grid, frames_and_counts_match_kernel_ref, .timeout = 300)
{
	static const char *scenes[] = {NULL, "spd:balls:2", "spd:rings:2"};
	static const int var[][4] = {
	    {8, 1, 6, 1}, {8, 0, 6, 1}, {8, 1, 0, 1}, {4, 1, 2, 0}, {1, 1, 6, 1}};
	const char *modes[] = {"cycle", "functional"};
	for (size_t s = 0; s < sizeof scenes / sizeof *scenes; s++)
		for (size_t k = 0; k < sizeof var / sizeof *var; k++) {
			grid_params gp;
			grid_params_default(&gp);
			gp.packet = var[k][0];
			gp.mailbox = var[k][1];
			gp.macro = var[k][2];
			gp.cull = var[k][3];
			world w;
			load_grid(&w, scenes[s], NULL, NULL, &gp);
			for (int m = 0; m < 2; m++) {
				saar_config c;
				cfg_small(&c, 40, modes[m], m == 1 && k == 0);
				char what[128];
				snprintf(what, sizeof what, "%s variant %zu %s",
				         scenes[s] ? scenes[s] : "embedded", k, modes[m]);
				chip *ch = tu_run_chip(&w, &c);
				tu_assert_identical(ch, what);
				assert_counts(ch, &w, 40, what);
				chip_destroy(ch);
			}
			world_free(&w);
		}
}

/* A shared view (the conference room) at a small size. */
Test(chip_grid, shared_view_matches_kernel_ref, .timeout = 300)
{
	char views[1024], sc[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	SCENE_OR_SKIP(sc, "conference_69k/conference.obj.gz");
	world w;
	load_grid(&w, NULL, views, "conference", NULL);
	saar_config c;
	cfg_small(&c, 48, "cycle", 0);
	chip *ch = tu_run_chip(&w, &c);
	tu_assert_identical(ch, "conference");
	assert_counts(ch, &w, 48, "conference");
	chip_destroy(ch);
	world_free(&w);
}

/* The grid unit reads the grid from the chip's memory: a cell list read
 * one entry off (THR_MUT_GRID_LIST_NEXT) and a grid image whose cell
 * offsets were cleared in memory (the host's grid unchanged) both change
 * the frame. Mistakes caught: the unit taking lists or ranges from the
 * host's grid (the frame right although memory is wrong). */
Test(chip_grid, wrong_list_or_cells_change_the_frame, .timeout = 120)
{
	world w;
	load_grid(&w, NULL, NULL, NULL, NULL);
	saar_config c;
	cfg_small(&c, 48, "cycle", 0);
	diag d;
	chip *ch = chip_create(&c, &w, &d);
	cr_assert(ch, "%s", d.msg);
	ch->env.mutant = THR_MUT_GRID_LIST_NEXT;
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	chip_check k;
	cr_assert_eq(chip_check_frame(ch, &k, &d), 0, "%s", d.msg);
	cr_assert_not(k.cmp.identical, "a list read one entry off gave the frame");
	chip_destroy(ch);

	ch = chip_create(&c, &w, &d);
	cr_assert(ch, "%s", d.msg);
	uint64_t n = ch->gimg.refs_base - ch->gimg.cells_base;
	uint8_t *zero = calloc(1, n);
	cr_assert(zero);
	cr_assert_eq(ms_write(&ch->store, ch->gimg.cells_base, n, zero), 0);
	free(zero);
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	cr_assert_eq(chip_check_frame(ch, &k, &d), 0, "%s", d.msg);
	cr_assert_not(k.cmp.identical, "empty cells in memory gave the frame");
	chip_destroy(ch);
	world_free(&w);
}

/* With a world cache, functional runs keep the frame's packet record and
 * replay it (sim/modes/stored.c): a grid run after a kd run of the same
 * frame must not replay the kd record (its reads hit the same bytes of
 * the frame's image, so the replay's checksums would not see it). Mistake
 * caught (seen failing): the record's key without the grid (the grid
 * run's counts are the kd-tree's). */
Test(chip_grid, packet_record_is_not_the_kd_trees, .timeout = 120)
{
	char dir[128];
	tu_tmpdir(dir, sizeof dir);
	for (int a = 0; a < 3; a++) { /* kd, grid (recorded), grid (replayed) */
		world_opts o;
		world_opts_default(&o);
		o.cache_dir = dir;
		o.accel = a ? WORLD_ACCEL_GRID : WORLD_ACCEL_KD;
		world w;
		diag d;
		cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
		saar_config c;
		cfg_small(&c, 40, "functional", 0);
		c.chip.accel = a ? CFG_ACCEL_GRID : CFG_ACCEL_KD;
		chip *ch = tu_run_chip(&w, &c);
		tu_assert_identical(ch, a ? "grid" : "kd");
		if (a)
			assert_counts(ch, &w, 40, a == 1 ? "grid after kd" : "grid replayed");
		chip_destroy(ch);
		world_free(&w);
	}
}

/* The report names the grid (config.chip.accel, the `grid` section with
 * its image's bases) with --accel grid, and a kd run's has no `grid`
 * section (default reports as before). Mistakes caught: the section never
 * written (planted, seen failing), written for kd runs, bases out of
 * order. */
Test(chip_grid, report_names_the_grid, .timeout = 60)
{
	char dir[128], args[400];
	tu_tmpdir(dir, sizeof dir);
	snprintf(args, sizeof args, "--size 16x16 --accel grid --quiet --report %s/g.json", dir);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 0);
	snprintf(args, sizeof args, "--size 16x16 --quiet --report %s/k.json", dir);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 0);
	char *g = tu_slurp(dir, "g.json"), *k = tu_slurp(dir, "k.json");
	cr_assert(strstr(g, "\"accel\": \"grid\""), "config.chip.accel is not grid");
	cr_assert(strstr(k, "\"accel\": \"kd\""), "config.chip.accel is not kd");
	cr_assert_null(strstr(k, "\"grid\": {"), "a kd report with a grid section");
	char *s = strstr(g, "\"grid\": {");
	cr_assert(s, "no grid section");
	unsigned long long cb = 0, rb = 0, mb = 0;
	char *p = strstr(s, "\"cells_base\": "), *q = strstr(s, "\"refs_base\": "),
	     *r = strstr(s, "\"macro_base\": ");
	cr_assert(p && q && r);
	cb = strtoull(p + 14, NULL, 10);
	rb = strtoull(q + 13, NULL, 10);
	mb = strtoull(r + 14, NULL, 10);
	cr_assert(cb > 0 && cb < rb && rb < mb, "bases %llu %llu %llu", cb, rb, mb);
}

/* Damaged grid data in the chip's memory (every cell's list offsets set
 * to 0xff..: ranges past the cell lists) fails the frame with one message
 * naming the grid, in cycle and functional fidelity, instead of reading
 * lists out of bounds or drawing a wrong frame as if memory were sound.
 * Mistake caught (planted, seen failing): the range not checked against
 * the references (here the cells then read as empty: the frame ends
 * without a word). */
Test(chip_grid, damaged_cells_fail_the_frame, .timeout = 120)
{
	world w;
	load_grid(&w, NULL, NULL, NULL, NULL);
	const char *modes[] = {"cycle", "functional"};
	for (int m = 0; m < 2; m++) {
		saar_config c;
		cfg_small(&c, 32, modes[m], 0);
		diag d = {{0}};
		chip *ch = chip_create(&c, &w, &d);
		cr_assert(ch, "%s", d.msg);
		uint64_t n = ch->gimg.refs_base - ch->gimg.cells_base;
		uint8_t *ff = malloc(n);
		cr_assert(ff);
		memset(ff, 0xff, n);
		cr_assert_eq(ms_write(&ch->store, ch->gimg.cells_base, n, ff), 0);
		free(ff);
		cr_assert_eq(chip_run(ch, &d), -1, "%s: the frame ended", modes[m]);
		cr_assert(strstr(d.msg, "grid") && strstr(d.msg, "damaged"), "%s: %s", modes[m],
		          d.msg);
		chip_destroy(ch);
	}
	world_free(&w);
}
