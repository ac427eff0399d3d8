/*
 * test_spd.c: the procedural scenes: documented triangle counts, closed
 * (edge-manifold) meshes, determinism, bad specs.
 */
#include <string.h>

#include "kernel-ref/spd.h"
#include "kernel-ref/world.h"
#include "tests/testutil.h"

typedef struct edge {
	uint32_t a[3], b[3];
} edge;

static int cmp_edge(const void *x, const void *y)
{
	return memcmp(x, y, sizeof(edge));
}

/* Number of edges not shared by exactly two triangles (corners compared by
 * their exact bits). */
static uint64_t open_edges(const scene *s)
{
	edge *e = malloc(sizeof *e * 3 * (size_t)s->ntris);
	for (uint32_t t = 0; t < s->ntris; t++)
		for (int k = 0; k < 3; k++) {
			vec3 p = s->v[3 * t + k], q = s->v[3 * t + (k + 1) % 3];
			uint32_t pa[3], qa[3];
			memcpy(pa, &p, sizeof pa);
			memcpy(qa, &q, sizeof qa);
			int swap = memcmp(pa, qa, sizeof pa) > 0;
			memcpy(e[3 * t + k].a, swap ? qa : pa, sizeof pa);
			memcpy(e[3 * t + k].b, swap ? pa : qa, sizeof pa);
		}
	size_t n = 3 * (size_t)s->ntris;
	qsort(e, n, sizeof *e, cmp_edge);
	uint64_t bad = 0;
	for (size_t i = 0; i < n;) {
		size_t j = i;
		while (j < n && cmp_edge(&e[i], &e[j]) == 0)
			j++;
		bad += (j - i) != 2;
		i = j;
	}
	free(e);
	return bad;
}

static void gen(scene *s, view *v, const char *spec)
{
	diag d;
	cr_assert_eq(spd_generate(s, v, spec, &d), 0, "%s: %s", spec, d.msg);
	cr_assert_eq(s->ntris, spd_triangles(spec), "%s: %u triangles, formula says %llu", spec,
	             s->ntris, (unsigned long long)spd_triangles(spec));
	cr_assert_eq(s->ndegenerate, 0, "%s has degenerate triangles", spec);
}

Test(spd, documented_counts)
{
	/* docs/spd.md: balls (9^(L+1)-1)/8 spheres of 2 T (T/2-1) triangles + 2;
	 * tetra 4^(L+1); mount 4^L + 4 spheres; rings 5 L^2 tori of 2 (2T)(T/2) + 2 */
	cr_assert_eq(spd_triangles("spd:balls:0:12"), 1 * 120 + 2);
	cr_assert_eq(spd_triangles("spd:balls:2:12"), 91 * 120 + 2);
	cr_assert_eq(spd_triangles("spd:balls:4"), 7381ull * 120 + 2);
	cr_assert_eq(spd_triangles("spd:tetra:6"), 16384);
	cr_assert_eq(spd_triangles("spd:mount:6"), 4096 + 4 * 224);
	cr_assert_eq(spd_triangles("spd:rings:2:8"), 5 * 4 * 2 * 16 * 4 + 2);
	cr_assert_eq(spd_triangles("spd:cornell"), 32);
	/* billiard: 112 (floor, felt, bed, rails, legs) + SIZE balls */
	cr_assert_eq(spd_triangles("spd:billiard"), 112 + 16 * 528);
	cr_assert_eq(spd_triangles("spd:billiard:0"), 112);
	cr_assert_eq(spd_triangles("spd:billiard:5:8"), 112 + 5 * 48);
	/* a user can dial from about 1k to 5M triangles */
	cr_assert_lt(spd_triangles("spd:balls:1"), 2000);
	cr_assert_gt(spd_triangles("spd:balls:5:16"), 5000000);
}

/* Edges of the billiard table not used by exactly two triangles, none of
 * them a hole in a closed object: the floor's border (4), the felt's long
 * edges (2, open) and short edges (2, also edges of the short rails'
 * boxes: 3 triangles), and the 4 vertical edges where a long and a short
 * rail's boxes meet (4 triangles). Every box and ball is closed. */
#define BILLIARD_OPEN 12

Test(spd, closed_meshes_and_counts)
{
	scene s;
	view v;
	gen(&s, &v, "spd:balls:2");
	cr_assert_eq(open_edges(&s), 4, "only the ground square's border is open");
	cr_assert_eq(v.nlights, 3);
	scene_free(&s);
	gen(&s, &v, "spd:tetra:4");
	cr_assert_eq(open_edges(&s), 0);
	scene_free(&s);
	gen(&s, &v, "spd:mount:5");
	cr_assert_eq(open_edges(&s), 3 * 32, "only the mountain's border is open");
	scene_free(&s);
	gen(&s, &v, "spd:rings:2:8");
	cr_assert_eq(open_edges(&s), 4, "tori are closed; the ground square's border is open");
	scene_free(&s);
	gen(&s, &v, "spd:cornell");
	scene_free(&s);
	/* Mistake caught: a ball or box left open, a ball count off the
	 * formula, the view's two lamps missing */
	gen(&s, &v, "spd:billiard:16:12");
	int oe = open_edges(&s);
	cr_assert_eq(oe, BILLIARD_OPEN,
	             "only the floor, the felt and touching boxes' edges, not %d", oe);
	cr_assert_eq(v.nlights, 2);
	cr_assert_eq(s.nmats, 12);
	scene_free(&s);
}

Test(spd, deterministic)
{
	scene a, b;
	gen(&a, NULL, "spd:mount:6");
	gen(&b, NULL, "spd:mount:6");
	cr_assert(memcmp(a.v, b.v, sizeof *a.v * 3 * a.ntris) == 0);
	scene_free(&a);
	scene_free(&b);
}

Test(spd, bad_specs)
{
	const char *bad[] = {"spd:",          "spd:nope",     "spd:balls:x",    "spd:balls:99",
	                     "spd:balls:2:2", "spd:tetra:3:", "spd:billiard:17"};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		scene s;
		diag d;
		cr_assert_eq(spd_generate(&s, NULL, bad[k], &d), -1, "%s should fail", bad[k]);
		cr_assert(strstr(d.msg, bad[k]) == d.msg, "message should name the spec: %s",
		          d.msg);
		cr_assert_eq(spd_triangles(bad[k]), 0);
	}
}

Test(spd, world_uses_the_standard_view)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = "spd:tetra:3";
	world w;
	diag d;
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	cr_assert_str_eq(w.v.name, "spd-tetra");
	cr_assert_eq(w.s.ntris, 256);
	world_free(&w);
}
