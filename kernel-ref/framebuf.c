/*
 * framebuf.c: fixed-point frame buffer, conversion, comparison (see
 * framebuf.h).
 */
#include "kernel-ref/framebuf.h"

#include <sys/mman.h>

#include <math.h>
#include <pthread.h>
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

/* 8-bit sRGB of a channel's fixed-point sum (the formula: IEC 61966-2-1's
 * transfer function, rounded to nearest). */
uint8_t fb_srgb8_formula(uint64_t acc)
{
	double lin = (double)acc * (1.0 / (double)(1u << FB_FRAC_BITS));
	if (!(lin > 0.0))
		return 0;
	if (lin >= 1.0)
		return 255;
	double s = lin <= 0.0031308 ? 12.92 * lin : 1.055 * pow(lin, 1.0 / 2.4) - 0.055;
	return (uint8_t)(s * 255.0 + 0.5);
}

/* The formula by table: it is a non-decreasing step function of the
 * integer sum, so 255 thresholds (the least sum giving each level) and a
 * coarse index into them give the same byte without a pow() per channel,
 * which was a tenth of a sampled run's host time at 1024x768 (the chip's
 * frame is converted for the check at every run). tests/test_framebuf.c
 * compares both at every sum below 1.0 (2^20 of them). */
#define SRGB_ONE    ((uint64_t)1 << FB_FRAC_BITS)
#define SRGB_COARSE 8                                  /* sums per coarse entry: 2^8 */
static uint32_t srgb_thr[256];                         /* [k]: least sum with level >= k */
static uint8_t srgb_at[(SRGB_ONE >> SRGB_COARSE) + 1]; /* the level at each coarse step */
static pthread_once_t srgb_once = PTHREAD_ONCE_INIT;

static void srgb_init(void)
{
	srgb_thr[0] = 0;
	for (int k = 1; k < 256; k++) {
		uint64_t lo = srgb_thr[k - 1], hi = SRGB_ONE; /* level(hi) = 255 >= k */
		while (lo < hi) {
			uint64_t mid = lo + (hi - lo) / 2;
			if (fb_srgb8_formula(mid) >= k)
				hi = mid;
			else
				lo = mid + 1;
		}
		srgb_thr[k] = (uint32_t)lo;
	}
	int k = 0;
	for (uint64_t i = 0; i <= SRGB_ONE >> SRGB_COARSE; i++) {
		while (k < 255 && (i << SRGB_COARSE) >= srgb_thr[k + 1])
			k++;
		srgb_at[i] = (uint8_t)k;
	}
}

/* The level of acc by the tables (srgb_init has run). */
static inline uint8_t srgb8_by_table(uint64_t acc)
{
	if (acc >= SRGB_ONE)
		return 255;
	int k = srgb_at[acc >> SRGB_COARSE];
	while (k < 255 && acc >= srgb_thr[k + 1])
		k++;
	return (uint8_t)k;
}

uint8_t fb_srgb8(uint64_t acc)
{
	pthread_once(&srgb_once, srgb_init);
	return srgb8_by_table(acc);
}

/* The tables made once for the frame, not once per channel. */
void fb_to_rgb8(const framebuf *fb, uint8_t *rgb8, float *rgbf)
{
	size_t n = (size_t)fb->w * (size_t)fb->h * 3;
	const double scale = 1.0 / (double)(1u << FB_FRAC_BITS);
	pthread_once(&srgb_once, srgb_init);
	if (rgb8)
		for (size_t i = 0; i < n; i++)
			rgb8[i] = srgb8_by_table(fb->acc[i]);
	if (rgbf)
		for (size_t i = 0; i < n; i++)
			rgbf[i] = (float)((double)fb->acc[i] * scale);
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
	/* the usual answer at every run's check, at memory speed: the
	 * per-pixel pass below costs several times more */
	if (np == 0 || !memcmp(a, b, np * 3))
		return c;
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
