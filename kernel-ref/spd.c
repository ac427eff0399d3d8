/*
 * spd.c: procedural scenes after Haines' Standard Procedural Databases
 * (see spd.h and docs/spd.md).
 *
 * Tessellation keeps meshes closed: a sphere is a UV grid whose poles are
 * single points and whose seam reuses the first column's vertices; a torus
 * is a periodic grid; every vertex position is computed once and reused, so
 * neighbouring triangles share bit-identical corners. The mountain's heights
 * come from a hash of the grid point (midpoint displacement whose random
 * term depends only on the point), so the mesh is the same whatever order
 * it is built in.
 */
#include "kernel-ref/spd.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SPD_MAX_TRIANGLES 20000000ull

/* ---- tessellated primitives ------------------------------------------------ */

/* UV sphere, nu segments around (>= 3), nu/2 rings: 2 nu (nu/2 - 1) triangles. */
void spd_add_sphere(scene *s, vec3 c, float r, int nu, uint32_t mat)
{
	int nv = nu / 2 < 2 ? 2 : nu / 2;
	vec3 *p = malloc(sizeof *p * (size_t)(nv + 1) * (size_t)nu);
	for (int j = 0; j <= nv; j++)
		for (int i = 0; i < nu; i++) {
			float th = (float)M_PI * (float)j / (float)nv,
			      ph = 2.0f * (float)M_PI * (float)i / (float)nu;
			float st = (j == 0 || j == nv) ? 0.0f : sinf(th);
			float ct = j == 0 ? 1.0f : j == nv ? -1.0f : cosf(th);
			if (j == 0 || j == nv)
				ph = 0.0f; /* one exact pole point */
			p[j * nu + i] =
			    v3(c.x + r * st * cosf(ph), c.y + r * st * sinf(ph), c.z + r * ct);
		}
	for (int j = 0; j < nv; j++)
		for (int i = 0; i < nu; i++) {
			int i1 = (i + 1) % nu;
			vec3 a = p[j * nu + i], b = p[j * nu + i1], cc = p[(j + 1) * nu + i1],
			     d = p[(j + 1) * nu + i];
			vec3 t0[3] = {a, d, cc}, t1[3] = {a, cc, b};
			vec3 n0[3], n1[3];
			for (int k = 0; k < 3; k++) {
				n0[k] = v3_norm(v3_sub(t0[k], c));
				n1[k] = v3_norm(v3_sub(t1[k], c));
			}
			if (j != 0)
				scene_add_triangle(s, t1, n1, NULL, mat);
			if (j != nv - 1)
				scene_add_triangle(s, t0, n0, NULL, mat);
		}
	free(p);
}

static uint64_t sphere_tris(int nu)
{
	int nv = nu / 2 < 2 ? 2 : nu / 2;
	return 2ull * (uint64_t)nu * (uint64_t)(nv - 1);
}

/* Torus around axis `ax` (unit) through c: major radius R, minor r, nu x nv
 * periodic grid: 2 nu nv triangles. */
static void add_torus(scene *s, vec3 c, vec3 ax, float R, float r, int nu, int nv, uint32_t mat)
{
	vec3 u = fabsf(ax.x) < 0.9f ? v3(1, 0, 0) : v3(0, 1, 0);
	u = v3_norm(v3_cross(ax, u));
	vec3 w = v3_cross(ax, u);
	vec3 *p = malloc(sizeof *p * (size_t)nu * (size_t)nv),
	     *n = malloc(sizeof *n * (size_t)nu * (size_t)nv);
	for (int i = 0; i < nu; i++)
		for (int j = 0; j < nv; j++) {
			float a = 2.0f * (float)M_PI * (float)i / (float)nu,
			      b = 2.0f * (float)M_PI * (float)j / (float)nv;
			vec3 radial = v3_add(v3_scale(u, cosf(a)), v3_scale(w, sinf(a)));
			vec3 nn = v3_add(v3_scale(radial, cosf(b)), v3_scale(ax, sinf(b)));
			p[i * nv + j] = v3_add(c, v3_add(v3_scale(radial, R), v3_scale(nn, r)));
			n[i * nv + j] = nn;
		}
	for (int i = 0; i < nu; i++)
		for (int j = 0; j < nv; j++) {
			int i1 = (i + 1) % nu, j1 = (j + 1) % nv;
			int k[4] = {i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1};
			vec3 t0[3] = {p[k[0]], p[k[1]], p[k[2]]},
			     n0[3] = {n[k[0]], n[k[1]], n[k[2]]};
			vec3 t1[3] = {p[k[0]], p[k[2]], p[k[3]]},
			     n1[3] = {n[k[0]], n[k[2]], n[k[3]]};
			scene_add_triangle(s, t0, n0, NULL, mat);
			scene_add_triangle(s, t1, n1, NULL, mat);
		}
	free(p);
	free(n);
}

static void add_quad(scene *s, vec3 a, vec3 b, vec3 c, vec3 d, uint32_t mat)
{
	vec3 t0[3] = {a, b, c}, t1[3] = {a, c, d};
	scene_add_triangle(s, t0, NULL, NULL, mat);
	scene_add_triangle(s, t1, NULL, NULL, mat);
}

static uint32_t mat(scene *s, const char *name, vec3 kd, vec3 ks, float ns, float refl,
                    float transmit, float ni)
{
	material m = material_default(name);
	m.kd = m.ka = kd;
	m.ks = ks;
	m.ns = ns;
	m.reflect = refl;
	m.transmit = transmit;
	m.ni = ni;
	return scene_add_material(s, &m);
}

static void set_view(view *v, const char *name, vec3 eye, vec3 at, vec3 up, float fov,
                     const vec3 *lights, int nl)
{
	if (!v)
		return;
	memset(v, 0, sizeof *v);
	snprintf(v->name, sizeof v->name, "%s", name);
	v->cam = (camera){eye, at, up, fov};
	v->lights_given = 1;
	v->nlights = nl;
	for (int i = 0; i < nl; i++)
		v->lights[i] = (light){lights[i], v3(1, 1, 1)};
}

/* ---- balls: the sphereflake ------------------------------------------------ */

/* Nine children of radius r/3 around a sphere whose outward axis is `ax`:
 * six around its equator, three above, turned 30 degrees. */
static void flake(scene *s, vec3 c, float r, vec3 ax, int depth, int nu, uint32_t m)
{
	spd_add_sphere(s, c, r, nu, m);
	if (depth == 0)
		return;
	vec3 u = fabsf(ax.x) < 0.9f ? v3(1, 0, 0) : v3(0, 1, 0);
	u = v3_norm(v3_cross(ax, u));
	vec3 w = v3_cross(ax, u);
	float cr = r / 3.0f, dist = r + cr;
	for (int k = 0; k < 9; k++) {
		float az = k < 6 ? (float)k * (float)M_PI / 3.0f
		                 : (float)M_PI / 6.0f + (float)(k - 6) * 2.0f * (float)M_PI / 3.0f;
		float el = k < 6 ? 0.0f : (float)M_PI / 3.0f;
		vec3 dir =
		    v3_add(v3_scale(v3_add(v3_scale(u, cosf(az)), v3_scale(w, sinf(az))), cosf(el)),
		           v3_scale(ax, sinf(el)));
		flake(s, v3_add(c, v3_scale(dir, dist)), cr, dir, depth - 1, nu, m);
	}
}

static uint64_t pow_u(uint64_t b, int e)
{
	uint64_t r = 1;
	while (e-- > 0)
		r *= b;
	return r;
}

/* ---- mount: fractal mountain ------------------------------------------------- */

static float hash01(uint32_t i, uint32_t j)
{
	uint32_t h = i * 0x9E3779B1u ^ (j + 0x7F4A7C15u) * 0x85EBCA77u;
	h ^= h >> 15;
	h *= 0x2C1B3C6Du;
	h ^= h >> 12;
	return (float)(h & 0xFFFFFFu) / (float)0x1000000u - 0.5f;
}

/* Midpoint displacement on a triangular grid of n = 2^level steps per edge:
 * vertex (i, j), i + j <= n; each level fills the midpoints of the previous
 * level's edges (each edge belongs to exactly one upright cell) with the mean
 * of the edge's ends plus a random term that halves every level. */
static void add_mountain(scene *s, int level, vec3 A, vec3 B, vec3 C, float rough, uint32_t m)
{
	int n = 1 << level;
	int w = n + 1;
	float *h = calloc((size_t)w * (size_t)w, sizeof *h);
	for (int step = n, k = 0; step > 1; step /= 2, k++) {
		float amp = rough / (float)(1 << k);
		for (int i = 0; i + step <= n; i += step)
			for (int j = 0; i + j + step <= n; j += step) {
				/* every edge of the grid belongs to exactly one upright cell */
				int e[3][4] = {{i, j, i + step, j},
				               {i, j, i, j + step},
				               {i + step, j, i, j + step}};
				for (int q = 0; q < 3; q++) {
					int mi = (e[q][0] + e[q][2]) / 2,
					    mj = (e[q][1] + e[q][3]) / 2;
					h[mi * w + mj] = 0.5f * (h[e[q][0] * w + e[q][1]] +
					                         h[e[q][2] * w + e[q][3]]) +
					                 amp * hash01((uint32_t)mi, (uint32_t)mj);
				}
			}
	}
	vec3 *p = malloc(sizeof *p * (size_t)w * (size_t)w);
	for (int i = 0; i <= n; i++)
		for (int j = 0; i + j <= n; j++) {
			vec3 q = v3_add(A, v3_add(v3_scale(v3_sub(B, A), (float)i / (float)n),
			                          v3_scale(v3_sub(C, A), (float)j / (float)n)));
			/* the border stays at height 0 so the mountain meets the plain */
			int border = i == 0 || j == 0 || i + j == n;
			q.z += border ? 0.0f : fabsf(h[i * w + j]);
			p[i * w + j] = q;
		}
	for (int i = 0; i < n; i++)
		for (int j = 0; i + j < n; j++) {
			vec3 t0[3] = {p[i * w + j], p[(i + 1) * w + j], p[i * w + j + 1]};
			scene_add_triangle(s, t0, NULL, NULL, m);
			if (i + j + 1 < n) {
				vec3 t1[3] = {p[(i + 1) * w + j], p[(i + 1) * w + j + 1],
				              p[i * w + j + 1]};
				scene_add_triangle(s, t1, NULL, NULL, m);
			}
		}
	free(h);
	free(p);
}

/* ---- billiard: a pool table after seed 000's benchmark ------------------------ */

/* An axis-aligned box from lo to hi: six quads, 12 triangles. */
static void add_box(scene *s, vec3 lo, vec3 hi, uint32_t m)
{
	vec3 c[8];
	for (int k = 0; k < 8; k++)
		c[k] = v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
	static const int f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
	                            {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
	for (int k = 0; k < 6; k++)
		add_quad(s, c[f[k][0]], c[f[k][1]], c[f[k][2]], c[f[k][3]], m);
}

/* floor 2 + felt 2 + bed 12 + four rails 48 + four legs 48 */
#define BILLIARD_FIXED_TRIS 112ull
#define BALL_R              0.028575f /* 57.15 mm balls */
#define FELT_Z              0.8f

/* The table (a 2.54 x 1.27 m bed of green felt, glossy wooden rails on a
 * wooden body and legs) on a floor, with nb balls (z up, metres): the
 * cue ball, then a rack of up to 15 in five rows. The balls are glossy
 * (reflect 0.12) and so are the rails (0.25): with `drt: {gloss: N}`
 * their reflections blur, as the seed's balls do (§5.3). */
static void billiard(scene *s, view *v, int nb, int tess)
{
	uint32_t floor_m = mat(s, "floor", v3(0.45f, 0.4f, 0.35f), v3(0, 0, 0), 1, 0, 0, 1);
	uint32_t felt = mat(s, "felt", v3(0.05f, 0.35f, 0.12f), v3(0, 0, 0), 1, 0, 0, 1);
	uint32_t wood =
	    mat(s, "wood", v3(0.35f, 0.17f, 0.07f), v3(0.4f, 0.4f, 0.4f), 40, 0.25f, 0, 1);
	add_quad(s, v3(-4, -3, 0), v3(4, -3, 0), v3(4, 3, 0), v3(-4, 3, 0), floor_m);
	add_quad(s, v3(-1.27f, -0.635f, FELT_Z), v3(1.27f, -0.635f, FELT_Z),
	         v3(1.27f, 0.635f, FELT_Z), v3(-1.27f, 0.635f, FELT_Z), felt);
	add_box(s, v3(-1.37f, -0.735f, 0.6f), v3(1.37f, 0.735f, 0.79f), wood); /* the bed */
	const float rz = FELT_Z + 0.04f;
	add_box(s, v3(-1.37f, 0.635f, FELT_Z), v3(1.37f, 0.735f, rz), wood);
	add_box(s, v3(-1.37f, -0.735f, FELT_Z), v3(1.37f, -0.635f, rz), wood);
	add_box(s, v3(1.27f, -0.635f, FELT_Z), v3(1.37f, 0.635f, rz), wood);
	add_box(s, v3(-1.37f, -0.635f, FELT_Z), v3(-1.27f, 0.635f, rz), wood);
	for (int k = 0; k < 4; k++) {
		float x = k & 1 ? 1.1f : -1.1f, y = k & 2 ? 0.5f : -0.5f;
		add_box(s, v3(x - 0.06f, y - 0.06f, 0), v3(x + 0.06f, y + 0.06f, 0.6f), wood);
	}
	static const float col[8][3] = {
	    {0.9f, 0.75f, 0.1f}, {0.1f, 0.2f, 0.7f}, {0.8f, 0.1f, 0.1f}, {0.4f, 0.1f, 0.5f},
	    {0.9f, 0.45f, 0.1f}, {0.1f, 0.5f, 0.2f}, {0.5f, 0.1f, 0.1f}, {0.03f, 0.03f, 0.03f}};
	uint32_t bm[9];
	for (int k = 0; k < 8; k++)
		bm[k] = mat(s, "ball", v3(col[k][0], col[k][1], col[k][2]), v3(0.6f, 0.6f, 0.6f),
		            80, 0.12f, 0, 1);
	bm[8] = mat(s, "cue", v3(0.9f, 0.9f, 0.85f), v3(0.6f, 0.6f, 0.6f), 80, 0.12f, 0, 1);
	const float zc = FELT_Z + BALL_R, gap = 2.0f * BALL_R + 0.0005f;
	if (nb > 0)
		spd_add_sphere(s, v3(-0.635f, 0.05f, zc), BALL_R, tess, bm[8]);
	for (int b = 1, row = 0; b < nb; row++)
		for (int j = 0; j <= row && b < nb; j++, b++)
			spd_add_sphere(s,
			               v3(0.635f + (float)row * gap * 0.8660254f,
			                  ((float)j - 0.5f * (float)row) * gap, zc),
			               BALL_R, tess, bm[(b - 1) % 8]);
	vec3 l[2] = {v3(-0.6f, 0, 1.8f), v3(0.6f, 0, 1.8f)};
	set_view(v, "spd-billiard", v3(-0.9f, -1.2f, 1.5f), v3(0.25f, 0, FELT_Z), v3(0, 0, 1), 40,
	         l, 2);
}

/* ---- the generators ------------------------------------------------------------ */

typedef struct spd_spec {
	char name[16];
	int size, tess;
} spd_spec;

static const struct spd_info {
	const char *name;
	int def_size, max_size, def_tess;
} spd_table[] = {
    {"balls", 3, 6, 12},  {"tetra", 6, 10, 0},  {"mount", 6, 11, 16},
    {"rings", 4, 60, 16}, {"cornell", 0, 0, 0}, {"billiard", 16, 16, 24},
};

static const struct spd_info *parse(const char *spec, spd_spec *o, diag *d)
{
	if (strncmp(spec, SPD_PREFIX, strlen(SPD_PREFIX)) != 0)
		return diag_set(d, spec, 0, 0,
		                "not a procedural scene (expected spd:NAME[:SIZE[:TESS]])"),
		       NULL;
	const char *p = spec + strlen(SPD_PREFIX);
	size_t len = strcspn(p, ":");
	const struct spd_info *in = NULL;
	for (size_t k = 0; k < sizeof spd_table / sizeof *spd_table; k++)
		if (strlen(spd_table[k].name) == len && strncmp(p, spd_table[k].name, len) == 0)
			in = &spd_table[k];
	if (!in)
		return diag_set(d, spec, 0, 0,
		                "unknown procedural scene (known: balls, tetra, mount, rings, "
		                "cornell, billiard)"),
		       NULL;
	snprintf(o->name, sizeof o->name, "%s", in->name);
	o->size = in->def_size;
	o->tess = in->def_tess;
	p += len;
	for (int field = 0; *p == ':' && field < 2; field++) {
		char *end;
		errno = 0;
		long v = strtol(p + 1, &end, 10);
		if (end == p + 1 || errno || (*end && *end != ':'))
			return diag_set(d, spec, 0, 0, "expected a whole number after ':'"), NULL;
		if (field == 0) {
			if (v < 0 || v > in->max_size)
				return diag_set(d, spec, 0, 0,
				                "size %ld out of range [0, %d] for %s", v,
				                in->max_size, in->name),
				       NULL;
			o->size = (int)v;
		} else {
			if (v < 4 || v > 256)
				return diag_set(d, spec, 0, 0,
				                "tessellation %ld out of range [4, 256]", v),
				       NULL;
			o->tess = (int)v;
		}
		p = end;
	}
	if (*p)
		return diag_set(d, spec, 0, 0,
		                "trailing characters (expected spd:NAME[:SIZE[:TESS]])"),
		       NULL;
	return in;
}

static uint64_t count(const spd_spec *o)
{
	if (!strcmp(o->name, "balls"))
		return (pow_u(9, o->size + 1) - 1) / 8 * sphere_tris(o->tess) + 2;
	if (!strcmp(o->name, "tetra"))
		return pow_u(4, o->size + 1);
	if (!strcmp(o->name, "mount"))
		return pow_u(4, o->size) + 4 * sphere_tris(o->tess);
	if (!strcmp(o->name, "rings"))
		return 5ull * (uint64_t)o->size * (uint64_t)o->size * 2ull *
		           (uint64_t)(2 * o->tess) * (uint64_t)(o->tess / 2) +
		       2;
	if (!strcmp(o->name, "billiard"))
		return BILLIARD_FIXED_TRIS + (uint64_t)o->size * sphere_tris(o->tess);
	return 32; /* cornell */
}

uint64_t spd_triangles(const char *spec)
{
	spd_spec o;
	return parse(spec, &o, NULL) ? count(&o) : 0;
}

static void tetra(scene *s, vec3 c, float r, int depth, uint32_t m)
{
	static const float dirs[4][3] = {{1, 1, 1}, {-1, -1, 1}, {-1, 1, -1}, {1, -1, -1}};
	if (depth == 0) {
		vec3 p[4];
		for (int k = 0; k < 4; k++)
			p[k] = v3_add(c, v3_scale(v3(dirs[k][0], dirs[k][1], dirs[k][2]), r));
		int f[4][3] = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
		for (int k = 0; k < 4; k++) {
			vec3 t[3] = {p[f[k][0]], p[f[k][1]], p[f[k][2]]};
			scene_add_triangle(s, t, NULL, NULL, m);
		}
		return;
	}
	for (int k = 0; k < 4; k++)
		tetra(s, v3_add(c, v3_scale(v3(dirs[k][0], dirs[k][1], dirs[k][2]), r * 0.5f)),
		      r * 0.5f, depth - 1, m);
}

int spd_generate(scene *s, view *v, const char *spec, diag *d)
{
	spd_spec o;
	if (!parse(spec, &o, d))
		return -1;
	uint64_t n = count(&o);
	if (n > SPD_MAX_TRIANGLES)
		return diag_set(d, spec, 0, 0, "%llu triangles is more than the %llu allowed",
		                (unsigned long long)n, SPD_MAX_TRIANGLES);
	scene_init(s, spec);
	if (!strcmp(o.name, "balls")) {
		uint32_t gold =
		    mat(s, "flake", v3(1.0f, 0.75f, 0.33f), v3(0.5f, 0.5f, 0.5f), 30, 0.5f, 0, 1);
		uint32_t ground =
		    mat(s, "ground", v3(0.75f, 0.75f, 0.75f), v3(0, 0, 0), 1, 0, 0, 1);
		flake(s, v3(0, 0, 0), 0.5f, v3(0, 0, 1), o.size, o.tess, gold);
		add_quad(s, v3(-6, -6, -0.5f), v3(6, -6, -0.5f), v3(6, 6, -0.5f), v3(-6, 6, -0.5f),
		         ground);
		vec3 l[3] = {v3(4, 3, 2), v3(1, -4, 4), v3(-3, 1, 5)};
		set_view(v, "spd-balls", v3(2.1f, 1.3f, 1.7f), v3(0, 0, 0), v3(0, 0, 1), 45, l, 3);
	} else if (!strcmp(o.name, "tetra")) {
		uint32_t m = mat(s, "tetra", v3(1.0f, 0.2f, 0.2f), v3(0, 0, 0), 1, 0, 0, 1);
		tetra(s, v3(0, 0, 0), 1.0f, o.size, m);
		vec3 l[1] = {v3(1.7f, -3.3f, 3.0f)};
		set_view(v, "spd-tetra", v3(1.1f, -3.2f, 1.8f), v3(0, 0, 0), v3(0, 0, 1), 45, l, 1);
	} else if (!strcmp(o.name, "mount")) {
		uint32_t rock = mat(s, "rock", v3(0.9f, 0.8f, 0.7f), v3(0, 0, 0), 1, 0, 0, 1);
		uint32_t glass =
		    mat(s, "glass", v3(1, 1, 1), v3(0.5f, 0.5f, 0.5f), 50, 0.1f, 0.85f, 1.5f);
		add_mountain(s, o.size, v3(-2, -1.5f, 0), v3(2, -1.5f, 0), v3(0, 2, 0), 0.9f, rock);
		vec3 c[4] = {v3(-0.7f, -0.9f, 0.9f), v3(0.6f, -0.7f, 1.0f), v3(0.0f, 0.3f, 1.3f),
		             v3(-0.2f, -1.3f, 0.5f)};
		for (int k = 0; k < 4; k++)
			spd_add_sphere(s, c[k], 0.25f, o.tess, glass);
		vec3 l[1] = {v3(-2.0f, -4.0f, 6.0f)};
		set_view(v, "spd-mount", v3(-0.3f, -5.2f, 1.6f), v3(0, 0, 0.6f), v3(0, 0, 1), 45, l,
		         1);
	} else if (!strcmp(o.name, "rings")) {
		uint32_t m =
		    mat(s, "ring", v3(0.9f, 0.3f, 0.3f), v3(0.6f, 0.6f, 0.6f), 40, 0.3f, 0, 1);
		uint32_t ground = mat(s, "ground", v3(0.6f, 0.6f, 0.75f), v3(0, 0, 0), 1, 0, 0, 1);
		int L = o.size;
		float span = 3.0f * (float)L;
		/* a grid of L x L pentagons of 5 interlocking tori each */
		for (int gx = 0; gx < L; gx++)
			for (int gy = 0; gy < L; gy++) {
				vec3 c0 = v3(3.0f * (float)gx - span / 2 + 1.5f,
				             3.0f * (float)gy - span / 2 + 1.5f, 0.6f);
				for (int k = 0; k < 5; k++) {
					float a = 2.0f * (float)M_PI * (float)k / 5.0f;
					vec3 c =
					    v3_add(c0, v3(0.8f * cosf(a), 0.8f * sinf(a), 0.0f));
					vec3 ax = v3_norm(v3(cosf(a), sinf(a), 0.6f));
					add_torus(s, c, ax, 0.5f, 0.1f, 2 * o.tess, o.tess / 2, m);
				}
			}
		add_quad(s, v3(-span, -span, 0), v3(span, -span, 0), v3(span, span, 0),
		         v3(-span, span, 0), ground);
		vec3 l[2] = {v3(span, -span, 2.0f * span), v3(-span, -0.5f * span, span)};
		set_view(v, "spd-rings", v3(0.9f * span, -1.3f * span, 0.9f * span), v3(0, 0, 0),
		         v3(0, 0, 1), 45, l, 2);
	} else if (!strcmp(o.name, "billiard")) {
		billiard(s, v, o.size, o.tess);
	} else { /* cornell: the Cornell box measurements (Cornell PCG) */
		uint32_t white = mat(s, "white", v3(0.73f, 0.73f, 0.73f), v3(0, 0, 0), 1, 0, 0, 1);
		uint32_t red = mat(s, "red", v3(0.65f, 0.05f, 0.05f), v3(0, 0, 0), 1, 0, 0, 1);
		uint32_t green = mat(s, "green", v3(0.12f, 0.45f, 0.15f), v3(0, 0, 0), 1, 0, 0, 1);
		static const float q[16][4][3] = {
		    {{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}}, /* floor */
		    {{556, 548.8f, 0},
		     {556, 548.8f, 559.2f},
		     {0, 548.8f, 559.2f},
		     {0, 548.8f, 0}}, /* ceiling */
		    {{549.6f, 0, 559.2f},
		     {0, 0, 559.2f},
		     {0, 548.8f, 559.2f},
		     {556, 548.8f, 559.2f}},                                          /* back */
		    {{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}}, /* green */
		    {{552.8f, 0, 0},
		     {549.6f, 0, 559.2f},
		     {556, 548.8f, 559.2f},
		     {556, 548.8f, 0}}, /* red */
		    {{343, 548.7f, 227},
		     {343, 548.7f, 332},
		     {213, 548.7f, 332},
		     {213, 548.7f, 227}},                                               /* light */
		    {{130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114}}, /* short */
		    {{290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272}},
		    {{130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114}},
		    {{82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65}},
		    {{240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225}},
		    {{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}}, /* tall */
		    {{423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406}},
		    {{472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456}},
		    {{314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296}},
		    {{265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247}},
		};
		for (int k = 0; k < 16; k++) {
			vec3 c[4];
			for (int i = 0; i < 4; i++)
				c[i] = v3(q[k][i][0], q[k][i][1], q[k][i][2]);
			add_quad(s, c[0], c[1], c[2], c[3], k == 3 ? green : k == 4 ? red : white);
		}
		vec3 l[1] = {v3(278, 540, 279.5f)};
		set_view(v, "spd-cornell", v3(278, 273, -800), v3(278, 273, -799), v3(0, 1, 0),
		         39.3f, l, 1);
	}
	return scene_finish(s, spec, d);
}
