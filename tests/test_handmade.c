/*
 * test_handmade.c: scenes and kd-trees built by hand (tests/handmade.h),
 * each made so that one named mistake of the shared traversal, triangle
 * test or shader changes a hit, a count or a pixel for certain: no
 * statistics, no SAH build deciding where the triangles land. Each test
 * names the mistake it catches; tests/mutants/ holds those mistakes as
 * patches, and `make mutate` checks that these tests fail on them.
 */
#include <math.h>
#include <string.h>

#include "kernel-ref/isect.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/render.h"
#include "tests/chiptest.h"
#include "tests/handmade.h"

/* Closest hit of one ray over every triangle of m, no tree: the scalar
 * triangle test and the hit rule (smallest t, then smaller address). */
static ray_hit brute_force(const mimg *m, vec3 o, vec3 d)
{
	ray_hit h = {INFINITY, 0, 0, PKT_NOHIT, 0};
	isect_ray ir = isect_prepare(d);
	for (uint32_t k = 0; k < m->ntris; k++) {
		uint32_t ta = (uint32_t)mimg_tri_addr(m, k);
		float t, bu, bv;
		if (isect_tri(&ir, o, mimg_tri_at(m, ta)->v, &t, &bu, &bv) &&
		    isect_better(t, ta, h.t, h.tri)) {
			h.t = t;
			h.tri = ta;
		}
	}
	return h;
}

static void set_ray(packet *p, int lane, vec3 o, vec3 d)
{
	p->ox[lane] = o.x;
	p->oy[lane] = o.y;
	p->oz[lane] = o.z;
	p->dx[lane] = d.x;
	p->dy[lane] = d.y;
	p->dz[lane] = d.z;
	p->tmax[lane] = INFINITY;
	p->wr[lane] = p->wg[lane] = p->wb[lane] = 1.0f;
	p->valid |= 1ull << lane;
}

/* ---- the far child ---- */

/* Mistake: the packet traversal never pushes the far child (it follows the
 * near one only), so rays that need only the far side of a split lose
 * their hits. Two quads either side of the split x = 0.25 (left quad in the
 * below leaf, right quad in the above leaf); one packet's rays cover both
 * sides, so whichever child is near, the other one holds rays: every ray
 * must get the hit a brute-force test of all four triangles gives, in both
 * directions across the split. */
Test(traverse, far_child_is_pushed_and_visited)
{
	world w;
	hm_begin(&w);
	/* triangles 0, 1: x in [-4, 0.1] at z = 0; 2, 3: x in [0.4, 4] at z = -0.5 */
	hm_quad(&w, v3(-4, -4, 0), v3(0.1f, -4, 0), v3(0.1f, 4, 0), v3(-4, 4, 0));
	hm_quad(&w, v3(0.4f, -4, -0.5f), v3(4, -4, -0.5f), v3(4, 4, -0.5f), v3(0.4f, 4, -0.5f));
	const kd_node nodes[] = {kd_make_inner(0, 0.25f, 1), kd_make_leaf(0, 2),
	                         kd_make_leaf(2, 2)};
	const uint32_t list[] = {0, 1, 2, 3};
	camera cam = {v3(0, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 40};
	hm_finish(&w, nodes, 3, list, 4, cam, NULL, 0);
	packet *p = hm_alloc(sizeof *p);
	trav_entry *stack = hm_alloc(PKT_STACK_MAX * sizeof *stack);
	for (int dir = 0; dir < 2; dir++) {
		/* dir 0: d.x > 0, the near child is below the split (left);
		 * dir 1: d.x < 0, the near child is above it (right) */
		vec3 d = v3_norm(v3(dir ? -0.01f : 0.01f, 0.02f, -1.0f));
		pkt_clear(p, PKT_PRIMARY, 0);
		p->n = PKT_RAYS;
		for (int i = 0; i < PKT_RAYS; i++) {
			/* lane 0 (the one that picks the near side) at the near end */
			int k = dir ? PKT_RAYS - 1 - i : i;
			set_ray(p, i, v3(-2.0f + 4.0f * ((float)k + 0.5f) / PKT_RAYS, 0.3f, 5), d);
		}
		pkt_trace(p, &w.m, stack, PKT_STACK_MAX, NULL);
		int left = 0, right = 0;
		for (int i = 0; i < PKT_RAYS; i++) {
			ray_hit h = brute_force(&w.m, v3(p->ox[i], p->oy[i], p->oz[i]), d);
			cr_assert_eq(p->tri[i], h.tri,
			             "direction %d, ray %d (x %.3f): hit %u, brute force %u", dir,
			             i, (double)p->ox[i], p->tri[i], h.tri);
			left += h.tri != PKT_NOHIT && mimg_tri_index(&w.m, h.tri) < 2;
			right += h.tri != PKT_NOHIT && mimg_tri_index(&w.m, h.tri) >= 2;
		}
		/* the packet needs both children */
		cr_assert(left > 8 && right > 8, "left %d right %d", left, right);
	}
	free(p);
	free(stack);
	world_free(&w);
}

/* ---- the order of the children ---- */

/* Two full quads facing the camera at z = +1 (triangles 0, 1) and z = -1
 * (2, 3), split at z = 0: the root (node 0), the below leaf (node 1: the
 * far quad) and the above leaf (node 2: the near quad). The camera at
 * z = 5 looks down -z, so every ray hits the near quad at t ~ 4 and the far
 * leaf starts at t ~ 5, beyond every hit: front to back, each packet takes
 * exactly two steps (root, near leaf) and tests two triangles. */
static void near_far_world(world *w)
{
	hm_begin(w);
	hm_quad(w, v3(-4, -4, 1), v3(4, -4, 1), v3(4, 4, 1), v3(-4, 4, 1));
	hm_quad(w, v3(-4, -4, -1), v3(4, -4, -1), v3(4, 4, -1), v3(-4, 4, -1));
	const kd_node nodes[] = {kd_make_inner(2, 0.0f, 1), kd_make_leaf(0, 2), kd_make_leaf(2, 2)};
	const uint32_t list[] = {2, 3, 0, 1};
	camera cam = {v3(0, 0, 5), v3(0, 0, 0), v3(0, 1, 0), 40};
	hm_finish(w, nodes, 3, list, 4, cam, NULL, 0);
}

enum { NF_SIZE = 32, NF_PACKETS = (NF_SIZE / 8) * (NF_SIZE / 8) };

/* Mistake: the far child is visited first. The traversal then reads the
 * far leaf and tests its triangles before the near leaf, which a ray must
 * still visit (its entry is before the far hit): three steps and four
 * triangle tests instead of two and two. kernel-ref's packet traversal,
 * step by step: node 0, then leaf 2, then done, for every packet. */
Test(traverse, near_child_first_stops_at_the_first_hit)
{
	world w;
	near_far_world(&w);
	cam_frame cf;
	cam_setup(&cf, &w.v.cam, NF_SIZE, NF_SIZE);
	packet *p = hm_alloc(sizeof *p);
	trav_entry *stack = hm_alloc(PKT_STACK_MAX * sizeof *stack);
	trav_state *s = hm_alloc(sizeof *s);
	const uint32_t *lists = mimg_lists(&w.m);
	for (int ty = 0; ty < NF_SIZE / 8; ty++)
		for (int tx = 0; tx < NF_SIZE / 8; tx++) {
			cam_primary_packet(&cf, tx, ty, p);
			cr_assert_eq(pkt_trav_begin(s, p, &w.m, stack, PKT_STACK_MAX), p->valid);
			uint32_t seen[8];
			int n = 0;
			trav_result r;
			for (pkt_trav_next(s, p, &w.m, &r); r.op != TRAV_DONE && n < 8;
			     pkt_trav_next(s, p, &w.m, &r)) {
				seen[n++] = r.node;
				if (r.op == TRAV_LEAF)
					for (uint32_t k = 0; k < r.leaf_count; k++)
						pkt_isect_tri(s, p, &w.m, r.mask,
						              lists[r.leaf_first + k]);
			}
			cr_assert_eq(n, 2, "tile %d,%d: %d steps, not root and near leaf", tx, ty,
			             n);
			cr_assert_eq(seen[0], 0);
			cr_assert_eq(seen[1], 2,
			             "tile %d,%d: leaf %u visited first, not the near 2", tx, ty,
			             seen[1]);
			for (uint64_t b = p->valid; b; b &= b - 1) {
				int i = __builtin_ctzll(b);
				cr_assert_lt(mimg_tri_index(&w.m, p->tri[i]), 2, "ray %d", i);
			}
			/* pkt_trace, the loop render.c uses, counts the same */
			trav_counts c = {0};
			cam_primary_packet(&cf, tx, ty, p);
			pkt_trace(p, &w.m, stack, PKT_STACK_MAX, &c);
			cr_assert_eq(c.node_steps, 2);
			cr_assert_eq(c.leaf_visits, 1);
			cr_assert_eq(c.tri_tests, 2);
		}
	free(p);
	free(stack);
	free(s);
	world_free(&w);
}

/* The same mistake seen on the chip: its traversal unit steps the same
 * state machine, so a frame of the near/far world takes two node steps,
 * one leaf and two triangle tests per packet (no lights, no secondary
 * rays), and renders kernel-ref's image. */
Test(chip_order, near_child_first_stops_at_the_first_hit)
{
	world w;
	near_far_world(&w);
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = NF_SIZE;
	chip *ch = tu_run_chip(&w, &c);
	cr_assert_eq(stats_get(&ch->st, "packets.primary"), NF_PACKETS);
	cr_assert_eq(stats_get(&ch->st, "trav.node_steps"), 2 * NF_PACKETS);
	cr_assert_eq(stats_get(&ch->st, "trav.leaf_visits"), NF_PACKETS);
	cr_assert_eq(stats_get(&ch->st, "isect.tri_tests"), 2 * NF_PACKETS);
	cr_assert_eq(stats_get(&ch->st, "mem.kd.reads"), 2 * NF_PACKETS);
	tu_assert_identical(ch, "near/far world");
	chip_destroy(ch);
	world_free(&w);
}

/* ---- hits behind the origin ---- */

/* Mistake: the triangle test accepts t > -eps instead of t > deltaT (a hit
 * at or just behind the ray's origin), the mistake that makes a secondary
 * ray hit the surface it leaves. The triangle (2,0,0) (0,2,0) (0,0,2) lies
 * in the plane x + y + z = 2; rays along z from (0.5, 0.5, z0): from
 * z0 = 1 the triangle is exactly at the origin (t = 0, computed exactly),
 * from 1 + 2^-22 it is 2^-22 behind (far below the error bound), from 1.5
 * half a unit behind, and rays along -z from 0.25 have it 0.75 behind; a
 * ray from 0.25 along +z hits it at 0.75. A second triangle well away
 * from every ray keeps the box larger than one triangle. Neither the
 * packet path nor the single-ray path may hit behind the origin. */
Test(isect, hit_behind_origin_is_refused)
{
	world w;
	hm_begin(&w);
	hm_tri(&w, v3(2, 0, 0), v3(0, 2, 0), v3(0, 0, 2));
	hm_tri(&w, v3(3, 3, 0), v3(3.5f, 3, 0), v3(3, 3.5f, 0));
	const kd_node nodes[] = {kd_make_leaf(0, 2)};
	const uint32_t list[] = {0, 1};
	camera cam = {v3(0.5f, 0.5f, 5), v3(0.5f, 0.5f, 0), v3(0, 1, 0), 40};
	hm_finish(&w, nodes, 1, list, 2, cam, NULL, 0);
	const float behind = 0x1p-22f;
	const struct {
		float z0, dz, t; /* t: the expected hit, 0 for none */
	} rays[] = {
	    {1.0f, 1, 0},          {1.0f, -1, 0}, /* on the plane, both ways: t = 0 */
	    {1.0f + behind, 1, 0}, {1.5f, 1, 0},  {0.25f, -1, 0}, {0.25f, 1, 0.75f}, /* in front */
	};
	const int n = (int)(sizeof rays / sizeof *rays);
	/* also some oblique rays from the plane x + y + z = 2 at points
	 * inside the triangle, leaving it on both sides */
	const vec3 on_plane[] = {v3(0.5f, 0.5f, 1), v3(0.25f, 0.75f, 1), v3(1, 0.5f, 0.5f)};
	const vec3 dirs[] = {v3(0.3f, 0.2f, 1), v3(-0.3f, -0.2f, -1), v3(1, 1, 1), v3(-1, -1, -1),
	                     v3(0.7f, -0.1f, 0.2f)};
	packet *p = hm_alloc(sizeof *p);
	trav_entry *stack = hm_alloc(PKT_STACK_MAX * sizeof *stack);
	pkt_clear(p, PKT_PRIMARY, 0);
	p->n = PKT_RAYS;
	int lanes = 0;
	for (int i = 0; i < n; i++)
		set_ray(p, lanes++, v3(0.5f, 0.5f, rays[i].z0), v3(0, 0, rays[i].dz));
	for (int a = 0; a < 3; a++)
		for (int b = 0; b < 5; b++)
			set_ray(p, lanes++, on_plane[a], v3_norm(dirs[b]));
	pkt_trace(p, &w.m, stack, PKT_STACK_MAX, NULL);
	for (int i = 0; i < lanes; i++) {
		vec3 o = v3(p->ox[i], p->oy[i], p->oz[i]), d = v3(p->dx[i], p->dy[i], p->dz[i]);
		float want = i < n ? rays[i].t : 0;
		ray_hit h = ray_trace(&w.m, o, d, INFINITY, 0, NULL);
		if (want > 0) {
			cr_assert_eq(p->tri[i], (uint32_t)mimg_tri_addr(&w.m, 0), "ray %d", i);
			cr_assert_float_eq(p->t[i], want, 1e-6f, "ray %d: t %g", i,
			                   (double)p->t[i]);
			cr_assert_eq(h.tri, p->tri[i], "ray %d, single-ray path", i);
		} else {
			cr_assert_eq(p->tri[i], PKT_NOHIT,
			             "ray %d from (%g, %g, %g) hit at t = %g, behind its origin", i,
			             (double)o.x, (double)o.y, (double)o.z, (double)p->t[i]);
			cr_assert_eq(h.tri, PKT_NOHIT, "ray %d, single-ray path: hit at t = %g", i,
			             (double)h.t);
		}
	}
	free(p);
	free(stack);
	world_free(&w);
}

/* ---- shadows ---- */

/* Mistake: shading ignores occlusion (a shadow ray's occluder is not
 * honoured, or no shadow ray is cast and the light is added anyway). A
 * floor (y = 0), a small blocker (y = 1, |x|, |z| <= 0.5) right under the
 * light at (0, 3, 0): the floor around the origin, |x|, |z| < 0.75, is in
 * the blocker's shadow, and the camera at (0, 4, 6) sees it past the
 * blocker's edge. The pixels there must be exactly the ambient term (the
 * frame rendered without shadow rays), a floor pixel at the left edge must
 * be lit; kernel-ref's frame and the chip's. */
Test(shadow, shadowed_pixel_gets_only_ambient)
{
	enum { S = 32 };
	world w;
	hm_begin(&w);
	hm_quad(&w, v3(-4, 0, -4), v3(-4, 0, 4), v3(4, 0, 4), v3(4, 0, -4));
	hm_quad(&w, v3(-0.5f, 1, -0.5f), v3(-0.5f, 1, 0.5f), v3(0.5f, 1, 0.5f), v3(0.5f, 1, -0.5f));
	const kd_node nodes[] = {kd_make_leaf(0, 4)};
	const uint32_t list[] = {0, 1, 2, 3};
	camera cam = {v3(0, 4, 6), v3(0, 0, 0), v3(0, 1, 0), 40};
	light l = {v3(0, 3, 0), v3(1, 1, 1)};
	hm_finish(&w, nodes, 1, list, 4, cam, &l, 1);
	uint8_t lit[S * S * 3], amb[S * S * 3], chipped[S * S * 3];
	for (int k = 0; k < 2; k++) {
		render_opts ro;
		render_opts_default(&ro);
		ro.width = ro.height = S;
		ro.shadows = !k; /* k = 1: no shadow rays, ambient only */
		framebuf fb;
		cr_assert_eq(fb_init(&fb, S, S), 0);
		render_stats st;
		diag d;
		cr_assert_eq(render_frame(&w.m, &w.v, &ro, &fb, &st, &d), 0, "%s", d.msg);
		fb_to_rgb8(&fb, k ? amb : lit, NULL);
		fb_free(&fb);
		if (!k)
			cr_assert_gt(st.shade.shadow_hits, 0, "no shadow ray was blocked");
	}
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = S;
	chip *ch = tu_run_chip(&w, &c);
	fb_to_rgb8(&ch->fb, chipped, NULL);
	chip_destroy(ch);
	/* the primary ray of each of these pixels hits the floor inside
	 * the shadow (checked by tracing it) */
	const int in_shadow[][2] = {{15, 15}, {16, 15}, {15, 16}, {16, 16}, {14, 16}, {17, 16}};
	for (size_t i = 0; i < sizeof in_shadow / sizeof *in_shadow; i++) {
		int x = in_shadow[i][0], y = in_shadow[i][1], o = (y * S + x) * 3;
		cam_frame cf;
		cam_setup(&cf, &w.v.cam, S, S);
		packet *p = hm_alloc(sizeof *p);
		trav_entry *stack = hm_alloc(PKT_STACK_MAX * sizeof *stack);
		cam_primary_packet(&cf, x / 8, y / 8, p);
		pkt_trace(p, &w.m, stack, PKT_STACK_MAX, NULL);
		int lane = (y % 8) * 8 + x % 8;
		vec3 hp = v3_add(v3(p->ox[lane], p->oy[lane], p->oz[lane]),
		                 v3_scale(v3(p->dx[lane], p->dy[lane], p->dz[lane]), p->t[lane]));
		cr_assert_lt(mimg_tri_index(&w.m, p->tri[lane]), 2, "pixel %d,%d: not the floor", x,
		             y);
		cr_assert(fabsf(hp.x) < 0.7f && fabsf(hp.z) < 0.7f, "pixel %d,%d sees (%g, %g)", x,
		          y, (double)hp.x, (double)hp.z);
		free(p);
		free(stack);
		for (int ch3 = 0; ch3 < 3; ch3++) {
			cr_assert_eq(
			    lit[o + ch3], amb[o + ch3],
			    "kernel-ref: pixel %d,%d in the shadow is lit (%d, ambient %d)", x, y,
			    lit[o + ch3], amb[o + ch3]);
			cr_assert_eq(chipped[o + ch3], amb[o + ch3],
			             "chip: pixel %d,%d in the shadow is lit (%d, ambient %d)", x,
			             y, chipped[o + ch3], amb[o + ch3]);
		}
	}
	/* the floor at the left edge is lit */
	int o = (16 * S + 1) * 3;
	cr_assert_gt(lit[o], amb[o] + 10, "kernel-ref: left floor %d, ambient %d", lit[o], amb[o]);
	cr_assert_gt(chipped[o], amb[o] + 10, "chip: left floor %d, ambient %d", chipped[o],
	             amb[o]);
	world_free(&w);
}
