/*
 * rtref.c: the reference packet tracer's command line.
 *
 *   rtref [--scene P | --views F --view N] [--size WxH] [--threads N]
 *         [--depth N] [--no-shadows] [--single-ray] [--out FILE] [--stats FILE.json]
 *         [--fp-trav E,M] [--fp-isect E,M] [--fp-shade E,M] [--fp-round MODE]
 *
 * Prints one summary line; writes the frame (PNG, EXR, ... by extension)
 * and a JSON stats file. Bad input: one line on stderr, exit status 2, no
 * output file.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/image.h"
#include "kernel-ref/jsonw.h"
#include "kernel-ref/render.h"
#include "kernel-ref/world.h"

static void usage(FILE *f)
{
	fprintf(f,
	        "usage: rtref [options]\n"
	        "  --size WxH            frame size (default 512x512; 1..16384 each)\n"
	        "  --threads N           host threads (default 1; 1..1024)\n"
	        "  --depth N             reflection/refraction depth (default 3; 0..16)\n"
	        "  --no-shadows          primary (and secondary) rays only, no shadow rays\n"
	        "  --single-ray          trace with the scalar single-ray path (for checking)\n"
	        "  --out FILE            write the frame (.png, .exr, .ppm, .tif)\n"
	        "  --stats FILE.json     write statistics as JSON\n"
	        "  --fp-trav E,M         traversal in a reduced format: E exponent (2..8) and M\n"
	        "                        mantissa bits (1..23); default full float (8,23)\n"
	        "  --fp-isect E,M        intersection (the Woop test) in a reduced format\n"
	        "  --fp-shade E,M        shading in a reduced format\n"
	        "  --fp-round MODE       their rounding: nearest (default), zero, up, down\n");
	fputs(world_usage, f);
}

static void write_stats(jsonw *j, const world *w, const render_opts *o, const render_stats *st)
{
	uint64_t total = 0;
	for (int t = 0; t < PKT_NTYPES; t++)
		total += st->rays[t];
	jsonw_obj_begin(j);
	jsonw_kstr(j, "program", "rtref");
	jsonw_kstr(j, "scene", w->scene_label);
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
	jsonw_kstr(j, "path", o->single_ray ? "single-ray" : "packet");
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
	jsonw_obj_end(j);
	jsonw_kuint(j, "memory_image_bytes", w->m.size);
	jsonw_knum(j, "load_ms", w->load_ms);
	jsonw_knum(j, "build_ms", w->kd_ms);
	jsonw_knum(j, "image_ms", w->image_ms);
	jsonw_kstr(j, "world_cache", world_cache_name(w->cache));
	jsonw_knum(j, "render_ms", st->render_ms);
	jsonw_knum(j, "mrays_per_s", st->render_ms > 0 ? (double)total / (st->render_ms * 1e3) : 0);
	/* tracing only (traversal + intersection, no ray generation or shading),
	 * per host thread: the figure comparable with other ray tracers' kernels */
	jsonw_knum(j, "trace_ms", st->trace_ms);
	jsonw_knum(j, "trace_mrays_per_s_per_thread",
	           st->trace_ms > 0 ? (double)total / (st->trace_ms * 1e3) : 0);
	jsonw_obj_end(j);
}

int main(int argc, char **argv)
{
	world_opts wo;
	world_opts_default(&wo);
	render_opts ro;
	render_opts_default(&ro);
	const char *out = NULL, *stats = NULL;
	const char *fp_arg[3] = {NULL, NULL, NULL}; /* traversal, intersection, shading */
	int fp_mode = FPR_NEAREST;
	pkt_precision prec;
	pkt_precision_full(&prec);
	diag d = {{0}};
	for (int i = 1; i < argc;) {
		int r = world_parse_arg(&wo, argc, argv, &i, &d);
		if (r < 0)
			return cli_bad("rtref", d.msg);
		if (r > 0)
			continue;
		const char *a = argv[i];
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			usage(stdout);
			return 0;
		}
		if (!strcmp(a, "--no-shadows") || !strcmp(a, "--single-ray")) {
			*(a[2] == 'n' ? &ro.shadows : &ro.single_ray) = a[2] == 'n' ? 0 : 1;
			i++;
			continue;
		}
		if (i + 1 >= argc) {
			fprintf(stderr, "rtref: %s: unknown option or missing value (see --help)\n",
			        a);
			return DIAG_EXIT;
		}
		const char *v = argv[i + 1];
		long n;
		if (!strcmp(a, "--size")) {
			if (cli_parse_size(v, &ro.width, &ro.height, &d))
				return cli_bad("rtref", d.msg);
		} else if (!strcmp(a, "--threads")) {
			if (cli_parse_int(a, v, 1, 1024, &n, &d))
				return cli_bad("rtref", d.msg);
			ro.threads = (int)n;
		} else if (!strcmp(a, "--depth")) {
			if (cli_parse_int(a, v, 0, 16, &n, &d))
				return cli_bad("rtref", d.msg);
			ro.max_depth = (int)n;
		} else if (!strcmp(a, "--out")) {
			out = v;
		} else if (!strcmp(a, "--stats")) {
			stats = v;
		} else if (!strcmp(a, "--fp-trav") || !strcmp(a, "--fp-isect") ||
		           !strcmp(a, "--fp-shade")) {
			fp_arg[a[5] == 't' ? 0 : a[5] == 'i' ? 1 : 2] = v;
		} else if (!strcmp(a, "--fp-round")) {
			fp_mode = fp_rmode_parse(v);
			if (fp_mode < 0) {
				fprintf(
				    stderr,
				    "rtref: --fp-round: expected nearest, zero, up or down, got "
				    "'%s'\n",
				    v);
				return DIAG_EXIT;
			}
		} else {
			fprintf(stderr, "rtref: %s: unknown option (see --help)\n", a);
			return DIAG_EXIT;
		}
		i += 2;
	}
	/* formats are parsed last: --fp-round may come after them */
	static const char *const fp_flag[3] = {"--fp-trav", "--fp-isect", "--fp-shade"};
	fpfmt *fp_dst[3] = {&prec.trav, &prec.isect, &prec.shade};
	for (int k = 0; k < 3; k++)
		if (fp_arg[k] && fpfmt_parse(fp_dst[k], fp_flag[k], fp_arg[k], fp_mode, &d))
			return cli_bad("rtref", d.msg);
	if (fp_arg[0] || fp_arg[1] || fp_arg[2])
		ro.prec = &prec;
	/* an unwritable --out format fails now, not after the run */
	if (out && img_reserve(out, &d))
		return cli_bad("rtref", d.msg);
	if (stats && strcmp(stats, "-") && af_reserve(stats, "", &d))
		return cli_bad("rtref", d.msg);
	world w;
	if (world_load(&w, &wo, &d))
		return cli_bad("rtref", d.msg);
	framebuf fb;
	if (fb_init(&fb, ro.width, ro.height)) {
		world_free(&w);
		return cli_bad("rtref", "out of memory for the frame buffer");
	}
	render_stats st;
	int rc = 0;
	if (render_frame(&w.m, &w.v, &ro, &fb, &st, &d)) {
		rc = cli_bad("rtref", d.msg);
		goto done;
	}
	/* the image and the statistics appear together or not at all */
	af_group outs = {0};
	if (out && fb_write(&fb, out, &outs, &d)) {
		rc = cli_bad("rtref", d.msg);
		goto done;
	}
	if (stats) {
		jsonw j;
		if (jsonw_open(&j, stats, &d)) {
			af_group_abort(&outs);
			rc = cli_bad("rtref", d.msg);
			goto done;
		}
		j.group = &outs;
		write_stats(&j, &w, &ro, &st);
		if (jsonw_close(&j, &d)) {
			af_group_abort(&outs);
			rc = cli_bad("rtref", d.msg);
			goto done;
		}
	}
	if (af_group_commit(&outs, &d)) {
		rc = cli_bad("rtref", d.msg);
		goto done;
	}
	uint64_t total = 0;
	for (int t = 0; t < PKT_NTYPES; t++)
		total += st.rays[t];
	char kd[96];
	if (w.cache == WORLD_CACHE_HIT)
		snprintf(kd, sizeof kd, "kd-tree %u nodes from the world cache", w.kd.nnodes);
	else
		snprintf(kd, sizeof kd, "kd-tree %u nodes built in %.1f ms", w.kd.nnodes, w.kd_ms);
	printf("rtref: %s, view %s, %dx%d, %d thread%s: %llu rays (%llu primary, %llu shadow, %llu "
	       "reflection, %llu refraction) in %.1f ms = %.2f Mrays/s; %s%s%s\n",
	       w.scene_label, w.v.name, ro.width, ro.height, ro.threads, ro.threads == 1 ? "" : "s",
	       (unsigned long long)total, (unsigned long long)st.rays[PKT_PRIMARY],
	       (unsigned long long)st.rays[PKT_SHADOW], (unsigned long long)st.rays[PKT_REFLECT],
	       (unsigned long long)st.rays[PKT_REFRACT], st.render_ms,
	       st.render_ms > 0 ? (double)total / (st.render_ms * 1e3) : 0.0, kd,
	       out ? "; wrote " : "", out ? out : "");
done:
	fb_free(&fb);
	world_free(&w);
	return rc;
}
