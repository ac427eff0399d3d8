/*
 * xform.h: affine transforms of points and normals in double precision
 * (row-major 3x4 matrices), shared by aff_flatten (aff.c), which places
 * meshes into the world, and the shader (shade.c), which moves a
 * two-level hit's object-space records into the world (docs/design.md,
 * "The chip on two-level scenes"). One code path for both, so a vertex
 * the shader moves is the float aff_flatten would have stored.
 */
#ifndef SAAR_KREF_XFORM_H
#define SAAR_KREF_XFORM_H

#include <math.h>

#include "kernel-ref/vecmath.h"

/* The normal matrix of m: the cofactors of its 3x3 part (the inverse
 * transpose times the determinant), sign-corrected for a mirroring m. */
static inline void xf_normal_matrix(const double m[12], double nm[9])
{
	const double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9],
	             i = m[10];
	nm[0] = e * i - f * h;
	nm[1] = f * g - d * i;
	nm[2] = d * h - e * g;
	nm[3] = c * h - b * i;
	nm[4] = a * i - c * g;
	nm[5] = b * g - a * h;
	nm[6] = b * f - c * e;
	nm[7] = c * d - a * f;
	nm[8] = a * e - b * d;
	double det = a * nm[0] + b * nm[1] + c * nm[2];
	if (det < 0)
		for (int k = 0; k < 9; k++)
			nm[k] = -nm[k];
}

/* m p, rounded to float once. */
static inline vec3 xf_point(const double m[12], const float *p)
{
	double r[3];
	for (int i = 0; i < 3; i++)
		r[i] = m[4 * i] * p[0] + m[4 * i + 1] * p[1] + m[4 * i + 2] * p[2] + m[4 * i + 3];
	return v3((float)r[0], (float)r[1], (float)r[2]);
}

/* nm n normalised (in double), rounded to float; a zero vector when it
 * has no length. */
static inline vec3 xf_normal(const double nm[9], const float *n)
{
	double r[3];
	for (int i = 0; i < 3; i++)
		r[i] = nm[3 * i] * n[0] + nm[3 * i + 1] * n[1] + nm[3 * i + 2] * n[2];
	double len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
	if (!(len > 0.0))
		return v3(0, 0, 0);
	return v3((float)(r[0] / len), (float)(r[1] / len), (float)(r[2] / len));
}

#endif
