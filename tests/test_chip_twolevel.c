/*
 * test_chip_twolevel.c: the chip on two-level scenes (issue 33 item 3;
 * units/toplevel.h, kernel-ref/tlimage.h): every frame is kernel-ref's
 * two-level frame, the chip reads the top level and the transforms from
 * its memory only, and the host's per-frame update is counted.
 */
#include "kernel-ref/tlimage.h"
#include "sim/memconfig.h"
#include "sim/report.h"
#include "tests/chiptest.h"

/* A floor at the root, a part placed twice by static transforms (two
 * instances of one object), and a spinning, moving, growing part. */
static const char *SCENE =
    "v\nfrom 0 0 9\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\n"
    "l 2 4 6\nl -3 2 5\nfm 0 0 0 0.8 0.8 0.8 0 0 0 10 0 0\nm\nvertices 4\n-4 -4 -1\n"
    "4 -4 -1\n4 4 -1\n-4 4 -1\ntriangles 2\n0 1 2\n0 2 3\n"
    "fm 0 0 0 0.9 0.1 0.1 0 0 0 10 0 0\nxs 1 1 1 0 0 1 0 -2.5 1.5 0 {\ni 0 part.aff\n}\n"
    "fm 0 0 0 0.1 0.9 0.1 0 0 0 10 0 0\nxs 1 1 1 0 0 1 40 2.5 1.5 0 {\ni 0 part.aff\n}\n"
    "fm 0 0 0 0.2 0.2 0.9 0 0 0 10 0 0\nx spin {\ni 0 part.aff\n}\nk spin {\n"
    "transl 4\n0 0 0 0 0 0 0\n0 0 -1 0 0 0 0\n3 0.5 -1 1 0 0 0\n3 0.5 -1 1 0 0 0\n"
    "rot 4\n0 0 0 1 0 0 0 0\n0 0 0 1 0 0 0 0\n3 0.3 0 1 250 0 0 0\n"
    "3 0.3 0 1 250 0 0 0\nscale 4\n0 1 1 1 0 0 0\n0 1 1 1 0 0 0\n"
    "3 1.5 0.7 1 0 0 0\n3 1.5 0.7 1 0 0 0\n}\n";
static const char *PART = "m\nvertices 4\n-1 -1 0\n1 -1 0\n0 1 0.5\n0 0 1\ntriangles 3\n"
                          "0 1 2\n0 1 3\n1 2 3\n";

/* The scene's files in a new folder; its entry file's path into p. */
static void write_scene(char *p, size_t n)
{
	char dir[128], part[1024];
	tu_tmpdir(dir, sizeof dir);
	tu_write(part, sizeof part, dir, "part.aff", PART);
	tu_write(p, n, dir, "scene.aff", SCENE);
}

static void load_two_level(world *w, const char *path, double t)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = path;
	o.two_level = 1;
	o.have_anim_time = 1;
	o.anim_time = t;
	diag d;
	cr_assert_eq(world_load(w, &o, &d), 0, "%s", d.msg);
	cr_assert(w->tl, "no two-level trees");
}

/* Moves two-level world w (AFF scene path) to time t. */
static void move_to(world *w, const char *path, double t)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = path;
	o.two_level = 1;
	diag d;
	cr_assert_eq(world_set_time(w, &o, t, &d), 0, "%s", d.msg);
}

/* Runs the chip; 1 when its frame is kernel-ref's two-level frame (packets
 * and single rays). */
static int run_identical(chip *ch)
{
	diag d;
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	tu_assert_report_ok(ch);
	chip_check k;
	cr_assert_eq(chip_check_frame(ch, &k, &d), 0, "%s", d.msg);
	return k.cmp.identical && k.single.identical;
}

/* A small cycle chip on w, its top level overwritten with the n bytes
 * top (none when NULL) before it runs: run_identical's answer. */
static int identical_with_top(world *w, const void *top, uint64_t n)
{
	saar_config c;
	tu_cfg_small(&c, 48, "cycle", 0);
	diag d;
	chip *ch = chip_create(&c, w, &d);
	cr_assert(ch, "%s", d.msg);
	if (top)
		cr_assert_eq(ms_write(&ch->store, ch->tli.top_base, n, top), 0);
	int same = run_identical(ch);
	chip_destroy(ch);
	return same;
}

/* Every frame, in cycle and functional fidelity, with and without the
 * VMA, is kernel-ref's two-level frame, and the transformation unit ran
 * (its ops: the instances entered and the shaded packets moved back).
 * Mistakes caught: a hit named by its object-space triangle address (the
 * triangle map skipped: the shader reads another triangle), rays traced
 * in world space (the transformation skipped), the instance records read
 * in another order than the BVH's leaves, the world packet not restored
 * after an instance (hits of the object-space copy shaded). */
Test(chip_twolevel, frames_match_kernel_ref, .timeout = 120)
{
	char p[1024];
	write_scene(p, sizeof p);
	const double ts[] = {0, 1.2, 2.5};
	const char *modes[] = {"cycle", "functional"};
	for (int k = 0; k < 3; k++) {
		world w;
		load_two_level(&w, p, ts[k]);
		for (int m = 0; m < 2; m++)
			for (int v = 0; v < 2; v++) {
				saar_config c;
				tu_cfg_small(&c, 48, modes[m], v);
				diag d;
				chip *ch = chip_create(&c, &w, &d);
				cr_assert(ch, "%s", d.msg);
				cr_assert(run_identical(ch), "t=%g %s vma=%d: the frame differs",
				          ts[k], modes[m], v);
				cr_assert(
				    stats_get(&ch->st, "xform.instances") > 0 &&
				        stats_get(&ch->st, "rtp0.xform.ops") +
				                stats_get(&ch->st, "rtp1.xform.ops") >
				            stats_get(&ch->st, "xform.instances"),
				    "transformations %llu, xform ops elsewhere",
				    (unsigned long long)stats_get(&ch->st, "xform.instances"));
				chip_destroy(ch);
			}
		world_free(&w);
	}
}

/* The rays that miss the scene box are some of the flat scene's: the top
 * level counts them at its root. Mistake caught: the object's traversal
 * counting its rays that miss the object's box as scene-box misses (274
 * packets and 12,298 rays on Robots at 128x96, where the flat scene has
 * none), or the top level counting none. */
Test(chip_twolevel, box_misses_are_the_flat_scenes, .timeout = 120)
{
	/* the scene with a wide view: its edges look past the scene box */
	char dir[128], part[1024], p[1024], wide[2048];
	tu_tmpdir(dir, sizeof dir);
	tu_write(part, sizeof part, dir, "part.aff", PART);
	const char *a = strstr(SCENE, "angle 45");
	cr_assert(a);
	snprintf(wide, sizeof wide, "%.*sangle 120%s", (int)(a - SCENE), SCENE, a + 8);
	tu_write(p, sizeof p, dir, "scene.aff", wide);
	world f, w;
	world_opts o;
	world_opts_default(&o);
	o.scene = p;
	o.have_anim_time = 1;
	o.anim_time = 1.2;
	diag d;
	cr_assert_eq(world_load(&f, &o, &d), 0, "%s", d.msg);
	load_two_level(&w, p, 1.2);
	uint64_t got[2][2];
	world *ws[2] = {&f, &w};
	for (int k = 0; k < 2; k++) {
		saar_config c;
		tu_cfg_small(&c, 48, "cycle", 0);
		chip *ch = chip_create(&c, ws[k], &d);
		cr_assert(ch, "%s", d.msg);
		cr_assert(run_identical(ch), "%s: the frame differs", k ? "two-level" : "flat");
		got[k][0] = stats_get(&ch->st, "skip.box_miss_rays");
		got[k][1] = stats_get(&ch->st, "skip.box_miss_packets");
		chip_destroy(ch);
	}
	cr_assert_gt(got[0][0], 0, "the view has no ray that misses the scene box");
	/* the top level's root box holds the flat scene's (it is made of
	 * the instances' object boxes moved into the world), so its misses
	 * are some of the flat scene's: of this view's, 2048 of 2108 */
	cr_assert(got[1][0] > 0 && got[1][0] <= got[0][0] && got[1][1] <= got[0][1],
	          "two-level: %llu rays and %llu packets miss the scene box, flat: %llu and %llu",
	          (unsigned long long)got[1][0], (unsigned long long)got[1][1],
	          (unsigned long long)got[0][0], (unsigned long long)got[0][1]);
	world_free(&f);
	world_free(&w);
}

/* The same on BART Robots (221 instances of 23 objects) at two times. */
Test(chip_twolevel, robots_frames_match_kernel_ref, .timeout = 300)
{
	char aff[1024];
	SCENE_OR_SKIP(aff, "bart_robots_aff/aff/Robot.aff");
	const double ts[] = {0, 12.5};
	for (int k = 0; k < 2; k++) {
		world w;
		load_two_level(&w, aff, ts[k]);
		saar_config c;
		tu_cfg_small(&c, 64, "cycle", 0);
		diag d;
		chip *ch = chip_create(&c, &w, &d);
		cr_assert(ch, "%s", d.msg);
		cr_assert(run_identical(ch), "t=%g: the frame differs", ts[k]);
		chip_destroy(ch);
		world_free(&w);
	}
}

/* The top level as the chip's memory holds it at 0 + 2.5 s: its nodes and
 * instance records (copied, malloc'd) and their bytes. */
static uint8_t *top_bytes(const world *w, uint64_t *n)
{
	tl_image im;
	diag d;
	cr_assert_eq(tli_build(&im, w->tl, &w->m, &d), 0, "%s", d.msg);
	*n = im.top_bytes;
	uint8_t *b = malloc(im.top_bytes);
	cr_assert(b);
	memcpy(b, im.bytes + im.top_base, im.top_bytes);
	tli_free(&im);
	return b;
}

/* A stale instance transform: the chip of the frame at t = 2.5 whose
 * memory holds the top level of t = 0 (the update not written) renders
 * another frame than kernel-ref's at 2.5, so the chip takes its
 * transforms from memory, not from the host's scene. And the host's
 * update (tli_write_top after tl_frame) holds the new frame's top level
 * byte for byte. Mistakes caught: the units reading the host's tl_scene
 * (the frame right although memory is stale); an update that rewrites the
 * BVH but leaves the instance records (their transforms) of the last
 * frame. */
Test(chip_twolevel, stale_transform_changes_the_frame, .timeout = 120)
{
	char p[1024];
	write_scene(p, sizeof p);
	world w;
	load_two_level(&w, p, 0);
	uint64_t n0, n1;
	uint8_t *old = top_bytes(&w, &n0);
	/* the host's update: the image of t = 0, the top level rewritten */
	tl_image im;
	diag d;
	cr_assert_eq(tli_build(&im, w.tl, &w.m, &d), 0, "%s", d.msg);
	move_to(&w, p, 2.5);
	cr_assert_eq(tli_write_top(&im, w.tl), n0);
	uint8_t *now = top_bytes(&w, &n1);
	cr_assert_eq(n0, n1);
	cr_assert(memcmp(old, now, n0) != 0, "the top level did not move");
	cr_assert(memcmp(im.bytes + im.top_base, now, n1) == 0,
	          "the update differs from the frame's top level");
	tli_free(&im);
	cr_assert_not(identical_with_top(&w, old, n0),
	              "a stale top level in memory gave the new frame");
	free(old);
	free(now);
	world_free(&w);
}

/* A stale forward matrix: the chip of the frame at t = 2.5 whose instance
 * records hold the walk's part of 2.5 but the shading transforms (forward
 * and normal matrices) of t = 0 traces the right rays to the right
 * object-space triangles and shades them where they were at t = 0: its
 * frame differs from kernel-ref's. So the RGS takes a hit's transform
 * from the instance record in memory, not from the host's scene, and an
 * update must rewrite it. Mistakes caught: the shader handed the host's
 * matrices (the frame right although memory is stale); an update that
 * keeps the forward matrices of the first frame (also caught by
 * warm_frames_match_kernel_ref). */
Test(chip_twolevel, stale_forward_matrix_changes_the_frame, .timeout = 120)
{
	char p[1024];
	write_scene(p, sizeof p);
	world w;
	load_two_level(&w, p, 0);
	uint64_t n0, n1;
	uint8_t *old = top_bytes(&w, &n0);
	move_to(&w, p, 2.5);
	uint8_t *now = top_bytes(&w, &n1);
	cr_assert_eq(n0, n1);
	cr_assert(identical_with_top(&w, NULL, 0), "the frame at 2.5 differs");
	/* t = 0's shading transforms, record for record in 2.5's order */
	uint64_t nodes = (uint64_t)w.tl->nnode * TLI_NODE_BYTES;
	for (uint32_t k = 0; k < w.tl->ninst; k++) {
		uint64_t r = nodes + (uint64_t)k * TLI_INST_BYTES + TLI_INST_WALK_BYTES;
		/* the same instance's record of t = 0: found by its map entry */
		uint32_t map;
		memcpy(&map, now + nodes + (uint64_t)k * TLI_INST_BYTES + 156, 4);
		for (uint32_t j = 0; j < w.tl->ninst; j++) {
			uint64_t q = nodes + (uint64_t)j * TLI_INST_BYTES;
			uint32_t m0;
			memcpy(&m0, old + q + 156, 4);
			if (m0 == map)
				memcpy(now + r, old + q + TLI_INST_WALK_BYTES, SHADE_XF_BYTES);
		}
	}
	cr_assert_not(identical_with_top(&w, now, n1),
	              "stale forward matrices in memory gave the new frame");
	free(old);
	free(now);
	world_free(&w);
}

/* The update's bytes are the top level's (nodes and instance records),
 * and its time is one transfer of them on the host bus; the report has
 * them. Mistakes caught: update bytes not counted (0), the whole image
 * counted as the update, a time not of those bytes. */
Test(chip_twolevel, update_is_counted, .timeout = 60)
{
	char p[1024];
	write_scene(p, sizeof p);
	world w;
	load_two_level(&w, p, 1);
	saar_config c;
	tu_cfg_small(&c, 32, "cycle", 0);
	diag d;
	chip *ch = chip_create(&c, &w, &d);
	cr_assert(ch, "%s", d.msg);
	cr_assert(run_identical(ch));
	uint64_t want =
	    (uint64_t)w.tl->nnode * TLI_NODE_BYTES + (uint64_t)w.tl->ninst * TLI_INST_BYTES;
	cr_assert_eq(ch->update_bytes, want, "update %llu bytes, want %llu",
	             (unsigned long long)ch->update_bytes, (unsigned long long)want);
	hbus_params hp;
	hbus h;
	hier_hbus_params(&c, &hp);
	cr_assert_eq(hbus_init(&h, &hp, &d), 0);
	cr_assert_float_eq(ch->update_ms, (double)hbus_duration(&h, (uint32_t)want) * 1e-9, 1e-12);
	char dir[128], path[1024];
	tu_tmpdir(dir, sizeof dir);
	snprintf(path, sizeof path, "%s/r.json", dir);
	report_info ri = {ch, &w, NULL, 0, 0, NULL, 0, NULL};
	cr_assert_eq(report_json(path, &ri, &d), 0, "%s", d.msg);
	char key[64];
	snprintf(key, sizeof key, "\"update_bytes\":%llu", (unsigned long long)want);
	char *r = tu_squeeze_json(tu_slurp(dir, "r.json"));
	cr_assert(strstr(r, key), "the report has no %s", key);
	chip_destroy(ch);
	world_free(&w);
}

/* saarsim --two-level runs an animation on one warm chip, every frame
 * checked, one report with each frame's update; --anim-cold runs a chip
 * per frame (numbered reports); sampled fidelity is refused in one line.
 * Mistakes caught: the flag refused, or accepted and ignored (no
 * two_level in the report); frames before the last not checked; a warm
 * run's --out writing the last frame only, or a frame's image written
 * after the world moved on (each must equal rtref --two-level's frame of
 * the same number). */
Test(chip_twolevel, saarsim_flag, .timeout = 120)
{
	char p[1024], args[1400];
	write_scene(p, sizeof p);
	char dir[128];
	tu_tmpdir(dir, sizeof dir);
	snprintf(args, sizeof args,
	         "--scene %s --two-level --size 32x32 --anim-fps 2 --frames 3 --report %s/w.json "
	         "--out %s/w.ppm",
	         p, dir, dir);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 0);
	snprintf(args, sizeof args,
	         "--scene %s --two-level --size 32x32 --anim-fps 2 --frames 3 --out %s/k.ppm", p,
	         dir);
	cr_assert_eq(tu_prog(dir, "rtref", args), 0);
	for (int i = 0; i < 3; i++) {
		char a[32], b[32];
		snprintf(a, sizeof a, "w-%04d.ppm", i);
		snprintf(b, sizeof b, "k-%04d.ppm", i);
		const char *x = tu_slurp(dir, a), *y = tu_slurp(dir, b);
		cr_assert(!memcmp(x, y, 13 + 32 * 32 * 3), "warm frame %d differs from rtref's", i);
	}
	char *r = tu_squeeze_json(tu_slurp(dir, "w.json"));
	cr_assert(strstr(r, "\"warm\":true,\"frames_checked_before_last\":2,"
	                    "\"frames_identical_before_last\":2"),
	          "warm run: frames not checked");
	cr_assert(strstr(r, "\"identical_8bit\":true"), "the last frame differs");
	snprintf(args, sizeof args,
	         "--scene %s --two-level --size 32x32 --anim-fps 2 --frames 2 --anim-cold "
	         "--report %s/r.json",
	         p, dir);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 0);
	for (int i = 0; i < 2; i++) {
		char name[32];
		snprintf(name, sizeof name, "r-%04d.json", i);
		r = tu_squeeze_json(tu_slurp(dir, name));
		cr_assert(strstr(r, "\"two_level\":{"), "%s without two_level", name);
		cr_assert(strstr(r, "\"warm\":false"), "%s: not a cold run", name);
		cr_assert(strstr(r, "\"identical_8bit\":true"), "%s: frame differs", name);
	}
	snprintf(args, sizeof args, "--scene %s --two-level --fidelity sampled", p);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 2);
	tu_one_line(dir, "saarsim", "--two-level: cycle or functional fidelity only");
	snprintf(args, sizeof args, "--scene %s --anim-cold", p);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 2);
	tu_one_line(dir, "saarsim", "--anim-cold: for a --two-level animation");
}

/* The text's host-bus update is the JSON's update_bytes: a mean over the
 * frames, which the text truncated and the JSON rounded (Robots, three
 * frames of 80648, 80520 and 80520 bytes: 80562 against 80563). */
Test(chip_twolevel, update_in_text_is_the_jsons, .timeout = 120)
{
	char aff[512], dir[128], args[1400];
	SCENE_OR_SKIP(aff, "bart_robots_aff/aff/Robot.aff");
	tu_tmpdir(dir, sizeof dir);
	snprintf(args, sizeof args,
	         "--scene %s --two-level --anim-time 10 --anim-fps 2 --frames 3 --size 32x32 "
	         "--no-check --report %s/u.json",
	         aff, dir);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 0, "%s", tu_slurp(dir, "err"));
	const char *ut = strstr(tu_slurp(dir, "out"), "; update "),
	           *uj = strstr(tu_squeeze_json(tu_slurp(dir, "u.json")), "\"update_bytes\":");
	cr_assert(ut && uj);
	cr_assert_eq(strtoull(ut + 9, NULL, 10), strtoull(uj + 15, NULL, 10),
	             "text %.20s, JSON %.24s", ut, uj);
}

/* ---- warm animations (chip_anim_update) ---- */

typedef struct warm {
	world *w;
	const char *path;
	const double *ts;
	int checked, identical;
	uint64_t want[8]; /* each frame's changed 128-byte lines' bytes, computed here */
} warm;

/* The bytes of the 128-byte lines in which images a and b differ. */
static uint64_t changed_bytes(const tl_image *a, const tl_image *b)
{
	cr_assert_eq(a->size, b->size);
	uint64_t n = 0;
	for (uint64_t x = 0; x < a->size; x += 128) {
		uint64_t len = a->size - x < 128 ? a->size - x : 128;
		n += memcmp(a->bytes + x, b->bytes + x, len) ? len : 0;
	}
	return n;
}

/* The test's own between-frames step: check the frame that ended, move
 * the world to ts[f], the image before and after (for want[f]), then
 * the chip's update. */
static int warm_step(chip *c, int f, void *ctx, diag *d)
{
	warm *x = ctx;
	chip_check k;
	cr_assert_eq(chip_check_frame(c, &k, d), 0, "%s", d->msg);
	x->checked++;
	x->identical += k.cmp.identical && k.single.identical;
	tl_image before, after;
	cr_assert_eq(tli_build(&before, x->w->tl, &x->w->m, d), 0);
	move_to(x->w, x->path, x->ts[f]);
	cr_assert_eq(tli_build(&after, x->w->tl, &x->w->m, d), 0);
	x->want[f] = changed_bytes(&before, &after);
	tli_free(&before);
	tli_free(&after);
	return chip_anim_update(c, f, d);
}

/* Runs frames ts[0..n) on one chip; returns the frames identical to
 * kernel-ref's (the last included). */
static int run_warm(const char *path, const double *ts, int n, const char *mode, int with_vma,
                    int keep_stale, warm *x)
{
	world w;
	load_two_level(&w, path, ts[0]);
	saar_config c;
	tu_cfg_small(&c, 48, mode, with_vma);
	c.frame.frames = n;
	diag d;
	chip *ch = chip_create(&c, &w, &d);
	cr_assert(ch, "%s", d.msg);
	*x = (warm){&w, path, ts, 0, 0, {0}};
	ch->between = warm_step;
	ch->between_ctx = x;
	ch->anim_keep_stale = keep_stale;
	int same = run_identical(ch);
	/* the scene moves between the test's times: a count of 0 on both sides
	 * (nothing written, nothing changed) or of the whole top level would
	 * not tell a right update from a wrong one */
	for (int f = 1; f < n; f++)
		cr_assert(x->want[f] > 0 && x->want[f] <= ch->tli.top_bytes,
		          "frame %d: %llu changed bytes (top level %llu)", f,
		          (unsigned long long)x->want[f], (unsigned long long)ch->tli.top_bytes);
	for (int f = 1; f < n; f++)
		cr_assert_eq(ch->frame_update[f], x->want[f],
		             "frame %d: update %llu bytes, the changed lines hold %llu", f,
		             (unsigned long long)ch->frame_update[f],
		             (unsigned long long)x->want[f]);
	cr_assert_eq(ch->frame_update[0], ch->tli.top_bytes, "frame 0's update is the top level");
	/* the shading image's records are in object space: the top level is
	 * all that moves */
	for (int f = 1; f < n; f++)
		cr_assert_eq(ch->frame_update_top[f], ch->frame_update[f],
		             "frame %d: %llu of the update's %llu bytes outside the top level", f,
		             (unsigned long long)(ch->frame_update[f] - ch->frame_update_top[f]),
		             (unsigned long long)ch->frame_update[f]);
	chip_destroy(ch);
	world_free(&w);
	return x->identical + same;
}

/* One warm chip through four frames, in cycle and functional fidelity,
 * with and without the VMA: every frame is kernel-ref's, and each frame's
 * update is the bytes of the lines that changed. Mistakes caught: the
 * update not written into the chip's memory (the frame drawn with the last
 * one's instances), update bytes not counted or counted as the whole
 * image. */
Test(chip_twolevel, warm_frames_match_kernel_ref, .timeout = 120)
{
	char p[1024];
	write_scene(p, sizeof p);
	const double ts[] = {0, 0.8, 1.6, 2.5};
	const char *modes[] = {"cycle", "functional"};
	for (int m = 0; m < 2; m++)
		for (int v = 0; v < 2; v++) {
			warm x;
			int same = run_warm(p, ts, 4, modes[m], v, 0, &x);
			cr_assert_eq(x.checked, 3);
			cr_assert_eq(same, 4, "%s vma=%d: %d of 4 frames identical", modes[m], v,
			             same);
		}
}

/* BART Robots warm through three frames (robots walking, the camera
 * moving): every frame is kernel-ref's. Mistakes caught: the camera (or
 * lights) of the first frame kept; the update missing records of a moved
 * robot part. */
Test(chip_twolevel, warm_robots, .timeout = 300)
{
	char aff[1024];
	SCENE_OR_SKIP(aff, "bart_robots_aff/aff/Robot.aff");
	const double ts[] = {10, 10.5, 11};
	warm x;
	int same = run_warm(aff, ts, 3, "cycle", 0, 0, &x);
	cr_assert_eq(same, 3, "%d of 3 frames identical", same);
}

/* The update's lines left in the caches (not dropped): a frame traced
 * and shaded from stale top-level records (nodes, instance records with
 * their transforms) differs from kernel-ref's.
 * Shows the caches carry data and the per-frame check sees a warm chip's
 * stale lines (the mistake the invalidation avoids). */
Test(chip_twolevel, stale_cache_lines_change_the_frame, .timeout = 120)
{
	char p[1024];
	write_scene(p, sizeof p);
	const double ts[] = {0, 0.8, 1.6, 2.5};
	warm x;
	int same = run_warm(p, ts, 4, "cycle", 1, 1, &x);
	cr_assert_lt(same, 4, "stale cache lines, yet every frame identical");
}
