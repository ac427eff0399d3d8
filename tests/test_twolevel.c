/*
 * test_twolevel.c: two-level trees (kernel-ref/twolevel.c) against one
 * tree over the scene flattened at the same time. The bottom level is
 * built once; every frame moves the world and rebuilds only the top.
 */
#include "kernel-ref/tlflat.h"
#include "kernel-ref/twolevel.h"
#include "tests/testutil.h"

/* A frame of world w with options o as 8-bit RGB (malloc'd). */
static uint8_t *tl_image(const world *w, const render_opts *o)
{
	framebuf fb;
	diag d = {{0}};
	cr_assert_eq(fb_init(&fb, o->width, o->height), 0);
	render_stats st;
	cr_assert_eq(render_frame(&w->m, &w->v, o, &fb, &st, &d), 0, "%s", d.msg);
	uint8_t *rgb = malloc((size_t)o->width * (size_t)o->height * 3);
	cr_assert(rgb);
	fb_to_rgb8(&fb, rgb, NULL);
	fb_free(&fb);
	return rgb;
}

static size_t tl_differ(const uint8_t *a, const uint8_t *b, size_t npix)
{
	size_t n = 0;
	for (size_t i = 0; i < npix; i++)
		n += memcmp(a + 3 * i, b + 3 * i, 3) != 0;
	return n;
}

/* Every frame of world o (an AFF scene) at the times ts: the two-level
 * image by packets equals its single-ray image and the image of one tree
 * over the scene flattened at the time with each triangle tested in its
 * object's space (tlflat.h) exactly, and differs from the flattened
 * single tree's world-space image in at most max_share of the pixels (the
 * rounding of the world-space test). The two-level world (--two-level)
 * shades from its object-space image, the flat one from the scene
 * flattened at the time. */
static void tl_check_frames(world_opts *o, const double *ts, int nt, int w, int h, double max_share)
{
	world wd, wt;
	diag d = {{0}};
	o->have_anim_time = 1;
	o->anim_time = ts[0];
	o->two_level = 0;
	cr_assert_eq(world_load(&wd, o, &d), 0, "%s", d.msg);
	world_opts ot = *o;
	ot.two_level = 1;
	cr_assert_eq(world_load(&wt, &ot, &d), 0, "%s", d.msg);
	cr_assert(wt.tl);
	render_opts ro;
	render_opts_default(&ro);
	ro.width = w;
	ro.height = h;
	size_t npix = (size_t)w * (size_t)h;
	for (int k = 0; k < nt; k++) {
		if (k > 0) {
			cr_assert_eq(world_set_time(&wd, o, ts[k], &d), 0, "%s", d.msg);
			cr_assert_eq(world_set_time(&wt, &ot, ts[k], &d), 0, "%s", d.msg);
		}
		ro.tracer = NULL;
		ro.single_ray = 0;
		uint8_t *flat = tl_image(&wd, &ro);
		ro.tracer = &wt.tl->tracer;
		uint8_t *pk = tl_image(&wt, &ro);
		ro.single_ray = 1;
		uint8_t *sr = tl_image(&wt, &ro);
		tl_flat fl;
		cr_assert_eq(tl_flat_init(&fl, wt.tl, &wd.m, &d), 0, "%s", d.msg);
		ro.tracer = &fl.tracer;
		uint8_t *fo = tl_image(&wt, &ro);
		ro.single_ray = 0;
		uint8_t *fp = tl_image(&wt, &ro);
		tl_flat_free(&fl);
		size_t ps = tl_differ(pk, sr, npix), pf = tl_differ(pk, flat, npix);
		size_t po = tl_differ(pk, fo, npix), pp = tl_differ(fo, fp, npix);
		cr_assert_eq(ps, 0, "t=%g: two-level packets and single rays differ in %zu pixels",
		             ts[k], ps);
		cr_assert_eq(po, 0,
		             "t=%g: two-level and one flat tree (object-space tests) differ in %zu "
		             "pixels",
		             ts[k], po);
		cr_assert_eq(pp, 0,
		             "t=%g: the flat reference's two render paths differ in %zu pixels",
		             ts[k], pp);
		cr_assert((double)pf <= max_share * (double)npix,
		          "t=%g: two-level and flat differ in %zu of %zu pixels", ts[k], pf, npix);
		if (getenv("TL_SHOW_DIFF"))
			fprintf(stderr, "t=%g: two-level and flat differ in %zu of %zu pixels\n",
			        ts[k], pf, npix);
		free(flat);
		free(pk);
		free(sr);
		free(fo);
		free(fp);
	}
	world_free(&wt);
	world_free(&wd);
}

/* Mistakes: a wrong inverse (rays moved by the transpose, or translated
 * before rotating), an instance box left in object space, a top level not
 * rebuilt for the frame (instances where they were at the first time),
 * hits compared by object-local triangle addresses. Any of them moves
 * whole objects in the image; rounding of the world-space test moves at
 * most a few edge pixels (measured: 11, 1 and 0 of 19,200 at 160x120 on
 * Robots at t = 0, 12.5 and 30). Against the object-space flat tree
 * (tlflat.h) nothing may differ: a box test that drops a ray grazing an
 * instance (seen: slabs narrowed by 1e-6 and boxes not widened fail the
 * small scenes here by 169 to 2104 pixels) or a bottom level that loses
 * an edge hit shows. */
Test(twolevel, robots_frames_match_flattened, .timeout = 300)
{
	char aff[1024];
	SCENE_OR_SKIP(aff, "bart_robots_aff/aff/Robot.aff");
	world_opts o;
	world_opts_default(&o);
	o.scene = aff;
	const double ts[] = {0, 7.3, 12.5, 21, 30, 41.7};
	tl_check_frames(&o, ts, 6, 128, 96, 0.002);
}

static const char *SPIN =
    "v\nfrom 0 0 6\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\n"
    "l 2 4 6\nm\nvertices 4\n-3 -3 -1\n3 -3 -1\n3 3 -1\n-3 3 -1\ntriangles 2\n"
    "0 1 2\n0 2 3\nx spin {\nfm 0 0 0 0.9 0.2 0.2 0 0 0 10 0 0\nm\nvertices 3\n"
    "-1 -1 0\n1 -1 0\n0 1 0.5\ntriangles 1\n0 1 2\n}\nk spin {\n"
    "transl 4\n0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n3 0.5 0.2 1 0 0 0\n3 0.5 0.2 1 0 0 0\n"
    "rot 4\n0 0 0 1 0 0 0 0\n0 0 0 1 0 0 0 0\n3 0.3 0 1 250 0 0 0\n"
    "3 0.3 0 1 250 0 0 0\nscale 4\n0 1 1 1 0 0 0\n0 1 1 1 0 0 0\n"
    "3 1.5 0.7 1 0 0 0\n3 1.5 0.7 1 0 0 0\n}\n";

/* The same on a scene made here: a mesh at the root (an object without a
 * transform) and a spinning, moving, growing one in front of it, with a
 * camera, at four times. */
Test(twolevel, small_scene_frames, .timeout = 60)
{
	char dir[128], p[1024];
	tu_tmpdir(dir, sizeof dir);
	tu_write(p, sizeof p, dir, "spin.aff", SPIN);
	world_opts o;
	world_opts_default(&o);
	o.scene = p;
	const double ts[] = {0, 1, 1.7, 3};
	tl_check_frames(&o, ts, 4, 48, 48, 0.01);
}

/* rtref --two-level renders the frames through the two-level trees (its
 * stats say so) within the same tolerance of the flat frames; rtref
 * refuses it on a scene that is not AFF (saarsim's flag:
 * test_chip_twolevel.c). Mistake caught: the flag accepted but ignored. */
Test(twolevel, rtref_flag, .timeout = 60)
{
	char dir[128], p[1024], args[1400];
	tu_tmpdir(dir, sizeof dir);
	tu_write(p, sizeof p, dir, "spin.aff", SPIN);
	snprintf(args, sizeof args,
	         "--scene %s --size 32x32 --anim-fps 1 --frames 3 --two-level --out %s/t.ppm "
	         "--stats %s/t.json",
	         p, dir, dir);
	cr_assert_eq(tu_prog(dir, "rtref", args), 0);
	cr_assert(strstr(tu_slurp(dir, "t-0002.json"), "\"two_level\""), "stats without two_level");
	snprintf(args, sizeof args,
	         "--scene %s --size 32x32 --anim-fps 1 --frames 3 --out %s/f.ppm --stats %s/f.json",
	         p, dir, dir);
	cr_assert_eq(tu_prog(dir, "rtref", args), 0);
	/* traced another way: other traversal counts */
	char *ts = strstr(tu_slurp(dir, "t-0001.json"), "\"kd_node_visits\"");
	char *fs = strstr(tu_slurp(dir, "f-0001.json"), "\"kd_node_visits\"");
	cr_assert(ts && fs && strncmp(ts, fs, 32), "the same traversal counts with --two-level");
	for (int i = 0; i < 3; i++) {
		char a[32], b[32];
		snprintf(a, sizeof a, "t-%04d.ppm", i);
		snprintf(b, sizeof b, "f-%04d.ppm", i);
		const uint8_t *x = (const uint8_t *)tu_slurp(dir, a) + 13,
		              *y = (const uint8_t *)tu_slurp(dir, b) + 13;
		size_t n = tl_differ(x, y, 32 * 32);
		cr_assert(n <= 10, "frame %d: %zu pixels differ", i, n);
	}
	cr_assert_eq(tu_prog(dir, "rtref", "--scene spd:tetra --two-level"), 2);
	tu_one_line(dir, "rtref", "--two-level: needs an AFF scene");
}

/* Instances of one part share its object, and each keeps its own
 * triangles. Mistakes caught: parts that differ merged into one object
 * (the hash trusted without comparing), a hit named by the first
 * instance's triangles (every copy shaded as the first; here the copies
 * have other materials). */
Test(twolevel, instances_share_objects, .timeout = 60)
{
	char dir[128], p[1024];
	tu_tmpdir(dir, sizeof dir);
	tu_write(p, sizeof p, dir, "part.aff",
	         "m\nvertices 3\n-1 -1 0\n1 -1 0\n0 1 0\ntriangles 1\n0 1 2\n");
	tu_write(p, sizeof p, dir, "other.aff",
	         "m\nvertices 3\n-1 -1 0\n1 -1 0\n0 1.5 0\ntriangles 1\n0 1 2\n");
	tu_write(p, sizeof p, dir, "inst.aff",
	         "v\nfrom 0 0 8\nat 0 0 0\nup 0 1 0\nangle 60\nhither 1\nresolution 8 8\n"
	         "l 0 3 8\nfm 0 0 0 0.9 0.1 0.1 0 0 0 10 0 0\n"
	         "xs 1 1 1 0 0 1 0 -2.5 0 0 {\ni 0 part.aff\n}\n"
	         "fm 0 0 0 0.1 0.9 0.1 0 0 0 10 0 0\n"
	         "xs 1 1 1 0 0 1 30 2.5 0 0 {\ni 0 part.aff\n}\n"
	         "fm 0 0 0 0.1 0.1 0.9 0 0 0 10 0 0\n"
	         "x mover {\ni 0 other.aff\n}\n"
	         "k mover {\ntransl 4\n0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n1 0 2 -1 0 0 0\n"
	         "1 0 2 -1 0 0 0\n}\n");
	aff_scene a;
	diag d = {{0}};
	cr_assert_eq(aff_load(&a, p, NULL, NULL, &d), 0, "%s", d.msg);
	kd_params kp;
	kd_params_default(&kp);
	tl_scene t;
	cr_assert_eq(tl_build(&t, &a, &kp, &d), 0, "%s", d.msg);
	cr_assert(t.ninst == 3 && t.nobj == 2, "%u instances of %u objects, want 3 of 2", t.ninst,
	          t.nobj);
	tl_free(&t);
	aff_free(&a);
	world_opts o;
	world_opts_default(&o);
	o.scene = p;
	const double ts[] = {0, 0.5, 1};
	tl_check_frames(&o, ts, 3, 48, 48, 0.01);
}

/* Pixels in which the two-level frame of SPIN at time t (shade_fault
 * fault planted) differs from the flat frame, of 48 x 48. */
static size_t spin_differ(double t, int fault)
{
	char dir[128], p[1024];
	tu_tmpdir(dir, sizeof dir);
	tu_write(p, sizeof p, dir, "spin.aff", SPIN);
	world_opts o;
	world_opts_default(&o);
	o.scene = p;
	o.have_anim_time = 1;
	o.anim_time = t;
	world wd, wt;
	diag d = {{0}};
	cr_assert_eq(world_load(&wd, &o, &d), 0, "%s", d.msg);
	o.two_level = 1;
	cr_assert_eq(world_load(&wt, &o, &d), 0, "%s", d.msg);
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = 48;
	uint8_t *flat = tl_image(&wd, &ro);
	ro.tracer = &wt.tl->tracer;
	shade_fault = fault;
	uint8_t *two = tl_image(&wt, &ro);
	shade_fault = SHADE_FAULT_NONE;
	size_t n = tl_differ(flat, two, 48 * 48);
	free(flat);
	free(two);
	world_free(&wt);
	world_free(&wd);
	return n;
}

/* The two-level shading image is in object space, the same at every time
 * (its records do not move with the frame), and the shader moves a hit's
 * corners and normals into the world by its instance's matrices. Mistake
 * planted: the normals left in object space (the normal transform
 * skipped; the corners still moved): the spinning part is lit as if it
 * had not turned, so the frame differs from the flat one in far more
 * than the edge pixels the object-space test's rounding moves. */
Test(twolevel, normals_moved_back, .timeout = 60)
{
	const double ts[] = {1.7, 3};
	for (int k = 0; k < 2; k++) {
		size_t ok = spin_differ(ts[k], SHADE_FAULT_NONE);
		size_t bad = spin_differ(ts[k], SHADE_FAULT_NO_NORMAL_XF);
		cr_assert(ok <= 23, "t=%g: %zu pixels differ from the flat frame", ts[k], ok);
		cr_assert(bad > 100,
		          "t=%g: normals left in object space, yet only %zu pixels differ", ts[k],
		          bad);
	}
}

/* The shading image does not change between frames: world_set_time
 * moves only the top level. Mistake caught: the image rebuilt from the
 * scene flattened at the frame's time (world-space records: the warm
 * update would carry every moved part's records again). */
Test(twolevel, shading_image_is_the_same_at_every_time, .timeout = 60)
{
	char dir[128], p[1024];
	tu_tmpdir(dir, sizeof dir);
	tu_write(p, sizeof p, dir, "spin.aff", SPIN);
	world_opts o;
	world_opts_default(&o);
	o.scene = p;
	o.two_level = 1;
	world w;
	diag d = {{0}};
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	uint64_t n = w.m.size;
	uint8_t *b0 = malloc(n);
	cr_assert(b0);
	memcpy(b0, w.m.bytes, n);
	cr_assert_eq(world_set_time(&w, &o, 1.7, &d), 0, "%s", d.msg);
	cr_assert_eq(w.m.size, n);
	cr_assert(memcmp(b0, w.m.bytes, n) == 0, "the shading image changed with the time");
	free(b0);
	world_free(&w);
}
