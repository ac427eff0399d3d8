/*
 * simd.h: native-width float vectors for the packet tracer.
 *
 * GCC/Clang vector extensions give portable vectors. The width matches the
 * target's registers: 16 lanes with AVX-512, 8 with AVX, 4 otherwise (SSE2 on
 * baseline x86-64, NEON on ARM, plain scalar code elsewhere). Wider
 * generic vectors are split by the compiler, and some operations
 * (integer compares, selects) then fall back to element-by-element code,
 * which was measured to cost several times more. A 64-ray packet is
 * PKT_RAYS / SIMD_W groups.
 *
 * Selections use bitwise blends, never arithmetic, so a selected value is
 * bit-exact: the packet and single-ray paths produce identical floats.
 */
#ifndef SAAR_KREF_SIMD_H
#define SAAR_KREF_SIMD_H

#include <stdint.h>
#include <string.h>

#if defined(__AVX512F__)
#include <immintrin.h>
#define SIMD_W 16
#elif defined(__AVX__)
#include <immintrin.h>
#define SIMD_W 8
#elif defined(__SSE__)
#include <xmmintrin.h>
#define SIMD_W 4
#else
#define SIMD_W 4
#endif

typedef float fv __attribute__((vector_size(SIMD_W * 4)));
typedef int32_t iv __attribute__((vector_size(SIMD_W * 4)));

#define SIMD_MASK ((unsigned)((1ull << SIMD_W) - 1u))

static inline fv fv_set1(float x)
{
	fv v;
#if defined(__AVX512F__)
	__m512 b = _mm512_set1_ps(x);
	memcpy(&v, &b, sizeof v);
#elif defined(__AVX__)
	__m256 b = _mm256_set1_ps(x);
	memcpy(&v, &b, sizeof v);
#elif defined(__SSE__)
	__m128 b = _mm_set1_ps(x);
	memcpy(&v, &b, sizeof v);
#else
	for (int i = 0; i < SIMD_W; i++)
		v[i] = x;
#endif
	return v;
}
static inline iv iv_set1(int32_t x)
{
	iv v = {0};
#if defined(__AVX512F__)
	/* (the lane loop became two 8-lane stores and a 16-lane load, which
	 * the store buffer cannot forward) */
	__m512i b = _mm512_set1_epi32(x);
	memcpy(&v, &b, sizeof v);
#else
	for (int i = 0; i < SIMD_W; i++)
		v[i] = x;
#endif
	return v;
}
static inline fv fv_load(const float *p)
{
	fv v;
	memcpy(&v, p, sizeof v);
	return v;
}
static inline iv iv_load(const int32_t *p)
{
	iv v;
	memcpy(&v, p, sizeof v);
	return v;
}
static inline void fv_store(float *p, fv v)
{
	memcpy(p, &v, sizeof v);
}
/* m ? a : b, lane by lane; m lanes are all-ones or zero. */
static inline fv fv_sel(iv m, fv a, fv b)
{
	return (fv)((m & (iv)a) | (~m & (iv)b));
}
/* x86's min or max instruction (op) on two fv, where there is one: a
 * vector cast is the bits unchanged */
#if defined(__AVX512F__)
#define FV_X86(op, a, b) ((fv)_mm512_##op##_ps((__m512)(a), (__m512)(b)))
#elif defined(__AVX__)
#define FV_X86(op, a, b) ((fv)_mm256_##op##_ps((__m256)(a), (__m256)(b)))
#elif defined(__SSE__)
#define FV_X86(op, a, b) ((fv)_mm_##op##_ps((__m128)(a), (__m128)(b)))
#endif
/* a < b ? a : b per lane (b when either is NaN, and of two zeros): the
 * semantics of x86's min instructions, so those where there are (gcc
 * made a compare and a blend of the select) */
static inline fv fv_min(fv a, fv b)
{
#ifdef FV_X86
	return FV_X86(min, a, b);
#else
	return fv_sel(a < b, a, b);
#endif
}
/* a > b ? a : b per lane (b when either is NaN, and of two zeros) */
static inline fv fv_max(fv a, fv b)
{
#ifdef FV_X86
	return FV_X86(max, a, b);
#else
	return fv_sel(a > b, a, b);
#endif
}
static inline fv fv_abs(fv a)
{
	return (fv)((iv)a & iv_set1(0x7fffffff));
}

/* Square root, lane by lane (correctly rounded, as sqrtf). */
static inline fv fv_sqrt(fv a)
{
#if defined(__AVX512F__)
	__m512 x;
	memcpy(&x, &a, sizeof x);
	x = _mm512_sqrt_ps(x);
	memcpy(&a, &x, sizeof a);
#elif defined(__AVX__)
	__m256 x;
	memcpy(&x, &a, sizeof x);
	x = _mm256_sqrt_ps(x);
	memcpy(&a, &x, sizeof a);
#elif defined(__SSE__)
	__m128 x;
	memcpy(&x, &a, sizeof x);
	x = _mm_sqrt_ps(x);
	memcpy(&a, &x, sizeof a);
#else
	for (int i = 0; i < SIMD_W; i++)
		a[i] = __builtin_sqrtf(a[i]);
#endif
	return a;
}

/* Bits SIMD_W g .. SIMD_W g + SIMD_W - 1 of a packet mask: group g's lanes. */
static inline unsigned grp_bits(uint64_t mask, int g)
{
	return (unsigned)(mask >> (SIMD_W * g)) & SIMD_MASK;
}

/* Bit i of b becomes lane i (all-ones or zero): b in every lane, tested
 * against each lane's own bit. */
static inline iv iv_from_bits(unsigned b)
{
#if SIMD_W == 16 && defined(__AVX512F__)
	iv v;
	__m512i x = _mm512_maskz_set1_epi32((__mmask16)b, -1);
	memcpy(&v, &x, sizeof v);
	return v;
#else
#if SIMD_W == 16
	const iv bit = {1,   2,   4,    8,    16,   32,   64,    128,
	                256, 512, 1024, 2048, 4096, 8192, 16384, 32768};
#elif SIMD_W == 8
	const iv bit = {1, 2, 4, 8, 16, 32, 64, 128};
#else
	const iv bit = {1, 2, 4, 8};
#endif
	/* == bit, not != 0: each lane's bit is one bit, and an equality is
	 * one compare where != is two */
	return (iv_set1((int32_t)b) & bit) == bit;
#endif
}

/* Lane i of m (all-ones or zero) becomes bit i. */
static inline unsigned iv_bits(iv m)
{
#if defined(__AVX512F__)
	__m512i x;
	memcpy(&x, &m, sizeof x);
	return (unsigned)_mm512_cmplt_epi32_mask(x, _mm512_setzero_si512());
#elif defined(__AVX__)
	__m256 x;
	memcpy(&x, &m, sizeof x);
	return (unsigned)_mm256_movemask_ps(x);
#elif defined(__SSE__)
	__m128 x;
	memcpy(&x, &m, sizeof x);
	return (unsigned)_mm_movemask_ps(x);
#else
	unsigned b = 0;
	for (int i = 0; i < SIMD_W; i++)
		b |= (unsigned)(m[i] != 0) << i;
	return b;
#endif
}

#endif
