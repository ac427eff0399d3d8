/*
 * test_rtref_cli.c: rtref end to end: a good run writes the image and a
 * JSON stats file; every kind of bad input gives one line on stderr, exit
 * status 2 and no output file.
 */
#include <math.h>

#include "kernel-ref/simd.h"
#include "tests/testutil.h"

static char dir[256];

static void setup(void)
{
	tu_tmpdir(dir, sizeof dir);
}

static int rtref(const char *args)
{
	return tu_prog(dir, "rtref", args);
}

#define exists(name)          tu_exists(dir, name)
#define slurp(name)           tu_slurp(dir, name)
#define one_line_naming(what) tu_one_line(dir, "rtref", what)

TestSuite(rtref_cli, .init = setup);

Test(rtref_cli, good_run_writes_image_and_stats)
{
	char args[1024];
	snprintf(args, sizeof args, "--size 64x48 --threads 2 --out %s/f.png --stats %s/s.json",
	         dir, dir);
	cr_assert_eq(rtref(args), 0);
	cr_assert(exists("f.png") && exists("s.json"));
	cr_assert_eq(tu_temps(dir, "f.png") + tu_temps(dir, "s.json"), 0);
	char p[512], buf[8192] = {0};
	snprintf(p, sizeof p, "%s/s.json", dir);
	FILE *f = fopen(p, "r");
	cr_assert(fread(buf, 1, sizeof buf - 1, f) > 0);
	fclose(f);
	const char *keys[] = {"\"rays\"",           "\"kd_node_visits\"", "\"leaf_visits\"",
	                      "\"triangle_tests\"", "\"build_ms\"",       "\"render_ms\"",
	                      "\"mrays_per_s\"",    "\"shadow\"",         "\"simd_lanes\""};
	for (size_t k = 0; k < sizeof keys / sizeof *keys; k++)
		cr_assert(strstr(buf, keys[k]), "stats lack %s", keys[k]);
	/* the packet groups' width of this build (make bench prints it) */
	int lanes = 0;
	cr_assert_eq(sscanf(strstr(buf, "\"simd_lanes\"") + 12, ": %d", &lanes), 1);
	cr_assert_eq(lanes, SIMD_W, "simd_lanes %d, the build's groups are %d wide", lanes, SIMD_W);
}

/* Mistake: --cone-cull ignored (render_opts.cone_cull not set: nothing
 * culled) or culling that changes the frame. The DRT room (lens and area
 * lights) with and without it: the same image bytes, and triangles culled
 * only with it. */
Test(rtref_cli, cone_cull_keeps_the_frame)
{
	char args[1024];
	for (int on = 0; on < 2; on++) {
		snprintf(args, sizeof args,
		         "--size 48x48 --spp 4 --aperture 0.8 --light-size 1.5 --out %s/c%d.ppm "
		         "--stats %s/c%d.json%s",
		         dir, on, dir, on, on ? " --cone-cull" : "");
		cr_assert_eq(rtref(args), 0, "%s", slurp("err"));
	}
	char cmd[1024];
	snprintf(cmd, sizeof cmd, "cmp -s %s/c0.ppm %s/c1.ppm", dir, dir);
	cr_assert_eq(tu_run(cmd), 0, "the frame changes with --cone-cull");
	cr_assert(strstr(slurp("c0.json"), "\"cone_culled\": 0,"),
	          "nothing culled without the flag");
	const char *s1 = slurp("c1.json");
	cr_assert(strstr(s1, "\"cone_culled\"") && !strstr(s1, "\"cone_culled\": 0,"),
	          "triangles culled with it");
}

/* The stats say which camera and lights were rendered. */
Test(rtref_cli, stats_describe_camera_and_lights)
{
	char args[512];
	snprintf(args, sizeof args, "--size 16x12 --eye 0,1,9 --light 2,3,4 --stats %s/s.json",
	         dir);
	cr_assert_eq(rtref(args), 0, "%s", slurp("err"));
	char *s = tu_squeeze_json(slurp("s.json"));
	cr_assert(strstr(s, "\"view\":\"custom\",\"camera\":{\"eye\":[0.0,1.0,9.0]"), "%s", s);
	cr_assert(strstr(s, "\"light_positions\":[[2.0,3.0,4.0]]"), "%s", s);
}

Test(rtref_cli, missing_scene_file)
{
	char args[1024];
	snprintf(args, sizeof args, "--scene %s/nope.obj --out %s/f.png", dir, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("nope.obj");
	cr_assert_not(exists("f.png"));
}

Test(rtref_cli, malformed_scene)
{
	char p[512], args[1024];
	tu_write(p, sizeof p, dir, "bad.obj", "v 1 2\nf 1 2 x\n\x01\x02garbage\n");
	snprintf(args, sizeof args, "--scene %s --out %s/f.png", p, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("bad.obj");
	cr_assert_not(exists("f.png"));
}

Test(rtref_cli, nan_vertex_names_file_and_line)
{
	char p[512], args[1024];
	tu_write(p, sizeof p, dir, "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
	snprintf(args, sizeof args, "--scene %s --out %s/f.png", p, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("nan.obj:3");
	cr_assert_not(exists("f.png"));
}

Test(rtref_cli, zero_triangles)
{
	char p[512], args[1024];
	tu_write(p, sizeof p, dir, "empty.obj", "v 0 0 0\nv 1 0 0\n");
	snprintf(args, sizeof args, "--scene %s --out %s/f.png", p, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("empty.obj");
}

Test(rtref_cli, bad_view_file)
{
	char p[512], args[1024];
	tu_write(
	    p, sizeof p, dir, "v.yaml",
	    "views:\n  a:\n    camera: {eye: [0,0,1], lookat: [0,0,0], up: [0,1,0], fov: 400}\n");
	snprintf(args, sizeof args, "--views %s --view a --out %s/f.png", p, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("v.yaml:3");
	cr_assert_not(exists("f.png"));
}

Test(rtref_cli, absurd_sizes_and_threads)
{
	char args[1024];
	const char *bad[] = {"--size 0x10",
	                     "--size 100000x10",
	                     "--size 10",
	                     "--size axb",
	                     "--threads 0",
	                     "--threads 99999",
	                     "--threads two",
	                     "--depth -1",
	                     "--fov 0",
	                     "--eye 1,2",
	                     "--bogus-flag 3",
	                     "--kd-max-depth 65",
	                     "--kd-max-depth 3.7",
	                     "--kd-leaf-size 100000",
	                     "--kd-cost-trav 0",
	                     "--kd-footprint 0.2",
	                     "--kd-footprint nan"};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		snprintf(args, sizeof args, "%s --out %s/f.png", bad[k], dir);
		cr_assert_eq(rtref(args), 2, "'%s' should exit 2", bad[k]);
		char flag[64];
		snprintf(flag, sizeof flag, "%s", bad[k]);
		flag[strcspn(flag, " ")] = 0;
		one_line_naming(flag);
		cr_assert_not(exists("f.png"));
	}
	/* the deepest tree the config key allows (kdtree.max_depth, 64 =
	 * the traversal stack) is accepted here too */
	snprintf(args, sizeof args, "--kd-max-depth 64 --size 16x16 --out %s/f.png", dir);
	cr_assert_eq(rtref(args), 0, "%s", slurp("err"));
}

/* The kdtree object of rtref's stats in dir/s.json: the node count and
 * the footprint's growth; the footprint's source in from (64 bytes). */
static void kd_stats(unsigned long *nodes, double *grow, char *from)
{
	const char *s = slurp("s.json");
	const char *k = strstr(s, "\"kdtree\": {");
	cr_assert(k, "no kdtree object in the stats");
	const char *n = strstr(k, "\"nodes\": "), *g = strstr(k, "\"footprint_grow\": "),
	           *f = strstr(k, "\"footprint_from\": \"");
	cr_assert(n && g && f, "no nodes, footprint_grow or footprint_from in the kdtree object");
	*nodes = strtoul(n + 9, NULL, 10);
	*grow = strtod(g + 18, NULL);
	f += 19;
	size_t len = strcspn(f, "\"");
	snprintf(from, 64, "%.*s", (int)(len < 63 ? len : 63), f);
}

/* rtref's own tree takes its primary packet's footprint (world.c,
 * view_kd). Mistakes caught: the view's footprint worked out but not
 * built with (the same tree as the plain SAH's), or taken for one image
 * height whatever --size says (a packet of a frame 8 times higher is 8
 * times narrower), or from the views file's eye when --eye moves it;
 * --kd-footprint not winning over it. */
Test(rtref_cli, own_tree_takes_the_views_packet_footprint)
{
	char args[1024], from[64];
	unsigned long n[4];
	double g[4];
	const char *run[4] = {"--size 64x64", "--size 64x512", "--size 64x64 --kd-footprint 0",
	                      "--size 64x64 --kd-footprint 0.002"};
	const char *want[4] = {"view", "view", "none", "scene"};
	for (int i = 0; i < 4; i++) {
		snprintf(args, sizeof args, "%s --world-cache off --stats %s/s.json", run[i], dir);
		cr_assert_eq(rtref(args), 0, "%s: %s", run[i], slurp("err"));
		kd_stats(&n[i], &g[i], from);
		cr_assert_str_eq(from, want[i], "%s", run[i]);
	}
	cr_assert_neq(n[0], n[2], "the view's footprint built the plain SAH's tree (%lu nodes)",
	              n[0]);
	cr_assert_float_eq(g[0] / g[1], 8.0, 1e-5, "growth %g at 64 rows, %g at 512", g[0], g[1]);
	cr_assert_eq(g[2], 0);
	/* the camera flags apply: an eye twice as far, a wider footprint */
	double ge[2];
	const char *eyes[2] = {"--eye 0,0,3000", "--eye 0,0,6000"};
	for (int i = 0; i < 2; i++) {
		snprintf(args, sizeof args,
		         "--size 64x64 %s --lookat 0,0,0 --world-cache off --stats %s/s.json",
		         eyes[i], dir);
		cr_assert_eq(rtref(args), 0, "%s: %s", eyes[i], slurp("err"));
		unsigned long nn;
		kd_stats(&nn, &ge[i], from);
	}
	cr_assert_gt(ge[1], 1.5 * ge[0], "--eye not applied to the footprint (%g, %g)", ge[0],
	             ge[1]);
}

/* A scene file without a views file is framed by its box, and rtref's
 * tree takes that view's packet footprint too (world.c, view_kd and
 * fp_framed_eye). Mistakes caught: the scene's fraction taken instead
 * (the footprint's source "scene"), the framed view's field of view or
 * eye not the one rendered (the growth not the packet's width at the
 * box's centre: 8 pixels of a 64-row frame of 45 degrees, at the framed
 * eye's distance), the image height left out of the world cache's key (a
 * hit from a 64-row run serving a 512-row one), --eye not applied. */
Test(rtref_cli, framed_scene_file_takes_its_views_packet_footprint)
{
	char file[512], args[1600], from[64];
	SCENE_OR_SKIP(file, "utah_teapot/teapot.obj");
	const char *run[4] = {"--size 64x64", "--size 64x512", "--size 64x64",
	                      "--size 64x64 --kd-footprint 0"};
	const char *want[4] = {"view", "view", "view", "none"};
	const char *cachestate[3] = {"\"world_cache\": \"stored\"", "\"world_cache\": \"stored\"",
	                             "\"world_cache\": \"hit\""};
	unsigned long n[4];
	double g[4];
	for (int i = 0; i < 4; i++) {
		snprintf(args, sizeof args, "--scene %s %s --world-cache %s/wc --stats %s/s.json",
		         file, run[i], dir, dir);
		cr_assert_eq(rtref(args), 0, "%s: %s", run[i], slurp("err"));
		kd_stats(&n[i], &g[i], from);
		cr_assert_str_eq(from, want[i], "%s", run[i]);
		if (i < 3)
			cr_assert(strstr(slurp("s.json"), cachestate[i]),
			          "run %d: world cache not %s", i, cachestate[i]);
		if (i == 0) { /* half a packet's width at the framed eye's distance */
			double e[3], l[3];
			const char *st = slurp("s.json"), *ce = strstr(st, "\"eye\": ["),
			           *cl = strstr(st, "\"lookat\": [");
			cr_assert(ce && cl && strstr(st, "\"view\": \"bbox\""), "no framed camera");
			cr_assert_eq(sscanf(ce + 8, " %lf , %lf , %lf", &e[0], &e[1], &e[2]), 3);
			cr_assert_eq(sscanf(cl + 11, " %lf , %lf , %lf", &l[0], &l[1], &l[2]), 3);
			double dist =
			    sqrt((e[0] - l[0]) * (e[0] - l[0]) + (e[1] - l[1]) * (e[1] - l[1]) +
			         (e[2] - l[2]) * (e[2] - l[2]));
			double want_g = 0.5 * (8.0 * 2.0 * tan(45.0 * M_PI / 360.0) / 64.0) * dist;
			cr_assert_float_eq(g[0], want_g, 1e-4 * want_g, "growth %g, a packet's %g",
			                   g[0], want_g);
		}
	}
	cr_assert_float_eq(g[0] / g[1], 8.0, 1e-5, "growth %g at 64 rows, %g at 512", g[0], g[1]);
	cr_assert_eq(g[2], g[0], "the cache hit's growth %g, the stored one's %g", g[2], g[0]);
	cr_assert_neq(n[0], n[3], "the framed view's footprint built the plain SAH's tree");
	/* --eye applies: an eye twice as far, a wider footprint */
	double ge[2];
	const char *eyes[2] = {"--eye 0,30,300", "--eye 0,30,600"};
	for (int i = 0; i < 2; i++) {
		snprintf(args, sizeof args,
		         "--scene %s --size 64x64 %s --lookat 0,30,0 --world-cache off --stats "
		         "%s/s.json",
		         file, eyes[i], dir);
		cr_assert_eq(rtref(args), 0, "%s: %s", eyes[i], slurp("err"));
		unsigned long nn;
		kd_stats(&nn, &ge[i], from);
		cr_assert_str_eq(from, "view", "%s", eyes[i]);
	}
	cr_assert_gt(ge[1], 1.5 * ge[0], "--eye not applied to the footprint (%g, %g)", ge[0],
	             ge[1]);
}

Test(rtref_cli, unwritable_output_leaves_nothing)
{
	char args[1024];
	snprintf(args, sizeof args, "--size 16x16 --out %s/no/such/dir/f.png", dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("f.png");
	/* --stats is checked before the render too, and says what is wrong
	 * (the render ran first, then "No such file or directory") */
	snprintf(args, sizeof args, "--size 16x16 --stats %s/missing/s.json", dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("folder");
	one_line_naming("missing does not exist");
}

/* The image and the statistics appear together or not at all: a --stats
 * that cannot be written leaves no new image (it was written before the
 * statistics failed) and keeps a file already at the image's path. */
Test(rtref_cli, failed_stats_writes_no_image)
{
	char args[1024], p[512];
	snprintf(p, sizeof p, "%s/s.json", dir);
	cr_assert_eq(mkdir(p, 0755), 0);
	snprintf(args, sizeof args, "--size 16x16 --out %s/f.png --stats %s", dir, p);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("s.json");
	cr_assert_not(exists("f.png"), "the image was written");
	tu_write(p, sizeof p, dir, "f.png", "precious\n");
	cr_assert_eq(rtref(args), 2);
	cr_assert_str_eq(slurp("f.png"), "precious\n", "the image was replaced");
	cr_assert_eq(tu_temps(dir, "f.png"), 0);
}

Test(rtref_cli, world_cache_gives_the_same_frame)
{
	char args[1024], cmd[1024];
	snprintf(args, sizeof args, "--scene spd:tetra:2 --size 48x32 --out %s/a.ppm", dir);
	cr_assert_eq(rtref(args), 0, "%s", slurp("err"));
	for (int i = 0; i < 2; i++) {
		snprintf(args, sizeof args,
		         "--scene spd:tetra:2 --size 48x32 --world-cache %s/c --out %s/b%d.ppm",
		         dir, dir, i);
		cr_assert_eq(rtref(args), 0, "%s", slurp("err"));
		char *out = slurp("out");
		cr_assert(i ? strstr(out, "nodes from the world cache") != NULL
		            : strstr(out, "nodes built in") != NULL,
		          "%s", out);
		snprintf(cmd, sizeof cmd, "cmp -s %s/a.ppm %s/b%d.ppm", dir, dir, i);
		cr_assert_eq(tu_run(cmd), 0, "run %d: the frames differ", i);
	}
}

/* Issue 28: a PLY with a form feed before end_header hung rtref inside
 * Assimp; 3,000 random bytes named g.ase rendered as a scene. Each is one
 * line and exit 2, at once. (timeout: the old code hangs.) */
Test(rtref_cli, bad_scene_files_are_one_line, .timeout = 120)
{
	char p[512], args[1024], cmd[2048];
	tu_write(
	    p, sizeof p, dir, "h.ply",
	    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\fend_header\n0\n0\n0\n");
	snprintf(args, sizeof args, "--scene %s --size 8x8 --out %s/f.png", p, dir);
	snprintf(cmd, sizeof cmd, "timeout 60 %s/rtref %s >%s/out 2>%s/err", tu_bin_dir(), args,
	         dir, dir);
	cr_assert_eq(tu_run(cmd), 2);
	one_line_naming("h.ply:5:1: control byte 0x0c in the PLY header");
	unsigned char noise[3000];
	tu_noise(noise, sizeof noise, 28);
	tu_write_bytes(p, sizeof p, dir, "g.ase", noise, sizeof noise);
	snprintf(args, sizeof args, "--scene %s --size 8x8 --out %s/f.png", p, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("g.ase: unsupported scene format '.ase'");
	cr_assert_not(exists("f.png"));
}

/* rtref's frame cut short by the file-size limit: one line naming it,
 * exit 2, neither the frame nor --stats left (it ended with status 0 and
 * a truncated PNG); a .jpg is refused before the render. */
Test(rtref_cli, image_write_cut_short_or_unlisted_format_is_refused)
{
	char args[1024];
	snprintf(args, sizeof args, "--size 256x256 --out %s/x.png --stats %s/s.json", dir, dir);
	cr_assert_eq(tu_run_env("trap '' XFSZ; ulimit -f 4;", dir, "rtref", args), 2, "%s",
	             slurp("err"));
	one_line_naming("x.png");
	cr_assert(!exists("x.png") && !exists("s.json"), "a file was left");
	cr_assert_eq(tu_temps(dir, "x.png"), 0);
	snprintf(args, sizeof args, "--size 16x16 --out %s/x.jpg", dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("x.jpg");
	cr_assert_not(exists("x.jpg"));
}

/* Mistake: --size's sides read by strtol, which takes a leading blank or
 * sign: " 64x64" and "+64x64" were accepted while "64x64 " was refused.
 * Every such size is refused by both programs (one line, exit 2); plain
 * digits still pass. */
Test(rtref_cli, size_is_digits_only)
{
	char args[1024];
	const char *bad[] = {"' 64x64'", "+64x64", "'64x64 '", "64x+64",
	                     "'64x 64'", "64x-8",  "'\t8x8'"};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		snprintf(args, sizeof args, "--size %s --out %s/f.png", bad[k], dir);
		cr_assert_eq(rtref(args), 2, "--size %s", bad[k]);
		one_line_naming("--size");
		cr_assert_not(exists("f.png"));
		snprintf(args, sizeof args, "--size %s --dry-run", bad[k]);
		cr_assert_eq(tu_prog(dir, "saarsim", args), 2, "saarsim --size %s", bad[k]);
		tu_one_line(dir, "saarsim", "--size");
	}
	snprintf(args, sizeof args, "--size 16X12 --out %s/f.png", dir);
	cr_assert_eq(rtref(args), 0, "%s", slurp("err"));
	cr_assert_eq(tu_prog(dir, "saarsim", "--size 16x12 --dry-run"), 0, "%s", slurp("err"));
}

/* Mistake: options that contradict each other accepted, one of them then
 * ignored without a word: --light after --no-lights (no shadow rays), a
 * --grid-* flag on a kd-tree run, rtref's packet-only --cone-cull and
 * --per-lane with --single-ray, saarsim-stress's --views with
 * --no-precision. Each is one line and exit 2 before anything runs, and
 * the flags still work where they apply. */
Test(rtref_cli, contradictory_options_are_refused)
{
	static const struct {
		const char *prog, *args, *names;
	} bad[] = {
	    {"rtref", "--cone-cull --single-ray", "--cone-cull"},
	    {"rtref", "--single-ray --per-lane", "--per-lane"},
	    {"rtref", "--grid-packet 1", "--grid-packet"},
	    {"rtref", "--accel kd --grid-cull 0", "--grid-cull"},
	    {"rtref", "--no-lights --light 1,1,1", "--light"},
	    {"saarsim", "--light 1,1,1 --no-lights --dry-run", "--no-lights"},
	    {"saarsim", "--grid-macro 0 --dry-run", "--grid-macro"},
	    {"saarsim-stress", "--views /nonexistent.yaml --quick --no-precision", "--views"},
	    {"saarsim-stress", "--quick --out", "--out needs a value"},
	};
	char args[1024];
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		snprintf(args, sizeof args, "%s --out %s/f.png", bad[k].args, dir);
		if (!strcmp(bad[k].prog, "saarsim-stress"))
			snprintf(args, sizeof args, "%s", bad[k].args);
		cr_assert_eq(tu_prog(dir, bad[k].prog, args), 2, "%s %s", bad[k].prog, bad[k].args);
		tu_one_line(dir, bad[k].prog, bad[k].names);
		cr_assert_not(exists("f.png"));
	}
	cr_assert_eq(rtref("--size 16x16 --accel grid --grid-packet 1 --no-lights"), 0, "%s",
	             slurp("err"));
	cr_assert_eq(rtref("--size 16x16 --single-ray --light 1,1,1 --light 2,2,2"), 0, "%s",
	             slurp("err"));
	cr_assert_eq(tu_prog(dir, "saarsim", "--set chip.accel=grid --grid-macro 0 --dry-run"), 0,
	             "%s", slurp("err"));
}

/* Mistake: an animation's numbered outputs checked for frame 0 only (the
 * unnumbered path, or f-0000), so a later frame's path that names a
 * folder failed after the frames before it were rendered and written.
 * Every numbered path is checked before the first frame: one line naming
 * the path, exit 2, no frame written; a plain file at a later path is
 * replaced as usual. */
Test(rtref_cli, numbered_outputs_are_checked_before_the_first_frame)
{
	char aff[512], args[2048], sub[600];
	tu_write(aff, sizeof aff, dir, "t.aff",
	         "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\n"
	         "l 0 5 5\nf 0.5 0.5 0.5 1 0 0 0 1\np 3\n-1 -1 0\n1 -1 0\n0 1 0\n");
	snprintf(sub, sizeof sub, "%s/f-0002.png", dir);
	cr_assert_eq(mkdir(sub, 0777), 0);
	snprintf(args, sizeof args, "--scene %s --anim-fps 2 --frames 3 --size 8x8 --out %s/f.png",
	         aff, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("f-0002.png");
	cr_assert_not(exists("f-0000.png") || exists("f-0001.png"));
	snprintf(sub, sizeof sub, "%s/r-0001.json", dir);
	cr_assert_eq(mkdir(sub, 0777), 0);
	snprintf(args, sizeof args,
	         "--scene %s --anim-fps 2 --frames 2 --size 8x8 --out %s/g.png --report "
	         "%s/r.json",
	         aff, dir, dir);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 2);
	tu_one_line(dir, "saarsim", "r-0001.json");
	cr_assert_not(exists("g-0000.png") || exists("r-0000.json"));
	/* a file at a later frame's path is written over */
	tu_write(sub, sizeof sub, dir, "h-0001.png", "old");
	snprintf(args, sizeof args, "--scene %s --anim-fps 2 --frames 2 --size 8x8 --out %s/h.png",
	         aff, dir);
	cr_assert_eq(rtref(args), 0, "%s", slurp("err"));
	cr_assert(exists("h-0000.png"));
	cr_assert_neq(strcmp(slurp("h-0001.png"), "old"), 0);
}

/* rtref's --out and --stats naming one file (the stats replaced the
 * frame: x.ppm held JSON), and a flag of one value given twice (the
 * second silently won), are one line each, exit 2, before the render. */
Test(rtref_cli, one_file_for_two_outputs_and_flags_given_twice_are_refused)
{
	char args[1024];
	snprintf(args, sizeof args, "--size 16x16 --out %s/x.ppm --stats %s/./x.ppm", dir, dir);
	cr_assert_eq(rtref(args), 2);
	one_line_naming("--out and --stats name the same file");
	cr_assert_not(exists("x.ppm"));
	cr_assert_eq(rtref("--size 16x16 --scene spd:balls:1 --scene spd:balls:2"), 2);
	one_line_naming("--scene: given twice");
	cr_assert_eq(rtref("--size 16x16 --light 1,1,1 --light 2,2,2 --kd-leaf-size 2 "
	                   "--kd-leaf-size 3"),
	             0, "%s", slurp("err"));
}
