/*
 * test_simd.c: kernel-ref's vector helpers (simd.h) give, lane for lane
 * and bit for bit, what their scalar definitions say. The packet and
 * single-ray paths rely on it: a selected value is bit-exact, so both
 * make identical floats.
 *
 * fv_min and fv_max are x86's min and max instructions where the build
 * has them (session 58: gcc had made each a compare and a blend). Those
 * instructions return their second operand when the compare is false:
 * when either value is NaN and for two zeros of either sign, which is
 * a < b ? a : b exactly. The mistake this is written to catch: the
 * operands swapped (tests/mutants/98-fv-min-operands-swapped.patch), which
 * gives the same minimum of two ordinary numbers and another value for a
 * NaN or a pair of zeros. iv_from_bits sets the lanes whose bit is set,
 * for any pattern of bits; the mistake: a lane's masked bit compared with
 * 1, not with its own bit, so only lane 0 is ever set
 * (tests/mutants/102-iv-from-bits-lane-zero-only.patch).
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "kernel-ref/simd.h"
#include "tests/testutil.h"

static uint32_t bits_of(float x)
{
	uint32_t u;
	memcpy(&u, &x, sizeof u);
	return u;
}

/* Pairs that tell the operands apart: NaN on either side, zeros of both
 * signs in both orders, infinities, and ordinary numbers. */
static const float pair_a[] = {NAN,  1.0f,     NAN,       0.0f, -0.0f, -0.0f,
                               0.0f, INFINITY, -INFINITY, 2.0f, -3.5f, 1e-40f};
static const float pair_b[] = {1.0f, NAN,  NAN,   -0.0f, 0.0f,  -0.0f,
                               0.0f, 5.0f, -1.0f, 2.0f,  7.25f, -1e-40f};
#define NPAIRS ((int)(sizeof pair_a / sizeof pair_a[0]))

Test(simd, min_and_max_are_the_selects_bit_for_bit)
{
	for (int k0 = 0; k0 < NPAIRS; k0 += SIMD_W) {
		float a[SIMD_W], b[SIMD_W], mn[SIMD_W], mx[SIMD_W];
		for (int l = 0; l < SIMD_W; l++) {
			int k = k0 + l < NPAIRS ? k0 + l : l % NPAIRS;
			a[l] = pair_a[k];
			b[l] = pair_b[k];
		}
		fv_store(mn, fv_min(fv_load(a), fv_load(b)));
		fv_store(mx, fv_max(fv_load(a), fv_load(b)));
		for (int l = 0; l < SIMD_W; l++) {
			float want_mn = a[l] < b[l] ? a[l] : b[l];
			float want_mx = a[l] > b[l] ? a[l] : b[l];
			cr_assert_eq(bits_of(mn[l]), bits_of(want_mn),
			             "fv_min(%g, %g) lane %d: bits %08x, a < b ? a : b is %08x",
			             (double)a[l], (double)b[l], l, bits_of(mn[l]),
			             bits_of(want_mn));
			cr_assert_eq(bits_of(mx[l]), bits_of(want_mx),
			             "fv_max(%g, %g) lane %d: bits %08x, a > b ? a : b is %08x",
			             (double)a[l], (double)b[l], l, bits_of(mx[l]),
			             bits_of(want_mx));
		}
	}
}

Test(simd, lanes_from_bits_take_each_lanes_own_bit)
{
	for (unsigned b = 0; b <= SIMD_MASK; b += b < 64 ? 1u : 97u) {
		iv v = iv_from_bits(b);
		int32_t lane[SIMD_W];
		memcpy(lane, &v, sizeof lane);
		for (int l = 0; l < SIMD_W; l++)
			cr_assert_eq(lane[l], (b >> l) & 1u ? -1 : 0, "bits %#x, lane %d: %d", b, l,
			             lane[l]);
		cr_assert_eq(iv_bits(v), b, "bits %#x back from the lanes: %#x", b, iv_bits(v));
	}
}
