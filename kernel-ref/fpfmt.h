/*
 * fpfmt.h: reduced-precision floating-point formats, emulated on float.
 *
 * SaarCOR cut each pipeline stage's floating-point units down to the
 * precision that stage needed (seed 002 §4.6). A format here is
 * {exponent bits 2..8, mantissa bits 1..23, rounding mode}; fp_round()
 * rounds a float to the nearest (or directed) value of that format by
 * integer manipulation of its bits. The emulated value stays a float, so
 * the shared math keeps its float code and only rounds after each
 * operation.
 *
 * Range: the format's exponent has the IEEE bias 2^(e-1) - 1. Results
 * beyond the largest finite value overflow as IEEE does (to +-inf when the
 * rounding goes away from zero, to the largest finite value otherwise);
 * results below the smallest normal value are flushed (no subnormals):
 * to zero, except that a directed rounding away from zero gives the
 * smallest normal, so fp_round_up / fp_round_down stay bounds. NaN stays
 * NaN, infinities stay infinite.
 *
 * The 8-exponent, 23-mantissa format is the identity whatever the mode
 * (fpfmt.full): callers test that flag once per packet and keep their full
 * precision code, so the reference path costs nothing.
 */
#ifndef SAAR_KREF_FPFMT_H
#define SAAR_KREF_FPFMT_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "kernel-ref/diag.h"

enum fp_rmode { FPR_NEAREST, FPR_ZERO, FPR_UP, FPR_DOWN, FPR_NMODES };

typedef struct fpfmt {
	int ebits, mbits, rmode;
	int full;         /* 8 exponent and 23 mantissa bits: fp_round is the identity */
	uint32_t drop;    /* float mantissa bits dropped: 23 - mbits */
	uint32_t maxfin;  /* magnitude bits of the largest finite value */
	uint32_t minnorm; /* magnitude bits of the smallest normal value */
	float u;          /* relative error of one emulated operation (see fp_gamma) */
	float gam[9];     /* fp_gamma(1..8), precomputed: the emulation asks per test */
} fpfmt;

/* Sets up a format; returns -1 (and leaves f full precision) when a field
 * is out of range. */
int fpfmt_init(fpfmt *f, int ebits, int mbits, int rmode);

/* The identity format (float itself). */
fpfmt fpfmt_full(void);

/* "E,M" (exponent and mantissa bits) with the given rounding mode; errors
 * name `flag`. */
int fpfmt_parse(fpfmt *f, const char *flag, const char *s, int rmode, diag *d);

/* "nearest", "zero", "up", "down" -> FPR_*; -1 if none. */
int fp_rmode_parse(const char *s);
const char *fp_rmode_name(int rmode);

/* Writes "E,M mode" (or "float" for the identity) into buf. */
void fpfmt_describe(const fpfmt *f, char *buf, size_t n);

/* Relative error bound gamma(n) = n u / (1 - n u) of n chained emulated
 * operations (pbrt's gamma with this format's u); +inf when n u >= 1 (a
 * 1- or 2-bit mantissa has no useful bound: callers then widen to
 * everything). u is the unit roundoff 2^-(m+1) for nearest rounding and
 * 2^-m for the directed modes (their error reaches a whole ulp), plus
 * 2^-24 when m < 23: the emulation rounds to float first and then to the
 * format, and the bound covers both roundings. */
float fp_gamma_calc(const fpfmt *f, int n);
static inline float fp_gamma(const fpfmt *f, int n)
{
	return n >= 1 && n <= 8 ? f->gam[n] : fp_gamma_calc(f, n);
}

static inline uint32_t fp_bits(float x)
{
	uint32_t b;
	memcpy(&b, &x, sizeof b);
	return b;
}
static inline float fp_from_bits(uint32_t b)
{
	float x;
	memcpy(&x, &b, sizeof x);
	return x;
}

/* The next float above / below a finite x (nextafterf without the libm
 * call; infinities and NaN pass through). */
static inline float fp_next_up(float x)
{
	uint32_t b = fp_bits(x);
	if ((b & 0x7fffffffu) >= 0x7f800000u)
		return x;
	if ((b & 0x7fffffffu) == 0)
		return fp_from_bits(1u);
	return fp_from_bits(b & 0x80000000u ? b - 1u : b + 1u);
}
static inline float fp_next_down(float x)
{
	return -fp_next_up(-x);
}

/* Rounds x in mode `mode` (an FPR_* value). */
static inline float fp_round_mode(const fpfmt *f, float x, int mode)
{
	if (f->full)
		return x;
	uint32_t b = fp_bits(x), sign = b & 0x80000000u, mag = b & 0x7fffffffu;
	if (mag >= 0x7f800000u)
		return x; /* inf and NaN */
	int neg = sign != 0;
	/* does this mode move away from zero for this sign? */
	int away = mode == FPR_NEAREST || (mode == FPR_UP && !neg) || (mode == FPR_DOWN && neg);
	if (f->drop) {
		uint32_t low = (1u << f->drop) - 1u, rest = mag & low;
		mag &= ~low;
		if (rest) {
			if (mode == FPR_NEAREST) {
				uint32_t half = 1u << (f->drop - 1);
				if (rest > half || (rest == half && (mag >> f->drop) & 1u))
					mag += 1u << f->drop; /* a carry moves into the exponent */
			} else if (away)
				mag += 1u << f->drop;
		}
	}
	if (mag > f->maxfin)
		mag = away ? 0x7f800000u : f->maxfin;
	else if (mag < f->minnorm && mag != 0) {
		/* below the smallest normal: flush; a directed rounding away from
		 * zero keeps a bound (the smallest normal) */
		int up = mode != FPR_NEAREST && away;
		mag = up ? f->minnorm : 0u;
	}
	return fp_from_bits(sign | mag);
}

/* Rounds x to the format with its own rounding mode. */
static inline float fp_round(const fpfmt *f, float x)
{
	return fp_round_mode(f, x, f->rmode);
}

/* Smallest format value >= x, largest <= x: conservative bounds. */
static inline float fp_round_up(const fpfmt *f, float x)
{
	return fp_round_mode(f, x, FPR_UP);
}
static inline float fp_round_down(const fpfmt *f, float x)
{
	return fp_round_mode(f, x, FPR_DOWN);
}

#endif
