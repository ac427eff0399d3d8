/*
 * isect.h: the watertight ray/triangle test (Woop, Benthin, Wald, JCGT
 * 2013), on the 36-byte triangle record, shared by the packet path, the
 * single-ray path and the chip model's intersection unit.
 *
 * The ray is transformed so that it runs along +z from the origin (axis
 * permutation kx,ky,kz with kz the dominant direction axis, then a shear);
 * the 2D edge functions U,V,W of the sheared triangle decide the hit. When
 * an edge function is exactly zero (ray through an edge or vertex) it is
 * recomputed in double precision, which makes the test watertight: a ray
 * through a shared edge hits at least one of the two triangles.
 *
 * Every step uses the same operations in the same order in the scalar and
 * the SIMD form (no FMA contraction: the Makefile passes -ffp-contract=off),
 * so both produce bit-identical t and barycentrics.
 */
#ifndef SAAR_KREF_ISECT_H
#define SAAR_KREF_ISECT_H

#include "vecmath.h"

/* gamma(n) = n u / (1 - n u), u = 2^-24: the relative error bound of n
 * chained float roundings (pbrt, "Floating-Point Error"). */
#define ISECT_GAMMA(n) ((float)(n)*0x1p-24f / (1.0f - (float)(n)*0x1p-24f))

/* Per-ray constants of the test. */
typedef struct isect_ray {
	int kx, ky, kz;
	float sx, sy, sz;
} isect_ray;

static inline isect_ray isect_prepare(vec3 d)
{
	isect_ray r;
	float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
	r.kz = (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
	r.kx = r.kz == 2 ? 0 : r.kz + 1;
	r.ky = r.kx == 2 ? 0 : r.kx + 1;
	if (v3_get(d, r.kz) < 0.0f) {
		int t = r.kx;
		r.kx = r.ky;
		r.ky = t;
	}
	float dz = v3_get(d, r.kz);
	r.sx = v3_get(d, r.kx) / dz;
	r.sy = v3_get(d, r.ky) / dz;
	r.sz = 1.0f / dz;
	return r;
}

/* Edge functions recomputed in double when one is exactly zero. */
static inline void isect_uvw_double(float ax, float ay, float bx, float by, float cx, float cy,
                                    float *u, float *v, float *w)
{
	*u = (float)((double)cx * (double)by - (double)cy * (double)bx);
	*v = (float)((double)ax * (double)cy - (double)ay * (double)cx);
	*w = (float)((double)bx * (double)ay - (double)by * (double)ax);
}

/* Scalar test. Returns 1 and fills t and barycentrics (bu for v1, bv for
 * v2) when the ray hits the triangle at t > 0 (either facing). */
static inline int isect_tri(const isect_ray *r, vec3 o, const float v[3][3], float *t, float *bu,
                            float *bv)
{
	vec3 a = v3_sub(v3(v[0][0], v[0][1], v[0][2]), o);
	vec3 b = v3_sub(v3(v[1][0], v[1][1], v[1][2]), o);
	vec3 c = v3_sub(v3(v[2][0], v[2][1], v[2][2]), o);
	float akz = v3_get(a, r->kz), bkz = v3_get(b, r->kz), ckz = v3_get(c, r->kz);
	float ax = v3_get(a, r->kx) - r->sx * akz;
	float ay = v3_get(a, r->ky) - r->sy * akz;
	float bx = v3_get(b, r->kx) - r->sx * bkz;
	float by = v3_get(b, r->ky) - r->sy * bkz;
	float cx = v3_get(c, r->kx) - r->sx * ckz;
	float cy = v3_get(c, r->ky) - r->sy * ckz;
	float u = cx * by - cy * bx;
	float vv = ax * cy - ay * cx;
	float w = bx * ay - by * ax;
	if (u == 0.0f || vv == 0.0f || w == 0.0f)
		isect_uvw_double(ax, ay, bx, by, cx, cy, &u, &vv, &w);
	if ((u < 0.0f || vv < 0.0f || w < 0.0f) && (u > 0.0f || vv > 0.0f || w > 0.0f))
		return 0;
	float det = u + vv + w;
	if (det == 0.0f)
		return 0;
	float az = r->sz * akz, bz = r->sz * bkz, cz = r->sz * ckz;
	float tt = u * az + vv * bz + w * cz;
	float tv = tt / det;
	/* t must be conservatively > 0: a ray starting on (or within rounding
	 * error of) the triangle's plane must not hit it. The bound deltaT
	 * follows pbrt-v4 (IntersectTriangle): error terms of the sheared
	 * coordinates, then of the edge functions, then of t. */
	float mzt = fmaxf(fabsf(az), fmaxf(fabsf(bz), fabsf(cz)));
	float mxt = fmaxf(fabsf(ax), fmaxf(fabsf(bx), fabsf(cx)));
	float myt = fmaxf(fabsf(ay), fmaxf(fabsf(by), fabsf(cy)));
	float dz = ISECT_GAMMA(3) * mzt;
	float dx = ISECT_GAMMA(5) * (mxt + mzt), dy = ISECT_GAMMA(5) * (myt + mzt);
	float de = 2.0f * (ISECT_GAMMA(2) * mxt * myt + dy * mxt + dx * myt);
	float me = fmaxf(fabsf(u), fmaxf(fabsf(vv), fabsf(w)));
	float dt = 3.0f * (ISECT_GAMMA(3) * me * mzt + de * mzt + dz * me) / fabsf(det);
	if (!(tv > dt))
		return 0;
	*t = tv;
	*bu = vv / det;
	*bv = w / det;
	return 1;
}

/* The hit order: smaller t wins, equal t goes to the smaller triangle
 * address, so the result does not depend on the order of the tests. */
static inline int isect_better(float t, unsigned tri, float best_t, unsigned best_tri)
{
	return t < best_t || (t == best_t && tri < best_tri);
}

#endif
