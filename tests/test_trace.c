/*
 * test_trace.c: intersection and traversal: watertightness, edge and
 * vertex hits, packet path == single-ray path, thread-count determinism.
 * What the pixels should be is tests/test_oracles.c's business.
 */
#include <math.h>
#include <string.h>

#include "kernel-ref/camera.h"
#include "kernel-ref/framebuf.h"
#include "kernel-ref/image.h"
#include "kernel-ref/isect.h"
#include "kernel-ref/render.h"
#include "kernel-ref/world.h"
#include "tests/testutil.h"

/* A closed UV sphere whose triangles share exact vertex values. */
static void make_sphere(scene *s, vec3 c, float r, int nu, int nv)
{
	scene_init(s, "test:sphere");
	material m = material_default("s");
	scene_add_material(s, &m);
	for (int j = 0; j < nv; j++)
		for (int i = 0; i < nu; i++) {
			vec3 p[4];
			for (int k = 0; k < 4; k++) {
				int ii = (i + (k == 1 || k == 2)) % nu, jj = j + (k >= 2);
				float th = (float)M_PI * (float)jj / (float)nv;
				float ph = 2.0f * (float)M_PI * (float)ii / (float)nu;
				/* the poles are one exact point */
				float st = (jj == 0 || jj == nv) ? 0.0f : sinf(th);
				float ct = jj == 0 ? 1.0f : jj == nv ? -1.0f : cosf(th);
				p[k] = v3(c.x + r * st * cosf(ph), c.y + r * ct,
				          c.z + r * st * sinf(ph));
			}
			vec3 a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[2], p[3]};
			if (j != 0)
				scene_add_triangle(s, a, NULL, NULL, 0);
			if (j != nv - 1)
				scene_add_triangle(s, b, NULL, NULL, 0);
		}
	diag d;
	cr_assert_eq(scene_finish(s, "sphere", &d), 0);
}

static void build(world *w, scene *s)
{
	tu_build_world(w, s);
}

/* Traces a 512x512 frame of primary rays from eye towards c; for every hit,
 * continues the ray beyond the hit: seen from outside it must hit the far
 * side; from inside every ray must hit. Returns the number of leaks. */
static uint64_t count_leaks(const world *w, vec3 eye, vec3 c, int inside)
{
	camera cam = {eye, c, v3(0, 1, 0.1f), inside ? 120.0f : 40.0f};
	cam_frame cf;
	cam_setup(&cf, &cam, 512, 512);
	static trav_entry stack[PKT_STACK_MAX];
	static packet p, q;
	uint64_t leaks = 0, hits = 0;
	for (int ty = 0; ty < 64; ty++)
		for (int tx = 0; tx < 64; tx++) {
			cam_primary_packet(&cf, tx, ty, &p);
			pkt_trace(&p, &w->m, stack, PKT_STACK_MAX, NULL);
			if (inside) {
				for (uint64_t b = p.valid; b; b &= b - 1)
					leaks += p.tri[__builtin_ctzll(b)] == PKT_NOHIT;
				continue;
			}
			/* continue each hit ray from just inside the surface */
			q = p;
			q.valid = 0;
			for (uint64_t b = p.valid; b; b &= b - 1) {
				int i = __builtin_ctzll(b);
				if (p.tri[i] == PKT_NOHIT)
					continue;
				hits++;
				float t = nextafterf(p.t[i], INFINITY);
				q.ox[i] = p.ox[i] + t * p.dx[i];
				q.oy[i] = p.oy[i] + t * p.dy[i];
				q.oz[i] = p.oz[i] + t * p.dz[i];
				q.tmax[i] = INFINITY;
				q.valid |= 1ull << i;
			}
			pkt_trace(&q, &w->m, stack, PKT_STACK_MAX, NULL);
			for (uint64_t b = q.valid; b; b &= b - 1)
				leaks += q.tri[__builtin_ctzll(b)] == PKT_NOHIT;
		}
	if (!inside)
		cr_assert_gt(hits, 50000, "the sphere should fill much of the frame (%llu hits)",
		             (unsigned long long)hits);
	return leaks;
}

Test(trace, watertight_sphere_inside_and_outside)
{
	scene s;
	make_sphere(&s, v3(0.3f, -0.2f, 0.1f), 1.0f, 48, 24);
	world w;
	build(&w, &s);
	cr_assert_eq(count_leaks(&w, v3(0.31f, -0.18f, 0.12f), v3(0.3f, -0.2f, 2.0f), 1), 0);
	cr_assert_eq(count_leaks(&w, v3(0.3f, 0.0f, 0.1f), v3(-2.0f, -0.4f, 0.5f), 1), 0);
	cr_assert_eq(count_leaks(&w, v3(0.3f, 0.1f, 4.0f), v3(0.3f, -0.2f, 0.1f), 0), 0);
	cr_assert_eq(count_leaks(&w, v3(-3.1f, 2.2f, -1.7f), v3(0.3f, -0.2f, 0.1f), 0), 0);
	world_free(&w);
}

Test(trace, edge_and_vertex_hits)
{
	/* two triangles sharing the edge x = 0 in the plane z = 0 */
	float t1[3][3] = {{0, -1, 0}, {0, 1, 0}, {-1, 0, 0}};
	float t2[3][3] = {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}};
	vec3 d = v3(0, 0, -1);
	isect_ray r = isect_prepare(d);
	float t, bu, bv;
	/* a ray exactly through the shared edge hits at least one triangle */
	for (float y = -0.75f; y <= 0.75f; y += 0.25f) {
		int h = isect_tri(&r, v3(0, y, 1), t1, &t, &bu, &bv) |
		        isect_tri(&r, v3(0, y, 1), t2, &t, &bu, &bv);
		cr_assert(h, "edge ray at y=%g leaked", y);
		cr_assert_float_eq(t, 1.0f, 0.0f);
	}
	/* through a vertex shared by a fan of 6 triangles */
	int hits = 0;
	for (int k = 0; k < 6; k++) {
		float a0 = (float)k * (float)M_PI / 3.0f, a1 = (float)(k + 1) * (float)M_PI / 3.0f;
		float tv[3][3] = {{0, 0, 0}, {cosf(a0), sinf(a0), 0}, {cosf(a1), sinf(a1), 0}};
		hits += isect_tri(&r, v3(0, 0, 5), tv, &t, &bu, &bv);
	}
	cr_assert_geq(hits, 1, "a ray through a shared vertex must hit the fan");
	/* just outside a triangle misses; degenerate triangles never hit */
	cr_assert_not(isect_tri(&r, v3(-1.0001f, 0, 1), t1, &t, &bu, &bv));
	float deg[3][3] = {{0, 0, 0}, {1, 1, 0}, {2, 2, 0}};
	cr_assert_not(isect_tri(&r, v3(1, 1, 1), deg, &t, &bu, &bv));
	/* axis-parallel rays with -0 components */
	isect_ray rz = isect_prepare(v3(-0.0f, 0.0f, -1.0f));
	cr_assert(isect_tri(&rz, v3(-0.25f, 0.1f, 3), t1, &t, &bu, &bv));
	cr_assert_float_eq(t, 3.0f, 0.0f);
}

/* Every primary ray of a view: packet hit == single-ray hit, bit for bit. */
static void compare_paths(const world *w, int size)
{
	cam_frame cf;
	cam_setup(&cf, &w->v.cam, size, size);
	static trav_entry stack[PKT_STACK_MAX];
	static packet p;
	uint64_t hits = 0;
	for (int ty = 0; ty < size / 8; ty++)
		for (int tx = 0; tx < size / 8; tx++) {
			cam_primary_packet(&cf, tx, ty, &p);
			pkt_trace(&p, &w->m, stack, PKT_STACK_MAX, NULL);
			for (uint64_t b = p.valid; b; b &= b - 1) {
				int i = __builtin_ctzll(b);
				ray_hit h =
				    ray_trace(&w->m, v3(p.ox[i], p.oy[i], p.oz[i]),
				              v3(p.dx[i], p.dy[i], p.dz[i]), INFINITY, 0, NULL);
				cr_assert_eq(h.tri, p.tri[i],
				             "%s: tile %d,%d ray %d: single-ray hit %u, packet %u",
				             w->scene_label, tx, ty, i, h.tri, p.tri[i]);
				if (h.tri != PKT_NOHIT) {
					hits++;
					cr_assert(h.t == p.t[i] && h.bu == p.bu[i] &&
					          h.bv == p.bv[i]);
				}
			}
		}
	cr_assert_gt(hits, 0, "%s: no ray hit anything", w->scene_label);
}

Test(trace, packet_equals_single_ray_embedded)
{
	world_opts o;
	world_opts_default(&o);
	world w;
	diag d;
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	compare_paths(&w, 256);
	world_free(&w);
}

Test(trace, packet_equals_single_ray_on_shared_views, .timeout = 600)
{
	char views[1024];
	SCENE_OR_SKIP(views, "views.yaml");
	char names[32][VIEW_NAME_MAX];
	diag d;
	int n = view_list(views, names, 32, &d);
	cr_assert_gt(n, 0, "%s", d.msg);
	for (int k = 0; k < n; k++) {
		world_opts o;
		world_opts_default(&o);
		o.views = views;
		o.view = names[k];
		world w;
		cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
		compare_paths(&w, 256);
		world_free(&w);
	}
}

static void render_embedded(framebuf *fb, int threads, int size, render_stats *st)
{
	world_opts o;
	world_opts_default(&o);
	world w;
	diag d;
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = size;
	ro.threads = threads;
	cr_assert_eq(fb_init(fb, size, size), 0);
	cr_assert_eq(render_frame(&w.m, &w.v, &ro, fb, st, &d), 0, "%s", d.msg);
	world_free(&w);
}

Test(trace, image_identical_for_any_thread_count)
{
	framebuf a, b, c;
	render_stats sa, sb, sc;
	render_embedded(&a, 1, 200, &sa);
	render_embedded(&b, 2, 200, &sb);
	render_embedded(&c, 7, 200, &sc);
	size_t n = 200 * 200 * 3 * sizeof(uint64_t);
	cr_assert(memcmp(a.acc, b.acc, n) == 0, "1 vs 2 threads differ");
	cr_assert(memcmp(a.acc, c.acc, n) == 0, "1 vs 7 threads differ");
	cr_assert_eq(sa.rays[PKT_SHADOW], sc.rays[PKT_SHADOW]);
	cr_assert_gt(sa.rays[PKT_REFLECT], 0, "the mirror sphere spawns reflection rays");
	cr_assert_gt(sa.rays[PKT_REFRACT], 0, "the glass sphere spawns refraction rays");
	fb_free(&a);
	fb_free(&b);
	fb_free(&c);
}

Test(trace, skips_are_counted)
{
	world_opts o;
	world_opts_default(&o);
	o.no_lights = 1;
	world w;
	diag d;
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = 64;
	framebuf fb;
	fb_init(&fb, 64, 64);
	render_stats st;
	cr_assert_eq(render_frame(&w.m, &w.v, &ro, &fb, &st, &d), 0);
	cr_assert_eq(st.rays[PKT_SHADOW], 0, "no lights: no shadow rays");
	cr_assert_gt(st.shade.shadow_skip_nolight, 0);
	cr_assert_gt(st.shade.untextured_hits, 0);
	cr_assert_eq(st.shade.texel_reads, 0, "no textures: no texel reads");
	/* a camera looking away from the scene: every packet skips traversal */
	vec3 back = v3_sub(w.v.cam.eye, w.v.cam.lookat);
	w.v.cam.eye = v3_add(w.v.cam.eye, v3_scale(back, 100.0f));
	w.v.cam.lookat = v3_add(w.v.cam.eye, back);
	fb_clear(&fb);
	cr_assert_eq(render_frame(&w.m, &w.v, &ro, &fb, &st, &d), 0);
	cr_assert_eq(st.box_miss_packets, st.packets[PKT_PRIMARY]);
	cr_assert_eq(st.trav.node_steps, 0);
	fb_free(&fb);
	world_free(&w);
}

/* Loads the OBJ scene obj seen from cam, lit by one white light at
 * (0.3, 0.2, 2) (the scenes of the texture and shading tests). */
static void load_lit(world *w, const char *obj, camera cam)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = obj;
	o.have_eye = o.have_lookat = o.have_up = o.have_fov = 1;
	o.cam = cam;
	o.nlights = 1;
	o.lights[0] = (light){v3(0.3f, 0.2f, 2.0f), v3(1, 1, 1)};
	diag d;
	cr_assert_eq(world_load(w, &o, &d), 0, "%s", d.msg);
}

/* A quad with a red/blue checker map_Kd and a bump map, seen head-on:
 * texels are read (and counted), the colours follow the texture, and the
 * bump map changes the shading. */
static void render_quad(const char *dir, const char *mtl_extra, framebuf *fb, render_stats *st)
{
	char obj[512], mtl[512], text[1024];
	snprintf(text, sizeof text,
	         "newmtl tex\nKd 1 1 1\nKa 1 1 1\nKs 0 0 0\nNs 1\nmap_Kd checker.png\n%s\n",
	         mtl_extra);
	tu_write(mtl, sizeof mtl, dir, "quad.mtl", text);
	tu_write(obj, sizeof obj, dir, "quad.obj",
	         "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
	         "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tex\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
	world w;
	load_lit(&w, obj, (camera){v3(0, 0, 3), v3(0, 0, 0), v3(0, 1, 0), 30.0f});
	diag d;
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = 64;
	cr_assert_eq(fb_init(fb, 64, 64), 0);
	cr_assert_eq(render_frame(&w.m, &w.v, &ro, fb, st, &d), 0, "%s", d.msg);
	world_free(&w);
}

Test(trace, textures_and_bump_maps_are_shaded)
{
	char dir[256];
	tu_tmpdir(dir, sizeof dir);
	/* 2x2 checker: red top-left and bottom-right, blue elsewhere */
	uint8_t px[2 * 2 * 3] = {255, 0, 0, 0, 0, 255, 0, 0, 255, 255, 0, 0};
	char path[512];
	diag d;
	snprintf(path, sizeof path, "%s/checker.png", dir);
	cr_assert_eq(img_write(path, 2, 2, px, NULL, NULL, &d), 0, "%s", d.msg);
	uint8_t bump[4 * 4 * 3];
	for (int i = 0; i < 16; i++)
		memset(bump + 3 * i, (i * 53) % 256, 3); /* a rough height field */
	snprintf(path, sizeof path, "%s/bump.png", dir);
	cr_assert_eq(img_write(path, 4, 4, bump, NULL, NULL, &d), 0, "%s", d.msg);

	framebuf plain, bumped;
	render_stats sp, sb;
	render_quad(dir, "", &plain, &sp);
	render_quad(dir, "bump bump.png", &bumped, &sb);
	cr_assert_gt(sp.shade.texel_reads, 0);
	cr_assert_eq(sp.shade.untextured_hits, 0);
	cr_assert_gt(sb.shade.texel_reads, sp.shade.texel_reads, "bump mapping reads more texels");
	uint8_t a[64 * 64 * 3], b[64 * 64 * 3];
	fb_to_rgb8(&plain, a, NULL);
	fb_to_rgb8(&bumped, b, NULL);
	/* pixel (16,16) is in the top-left quarter of the quad (red texel),
	 * (48,16) in the top-right (blue texel) */
	const uint8_t *tl = a + 3 * (16 * 64 + 16), *tr = a + 3 * (16 * 64 + 48);
	cr_assert(tl[0] > 2 * tl[2] + 10, "top-left should be red: %d %d %d", tl[0], tl[1], tl[2]);
	cr_assert(tr[2] > 2 * tr[0] + 10, "top-right should be blue: %d %d %d", tr[0], tr[1],
	          tr[2]);
	cr_assert(memcmp(a, b, sizeof a) != 0, "the bump map must change the shading");
	fb_free(&plain);
	fb_free(&bumped);
}

/* Five quads side by side, each with its own material: plain, a map_Kd
 * checker, a bump map, a mirror (illum 3) and glass (d 0.5); the
 * background shows around them. */
static void lean_scene(const char *dir, world *w)
{
	uint8_t px[2 * 2 * 3] = {255, 0, 0, 0, 0, 255, 0, 0, 255, 255, 0, 0};
	uint8_t bump[4 * 4 * 3];
	for (int i = 0; i < 16; i++)
		memset(bump + 3 * i, (i * 53) % 256, 3);
	char path[512], obj[512], mtl[512], text[2048];
	diag d;
	snprintf(path, sizeof path, "%s/checker.png", dir);
	cr_assert_eq(img_write(path, 2, 2, px, NULL, NULL, &d), 0, "%s", d.msg);
	snprintf(path, sizeof path, "%s/bump.png", dir);
	cr_assert_eq(img_write(path, 4, 4, bump, NULL, NULL, &d), 0, "%s", d.msg);
	tu_write(mtl, sizeof mtl, dir, "five.mtl",
	         "newmtl plain\nKd 0.8 0.6 0.4\nKa 0.7 0.5 0.3\nKs 0 0 0\n"
	         "newmtl tex\nKd 1 1 1\nKa 0.9 0.8 0.7\nKs 0 0 0\nmap_Kd checker.png\n"
	         "newmtl bumpy\nKd 1 1 1\nKa 1 1 1\nKs 0 0 0\nbump bump.png\n"
	         "newmtl mirror\nKd 0.2 0.2 0.2\nKa 0.3 0.3 0.3\nKs 0.5 0.5 0.5\nillum 3\n"
	         "newmtl glass\nKd 0.1 0.2 0.3\nKa 0.4 0.4 0.4\nKs 0 0 0\nd 0.5\n");
	int n = snprintf(text, sizeof text, "mtllib five.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
	static const char *const mats[5] = {"plain", "tex", "bumpy", "mirror", "glass"};
	for (int q = 0; q < 5; q++) {
		float x0 = -5.0f + 2.0f * (float)q, x1 = x0 + 1.8f;
		n += snprintf(text + n, sizeof text - (size_t)n,
		              "v %g -1 0\nv %g -1 0\nv %g 1 0\nv %g 1 0\nusemtl %s\n"
		              "f %d/1 %d/2 %d/3\nf %d/1 %d/3 %d/4\n",
		              x0, x1, x1, x0, mats[q], 4 * q + 1, 4 * q + 2, 4 * q + 3, 4 * q + 1,
		              4 * q + 3, 4 * q + 4);
	}
	tu_write(obj, sizeof obj, dir, "five.obj", text);
	load_lit(w, obj, (camera){v3(0.2f, 0.3f, 6), v3(0, 0, 0), v3(0, 1, 0), 90.0f});
}

/* kernel-ref's shading without a read log (shade_packet_fp: lanes that
 * spawn no ray take shade.c's lean lane) against the shader with one
 * (shade_packet: every lane the general way): the same frame-buffer words,
 * child packets and counts, with no lights and depth 0 (where lean lanes
 * run: plain and textured hits, mirror and glass cut by the depth, misses,
 * the bump map left to the general lane), depth 1 (mirror and glass spawn
 * rays: general) and a light (shadow rays: general). Written to catch
 * SHADE_FAULT_LEAN_NO_TEXTURE (the lean lane without the map_Kd texel)
 * SHADE_FAULT_LEAN_NO_CLAMP (the packet's fixed-point conversion
 * without fb_fixed's clamp), SHADE_FAULT_LEAN_MEMO_TEXTURED (a textured
 * hit's result reused for the next lane on the triangle) and
 * SHADE_FAULT_LEAN_ONE_WEIGHT (the per-slot sums of one weight taken for
 * lanes whose weights differ: vary gives the packet's lanes different
 * weights, as a secondary packet's), planted below, each with one weight
 * for all lanes (a primary packet's: shade.c's per-slot sums) and varied
 * (its per-lane sums). */
static uint64_t lean_mismatches(const world *w, int depth, int nlights, vec3 background, int vary)
{
	static trav_entry stack[PKT_STACK_MAX];
	static packet p, ka[8], kb[8];
	framebuf fa, fb;
	cr_assert_eq(fb_init(&fa, 64, 64), 0);
	cr_assert_eq(fb_init(&fb, 64, 64), 0);
	shade_ctx sa = {.m = &w->m,
	                .lights = w->v.lights,
	                .nlights = nlights,
	                .max_depth = depth,
	                .background = background,
	                .fb = &fa};
	shade_ctx sb = sa;
	sb.fb = &fb;
	cam_frame cf;
	cam_setup(&cf, &w->v.cam, 64, 64);
	shade_read log_e[SHADE_LOG_CAP];
	shade_counts ca = {0}, cb = {0};
	uint64_t bad = 0;
	for (int t = 0; t < 64; t++) {
		cam_primary_packet(&cf, t % 8, t / 8, &p);
		pkt_trace(&p, &w->m, stack, PKT_STACK_MAX, NULL);
		for (int l = 0; vary && l < PKT_RAYS; l++) { /* as a secondary packet's */
			p.wr[l] *= 1.0f + 0.25f * (float)(l % 5);
			p.wb[l] *= 1.0f - 0.125f * (float)(l % 3);
		}
		shade_log log = {log_e, 0, SHADE_LOG_CAP, 0};
		int na = shade_packet(&sa, &p, ka, nlights + 2, &log, &ca);
		int nb = shade_packet_fp(&sb, NULL, &p, kb, nlights + 2, NULL, &cb);
		bad += na != nb;
		for (int k = 0; k < na && k < nb; k++)
			bad += memcmp(&ka[k], &kb[k], sizeof ka[k]) != 0;
	}
	bad += memcmp(&ca, &cb, sizeof ca) != 0;
	bad += memcmp(fa.acc, fb.acc, 64 * 64 * 3 * sizeof *fa.acc) != 0;
	fb_free(&fa);
	fb_free(&fb);
	return bad;
}

Test(trace, lean_shading_equals_the_general_shader)
{
	char dir[256];
	tu_tmpdir(dir, sizeof dir);
	world w;
	lean_scene(dir, &w);
	/* a background beyond the frame buffer's clamp on red and below zero
	 * on green: the misses' adds clamp and drop as fb_fixed does */
	const vec3 bgs[2] = {v3(0.1f, 0.2f, 0.3f), v3(5000.0f, -1.0f, 0.3f)};
	for (int vary = 0; vary < 2; vary++)
		for (int k = 0; k < 2; k++)
			for (int depth = 0; depth < 2; depth++)
				for (int nl = 0; nl < 2; nl++)
					cr_assert_eq(
					    lean_mismatches(&w, depth, nl, bgs[k], vary), 0,
					    "background %d, depth %d, %d lights, weights %s", k,
					    depth, nl, vary ? "varied" : "one");
	static const int faults[] = {SHADE_FAULT_LEAN_NO_TEXTURE, SHADE_FAULT_LEAN_NO_CLAMP,
	                             SHADE_FAULT_LEAN_MEMO_TEXTURED, SHADE_FAULT_LEAN_ONE_WEIGHT};
	for (int f = 0; f < 4; f++)
		for (int vary = 0; vary < 2; vary++) {
			shade_fault = faults[f];
			uint64_t planted = lean_mismatches(&w, 0, 0, bgs[1], vary);
			shade_fault = SHADE_FAULT_NONE;
			/* one weight for every lane leaves nothing to mistake */
			if (faults[f] != SHADE_FAULT_LEAN_ONE_WEIGHT || vary)
				cr_assert_gt(planted, 0,
				             "planted mistake %d went unnoticed (weights %s)",
				             faults[f], vary ? "varied" : "one");
		}
	world_free(&w);
}

/* A full tile's pinhole rays (camera.c's pinhole_packet, SIMD_W lanes at
 * a time) against the pixel-centre arithmetic written out per ray in one
 * order: the same floats, bit for bit, for cameras looking along every
 * axis sign. Written to catch the vector code summing or scaling in
 * another order than the per-ray path (sample_ray) rounds, e.g.
 * dx * dx + (dy * dy + dz * dz), or d / len for d * (1 / len), and (with
 * 16 lanes, where a lane group's y comes from two of the tile's eight
 * rows) a group given the wrong rows (seen to fail with the first two
 * swapped). */
Test(trace, pinhole_packet_is_the_per_ray_arithmetic)
{
	static packet p;
	static const float eyes[4][3] = {{0, 0, 5}, {3, -2, 1}, {-1, 7, -4}, {0.1f, 0.2f, 0.3f}};
	for (int e = 0; e < 4; e++) {
		camera cam = {v3(eyes[e][0], eyes[e][1], eyes[e][2]), v3(0.3f, -0.1f, 0.2f),
		              v3(0, 1, 0), 20.0f + 25.0f * (float)e};
		cam_frame c;
		cam_setup(&c, &cam, 24 + 8 * e, 16);
		for (int t = 0; t < (c.width / 8) * 2; t++) {
			int tx = t % (c.width / 8), ty = t / (c.width / 8);
			cr_assert_eq(cam_primary_packet(&c, tx, ty, &p), PKT_RAYS);
			for (int l = 0; l < PKT_RAYS; l++) {
				float x = (float)(tx * 8 + l % 8), y = (float)(ty * 8 + l / 8);
				float px = (2.0f * (x + 0.5f) / (float)c.width - 1.0f) * c.sx;
				float py = (1.0f - 2.0f * (y + 0.5f) / (float)c.height) * c.sy;
				float d[3] = {c.w.x + (c.u.x * px + c.v.x * py),
				              c.w.y + (c.u.y * px + c.v.y * py),
				              c.w.z + (c.u.z * px + c.v.z * py)};
				float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
				float inv = 1.0f / len;
				float got[3] = {p.dx[l], p.dy[l], p.dz[l]};
				for (int k = 0; k < 3; k++) {
					float want = len > 0.0f ? d[k] * inv : d[k];
					cr_assert(memcmp(&want, &got[k], 4) == 0,
					          "camera %d tile %d lane %d axis %d: %a, want %a",
					          e, t, l, k, got[k], want);
				}
			}
		}
	}
}
