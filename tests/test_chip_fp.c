/*
 * test_chip_fp.c: the chip's reduced-precision datapath (chip.fp.*): the
 * chip uses the same shared math as kernel-ref, so at a given format its
 * frame equals kernel-ref's frame rendered with that format bit for bit,
 * while the full-precision reference drifts away as bits are cut.
 */
#include <string.h>

#include "tests/chiptest.h"
#include "tests/testutil.h"

static uint8_t *kref(const world *w, int size, const pkt_precision *pp)
{
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = size;
	ro.prec = pp;
	framebuf fb;
	render_stats st;
	diag d;
	cr_assert_eq(fb_init(&fb, size, size), 0);
	cr_assert_eq(render_frame(&w->m, &w->v, &ro, &fb, &st, &d), 0, "%s", d.msg);
	uint8_t *rgb = malloc((size_t)size * size * 3);
	fb_to_rgb8(&fb, rgb, NULL);
	fb_free(&fb);
	return rgb;
}

static img_cmp chip_vs(const world *w, int size, int mant, const uint8_t *ref)
{
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = size;
	c.chip.fp.trav.mant = c.chip.fp.isect.mant = c.chip.fp.shade.mant = mant;
	diag d;
	chip *ch = chip_create(&c, w, &d);
	cr_assert(ch, "%s", d.msg);
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	tu_assert_report_ok(ch);
	uint8_t *a = malloc((size_t)size * size * 3);
	fb_to_rgb8(&ch->fb, a, NULL);
	img_cmp r = img_compare(a, ref, size, size);
	free(a);
	chip_destroy(ch);
	return r;
}

Test(chip_fp, reduced_formats_match_kernel_ref_at_the_same_format, .timeout = 300)
{
	world_opts o;
	world_opts_default(&o);
	world w;
	diag d;
	cr_assert_eq(world_load(&w, &o, &d), 0, "%s", d.msg);
	const int size = 64;
	uint8_t *full = kref(&w, size, NULL);
	double last_psnr = INFINITY;
	const int mants[] = {23, 16, 10};
	for (int k = 0; k < 3; k++) {
		pkt_precision pp;
		pkt_precision_full(&pp);
		cr_assert_eq(fpfmt_init(&pp.trav, 8, mants[k], FPR_NEAREST), 0);
		pp.isect = pp.shade = pp.trav;
		uint8_t *same = kref(&w, size, &pp);
		img_cmp a = chip_vs(&w, size, mants[k], same);
		cr_assert(a.identical,
		          "%d bits: chip differs from kernel-ref at the same format (%llu px)",
		          mants[k], (unsigned long long)a.differing_pixels);
		img_cmp b = chip_vs(&w, size, mants[k], full);
		if (mants[k] == 23)
			cr_assert(b.identical);
		else
			cr_assert_lt(b.psnr, last_psnr, "%d bits should be further from float",
			             mants[k]);
		last_psnr = b.psnr;
		free(same);
	}
	free(full);
	world_free(&w);
}

Test(chip_fp, config_keys_are_checked)
{
	saar_config c;
	cfg_defaults(&c);
	diag d;
	cr_assert_eq(cfg_set(&c, "chip.fp.isect.mant=12", &d), 0, "%s", d.msg);
	cr_assert_eq(c.chip.fp.isect.mant, 12);
	cr_assert_eq(cfg_set(&c, "chip.fp.round=zero", &d), 0, "%s", d.msg);
	cr_assert_eq(c.chip.fp.round, FPR_ZERO);
	cr_assert_eq(cfg_set(&c, "chip.fp.trav.mant=24", &d), -1);
	cr_assert(strstr(d.msg, "chip.fp.trav.mant"), "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "chip.fp.round=sideways", &d), -1);
}
