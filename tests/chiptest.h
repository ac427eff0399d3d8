/*
 * chiptest.h: set-up shared by the tests that run the chip model: load a
 * world, build and run a chip, compare its frame with kernel-ref's. Every
 * failure is a test assertion carrying the library's message.
 */
#ifndef SAAR_TESTS_CHIPTEST_H
#define SAAR_TESTS_CHIPTEST_H

#include "kernel-ref/world.h"
#include "sim/chip.h"
#include "sim/reportcheck.h"
#include "tests/testutil.h"

/* Every invariant of the chip's report holds (sim/reportcheck.h). */
static inline void tu_assert_report_ok(const chip *ch)
{
	static rc_list l;
	if (report_check(ch, &l))
		cr_assert_fail("%d report invariants failed; first: %s", l.n, l.msg[0]);
}

/* A small chip (2 RTPs x 4 threads) for size x size frames in fidelity
 * mode, with the VMA when with_vma. */
static inline void tu_cfg_small(saar_config *c, int size, const char *mode, int with_vma)
{
	cfg_defaults(c);
	c->frame.width = c->frame.height = size;
	c->chip.rtps = 2;
	c->chip.threads_per_rtp = 4;
	diag d;
	char kv[64];
	snprintf(kv, sizeof kv, "fidelity=%s", mode);
	cr_assert_eq(cfg_set(c, kv, &d), 0, "%s", d.msg);
	if (with_vma)
		cr_assert_eq(cfg_set(c, "memory.vma.enabled=true", &d), 0, "%s", d.msg);
}

/* Loads the scene at path (NULL: the view's, else the embedded room) with view vname of
 * the views file (NULL: the default view), through a world cache in cache_dir (NULL:
 * none). */
static inline void tu_load_world_cached(world *w, const char *path, const char *views,
                                        const char *vname, const char *cache_dir)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = path;
	o.views = views;
	o.view = vname;
	o.cache_dir = cache_dir;
	diag d;
	cr_assert_eq(world_load(w, &o, &d), 0, "%s", d.msg);
}

static inline void tu_load_world(world *w, const char *path, const char *views, const char *vname)
{
	tu_load_world_cached(w, path, views, vname, NULL);
}

/* kernel-ref's packet render of config c's frame on w: its 8-bit pixels
 * (malloc'd) and, with st, its stats. */
static inline uint8_t *tu_reference(const world *w, const saar_config *c, render_stats *st)
{
	render_opts ro;
	render_opts_default(&ro);
	ro.width = c->frame.width;
	ro.height = c->frame.height;
	ro.max_depth = c->shading.max_depth;
	framebuf fb;
	cr_assert_eq(fb_init(&fb, ro.width, ro.height), 0);
	render_stats own;
	diag d;
	cr_assert_eq(render_frame(&w->m, &w->v, &ro, &fb, st ? st : &own, &d), 0, "%s", d.msg);
	uint8_t *rgb = malloc((size_t)ro.width * ro.height * 3);
	cr_assert(rgb, "out of memory");
	fb_to_rgb8(&fb, rgb, NULL);
	fb_free(&fb);
	return rgb;
}

/* Builds a chip for c and runs every frame (its report's invariants
 * must hold); the caller destroys it. */
static inline chip *tu_run_chip(const world *w, const saar_config *c)
{
	diag d;
	chip *ch = chip_create(c, w, &d);
	cr_assert(ch, "%s", d.msg);
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	tu_assert_report_ok(ch);
	return ch;
}

/* The chip's frame is kernel-ref's, pixel for pixel, both the packet
 * render's and the single-ray render's. */
static inline void tu_assert_identical(chip *ch, const char *what)
{
	chip_check k;
	diag d;
	cr_assert_eq(chip_check_frame(ch, &k, &d), 0, "%s", d.msg);
	cr_assert(k.cmp.identical, "%s: %llu pixels differ from kernel-ref", what,
	          (unsigned long long)k.cmp.differing_pixels);
	cr_assert(k.single.identical, "%s: %llu pixels differ from kernel-ref's single-ray render",
	          what, (unsigned long long)k.single.differing_pixels);
}

#endif
