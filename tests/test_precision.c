/*
 * test_precision.c: reduced-precision formats (fpfmt.h) and the shared
 * math run through them (issue 7): rounding against a double-precision
 * reference in every mode, range boundaries, the identity fast path, full
 * precision through the new API bit-identical to the old one, no leaks at
 * 12 mantissa bits, image error growing as bits drop, and no crash or hang
 * at one mantissa bit.
 */
#include <math.h>

#include "kernel-ref/fpfmt.h"
#include "kernel-ref/render.h"
#include "kernel-ref/stress.h"
#include "kernel-ref/world.h"
#include "tests/testutil.h"

static uint64_t rng(uint64_t *s)
{
	*s = *s * 6364136223846793005ull + 1442695040888963407ull;
	return *s >> 11;
}

/* The reference: x rounded to e exponent and m mantissa bits in `mode`,
 * computed in double from the format's definition (fpfmt.h). */
static double ref_round(int e, int m, int mode, float xf)
{
	double x = xf;
	if (x != x || isinf(x) || x == 0)
		return x;
	int bias = (1 << (e - 1)) - 1;
	double maxfin = ldexp(2.0 - ldexp(1.0, -m), bias), minnorm = ldexp(1.0, 1 - bias);
	int neg = x < 0, ex;
	double a = fabs(x);
	frexp(a, &ex); /* a in [2^(ex-1), 2^ex) */
	double ulp = ldexp(1.0, ex - 1 - m);
	double lo = floor(a / ulp) * ulp, hi = lo + ulp, r;
	int away = mode == FPR_NEAREST || (mode == FPR_UP && !neg) || (mode == FPR_DOWN && neg);
	if (lo == a)
		r = a;
	else if (mode == FPR_NEAREST) {
		double mid = lo + ulp / 2;
		r = a < mid ? lo : a > mid ? hi : (fmod(lo / ulp, 2.0) == 0 ? lo : hi);
	} else
		r = away ? hi : lo;
	if (r > maxfin)
		r = away ? INFINITY : maxfin;
	else if (r < minnorm)
		r = (mode != FPR_NEAREST && away) ? minnorm : 0.0;
	return neg ? -r : r;
}

Test(precision, rounding_matches_double_reference)
{
	const int fm[][2] = {{8, 23}, {8, 22}, {8, 16}, {8, 12}, {8, 7},  {5, 10},
	                     {6, 9},  {4, 3},  {3, 2},  {2, 1},  {7, 23}, {8, 1}};
	uint64_t s = 12345;
	for (size_t k = 0; k < sizeof fm / sizeof *fm; k++)
		for (int mode = 0; mode < FPR_NMODES; mode++) {
			fpfmt f;
			cr_assert_eq(fpfmt_init(&f, fm[k][0], fm[k][1], mode), 0);
			for (int i = 0; i < 100000; i++) {
				/* normal floats over the whole exponent range, and a
				 * dense band around 1 where ties are frequent */
				uint32_t b = (uint32_t)rng(&s);
				if (i & 1)
					b = (b & 0x807fffffu) |
					    ((uint32_t)(120 + rng(&s) % 16) << 23);
				if (((b >> 23) & 0xffu) == 0 || ((b >> 23) & 0xffu) == 0xffu)
					continue; /* subnormal / inf / NaN: checked below */
				float x = fp_from_bits(b);
				float got = fp_round(&f, x);
				double want = f.full ? x : ref_round(fm[k][0], fm[k][1], mode, x);
				cr_assert((double)got == want && signbit(got) == signbit(x),
				          "e%d m%d %s: %a -> %a, want %a", fm[k][0], fm[k][1],
				          fp_rmode_name(mode), (double)x, (double)got, want);
				/* the directed versions bracket x */
				cr_assert_leq(fp_round_down(&f, x), x);
				cr_assert_geq(fp_round_up(&f, x), x);
			}
		}
}

Test(precision, boundaries)
{
	fpfmt h, b2, f;
	fpfmt_init(&h, 5, 10, FPR_NEAREST); /* IEEE half without subnormals */
	fpfmt_init(&b2, 8, 2, FPR_NEAREST);
	/* overflow: 65504 is half's largest; 65520 is the tie above it */
	cr_assert_eq(fp_round(&h, 65504.0f), 65504.0f);
	cr_assert_eq(fp_round(&h, 65519.0f), 65504.0f);
	cr_assert(isinf(fp_round(&h, 65520.0f)) && fp_round(&h, -65520.0f) < 0);
	cr_assert_eq(fp_round_down(&h, 1e6f), 65504.0f);
	cr_assert(isinf(fp_round_up(&h, 1e6f)));
	fpfmt_init(&f, 5, 10, FPR_ZERO);
	cr_assert_eq(fp_round(&f, 1e6f), 65504.0f);
	/* flush: half's smallest normal is 2^-14 */
	cr_assert_eq(fp_round(&h, 0x1p-14f), 0x1p-14f);
	cr_assert_eq(fp_round(&h, 0x1p-15f), 0.0f);
	cr_assert(signbit(fp_round(&h, -0x1p-15f)));
	cr_assert_eq(fp_round_up(&h, 0x1p-15f), 0x1p-14f);
	cr_assert_eq(fp_round_down(&h, 0x1p-15f), 0.0f);
	cr_assert_eq(fp_round_down(&h, -0x1p-15f), -0x1p-14f);
	cr_assert_eq(fp_round_up(&h, -0x1p-15f), 0.0f);
	/* float subnormals are flushed at 8 exponent bits too */
	cr_assert_eq(fp_round(&b2, 0x1p-140f), 0.0f);
	cr_assert_eq(fp_round_up(&b2, 0x1p-140f), 0x1p-126f);
	/* ties to even: 1.001b -> 1.0, 1.011b -> 1.1b, 1.101b -> 1.11b... */
	cr_assert_eq(fp_round(&b2, 1.125f), 1.0f);
	cr_assert_eq(fp_round(&b2, 1.375f), 1.5f);
	cr_assert_eq(fp_round(&b2, 1.625f), 1.5f);
	cr_assert_eq(fp_round(&b2, 1.875f), 2.0f); /* carry into the exponent */
	cr_assert_eq(fp_round(&b2, -1.125f), -1.0f);
	/* NaN stays NaN, infinities stay */
	cr_assert(isnan(fp_round(&h, NAN)));
	cr_assert(isnan(fp_round_up(&b2, NAN)));
	cr_assert(isinf(fp_round(&h, INFINITY)) && fp_round(&h, -INFINITY) < 0);
	fpfmt_init(&f, 5, 10, FPR_ZERO);
	cr_assert(isinf(fp_round(&f, INFINITY)));
	/* gamma: finite while n u is small, infinite when no bound exists */
	double u = 0x1p-11 + 0x1p-24; /* half's roundoff + the emulation's float step */
	cr_assert_float_eq(fp_gamma(&h, 1), u / (1 - u), 1e-9);
	cr_assert_geq(fp_gamma(&h, 3), 3 * u / (1 - 3 * u));
	fpfmt_init(&f, 8, 1, FPR_NEAREST);
	cr_assert(isinf(fp_gamma(&f, 5)));
	/* parsing */
	diag d;
	cr_assert_eq(fpfmt_parse(&f, "--fp-trav", "8,12", FPR_ZERO, &d), 0);
	cr_assert(f.ebits == 8 && f.mbits == 12 && f.rmode == FPR_ZERO && !f.full);
	cr_assert_neq(fpfmt_parse(&f, "--fp-trav", "9,12", FPR_NEAREST, &d), 0);
	cr_assert(strstr(d.msg, "--fp-trav"), "%s", d.msg);
	cr_assert_neq(fpfmt_parse(&f, "--fp-trav", "8", FPR_NEAREST, &d), 0);
	cr_assert_eq(fp_rmode_parse("zero"), FPR_ZERO);
	cr_assert_eq(fp_rmode_parse("sideways"), -1);
}

Test(precision, full_format_is_the_identity)
{
	for (int mode = 0; mode < FPR_NMODES; mode++) {
		fpfmt f;
		fpfmt_init(&f, 8, 23, mode);
		cr_assert(f.full);
		uint64_t s = 99;
		for (int i = 0; i < 200000; i++) {
			uint32_t b = (uint32_t)rng(&s); /* any bits: subnormals, inf, NaN */
			uint32_t r = fp_bits(fp_round(&f, fp_from_bits(b)));
			cr_assert_eq(r, b, "%08x -> %08x", b, r);
		}
	}
}

static void load_default(world *w)
{
	world_opts o;
	world_opts_default(&o);
	diag d;
	cr_assert_eq(world_load(w, &o, &d), 0, "%s", d.msg);
}

/* Renders the embedded scene at res x res with prec (NULL: full). */
static void render(const world *w, int res, const pkt_precision *prec, int single, framebuf *fb,
                   render_stats *st)
{
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = res;
	ro.prec = prec;
	ro.single_ray = single;
	diag d;
	cr_assert_eq(fb_init(fb, res, res), 0);
	cr_assert_eq(render_frame(&w->m, &w->v, &ro, fb, st, &d), 0, "%s", d.msg);
}

static int same_frame(const framebuf *a, const framebuf *b)
{
	return !memcmp(a->acc, b->acc, (size_t)a->w * (size_t)a->h * 3 * sizeof(uint64_t));
}

Test(precision, full_precision_api_is_bit_identical, .timeout = 120)
{
	world w;
	load_default(&w);
	pkt_precision full;
	pkt_precision_full(&full);
	framebuf a, b, c, e;
	render_stats sa, sb, sc, se;
	render(&w, 96, NULL, 0, &a, &sa);
	render(&w, 96, &full, 0, &b, &sb);
	render(&w, 96, &full, 1, &c, &sc);
	render(&w, 96, NULL, 1, &e, &se);
	cr_assert(same_frame(&a, &b), "full precision through pkt_precision changed the image");
	cr_assert(same_frame(&e, &c), "single-ray path with full pkt_precision changed the image");
	cr_assert_eq(sa.trav.node_steps, sb.trav.node_steps);
	cr_assert_eq(sa.trav.ray_tri_tests, sb.trav.ray_tri_tests);
	fb_free(&a);
	fb_free(&b);
	fb_free(&c);
	fb_free(&e);
	world_free(&w);
}

static pkt_precision reduced(int m, int trav_isect, int shade)
{
	pkt_precision p;
	pkt_precision_full(&p);
	if (trav_isect) {
		fpfmt_init(&p.trav, 8, m, FPR_NEAREST);
		fpfmt_init(&p.isect, 8, m, FPR_NEAREST);
	}
	if (shade)
		fpfmt_init(&p.shade, 8, m, FPR_NEAREST);
	return p;
}

Test(precision, no_leaks_at_12_mantissa_bits, .timeout = 300)
{
	const int modes[] = {FPR_NEAREST, FPR_ZERO};
	for (int k = 0; k < 2; k++) {
		pkt_precision p;
		pkt_precision_full(&p);
		fpfmt_init(&p.trav, 8, 12, modes[k]);
		fpfmt_init(&p.isect, 8, 12, modes[k]);
		const double scales[] = {1e-4, 1, 1e4};
		for (size_t i = 0; i < 3; i++) {
			stress_result r = stress_sphere_fp(scales[i], 0, 48, &p);
			cr_assert_gt(r.rays, 0);
			cr_assert_eq(r.leaked, 0, "%s, 12 bits %s: %llu leaked", r.name,
			             fp_rmode_name(modes[k]), (unsigned long long)r.leaked);
		}
		stress_result r = stress_sphere_fp(100, 1e5, 48, &p);
		cr_assert_eq(r.leaked, 0, "%s: %llu leaked", r.name, (unsigned long long)r.leaked);
	}
	/* 8 bits as well, at one scale */
	pkt_precision p8 = reduced(8, 1, 0);
	stress_result r = stress_sphere_fp(1, 0, 48, &p8);
	cr_assert_eq(r.leaked, 0, "8 bits: %llu leaked", (unsigned long long)r.leaked);
}

static double psnr_of(const world *w, const framebuf *ref, const pkt_precision *p, int res)
{
	framebuf fb;
	render_stats st;
	render(w, res, p, 0, &fb, &st);
	size_t n = (size_t)res * (size_t)res * 3;
	uint8_t *a = malloc(n), *b = malloc(n);
	fb_to_rgb8(ref, a, NULL);
	fb_to_rgb8(&fb, b, NULL);
	img_cmp c = img_compare(a, b, res, res);
	free(a);
	free(b);
	fb_free(&fb);
	return c.psnr;
}

Test(precision, image_error_grows_as_bits_drop, .timeout = 300)
{
	world w;
	load_default(&w);
	framebuf ref;
	render_stats st;
	render(&w, 96, NULL, 0, &ref, &st);
	pkt_precision p16 = reduced(16, 1, 0), p8 = reduced(8, 1, 0);
	pkt_precision s16 = reduced(16, 0, 1), s8 = reduced(8, 0, 1);
	double a16 = psnr_of(&w, &ref, &p16, 96), a8 = psnr_of(&w, &ref, &p8, 96);
	double b16 = psnr_of(&w, &ref, &s16, 96), b8 = psnr_of(&w, &ref, &s8, 96);
	cr_assert_lt(a8, a16, "traversal+intersection: 8 bits %.1f dB vs 16 bits %.1f dB", a8, a16);
	cr_assert_lt(b8, b16, "shading: 8 bits %.1f dB vs 16 bits %.1f dB", b8, b16);
	cr_assert_gt(a16, 30.0, "16 bits should be close to float (%.1f dB)", a16);
	fb_free(&ref);
	world_free(&w);
}

Test(precision, one_mantissa_bit_finishes, .timeout = 300)
{
	/* no usable error bound at all: traversal widens to everything; the
	 * run must simply finish */
	world w;
	load_default(&w);
	pkt_precision p1 = reduced(1, 1, 1);
	framebuf fb;
	render_stats st;
	render(&w, 16, &p1, 0, &fb, &st);
	cr_assert_gt(st.rays[PKT_PRIMARY], 0);
	fb_free(&fb);
	render(&w, 16, &p1, 1, &fb, &st);
	fb_free(&fb);
	world_free(&w);
	stress_result r = stress_sphere_fp(1, 0, 16, &p1);
	cr_assert_gt(r.rays, 0);
}

/* A packet of rays that pass just above the scene box (each origin a
 * little higher, each direction along x with a slight fall): at full
 * precision none enters the box; in a coarse traversal format, whose clip
 * is widened by that format's error bound, some do. */
static void grazing_packet(packet *p, const aabb *b)
{
	pkt_clear(p, PKT_PRIMARY, 0);
	float h = b->hi.y - b->lo.y, wdt = b->hi.x - b->lo.x;
	for (int i = 0; i < PKT_RAYS; i++) {
		p->ox[i] = b->lo.x - 0.5f * wdt;
		p->oy[i] = b->hi.y + h * (0.002f + 0.002f * (float)i);
		p->oz[i] = 0.5f * (b->lo.z + b->hi.z);
		p->dx[i] = 1.0f;
		p->dy[i] = -1e-4f;
		p->dz[i] = 0.0f;
		p->tmax[i] = INFINITY;
	}
	p->valid = ~0ull;
	p->n = PKT_RAYS;
}

/* pkt_trace_fp stops a packet after the clip when no ray enters the box
 * (traverse.c's trav_begin, lazy), at full precision only: a reduced
 * traversal format redoes the clip in that format, which can let rays in
 * that the full-precision clip kept out. The mistake this catches: the
 * stop taken in a reduced format too (those rays never traversed;
 * tests/mutants/99-lazy-clip-in-a-reduced-format.patch). The reference
 * is the chip's way, which sets every constant up first
 * (pkt_trav_begin_fp) and then runs the same loop (pkt_trace_run). */
Test(precision, a_reduced_clip_lets_in_what_the_full_clip_kept_out)
{
	world w;
	load_default(&w);
	static packet a, b;
	static trav_entry stack[PKT_STACK_MAX];
	trav_state s;
	grazing_packet(&a, &w.m.bounds);
	cr_assert_eq(pkt_trav_begin(&s, &a, &w.m, stack, PKT_STACK_MAX), 0,
	             "the set-up is wrong: a ray enters the box at full precision");
	pkt_precision pr = reduced(2, 1, 0);
	grazing_packet(&b, &w.m.bounds);
	uint64_t want = pkt_trav_begin_fp(&s, &b, &w.m, stack, PKT_STACK_MAX, &pr);
	cr_assert_neq(want, 0, "the set-up is wrong: no ray enters in the 2-bit format");
	trav_counts cw = {0}, cg = {0};
	pkt_trace_run(&s, &b, &w.m, NULL, &cw);
	grazing_packet(&a, &w.m.bounds);
	uint64_t got = pkt_trace_fp(&a, &w.m, stack, PKT_STACK_MAX, &cg, &pr);
	cr_assert_eq(got, want, "entered %#llx, the full set-up's %#llx", (unsigned long long)got,
	             (unsigned long long)want);
	cr_assert_eq(cg.node_steps, cw.node_steps, "%llu node steps, the full set-up's %llu",
	             (unsigned long long)cg.node_steps, (unsigned long long)cw.node_steps);
	cr_assert_gt(cw.node_steps, 0);
	world_free(&w);
}
