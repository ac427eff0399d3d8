/*
 * test_aff.c: the AFF reader (kernel-ref/aff.c) and BART's Kochanek-Bartels
 * splines (kernel-ref/kbspline.c). Each test names the mistake it is there
 * to catch. The scenes are tiny AFF texts written by the tests; one test
 * reads the shared BART Robots (../shared/scenes/bart_robots_aff) and
 * compares it at t = 0 with the flattened OBJ beside it.
 */
#include "kernel-ref/aff.h"
#include "kernel-ref/kbspline.h"
#include "tests/testutil.h"

#include <math.h>

/* ---- splines ---- */

static kb_key key(double t, double x, double tens, double cont, double bias)
{
	kb_key k = {t, {x, 0, 0, 0}, tens, cont, bias};
	return k;
}

/* Mistake: tangents without BART's spacing factor 2*dt / (dt_l + dt_r),
 * or with it inverted: a uniform motion keyed at uneven times then bends.
 * With the factor a Kochanek-Bartels curve with T = C = B = 0 reproduces
 * a linear motion exactly, however the keys are spaced. */
Test(aff_spline, linear_motion_with_uneven_keys)
{
	double ts[] = {0, 1, 3, 3.5, 6, 6.2};
	kb_key k[6];
	for (int i = 0; i < 6; i++)
		k[i] = key(ts[i], 2 * ts[i] + 1, 0, 0, 0);
	for (double t = 1; t <= 6; t += 0.125) {
		double p[3];
		kb_pos_eval(k, 6, t, p);
		cr_assert(fabs(p[0] - (2 * t + 1)) < 1e-9, "t=%g: %.12g, want %.12g", t, p[0],
		          2 * t + 1);
	}
}

/* Mistake: the weights of tension, continuity or bias swapped (1+B where
 * BART has 1-B, ...). One segment worked by hand from the formulas:
 * keys 0, 1, 3, 4 at t = 0..3, bias 0.5 at key 1: outgoing tangent
 * 0.5*(1-0.5)*2 + 0.5*(1+0.5)*1 = 1.25, incoming 0.5*1 + 0.5*2 = 1.5,
 * and at u = 0.5 the Hermite cubic gives 1.96875. Tension 1 at both
 * inner keys (zero tangents) gives 1 + 2*(3u^2 - 2u^3) = 1.3125 at u =
 * 0.25; continuity 0.5 at key 2: outgoing 0.5*2 + 0.5*1 = 1.5, incoming
 * 0.5*1.5*1 + 0.5*0.5*2 = 1.25, at u = 0.5: 1 + 0.75 + 0.25*(6-3-1.25) +
 * 0.125*(-4+1.5+1.25) = 2.03125 (1.96875 with 1+C and 1-C swapped). */
Test(aff_spline, tcb_weights_by_hand)
{
	kb_key k[4] = {key(0, 0, 0, 0, 0), key(1, 1, 0, 0, 0.5), key(2, 3, 0, 0, 0),
	               key(3, 4, 0, 0, 0)};
	double p[3];
	kb_pos_eval(k, 4, 1.5, p);
	cr_assert(fabs(p[0] - 1.96875) < 1e-12, "bias: %.12g, want 1.96875", p[0]);
	k[1].bias = 0;
	k[1].tension = k[2].tension = 1;
	kb_pos_eval(k, 4, 1.25, p);
	cr_assert(fabs(p[0] - 1.3125) < 1e-12, "tension: %.12g, want 1.3125", p[0]);
	k[1].tension = k[2].tension = 0;
	k[2].continuity = 0.5;
	kb_pos_eval(k, 4, 1.5, p);
	cr_assert(fabs(p[0] - 2.03125) < 1e-12, "continuity: %.12g, want 2.03125", p[0]);
}

/* Mistake: running the curve through the first and last key. BART's
 * first and last key only shape the end tangents; before key 1 and after
 * key n-2 the value holds. */
Test(aff_spline, end_keys_only_shape_tangents)
{
	kb_key k[5] = {key(0, 100, 0, 0, 0), key(1, 1, 0, 0, 0), key(2, 2, 0, 0, 0),
	               key(3, 3, 0, 0, 0), key(4, -100, 0, 0, 0)};
	double p[3];
	kb_pos_eval(k, 5, -5, p);
	cr_assert_float_eq(p[0], 1.0, 1e-12, "before: %g", p[0]);
	kb_pos_eval(k, 5, 0.5, p);
	cr_assert_float_eq(p[0], 1.0, 1e-12, "between key 0 and 1: %g", p[0]);
	kb_pos_eval(k, 5, 3.5, p);
	cr_assert_float_eq(p[0], 3.0, 1e-12, "after: %g", p[0]);
}

/* Mistake: a binary search over key times. BART takes the first segment,
 * in key order, whose end time exceeds t; Robots' gun_rot1 has times
 * that jump back (0 ... 48, then 42 ... 50), and only the linear rule
 * picks the segments the BART code does. Times here: 0 0 2 4 1 3 5 5. */
Test(aff_spline, keyframe_time_order_first_segment_rule)
{
	double ts[] = {0, 0, 2, 4, 1, 3, 5, 5};
	kb_key k[8];
	for (int i = 0; i < 8; i++)
		k[i] = key(ts[i], i, 0, 0, 0);
	uint32_t seg;
	double u;
	kb_segment(k, 8, 1.5, &seg, &u);
	cr_assert(seg == 0 && fabs(u - 0.75) < 1e-12, "t=1.5: segment %u u %g", seg, u);
	kb_segment(k, 8, 4.5, &seg, &u);
	cr_assert(seg == 4 && fabs(u - 0.75) < 1e-12, "t=4.5: segment %u u %g, want 4 0.75", seg,
	          u);
	kb_segment(k, 8, 3.5, &seg, &u);
	cr_assert(seg == 1 && fabs(u - 0.75) < 1e-12, "t=3.5: segment %u u %g, want 1 0.75", seg,
	          u);
}

static kb_key rkey(double t, double ax, double ay, double az, double deg)
{
	kb_key k = {t, {ax, ay, az, deg}, 0, 0, 0};
	return k;
}

/* q and the rotation of deg about z, up to sign. */
static void assert_zrot(const double q[4], double deg, const char *what)
{
	double h = deg * M_PI / 360.0;
	double d = fabs(q[0] * cos(h) + q[3] * sin(h));
	cr_assert(fabs(q[1]) < 1e-9 && fabs(q[2]) < 1e-9 && fabs(d - 1) < 1e-9,
	          "%s: q = (%g %g %g %g), want %g degrees about z", what, q[0], q[1], q[2], q[3],
	          deg);
}

/* Mistakes: degrees taken for radians, the half angle not halved, the
 * logarithms of q_i^-1 q_j taken in the wrong order. A uniform spin
 * (90 degrees a second about z) must come out uniform. */
Test(aff_spline, uniform_spin)
{
	kb_key k[5] = {rkey(0, 0, 0, 1, 0), rkey(1, 0, 0, 1, 90), rkey(2, 0, 0, 1, 180),
	               rkey(3, 0, 0, 1, 270), rkey(4, 0, 0, 1, 360)};
	double q[20], r[4];
	kb_rot_quats(k, 5, q);
	for (double t = 1; t <= 3; t += 0.25) {
		kb_rot_eval(k, q, 5, t, r);
		assert_zrot(r, 90 * t, "uniform spin");
	}
}

/* Mistake: no hemisphere flip. Keys at 0 and 340 degrees are 20 degrees
 * apart the short way; without negating q(340) the squad goes 340 degrees
 * the long way round (170 at the middle instead of -10). A non-unit axis
 * (BART's head_rot keys) must give the same rotation as the unit one. */
Test(aff_spline, acute_angle_flip_and_axis_length)
{
	kb_key k[4] = {rkey(0, 0, 0, 1, 0), rkey(1, 0, 0, 1, 0), rkey(2, 0, 0, 0.5, 340),
	               rkey(3, 0, 0, 2, 340)};
	double q[16], r[4];
	kb_rot_quats(k, 4, q);
	kb_rot_eval(k, q, 4, 1.5, r);
	assert_zrot(r, -10, "middle");
	kb_rot_eval(k, q, 4, 2, r);
	assert_zrot(r, -20, "end");
}

/* ---- the reader ---- */

static char dir[128];

static void setup_dir(void)
{
	tu_tmpdir(dir, sizeof dir);
}

/* Reads text as dir/name; fails the test on an error. */
static void load_ok(aff_scene *a, const char *name, const char *text)
{
	char p[1024];
	tu_write(p, sizeof p, dir, name, text);
	diag d = {{0}};
	cr_assert_eq(aff_load(a, p, NULL, NULL, &d), 0, "aff_load: %s", d.msg);
}

static void flat(const aff_scene *a, double t, scene *s)
{
	diag d = {{0}};
	cr_assert_eq(aff_flatten(a, t, 0, s, &d), 0, "aff_flatten: %s", d.msg);
}

static void assert_v3(vec3 v, double x, double y, double z, const char *what)
{
	cr_assert(fabs(v.x - x) < 1e-5 && fabs(v.y - y) < 1e-5 && fabs(v.z - z) < 1e-5,
	          "%s: (%g %g %g), want (%g %g %g)", what, v.x, v.y, v.z, x, y, z);
}

#define TRI "m\nvertices 3\n1 0 0\n0 1 0\n0 0 1\ntriangles 1\n0 1 2\n"

/* Mistake: the static transform's factors in the wrong order. xs is
 * T * R * S: (1,0,0) scaled by (2,3,1), turned 90 degrees about z, moved
 * by (10,0,0) is (10,2,0) ((10,3,0) with R before S); nested blocks
 * compose parent * child, so an outer move by (0,0,5) comes last. */
Test(aff_reader, static_transform_order, .init = setup_dir)
{
	aff_scene a;
	load_ok(&a, "xs.aff",
	        "xs 1 1 1 0 0 1 0 0 0 5 {\nxs 2 3 1\n0 0 1 90\n10 0 0\n{\n" TRI "}\n}\n");
	scene s;
	flat(&a, 0, &s);
	assert_v3(s.v[0], 10, 2, 5, "T*R*S under the parent");
	scene_free(&s);
	aff_free(&a);
}

/* Mistake: normals transformed like positions. Under a scale of 2 along
 * y a normal (1,1,0)/sqrt(2) must follow the inverse transpose: (2,1,0)
 * normalised, not (1,2,0). */
Test(aff_reader, normals_inverse_transpose, .init = setup_dir)
{
	aff_scene a;
	load_ok(&a, "n.aff",
	        "xs 1 2 1 1 0 0 0 0 0 0 {\nm\nvertices 3\n0 0 0\n1 -1 0\n0 0 1\n"
	        "normals 1\n0.70710678 0.70710678 0\ntriangles 1\n0 1 2 0 0 0\n}\n");
	scene s;
	flat(&a, 0, &s);
	assert_v3(s.n[0], 2 / sqrt(5), 1 / sqrt(5), 0, "normal");
	scene_free(&s);
	aff_free(&a);
}

/* Mistakes: normal and texture-coordinate indices taken to be the vertex
 * indices (27 of Robots' meshes have them differ), and a texture found
 * relative to the working folder. */
Test(aff_reader, separate_corner_indices, .init = setup_dir)
{
	char p[1024];
	tu_write(p, sizeof p, dir, "t.ppm", "P3\n1 1\n255\n1 2 3\n");
	aff_scene a;
	load_ok(&a, "ix.aff",
	        "m\nvertices 3\n0 0 0\n1 0 0\n0 1 0\nnormals 2\n1 0 0\n0 0 1\n"
	        "texturecoords 2 t.ppm\n0 0\n0.25 0.75\ntriangles 1\n2 1 0 1 1 0 1 0 1\n");
	scene s;
	flat(&a, 0, &s);
	assert_v3(s.v[0], 0, 1, 0, "vertex 2");
	assert_v3(s.n[2], 1, 0, 0, "normal 0");
	assert_v3(s.n[0], 0, 0, 1, "normal 1");
	cr_assert(s.uv[0].u == 0.25f && s.uv[1].v == 0.0f && s.uv[2].v == 0.75f,
	          "texture coordinates by their own indices");
	cr_assert_eq(a.ntex, 1);
	cr_assert(strstr(a.tex[0].path, dir), "texture beside the AFF file: %s", a.tex[0].path);
	scene_free(&s);
	aff_free(&a);
}

/* Mistake: a texture that cannot be decoded reported without the place
 * that names it (it is read when the scene is flattened, after the files
 * are closed). */
Test(aff_reader, bad_texture_names_its_line, .init = setup_dir)
{
	char p[1024];
	tu_write(p, sizeof p, dir, "bad.ppm", "P6\n4 4\n255\nshort");
	aff_scene a;
	load_ok(&a, "tex.aff",
	        "m\nvertices 3\n0 0 0\n1 0 0\n0 1 0\ntexturecoords 3 bad.ppm\n0 0\n1 0\n0 1\n"
	        "triangles 1\n0 1 2 0 1 2\n");
	scene s;
	diag d = {{0}};
	cr_assert_neq(aff_flatten(&a, 0, 1, &s, &d), 0, "a cut PPM was read");
	cr_assert(strstr(d.msg, "tex.aff:6:17: texture ") && strstr(d.msg, "bad.ppm"), "%s", d.msg);
	cr_assert(!strchr(d.msg, '\n'), "not one line: %s", d.msg);
	aff_free(&a);
}

/* Mistake: an include resolved against the working folder instead of the
 * including file's folder. The working folder holds a decoy part.aff
 * with two triangles; the one beside main.aff has one. The material set
 * by `fm` inside an include carries out of it (running state, as BART's
 * parser has it). */
Test(aff_reader, include_relative_to_including_file, .init = setup_dir)
{
	char p[1024], sub[256], old[1024];
	snprintf(sub, sizeof sub, "%s/sub", dir);
	cr_assert_eq(mkdir(sub, 0755), 0);
	tu_write(p, sizeof p, dir, "part.aff", TRI TRI);
	tu_write(p, sizeof p, sub, "part.aff", TRI "fm 0 0 0 0.5 0.25 0.125 0 0 0 10 0 0\n");
	tu_write(p, sizeof p, sub, "main.aff", "i 0 part.aff\n" TRI);
	cr_assert(getcwd(old, sizeof old));
	cr_assert_eq(chdir(dir), 0);
	aff_scene a;
	diag d = {{0}};
	int rc = aff_load(&a, "sub/main.aff", NULL, NULL, &d);
	cr_assert_eq(chdir(old), 0);
	cr_assert_eq(rc, 0, "%s", d.msg);
	cr_assert_eq(a.ntris, 2, "%u triangles: the decoy in the working folder was read", a.ntris);
	scene s;
	flat(&a, 0, &s);
	cr_assert(s.mats[s.mat[1]].kd.x == 0.5f, "fm from the include applies after it");
	scene_free(&s);
	aff_free(&a);
}

/* Mistakes: an `x` bound to its keyframes only when the `k` comes first
 * (BART puts it at the end), and a name without keyframes not taken as
 * the identity. Frames at two times differ. */
Test(aff_reader, animated_transform_binds_later_keys, .init = setup_dir)
{
	aff_scene a;
	load_ok(&a, "anim.aff",
	        "x mover {\n" TRI "}\nx nokeys {\n" TRI "}\n"
	        "k mover {\ntransl 4\n0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n"
	        "10 10 0 0 0 0 0\n10 10 0 0 0 0 0\n}\n");
	scene s0, s1;
	flat(&a, 0, &s0);
	flat(&a, 10, &s1);
	assert_v3(s0.v[0], 1, 0, 0, "t=0");
	assert_v3(s1.v[0], 11, 0, 0, "t=10");
	assert_v3(s1.v[3], 1, 0, 0, "no keyframes: identity");
	scene_free(&s0);
	scene_free(&s1);
	aff_free(&a);
}

/* Mistake: the camera block's rotation read the wrong way: BART's camera
 * looks down its local -z with +y up. Turning it 90 degrees about y makes
 * it look down -x. */
Test(aff_reader, animated_camera, .init = setup_dir)
{
	aff_scene a;
	load_ok(&a, "cam.aff",
	        "v\nfrom 0 0 0\nat 0 0 -1\nup 0 1 0\nangle 40\nhither 1\nresolution 4 3\n"
	        "l 1 2 3\n" TRI "k camera {\ntransl 4\n0 5 6 7 0 0 0\n0 5 6 7 0 0 0\n"
	        "1 5 6 7 0 0 0\n1 5 6 7 0 0 0\nrot 4\n0 0 1 0 90 0 0 0\n0 0 1 0 90 0 0 0\n"
	        "1 0 1 0 90 0 0 0\n1 0 1 0 90 0 0 0\n}\n");
	view v;
	diag d;
	cr_assert_eq(aff_view(&a, 0.5, &v, &d), 1, "%s", d.msg);
	assert_v3(v.cam.eye, 5, 6, 7, "eye");
	assert_v3(v3_sub(v.cam.lookat, v.cam.eye), -1, 0, 0, "view direction");
	assert_v3(v.cam.up, 0, 1, 0, "up");
	cr_assert_float_eq(v.cam.fov_deg, 40, 1e-6);
	cr_assert(v.nlights == 1 && v.lights[0].pos.z == 3.0f, "light");
	aff_free(&a);
}

/* Bad input: one line naming file:line:col, no crash, no allocation of a
 * declared count the file cannot hold, no endless include loop. */
static const struct bad {
	const char *text, *where, *what;
} BAD[] = {
    {"xs 1 1 1 0 0 1 0 0 0 0\nm\n", ":2:1:", "expected '{'"},
    {"q 1 2\n", ":1:1:", "unknown AFF command 'q'"},
    {"s 0 0 0 1\n", ":1:1:", "not supported"},
    {"}\n", ":1:1:", "closes no transform block"},
    {"x a {\n" TRI, ":9:1:", "opened at line 1 is not closed"},
    {"m\nvertices 3\n1 0 0\n0 1 0\n0 0 1\ntriangles 1\n0 1 3\n", ":7:5:", "vertex index 3"},
    {"m\nvertices 4000000\n1 2 3\n", ":2:10:", "more than the rest of the file"},
    {"m\nvertices 3\n1 0 0\n0 nan 0\n0 0 1\n", ":4:3:", "not finite"},
    {"m\nvertices 3\n1 0 0\n0 1.0x 0\n", ":4:3:", "found '1.0x'"},
    {"k a {\nrot 3\n0 0 1 0 0 0 0 0\n", ":2:5:", "out of range [4,"},
    {"k a {\ntransl 4\n0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n}\n"
     "k a {\n}\n",
     ":8:3:", "given twice"},
    {"k a {\nrot 4\n0 0 0 0 10 0 0 0\n1 0 0 1 0 0 0 0\n2 0 0 1 0 0 0 0\n3 0 0 1 0 0 0 0\n}\n",
     ":3:9:", "zero axis"},
    {"i 0 nothere.aff\n", ":1:5:", "cannot read included file"},
    {"i 0 loop.aff\n", ":1:1:", "nested deeper than 16"},
    {"m\nvertices 3\n1 0 0\x01\n0 1 0\n0 0 1\ntriangles 1\n0 1 2\n", ":3:6:", "control byte 0x01"},
    {"v\nfrom 0 0 0\nat 0 0 1\nup 0 1 0\nangle 0\n", ":5:7:", "not in (0, 180)"},
    {"m\nvertices 3\n1 0 0\n0 1 0\n0 0 1\ntriangles 1\n0 1", ":7:4:", "end of the file"},
};

/* Mistakes the table catches: a reader that crashes, allocates a declared
 * count before checking it, loops on a self-include, or names no place. */
Test(aff_reader, bad_input_one_line_with_place, .init = setup_dir)
{
	for (size_t i = 0; i < sizeof BAD / sizeof BAD[0]; i++) {
		char p[1024];
		tu_write(p, sizeof p, dir, "loop.aff", BAD[i].text);
		aff_scene a;
		diag d = {{0}};
		cr_assert_neq(aff_load(&a, p, NULL, NULL, &d), 0, "case %zu accepted", i);
		cr_assert(!strchr(d.msg, '\n'), "case %zu: not one line: %s", i, d.msg);
		cr_assert(strstr(d.msg, BAD[i].where) && strstr(d.msg, BAD[i].what),
		          "case %zu: '%s', want '%s' and '%s'", i, d.msg, BAD[i].where,
		          BAD[i].what);
		cr_assert(strstr(d.msg, "loop.aff"), "case %zu: names no file: %s", i, d.msg);
	}
}

/* The programs: a bad AFF file is one line and exit status 2 through the
 * same import entry in both; --anim-time needs an AFF scene. */
Test(aff_reader, programs_refuse_bad_aff, .init = setup_dir)
{
	char p[1024], args[1200];
	tu_write(p, sizeof p, dir, "bad.aff", TRI "q\n");
	snprintf(args, sizeof args, "--scene %s --size 8x8", p);
	cr_assert_eq(tu_prog(dir, "rtref", args), 2);
	tu_one_line(dir, "rtref", "bad.aff:8:1: unknown AFF command 'q'");
	cr_assert_eq(tu_prog(dir, "saarsim", args), 2);
	tu_one_line(dir, "saarsim", "bad.aff:8:1: unknown AFF command 'q'");
	cr_assert_eq(tu_prog(dir, "rtref", "--scene spd:tetra --anim-time 1"), 2);
	tu_one_line(dir, "rtref", "--anim-time: needs an AFF scene");
}

/* A triangle that moves 1 to the right per time unit, under a view. */
static const char *MOVING = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\n"
                            "resolution 8 8\nl 0 5 5\nx mover {\nm\nvertices 3\n-1 -1 0\n"
                            "1 -1 0\n0 1 0\ntriangles 1\n0 1 2\n}\nk mover {\ntransl 4\n"
                            "0 0 0 0 0 0 0\n0 0 0 0 0 0 0\n1 1 0 0 0 0 0\n1 1 0 0 0 0 0\n}\n";

/* Mistake: world_set_time leaving something of the old time behind (the
 * view, the kd-tree over the old triangles): moving a world to t = 1
 * must give what loading it at t = 1 gives. */
Test(aff_world, set_time_equals_load_at_time, .init = setup_dir)
{
	char p[1024];
	tu_write(p, sizeof p, dir, "moving.aff", MOVING);
	world_opts o;
	world_opts_default(&o);
	o.scene = p;
	o.have_anim_fps = 1;
	o.anim_fps = 4;
	world w, w1;
	diag d = {{0}};
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(world_set_time(&w, &o, world_frame_time(&o, 3), &d), 0, "%s", d.msg);
	o.have_anim_fps = 0;
	o.have_anim_time = 1;
	o.anim_time = 0.75;
	cr_assert_eq(world_load(&w1, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(w.s.ntris, w1.s.ntris);
	cr_assert(!memcmp(w.s.v, w1.s.v, 3 * sizeof *w.s.v), "the triangles differ");
	cr_assert(!memcmp(&w.v.cam, &w1.v.cam, sizeof w.v.cam), "the cameras differ");
	cr_assert_eq(w.m.size, w1.m.size);
	cr_assert(!memcmp(w.m.bytes, w1.m.bytes, w.m.size), "the memory images differ");
	cr_assert_str_eq(w.scene_label, w1.scene_label);
	/* and the time is not ignored by both: t = 0 is another frame (mistake:
	 * load and set_time both placing the scene at t = 0) */
	world w0;
	o.anim_time = 0;
	cr_assert_eq(world_load(&w0, &o, &d), 0, "%s", d.msg);
	cr_assert(memcmp(w0.s.v, w1.s.v, 3 * sizeof *w.s.v), "t = 0 and t = 0.75 are the same");
	world_free(&w0);
	world_free(&w);
	world_free(&w1);
}

/* Both programs render an animation: --anim-fps F --frames N writes one
 * file per frame (name-0000.png, ...), the frames differ, and each chip
 * frame is checked against kernel-ref's. Mistake caught: frames all at
 * the first time, or one file overwritten N times. */
Test(aff_world, programs_render_frames, .init = setup_dir)
{
	char p[1024], args[1400];
	tu_write(p, sizeof p, dir, "moving.aff", MOVING);
	snprintf(args, sizeof args,
	         "--scene %s --size 16x16 --anim-fps 2 --frames 2 --out %s/r.ppm", p, dir);
	cr_assert_eq(tu_prog(dir, "rtref", args), 0);
	cr_assert(strstr(tu_slurp(dir, "out"), "moving.aff@t=0.5"), "no frame at t = 0.5");
	char *f0 = tu_slurp(dir, "r-0000.ppm"), *f1 = tu_slurp(dir, "r-0001.ppm");
	cr_assert(strlen(f0) > 10 && memcmp(f0, f1, 16 * 16 * 3 + 10), "the two frames are equal");
	snprintf(
	    args, sizeof args,
	    "--scene %s --size 16x16 --anim-fps 2 --frames 2 --out %s/c.ppm --report %s/c.json", p,
	    dir, dir);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 0);
	const char *out = tu_slurp(dir, "out");
	const char *a = strstr(out, "packets identical"),
	           *b = a ? strstr(a + 1, "packets identical") : NULL;
	cr_assert(b, "not every chip frame was checked: %s", out);
	cr_assert(tu_exists(dir, "c-0001.ppm") && tu_exists(dir, "c-0001.json") &&
	              !tu_exists(dir, "c.ppm"),
	          "per-frame outputs");
	cr_assert(!memcmp(tu_slurp(dir, "c-0001.ppm"), tu_slurp(dir, "r-0001.ppm"), 16 * 16 * 3),
	          "the chip's frame 1 is not kernel-ref's");
}

/* ---- BART Robots against its flattened OBJ ---- */

/* A triangle's cell: its centroid on a grid of RB_CELL units. */
#define RB_CELL 0.05
#define RB_TOL  2e-3 /* the OBJ prints 7 significant digits: 5e-5 at 535 */

typedef struct rb_entry {
	int64_t cell[3];
	uint32_t tri;
} rb_entry;

static void rb_cell(const scene *s, uint32_t t, int64_t c[3])
{
	const vec3 *p = s->v + 3 * (uint64_t)t;
	for (int a = 0; a < 3; a++)
		c[a] = (int64_t)floor((v3_get(p[0], a) + v3_get(p[1], a) + v3_get(p[2], a)) / 3.0 /
		                      RB_CELL);
}

static int rb_cmp(const void *x, const void *y)
{
	const rb_entry *a = x, *b = y;
	for (int k = 0; k < 3; k++)
		if (a->cell[k] != b->cell[k])
			return a->cell[k] < b->cell[k] ? -1 : 1;
	return 0;
}

/* Triangle ta of a and tb of b have the same corners with the same texture
 * coordinates, in the same cyclic order (the same winding), within RB_TOL
 * (city2.aff has coincident copies of triangles that differ only in their
 * texture coordinates): 1 + the rotation r (a's corner k is b's corner
 * k + r), or 0. */
static int rb_same(const scene *a, uint32_t ta, const scene *b, uint32_t tb)
{
	const vec3 *p = a->v + 3 * (uint64_t)ta, *q = b->v + 3 * (uint64_t)tb;
	for (int r = 0; r < 3; r++) {
		int ok = 1;
		for (int k = 0; k < 3 && ok; k++) {
			vec3 d = v3_sub(p[k], q[(k + r) % 3]);
			vec2 u = a->uv[3 * (uint64_t)ta + k],
			     w = b->uv[3 * (uint64_t)tb + (k + r) % 3];
			ok = fabsf(d.x) < RB_TOL && fabsf(d.y) < RB_TOL && fabsf(d.z) < RB_TOL &&
			     fabsf(u.u - w.u) < RB_TOL && fabsf(u.v - w.v) < RB_TOL;
		}
		if (ok)
			return 1 + r;
	}
	return 0;
}

/* An unused triangle of a (index e, sorted by cell) matching triangle t
 * of b; -1 if none. Looks in t's cell and the 26 around it. */
static long rb_find(const rb_entry *e, uint32_t n, const uint8_t *used, const scene *a,
                    const scene *b, uint32_t t, int *rot)
{
	int64_t c[3];
	rb_cell(b, t, c);
	for (int dx = -1; dx <= 1; dx++)
		for (int dy = -1; dy <= 1; dy++)
			for (int dz = -1; dz <= 1; dz++) {
				rb_entry k = {{c[0] + dx, c[1] + dy, c[2] + dz}, 0};
				const rb_entry *hit = bsearch(&k, e, n, sizeof *e, rb_cmp);
				if (!hit)
					continue;
				while (hit > e && !rb_cmp(hit - 1, &k))
					hit--;
				for (; hit < e + n && !rb_cmp(hit, &k); hit++)
					if (!used[hit->tri] && (*rot = rb_same(a, hit->tri, b, t)))
						return hit->tri;
			}
	return -1;
}

/* Mistakes: any in the transforms, splines at t = 0, includes, the index
 * order of the meshes, the normals' transform, the texture coordinates
 * (their indices, a flipped v) or the materials. The flattened t = 0 OBJ in
 * ../shared/scenes/bart_robots was made from the same files by another
 * program: every triangle must have its match there (up to order and the
 * OBJ's 7 printed digits), with the same winding, texture coordinates,
 * normals and fm colours. */
Test(aff_robots, t0_equals_flattened_obj, .timeout = 120)
{
	char aff[1024], obj[1024];
	SCENE_OR_SKIP(aff, "bart_robots_aff/aff/Robot.aff");
	SCENE_OR_SKIP(obj, "bart_robots/robots.obj.gz");
	aff_scene a;
	diag d = {{0}};
	cr_assert_eq(aff_load(&a, aff, NULL, NULL, &d), 0, "%s", d.msg);
	scene s, o;
	flat(&a, 0, &s);
	cr_assert_eq(scene_import_inproc(&o, obj, NULL, NULL, &d), 0, "%s", d.msg);
	cr_assert_eq(s.ntris, 71708);
	cr_assert_eq(o.ntris, s.ntris);
	rb_entry *e = malloc(s.ntris * sizeof *e);
	uint8_t *used = calloc(s.ntris, 1);
	cr_assert(e && used);
	for (uint32_t t = 0; t < s.ntris; t++) {
		rb_cell(&s, t, e[t].cell);
		e[t].tri = t;
	}
	qsort(e, s.ntris, sizeof *e, rb_cmp);
	uint32_t missing = 0, first = 0, colour = 0, normal = 0;
	for (uint32_t t = 0; t < o.ntris; t++) {
		int rot = 0;
		long m = rb_find(e, s.ntris, used, &s, &o, t, &rot);
		if (m < 0) {
			if (!missing++)
				first = t;
			continue;
		}
		used[m] = 1;
		for (int k = 0; k < 3; k++) {
			uint64_t ia = 3 * (uint64_t)m + (uint64_t)k,
			         ib = 3 * (uint64_t)t + (k + rot - 1) % 3;
			normal += v3_len(v3_sub(s.n[ia], o.n[ib])) > RB_TOL;
		}
		vec3 dk = v3_sub(s.mats[s.mat[m]].kd, o.mats[o.mat[t]].kd);
		vec3 ds = v3_sub(s.mats[s.mat[m]].ks, o.mats[o.mat[t]].ks);
		colour += fabsf(dk.x) + fabsf(dk.y) + fabsf(dk.z) + fabsf(ds.x) + fabsf(ds.y) +
		              fabsf(ds.z) >
		          1e-4f;
	}
	const vec3 *f = o.v + 3 * (uint64_t)first;
	cr_assert_eq(missing, 0,
	             "%u OBJ triangles have no match, the first (%g %g %g) (%g %g %g) (%g %g %g)",
	             missing, f[0].x, f[0].y, f[0].z, f[1].x, f[1].y, f[1].z, f[2].x, f[2].y,
	             f[2].z);
	cr_assert_eq(colour, 0, "%u triangles with other fm colours than the OBJ's", colour);
	cr_assert_eq(normal, 0, "%u corners with other normals than the OBJ's", normal);
	/* and it moves: the robots and the camera at t = 10 are elsewhere */
	scene s10;
	flat(&a, 10, &s10);
	uint32_t moved = 0;
	for (uint64_t i = 0; i < 3 * (uint64_t)s.ntris; i++)
		moved += !rb_same(&s, (uint32_t)(i / 3), &s10, (uint32_t)(i / 3));
	cr_assert(moved > 3 * 10000, "only %u corners moved between t = 0 and 10", moved);
	view v0, v10;
	cr_assert_eq(aff_view(&a, 0, &v0, &d), 1);
	cr_assert_eq(aff_view(&a, 10, &v10, &d), 1);
	cr_assert(v3_len(v3_sub(v0.cam.eye, v10.cam.eye)) > 1, "the camera did not move");
	free(e);
	free(used);
	scene_free(&s);
	scene_free(&s10);
	scene_free(&o);
	aff_free(&a);
}
