/*
 * drt.h: distribution ray tracing's parameters and its sampled effects
 * (Boulos et al., Interactive Distribution Ray Tracing, seed 000 §3):
 * samples per pixel, a thin lens (depth of field), square area lights
 * (soft shadows), glossy reflection (a Phong lobe around the mirror
 * direction) and camera motion over the shutter (motion blur).
 *
 * The parameters travel with the view (views file key `drt`, the flags
 * in world.c); all zero is today's frame: one sample per pixel through
 * the pixel centre, a pinhole, point lights, mirrors, a still camera.
 * Every random number is a stable Sudoku sample (sudoku.h), a function of
 * the pixel, the sample index and the dimension only, so a still view
 * renders the same frame every time, whatever the order of its packets.
 *
 * A frame of spp samples traces spp primary packets per 8x8 tile, packet
 * s holding sample s of each of the tile's 64 pixels with weight 1/spp;
 * secondary rays stay grouped by type per parent packet (seed §3: a
 * packet holds one ray type, here 64 rays of one tile), and carry their
 * parent's sample index (packet.sample).
 */
#ifndef SAAR_KREF_DRT_H
#define SAAR_KREF_DRT_H

#include <stdint.h>

#include "kernel-ref/vecmath.h"

/* Limits of the parameters (docs/views.md "Distribution ray tracing"). */
#define DRT_SIZE_MAX  1e9f /* aperture, focus, light size, |motion| */
#define DRT_GLOSS_MAX 1e6f /* Phong exponent */

typedef struct drt_params {
	int spp;          /* samples per pixel: 1, 4, 16 or 64; 0 counts as 1 */
	float aperture;   /* lens diameter (scene units); 0: pinhole */
	float focus;      /* focal distance along the view direction; 0: |lookat - eye| */
	float light_size; /* side of each light's square; 0: point lights */
	float gloss;      /* Phong exponent of reflection rays; 0: perfect mirror */
	vec3 motion;      /* camera displacement over the shutter; 0: a still camera */
} drt_params;

/* Samples per pixel (spp 0 counts as 1). */
static inline int drt_spp(const drt_params *p)
{
	return p->spp > 1 ? p->spp : 1;
}

/* 1 when p asks for nothing beyond the pinhole frame. */
int drt_is_off(const drt_params *p);

/* What is wrong with p (a one-line message naming the key), or NULL.
 * *key gets the key's name ("spp", "aperture", ...). */
const char *drt_problem(const drt_params *p, const char **key);

/* What the shader needs of the parameters for one frame. */
typedef struct drt_shade {
	int spp;
	uint32_t width; /* pixel -> (x, y) */
	vec3 la, lb;    /* the light square's two edges (length light_size each) */
	float gloss;
} drt_shade;

/* The light squares lie across the camera's up vector (a ceiling light
 * faces down): la and lb span the plane perpendicular to up. */
void drt_shade_setup(drt_shade *s, const drt_params *p, vec3 up, uint32_t width);

/* The point of light l (at pos) that sample s of pixel `pixel` sees: the
 * centre offset by the light dimension's sample on the square; exactly
 * pos for a point light. */
vec3 drt_light_point(const drt_shade *s, vec3 pos, uint32_t pixel, int sample, int l);

/* Seed 000 §3.3: the mirror direction r (unit) perturbed by a Phong lobe
 * of exponent n from the sample (u1, u2): phi = 2 pi u1,
 * cos(theta) = u2^(1/(n+1)), in the frame W = r, U = W x e0 (or W x e1
 * when r is nearly e0), V = W x U. */
vec3 drt_glossy_dir(vec3 r, float n, float u1, float u2);

/* x + o, but x itself when o is zero (so a zero offset keeps the sign of
 * a zero x: -0 + +0 would be +0), so that a zero-sized effect gives
 * exactly the frame without it. */
static inline float drt_add(float x, float o)
{
	return o != 0.0f ? x + o : x;
}
static inline vec3 drt_add3(vec3 a, vec3 o)
{
	return v3(drt_add(a.x, o.x), drt_add(a.y, o.y), drt_add(a.z, o.z));
}

#endif
