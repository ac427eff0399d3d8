/*
 * rtref.c: the reference packet tracer's command line.
 *
 *   rtref [--scene P | --views F --view N] [--size WxH] [--threads N]
 *         [--depth N] [--no-shadows] [--single-ray] [--cone-cull] [--per-lane]
 *         [--out FILE]
 *         [--accel kd|grid] [--grid-lambda F] [--grid-macro N] [--grid-packet N]
 *         [--stats FILE.json] [--anim-time T] [--anim-fps F --frames N]
 *         [--fp-trav E,M] [--fp-isect E,M] [--fp-shade E,M] [--fp-round MODE]
 *
 * Prints one summary line; writes the frame (PNG, EXR, ... by extension)
 * and a JSON stats file. An animated (AFF) scene renders N frames at
 * T + i/F with --frames N, each its own summary line and files (the
 * frame number before the extension: out-0003.png). Bad input: one line on stderr, exit status 2,
 * no output file.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/grid.h"
#include "kernel-ref/image.h"
#include "kernel-ref/jsonw.h"
#include "kernel-ref/render.h"
#include "kernel-ref/simd.h"
#include "kernel-ref/twolevel.h"
#include "kernel-ref/world.h"

static void usage(FILE *f)
{
	fprintf(
	    f,
	    "usage: rtref [options]\n"
	    "  --size WxH            frame size (default 512x512; 1..16384 each)\n"
	    "  --threads N           host threads (default 1; 1..1024)\n"
	    "  --depth N             reflection/refraction depth (default 3; 0..16)\n"
	    "  --no-shadows          primary (and secondary) rays only, no shadow rays\n"
	    "  --single-ray          trace with the scalar single-ray path (for checking)\n"
	    "  --cone-cull           packets skip leaf triangles outside their rays' cone\n"
	    "                        (seed 004; the same frame; packets: not with --single-ray)\n"
	    "  --per-lane            trace packets by the chip's per-lane traversal instead\n"
	    "                        of the packet interval walk (frustum.h; the same frame;\n"
	    "                        not with --single-ray)\n"
	    "  --out FILE            write the frame (.png, .exr, .ppm, .tif)\n"
	    "  --stats FILE.json     write statistics as JSON\n"
	    "  --frames N            AFF scene with --anim-fps: N frames (1..100000) at\n"
	    "                        T + i/F, written as FILE-0000.png, FILE-0001.png, ...\n"
	    "  --fp-trav E,M         traversal in a reduced format: E exponent (2..8) and M\n"
	    "                        mantissa bits (1..23); default full float (8,23)\n"
	    "  --fp-isect E,M        intersection (the Woop test) in a reduced format\n"
	    "  --fp-shade E,M        shading in a reduced format\n"
	    "  --fp-round MODE       their rounding: nearest (default), zero, up, down\n");
	fputs(world_usage, f);
}

/* --two-level: the objects and the two levels' build times. */
static void two_level_stats(jsonw *j, const tl_scene *t)
{
	jsonw_key(j, "two_level");
	jsonw_obj_begin(j);
	jsonw_kuint(j, "instances", t->ninst);
	jsonw_kuint(j, "objects", t->nobj);
	jsonw_knum(j, "bottom_build_ms", t->build_ms);
	jsonw_knum(j, "top_build_ms", t->frame_ms);
	jsonw_obj_end(j);
}

/* --accel grid: the grid and its build time. */
static void grid_stats(jsonw *j, const grid *g)
{
	jsonw_key(j, "grid");
	jsonw_obj_begin(j);
	grid_json_fields(j, g);
	jsonw_knum(j, "build_ms", g->build_ms);
	jsonw_obj_end(j);
}

static void write_stats(jsonw *j, const world *w, const render_opts *o, const render_stats *st)
{
	uint64_t total = 0;
	for (int t = 0; t < PKT_NTYPES; t++)
		total += st->rays[t];
	jsonw_obj_begin(j);
	jsonw_kstr(j, "program", "rtref");
	jsonw_kstr(j, "scene", w->scene_label);
	if (w->aff)
		jsonw_knum(j, "anim_time", w->anim_time);
	jsonw_kstr(j, "view", w->v.name);
	view_json(j, &w->v);
	jsonw_kuint(j, "triangles", w->s.ntris);
	jsonw_key(j, "size");
	jsonw_arr_begin(j);
	jsonw_int(j, o->width);
	jsonw_int(j, o->height);
	jsonw_arr_end(j);
	jsonw_kint(j, "threads", o->threads);
	jsonw_kint(j, "max_depth", o->max_depth);
	jsonw_kint(j, "lights", w->v.nlights);
	jsonw_kstr(j, "path",
	           o->single_ray ? "single-ray"
	           : o->frustum  ? "packet-frustum"
	                         : "packet");
	jsonw_kint(j, "simd_lanes", SIMD_W); /* the packet groups' width, set by ARCH */
	if (o->prec) {
		char buf[64];
		jsonw_key(j, "precision");
		jsonw_obj_begin(j);
		fpfmt_describe(&o->prec->trav, buf, sizeof buf);
		jsonw_kstr(j, "traversal", buf);
		fpfmt_describe(&o->prec->isect, buf, sizeof buf);
		jsonw_kstr(j, "intersection", buf);
		fpfmt_describe(&o->prec->shade, buf, sizeof buf);
		jsonw_kstr(j, "shading", buf);
		jsonw_obj_end(j);
	}
	jsonw_key(j, "rays");
	jsonw_obj_begin(j);
	for (int t = 0; t < PKT_NTYPES; t++)
		jsonw_kuint(j, pkt_type_name(t), st->rays[t]);
	jsonw_kuint(j, "total", total);
	jsonw_obj_end(j);
	jsonw_key(j, "packets");
	jsonw_obj_begin(j);
	for (int t = 0; t < PKT_NTYPES; t++)
		jsonw_kuint(j, pkt_type_name(t), st->packets[t]);
	jsonw_obj_end(j);
	jsonw_kuint(j, "kd_node_visits", st->trav.node_steps);
	jsonw_kuint(j, "leaf_visits", st->trav.leaf_visits);
	jsonw_kuint(j, "triangle_tests", st->trav.tri_tests);
	jsonw_kuint(j, "ray_triangle_tests", st->trav.ray_tri_tests);
	jsonw_kuint(j, "max_stack_depth", st->trav.max_sp);
	jsonw_kbool(j, "cone_cull", o->cone_cull);
	jsonw_kuint(j, "cone_culled", st->trav.cone_culled);
	jsonw_kuint(j, "cone_saved_ray_tests", st->trav.cone_saved_ray_tests);
	jsonw_key(j, "skipped");
	jsonw_obj_begin(j);
	jsonw_kuint(j, "box_miss_packets", st->box_miss_packets);
	jsonw_kuint(j, "box_miss_rays", st->box_miss_rays);
	jsonw_kuint(j, "shadow_rays_no_lights", st->shade.shadow_skip_nolight);
	jsonw_kuint(j, "shadow_rays_light_behind", st->shade.shadow_skip_facing);
	jsonw_kuint(j, "packets_without_secondary", st->shade.secondary_skip);
	jsonw_kuint(j, "rays_cut_by_depth", st->shade.depth_cut);
	jsonw_kuint(j, "untextured_hits", st->shade.untextured_hits);
	jsonw_obj_end(j);
	jsonw_kuint(j, "texel_reads", st->shade.texel_reads);
	jsonw_kuint(j, "shadow_rays_occluded", st->shade.shadow_hits);
	jsonw_key(j, "kdtree");
	jsonw_obj_begin(j);
	jsonw_kuint(j, "nodes", w->kd.nnodes);
	jsonw_kuint(j, "leaves", w->kd.nleaves);
	jsonw_kuint(j, "empty_leaves", w->kd.nempty_leaves);
	jsonw_kint(j, "depth", w->kd.depth);
	jsonw_kuint(j, "budget_leaves", w->kd.nbudget_leaves);
	jsonw_knum(j, "sah_cost", w->kd.sah_cost);
	/* the SAH's packet footprint (kdtree.c): growth per side in scene
	 * units, from the view's packet or a fraction of the scene */
	jsonw_knum(j, "footprint_grow", w->kd.fp_grow);
	jsonw_kstr(j, "footprint_from",
	           w->kd.fp_angle > 0  ? "view"
	           : w->kd.fp_grow > 0 ? "scene"
	                               : "none");
	jsonw_obj_end(j);
	if (w->tl)
		two_level_stats(j, w->tl);
	/* with a grid, kd_node_visits counts slice (or DDA) steps and
	 * leaf_visits the cells visited */
	jsonw_kstr(j, "accel", w->grid ? "grid" : w->tl ? "two-level" : "kd");
	if (w->grid)
		grid_stats(j, w->grid);
	jsonw_kuint(j, "memory_image_bytes", w->m.size);
	jsonw_knum(j, "load_ms", w->load_ms);
	jsonw_knum(j, "build_ms", w->kd_ms);
	jsonw_knum(j, "image_ms", w->image_ms);
	jsonw_kstr(j, "world_cache", world_cache_name(w->cache));
	world_cache_json(j, w);
	jsonw_knum(j, "render_ms", st->render_ms);
	jsonw_knum(j, "mrays_per_s", st->render_ms > 0 ? (double)total / (st->render_ms * 1e3) : 0);
	/* tracing only (traversal + intersection, no ray generation or shading),
	 * per host thread: the figure comparable with other ray tracers' kernels */
	jsonw_knum(j, "trace_ms", st->trace_ms);
	jsonw_knum(j, "trace_mrays_per_s_per_thread",
	           st->trace_ms > 0 ? (double)total / (st->trace_ms * 1e3) : 0);
	jsonw_obj_end(j);
}

/* The command line. */
typedef struct cli {
	world_opts wo;
	render_opts ro;
	const char *out, *stats;
	int frames;            /* --frames N (animation) */
	const char *fp_arg[3]; /* traversal, intersection, shading */
	int fp_mode;
	pkt_precision prec; /* ro.prec points here when a format is given */
} cli;

/* The value flags; 0, or the exit status after the message. */
static int value_flag(cli *a, const char *f, const char *v, diag *d)
{
	long n;
	if (!strcmp(f, "--size")) {
		if (cli_parse_size(v, &a->ro.width, &a->ro.height, d))
			return cli_bad("rtref", d->msg);
	} else if (!strcmp(f, "--threads")) {
		if (cli_parse_int(f, v, 1, 1024, &n, d))
			return cli_bad("rtref", d->msg);
		a->ro.threads = (int)n;
	} else if (!strcmp(f, "--depth")) {
		if (cli_parse_int(f, v, 0, 16, &n, d))
			return cli_bad("rtref", d->msg);
		a->ro.max_depth = (int)n;
	} else if (!strcmp(f, "--frames")) {
		if (cli_parse_int(f, v, 1, 100000, &n, d))
			return cli_bad("rtref", d->msg);
		a->frames = (int)n;
	} else if (!strcmp(f, "--out")) {
		a->out = v;
	} else if (!strcmp(f, "--stats")) {
		a->stats = v;
	} else if (!strcmp(f, "--fp-trav") || !strcmp(f, "--fp-isect") ||
	           !strcmp(f, "--fp-shade")) {
		a->fp_arg[f[5] == 't' ? 0 : f[5] == 'i' ? 1 : 2] = v;
	} else if (!strcmp(f, "--fp-round")) {
		a->fp_mode = fp_rmode_parse(v);
		if (a->fp_mode < 0) {
			fprintf(stderr,
			        "rtref: --fp-round: expected nearest, zero, up or down, got '%s'\n",
			        v);
			return DIAG_EXIT;
		}
	} else {
		fprintf(stderr, "rtref: %s: unknown option (see --help)\n", f);
		return DIAG_EXIT;
	}
	return 0;
}

/* Reads the arguments into a, the number formats last (--fp-round may
 * come after them). Returns -1 to go on, else the exit status (0 after
 * --help). */
static int parse_args(int argc, char **argv, cli *a, diag *d)
{
	memset(a, 0, sizeof *a);
	a->frames = 1;
	world_opts_default(&a->wo);
	render_opts_default(&a->ro);
	a->ro.frustum = 1;
	a->fp_mode = FPR_NEAREST;
	pkt_precision_full(&a->prec);
	for (int i = 1; i < argc;) {
		int r = world_parse_arg(&a->wo, argc, argv, &i, d);
		if (r < 0)
			return cli_bad("rtref", d->msg);
		if (r > 0)
			continue;
		const char *f = argv[i];
		if (!strcmp(f, "-h") || !strcmp(f, "--help")) {
			usage(stdout);
			return 0;
		}
		if (!strcmp(f, "--cone-cull") || !strcmp(f, "--per-lane")) {
			*(f[2] == 'c' ? &a->ro.cone_cull : &a->ro.frustum) = f[2] == 'c';
			i++;
			continue;
		}
		if (!strcmp(f, "--no-shadows") || !strcmp(f, "--single-ray")) {
			*(f[2] == 'n' ? &a->ro.shadows : &a->ro.single_ray) = f[2] == 'n' ? 0 : 1;
			i++;
			continue;
		}
		if (i + 1 >= argc) {
			fprintf(stderr, "rtref: %s: unknown option or missing value (see --help)\n",
			        f);
			return DIAG_EXIT;
		}
		int rc = value_flag(a, f, argv[i + 1], d);
		if (rc)
			return rc;
		i += 2;
	}
	static const char *const fp_flag[3] = {"--fp-trav", "--fp-isect", "--fp-shade"};
	fpfmt *fp_dst[3] = {&a->prec.trav, &a->prec.isect, &a->prec.shade};
	for (int k = 0; k < 3; k++)
		if (a->fp_arg[k] && fpfmt_parse(fp_dst[k], fp_flag[k], a->fp_arg[k], a->fp_mode, d))
			return cli_bad("rtref", d->msg);
	if (a->fp_arg[0] || a->fp_arg[1] || a->fp_arg[2])
		a->ro.prec = &a->prec;
	if (a->frames > 1 && !a->wo.have_anim_fps)
		return cli_bad("rtref", "--frames: needs --anim-fps F (frame i is at T + i/F)");
	if (world_opts_check(&a->wo, d))
		return cli_bad("rtref", d->msg);
	/* the packet-only options would be ignored without a word */
	if (a->ro.single_ray && (a->ro.cone_cull || !a->ro.frustum))
		return cli_bad("rtref", a->ro.cone_cull
		                            ? "--cone-cull: packets only, not with --single-ray"
		                            : "--per-lane: packets only, not with --single-ray");
	world_opts_packet_tree(&a->wo, a->ro.height); /* rtref's own tree */
	return -1;
}

/* The image and the statistics appear together or not at all. Returns
 * the exit status. */
static int write_outputs(const cli *a, const char *out, const char *stats, const world *w,
                         const framebuf *fb, const render_stats *st, diag *d)
{
	af_group outs = {0};
	if (out && fb_write(fb, out, &outs, d))
		return cli_bad("rtref", d->msg);
	if (stats) {
		jsonw j;
		if (jsonw_open(&j, stats, d)) {
			af_group_abort(&outs);
			return cli_bad("rtref", d->msg);
		}
		j.group = &outs;
		write_stats(&j, w, &a->ro, st);
		if (jsonw_close(&j, d)) {
			af_group_abort(&outs);
			return cli_bad("rtref", d->msg);
		}
	}
	if (af_group_commit(&outs, d))
		return cli_bad("rtref", d->msg);
	return 0;
}

/* The one summary line on stdout. */
static void print_summary(const cli *a, const char *out, const world *w, const render_stats *st)
{
	const render_opts *ro = &a->ro;
	uint64_t total = 0;
	for (int t = 0; t < PKT_NTYPES; t++)
		total += st->rays[t];
	char kd[160];
	if (w->tl)
		snprintf(kd, sizeof kd,
		         "two-level: %u instances of %u objects (their trees built once in %.1f "
		         "ms), top level built in %.2f ms",
		         w->tl->ninst, w->tl->nobj, w->tl->build_ms, w->tl->frame_ms);
	else if (w->grid)
		snprintf(kd, sizeof kd, "grid %dx%dx%d with %u references built in %.1f ms",
		         w->grid->n[0], w->grid->n[1], w->grid->n[2], w->grid->nrefs,
		         w->grid->build_ms);
	else if (w->cache == WORLD_CACHE_HIT)
		snprintf(kd, sizeof kd, "kd-tree %u nodes from the world cache", w->kd.nnodes);
	else
		snprintf(kd, sizeof kd, "kd-tree %u nodes built in %.1f ms", w->kd.nnodes,
		         w->kd_ms);
	printf("rtref: %s, view %s, %dx%d, %d thread%s: %llu rays (%llu primary, %llu shadow, %llu "
	       "reflection, %llu refraction) in %.1f ms = %.2f Mrays/s; %s%s%s\n",
	       w->scene_label, w->v.name, ro->width, ro->height, ro->threads,
	       ro->threads == 1 ? "" : "s", (unsigned long long)total,
	       (unsigned long long)st->rays[PKT_PRIMARY], (unsigned long long)st->rays[PKT_SHADOW],
	       (unsigned long long)st->rays[PKT_REFLECT], (unsigned long long)st->rays[PKT_REFRACT],
	       st->render_ms, st->render_ms > 0 ? (double)total / (st->render_ms * 1e3) : 0.0, kd,
	       out ? "; wrote " : "", out ? out : "");
}

/* Frame i: the world moved to its time (after the first), rendered and
 * written. Returns the exit status. */
static int render_one(const cli *a, world *w, framebuf *fb, int i, diag *d)
{
	if (i > 0 && world_set_time(w, &a->wo, world_frame_time(&a->wo, i), d))
		return cli_bad("rtref", d->msg);
	char ob[4096], sb[4096];
	const char *out = cli_frame_path(a->out, a->frames, i, ob, sizeof ob);
	const char *stats = cli_frame_path(a->stats, a->frames, i, sb, sizeof sb);
	render_stats st;
	fb_clear(fb); /* render_frame adds into it */
	if (render_frame(&w->m, &w->v, &a->ro, fb, &st, d))
		return cli_bad("rtref", d->msg);
	int rc = write_outputs(a, out, stats, w, fb, &st, d);
	if (!rc)
		print_summary(a, out, w, &st);
	return rc;
}

int main(int argc, char **argv)
{
	static cli a;
	diag d = {{0}};
	int rc = parse_args(argc, argv, &a, &d);
	if (rc >= 0)
		return rc;
	/* an unwritable --out folder fails now, its format once the scene is
	 * imported (img_reserve_file in image.h: not beside the importer's
	 * fork), both before the run; an animation's numbered files all of them
	 * (frame 0's reserved, the others' paths checked) */
	char ob[4096], sb[4096];
	const char *out0 = cli_frame_path(a.out, a.frames, 0, ob, sizeof ob);
	const char *stats0 = cli_frame_path(a.stats, a.frames, 0, sb, sizeof sb);
	/* numbered alike, so frame 0's names tell (--out x.ppm --stats x.ppm
	 * left the stats in x.ppm) */
	if (out0 && stats0 && strcmp(stats0, "-")) {
		static char ko[8192], ks[8192];
		cli_output_key(out0, ko, sizeof ko);
		cli_output_key(stats0, ks, sizeof ks);
		if (!strcmp(ko, ks))
			return cli_bad("rtref", "--out and --stats name the same file (each would "
			                        "replace the other's)");
	}
	if (out0 && img_reserve_file(out0, &d))
		return cli_bad("rtref", d.msg);
	if (stats0 && strcmp(stats0, "-") && af_reserve(stats0, "", &d))
		return cli_bad("rtref", d.msg);
	if (cli_check_frame_paths(a.out, a.frames, &d) ||
	    cli_check_frame_paths(a.stats, a.frames, &d))
		return cli_bad("rtref", d.msg);
	world w;
	if (world_load(&w, &a.wo, &d))
		return cli_bad("rtref", d.msg);
	if (a.out && img_can_write(a.out, &d)) {
		world_free(&w);
		return cli_bad("rtref", d.msg);
	}
	if (w.tl)
		a.ro.tracer = &w.tl->tracer;
	if (w.grid)
		a.ro.tracer = &w.grid->tracer;
	if (w.grid && (a.ro.prec || a.ro.cone_cull)) {
		world_free(&w);
		return cli_bad("rtref",
		               "--accel grid: traces at full precision without cone culling "
		               "(no --fp-*, --cone-cull)");
	}
	if (w.tl && a.ro.prec) {
		world_free(&w);
		return cli_bad("rtref", "--two-level: traces at full precision only (no --fp-*)");
	}
	if (w.tl && a.ro.cone_cull) {
		world_free(&w);
		return cli_bad("rtref",
		               "--two-level: its tracer does not cull by cone (no --cone-cull)");
	}
	framebuf fb;
	if (fb_init(&fb, a.ro.width, a.ro.height)) {
		world_free(&w);
		return cli_bad("rtref", "out of memory for the frame buffer");
	}
	rc = 0;
	for (int i = 0; i < a.frames && !rc; i++)
		rc = render_one(&a, &w, &fb, i, &d);
	fb_free(&fb);
	world_free(&w);
	return rc;
}
