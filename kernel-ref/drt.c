/*
 * drt.c: distribution ray tracing's parameters, area-light points and
 * glossy directions (see drt.h; seed 000 §3.2, §3.3).
 */
#include "kernel-ref/drt.h"

#include "kernel-ref/sudoku.h"

#include <stddef.h>

int drt_is_off(const drt_params *p)
{
	return drt_spp(p) == 1 && p->aperture == 0.0f && p->light_size == 0.0f &&
	       p->gloss == 0.0f && p->motion.x == 0.0f && p->motion.y == 0.0f &&
	       p->motion.z == 0.0f;
}

const char *drt_problem(const drt_params *p, const char **key)
{
	*key = "spp";
	if (!sudoku_spp_ok(drt_spp(p)) || p->spp < 0)
		return "spp must be 1, 4, 16 or 64";
	*key = "aperture";
	if (!(p->aperture >= 0.0f && p->aperture <= DRT_SIZE_MAX))
		return "aperture must be from 0 (a pinhole) to 1e9";
	*key = "focus";
	if (!(p->focus >= 0.0f && p->focus <= DRT_SIZE_MAX))
		return "focus must be from 0 (the lookat distance) to 1e9";
	*key = "light_size";
	if (!(p->light_size >= 0.0f && p->light_size <= DRT_SIZE_MAX))
		return "light_size must be from 0 (point lights) to 1e9";
	*key = "gloss";
	if (!(p->gloss == 0.0f || (p->gloss >= 1.0f && p->gloss <= DRT_GLOSS_MAX)))
		return "gloss must be 0 (a mirror) or a Phong exponent from 1 to 1e6";
	*key = "motion";
	if (!(v3_finite(p->motion) && v3_len(p->motion) <= DRT_SIZE_MAX))
		return "motion must be a finite displacement no longer than 1e9";
	return NULL;
}

void drt_shade_setup(drt_shade *s, const drt_params *p, vec3 up, uint32_t width)
{
	s->spp = drt_spp(p);
	s->width = width ? width : 1;
	s->gloss = p->gloss;
	vec3 n = v3_norm(up);
	/* any axis not parallel to up, then two edges across it */
	vec3 a = fabsf(n.x) < 0.9f ? v3(1, 0, 0) : v3(0, 1, 0);
	vec3 e1 = v3_norm(v3_cross(n, a)), e2 = v3_cross(n, e1);
	s->la = v3_scale(e1, p->light_size);
	s->lb = v3_scale(e2, p->light_size);
}

vec3 drt_light_point(const drt_shade *s, vec3 pos, uint32_t pixel, int sample, int l)
{
	float u, v;
	sudoku_sample(pixel % s->width, pixel / s->width, sample, SUDOKU_DIM_LIGHT + l, s->spp, &u,
	              &v);
	vec3 o = v3_add(v3_scale(s->la, u - 0.5f), v3_scale(s->lb, v - 0.5f));
	return drt_add3(pos, o);
}

vec3 drt_glossy_dir(vec3 r, float n, float u1, float u2)
{
	vec3 w = v3_norm(r);
	/* U = W x e0, or W x e1 when W is nearly e0 (seed §3.3) */
	vec3 uu = v3(0, w.z, -w.y);
	if (v3_len(uu) < 0.1f)
		uu = v3(-w.z, 0, w.x);
	uu = v3_norm(uu);
	vec3 vv = v3_cross(w, uu);
	float phi = 2.0f * (float)M_PI * u1;
	float ct = powf(u2, 1.0f / (n + 1.0f));
	float st = sqrtf(fmaxf(0.0f, 1.0f - ct * ct));
	return v3_add(v3_add(v3_scale(uu, cosf(phi) * st), v3_scale(vv, sinf(phi) * st)),
	              v3_scale(w, ct));
}
