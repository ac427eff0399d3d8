/*
 * scene.c: the scene builder and its invariants (see scene.h).
 *
 * Importers and generators append triangles one at a time; storage grows
 * geometrically, so building is amortised O(n). scene_finish() is the one
 * place the invariants are established, so every source of scenes gets the
 * same checks and the same error messages.
 */
#include "kernel-ref/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *xrealloc(void *p, size_t n)
{
	void *q = realloc(p, n);
	if (!q && n) {
		/* Out of memory while building a scene is not bad input; there is
		 * nothing sensible to continue with. The line says why (the
		 * importer process reports its memory limit on it). */
		fputs("scene: out of memory building the scene\n", stderr);
		abort();
	}
	return q;
}

void scene_init(scene *s, const char *name)
{
	memset(s, 0, sizeof *s);
	snprintf(s->name, sizeof s->name, "%s", name ? name : "");
	s->bounds = aabb_empty();
}

material material_default(const char *name)
{
	material m;
	memset(&m, 0, sizeof m);
	snprintf(m.name, sizeof m.name, "%s", name ? name : "default");
	m.kd = v3(0.7f, 0.7f, 0.7f);
	m.ka = m.kd;
	m.ns = 1.0f;
	m.ni = 1.0f;
	m.tex_kd = -1;
	m.tex_bump = -1;
	m.bump_scale = 1.0f;
	return m;
}

uint32_t scene_add_material(scene *s, const material *m)
{
	s->mats = xrealloc(s->mats, (s->nmats + 1) * sizeof *s->mats);
	s->mats[s->nmats] = *m;
	return s->nmats++;
}

void scene_add_triangle(scene *s, const vec3 p[3], const vec3 *n, const vec2 *uv, uint32_t mat)
{
	if (s->ntris == s->cap) {
		uint32_t cap = s->cap ? s->cap * 2 : 1024;
		s->v = xrealloc(s->v, (size_t)cap * 3 * sizeof *s->v);
		s->n = xrealloc(s->n, (size_t)cap * 3 * sizeof *s->n);
		s->uv = xrealloc(s->uv, (size_t)cap * 3 * sizeof *s->uv);
		s->mat = xrealloc(s->mat, (size_t)cap * sizeof *s->mat);
		s->cap = cap;
	}
	size_t k = 3 * (size_t)s->ntris;
	for (int i = 0; i < 3; i++) {
		s->v[k + i] = p[i];
		/* A zero normal marks "use the face normal" for scene_finish. */
		s->n[k + i] = n ? n[i] : v3(0, 0, 0);
		s->uv[k + i] = uv ? uv[i] : (vec2){0, 0};
	}
	if (uv)
		s->has_uv = 1;
	s->mat[s->ntris++] = mat;
}

int scene_finish(scene *s, const char *file, diag *d)
{
	if (s->ntris == 0)
		return diag_set(d, file, 0, 0, "scene has no triangles");
	if (s->nmats == 0) {
		material m = material_default("default");
		scene_add_material(s, &m);
	}
	s->bounds = aabb_empty();
	s->ndegenerate = 0;
	for (uint32_t t = 0; t < s->ntris; t++) {
		vec3 *p = s->v + 3 * (size_t)t;
		for (int i = 0; i < 3; i++) {
			if (!v3_finite(p[i]))
				return diag_set(
				    d, file, 0, 0,
				    "triangle %u has a NaN or infinite vertex coordinate", t);
			s->bounds = aabb_grow(s->bounds, p[i]);
		}
		vec3 fn = v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0]));
		float fl = v3_len(fn);
		if (!(fl > 0.0f))
			s->ndegenerate++;
		fn = fl > 0.0f ? v3_scale(fn, 1.0f / fl) : v3(0, 0, 1);
		vec3 *n = s->n + 3 * (size_t)t;
		for (int i = 0; i < 3; i++) {
			float l = v3_len(n[i]);
			/* Zero-length or non-finite normals are replaced by the face
			 * normal (documented in docs/views.md, "bad numbers"). */
			n[i] = (isfinite(l) && l > 0.0f) ? v3_scale(n[i], 1.0f / l) : fn;
		}
		vec2 *uv = s->uv + 3 * (size_t)t;
		for (int i = 0; i < 3; i++)
			if (!isfinite(uv[i].u) || !isfinite(uv[i].v))
				uv[i] = (vec2){0, 0};
		if (s->mat[t] >= s->nmats)
			s->mat[t] = 0;
	}
	for (uint32_t i = 0; i < s->nmats; i++) {
		material *m = &s->mats[i];
		if (m->tex_kd >= (int32_t)s->ntexs)
			m->tex_kd = -1;
		if (m->tex_bump >= (int32_t)s->ntexs)
			m->tex_bump = -1;
	}
	return 0;
}

void scene_free(scene *s)
{
	free(s->v);
	free(s->n);
	free(s->uv);
	free(s->mat);
	free(s->mats);
	for (uint32_t i = 0; s->texs && i < s->ntexs; i++)
		free(s->texs[i].rgba);
	free(s->texs);
	memset(s, 0, sizeof *s);
}
