/*
 * isect_v.h: the steps of the packet triangle test over SIMD_W lanes
 * (the watertight test of isect.h, Woop et al. 2013, lane by lane): the
 * sheared corners, the edge functions, the inside test and the hit
 * distance in front of the origin, shared by
 * traverse.c's pkt_isect_tri_v, which the chip and the check use, and
 * frustum.c's fru_isect, rtref's own leaf test: both compute the same
 * operations in the same order, so the same floats, whichever runs them.
 */
#ifndef SAAR_KREF_ISECT_V_H
#define SAAR_KREF_ISECT_V_H

#include "kernel-ref/isect.h"
#include "kernel-ref/memimage.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/simd.h"

/* One corner (cx, cy, cz, in the rays' axis permutation) relative to the
 * origin (okx, oky, okz), sheared by sx, sy: *vx, *vy the sheared x and y,
 * *vkz the unsheared z. The lanes hold rays (isect_v_uniform: the corner
 * broadcast) or triangles (frustum.c's fru_ray_tris: the ray broadcast);
 * one function, so the same floats for each ray and corner either way. */
static inline void isect_v_shear(fv cx, fv cy, fv cz, fv okx, fv oky, fv okz, fv sx, fv sy, fv *vx,
                                 fv *vy, fv *vkz)
{
	*vkz = cz - okz;
	*vx = (cx - okx) - sx * *vkz;
	*vy = (cy - oky) - sy * *vkz;
}

/* The corners of tr relative to the rays' origins in the axis
 * permutation every ray of the packet shares (pkt_rayc.uniform), lanes
 * o..o+SIMD_W-1, sheared by sx, sy (isect_prepare): vx, vy the sheared
 * x and y, vkz the unsheared z. */
static inline void isect_v_uniform(const pkt_rayc *rc, int o, const mimg_tri *tr, fv sx, fv sy,
                                   fv vx[3], fv vy[3], fv vkz[3])
{
	fv okx = fv_load(rc->okx + o), oky = fv_load(rc->oky + o);
	fv okz = fv_load(rc->okz + o);
	/* unrolled: gcc's loop kept the nine vectors in memory */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC unroll 3
#endif
	for (int k = 0; k < 3; k++)
		isect_v_shear(fv_set1(tr->v[k][rc->ukx]), fv_set1(tr->v[k][rc->uky]),
		              fv_set1(tr->v[k][rc->ukz]), okx, oky, okz, sx, sy, &vx[k], &vy[k],
		              &vkz[k]);
}

/* The edge functions u, v, w of the sheared corners; a lane of gb where
 * one is zero has all three redone in double (isect_uvw_double). */
static inline void isect_v_edges(const fv vx[3], const fv vy[3], unsigned gb, fv *uo, fv *vo,
                                 fv *wo)
{
	fv u = vx[2] * vy[1] - vy[2] * vx[1];
	fv v = vx[0] * vy[2] - vy[0] * vx[2];
	fv w = vx[1] * vy[0] - vy[1] * vx[0];
	fv zero = fv_set1(0.0f);
	unsigned dbl = iv_bits((u == zero) | (v == zero) | (w == zero)) & gb;
	for (unsigned k = dbl; k; k &= k - 1) {
		int l = __builtin_ctz(k);
		float uu, vv, ww;
		isect_uvw_double(vx[0][l], vy[0][l], vx[1][l], vy[1][l], vx[2][l], vy[2][l], &uu,
		                 &vv, &ww);
		u[l] = uu;
		v[l] = vv;
		w[l] = ww;
	}
	*uo = u;
	*vo = v;
	*wo = w;
}

/* The bound on the rounding error of t = (u az + v bz + w cz) / det below
 * which a hit counts as behind the origin (isect_tri's conservative t > 0,
 * pbrt's deltaT); az, bz, cz: the corners' z scaled by sz. */
static inline fv isect_v_dt(fv u, fv v, fv w, fv det, fv az, fv bz, fv cz, const fv vx[3],
                            const fv vy[3])
{
	fv mzt = fv_max(fv_abs(az), fv_max(fv_abs(bz), fv_abs(cz)));
	fv mxt = fv_max(fv_abs(vx[0]), fv_max(fv_abs(vx[1]), fv_abs(vx[2])));
	fv myt = fv_max(fv_abs(vy[0]), fv_max(fv_abs(vy[1]), fv_abs(vy[2])));
	fv dz = fv_set1(ISECT_GAMMA(3)) * mzt;
	fv dx = fv_set1(ISECT_GAMMA(5)) * (mxt + mzt), dy = fv_set1(ISECT_GAMMA(5)) * (myt + mzt);
	fv de = fv_set1(2.0f) * (fv_set1(ISECT_GAMMA(2)) * mxt * myt + dy * mxt + dx * myt);
	fv me = fv_max(fv_abs(u), fv_max(fv_abs(v), fv_abs(w)));
	return fv_set1(3.0f) * (fv_set1(ISECT_GAMMA(3)) * me * mzt + de * mzt + dz * me) /
	       fv_abs(det);
}

/* The lanes of gb whose ray meets the triangle: edge functions u, v, w
 * not of mixed sign and their sum, the determinant (*det), not zero. */
static inline unsigned isect_v_inside(fv u, fv v, fv w, unsigned gb, fv *det)
{
	fv zero = fv_set1(0.0f);
	iv neg = (u < zero) | (v < zero) | (w < zero);
	iv posv = (u > zero) | (v > zero) | (w > zero);
	*det = u + v + w;
	return iv_bits(~(neg & posv) & (*det != zero)) & gb;
}

/* Of the lanes okb (isect_v_inside's), those whose hit distance
 * *t = (u az + v bz + w cz) / det, the corners' z scaled by sz, lies in
 * front of the origin by more than its rounding bound (isect_tri's
 * conservative t > 0, pbrt's deltaT: isect_v_dt). */
static inline unsigned isect_v_front(fv u, fv v, fv w, fv det, fv sz, const fv vx[3],
                                     const fv vy[3], const fv vkz[3], unsigned okb, fv *t)
{
	fv az = sz * vkz[0], bz = sz * vkz[1], cz = sz * vkz[2];
	*t = (u * az + v * bz + w * cz) / det;
	return okb & iv_bits(*t > isect_v_dt(u, v, w, det, az, bz, cz, vx, vy));
}

#endif
