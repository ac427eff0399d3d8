/*
 * stress.c: numerical stress cases for kernel-ref (see stress.h).
 *
 * Each case builds its scene in code, so it needs no files and runs the
 * same everywhere; the counts it returns are the ones docs/NUMERICS.md
 * reports and tests/test_stress.c requires to be zero.
 */
#include "kernel-ref/stress.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "kernel-ref/camera.h"
#include "kernel-ref/isect.h"
#include "kernel-ref/render.h"
#include "kernel-ref/spd.h"
#include "kernel-ref/world.h"

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* Builds tree and image for w->s (already finished) and sets a view. */
static void build(world *w, const kd_params *kp)
{
	kd_params def;
	kd_params_default(&def);
	diag d;
	if (kd_build(&w->kd, &w->s, kp ? kp : &def, &d) || mimg_build(&w->m, &w->s, &w->kd, &d)) {
		fprintf(stderr, "stress: %s\n", d.msg);
		abort(); /* scenes built here are valid by construction */
	}
}

static void one_material(scene *s)
{
	material m = material_default("stress");
	scene_add_material(s, &m);
}

typedef struct tracer {
	trav_entry stack[PKT_STACK_MAX];
	packet p;
} tracer;

/* Traces n arbitrary rays in packets of 64 and, for each, also the
 * single-ray path; returns misses and counts packet/single mismatches. */
static uint64_t trace_rays(const world *w, const vec3 *o, const vec3 *d, size_t n, tracer *t,
                           uint64_t *mismatch, const pkt_precision *prec)
{
	uint64_t miss = 0;
	for (size_t base = 0; base < n; base += PKT_RAYS) {
		pkt_clear(&t->p, PKT_PRIMARY, 0);
		for (size_t k = 0; k < PKT_RAYS && base + k < n; k++) {
			t->p.ox[k] = o[base + k].x;
			t->p.oy[k] = o[base + k].y;
			t->p.oz[k] = o[base + k].z;
			t->p.dx[k] = d[base + k].x;
			t->p.dy[k] = d[base + k].y;
			t->p.dz[k] = d[base + k].z;
			t->p.tmax[k] = INFINITY;
			t->p.valid |= 1ull << k;
		}
		t->p.n = PKT_RAYS;
		pkt_trace_fp(&t->p, &w->m, t->stack, PKT_STACK_MAX, NULL, prec);
		for (size_t k = 0; k < PKT_RAYS && base + k < n; k++) {
			ray_hit h =
			    ray_trace_fp(&w->m, o[base + k], d[base + k], INFINITY, 0, NULL, prec);
			miss += t->p.tri[k] == PKT_NOHIT;
			*mismatch +=
			    h.tri != t->p.tri[k] || (h.tri != PKT_NOHIT && h.t != t->p.t[k]);
		}
	}
	return miss;
}

static vec3 dir_of(double az, double el)
{
	return v3((float)(cos(el) * cos(az)), (float)(cos(el) * sin(az)), (float)sin(el));
}

/* ---- closed sphere --------------------------------------------------------- */

static void sphere_world(world *w, double scale, double offset)
{
	memset(w, 0, sizeof *w);
	scene_init(&w->s, "stress:sphere");
	one_material(&w->s);
	vec3 c = v3((float)offset, (float)(offset / 2), (float)(-offset / 3));
	spd_add_sphere(&w->s, c, (float)scale, 48, 0);
	diag d;
	if (scene_finish(&w->s, "stress", &d))
		abort();
	build(w, NULL);
}

stress_result stress_sphere(double scale, double offset, int res)
{
	return stress_sphere_fp(scale, offset, res, NULL);
}

stress_result stress_sphere_fp(double scale, double offset, int res, const pkt_precision *prec)
{
	stress_result r = {{0}, 0, 0, 0, 0, 0, 0, 0, 0};
	snprintf(r.name, sizeof r.name, "closed sphere, radius %g, centre at %g", scale, offset);
	r.measured = ST_LEAK | ST_MISMATCH;
	double t0 = now_ms();
	world w;
	sphere_world(&w, scale, offset);
	vec3 c = v3((float)offset, (float)(offset / 2), (float)(-offset / 3));
	size_t n = (size_t)res * (size_t)res;
	vec3 *o = malloc(sizeof *o * n), *d = malloc(sizeof *d * n);
	tracer *t = aligned_alloc(64, (sizeof(tracer) + 63) & ~(size_t)63);
	/* inside: from near the centre in all directions */
	for (size_t k = 0; k < n; k++) {
		o[k] = v3_add(c, v3_scale(v3(0.013f, -0.021f, 0.007f), (float)scale));
		d[k] = dir_of(2 * M_PI * (double)(k % (size_t)res) / res + 0.01,
		              M_PI * ((double)(k / (size_t)res) + 0.5) / res - M_PI / 2);
	}
	r.leaked += trace_rays(&w, o, d, n, t, &r.mismatch, prec);
	r.rays += n;
	/* outside: a camera 4 radii away; every hit continued past the surface
	 * must hit the far side */
	camera cam = {v3_add(c, v3_scale(v3(1.2f, 1.6f, 3.4f), (float)scale)), c, v3(0, 0, 1),
	              40.0f};
	cam_frame cf;
	cam_setup(&cf, &cam, res, res);
	size_t m = 0;
	for (int ty = 0; ty < res / 8; ty++)
		for (int tx = 0; tx < res / 8; tx++) {
			cam_primary_packet(&cf, tx, ty, &t->p);
			pkt_trace_fp(&t->p, &w.m, t->stack, PKT_STACK_MAX, NULL, prec);
			r.rays += (uint64_t)__builtin_popcountll(t->p.valid);
			for (uint64_t b = t->p.valid; b; b &= b - 1) {
				int i = __builtin_ctzll(b);
				if (t->p.tri[i] == PKT_NOHIT)
					continue;
				float tt = nextafterf(t->p.t[i], INFINITY);
				vec3 po = v3(t->p.ox[i], t->p.oy[i], t->p.oz[i]);
				vec3 pd = v3(t->p.dx[i], t->p.dy[i], t->p.dz[i]);
				/* The continuation origin po + t pd is rounded to float:
				 * judge only rays whose chord through the inscribed
				 * sphere is long against that rounding (near the
				 * silhouette the origin may land beyond the exit). */
				double oc[3] = {(double)c.x - po.x, (double)c.y - po.y,
				                (double)c.z - po.z};
				double dl = sqrt((double)pd.x * pd.x + (double)pd.y * pd.y +
				                 (double)pd.z * pd.z);
				double along = (oc[0] * pd.x + oc[1] * pd.y + oc[2] * pd.z) / dl;
				double h2 =
				    oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - along * along;
				double rin = scale * cos(M_PI / 48) * cos(M_PI / 24);
				double far = fabs(offset) + scale;
				double margin = 16.0 * far * 0x1p-24;
				if (rin * rin - h2 < margin * margin) {
					r.ties++; /* too shallow to judge at this precision */
					continue;
				}
				o[m] = v3_add(po, v3_scale(pd, tt));
				d[m++] = pd;
			}
		}
	r.leaked += trace_rays(&w, o, d, m, t, &r.mismatch, prec);
	r.rays += m;
	free(o);
	free(d);
	free(t);
	world_free(&w);
	r.ms = now_ms() - t0;
	return r;
}

/* Is q inside the tetrahedron whose 4 triangles start at c (12 corners),
 * farther than a few float steps from every face? Computed in double. */
static int inside_tetra(const vec3 *c, vec3 q)
{
	for (int f = 0; f < 4; f++) {
		const vec3 *t = c + 3 * f;
		double e1[3] = {(double)t[1].x - t[0].x, (double)t[1].y - t[0].y,
		                (double)t[1].z - t[0].z};
		double e2[3] = {(double)t[2].x - t[0].x, (double)t[2].y - t[0].y,
		                (double)t[2].z - t[0].z};
		double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
		               e1[0] * e2[1] - e1[1] * e2[0]};
		double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
		if (!(nl > 0))
			return 0;
		/* the opposite corner tells which side is inside */
		const vec3 *o = c + 3 * ((f + 1) % 4);
		vec3 opp = o[0];
		for (int k = 0; k < 3; k++)
			if (memcmp(&o[k], &t[0], sizeof(vec3)) &&
			    memcmp(&o[k], &t[1], sizeof(vec3)) &&
			    memcmp(&o[k], &t[2], sizeof(vec3)))
				opp = o[k];
		double so = (n[0] * ((double)opp.x - t[0].x) + n[1] * ((double)opp.y - t[0].y) +
		             n[2] * ((double)opp.z - t[0].z)) /
		            nl;
		double sq = (n[0] * ((double)q.x - t[0].x) + n[1] * ((double)q.y - t[0].y) +
		             n[2] * ((double)q.z - t[0].z)) /
		            nl;
		double scale = fmax(fabs((double)q.x), fmax(fabs((double)q.y), fabs((double)q.z)));
		double margin = 4.0 * scale * 0x1p-24;
		if (!(so * sq > 0) || fabs(sq) < margin)
			return 0;
	}
	return 1;
}

stress_result stress_spd_tetra(double scale, double offset, int res)
{
	stress_result r = {{0}, 0, 0, 0, 0, 0, 0, 0, ST_LEAK | ST_MISMATCH};
	snprintf(r.name, sizeof r.name, "SPD tetra (closed tetrahedra), scale %g, moved to %g",
	         scale, offset);
	double t0 = now_ms();
	world w;
	memset(&w, 0, sizeof w);
	view sv;
	diag d;
	if (spd_generate(&w.s, &sv, "spd:tetra:4", &d))
		abort();
	vec3 off = v3((float)offset, (float)(offset / 2), (float)(-offset / 3));
	for (uint32_t k = 0; k < 3 * w.s.ntris; k++)
		w.s.v[k] = v3_add(v3_scale(w.s.v[k], (float)scale), off);
	if (scene_finish(&w.s, "stress", &d))
		abort();
	build(&w, NULL);
	camera cam = {v3_add(v3_scale(sv.cam.eye, (float)scale), off),
	              v3_add(v3_scale(sv.cam.lookat, (float)scale), off), sv.cam.up,
	              sv.cam.fov_deg};
	cam_frame cf;
	cam_setup(&cf, &cam, res, res);
	size_t n = (size_t)res * (size_t)res;
	vec3 *o = malloc(sizeof *o * n), *dd = malloc(sizeof *dd * n);
	tracer *t = aligned_alloc(64, (sizeof(tracer) + 63) & ~(size_t)63);
	size_t m = 0;
	for (int ty = 0; ty < res / 8; ty++)
		for (int tx = 0; tx < res / 8; tx++) {
			cam_primary_packet(&cf, tx, ty, &t->p);
			pkt_trace(&t->p, &w.m, t->stack, PKT_STACK_MAX, NULL);
			r.rays += (uint64_t)__builtin_popcountll(t->p.valid);
			for (uint64_t b = t->p.valid; b; b &= b - 1) {
				int i = __builtin_ctzll(b);
				if (t->p.tri[i] == PKT_NOHIT)
					continue;
				vec3 po = v3(t->p.ox[i], t->p.oy[i], t->p.oz[i]);
				vec3 pd = v3(t->p.dx[i], t->p.dy[i], t->p.dz[i]);
				/* step 16 float spacings of the hit point's magnitude past
				 * the entry (pd is unit length), so that q can be judged
				 * inside by the margin below */
				vec3 hp = v3_add(po, v3_scale(pd, t->p.t[i]));
				float mag = fmaxf(fabsf(hp.x), fmaxf(fabsf(hp.y), fabsf(hp.z)));
				vec3 q =
				    v3_add(po, v3_scale(pd, t->p.t[i] + 16.0f * mag * 0x1p-24f));
				/* judge only if the (rounded) continuation origin lies
				 * inside the tetrahedron it entered, by a margin, in
				 * double: spd.c emits 4 triangles per tetrahedron */
				uint32_t tet = mimg_tri_index(&w.m, t->p.tri[i]) / 4;
				if (!inside_tetra(w.s.v + 12 * (size_t)tet, q)) {
					r.ties++;
					continue;
				}
				o[m] = q;
				dd[m++] = pd;
			}
		}
	r.leaked += trace_rays(&w, o, dd, m, t, &r.mismatch, NULL);
	r.rays += m;
	free(o);
	free(dd);
	free(t);
	world_free(&w);
	r.ms = now_ms() - t0;
	return r;
}

stress_result stress_acne(double scale, double offset, int res)
{
	stress_result r = {{0}, 0, 0, 0, 0, 0, 0, 0, 0};
	snprintf(r.name, sizeof r.name, "shadow acne, sphere radius %g at %g", scale, offset);
	r.measured = ST_ACNE;
	double t0 = now_ms();
	world w;
	sphere_world(&w, scale, offset);
	vec3 c = v3((float)offset, (float)(offset / 2), (float)(-offset / 3));
	w.v.cam = (camera){v3_add(c, v3_scale(v3(1.2f, 1.6f, 3.4f), (float)scale)), c, v3(0, 0, 1),
	                   40.0f};
	w.v.nlights = 1;
	w.v.lights[0] = (light){v3_add(c, v3_scale(v3(6, 7, 10), (float)scale)), v3(1, 1, 1)};
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = res;
	ro.max_depth = 0;
	framebuf fb;
	render_stats st;
	diag d;
	if (fb_init(&fb, res, res) || render_frame(&w.m, &w.v, &ro, &fb, &st, &d))
		abort();
	r.rays = st.rays[PKT_SHADOW];
	r.acne = st.shade.shadow_hits;
	fb_free(&fb);
	world_free(&w);
	r.ms = now_ms() - t0;
	return r;
}

/* ---- vertices, edges, flat cells ---------------------------------------------- */

static void grid_world(world *w, int n, const kd_params *kp)
{
	memset(w, 0, sizeof *w);
	scene_init(&w->s, "stress:grid");
	one_material(&w->s);
	for (int i = 0; i < n; i++)
		for (int j = 0; j < n; j++) {
			vec3 a = v3((float)i, (float)j, 0), b = v3((float)i + 1, (float)j, 0);
			vec3 c = v3((float)i + 1, (float)j + 1, 0),
			     e = v3((float)i, (float)j + 1, 0);
			vec3 t0[3] = {a, b, c}, t1[3] = {a, c, e};
			scene_add_triangle(&w->s, t0, NULL, NULL, 0);
			scene_add_triangle(&w->s, t1, NULL, NULL, 0);
		}
	/* a fan of 12 triangles around (n/2 + 0.5, n/2 + 0.5, 1) */
	vec3 fc = v3((float)n / 2 + 0.5f, (float)n / 2 + 0.5f, 1);
	for (int k = 0; k < 12; k++) {
		double a0 = 2 * M_PI * k / 12, a1 = 2 * M_PI * (k + 1) / 12;
		vec3 t[3] = {fc, v3_add(fc, v3((float)(0.4 * cos(a0)), (float)(0.4 * sin(a0)), 0)),
		             v3_add(fc, v3((float)(0.4 * cos(a1)), (float)(0.4 * sin(a1)), 0))};
		if (k == 11) /* close the fan exactly on its first spoke */
			t[2] = v3_add(fc, v3(0.4f, 0.0f, 0));
		scene_add_triangle(&w->s, t, NULL, NULL, 0);
	}
	diag d;
	if (scene_finish(&w->s, "stress", &d))
		abort();
	build(w, kp);
}

/* The end of a ray-list case: traces the m rays (packets and single
 * rays), counts misses as leaks and path mismatches, frees everything. */
static void finish_rays(stress_result *r, world *w, vec3 *o, vec3 *d, size_t m, double t0)
{
	tracer *t = aligned_alloc(64, (sizeof(tracer) + 63) & ~(size_t)63);
	r->measured = ST_LEAK | ST_MISMATCH;
	r->leaked = trace_rays(w, o, d, m, t, &r->mismatch, NULL);
	r->rays = m;
	free(t);
	free(o);
	free(d);
	world_free(w);
	r->ms = now_ms() - t0;
}

stress_result stress_vertices_edges(int n)
{
	stress_result r = {{0}, 0, 0, 0, 0, 0, 0, 0, 0};
	snprintf(r.name, sizeof r.name,
	         "rays at shared vertices and edges (%dx%d strip grid, 12-fan)", n, n);
	double t0 = now_ms();
	world w;
	grid_world(&w, n, NULL);
	size_t cap = (size_t)(n + 1) * (size_t)(n + 1) * 3 + 64;
	vec3 *o = malloc(sizeof *o * cap), *d = malloc(sizeof *d * cap);
	size_t m = 0;
	for (int i = 0; i <= n; i++)
		for (int j = 0; j <= n; j++) {
			/* interior vertices, edge midpoints and diagonal midpoints */
			vec3 targets[3] = {v3((float)i, (float)j, 0),
			                   v3((float)i + 0.5f, (float)j, 0),
			                   v3((float)i + 0.5f, (float)j + 0.5f, 0)};
			for (int k = 0; k < 3; k++) {
				vec3 q = targets[k];
				if (q.x <= 0 || q.y <= 0 || q.x >= (float)n || q.y >= (float)n)
					continue; /* the outer border is not shared */
				o[m] = v3_add(q, v3(0.37f, -0.21f, 3.0f));
				d[m] = v3_sub(q, o[m]);
				m++;
			}
		}
	vec3 fc = v3((float)n / 2 + 0.5f, (float)n / 2 + 0.5f, 1);
	for (int k = 0; k < 64 && m < cap; k++) {
		o[m] = v3_add(fc, v3_scale(dir_of(0.1 * k, 0.3 + 0.02 * k), 2.0f));
		d[m] = v3_sub(fc, o[m]);
		m++;
	}
	finish_rays(&r, &w, o, d, m, t0);
	return r;
}

stress_result stress_flat_axis_parallel(int n)
{
	stress_result r = {{0}, 0, 0, 0, 0, 0, 0, 0, 0};
	snprintf(r.name, sizeof r.name, "flat %dx%d grid, axis-parallel rays with +0/-0 components",
	         n, n);
	double t0 = now_ms();
	world w;
	grid_world(&w, n, NULL);
	size_t cap = (size_t)(2 * n) * (size_t)(2 * n) * 8;
	vec3 *o = malloc(sizeof *o * cap), *d = malloc(sizeof *d * cap);
	size_t m = 0;
	for (int i = 1; i < 2 * n; i++)
		for (int j = 1; j < 2 * n; j++) {
			float x = 0.5f * (float)i, y = 0.5f * (float)j;
			if (fabsf(x - ((float)n / 2 + 0.5f)) < 0.5f &&
			    fabsf(y - ((float)n / 2 + 0.5f)) < 0.5f)
				continue; /* under the fan: would hit it first, not a leak */
			for (int s = 0; s < 4; s++) {
				float dx = (s & 1) ? -0.0f : 0.0f, dy = (s & 2) ? -0.0f : 0.0f;
				o[m] = v3(x, y, 2.0f);
				d[m++] = v3(dx, dy, -1.0f);
				o[m] = v3(x, y, -2.0f);
				d[m++] = v3(dx, dy, 1.0f);
			}
		}
	finish_rays(&r, &w, o, d, m, t0);
	return r;
}

/* ---- degenerate and duplicate geometry, deep trees -------------------------- */

stress_result stress_degenerate(int res)
{
	stress_result r = {{0}, 0, 0, 0, 0, 0, 0, 0, 0};
	snprintf(r.name, sizeof r.name, "degenerate, sliver, duplicate, coplanar; depth-60 tree");
	r.measured = ST_LEAK | ST_MISMATCH;
	double t0 = now_ms();
	world w;
	memset(&w, 0, sizeof w);
	scene_init(&w.s, "stress:degenerate");
	material a = material_default("a"), b = material_default("b");
	b.kd = v3(0.2f, 0.8f, 0.3f);
	b.reflect = 0.5f;
	scene_add_material(&w.s, &a);
	scene_add_material(&w.s, &b);
	/* background box (closed) */
	spd_add_sphere(&w.s, v3(0, 0, 0), 20.0f, 24, 0);
	for (int k = 0; k < 200; k++) {
		float x = (float)(k % 20) - 10.0f, y = (float)(k / 20) - 5.0f;
		vec3 p0 = v3(x, y, 0), p1 = v3(x + 0.9f, y, 0.1f), p2 = v3(x, y + 0.9f, 0.2f);
		vec3 t[3];
		switch (k % 5) {
		case 0: /* zero area: two equal corners */
			t[0] = p0, t[1] = p0, t[2] = p2;
			break;
		case 1: /* collinear */
			t[0] = p0, t[1] = v3_add(p0, v3(0.5f, 0.5f, 0)),
			t[2] = v3_add(p0, v3(1, 1, 0));
			break;
		case 2: /* sliver, 1e-6 wide */
			t[0] = p0, t[1] = p1, t[2] = v3_add(p0, v3(0.9f, 1e-6f, 0.1f));
			break;
		default: /* an ordinary one, duplicated with reversed winding (and a
		          * coplanar overlapping twin of another material) */
			t[0] = p0, t[1] = p1, t[2] = p2;
			break;
		}
		scene_add_triangle(&w.s, t, NULL, NULL, 0);
		if (k % 5 >= 3) {
			vec3 rev[3] = {t[0], t[2], t[1]};
			scene_add_triangle(&w.s, rev, NULL, NULL, 1);
			vec3 ov[3] = {v3_add(p0, v3(0.3f, 0.3f, 0.1f)),
			              v3_add(p1, v3(0.3f, 0.3f, 0.1f)),
			              v3_add(p2, v3(0.3f, 0.3f, 0.1f))};
			scene_add_triangle(&w.s, ov, NULL, NULL, 1);
		}
	}
	diag d;
	if (scene_finish(&w.s, "stress", &d))
		abort();
	kd_params kp;
	kd_params_default(&kp);
	kp.max_depth = 60;
	kp.leaf_size = 1;
	kp.cost_isect = 50.0f; /* splitting pays: a deep tree */
	build(&w, &kp);
	w.v.cam = (camera){v3(2, -14, 9), v3(0, 0, 0), v3(0, 0, 1), 60.0f};
	w.v.nlights = 1;
	w.v.lights[0] = (light){v3(3, -4, 12), v3(1, 1, 1)};
	/* packet == single ray on all primary rays, including grazing ones */
	cam_frame cf;
	cam_setup(&cf, &w.v.cam, res, res);
	tracer *t = aligned_alloc(64, (sizeof(tracer) + 63) & ~(size_t)63);
	for (int ty = 0; ty < res / 8; ty++)
		for (int tx = 0; tx < res / 8; tx++) {
			cam_primary_packet(&cf, tx, ty, &t->p);
			pkt_trace(&t->p, &w.m, t->stack, PKT_STACK_MAX, NULL);
			for (uint64_t bb = t->p.valid; bb; bb &= bb - 1) {
				int i = __builtin_ctzll(bb);
				ray_hit h = ray_trace(&w.m, v3(t->p.ox[i], t->p.oy[i], t->p.oz[i]),
				                      v3(t->p.dx[i], t->p.dy[i], t->p.dz[i]),
				                      INFINITY, 0, NULL);
				r.mismatch += h.tri != t->p.tri[i];
				r.leaked +=
				    h.tri == PKT_NOHIT; /* everything is inside the sphere */
				r.rays++;
			}
		}
	free(t);
	/* the same frame for 1, 2 and 5 host threads */
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = res;
	ro.max_depth = 2;
	framebuf fb[3];
	render_stats st;
	int threads[3] = {1, 2, 5};
	for (int k = 0; k < 3; k++) {
		ro.threads = threads[k];
		if (fb_init(&fb[k], res, res) || render_frame(&w.m, &w.v, &ro, &fb[k], &st, &d))
			abort();
	}
	size_t bytes = (size_t)res * (size_t)res * 3 * sizeof(uint64_t);
	r.mismatch += memcmp(fb[0].acc, fb[1].acc, bytes) != 0;
	r.mismatch += memcmp(fb[0].acc, fb[2].acc, bytes) != 0;
	for (int k = 0; k < 3; k++)
		fb_free(&fb[k]);
	world_free(&w);
	r.ms = now_ms() - t0;
	return r;
}

/* ---- random rays against random triangles, against double precision ---------- */

static uint64_t lcg(uint64_t *s)
{
	*s = *s * 6364136223846793005ull + 1442695040888963407ull;
	return *s >> 11;
}
static double urand(uint64_t *s)
{
	return (double)lcg(s) / (double)(1ull << 53) * 2.0 - 1.0;
}

/* The reference: Moller-Trumbore in double. Returns 1 on a hit with t > 0,
 * and the smallest |barycentric| in *edge (how close to an edge it is). */
static int ref_hit(const double o[3], const double d[3], const double v[3][3], double *t,
                   double *edge)
{
	double e1[3], e2[3], p[3], q[3], s[3];
	for (int k = 0; k < 3; k++) {
		e1[k] = v[1][k] - v[0][k];
		e2[k] = v[2][k] - v[0][k];
		s[k] = o[k] - v[0][k];
	}
	p[0] = d[1] * e2[2] - d[2] * e2[1];
	p[1] = d[2] * e2[0] - d[0] * e2[2];
	p[2] = d[0] * e2[1] - d[1] * e2[0];
	double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
	if (det == 0)
		return 0;
	double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
	q[0] = s[1] * e1[2] - s[2] * e1[1];
	q[1] = s[2] * e1[0] - s[0] * e1[2];
	q[2] = s[0] * e1[1] - s[1] * e1[0];
	double vv = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
	*t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
	*edge = fmin(fabs(u), fmin(fabs(vv), fabs(1 - u - vv)));
	return u >= 0 && vv >= 0 && u + vv <= 1 && *t > 0;
}

stress_result stress_random(uint64_t n, uint32_t seed)
{
	stress_result r = {{0}, 0, 0, 0, 0, 0, 0, 0, 0};
	snprintf(r.name, sizeof r.name, "random rays x random triangles vs double precision");
	r.measured = ST_DISAGREE;
	double t0 = now_ms();
	uint64_t s = seed;
	for (uint64_t k = 0; k < n; k++) {
		float v[3][3];
		double vd[3][3], od[3], dd[3];
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 3; j++)
				vd[i][j] = v[i][j] = (float)urand(&s);
		/* three draws in a fixed order (a call's arguments are taken in
		 * an order C leaves open: gcc took these last to first, clang
		 * first to last, and the two built other rays) */
		float oz = (float)(2 * urand(&s));
		float oy = (float)(2 * urand(&s));
		float ox = (float)(2 * urand(&s));
		vec3 o = v3(ox, oy, oz);
		/* aim at a random point near the triangle so about half hit */
		double b1 = (urand(&s) + 1) * 0.6, b2 = (urand(&s) + 1) * 0.6;
		vec3 tgt =
		    v3((float)(vd[0][0] + b1 * (vd[1][0] - vd[0][0]) + b2 * (vd[2][0] - vd[0][0])),
		       (float)(vd[0][1] + b1 * (vd[1][1] - vd[0][1]) + b2 * (vd[2][1] - vd[0][1])),
		       (float)(vd[0][2] + b1 * (vd[1][2] - vd[0][2]) + b2 * (vd[2][2] - vd[0][2])));
		vec3 d = v3_sub(tgt, o);
		od[0] = o.x, od[1] = o.y, od[2] = o.z;
		dd[0] = d.x, dd[1] = d.y, dd[2] = d.z;
		isect_ray ir = isect_prepare(d);
		float t = 0, bu, bv;
		int hf = isect_tri(&ir, o, (const float(*)[3])v, &t, &bu, &bv);
		double tr = 0, edge = 1;
		int hd = ref_hit(od, dd, (const double(*)[3])vd, &tr, &edge);
		r.rays++;
		/* within rounding of an edge, or at t ~ 0, either answer is right */
		int tie = edge < 1e-5 || (hd && tr < 1e-5);
		/* t's rounding error grows as 1/cos(incidence): a grazing ray's t
		 * may differ by that much and still be the right hit */
		double e1[3], e2[3], nn[3];
		for (int a = 0; a < 3; a++) {
			e1[a] = vd[1][a] - vd[0][a];
			e2[a] = vd[2][a] - vd[0][a];
		}
		nn[0] = e1[1] * e2[2] - e1[2] * e2[1];
		nn[1] = e1[2] * e2[0] - e1[0] * e2[2];
		nn[2] = e1[0] * e2[1] - e1[1] * e2[0];
		double cosi = fabs(nn[0] * dd[0] + nn[1] * dd[1] + nn[2] * dd[2]) /
		              (sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]) *
		                   sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]) +
		               1e-300);
		double tol = 1e-5 * (1 + fabs(tr)) / fmax(cosi, 1e-9);
		/* within 1e-4 of parallel to the plane the hit point is not
		 * resolvable in single precision: the conservative t > deltaT
		 * test may reject such a hit (a tie, counted apart) */
		tie |= cosi < 1e-4;
		if (hf != hd || (hf && fabs(t - tr) > tol)) {
			if (tie)
				r.ties++;
			else {
				r.disagree++;
				if (getenv("SAAR_STRESS_DEBUG"))
					fprintf(stderr,
					        "disagree: cos %.3g float hit %d t %.9g, double "
					        "hit %d t "
					        "%.9g edge %.3g; "
					        "tri (%a %a %a) (%a %a %a) (%a %a %a) o (%a %a %a) "
					        "d (%a %a %a)\n",
					        cosi, hf, t, hd, tr, edge, v[0][0], v[0][1],
					        v[0][2], v[1][0], v[1][1], v[1][2], v[2][0],
					        v[2][1], v[2][2], o.x, o.y, o.z, d.x, d.y, d.z);
			}
		}
	}
	r.ms = now_ms() - t0;
	return r;
}
