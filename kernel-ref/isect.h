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

#include "kernel-ref/fpfmt.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/vecmath.h"

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

/* The Woop test evaluated in a reduced format f (the chip's intersection
 * unit at reduced precision; docs/NUMERICS.md). Every operation is rounded
 * to f; the vertex and origin coordinates enter as the floats read from
 * memory. Conservative instead of exact:
 *
 *  - Edge functions. deltaE bounds each edge function's error against the
 *    exact value for the float inputs (pbrt-v4's derivation with f's gamma,
 *    plus the second-order and flush-to-zero terms). An edge function with
 *    |E| <= deltaE counts as zero, i.e. neutral; the test rejects only when
 *    one edge function is below -deltaE and another above +deltaE. So
 *    every triangle the float ray hits exactly (all exact edge functions
 *    of one sign) is accepted: a computed sign that is not neutral is the
 *    exact sign. A ray near a shared edge is accepted by both triangles;
 *    the closest-hit rule picks one (at worst an extra hit, never a gap).
 *    No double-precision fallback is needed: zero is inside the neutral band.
 *  - t. A triangle whose vertices all lie provably in front of the origin
 *    is accepted with t clamped to their range (its t may be rough, its
 *    existence is not in doubt). Any other triangle needs t > deltaT, a
 *    bound on t's error (see below), so a ray starting on a triangle's
 *    plane still never hits it.
 *
 * What it cannot resolve: a triangle that straddles the origin's plane
 * (across the ray) and whose projected size is within the error of its
 * sheared coordinates (about u times its distance from the origin) is
 * rejected, like the grazing case at full precision. */
/* max/min without libm calls (the emulation path checks NaN itself). */
static inline float fp_max_(float a, float b)
{
	return a > b ? a : b;
}
static inline float fp_min_(float a, float b)
{
	return a < b ? a : b;
}

static inline int isect_tri_fp(const fpfmt *f, const isect_ray *r, vec3 o, const float v[3][3],
                               float *t, float *bu, float *bv)
{
	const float ok[3] = {v3_get(o, r->kx), v3_get(o, r->ky), v3_get(o, r->kz)};
	float sx = fp_round(f, r->sx), sy = fp_round(f, r->sy), sz = fp_round(f, r->sz);
	float x[3], y[3], z[3], zs[3];
	float mxa = 0, mya = 0, mza = 0, mxt = 0, myt = 0, mzt = 0;
	for (int k = 0; k < 3; k++) {
		float ax = fp_round(f, v[k][r->kx] - ok[0]);
		float ay = fp_round(f, v[k][r->ky] - ok[1]);
		z[k] = fp_round(f, v[k][r->kz] - ok[2]);
		x[k] = fp_round(f, ax - fp_round(f, sx * z[k]));
		y[k] = fp_round(f, ay - fp_round(f, sy * z[k]));
		zs[k] = fp_round(f, sz * z[k]);
		mxa = fp_max_(mxa, fabsf(ax));
		mya = fp_max_(mya, fabsf(ay));
		mza = fp_max_(mza, fabsf(z[k]));
		mxt = fp_max_(mxt, fabsf(x[k]));
		myt = fp_max_(myt, fabsf(y[k]));
		mzt = fp_max_(mzt, fabsf(zs[k]));
	}
	if (!(mxa + mya + mza + mxt + myt + mzt < INFINITY))
		return 0; /* NaN or overflowed coordinates: beyond the format's range */
	float u = fp_round(f, fp_round(f, x[2] * y[1]) - fp_round(f, y[2] * x[1]));
	float vv = fp_round(f, fp_round(f, x[0] * y[2]) - fp_round(f, y[0] * x[2]));
	float w = fp_round(f, fp_round(f, x[1] * y[0]) - fp_round(f, y[1] * x[0]));
	/* error bounds (computed in float: their own rounding, 2^-24, is far
	 * inside the slack of f's gammas). |sx|, |sy| <= 1 since kz is the
	 * dominant axis, so |sx z| <= |z|. */
	float tiny = fp_from_bits(f->minnorm);
	float g2 = fp_gamma(f, 2), g5 = fp_gamma(f, 5);
	float dx = g5 * (mxa + mza) + 2.0f * tiny, dy = g5 * (mya + mza) + 2.0f * tiny;
	float de = 2.0f * (g2 * mxt * myt + dy * mxt + dx * myt + dx * dy) + 3.0f * tiny;
	if (!(de == de))
		return 0; /* no usable bound (overflowed coordinates) */
	int neg = u < -de || vv < -de || w < -de;
	int pos = u > de || vv > de || w > de;
	if (neg && pos)
		return 0;
	float det = fp_round(f, fp_round(f, u + vv) + w);
	float tt = fp_round(f, fp_round(f, fp_round(f, u * zs[0]) + fp_round(f, vv * zs[1])) +
	                           fp_round(f, w * zs[2]));
	float tv = fp_round(f, tt / det);
	/* zs[k] is vertex k's distance along the ray, within dz of the exact
	 * one. A triangle with every vertex in front of the origin lies in
	 * front entirely: accept it whatever the precision of t, which is
	 * clamped to the vertices' range (the exact hit of a triangle the ray
	 * meets is a convex combination of them). This keeps a triangle too
	 * small to resolve at this precision from being dropped: at worst its
	 * t and barycentrics are rough (image error, no leak). */
	float g4 = fp_gamma(f, 4), g6 = fp_gamma(f, 6);
	float zlo = fp_min_(zs[0], fp_min_(zs[1], zs[2])),
	      zhi = fp_max_(zs[0], fp_max_(zs[1], zs[2]));
	float dz = g4 * mzt + tiny;
	if (zlo > dz) {
		if (!(tv >= zlo))
			tv = zlo; /* also NaN: det rounded to zero */
		else if (tv > zhi)
			tv = zhi;
	} else {
		/* Otherwise t must be provably > 0 (a ray starting on the plane
		 * never hits it). With computed edge functions e = E + eta the
		 * computed t' = sum e z / sum e satisfies t' - t = sum eta
		 * (z - t) / det, so with K = deltaE / |det|:
		 * |t' - t| <= K sum |z - t'| / (1 - 3K); plus the roundings of
		 * the sums, the product terms and the division (gamma(6) of
		 * sum |e z| / |det|) and the error of z (dz sum |e| / |det|).
		 * Tighter than pbrt's bound, which has max |z| where the spread
		 * |z - t| suffices: at 8 to 12 mantissa bits that factor decides
		 * whether any hit survives. */
		if (det == 0.0f || det != det)
			return 0;
		float ad = fabsf(det), k = de / ad;
		if (!(3.0f * k < 1.0f))
			return 0; /* not resolvable: t's sign is unknown */
		float sz_ = fabsf(zs[0] - tv) + fabsf(zs[1] - tv) + fabsf(zs[2] - tv);
		float se = fabsf(u) + fabsf(vv) + fabsf(w);
		float sez = fabsf(u * zs[0]) + fabsf(vv * zs[1]) + fabsf(w * zs[2]);
		float dt = (k * sz_ / (1.0f - 3.0f * k) + (g6 * sez + dz * se) / ad) * 1.0001f;
		if (!(tv > dt))
			return 0;
	}
	float b1 = fp_round(f, vv / det), b2 = fp_round(f, w / det);
	if (!(fabsf(b1) <= 2.0f && fabsf(b2) <= 2.0f))
		b1 = b2 = 1.0f / 3.0f; /* unresolved: the centre, so shading stays finite */
	*t = tv;
	*bu = b1;
	*bv = b2;
	return 1;
}

/* The hit order: smaller t wins, equal t goes to the smaller triangle
 * address, so the result does not depend on the order of the tests. */
static inline int isect_better(float t, unsigned tri, float best_t, unsigned best_tri)
{
	return t < best_t || (t == best_t && tri < best_tri);
}

/* A single ray's hit (t, bu, bv) on triangle ta (of instance inst), kept
 * in *h by that rule; with any_hit an occluder before tmax ends the
 * search: returns 1 then. Every scalar path (ray_trace, the grid's DDA,
 * the flat two-level reference) takes its hits through this. */
static inline int isect_take(ray_hit *h, float t, float bu, float bv, uint32_t ta, uint32_t inst,
                             int any_hit, float tmax)
{
	if (any_hit) {
		if (!(t < tmax))
			return 0;
		h->t = t;
		h->tri = ta;
		return 1;
	}
	if (isect_better(t, ta, h->t, h->tri))
		*h = (ray_hit){t, bu, bv, ta, inst};
	return 0;
}

#endif
