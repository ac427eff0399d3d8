/*
 * fpfmt.c: reduced-precision formats (see fpfmt.h): set-up, parsing and
 * error bounds. The rounding itself is inline in the header because the
 * emulated datapaths call it after every operation.
 */
#include "kernel-ref/fpfmt.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

static const char *const mode_names[FPR_NMODES] = {"nearest", "zero", "up", "down"};

int fpfmt_init(fpfmt *f, int ebits, int mbits, int rmode)
{
	*f = fpfmt_full();
	if (ebits < 2 || ebits > 8 || mbits < 1 || mbits > 23 || rmode < 0 || rmode >= FPR_NMODES)
		return -1;
	f->ebits = ebits;
	f->mbits = mbits;
	f->rmode = rmode;
	f->full = ebits == 8 && mbits == 23;
	f->drop = (uint32_t)(23 - mbits);
	uint32_t bias = (1u << (ebits - 1)) - 1u; /* IEEE bias of the format */
	f->maxfin = ((bias + 127u) << 23) | ((((1u << mbits) - 1u)) << f->drop);
	f->minnorm = (128u - bias) << 23;
	/* one operation: the format's rounding, plus the float rounding the
	 * emulation does first (not there when the format keeps all 23 bits) */
	double u = rmode == FPR_NEAREST ? ldexp(1.0, -(mbits + 1)) : ldexp(1.0, -mbits);
	if (mbits < 23)
		u += 0x1p-24;
	f->u = (float)u;
	for (int n = 1; n <= 8; n++)
		f->gam[n] = fp_gamma_calc(f, n);
	return 0;
}

fpfmt fpfmt_full(void)
{
	fpfmt f;
	memset(&f, 0, sizeof f);
	f.ebits = 8;
	f.mbits = 23;
	f.rmode = FPR_NEAREST;
	f.full = 1;
	f.maxfin = 0x7f7fffffu;
	f.minnorm = 0x00800000u;
	f.u = 0x1p-24f;
	for (int n = 1; n <= 8; n++)
		f.gam[n] = fp_gamma_calc(&f, n);
	return f;
}

float fp_gamma_calc(const fpfmt *f, int n)
{
	double nu = (double)n * (double)f->u;
	if (nu >= 0.5)
		return INFINITY; /* no useful bound: widen to everything */
	/* rounded up to float so the bound never shrinks */
	return nextafterf((float)(nu / (1.0 - nu)), INFINITY);
}

int fp_rmode_parse(const char *s)
{
	for (int k = 0; k < FPR_NMODES; k++)
		if (!strcmp(s, mode_names[k]))
			return k;
	return -1;
}

const char *fp_rmode_name(int rmode)
{
	return rmode >= 0 && rmode < FPR_NMODES ? mode_names[rmode] : "?";
}

int fpfmt_parse(fpfmt *f, const char *flag, const char *s, int rmode, diag *d)
{
	char *end;
	errno = 0;
	long e = strtol(s, &end, 10);
	if (end == s || *end != ',' || errno)
		return diag_set(d, flag, 0, 0,
		                "expected E,M (exponent and mantissa bits), got '%s'", s);
	const char *q = end + 1;
	long m = strtol(q, &end, 10);
	if (end == q || *end || errno)
		return diag_set(d, flag, 0, 0,
		                "expected E,M (exponent and mantissa bits), got '%s'", s);
	if (e < 2 || e > 8 || m < 1 || m > 23)
		return diag_set(d, flag, 0, 0,
		                "'%s': exponent bits must be 2..8 and mantissa bits 1..23", s);
	if (fpfmt_init(f, (int)e, (int)m, rmode))
		return diag_set(d, flag, 0, 0, "bad rounding mode %d", rmode);
	return 0;
}

void fpfmt_describe(const fpfmt *f, char *buf, size_t n)
{
	if (f->full)
		snprintf(buf, n, "float");
	else
		snprintf(buf, n, "e%d m%d %s", f->ebits, f->mbits, fp_rmode_name(f->rmode));
}
