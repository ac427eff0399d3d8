/*
 * default_scene.c: the embedded default scene and its view.
 *
 * A Cornell-like room (0..10 on every axis, +y up, open towards +z where the
 * camera stands) with a rotated diffuse box, a mirror sphere and a glass
 * sphere. Every corner is computed once and reused, so neighbouring
 * triangles share bit-identical vertices and rays cannot slip through
 * cracks; nothing is random, so the scene is the same on every run.
 */
#include "kernel-ref/scene.h"
#include "kernel-ref/view.h"

#include <math.h>
#include <stdio.h>

#define SPHERE_RINGS 20
#define SPHERE_SEGS  40

static const float PI = 3.14159265358979f;

/* Adds quad a-b-c-d as two triangles, wound so the face normal points along
 * `facing` (the builder derives face normals from the winding). */
static void quad(scene *s, vec3 a, vec3 b, vec3 c, vec3 d, vec3 facing, uint32_t mat)
{
	if (v3_dot(v3_cross(v3_sub(b, a), v3_sub(c, a)), facing) < 0) {
		vec3 t = b;
		b = d;
		d = t;
	}
	vec3 t1[3] = {a, b, c}, t2[3] = {a, c, d};
	scene_add_triangle(s, t1, NULL, NULL, mat);
	scene_add_triangle(s, t2, NULL, NULL, mat);
}

static uint32_t add_mat(scene *s, const char *name, vec3 kd, vec3 ks, float ns, float reflect,
                        float transmit, float ni)
{
	material m = material_default(name);
	m.kd = kd;
	m.ka = kd;
	m.ks = ks;
	m.ns = ns;
	m.reflect = reflect;
	m.transmit = transmit;
	m.ni = ni;
	return scene_add_material(s, &m);
}

/* Box of size (sx, sy, sz) standing on y = 0 at (cx, cz), turned by `deg`
 * about +y. The 8 corners are computed once and shared by all faces. */
static void box(scene *s, float cx, float cz, float sx, float sy, float sz, float deg, uint32_t mat)
{
	float c = cosf(deg * PI / 180.0f), sn = sinf(deg * PI / 180.0f);
	vec3 p[8];
	for (int i = 0; i < 8; i++) {
		float x = (i & 1 ? 0.5f : -0.5f) * sx, z = (i & 4 ? 0.5f : -0.5f) * sz;
		p[i] = v3(cx + c * x + sn * z, i & 2 ? sy : 0.0f, cz - sn * x + c * z);
	}
	vec3 mid = v3(cx, 0.5f * sy, cz);
	/* Corner index bits: 1 = +x, 2 = +y, 4 = +z (box space). */
	static const int faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 2, 6, 4},
	                                {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}};
	for (int f = 0; f < 6; f++) {
		const int *q = faces[f];
		vec3 centre =
		    v3_scale(v3_add(v3_add(p[q[0]], p[q[1]]), v3_add(p[q[2]], p[q[3]])), 0.25f);
		quad(s, p[q[0]], p[q[1]], p[q[2]], p[q[3]], v3_sub(centre, mid), mat);
	}
}

/* UV sphere with smooth normals. Grid points are computed once per (ring,
 * segment); the seam reuses segment 0 and the poles are single points, so
 * the mesh is closed. */
static void sphere(scene *s, vec3 c, float r, uint32_t mat)
{
	vec3 g[SPHERE_RINGS + 1][SPHERE_SEGS];
	for (int i = 0; i <= SPHERE_RINGS; i++) {
		float th = PI * (float)i / SPHERE_RINGS;
		for (int j = 0; j < SPHERE_SEGS; j++) {
			float ph = 2.0f * PI * (float)j / SPHERE_SEGS;
			/* Exact poles: sinf(PI) is not 0 in float. */
			float st = (i == 0 || i == SPHERE_RINGS) ? 0.0f : sinf(th);
			float ct = i == 0 ? 1.0f : i == SPHERE_RINGS ? -1.0f : cosf(th);
			g[i][j] = v3(st * cosf(ph), ct, st * sinf(ph));
		}
	}
	for (int i = 0; i < SPHERE_RINGS; i++) {
		for (int j = 0; j < SPHERE_SEGS; j++) {
			int k = (j + 1) % SPHERE_SEGS;
			vec3 n[4] = {g[i][j], g[i + 1][j], g[i + 1][k], g[i][k]};
			vec3 p[4];
			for (int q = 0; q < 4; q++)
				p[q] = v3_add(c, v3_scale(n[q], r));
			/* Outward winding: (p1-p0) x (p2-p0) along the normal. */
			if (i != SPHERE_RINGS - 1) {
				vec3 tp[3] = {p[0], p[2], p[1]}, tn[3] = {n[0], n[2], n[1]};
				scene_add_triangle(s, tp, tn, NULL, mat);
			}
			if (i != 0) {
				vec3 tp[3] = {p[0], p[3], p[2]}, tn[3] = {n[0], n[3], n[2]};
				scene_add_triangle(s, tp, tn, NULL, mat);
			}
		}
	}
}

void scene_default(scene *s)
{
	scene_init(s, "embedded:cornell");
	uint32_t white = add_mat(s, "white", v3(0.73f, 0.73f, 0.73f), v3(0, 0, 0), 1, 0, 0, 1);
	uint32_t red = add_mat(s, "red", v3(0.63f, 0.065f, 0.05f), v3(0, 0, 0), 1, 0, 0, 1);
	uint32_t green = add_mat(s, "green", v3(0.14f, 0.45f, 0.091f), v3(0, 0, 0), 1, 0, 0, 1);
	uint32_t boxm = add_mat(s, "box", v3(0.75f, 0.72f, 0.65f), v3(0, 0, 0), 1, 0, 0, 1);
	uint32_t mirror =
	    add_mat(s, "mirror", v3(0.05f, 0.05f, 0.05f), v3(0.9f, 0.9f, 0.9f), 200, 0.8f, 0, 1);
	uint32_t glass =
	    add_mat(s, "glass", v3(0, 0, 0), v3(0.1f, 0.1f, 0.1f), 200, 0.1f, 0.9f, 1.5f);

	/* Room corners: bit 1 = x 10, bit 2 = y 10, bit 4 = z 10. */
	vec3 r[8];
	for (int i = 0; i < 8; i++)
		r[i] = v3(i & 1 ? 10.0f : 0.0f, i & 2 ? 10.0f : 0.0f, i & 4 ? 10.0f : 0.0f);
	quad(s, r[0], r[1], r[5], r[4], v3(0, 1, 0), white);  /* floor */
	quad(s, r[2], r[3], r[7], r[6], v3(0, -1, 0), white); /* ceiling */
	quad(s, r[0], r[1], r[3], r[2], v3(0, 0, 1), white);  /* back wall */
	quad(s, r[0], r[2], r[6], r[4], v3(1, 0, 0), red);    /* left wall */
	quad(s, r[1], r[3], r[7], r[5], v3(-1, 0, 0), green); /* right wall */

	box(s, 3.0f, 3.0f, 2.8f, 6.0f, 2.8f, 18.0f, boxm);
	sphere(s, v3(7.0f, 1.61f, 3.2f), 1.6f, mirror);
	sphere(s, v3(5.2f, 1.51f, 7.0f), 1.5f, glass);

	/* Built from constants: scene_finish cannot fail here. */
	scene_finish(s, s->name, NULL);
}

void view_default(view *v)
{
	*v = (view){0};
	snprintf(v->name, sizeof v->name, "default");
	v->cam.eye = v3(5.0f, 5.0f, 22.0f);
	v->cam.lookat = v3(5.0f, 5.0f, 0.0f);
	v->cam.up = v3(0, 1, 0);
	v->cam.fov_deg = 45.0f;
	/* Two lights under the ceiling at half strength each, so together
	 * they light the room like one white light. */
	v->lights_given = 1;
	v->nlights = 2;
	v->lights[0] = (light){v3(3.5f, 9.5f, 4.5f), v3(0.5f, 0.5f, 0.5f)};
	v->lights[1] = (light){v3(6.5f, 9.5f, 5.5f), v3(0.5f, 0.5f, 0.5f)};
}
