/*
 * fastdiv.h: exact unsigned 64-bit division by a divisor fixed at setup,
 * by a multiplication.
 *
 * The simulator divides by the same few numbers at every event: a clock's
 * period (eng_next_edge), an L1's line size and set count when they are not
 * powers of two (36-byte triangle lines). A 64-bit division instruction
 * takes tens of cycles (the profile put a third of the SDRAM access's
 * samples right after its divisions: docs/PERFORMANCE.md, "Target 2"); a
 * multiplication and one correction step give the same quotient for every
 * dividend.
 *
 * Why it is exact: inv = floor((2^64 - 1) / d) >= 2^64 / d - 1, so for
 * every t < 2^64, t / d - 1 < t * inv / 2^64 <= t / d; the high half of
 * t * inv, rounded down, is the quotient q or q - 1, and the remainder
 * t - q' * d tells which (tests/test_engine.c checks against `/`).
 */
#ifndef SAAR_SIM_CORE_FASTDIV_H
#define SAAR_SIM_CORE_FASTDIV_H

#include <stdint.h>

typedef struct fastdiv {
	uint64_t d;   /* the divisor, >= 1 */
	uint64_t inv; /* UINT64_MAX / d; 0: not set up, fastdiv_div divides */
} fastdiv;

static inline fastdiv fastdiv_of(uint64_t d)
{
	return (fastdiv){d, d ? UINT64_MAX / d : 0};
}

/* t / f.d */
static inline uint64_t fastdiv_div(fastdiv f, uint64_t t)
{
	if (!f.inv)
		return t / f.d;
	__extension__ typedef unsigned __int128 fastdiv_u128;
	uint64_t q = (uint64_t)(((fastdiv_u128)t * f.inv) >> 64);
	if (t - q * f.d >= f.d)
		q++;
	return q;
}

/* t % f.d */
static inline uint64_t fastdiv_mod(fastdiv f, uint64_t t)
{
	return t - fastdiv_div(f, t) * f.d;
}

#endif
