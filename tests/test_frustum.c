/*
 * test_frustum.c: kernel-ref's packet shortcut (frustum.h, fru_trace)
 * against the per-lane traversal (pkt_trace_cone), hit for hit and count
 * for count, on generated packets: camera packets, packets from one point
 * with zero direction components and partial masks, mixed-direction
 * packets, and shadow packets from a light and from surfaces.
 *
 * The mistakes it is written to catch (planted with fru_fault, and seen
 * to fail): FRU_FAULT_ALWAYS_NEAR (the shortcut enters the near child
 * where every ray needs only the far one) and FRU_FAULT_ONE_DIRECTION
 * (the plane-distance interval from one ray's direction: the shortcut
 * skips children other rays need), and in the walk's own pops and
 * steps: FRU_FAULT_POP_ALL (a pop keeps rays whose best hit lies before
 * the entry: counted work differs) and FRU_FAULT_STALE_SEGMENTS (a pop
 * leaves the segment buffers unswapped: rays step with another node's
 * segments), and in its own leaf test: FRU_FAULT_BARY_SWAP (the late
 * barycentric division takes the wrong edge function).
 *
 * The leaf test's triangle-parallel way (fru_tri_path: each ray against
 * SIMD_W of a leaf's triangles at once) is checked the same way on a pile
 * of triangles that every split plane cuts (leaves of more than SIMD_W
 * triangles, shadow rays with many occluders), forced for every leaf and
 * left to the automatic choice; the mistakes it is written to catch:
 * FRU_FAULT_TRI_SHADOW_LAST (a shadow ray records its last occluder of a
 * chunk, not its first), FRU_FAULT_TRI_ONE_CHUNK (triangles past the
 * first SIMD_W of a leaf skipped), and, by a crafted ray whose float edge
 * function rounds to zero, the double-precision redo skipped
 * (tests/mutants/51-fru-tri-no-double-redo.patch).
 */
#include <math.h>
#include <string.h>

#include "kernel-ref/camera.h"
#include "kernel-ref/cone.h"
#include "kernel-ref/frustum.h"
#include "kernel-ref/simd.h"
#include "kernel-ref/world.h"
#include "tests/testutil.h"

static uint32_t rng_next(uint32_t *s)
{
	*s ^= *s << 13;
	*s ^= *s >> 17;
	*s ^= *s << 5;
	return *s;
}

static float rng_unit(uint32_t *s)
{
	return (float)(rng_next(s) >> 8) * 0x1p-24f;
}

/* A test scene begun with one default material (scene_open), and
 * finished into world w (scene_close). */
static void scene_open(scene *s, const char *name)
{
	scene_init(s, name);
	material mt = material_default("m");
	scene_add_material(s, &mt);
}

static void scene_close(world *w, scene *s, const char *name)
{
	diag d;
	cr_assert_eq(scene_finish(s, name, &d), 0);
	tu_build_world(w, s);
}

/* Random small triangles in [-1, 1]^3 and axis-aligned quads on planes a
 * kd-tree splits at (faces in split planes, rays grazing them). */
static void make_soup(world *w)
{
	scene s;
	scene_open(&s, "test:soup");
	uint32_t seed = 12345;
	for (int k = 0; k < 3000; k++) {
		vec3 c =
		    v3(2 * rng_unit(&seed) - 1, 2 * rng_unit(&seed) - 1, 2 * rng_unit(&seed) - 1);
		vec3 t[3];
		for (int j = 0; j < 3; j++)
			t[j] = v3_add(c, v3(0.1f * rng_unit(&seed), 0.1f * rng_unit(&seed),
			                    0.1f * rng_unit(&seed)));
		scene_add_triangle(&s, t, NULL, NULL, 0);
	}
	for (int k = 0; k < 8; k++) {
		float q = -0.75f + 0.25f * (float)k;
		vec3 a[3] = {v3(q, -1, -1), v3(q, 1, -1), v3(q, 1, 1)};
		vec3 b[3] = {v3(-1, q, -1), v3(1, q, 1), v3(1, q, -1)};
		scene_add_triangle(&s, a, NULL, NULL, 0);
		scene_add_triangle(&s, b, NULL, NULL, 0);
	}
	scene_close(w, &s, "soup");
}

enum { KIND_CAMERA, KIND_POINT, KIND_MIXED, KIND_LIGHT, KIND_SURFACE, NKINDS };

/* Packet number n of the given kind. */
static void make_packet(packet *p, int kind, int n, uint32_t *seed)
{
	pkt_clear(p, kind >= KIND_LIGHT ? PKT_SHADOW : PKT_PRIMARY, 0);
	vec3 o = v3(3 * rng_unit(seed) - 1.5f, 3 * rng_unit(seed) - 1.5f, 2.5f + rng_unit(seed));
	vec3 aim = v3(rng_unit(seed) - 0.5f, rng_unit(seed) - 0.5f, -1);
	for (int i = 0; i < PKT_RAYS; i++) {
		vec3 d =
		    v3_add(aim, v3(0.3f * rng_unit(seed) - 0.15f, 0.3f * rng_unit(seed) - 0.15f,
		                   0.3f * rng_unit(seed) - 0.15f));
		if (kind == KIND_MIXED || kind == KIND_SURFACE)
			d = v3(rng_unit(seed) - 0.5f, rng_unit(seed) - 0.5f, rng_unit(seed) - 0.5f);
		if (kind == KIND_POINT && (i % 7) == 0)
			*((i % 3) == 0   ? &d.x
			  : (i % 3) == 1 ? &d.y
			                 : &d.z) = 0.0f; /* zero component */
		/* mixed: from one point inside the scene, every sign on every axis */
		vec3 oi = kind == KIND_SURFACE ? v3(2 * rng_unit(seed) - 1, 2 * rng_unit(seed) - 1,
		                                    2 * rng_unit(seed) - 1)
		          : kind == KIND_MIXED ? v3_scale(o, 0.2f)
		                               : o;
		p->ox[i] = oi.x, p->oy[i] = oi.y, p->oz[i] = oi.z;
		p->dx[i] = d.x, p->dy[i] = d.y, p->dz[i] = d.z;
		p->tmax[i] = kind >= KIND_LIGHT ? 0.5f + 3 * rng_unit(seed) : INFINITY;
		p->pixel[i] = (uint32_t)i;
	}
	p->n = PKT_RAYS;
	/* every third packet partly valid */
	p->valid = n % 3 ? ~0ull : ((uint64_t)rng_next(seed) << 32 | rng_next(seed));
}

/* Triangles each spanning the box [-1, 1]^3 corner region to corner
 * region: every split plane cuts every one, so the tree's leaves hold
 * most of them (more than SIMD_W) and a ray meets many. */
static void make_pile(world *w)
{
	scene s;
	scene_open(&s, "test:pile");
	uint32_t seed = 4242;
	for (int k = 0; k < 3 * SIMD_W + 5; k++) {
		vec3 t[3];
		for (int j = 0; j < 3; j++) {
			float x = 0.8f + 0.2f * rng_unit(&seed), y = 0.8f + 0.2f * rng_unit(&seed),
			      z = 0.8f + 0.2f * rng_unit(&seed);
			/* corners in opposite octants, so each triangle crosses the
			 * middle of every axis */
			int o = (k + j) % 3;
			t[j] = v3(o == 0 ? -x : x, o == 1 ? -y : y, j == 2 ? -z : z);
		}
		scene_add_triangle(&s, t, NULL, NULL, 0);
	}
	scene_close(w, &s, "pile");
}

/* The most triangles of one leaf of w's tree. */
static uint32_t largest_leaf(const world *w)
{
	const kd_node *nodes = mimg_nodes(&w->m);
	uint32_t most = 0;
	for (uint32_t i = 0; i < w->m.nnodes; i++)
		if (kd_is_leaf(nodes[i]) && kd_count(nodes[i]) > most)
			most = kd_count(nodes[i]);
	return most;
}

/* Rays whose results differ between the two paths, plus 1 per packet
 * whose counts differ; coherent: packets the shortcut took. */
static uint64_t mismatches(const world *w, int kind, int npk, int cull, uint64_t *coherent)
{
	static trav_entry stack[PKT_STACK_MAX];
	static packet a, b;
	uint32_t seed = 777u + (uint32_t)kind * 1000u;
	uint64_t bad = 0;
	for (int n = 0; n < npk; n++) {
		if (kind == KIND_CAMERA) {
			camera cam = {v3(0.3f, 0.2f, 3), v3(0, 0, 0), v3(0, 1, 0), 50.0f};
			cam_frame cf;
			cam_setup(&cf, &cam, 128, 128);
			cam_primary_packet(&cf, n % 16, (n / 16) % 16, &a);
		} else
			make_packet(&a, kind, n, &seed);
		b = a;
		trav_counts ca = {0}, cb = {0};
		uint64_t ea = pkt_trace_cone(&a, &w->m, stack, PKT_STACK_MAX, &ca, NULL, cull);
		trav_state st;
		packet probe = b;
		uint64_t eb = pkt_trav_begin(&st, &probe, &w->m, stack, PKT_STACK_MAX);
		*coherent += (uint64_t)fru_coherent(&st, &probe, eb);
		eb = fru_trace(&b, &w->m, stack, PKT_STACK_MAX, &cb, NULL, cull);
		bad += ea != eb || memcmp(&ca, &cb, sizeof ca) != 0;
		for (uint64_t v = a.valid; v; v &= v - 1) {
			int i = __builtin_ctzll(v);
			bad += memcmp(&a.t[i], &b.t[i], 4) || a.tri[i] != b.tri[i] ||
			       memcmp(&a.bu[i], &b.bu[i], 4) || memcmp(&a.bv[i], &b.bv[i], 4);
		}
	}
	return bad;
}

static world soup;

static void setup_soup(void)
{
	make_soup(&soup);
}

static void teardown_soup(void)
{
	world_free(&soup);
}

Test(frustum, same_hits_and_counts_as_per_lane, .init = setup_soup, .fini = teardown_soup)
{
	static const char *names[NKINDS] = {"camera", "one point", "mixed", "light", "surface"};
	for (int cull = 0; cull < 2; cull++)
		for (int k = 0; k < NKINDS; k++) {
			uint64_t coh = 0, bad = mismatches(&soup, k, 256, cull, &coh);
			cr_assert_eq(bad, 0, "%s packets (cull %d): %llu mismatches", names[k],
			             cull, (unsigned long long)bad);
			/* the shortcut is taken where it should be, and only there */
			if (k == KIND_CAMERA || k == KIND_LIGHT || k == KIND_POINT)
				cr_assert_gt(coh, 100, "%s: %llu of 256 coherent", names[k],
				             (unsigned long long)coh);
			if (k == KIND_MIXED)
				cr_assert_eq(coh, 0, "mixed: %llu coherent",
				             (unsigned long long)coh);
		}
}

/* Each planted mistake must show up as mismatches (the check can fail). */
Test(frustum, planted_mistakes_are_caught, .init = setup_soup, .fini = teardown_soup)
{
	static const int faults[] = {FRU_FAULT_ALWAYS_NEAR, FRU_FAULT_ONE_DIRECTION,
	                             FRU_FAULT_POP_ALL, FRU_FAULT_STALE_SEGMENTS,
	                             FRU_FAULT_BARY_SWAP};
	for (int f = 0; f < (int)(sizeof faults / sizeof faults[0]); f++) {
		fru_fault = faults[f];
		uint64_t coh = 0, bad = 0;
		for (int k = 0; k < NKINDS; k++)
			bad += mismatches(&soup, k, 256, 0, &coh);
		fru_fault = FRU_FAULT_NONE;
		cr_assert_gt(bad, 0, "fault %d went unnoticed", faults[f]);
	}
}

static world pile;

static void setup_pile(void)
{
	make_pile(&pile);
}

static void teardown_pile(void)
{
	world_free(&pile);
	fru_tri_path = FRU_TRI_AUTO;
	fru_fault = FRU_FAULT_NONE;
}

/* The triangle-parallel leaf test against the per-lane reference, forced
 * for every leaf, never taken and chosen automatically: the same hits
 * (t, triangle, barycentrics bit for bit; a shadow ray's first occluder
 * in the leaf's order) and the same counts. Mistakes it catches: a
 * shadow ray taking another occluder than its first, triangles of a long
 * leaf skipped, any operation of the test done differently (the planted
 * faults below). */
Test(frustum, triangle_parallel_leaves_equal_per_triangle, .init = setup_pile,
     .fini = teardown_pile)
{
	cr_assert_gt(largest_leaf(&pile), 2 * SIMD_W, "largest leaf %u",
	             (unsigned)largest_leaf(&pile));
	static const int paths[] = {FRU_TRI_ALWAYS, FRU_TRI_NEVER, FRU_TRI_AUTO};
	for (int q = 0; q < 3; q++)
		for (int k = 0; k < NKINDS; k++) {
			fru_tri_path = paths[q];
			uint64_t coh = 0, bad = mismatches(&pile, k, 128, 0, &coh);
			fru_tri_path = FRU_TRI_AUTO;
			cr_assert_eq(bad, 0, "path %d, kind %d: %llu mismatches", paths[q], k,
			             (unsigned long long)bad);
		}
}

/* Each planted mistake of the triangle-parallel test shows up. */
Test(frustum, triangle_parallel_planted_mistakes_are_caught, .init = setup_pile,
     .fini = teardown_pile)
{
	static const int faults[] = {FRU_FAULT_TRI_SHADOW_LAST, FRU_FAULT_TRI_ONE_CHUNK,
	                             FRU_FAULT_BARY_SWAP};
	for (int f = 0; f < (int)(sizeof faults / sizeof faults[0]); f++) {
		fru_fault = faults[f];
		fru_tri_path = FRU_TRI_ALWAYS;
		uint64_t coh = 0, bad = 0;
		for (int k = 0; k < NKINDS; k++)
			bad += mismatches(&pile, k, 128, 0, &coh);
		fru_fault = FRU_FAULT_NONE;
		fru_tri_path = FRU_TRI_AUTO;
		cr_assert_gt(bad, 0, "fault %d went unnoticed", faults[f]);
	}
}

/* A ray down the z axis from (0, 0, 1) past a triangle at z = 0 whose
 * edge from c1 = (-1, -1 - e) to c2 = (1 + e, 1 + 2e), e = 2^-12, passes
 * 2^-24 / |c2 - c1| beside the axis: its edge function (1 + e)(-1 - e)
 * + (1 + 2e) is -2^-24, which float rounds to 0 (the product's 2^-24 is
 * a tie, to even), so only the double-precision redo (isect_uvw_double)
 * sees the ray miss it; it goes on to the floor at z = -1. Mistake
 * caught: the triangle-parallel test skipping the redo (the ray then
 * stops at t = 1). Either axis permutation (kx, ky) gives the same: a
 * swap negates every edge function exactly. */
Test(frustum, triangle_parallel_redoes_zero_edges_in_double)
{
	const float e = 0x1p-12f;
	scene s;
	scene_open(&s, "test:edge");
	vec3 tri[3] = {v3(1, -1, 0), v3(-1, -1 - e, 0), v3(1 + e, 1 + 2 * e, 0)};
	vec3 floor[3] = {v3(-8, -8, -1), v3(8, -8, -1), v3(0, 8, -1)};
	scene_add_triangle(&s, tri, NULL, NULL, 0);
	scene_add_triangle(&s, floor, NULL, NULL, 0);
	world w;
	scene_close(&w, &s, "edge");
	static trav_entry stack[PKT_STACK_MAX];
	static const int paths[] = {FRU_TRI_NEVER, FRU_TRI_ALWAYS, FRU_TRI_AUTO};
	for (int q = 0; q < 3; q++) {
		static packet p;
		pkt_clear(&p, PKT_PRIMARY, 0);
		for (int i = 0; i < PKT_RAYS; i++) {
			p.ox[i] = p.oy[i] = 0.0f, p.oz[i] = 1.0f;
			p.dx[i] = p.dy[i] = 0.0f, p.dz[i] = -1.0f;
			p.tmax[i] = INFINITY;
		}
		p.n = PKT_RAYS;
		p.valid = 1; /* one ray: a sparse packet, triangle-parallel when AUTO */
		fru_tri_path = paths[q];
		fru_trace(&p, &w.m, stack, PKT_STACK_MAX, NULL, NULL, 0);
		fru_tri_path = FRU_TRI_AUTO;
		cr_assert(p.tri[0] != PKT_NOHIT && p.t[0] == 2.0f,
		          "path %d: t %a (the edge's triangle at t 1 taken?)", paths[q],
		          (double)p.t[0]);
	}
	world_free(&w);
}
