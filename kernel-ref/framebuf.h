/*
 * framebuf.h: the order-independent frame buffer shared by kernel-ref and
 * the chip model (SaarCOR writes into a separate on-board frame buffer).
 *
 * Every ray adds a weighted contribution to its pixel. Contributions are
 * converted to unsigned fixed point (FB_FRAC_BITS fraction bits) before
 * they are added, and integer addition is associative, so the final image
 * does not depend on the order in which rays, packets or threads finish:
 * kernel-ref with any thread count and the chip with any schedule produce
 * bit-identical frames.
 */
#ifndef SAAR_KREF_FRAMEBUF_H
#define SAAR_KREF_FRAMEBUF_H

#include <stdint.h>

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/diag.h"

#define FB_FRAC_BITS   20
#define FB_MAX_CONTRIB 1024.0f /* per-ray clamp: keeps sums far from overflow */

typedef struct framebuf {
	int w, h;
	uint64_t *acc; /* 3 per pixel, fixed point */
} framebuf;

/* 8-bit sRGB of one channel's fixed-point sum: fb_srgb8 by table (what
 * fb_to_rgb8 uses), fb_srgb8_formula by the transfer function itself (the
 * same byte at every sum; tests compare them). */
uint8_t fb_srgb8(uint64_t acc);
uint8_t fb_srgb8_formula(uint64_t acc);

/* A cleared frame buffer. */
int fb_init(framebuf *fb, int w, int h);
void fb_free(framebuf *fb);
void fb_clear(framebuf *fb);

static inline uint64_t fb_fixed(float c)
{
	if (!(c > 0.0f))
		return 0; /* negative, zero or NaN adds nothing */
	if (c > FB_MAX_CONTRIB)
		c = FB_MAX_CONTRIB;
	return (uint64_t)(c * (float)(1u << FB_FRAC_BITS) + 0.5f);
}

static inline void fb_add(framebuf *fb, uint32_t pixel, float r, float g, float b)
{
	uint64_t *a = fb->acc + 3 * (uint64_t)pixel;
	a[0] += fb_fixed(r);
	a[1] += fb_fixed(g);
	a[2] += fb_fixed(b);
}

/* Converts to 8-bit sRGB (w*h*3) and, if rgbf is non-NULL, linear floats. */
void fb_to_rgb8(const framebuf *fb, uint8_t *rgb8, float *rgbf);

/* Writes the frame (format from the extension) atomically; with a group g
 * it is renamed into place by af_group_commit (atomicfile.h). */
int fb_write(const framebuf *fb, const char *path, af_group *g, diag *d);

/* Compares two 8-bit images: differing pixels and PSNR (dB; INFINITY when
 * identical). */
typedef struct img_cmp {
	uint64_t differing_pixels;
	double psnr;
	int identical;
} img_cmp;
img_cmp img_compare(const uint8_t *a, const uint8_t *b, int w, int h);

#endif
