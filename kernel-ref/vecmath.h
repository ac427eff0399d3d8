/*
 * vecmath.h: small 3-vector helpers shared by kernel-ref and the chip model.
 *
 * Plain structs passed by value; everything is static inline so the compiler
 * keeps them in registers. No SIMD here: packet code vectorises across rays,
 * never inside one vector.
 */
#ifndef SAAR_KREF_VECMATH_H
#define SAAR_KREF_VECMATH_H

#include <math.h>

typedef struct vec3 {
	float x, y, z;
} vec3;

typedef struct vec2 {
	float u, v;
} vec2;

static inline vec3 v3(float x, float y, float z)
{
	return (vec3){x, y, z};
}
static inline vec3 v3_add(vec3 a, vec3 b)
{
	return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline vec3 v3_sub(vec3 a, vec3 b)
{
	return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline vec3 v3_mul(vec3 a, vec3 b)
{
	return v3(a.x * b.x, a.y * b.y, a.z * b.z);
}
static inline vec3 v3_scale(vec3 a, float s)
{
	return v3(a.x * s, a.y * s, a.z * s);
}
static inline float v3_dot(vec3 a, vec3 b)
{
	return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline vec3 v3_cross(vec3 a, vec3 b)
{
	return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v3_len(vec3 a)
{
	return sqrtf(v3_dot(a, a));
}
static inline vec3 v3_norm(vec3 a)
{
	float l = v3_len(a);
	return l > 0.0f ? v3_scale(a, 1.0f / l) : a;
}
static inline vec3 v3_min(vec3 a, vec3 b)
{
	return v3(fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z));
}
static inline vec3 v3_max(vec3 a, vec3 b)
{
	return v3(fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z));
}
static inline float v3_get(vec3 a, int axis)
{
	return axis == 0 ? a.x : axis == 1 ? a.y : a.z;
}
static inline int v3_finite(vec3 a)
{
	return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

/* Axis-aligned box. An empty box has lo > hi. */
typedef struct aabb {
	vec3 lo, hi;
} aabb;

static inline aabb aabb_empty(void)
{
	return (aabb){v3(INFINITY, INFINITY, INFINITY), v3(-INFINITY, -INFINITY, -INFINITY)};
}
static inline aabb aabb_grow(aabb b, vec3 p)
{
	return (aabb){v3_min(b.lo, p), v3_max(b.hi, p)};
}
static inline aabb aabb_union(aabb a, aabb b)
{
	return (aabb){v3_min(a.lo, b.lo), v3_max(a.hi, b.hi)};
}
static inline float aabb_area(aabb b)
{
	vec3 d = v3_sub(b.hi, b.lo);
	if (d.x < 0 || d.y < 0 || d.z < 0)
		return 0.0f;
	return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
}

#endif
