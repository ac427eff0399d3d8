/*
 * test_compiler.c: the build's compiler and flags keep what the C source
 * says about floating point. This file is compiled with the flags of
 * everything else (the Makefile's XCFLAGS), so a flag that lets the
 * compiler break a rule breaks it here too.
 *
 * Found by the stress suite's full run (`make stress`, session 54): one of
 * its 5,000,000 random rays disagreed with the double-precision reference,
 * and only at -O2. Debian 12's GCC 12.2 vectorizes (SLP, on by default at
 * -O2 since GCC 12) two doubles narrowed into a struct's float fields and
 * widened back, and stores the original doubles: the reference traced the
 * ray from an origin the float test never saw. The Makefile turns the
 * vectorizer off (NOSLP); nothing measured got slower.
 */
#include "tests/testutil.h"

typedef struct tc_vec3 {
	float x, y, z;
} tc_vec3;

/* Kept out of line with its inputs from memory: the compiler cannot fold
 * the conversions at the call. */
__attribute__((noinline)) static void narrow_widen(const double in[3], tc_vec3 *o, double out[3])
{
	*o = (tc_vec3){(float)in[0], (float)in[1], (float)in[2]};
	out[0] = o->x, out[1] = o->y, out[2] = o->z;
}

/* The same through memory: two doubles narrowed into a float array, read
 * back into doubles (GCC 12.2 with SLP stores the original doubles here
 * too). */
__attribute__((noinline)) static void narrow_widen_mem(const double in[2], float f[2],
                                                       double out[2])
{
	f[0] = (float)in[0];
	f[1] = (float)in[1];
	out[0] = f[0];
	out[1] = f[1];
}

/* A double narrowed to float and widened back is the float's value, not
 * the double's (C11 6.3.1.5). Catches the SLP vectorizer of GCC 12.2 at
 * -O2 left on (the Makefile's NOSLP taken out: mutant 85), under which
 * out[0] and out[1] are the unrounded 0.1 and 0.2. */
Test(compiler, a_float_keeps_its_rounding_when_widened)
{
	volatile double src[3] = {0.1, 0.2, 0.3};
	double in[3] = {src[0], src[1], src[2]}, out[3];
	tc_vec3 o;
	narrow_widen(in, &o, out);
	const float want[3] = {0.1f, 0.2f, 0.3f};
	for (int k = 0; k < 3; k++) {
		cr_assert_eq(out[k], (double)want[k], "field %d widened to %a, not the float %a", k,
		             out[k], (double)want[k]);
		cr_assert_neq(out[k], in[k], "field %d kept the double %a", k, in[k]);
	}
	cr_assert_eq((double)o.x, (double)want[0]);
	float f[2];
	double out2[2];
	narrow_widen_mem(in, f, out2);
	for (int k = 0; k < 2; k++)
		cr_assert_eq(out2[k], (double)f[k], "element %d read back as %a, not the float %a",
		             k, out2[k], (double)f[k]);
}
