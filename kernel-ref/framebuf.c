/*
 * framebuf.c: fixed-point frame buffer, conversion, comparison (see
 * framebuf.h).
 */
#include "kernel-ref/framebuf.h"

#include <sys/mman.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/image.h"

#define FB_HUGE ((uintptr_t)2 << 20)

int fb_init(framebuf *fb, int w, int h)
{
	fb->w = w;
	fb->h = h;
	size_t n = (size_t)w * (size_t)h * 3 * sizeof *fb->acc;
	fb->acc = calloc(1, n);
	if (!fb->acc)
		return -1;
	/* 19 MB at 1024x768: in huge pages its first touch takes a few page
	 * faults instead of thousands (a tenth of a sampled run's host time
	 * with stored warming) */
	uintptr_t a = ((uintptr_t)fb->acc + FB_HUGE - 1) & ~(uintptr_t)(FB_HUGE - 1),
	          e = ((uintptr_t)fb->acc + n) & ~(uintptr_t)(FB_HUGE - 1);
	if (e > a)
		madvise((void *)a, e - a, MADV_HUGEPAGE);
	return 0;
}

void fb_free(framebuf *fb)
{
	free(fb->acc);
	fb->acc = NULL;
}

void fb_clear(framebuf *fb)
{
	memset(fb->acc, 0, (size_t)fb->w * (size_t)fb->h * 3 * sizeof *fb->acc);
}

static uint8_t to_srgb8(double lin)
{
	if (!(lin > 0.0))
		return 0;
	if (lin >= 1.0)
		return 255;
	double s = lin <= 0.0031308 ? 12.92 * lin : 1.055 * pow(lin, 1.0 / 2.4) - 0.055;
	return (uint8_t)(s * 255.0 + 0.5);
}

void fb_to_rgb8(const framebuf *fb, uint8_t *rgb8, float *rgbf)
{
	size_t n = (size_t)fb->w * (size_t)fb->h * 3;
	const double scale = 1.0 / (double)(1u << FB_FRAC_BITS);
	for (size_t i = 0; i < n; i++) {
		double lin = (double)fb->acc[i] * scale;
		if (rgb8)
			rgb8[i] = to_srgb8(lin);
		if (rgbf)
			rgbf[i] = (float)lin;
	}
}

int fb_write(const framebuf *fb, const char *path, af_group *g, diag *d)
{
	size_t n = (size_t)fb->w * (size_t)fb->h * 3;
	uint8_t *rgb8 = malloc(n);
	float *rgbf = malloc(n * sizeof *rgbf);
	if (!rgb8 || !rgbf) {
		free(rgb8);
		free(rgbf);
		return diag_set(d, path, 0, 0, "out of memory");
	}
	fb_to_rgb8(fb, rgb8, rgbf);
	int rc = img_write(path, fb->w, fb->h, rgb8, rgbf, g, d);
	free(rgb8);
	free(rgbf);
	return rc;
}

img_cmp img_compare(const uint8_t *a, const uint8_t *b, int w, int h)
{
	img_cmp c = {0, INFINITY, 1};
	double se = 0.0;
	size_t np = (size_t)w * (size_t)h;
	for (size_t p = 0; p < np; p++) {
		int diff = 0;
		for (int k = 0; k < 3; k++) {
			int e = (int)a[3 * p + k] - (int)b[3 * p + k];
			se += (double)e * e;
			diff |= e != 0;
		}
		c.differing_pixels += (uint64_t)diff;
	}
	if (c.differing_pixels) {
		c.identical = 0;
		double mse = se / (double)(np * 3);
		c.psnr = 10.0 * log10(255.0 * 255.0 / mse);
	}
	return c;
}
