/*
 * test_view.c: views files (view_load, view_list), camera checks and the
 * default light. Every error must read "FILE:LINE:COL: ..." and point at
 * the offending node.
 */
#include "kernel-ref/camera.h"
#include "kernel-ref/view.h"
#include "kernel-ref/world.h"
#include "kernel-ref/yload.h"
#include "tests/testutil.h"

#include <math.h>
#include <string.h>

#define CAM "    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: 45}\n"

/* Writes a views file whose view `a` has the given body (after "  a:\n"). */
static void write_views(char *path, size_t n, const char *body)
{
	char dir[256], text[4096];
	tu_tmpdir(dir, sizeof dir);
	snprintf(text, sizeof text, "# test views\nviews:\n  a:\n%s  b:\n    scene: b.obj\n" CAM,
	         body);
	tu_write(path, n, dir, "views.yaml", text);
}

/* 1-based column of `needle` on 1-based `line` of the file's text. */
static int col_of(const char *path, int line, const char *needle)
{
	char buf[512];
	FILE *f = fopen(path, "r");
	cr_assert(f);
	for (int i = 0; i < line; i++)
		cr_assert(fgets(buf, sizeof buf, f), "file has no line %d", line);
	fclose(f);
	const char *p = strstr(buf, needle);
	cr_assert(p, "'%s' not on line %d", needle, line);
	return (int)(p - buf) + 1;
}

/* view_load of `a` must fail with exactly "path:line:col: <starts with msg>". */
static void expect_error(const char *body, int line, const char *needle, const char *msg)
{
	char path[512], want[1024];
	write_views(path, sizeof path, body);
	view v;
	diag d = {{0}};
	cr_assert_eq(view_load(&v, path, "a", &d), -1, "should fail: %s", body);
	int col = needle ? col_of(path, line, needle) : 0;
	snprintf(want, sizeof want, "%s:%d:%d: %s", path, line, col, msg);
	cr_assert(strncmp(d.msg, want, strlen(want)) == 0, "got  '%s'\nwant '%s...'", d.msg, want);
}

Test(view, shared_views_file)
{
	char path[1024];
	SCENE_OR_SKIP(path, "views.yaml");
	char names[32][VIEW_NAME_MAX];
	diag d = {{0}};
	int n = view_list(path, names, 32, &d);
	cr_assert_eq(n, 10, "%s", d.msg);
	cr_assert_str_eq(names[0], "cornell");
	cr_assert_str_eq(names[9], "sibenik");
	for (int i = 0; i < n; i++) {
		view v;
		cr_assert_eq(view_load(&v, path, names[i], &d), 0, "%s: %s", names[i], d.msg);
		cr_assert_str_eq(v.name, names[i]);
		cr_assert(v.lights_given && v.nlights >= 1);
		cr_assert(strncmp(v.scene, tu_scenes_dir(), strlen(tu_scenes_dir())) == 0,
		          "scene path %s is resolved against the views file", v.scene);
	}
	view v;
	cr_assert_eq(view_load(&v, path, "conference", &d), 0, "%s", d.msg);
	cr_assert_eq(v.cam.eye.x, -800.0f);
	cr_assert_eq(v.cam.eye.y, 400.0f);
	cr_assert_eq(v.cam.eye.z, -800.0f);
	cr_assert_eq(v.cam.lookat.x, 300.0f);
	cr_assert_eq(v.cam.lookat.y, 100.0f);
	cr_assert_eq(v.cam.lookat.z, 0.0f);
	cr_assert_eq(v.cam.up.y, 1.0f);
	cr_assert_eq(v.cam.fov_deg, 60.0f);
	cr_assert_eq(v.nlights, 2);
	cr_assert_eq(v.lights[0].pos.x, 300.0f);
	cr_assert_eq(v.lights[0].pos.y, 500.0f);
	cr_assert_eq(v.lights[0].pos.z, -200.0f);
	cr_assert_eq(v.lights[1].pos.x, 700.0f);
	cr_assert_eq(v.lights[1].pos.z, -400.0f);
	cr_assert_eq(v.lights[1].color.x, 1.0f);
	char want[1100];
	snprintf(want, sizeof want, "%s/conference_69k/conference.obj.gz", tu_scenes_dir());
	cr_assert_str_eq(v.scene, want);

	cr_assert_eq(view_load(&v, path, "robots", &d), 0, "%s", d.msg);
	cr_assert_float_eq(v.cam.fov_deg, 36.87f, 1e-5);
}

Test(view, minimal_view_and_default_light)
{
	char path[512];
	write_views(path, sizeof path, "    scene: sub/s.obj\n" CAM "    note: \"free text\"\n");
	view v;
	diag d = {{0}};
	cr_assert_eq(view_load(&v, path, "a", &d), 0, "%s", d.msg);
	cr_assert_eq(v.lights_given, 0);
	cr_assert_eq(v.nlights, 0);
	cr_assert_eq(v.cam.eye.z, 5.0f);
	cr_assert_eq(v.cam.fov_deg, 45.0f);
	char want[600];
	snprintf(want, sizeof want, "%.*s/sub/s.obj", (int)(strrchr(path, '/') - path), path);
	cr_assert_str_eq(v.scene, want);

	scene s;
	scene_init(&s, "t");
	s.bounds = (aabb){v3(-1, -2, -2), v3(1, 2, 2)}; /* half diagonal 3 */
	view_place_default_light(&v, &s);
	cr_assert_eq(v.nlights, 1);
	cr_assert_float_eq(v.lights[0].pos.x, 0.0f, 1e-6);
	cr_assert_float_eq(v.lights[0].pos.y, 6.0f, 1e-5);
	cr_assert_float_eq(v.lights[0].pos.z, 3.0f, 1e-5);
	cr_assert_eq(v.lights[0].color.y, 1.0f);
	view_place_default_light(&v, &s);
	cr_assert_eq(v.nlights, 1, "placed once");
}

Test(view, errors_point_at_the_node)
{
	expect_error("    scene: s.obj\n    colour: red\n" CAM, 5, "colour",
	             "unknown key 'colour'");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: 45, "
	             "zoom: 2}\n",
	             4, "zoom", "unknown key 'zoom' in camera");
	expect_error("    camera: {eye: [1.0x, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: 45}\n",
	             4, "1.0x", "eye: '1.0x' is not a number");
	expect_error("    camera: {eye: [0, nan, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: 45}\n",
	             4, "nan", "eye: 'nan' is not a finite number");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: .inf}\n",
	             4, ".inf", "fov: '.inf' is not a finite number");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 1e99], up: [0, 1, 0], fov: 4}\n",
	             4, "1e99", "lookat: '1e99' is not a finite number");
	expect_error("    scene: s.obj\n", 4, "scene", "view 'a' has no camera");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: 0}\n", 4,
	             "0}", "fov must be between 0 and 180");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: 180}\n",
	             4, "180", "fov must be between 0 and 180");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 0, -2], fov: 45}\n",
	             4, "[0, 0, -2]", "up is parallel to the view direction");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 5], up: [0, 1, 0], fov: 45}\n", 4,
	             "[0, 0, 5], up", "eye and lookat are the same point");
	expect_error("    camera: {eye: [0, 0], lookat: [0, 0, 0], up: [0, 1, 0], fov: 45}\n", 4,
	             "[0, 0]", "eye must have exactly 3 numbers, got 2");
	expect_error("    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0]}\n", 4, "{eye",
	             "camera of view 'a' has no 'fov'");
	expect_error("    lights: [[1, 2, 3], [1, 2, x]]\n" CAM, 4, "x]", "light position: 'x'");
	expect_error("    lights: [[1,2,3],[1,2,3],[1,2,3],[1,2,3],[1,2,3],[1,2,3],[1,2,3],"
	             "[1,2,3],[1,2,3],[1,2,3],[1,2,3],[1,2,3],[1,2,3],[1,2,3],[1,2,3],"
	             "[1,2,3],[9,9,9]]\n" CAM,
	             4, "[9,9,9]", "more than 16 lights");
}

Test(view, unknown_name_lists_views)
{
	char path[512];
	write_views(path, sizeof path, "    scene: s.obj\n" CAM);
	view v;
	diag d = {{0}};
	cr_assert_eq(view_load(&v, path, "zz", &d), -1);
	char want[700];
	snprintf(want, sizeof want, "%s: no view named 'zz'; available views: a, b", path);
	cr_assert_str_eq(d.msg, want);
}

Test(view, file_level_errors)
{
	char dir[256], path[512], want[700];
	diag d = {{0}};
	view v;
	cr_assert_eq(view_load(&v, "/nonexistent/views.yaml", "a", &d), -1);
	cr_assert(strncmp(d.msg, "/nonexistent/views.yaml: ", 25) == 0, "%s", d.msg);

	tu_tmpdir(dir, sizeof dir);
	/* Not YAML: an unclosed flow sequence. */
	tu_write(path, sizeof path, dir, "bad.yaml", "views:\n  a: [1, 2\n  b: 3\n");
	cr_assert_eq(view_load(&v, path, "a", &d), -1);
	snprintf(want, sizeof want, "%s:3:4: not valid YAML: ", path);
	cr_assert(strncmp(d.msg, want, strlen(want)) == 0, "got '%s', want '%s'", d.msg, want);
	char names[4][VIEW_NAME_MAX];
	cr_assert_eq(view_list(path, names, 4, &d), -1);
	cr_assert(strncmp(d.msg, want, strlen(want)) == 0, "%s", d.msg);

	tu_write(path, sizeof path, dir, "noviews.yaml", "cameras:\n  a: 1\n");
	cr_assert_eq(view_load(&v, path, "a", &d), -1);
	snprintf(want, sizeof want,
	         "%s:1:1: unknown top-level key 'cameras' (a views file has only `views`)", path);
	cr_assert_str_eq(d.msg, want);

	/* what the config loader refuses too: a key beside `views`, `views`
	 * twice, a view name twice (the later one was silently ignored), a
	 * second document */
	const char *cam =
	    "    camera: {eye: [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, 0], fov: 45}\n";
	struct {
		const char *text, *msg;
	} files[] = {
	    {"views:\n  a:\n%sextra: 1\n", ":4:1: unknown top-level key 'extra'"},
	    {"views:\n  a:\n%sviews:\n  b: 1\n", ":4:1: duplicate key 'views' (first at line 1)"},
	    {"views:\n  a:\n%s  a:\n%s", ":4:3: duplicate view name 'a' (first at line 2)"},
	    {"views:\n  a:\n%s---\nviews: {}\n", ":5:1: only one YAML document is allowed"},
	};
	for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
		char text[512];
		snprintf(text, sizeof text, files[i].text, cam, cam);
		tu_write(path, sizeof path, dir, "dup.yaml", text);
		cr_assert_eq(view_load(&v, path, "a", &d), -1, "case %zu loaded", i);
		snprintf(want, sizeof want, "%s%s", path, files[i].msg);
		cr_assert(strncmp(d.msg, want, strlen(want)) == 0, "case %zu: got '%s', want '%s'",
		          i, d.msg, want);
		cr_assert_eq(view_list(path, names, 4, &d), -1, "case %zu listed", i);
	}
	/* a list of names too long for one line ends with how many more */
	char big[8192] = "views:\n";
	for (int i = 0; i < 60; i++)
		snprintf(big + strlen(big), sizeof big - strlen(big), "  view_number_%03d:\n%s", i,
		         cam);
	tu_write(path, sizeof path, dir, "many.yaml", big);
	cr_assert_eq(view_load(&v, path, "zz", &d), -1);
	cr_assert(strstr(d.msg, "view_number_000, view_number_001") && strstr(d.msg, " more"), "%s",
	          d.msg);

	tu_write(path, sizeof path, dir, "prose.yaml", "just some words\n");
	cr_assert_eq(view_list(path, names, 4, &d), -1);
	snprintf(want, sizeof want, "%s:1:1: no top-level `views` mapping", path);
	cr_assert_str_eq(d.msg, want);

	tu_write(path, sizeof path, dir, "empty.yaml", "");
	cr_assert_eq(view_list(path, names, 4, &d), -1);
	cr_assert(strncmp(d.msg, path, strlen(path)) == 0, "%s", d.msg);
}

/* Writes text to a fresh views.yaml; view_load of `a` must give exactly
 * "path<where_msg>" (where_msg "" = must load). */
static void expect_load(const char *text, const char *where_msg)
{
	char dir[256], path[512], want[1024];
	tu_tmpdir(dir, sizeof dir);
	tu_write(path, sizeof path, dir, "views.yaml", text);
	view v;
	diag d = {{0}};
	int rc = view_load(&v, path, "a", &d);
	if (!*where_msg) {
		cr_assert_eq(rc, 0, "%s", d.msg);
		return;
	}
	cr_assert_eq(rc, -1, "loaded, want%s", where_msg);
	snprintf(want, sizeof want, "%s%s", path, where_msg);
	cr_assert_str_eq(d.msg, want);
}

/* The limits of a views file (docs/views.md "Limits"), each refused at the
 * event that breaks it; the old loader read all of it (and took minutes
 * over 200,000 `[`). The largest input within each limit loads. */
Test(view, size_depth_and_node_limits)
{
	const char *head = "views:\n  a:\n" CAM "    note: ";
	char want[256];
	/* depth: the root, `views` and `a` are three levels; a note nested to
	 * the limit loads, one more is refused where it opens */
	char *close = tu_repeat("", "]", YL_DEPTH_MAX - 3, "\n");
	char *text = tu_repeat(head, "[", YL_DEPTH_MAX - 3, close);
	expect_load(text, "");
	free(text);
	free(close);
	text = tu_repeat(head, "[", 200000, "\n");
	expect_load(text, ":4:40: YAML nested deeper than 32 levels (the depth limit for a views "
	                  "file)");
	free(text);

	/* nodes: 26 before the note's items (root, views, a, the camera's 19,
	 * note and its sequence); the items up to the limit load */
	char *open = tu_repeat(head, "[", 1, "");
	text = tu_repeat(open, "0,", VIEW_NODES_MAX - 27, "0]\n");
	expect_load(text, "");
	free(text);
	text = tu_repeat(open, "0,", VIEW_NODES_MAX - 26, "0]\n");
	snprintf(want, sizeof want,
	         ":4:%d: more than %d YAML nodes (the node limit for a views file)",
	         12 + 2 * (VIEW_NODES_MAX - 26), VIEW_NODES_MAX);
	expect_load(text, want);
	free(text);
	free(open);

	/* size: VIEW_FILE_MAX bytes load, one more does not */
	size_t pad = VIEW_FILE_MAX - strlen(head) - strlen("1\n#\n");
	text = tu_repeat("", " ", pad, "");
	char *full = tu_repeat(head, "1\n#", 1, text);
	free(text);
	text = tu_repeat(full, "", 0, "\n");
	cr_assert_eq(strlen(text), VIEW_FILE_MAX);
	expect_load(text, "");
	free(text);
	text = tu_repeat(full, " ", 1, "\n");
	snprintf(want, sizeof want, ": larger than the size limit for a views file (%u bytes)",
	         VIEW_FILE_MAX);
	expect_load(text, want);
	free(text);
	free(full);
}

/* Anchors and aliases are refused (kernel-ref/yload.h says why), also in a
 * note: the billion laughs (nine levels of ten aliases each) at its first
 * anchor. The old loader accepted it. */
Test(view, anchors_and_aliases_are_refused)
{
	char text[4096] = "views:\n  a:\n" CAM "    note:\n      lol0: &a0 [lol]\n";
	for (int i = 1; i < 10; i++) {
		snprintf(text + strlen(text), sizeof text - strlen(text), "      lol%d: &a%d [", i,
		         i);
		for (int j = 0; j < 10; j++)
			snprintf(text + strlen(text), sizeof text - strlen(text), "%s*a%d",
			         j ? ", " : "", i - 1);
		snprintf(text + strlen(text), sizeof text - strlen(text), "]\n");
	}
	expect_load(text, ":5:13: YAML anchors and aliases are not allowed in a views file (&a0)");
	expect_load("views:\n  a:\n    camera: {eye: &e [0, 0, 5], lookat: [0, 0, 0], up: [0, 1, "
	            "0], fov: 45}\n",
	            ":3:19: YAML anchors and aliases are not allowed in a views file (&e)");
}

Test(view, camera_validate_flags)
{
	diag d = {{0}};
	camera c = {v3(0, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 45};
	cr_assert_eq(camera_validate(&c, "--eye", &d), 0);
	c.up = v3(0, 0, 3);
	cr_assert_eq(camera_validate(&c, "--up", &d), -1);
	cr_assert_str_eq(d.msg, "--up: up is parallel to the view direction (lookat - eye)");
	c.up = v3(0, 1, 0);
	c.fov_deg = NAN;
	cr_assert_eq(camera_validate(&c, "--fov", &d), -1);
	c.fov_deg = 200;
	cr_assert_eq(camera_validate(&c, "--fov", &d), -1);
	cr_assert(strstr(d.msg, "--fov: fov must be between"), "%s", d.msg);
}

/* The camera basis is built in float through squared lengths: a view
 * direction that overflows (two huge finite points: lookat - eye is
 * infinite) made a NaN basis and a blank frame with no error, and one
 * whose squared length overflows (eye at 1e20) was blamed on up. Each is
 * refused for what it is; a far but representable camera is accepted and
 * gives a finite basis. */
Test(view, camera_beyond_float_range_is_refused)
{
	diag d = {{0}};
	struct {
		camera c;
		const char *msg;
	} cases[] = {
	    {{v3(-3e38f, 5, 5), v3(3e38f, 5, 5), v3(0, 1, 0), 45}, "too far apart"},
	    {{v3(1e20f, 5, 5), v3(0, 0, 0), v3(0, 1, 0), 45}, "too far apart"},
	    {{v3(1e-25f, 0, 0), v3(0, 0, 0), v3(0, 1, 0), 45}, "too close together"},
	    {{v3(0, 0, 5), v3(0, 0, 0), v3(0, 1e25f, 0), 45}, "up is too long or too short"},
	    {{v3(0, 0, 5), v3(0, 0, 0), v3(0, 1e-25f, 0), 45}, "up is too long or too short"},
	    {{v3(1e18f, 5, 5), v3(0, 0, 0), v3(0, 1, 0), 45}, NULL},
	    {{v3(0, 0, 5), v3(0, 0, 0), v3(0, 1e-15f, 0), 45}, NULL},
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
		int rc = camera_validate(&cases[i].c, "--eye", &d);
		if (cases[i].msg) {
			cr_assert_eq(rc, -1, "case %zu accepted", i);
			cr_assert(strstr(d.msg, cases[i].msg), "case %zu: %s", i, d.msg);
			continue;
		}
		cr_assert_eq(rc, 0, "case %zu: %s", i, d.msg);
		cam_frame cs;
		cam_setup(&cs, &cases[i].c, 64, 64);
		cr_assert(v3_finite(cs.u) && v3_finite(cs.v) && v3_finite(cs.w), "case %zu", i);
		cr_assert_float_eq(v3_len(cs.u), 1.0f, 1e-5f, "case %zu", i);
		cr_assert_float_eq(v3_len(cs.w), 1.0f, 1e-5f, "case %zu", i);
	}
}

Test(view, default_view_frames_default_scene)
{
	view v;
	diag d = {{0}};
	view_default(&v);
	cr_assert_eq(camera_validate(&v.cam, "default", &d), 0, "%s", d.msg);
	cr_assert_eq(v.nlights, 2);
	scene s;
	scene_default(&s);
	for (int i = 0; i < v.nlights; i++) {
		vec3 p = v.lights[i].pos;
		cr_assert(p.x > s.bounds.lo.x && p.x < s.bounds.hi.x);
		cr_assert(p.y > s.bounds.lo.y && p.y < s.bounds.hi.y, "below the ceiling");
		cr_assert(p.z > s.bounds.lo.z && p.z < s.bounds.hi.z);
	}
	scene_free(&s);
}

/* A scene file given without a view is framed by its bounding box, by the
 * shared views file's "bbox framed from +z" rule (the embedded room's
 * camera showed the bunny as a few pixels): its camera is the one the
 * views file gives those scenes, computed independently, and its light
 * too. */
Test(view, scene_without_view_is_framed_by_its_box)
{
	const char *names[] = {"teapot", "bunny", "dragon4"};
	char views[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	for (int i = 0; i < 3; i++) {
		view ref;
		diag d;
		cr_assert_eq(view_load(&ref, views, names[i], &d), 0, "%s", d.msg);
		world_opts o;
		world_opts_default(&o);
		o.scene = ref.scene;
		world w;
		cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
		cr_assert_str_eq(w.v.name, "bbox");
		const vec3 a[4] = {w.v.cam.eye, w.v.cam.lookat, w.v.lights[0].pos, w.v.cam.up};
		const vec3 b[4] = {ref.cam.eye, ref.cam.lookat, ref.lights[0].pos, ref.cam.up};
		float size = v3_len(v3_sub(w.s.bounds.hi, w.s.bounds.lo));
		for (int k = 0; k < 4; k++)
			cr_assert_lt(v3_len(v3_sub(a[k], b[k])), 1e-4f * size,
			             "%s: point %d is (%g, %g, %g), the views file's (%g, %g, %g)",
			             names[i], k, a[k].x, a[k].y, a[k].z, b[k].x, b[k].y, b[k].z);
		cr_assert_eq(w.v.cam.fov_deg, ref.cam.fov_deg);
		cr_assert_eq(w.v.nlights, 1);
		world_free(&w);
	}
}

/* Mistake: a "\0" escape taken as the end of the string: libyaml keeps
 * the NUL inside the value, every reader takes values as C strings, so
 * `scene: "good.obj\0x"` loaded good.obj with exit 0. A NUL in any string
 * (a value or a key, views file or config: the same reader) is refused at
 * its node. */
Test(view, nul_in_a_string_is_refused)
{
	expect_error("    scene: \"s.obj\\0x\"\n" CAM, 4, "\"s.obj",
	             "a NUL byte (\\0) in a string");
	expect_error("    note: \"\\0\"\n" CAM, 4, "\"\\0", "a NUL byte (\\0) in a string");
	char dir[256], path[512];
	tu_tmpdir(dir, sizeof dir);
	tu_write(path, sizeof path, dir, "c.yaml", "name: \"x\\0y\"\n");
	char args[700];
	snprintf(args, sizeof args, "--config %s --dry-run", path);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 2);
	tu_one_line(dir, "saarsim", "c.yaml:1:7: a NUL byte");
}

/* Mistake: a scene that a view names and that does not load reported
 * without the views file (`x.obj: cannot open scene file: ...`), so the
 * user is not shown which view's line names it. The message names the
 * views file at the `scene:` value's line and column, then the scene and
 * its own reason, for a missing file and an unknown procedural scene. */
Test(view, scene_that_does_not_load_is_named_at_its_view)
{
	char path[512];
	write_views(path, sizeof path, "    scene: nonexist.obj\n" CAM);
	char dir[512];
	snprintf(dir, sizeof dir, "%.*s", (int)(strrchr(path, '/') - path), path);
	char args[1200], want[1200];
	snprintf(args, sizeof args, "--views %s --view a --size 8x8", path);
	cr_assert_eq(tu_prog(dir, "rtref", args), 2);
	snprintf(want, sizeof want,
	         "%s:4:12: scene %s/nonexist.obj: cannot open scene file: No such file", path, dir);
	tu_one_line(dir, "rtref", want);
	write_views(path, sizeof path, "    scene: spd:nope\n" CAM);
	snprintf(dir, sizeof dir, "%.*s", (int)(strrchr(path, '/') - path), path);
	snprintf(args, sizeof args, "--views %s --view a --size 8x8 --no-check", path);
	cr_assert_eq(tu_prog(dir, "saarsim", args), 2);
	snprintf(want, sizeof want, "%s:4:12: scene spd:nope: unknown procedural scene", path);
	tu_one_line(dir, "saarsim", want);
}

/* Mistake: a view named "" loaded, though --view cannot name it, and the
 * unknown-name message then said "available views: (none)" for a file
 * that has views (the list's separator was decided by its length, and an
 * empty first name added nothing). An empty name is refused at its key;
 * the list names every view. */
Test(view, empty_view_name_is_refused)
{
	char dir[256], path[512];
	tu_tmpdir(dir, sizeof dir);
	tu_write(path, sizeof path, dir, "v.yaml", "views:\n  x:\n" CAM "  \"\":\n" CAM);
	view v;
	diag d = {{0}};
	cr_assert_eq(view_load(&v, path, "a", &d), -1);
	char want[700];
	snprintf(want, sizeof want, "%s:4:3: empty view name", path);
	cr_assert_str_eq(d.msg, want);
	char names[4][VIEW_NAME_MAX];
	cr_assert_eq(view_list(path, names, 4, &d), -1);
	cr_assert_str_eq(d.msg, want);
}
