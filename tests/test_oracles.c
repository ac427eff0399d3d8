/*
 * test_oracles.c: kernel-ref's frames of small scenes built here, pixel by
 * pixel against values computed in this file in double precision from
 * the formulas the shader is documented to follow (docs/kernel-ref.md
 * "Shading"), never from the program's own output:
 *
 *   - a Lambertian plane under a coloured point light (ambient + diffuse,
 *     and a Phong highlight), sRGB-encoded to 8 bits;
 *   - a box's shadow on a plane: which pixels are dark, from the geometry
 *     of the shadow volume;
 *   - a mirror: the colour of the wall it reflects, at the pixels where
 *     the law of reflection puts it;
 *   - a tilted glass slab: a thin stripe behind it appears where Snell's
 *     law moves it;
 *   - a textured quad: the texel at each pixel centre (nearest texel,
 *     repeat, row 0 at v = 1).
 *
 * The chip and both references share this math (docs/design.md "What the
 * references share"), so only an oracle from outside can say it is right.
 * Each test names the mistake it catches; docs/TESTING.md ("Checks that
 * can fail") lists the mistakes made to show they fail. Pixels within a
 * small margin of a geometric boundary (an edge, a shadow's rim, a texel
 * border) are left out: there the pixel centre's side is decided by
 * float rounding, not by the formula. Elsewhere every pixel must be
 * within one 8-bit level (fixed-point accumulation and float shading
 * against double here).
 */
#include <math.h>
#include <string.h>

#include "kernel-ref/kdtree.h"
#include "kernel-ref/render.h"
#include "kernel-ref/world.h"
#include "tests/testutil.h"

/* ---- double-precision vectors ---- */

typedef struct dv {
	double x, y, z;
} dv;

static dv d3(double x, double y, double z)
{
	return (dv){x, y, z};
}
static dv dadd(dv a, dv b)
{
	return d3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static dv dsub(dv a, dv b)
{
	return d3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static dv dscale(dv a, double s)
{
	return d3(a.x * s, a.y * s, a.z * s);
}
static dv dmul(dv a, dv b)
{
	return d3(a.x * b.x, a.y * b.y, a.z * b.z);
}
static double ddot(dv a, dv b)
{
	return a.x * b.x + a.y * b.y + a.z * b.z;
}
static dv dcross(dv a, dv b)
{
	return d3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static dv dnorm(dv a)
{
	return dscale(a, 1.0 / sqrt(ddot(a, a)));
}
static dv dfrom(vec3 v)
{
	return d3(v.x, v.y, v.z);
}

/* ---- the oracle's camera, display and shading model ---- */

/* A pinhole camera with a vertical field of view, square pixels and rays
 * through pixel centres (docs/kernel-ref.md; camera.h). */
typedef struct ocam {
	dv eye, u, v, w;
	double sx, sy;
	int width, height;
} ocam;

static ocam ocam_make(const camera *c, int width, int height)
{
	ocam o;
	o.eye = dfrom(c->eye);
	o.w = dnorm(dsub(dfrom(c->lookat), o.eye));
	o.u = dnorm(dcross(o.w, dfrom(c->up)));
	o.v = dcross(o.u, o.w);
	o.sy = tan(c->fov_deg * M_PI / 360.0);
	o.sx = o.sy * width / height;
	o.width = width;
	o.height = height;
	return o;
}

static dv ocam_dir(const ocam *c, int x, int y)
{
	double px = (2.0 * (x + 0.5) / c->width - 1.0) * c->sx;
	double py = (1.0 - 2.0 * (y + 0.5) / c->height) * c->sy;
	return dnorm(dadd(c->w, dadd(dscale(c->u, px), dscale(c->v, py))));
}

/* sRGB encoding (IEC 61966-2-1) of a linear value in [0, 1], 8 bits. */
static int srgb8(double lin)
{
	if (!(lin > 0))
		return 0;
	if (lin >= 1)
		return 255;
	double s = lin <= 0.0031308 ? 12.92 * lin : 1.055 * pow(lin, 1 / 2.4) - 0.055;
	return (int)floor(s * 255 + 0.5);
}

#define AMBIENT 0.15 /* the SaarCOR shader's ambient factor (docs/kernel-ref.md) */

/* One point light's direct term at a visible, unshadowed point: Lambert
 * (kd N.L) plus Phong (ks (R.V)^ns), times the light's colour; no
 * distance attenuation. n faces the viewer; dir is the view ray's. */
static dv direct(dv p, dv n, dv dir, dv lpos, dv lcol, dv kd, dv ks, double ns)
{
	dv l = dnorm(dsub(lpos, p));
	double ndl = ddot(n, l);
	if (ndl <= 0)
		return d3(0, 0, 0);
	dv r = dsub(dscale(n, 2 * ndl), l);
	double rv = ddot(r, dscale(dir, -1));
	double spec = rv > 0 ? pow(rv, ns > 0 ? ns : 1) : 0;
	return dmul(dadd(dscale(kd, ndl), dscale(ks, spec)), lcol);
}

/* ---- scenes ---- */

static void quad(scene *s, dv a, dv b, dv c, dv d, uint32_t mat, const vec2 *uv)
{
	vec3 p[4] = {v3((float)a.x, (float)a.y, (float)a.z), v3((float)b.x, (float)b.y, (float)b.z),
	             v3((float)c.x, (float)c.y, (float)c.z),
	             v3((float)d.x, (float)d.y, (float)d.z)};
	vec3 t1[3] = {p[0], p[1], p[2]}, t2[3] = {p[0], p[2], p[3]};
	vec2 u1[3], u2[3];
	if (uv) {
		u1[0] = u2[0] = uv[0];
		u1[1] = uv[1];
		u1[2] = u2[1] = uv[2];
		u2[2] = uv[3];
	}
	scene_add_triangle(s, t1, NULL, uv ? u1 : NULL, mat);
	scene_add_triangle(s, t2, NULL, uv ? u2 : NULL, mat);
}

/* A horizontal quad y = 0, x and z in [x0, x1] x [z0, z1]. */
static void floor_quad(scene *s, double x0, double x1, double z0, double z1, uint32_t mat)
{
	quad(s, d3(x0, 0, z0), d3(x1, 0, z0), d3(x1, 0, z1), d3(x0, 0, z1), mat, NULL);
}

static material mat_rgb(const char *name, dv ka, dv kd)
{
	material m = material_default(name);
	m.ka = v3((float)ka.x, (float)ka.y, (float)ka.z);
	m.kd = v3((float)kd.x, (float)kd.y, (float)kd.z);
	return m;
}

/* Builds the kd-tree and memory image of s (w takes s over). */
static void build(world *w, scene *s)
{
	diag d;
	cr_assert_eq(scene_finish(s, "oracle", &d), 0, "%s", d.msg);
	tu_build_world(w, s);
}

#define BG_R 0.05
#define BG_G 0.05
#define BG_B 0.08

/* kernel-ref's 8-bit frame of w seen by cam with the lights (n of them). */
static uint8_t *render(const world *w, const camera *cam, const light *lights, int n, int size)
{
	view v;
	memset(&v, 0, sizeof v);
	snprintf(v.name, sizeof v.name, "oracle");
	v.cam = *cam;
	v.lights_given = 1;
	v.nlights = n;
	for (int i = 0; i < n; i++)
		v.lights[i] = lights[i];
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = size;
	ro.background = v3((float)BG_R, (float)BG_G, (float)BG_B);
	framebuf fb;
	cr_assert_eq(fb_init(&fb, size, size), 0);
	render_stats st;
	diag d;
	cr_assert_eq(render_frame(&w->m, &v, &ro, &fb, &st, &d), 0, "%s", d.msg);
	uint8_t *rgb = malloc((size_t)size * size * 3);
	fb_to_rgb8(&fb, rgb, NULL);
	fb_free(&fb);
	return rgb;
}

/* Pixel comparison: counts pixels checked and those off by more than one
 * 8-bit level, keeping the first miss for the message. */
typedef struct tally {
	int checked, bad;
	char first[256];
} tally;

static void expect(tally *t, const uint8_t *img, int size, int x, int y, dv lin, const char *what)
{
	const uint8_t *p = img + 3 * ((size_t)y * size + x);
	int e[3] = {srgb8(lin.x), srgb8(lin.y), srgb8(lin.z)};
	t->checked++;
	for (int c = 0; c < 3; c++)
		if (abs(p[c] - e[c]) > 1) {
			if (!t->bad++)
				snprintf(t->first, sizeof t->first,
				         "%s pixel (%d,%d): got %d %d %d, expected %d %d %d", what,
				         x, y, p[0], p[1], p[2], e[0], e[1], e[2]);
			return;
		}
}

static void tally_ok(const tally *t, int min_checked, const char *test)
{
	cr_assert_geq(t->checked, min_checked, "%s: only %d pixels checked", test, t->checked);
	cr_assert_eq(t->bad, 0, "%s: %d of %d pixels off by more than one level; first: %s", test,
	             t->bad, t->checked, t->first);
}

/* Where a ray meets the plane coordinate axis = c (t > 0), or -1. */
static double hit_plane(dv o, dv d, int axis, double c)
{
	double oa = axis == 0 ? o.x : axis == 1 ? o.y : o.z;
	double da = axis == 0 ? d.x : axis == 1 ? d.y : d.z;
	double t = (c - oa) / da;
	return da != 0 && t > 0 ? t : -1;
}

/* Does the segment o + t d, t in (t0, t1), cross the box [lo, hi]
 * (slab test)? */
static int seg_hits_box(dv o, dv d, double t0, double t1, dv lo, dv hi)
{
	double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
	double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
	for (int a = 0; a < 3; a++) {
		if (dd[a] == 0) {
			if (oo[a] < l[a] || oo[a] > h[a])
				return 0;
			continue;
		}
		double ta = (l[a] - oo[a]) / dd[a], tb = (h[a] - oo[a]) / dd[a];
		if (ta > tb) {
			double x = ta;
			ta = tb;
			tb = x;
		}
		t0 = ta > t0 ? ta : t0;
		t1 = tb < t1 ? tb : t1;
	}
	return t0 <= t1;
}

/* ---- a Lambertian plane under a point light ---- */

/* Mistakes caught: a wrong ambient factor, the light's colour ignored,
 * distance attenuation the shader does not have, the Phong exponent
 * ignored, linear output instead of sRGB's curve, a wrong field of
 * view. */
static void lit_plane(dv ks, double ns, const char *test)
{
	const dv ka = d3(0.6, 0.5, 0.4), kd = d3(0.6, 0.5, 0.4);
	const dv lpos = d3(1.0, 2.0, 0.5), lcol = d3(0.9, 0.7, 0.5);
	scene s;
	scene_init(&s, "oracle:plane");
	material m = mat_rgb("plane", ka, kd);
	m.ks = v3((float)ks.x, (float)ks.y, (float)ks.z);
	m.ns = (float)ns;
	floor_quad(&s, -4, 4, -4, 4, scene_add_material(&s, &m));
	world w;
	build(&w, &s);
	camera cam = {v3(0, 3, 4), v3(0, 0, 0), v3(0, 1, 0), 50};
	light l = {v3((float)lpos.x, (float)lpos.y, (float)lpos.z),
	           v3((float)lcol.x, (float)lcol.y, (float)lcol.z)};
	enum { N = 64 };
	uint8_t *img = render(&w, &cam, &l, 1, N);
	ocam oc = ocam_make(&cam, N, N);
	tally t = {0};
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			dv d = ocam_dir(&oc, x, y);
			double th = hit_plane(oc.eye, d, 1, 0);
			dv p = dadd(oc.eye, dscale(d, th));
			if (th < 0 || (fabs(p.x) > 3.95 || fabs(p.z) > 3.95)) {
				if (th < 0 || fabs(p.x) > 4.05 || fabs(p.z) > 4.05)
					expect(&t, img, N, x, y, d3(BG_R, BG_G, BG_B),
					       "background");
				continue;
			}
			dv lin = dadd(dscale(ka, AMBIENT),
			              direct(p, d3(0, 1, 0), d, lpos, lcol, kd, ks, ns));
			expect(&t, img, N, x, y, lin, "plane");
		}
	tally_ok(&t, N * N * 9 / 10, test);
	free(img);
	world_free(&w);
}

Test(oracles, lambertian_plane_under_a_point_light)
{
	lit_plane(d3(0, 0, 0), 1, "lambert");
}

Test(oracles, phong_highlight_on_a_plane)
{
	lit_plane(d3(0.5, 0.4, 0.3), 12, "phong");
}

/* ---- a box's shadow on a plane ---- */

/* Mistakes caught: shadow rays that never count an occluder (no shadow),
 * an occluder beyond the light counted (tmax not the light's distance:
 * the ceiling above the light darkens everything), shadow rays cast away
 * from the light (the shadow in the wrong place). */
Test(oracles, box_shadow_on_a_plane)
{
	const dv ka = d3(0.7, 0.7, 0.7), kd = d3(0.7, 0.7, 0.7);
	const dv lpos = d3(0.8, 4.0, 0.3), lcol = d3(1, 1, 1);
	const dv lo = d3(-0.5, 0.6, -0.5), hi = d3(0.5, 1.4, 0.5);
	scene s;
	scene_init(&s, "oracle:shadow");
	material pm = mat_rgb("plane", ka, kd),
	         bm = mat_rgb("box", d3(0.3, 0.3, 0.9), d3(0.3, 0.3, 0.9));
	uint32_t plane = scene_add_material(&s, &pm), box = scene_add_material(&s, &bm);
	floor_quad(&s, -4, 4, -4, 4, plane);
	/* a ceiling above the light, out of the camera's sight: it must
	 * shadow nothing (a shadow ray ends at its light) */
	quad(&s, d3(-8, 6, -8), d3(8, 6, -8), d3(8, 6, 8), d3(-8, 6, 8), plane, NULL);
	/* the box's six faces */
	dv c[8];
	for (int i = 0; i < 8; i++)
		c[i] = d3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
	static const int f[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
	                            {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
	for (int k = 0; k < 6; k++)
		quad(&s, c[f[k][0]], c[f[k][1]], c[f[k][2]], c[f[k][3]], box, NULL);
	world w;
	build(&w, &s);
	camera cam = {v3(0, 5, 5), v3(0, 0, 0), v3(0, 1, 0), 45};
	light l = {v3((float)lpos.x, (float)lpos.y, (float)lpos.z), v3(1, 1, 1)};
	enum { N = 96 };
	uint8_t *img = render(&w, &cam, &l, 1, N);
	ocam oc = ocam_make(&cam, N, N);
	/* the box grown and shrunk by a margin: a ray between the two is
	 * too close to an edge to say */
	const double eps = 0.02;
	const dv glo = dsub(lo, d3(eps, eps, eps)), ghi = dadd(hi, d3(eps, eps, eps));
	const dv slo = dadd(lo, d3(eps, eps, eps)), shi = dsub(hi, d3(eps, eps, eps));
	tally t = {0};
	int dark = 0, lit = 0;
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			dv d = ocam_dir(&oc, x, y);
			if (seg_hits_box(oc.eye, d, 0, INFINITY, glo, ghi))
				continue; /* the box itself, or its silhouette */
			double th = hit_plane(oc.eye, d, 1, 0);
			dv p = dadd(oc.eye, dscale(d, th));
			if (th < 0 || fabs(p.x) > 3.95 || fabs(p.z) > 3.95)
				continue;
			dv toward = dsub(lpos, p); /* the shadow ray, t in (0, 1) */
			int in_grown = seg_hits_box(p, toward, 0, 1, glo, ghi);
			int in_shrunk = seg_hits_box(p, toward, 0, 1, slo, shi);
			if (in_grown != in_shrunk)
				continue; /* the shadow's rim */
			dv lin = dscale(ka, AMBIENT);
			if (in_shrunk)
				dark++;
			else {
				lit++;
				lin = dadd(
				    lin, direct(p, d3(0, 1, 0), d, lpos, lcol, kd, d3(0, 0, 0), 1));
			}
			expect(&t, img, N, x, y, lin, in_shrunk ? "shadowed plane" : "lit plane");
		}
	cr_assert_gt(dark, 200, "the shadow should cover many pixels (%d)", dark);
	cr_assert_gt(lit, 2000, "%d lit pixels", lit);
	tally_ok(&t, 3000, "shadow");
	free(img);
	world_free(&w);
}

/* ---- a mirror ---- */

/* A mirror quad in z = 0 faces the camera; behind the camera a wall at
 * z = 6, red left of x = 0.6 and blue right of it. No lights: every
 * surface shows its ambient term. A mirror pixel shows its own ambient
 * share (1 - reflect) and reflect times the wall point the reflected ray
 * reaches: r = d - 2 (d.n) n. Mistakes caught: a wrong reflection
 * direction (the wrong colour, or the edge between the colours in the
 * wrong place), the reflected weight not multiplied by reflect, or the
 * mirror's local share not reduced by it. */
Test(oracles, mirror_reflects_a_known_colour)
{
	const double kr = 0.75, edge = 0.6;
	const dv mka = d3(0.2, 0.2, 0.2), red = d3(4, 0, 0), blue = d3(0, 0, 4);
	scene s;
	scene_init(&s, "oracle:mirror");
	material mm = mat_rgb("mirror", mka, mka);
	mm.reflect = (float)kr;
	material rm = mat_rgb("red", red, d3(0, 0, 0)), bm = mat_rgb("blue", blue, d3(0, 0, 0));
	uint32_t mirror = scene_add_material(&s, &mm);
	uint32_t wr = scene_add_material(&s, &rm), wb = scene_add_material(&s, &bm);
	quad(&s, d3(-1, -1, 0), d3(1, -1, 0), d3(1, 1, 0), d3(-1, 1, 0), mirror, NULL);
	quad(&s, d3(-12, -12, 6), d3(edge, -12, 6), d3(edge, 12, 6), d3(-12, 12, 6), wr, NULL);
	quad(&s, d3(edge, -12, 6), d3(12, -12, 6), d3(12, 12, 6), d3(edge, 12, 6), wb, NULL);
	world w;
	build(&w, &s);
	camera cam = {v3(0, 0, 3), v3(0, 0, 0), v3(0, 1, 0), 50};
	enum { N = 64 };
	uint8_t *img = render(&w, &cam, NULL, 0, N);
	ocam oc = ocam_make(&cam, N, N);
	tally t = {0};
	int nred = 0, nblue = 0;
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			dv d = ocam_dir(&oc, x, y);
			double tm = hit_plane(oc.eye, d, 2, 0);
			dv p = dadd(oc.eye, dscale(d, tm));
			if (fabs(fabs(p.x) - 1) < 0.03 || fabs(fabs(p.y) - 1) < 0.03)
				continue; /* the mirror's edge */
			if (fabs(p.x) > 1 || fabs(p.y) > 1) {
				expect(&t, img, N, x, y, d3(BG_R, BG_G, BG_B), "background");
				continue;
			}
			dv n = d3(0, 0, 1);
			dv r = dsub(d, dscale(n, 2 * ddot(d, n)));
			dv q = dadd(p, dscale(r, hit_plane(p, r, 2, 6)));
			if (fabs(q.x - edge) < 0.05)
				continue; /* the reflected edge between the colours */
			int is_red = q.x < edge;
			nred += is_red;
			nblue += !is_red;
			dv lin = dadd(dscale(mka, (1 - kr) * AMBIENT),
			              dscale(is_red ? red : blue, kr * AMBIENT));
			expect(&t, img, N, x, y, lin, is_red ? "mirror (red)" : "mirror (blue)");
		}
	cr_assert_gt(nred, 300, "%d mirror pixels show red", nred);
	cr_assert_gt(nblue, 100, "%d mirror pixels show blue", nblue);
	tally_ok(&t, N * N * 8 / 10, "mirror");
	free(img);
	world_free(&w);
}

/* ---- refraction through a tilted slab ---- */

/* Refracts unit d at a surface with unit normal n facing the incoming
 * side, eta = n1 / n2 (Snell: n1 sin i = n2 sin t). */
static dv refract(dv d, dv n, double eta)
{
	double ci = -ddot(d, n);
	double k = 1 - eta * eta * (1 - ci * ci);
	cr_assert_geq(k, 0, "the oracle's slab has no total internal reflection");
	return dadd(dscale(d, eta), dscale(n, eta * ci - sqrt(k)));
}

/* Where the ray o + t d meets the plane through c with normal n (t > 0). */
static dv meet(dv o, dv d, dv c, dv n)
{
	double t = ddot(dsub(c, o), n) / ddot(d, n);
	cr_assert_gt(t, 0);
	return dadd(o, dscale(d, t));
}

/* A grey wall at z = 0 with a blue stripe x in [S0, S1], seen through a
 * glass slab (index 1.5, thickness 0.8) turned 35 degrees about y. The
 * oracle follows each pixel's ray through both faces with Snell's law and
 * looks at the x where it meets the wall. Mistakes caught: eta inverted
 * (n2 / n1 on entry), refraction ignored (the ray passes straight through:
 * the stripe stays where it is), a refracted weight other than transmit. */
#define S0 0.15
#define S1 0.30

Test(oracles, refraction_through_a_slab_moves_a_stripe_by_snells_law)
{
	const double ni = 1.5, th = 35 * M_PI / 180, thick = 0.8;
	const dv grey = d3(2, 2, 2), blue = d3(0, 0, 4);
	scene s;
	scene_init(&s, "oracle:slab");
	material gm = mat_rgb("grey", grey, d3(0, 0, 0)), bm = mat_rgb("stripe", blue, d3(0, 0, 0));
	material glass = mat_rgb("glass", d3(0, 0, 0), d3(0, 0, 0));
	glass.transmit = 1;
	glass.ni = (float)ni;
	uint32_t g = scene_add_material(&s, &gm), b = scene_add_material(&s, &bm);
	uint32_t gl = scene_add_material(&s, &glass);
	quad(&s, d3(-6, -6, 0), d3(S0, -6, 0), d3(S0, 6, 0), d3(-6, 6, 0), g, NULL);
	quad(&s, d3(S0, -6, 0), d3(S1, -6, 0), d3(S1, 6, 0), d3(S0, 6, 0), b, NULL);
	quad(&s, d3(S1, -6, 0), d3(6, -6, 0), d3(6, 6, 0), d3(S1, 6, 0), g, NULL);
	/* the slab: two parallel faces, normal n towards the camera. The
	 * shader tells entering from leaving by the winding (the geometric
	 * normal points out of the glass): the front face is wound about +n,
	 * the back one about -n. */
	const dv n = d3(sin(th), 0, cos(th)), e1 = d3(cos(th), 0, -sin(th)), e2 = d3(0, 1, 0);
	const dv front = d3(0, 0, 2), back = dsub(front, dscale(n, thick));
	for (int k = 0; k < 2; k++) {
		dv c = k ? back : front;
		dv a = dsub(dsub(c, dscale(e1, 4)), dscale(e2, 4));
		dv bb = dsub(dadd(c, dscale(e1, 4)), dscale(e2, 4));
		dv cc = dadd(dadd(c, dscale(e1, 4)), dscale(e2, 4));
		dv dd = dadd(dsub(c, dscale(e1, 4)), dscale(e2, 4));
		if (k)
			quad(&s, a, dd, cc, bb, gl, NULL);
		else
			quad(&s, a, bb, cc, dd, gl, NULL);
	}
	world w;
	build(&w, &s);
	camera cam = {v3(0, 0, 6), v3(0, 0, 0), v3(0, 1, 0), 30};
	enum { N = 96 };
	uint8_t *img = render(&w, &cam, NULL, 0, N);
	ocam oc = ocam_make(&cam, N, N);
	/* the oracle's sanity: the central ray leaves the slab parallel to
	 * itself, shifted sideways by thick sin(i - r) / cos r */
	{
		dv d = d3(0, 0, -1);
		dv p1 = meet(oc.eye, d, front, n), t1 = refract(d, n, 1 / ni);
		dv p2 = meet(p1, t1, back, n), t2 = refract(t1, n, ni);
		double i = th, r = asin(sin(th) / ni);
		double off = sqrt(ddot(dcross(dsub(p2, oc.eye), d), dcross(dsub(p2, oc.eye), d)));
		cr_assert(fabs(off - thick * sin(i - r) / cos(r)) < 1e-9, "offset %g", off);
		cr_assert(fabs(ddot(t2, d) - 1) < 1e-12, "the ray leaves parallel");
	}
	tally t = {0};
	int stripe_px = 0, moved = 0;
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			dv d = ocam_dir(&oc, x, y);
			dv p1 = meet(oc.eye, d, front, n), t1 = refract(d, n, 1 / ni);
			dv p2 = meet(p1, t1, back, n), t2 = refract(t1, n, ni);
			dv q = meet(p2, t2, d3(0, 0, 0), d3(0, 0, 1));
			/* where the ray would meet the wall without the slab */
			dv q0 = meet(oc.eye, d, d3(0, 0, 0), d3(0, 0, 1));
			if (fabs(q.x - S0) < 0.01 || fabs(q.x - S1) < 0.01)
				continue;
			int in = q.x > S0 && q.x < S1;
			stripe_px += in;
			moved += in != (q0.x > S0 && q0.x < S1);
			expect(&t, img, N, x, y, dscale(in ? blue : grey, AMBIENT),
			       in ? "stripe" : "wall");
		}
	cr_assert_gt(stripe_px, 300, "%d stripe pixels", stripe_px);
	cr_assert_gt(moved, 300, "the slab should move the stripe (%d pixels change)", moved);
	tally_ok(&t, N * N * 8 / 10, "slab");
	free(img);
	world_free(&w);
}

/* ---- a textured quad ---- */

/* A 4x4 texture of distinct colours on the quad [-1, 1]^2 at z = 0, with
 * uv = (x + 1, y + 1): it repeats twice each way. A light at the eye. At
 * each pixel centre the oracle takes u, v at the hit point, wraps them
 * into [0, 1) and reads the nearest texel, column floor(u w), row
 * floor((1 - v) h) (row 0 is the top, v = 1); the colour multiplies Ka
 * and Kd. Mistakes caught: v not flipped, clamping instead of repeat,
 * the texel not multiplying the ambient term, uv interpolated with the
 * wrong barycentric weights. */
Test(oracles, textured_quad_shows_its_texels)
{
	enum { TW = 4, TH = 4, N = 64 };
	scene s;
	scene_init(&s, "oracle:texture");
	s.texs = calloc(1, sizeof *s.texs);
	cr_assert(s.texs);
	s.ntexs = 1;
	texture *tx = &s.texs[0];
	snprintf(tx->path, sizeof tx->path, "oracle:4x4");
	tx->w = TW;
	tx->h = TH;
	tx->rgba = malloc(TW * TH * 4);
	cr_assert(tx->rgba);
	for (int j = 0; j < TH; j++)
		for (int i = 0; i < TW; i++) {
			uint8_t *p = tx->rgba + 4 * (j * TW + i);
			p[0] = (uint8_t)(30 + 60 * i);
			p[1] = (uint8_t)(30 + 60 * j);
			p[2] = (uint8_t)(220 - 25 * (i + j));
			p[3] = 255;
		}
	material m = mat_rgb("tex", d3(1, 1, 1), d3(1, 1, 1));
	m.tex_kd = 0;
	vec2 uv[4] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
	quad(&s, d3(-1, -1, 0), d3(1, -1, 0), d3(1, 1, 0), d3(-1, 1, 0), scene_add_material(&s, &m),
	     uv);
	/* the oracle's copy of the texels (the scene's go to the world) */
	uint8_t texels[TW * TH * 4];
	memcpy(texels, tx->rgba, sizeof texels);
	world w;
	build(&w, &s);
	const dv lpos = d3(0, 0, 3), lcol = d3(0.8, 0.8, 0.8);
	camera cam = {v3(0, 0, 3), v3(0, 0, 0), v3(0, 1, 0), 45};
	light l = {v3(0, 0, 3), v3(0.8f, 0.8f, 0.8f)};
	uint8_t *img = render(&w, &cam, &l, 1, N);
	ocam oc = ocam_make(&cam, N, N);
	tally t = {0};
	int seen[TW * TH] = {0};
	for (int y = 0; y < N; y++)
		for (int x = 0; x < N; x++) {
			dv d = ocam_dir(&oc, x, y);
			dv p = dadd(oc.eye, dscale(d, hit_plane(oc.eye, d, 2, 0)));
			if (fabs(p.x) > 0.97 || fabs(p.y) > 0.97)
				continue; /* the quad's edge and what lies outside */
			double u = p.x + 1, v = p.y + 1;
			u -= floor(u);
			v -= floor(v);
			double fu = u * TW, fv = (1 - v) * TH;
			if (fabs(fu - floor(fu + 0.5)) < 0.06 || fabs(fv - floor(fv + 0.5)) < 0.06)
				continue; /* a texel border: rounding decides */
			int i = (int)floor(fu), j = (int)floor(fv);
			const uint8_t *c = texels + 4 * (j * TW + i);
			dv tex = d3(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0);
			dv k = dadd(
			    d3(AMBIENT, AMBIENT, AMBIENT),
			    direct(p, d3(0, 0, 1), d, lpos, lcol, d3(1, 1, 1), d3(0, 0, 0), 1));
			seen[j * TW + i]++;
			expect(&t, img, N, x, y, dmul(tex, k), "texel");
		}
	for (int k = 0; k < TW * TH; k++)
		cr_assert_gt(seen[k], 10, "texel %d,%d seen at %d pixels", k % TW, k / TW, seen[k]);
	tally_ok(&t, N * N * 4 / 10, "texture");
	free(img);
	world_free(&w);
}

/* The sRGB byte by table (fb_srgb8, what every frame's conversion uses)
 * equals the transfer function's (fb_srgb8_formula) at every fixed-point
 * sum below 1.0 and just above it: the table stands for the formula only
 * because the formula is a step function it reproduces exactly. Mistakes
 * caught: a threshold one sum off (a level's first sum converted to the
 * level below), a coarse index rounding up (the levels near 0, many per
 * coarse step, skipped), sums at or past 1.0 not saturating. */
Test(oracles, srgb_table_equals_the_transfer_function_at_every_sum)
{
	uint64_t bad = 0, first = 0;
	for (uint64_t a = 0; a <= ((uint64_t)1 << FB_FRAC_BITS) + 64; a++)
		if (fb_srgb8(a) != fb_srgb8_formula(a) && !bad++)
			first = a;
	cr_assert_eq(bad, 0, "%llu sums differ, the first %llu (table %d, formula %d)",
	             (unsigned long long)bad, (unsigned long long)first, fb_srgb8(first),
	             fb_srgb8_formula(first));
	cr_assert_eq(fb_srgb8(UINT64_MAX / 2), 255);
}

/* img_compare, which every run's check goes through: a frame differing
 * from its reference only in the last byte is not identical (one pixel,
 * a finite PSNR), and equal frames are (no pixel, PSNR infinite).
 * Mistakes caught: the equal-bytes shortcut comparing fewer bytes than
 * the frame holds (a pixel count for a byte count: the last two thirds
 * unseen), or answering "identical" without comparing. */
Test(oracles, img_compare_sees_a_difference_in_the_last_byte)
{
	enum { W = 7, H = 5, N = W * H * 3 };
	uint8_t a[N], b[N];
	for (int i = 0; i < N; i++)
		a[i] = b[i] = (uint8_t)(i * 37);
	img_cmp same = img_compare(a, b, W, H);
	cr_assert(same.identical && same.differing_pixels == 0 && isinf(same.psnr));
	b[N - 1] ^= 1;
	img_cmp one = img_compare(a, b, W, H);
	cr_assert(!one.identical, "a frame differing in its last byte called identical");
	cr_assert_eq(one.differing_pixels, 1);
	cr_assert(isfinite(one.psnr) && one.psnr > 40.0, "psnr %g", one.psnr);
}
