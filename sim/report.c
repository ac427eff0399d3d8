/*
 * report.c: text summary, JSON report and CSV row (see report.h,
 * docs/report.md).
 *
 * Memory figures per frame come from the cumulative snapshots chip_run takes
 * after every frame (chip.frame_port, chip.frame_mem): a span of frames is
 * the difference of two snapshots, so per-frame, steady-state and whole-run
 * figures are computed the same way and always add up.
 */
#include "sim/report.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/infile.h"
#include "sim/hostmem.h"
#include "sim/memconfig.h"
#include "sim/report_mem.h"
#include "sim/reportcheck.h"

static double ratio(double a, double b)
{
	return b > 0 ? a / b : 0.0;
}

static uint64_t get(const chip *c, const char *name)
{
	return stats_get(&c->st, name);
}

/* ---- fidelity (docs/fidelity.md) ---- */

typedef struct fidfig {
	const char *mode;
	double cycles, half;        /* mean cycles per frame over the steady span; 95% half-width */
	double lo;                  /* the interval's low end: never below the bound */
	double fps, fps_lo, fps_hi; /* fps_hi < 0: unbounded */
	double fps_bound;           /* busiest-resource bound (last frame) */
	const char *bound_by;
} fidfig;

/* Units of the last frame in the memory-bound stratum. */
static int hard_units(const chip_fidelity *F)
{
	int n = 0;
	for (int u = 0; u < F->nreg; u++)
		n += F->unit_pc[u].hard;
	return n;
}

static void fidfig_get(const chip *c, fidfig *x)
{
	const chip_fidelity *F = &c->fid;
	int f0 = c->frames_done > 1 ? 1 : 0, n = c->frames_done - f0;
	double s = 0, h2 = 0, fl = 0;
	for (int f = f0; f < c->frames_done; f++) {
		s += F->est[f];
		h2 += F->half[f] * F->half[f];
		fl += F->even_floor[f];
	}
	double hz = c->cfg.chip.clock_mhz * 1e6;
	x->mode = cfg_enum_name(&c->cfg, "fidelity");
	x->cycles = ratio(s, n);
	x->half = n ? sqrt(h2) / n : 0;
	x->fps = ratio(hz, x->cycles);
	x->fps_lo = ratio(hz, x->cycles + x->half);
	/* sampled: never below the bound of the frame's work spread evenly
	 * over the RTPs; the estimate itself stays at or above the busiest
	 * RTP's work in this run (frame.c), so the run's per-RTP utilisation
	 * stays a rate, but the cycle run hands tiles to the RTPs in another
	 * order, and its busiest RTP may hold less (docs/fidelity.md "A floor
	 * from the sampled run's own tile order") */
	x->lo = fmax(x->cycles - x->half, F->mode == CFG_FIDELITY_SAMPLED ? ratio(fl, n) : -1);
	x->fps_hi = x->lo > 0 ? hz / x->lo : -1;
	/* a frame takes whole cycles: the bound's, rounded up as a
	 * functional frame's cycles_per_frame are (frame.c) */
	x->fps_bound = ratio(hz, ceil(F->res_cycles[F->bound_by]));
	x->bound_by = chip_res_name(F->bound_by);
}

/* The demand model of the last frame (docs/fidelity.md "Demand models"):
 * "max", "pnorm" or "linear", "none" when every tile was detailed. */
static const char *model_name(const chip_fidelity *F)
{
	return F->exact ? "none" : F->model.linear ? "linear" : F->model.p > 0 ? "pnorm" : "max";
}

/* "max, SDRAM factor 1.52, overlap 0.30", "pnorm, p 1.50" or "linear", for
 * the text line. */
static const char *model_str(const chip_fidelity *F, char *buf, size_t n)
{
	if (F->model.linear)
		snprintf(buf, n, "%s", model_name(F));
	else if (F->model.p > 0)
		snprintf(buf, n, "%s, p %.2f", model_name(F), F->model.p);
	else
		snprintf(buf, n, "%s, SDRAM factor %.2f, overlap %.2f", model_name(F), F->model.k,
		         F->model.g);
	return buf;
}

/* " (stored warming, auto; jump skip, memory/compute 0.69)" or "", for the
 * text line: the warming, and the jump the last frame took. */
static const char *warm_str(const chip *c, char *buf, size_t n)
{
	const chip_fidelity *F = &c->fid;
	if (!chip_warm_stored(c))
		snprintf(buf, n, "%s", "");
	else
		snprintf(buf, n, " (stored warming%s; jump %s, memory/compute %.2f)",
		         c->warm_auto ? ", auto" : "", cfg_jump_name(F->jump), F->mem_ratio);
	return buf;
}

static void fidelity_text(FILE *f, const chip *c)
{
	const chip_fidelity *F = &c->fid;
	fidfig x;
	fidfig_get(c, &x);
	if (F->mode == CFG_FIDELITY_FUNCTIONAL)
		fprintf(f,
		        "  fidelity functional: no timing; fps <= %.2f (a bound: the busiest "
		        "resource is %s, %.0f cycles/frame)\n",
		        x.fps_bound, x.bound_by, ceil(F->res_cycles[F->bound_by]));
	else if (chip_estimates(&c->cfg)) {
		char ms[64], ws[96];
		fprintf(f,
		        "  fidelity sampled: %d units (%d memory bound) x %d tiles (+%d warm-up), "
		        "demand %s in the last frame; cycles "
		        "%.0f +- %.0f (95%%), fps %.2f [%.2f, %.2f]; %llu tiles detailed, %llu "
		        "functional%s; %llu replayed from the packet record\n",
		        F->nreg, hard_units(F), F->unit_tiles, F->warmup_tiles,
		        model_str(F, ms, sizeof ms), x.cycles, x.half, x.fps, x.fps_lo, x.fps_hi,
		        (unsigned long long)F->detailed_tiles,
		        (unsigned long long)F->functional_tiles, warm_str(c, ws, sizeof ws),
		        (unsigned long long)F->replayed_tiles);
	} else if (F->mode == CFG_FIDELITY_SAMPLED)
		fputs("  fidelity sampled: every tile detailed (identical to cycle)\n", f);
}

static void fidelity_json(jsonw *j, const chip *c)
{
	const chip_fidelity *F = &c->fid;
	fidfig x;
	fidfig_get(c, &x);
	jsonw_key(j, "fidelity");
	jsonw_obj_begin(j);
	jsonw_kstr(j, "mode", x.mode);
	jsonw_kbool(j, "timed", F->mode != CFG_FIDELITY_FUNCTIONAL);
	jsonw_kbool(j, "estimated", chip_estimates(&c->cfg));
	jsonw_knum(j, "cycles_per_frame", x.cycles);
	jsonw_key(j, "cycles_ci95");
	jsonw_arr_begin(j);
	jsonw_num(j, x.lo);
	jsonw_num(j, x.cycles + x.half);
	jsonw_arr_end(j);
	jsonw_knum(j, "fps", x.fps);
	jsonw_key(j, "fps_ci95");
	jsonw_arr_begin(j);
	jsonw_num(j, x.fps_lo);
	if (x.fps_hi < 0)
		jsonw_null(j);
	else
		jsonw_num(j, x.fps_hi);
	jsonw_arr_end(j);
	if (F->mode == CFG_FIDELITY_SAMPLED) {
		jsonw_kint(j, "units_per_frame", F->nreg);
		jsonw_kint(j, "planned_units", F->nunits);
		jsonw_kint(j, "memory_bound_units", hard_units(F));
		jsonw_kint(j, "unit_tiles", F->unit_tiles);
		jsonw_kint(j, "warmup_tiles", F->warmup_tiles);
		jsonw_knum(j, "sample_rate", c->cfg.sampling.rate);
		jsonw_kstr(j, "demand_model", model_name(F));
		/* the warming that ran, and whether sampling.warming auto chose it */
		jsonw_kstr(j, "warming", chip_warm_stored(c) ? "stored" : "full");
		jsonw_kbool(j, "warming_auto", c->warm_auto);
		/* stored warming: how regions end before a jump (sampling.jump,
		 * auto resolved per frame by its own ratio) */
		jsonw_key(j, "jump_frames");
		jsonw_obj_begin(j);
		for (int q = CFG_JUMP_RELAX; q < CFG_JUMP_AUTO; q++)
			if (F->jump_frames[q])
				jsonw_kint(j, cfg_jump_name(q), F->jump_frames[q]);
		jsonw_obj_end(j);
		jsonw_key(j, "memory_to_compute");
		if (chip_warm_stored(c))
			jsonw_num(j, F->mem_ratio);
		else
			jsonw_null(j);
		int maxm = !F->exact && !F->model.linear && !(F->model.p > 0);
		jsonw_key(j, "sdram_factor");
		if (maxm)
			jsonw_num(j, F->model.k);
		else
			jsonw_null(j);
		jsonw_key(j, "overlap");
		if (maxm)
			jsonw_num(j, F->model.g);
		else
			jsonw_null(j);
		jsonw_key(j, "norm_exponent");
		if (!F->exact && F->model.p > 0 && isfinite(F->model.p))
			jsonw_num(j, F->model.p);
		else
			jsonw_null(j);
		jsonw_key(j, "demand_coefficients");
		if (F->exact || !F->model.linear) {
			jsonw_null(j);
		} else {
			jsonw_obj_begin(j);
			for (int i = 0; i < SMP_LIN; i++)
				jsonw_knum(j, chip_lin_name(i), F->model.beta[i]);
			jsonw_obj_end(j);
		}
		jsonw_key(j, "unit_cycles_per_demand");
		jsonw_arr_begin(j);
		for (int u = 0; u < F->nreg; u++)
			jsonw_num(j, F->unit_rate[u]);
		jsonw_arr_end(j);
	}
	jsonw_kuint(j, "detailed_tiles", F->detailed_tiles);
	jsonw_kuint(j, "functional_tiles", F->functional_tiles);
	jsonw_kuint(j, "replayed_tiles", F->replayed_tiles);
	jsonw_kuint(j, "detailed_cycles", F->detailed_cycles);
	jsonw_knum(j, "fps_bound", x.fps_bound);
	jsonw_kstr(j, "bound_by", x.bound_by);
	jsonw_key(j, "resource_cycles");
	jsonw_obj_begin(j);
	for (int r = 0; r < RES_N; r++)
		jsonw_knum(j, chip_res_name(r), F->res_cycles[r]);
	jsonw_obj_end(j);
	jsonw_obj_end(j);
}

/* Cycles each unit type's reads waited for memory (issue -> data, summed
 * over reads; overlapping reads of one packet all count). The fixed model
 * answers every read after memory.latency cycles. Only timed reads wait:
 * an estimated sampled run scales its detailed regions' waits by the
 * frame's estimated cycles over theirs (the same ratio estimate as its
 * cycles), and a functional run's hierarchy has none to give (-1). */
static double stall_cycles(const chip *c, int type)
{
	const chip_fidelity *F = &c->fid;
	if (type < 0) /* a unit kind without reads of its own (units/unit_table.h) */
		return -1;
	hier_stats h;
	if (hier_get_stats(&c->mem, &h))
		return (double)(c->mem.n.reads[type] * (uint64_t)c->cfg.memory.latency);
	if (F->mode == CFG_FIDELITY_FUNCTIONAL)
		return -1;
	if (chip_estimates(&c->cfg) && F->detailed_cycles)
		return round((double)h.wait_cycles[type] * (double)chip_cycles(c) /
		             (double)F->detailed_cycles);
	return (double)h.wait_cycles[type];
}

/* A ratio, or null where it has no denominator (stored as -1). */
static void knum_or_null(jsonw *j, const char *key, double v)
{
	jsonw_key(j, key);
	if (v < 0)
		jsonw_null(j);
	else
		jsonw_num(j, v);
}

static void memfig_json(jsonw *j, const memfig *m)
{
	jsonw_obj_begin(j);
	jsonw_kint(j, "first_frame", m->first);
	jsonw_kint(j, "last_frame", m->last);
	jsonw_knum(j, "cycles", m->cycles);
	jsonw_knum(j, "fps", m->fps);
	jsonw_knum(j, "sdram_mb", m->sdram_mb);
	jsonw_knum(j, "pci_mb", m->pci_mb);
	jsonw_key(j, "hit_rate");
	jsonw_obj_begin(j);
	for (int k = 0; k < HR_N; k++)
		knum_or_null(j, fig_hit_name(k), m->hit[k]);
	jsonw_obj_end(j);
	knum_or_null(j, "meta_share", m->meta_share);
	knum_or_null(j, "sdram_row_hit_rate", m->row_hit_rate);
	knum_or_null(j, "sdram_utilisation", m->sdram_util);
	knum_or_null(j, "pci_utilisation", m->pci_util);
	jsonw_obj_end(j);
}

static void cache_fields(jsonw *j, const char *key, const cache_stats *s)
{
	jsonw_key(j, key);
	jsonw_obj_begin(j);
	jsonw_kuint(j, "accesses", s->accesses);
	jsonw_kuint(j, "hits", s->hits);
	jsonw_kuint(j, "misses", s->misses);
	jsonw_knum(j, "hit_rate", ratio((double)s->hits, (double)s->accesses));
	jsonw_kuint(j, "mshr_merges", s->merges);
	jsonw_kuint(j, "bytes_requested", s->bytes);
	jsonw_kuint(j, "fill_bytes", s->fill_bytes);
	jsonw_obj_end(j);
}

static void pct(FILE *f, const char *name, double r)
{
	if (r < 0)
		fprintf(f, " %s -", name);
	else
		fprintf(f, " %s %.1f%%", name, 100 * r);
}

/* One reference's comparison, for the text's check line. */
static void check_text(FILE *f, const char *ref, const img_cmp *m, int cached)
{
	fprintf(f, " %s %s (PSNR %.2f dB, %llu differing pixels%s)", ref,
	        m->identical ? "identical" : "DIFFERENT", m->psnr,
	        (unsigned long long)m->differing_pixels,
	        cached ? ", its frame from the world cache" : "");
}

/* The mean over the frames of a per-frame update figure (not rounded:
 * the text prints it as the JSON's update_bytes is rounded). */
static double anim_mean(const chip *c, const uint64_t *v)
{
	double s = 0;
	for (int f = 0; f < c->frames_done; f++)
		s += (double)v[f];
	return c->frames_done ? s / c->frames_done : 0;
}

static double anim_mean_ms(const chip *c)
{
	double s = 0;
	for (int f = 0; f < c->frames_done; f++)
		s += c->frame_update_ms[f];
	return ratio(s, c->frames_done);
}

void report_text(FILE *f, const report_info *ri)
{
	const chip *c = ri->c;
	const saar_config *g = &c->cfg;
	uint64_t cyc = chip_cycles(c);
	fprintf(f, "saarsim: %s, view %s, %dx%d, %d frame%s, config %s\n", ri->w->scene_label,
	        ri->w->v.name, g->frame.width, g->frame.height, c->frames_done,
	        c->frames_done == 1 ? "" : "s", g->name);
	if (ri->w->view_changed) {
		char vd[1024];
		view_describe(&ri->w->v, vd, sizeof vd);
		fprintf(f, "  view: %s\n", vd);
	}
	fprintf(f, "  chip: %d RTP%s x %d thread%s at %g MHz; ", g->chip.rtps,
	        g->chip.rtps == 1 ? "" : "s", g->chip.threads_per_rtp,
	        g->chip.threads_per_rtp == 1 ? "" : "s", g->chip.clock_mhz);
	if (c->frame_mem)
		fprintf(f, "memory hierarchy, %d MB SDRAM, %s\n", g->memory.sdram.mb,
		        g->memory.vma.enabled ? "VMA over the host bus" : "no VMA");
	else
		fprintf(f, "memory fixed, %d cycles\n", g->memory.latency);
	fprintf(f, "  cycles per frame %.0f = %.2f fps%s", ratio((double)cyc, c->frames_done),
	        fig_fps(c), c->fid.mode == CFG_FIDELITY_FUNCTIONAL ? " (bound)" : "");
	if (c->frames_done > 1) {
		/* The headline is the whole run's mean, cold first frame included;
		 * name it so, with the steady state (the Table 5 figure) beside it. */
		memfig ss;
		fig_steady_state(c, &ss);
		fprintf(f,
		        " (mean of all %d frames, the cold first frame included); steady state "
		        "(frames 2..%d): %.0f cycles per frame = %.2f fps",
		        c->frames_done, c->frames_done, ss.cycles, ss.fps);
	}
	fputc('\n', f);
	if (c->w->tl)
		fprintf(
		    f,
		    "  two-level: %u instances of %u objects; %llu top-level steps, %llu "
		    "transformations, %llu to the world; update %lld bytes = %.3f ms over the host "
		    "bus%s\n",
		    c->w->tl->ninst, c->w->tl->nobj,
		    (unsigned long long)get(c, "toplevel.node_steps"),
		    (unsigned long long)get(c, "xform.instances"),
		    (unsigned long long)(chip_rtp_sum(c, "xform.ops") - get(c, "xform.instances")),
		    llround(anim_mean(c, c->frame_update)), anim_mean_ms(c),
		    c->frames_done > 1 ? " (mean per frame)" : "");
	if (c->w->grid) /* the rays line's kd steps are then the grid's slice steps */
		fprintf(f,
		        "  grid: %dx%dx%d cells, %u references, %llu bytes after the frame's "
		        "image; kd steps below are slice steps, leaves cells\n",
		        c->w->grid->n[0], c->w->grid->n[1], c->w->grid->n[2], c->w->grid->nrefs,
		        (unsigned long long)c->gimg.grid_bytes);
	fidelity_text(f, c);
	fputs("  units:", f);
	for (int k = 0; k < UNIT_NKINDS; k++)
		fprintf(f, " %s %.1f%%", chip_unit_name(k), 100 * fig_util(c, k, -1));
	fputs("\n  threads:", f);
	double occ[THR_NSTATES];
	if (fig_thread_shares(c, occ))
		for (int s = 0; s < THR_NSTATES; s++)
			fprintf(f, " %s %.1f%%", chip_state_name(s), 100 * occ[s]);
	else
		fputs(" not timed (functional mode: no thread states)", f);
	uint64_t steps = get(c, "trav.node_steps"), tests = get(c, "isect.tri_tests");
	char per[32] = "-"; /* no test, no ratio (it read 0.00:1) */
	if (tests)
		snprintf(per, sizeof per, "%.2f", (double)steps / (double)tests);
	fprintf(f,
	        "\n  rays: %llu primary, %llu shadow, %llu reflection, %llu refraction; "
	        "%llu kd steps, %llu triangle tests (%s:1), %llu stack overflows\n",
	        (unsigned long long)get(c, "rays.primary"),
	        (unsigned long long)get(c, "rays.shadow"),
	        (unsigned long long)get(c, "rays.reflection"),
	        (unsigned long long)get(c, "rays.refraction"), (unsigned long long)steps,
	        (unsigned long long)tests, per, (unsigned long long)get(c, "trav.stack_overflows"));
	memfig m;
	/* the fixed model has no SDRAM: its bytes are the memory port's */
	const char *mem_name = c->frame_mem ? "SDRAM" : "memory port";
	if (c->frames_done > 1) {
		for (int fr = 0; fr < c->frames_done; fr++) {
			fig_span(c, fr, fr + 1, &m);
			fprintf(
			    f, "  frame %d: %.0f cycles = %.2f fps, %s %.2f MB, PCI %.2f MB, hits:",
			    fr + 1, m.cycles, m.fps, mem_name, m.sdram_mb, m.pci_mb);
			for (int k = 0; k < HR_N; k++)
				if (k < MEM_NTYPES || g->memory.vma.enabled)
					pct(f, fig_hit_name(k), m.hit[k]);
			if (c->w->tl) /* a warm two-level animation: the frame's update */
				fprintf(f, "; update %.3f MB (top level %.3f) = %.2f ms",
				        (double)c->frame_update[fr] / (1 << 20),
				        (double)c->frame_update_top[fr] / (1 << 20),
				        c->frame_update_ms[fr]);
			fputc('\n', f);
		}
	}
	fig_steady_state(c, &m);
	fprintf(f, "  %s: %.2f fps, %s %.2f MB/frame, PCI %.2f MB/frame\n",
	        c->frames_done > 1 ? "steady state (mean of frames 2..N)" : "frame", m.fps,
	        mem_name, m.sdram_mb, m.pci_mb);
	if (c->frame_mem) {
		fputs("  hit rates:", f);
		for (int k = 0; k < HR_N; k++)
			if (k < MEM_NTYPES || g->memory.vma.enabled)
				pct(f, fig_hit_name(k), m.hit[k]);
		fputs("\n  SDRAM:", f);
		pct(f, "row hits", m.row_hit_rate);
		fputc(',', f);
		pct(f, "bus busy", m.sdram_util);
		fputc(',', f);
		pct(f, "meta-data", m.meta_share);
		fputs(" of accesses", f);
		if (g->memory.vma.enabled) {
			fputc(';', f);
			pct(f, "PCI busy", m.pci_util);
		}
		fputc('\n', f);
	}
	if (stall_cycles(c, 0) >= 0) {
		fputs("  read cycles waiting for memory:", f);
		for (int k = 0; k < UNIT_NKINDS; k++) {
			double wait = stall_cycles(c, unit_table[k].mem);
			if (wait < 0) /* a kind without reads of its own */
				fprintf(f, " %s -", chip_unit_name(k));
			else
				fprintf(f, " %s %.0f", chip_unit_name(k), wait);
		}
		fputs(chip_estimates(&c->cfg) ? " (estimated)\n" : "\n", f);
	}
	if (ri->check && ri->check->done) {
		fputs("  check vs kernel-ref:", f);
		check_text(f, "packets", &ri->check->cmp, ri->check->cached);
		fputc(',', f);
		check_text(f, "single rays", &ri->check->single, ri->check->single_cached);
		fputc('\n', f);
		if (ri->check->replay_bad)
			fprintf(f, "  check: %s\n", ri->check->replay_msg);
	}
	fprintf(f, "  host: %.3f s simulating (%.3g cycles/s), %.3f s loading", c->sim_ms / 1e3,
	        ratio((double)cyc, c->sim_ms / 1e3), ri->load_ms / 1e3);
	if (ri->w->cache != WORLD_CACHE_OFF && world_cache_is_default(ri->w))
		fprintf(f, " (world cache: %s in %s, the default folder)",
		        world_cache_name(ri->w->cache), ri->w->cache_dir);
	else if (ri->w->cache != WORLD_CACHE_OFF)
		fprintf(f, " (world cache: %s)", world_cache_name(ri->w->cache));
	else if (ri->w->cache_note[0])
		fprintf(f, " (world cache off: %s)", ri->w->cache_note);
	if (c->rec_state != REC_OFF)
		fprintf(f, "; packet record %s (%.3f s of the simulating)",
		        chip_rec_name(c->rec_state), c->rec_ms / 1e3);
	if (c->warm_state != WARM_OFF)
		fprintf(f, "; stored warming %s (%.3f s of the simulating)",
		        chip_warm_name(c->warm_state), c->warm_ms / 1e3);
	fputc('\n', f);
}

static void kv(jsonw *j, const char *k, uint64_t v)
{
	jsonw_kuint(j, k, v);
}

/* A JSON object whose fields are registry counters: {report key, counter}. */
typedef struct kv_map {
	const char *key, *counter;
} kv_map;

static void kv_object(jsonw *j, const chip *c, const char *name, const kv_map *m, size_t n)
{
	jsonw_key(j, name);
	jsonw_obj_begin(j);
	for (size_t i = 0; i < n; i++)
		kv(j, m[i].key, get(c, m[i].counter));
	jsonw_obj_end(j);
}

static const kv_map skipped_map[] = {
    {"box_miss_packets", "skip.box_miss_packets"},
    {"box_miss_rays", "skip.box_miss_rays"},
    {"shadow_rays_no_lights", "skip.shadow_no_light"},
    {"shadow_rays_light_behind", "skip.shadow_light_behind"},
    {"packets_without_secondary", "skip.no_secondary"},
    {"rays_cut_by_depth", "skip.depth_cut"},
    {"untextured_hits", "skip.untextured_hits"},
};

static const kv_map shading_map[] = {
    {"hits", "shade.hits"},
    {"misses", "shade.misses"},
    {"texel_reads", "shade.texel_reads"},
    {"shadow_rays_occluded", "shade.shadow_occluded"},
    {"shadow_rays_lit", "shade.shadow_lit"},
    {"reads_logged", "rgs.shade_reads"},
    {"requests", "rgs.shade_requests"},
    {"spawned_packets", "rgs.spawned_packets"},
    {"max_queue", "rgs.max_queue"},
};

/* The run: config, scene, view, sizes, frames, cycles and fidelity. */
static void json_run(jsonw *j, const report_info *ri)
{
	const chip *c = ri->c;
	const world *w = ri->w;
	const saar_config *g = &c->cfg;
	jsonw_kstr(j, "program", "saarsim");
	/* the config as simulated: the host bus's "the preset's" (0, -1)
	 * written as the preset's values (they were nowhere in the report) */
	static saar_config rc; /* large: not on the stack */
	rc = *g;
	hbus_params hp;
	hier_hbus_params(g, &hp);
	rc.memory.hostbus.width_bits = (int)hp.width_bits;
	rc.memory.hostbus.clock_mhz = hp.clock_mhz;
	rc.memory.hostbus.burst = (int)hp.burst;
	rc.memory.hostbus.latency_ns = hp.latency_ns;
	jsonw_key(j, "config");
	cfg_write_json(&rc, j);
	jsonw_kstr(j, "scene", w->scene_label);
	jsonw_kstr(j, "view", w->v.name);
	view_json(j, &w->v);
	kv(j, "triangles", w->s.ntris);
	kv(j, "lights", (uint64_t)w->v.nlights);
	jsonw_key(j, "size");
	jsonw_arr_begin(j);
	jsonw_int(j, g->frame.width);
	jsonw_int(j, g->frame.height);
	jsonw_arr_end(j);
	jsonw_key(j, "kdtree");
	jsonw_obj_begin(j);
	kv(j, "nodes", w->kd.nnodes);
	kv(j, "leaves", w->kd.nleaves);
	jsonw_kint(j, "depth", w->kd.depth);
	/* the limit the build used (config kdtree.max_depth, 0: automatic);
	 * two-level scenes build one tree per object, each with its own */
	if (w->tl) {
		jsonw_key(j, "depth_limit");
		jsonw_null(j);
	} else {
		jsonw_kint(j, "depth_limit", kd_depth_limit(g->kdtree.max_depth, w->s.ntris));
	}
	kv(j, "budget_leaves", w->kd.nbudget_leaves);
	jsonw_obj_end(j);
	kv(j, "memory_image_bytes", c->image_bytes);
	kv(j, "spill_base", c->spill_base);

	kv(j, "frames", (uint64_t)c->frames_done);
	jsonw_key(j, "cycles_per_frame");
	jsonw_arr_begin(j);
	for (int f = 0; f < c->frames_done; f++)
		jsonw_uint(j, c->frame_cycles[f]);
	jsonw_arr_end(j);
	kv(j, "cycles", chip_cycles(c));
	jsonw_knum(j, "clock_mhz", g->chip.clock_mhz);
	jsonw_knum(j, "fps", fig_fps(c));
	kv(j, "events", c->events);
	fidelity_json(j, c);
}

/* Per unit kind: count, operations, rays, busy cycles, utilisation. */
static void json_units(jsonw *j, const chip *c)
{
	char name[96];
	jsonw_key(j, "units");
	jsonw_obj_begin(j);
	for (int k = 0; k < UNIT_NKINDS; k++) {
		const char *un = chip_unit_name(k);
		jsonw_key(j, un);
		jsonw_obj_begin(j);
		jsonw_kint(j, "units", (int64_t)chip_unit_cfg(&c->cfg, k)->count * c->nrtp);
		snprintf(name, sizeof name, "%s.ops", un);
		kv(j, "ops", chip_rtp_sum(c, name));
		snprintf(name, sizeof name, "%s.rays", un);
		kv(j, "rays", chip_rtp_sum(c, name));
		snprintf(name, sizeof name, "%s.busy_cycles", un);
		uint64_t busy = chip_rtp_sum(c, name);
		kv(j, "busy_cycles", busy);
		jsonw_knum(j, "utilisation", fig_util(c, k, -1));
		jsonw_key(j, "per_rtp_utilisation");
		jsonw_arr_begin(j);
		for (int r = 0; r < c->nrtp; r++)
			jsonw_num(j, fig_util(c, k, r));
		jsonw_arr_end(j);
		jsonw_obj_end(j);
	}
	jsonw_obj_end(j);
}

/* Thread contexts and the shares of their time in each state. */
static void json_threads(jsonw *j, const chip *c)
{
	jsonw_key(j, "threads");
	jsonw_obj_begin(j);
	jsonw_kint(j, "contexts", (int64_t)c->nrtp * c->tpr);
	double occ[THR_NSTATES];
	int timed = fig_thread_shares(c, occ);
	for (int s = 0; s < THR_NSTATES; s++) {
		/* no thread time at all (functional: nothing is timed): no
		 * shares, rather than four zeros that do not add up to 1 */
		if (timed) {
			jsonw_knum(j, chip_state_name(s), occ[s]);
		} else {
			jsonw_key(j, chip_state_name(s));
			jsonw_null(j);
		}
	}
	jsonw_obj_end(j);
}

/* Packets and rays per type; traversal and intersection work. */
static void json_rays(jsonw *j, const chip *c)
{
	char name[96];
	static const char *const tn[PKT_NTYPES] = {"primary", "shadow", "reflection", "refraction"};
	for (int pass = 0; pass < 2; pass++) {
		jsonw_key(j, pass ? "rays" : "packets");
		jsonw_obj_begin(j);
		uint64_t sum = 0;
		for (int t = 0; t < PKT_NTYPES; t++) {
			snprintf(name, sizeof name, "%s.%s", pass ? "rays" : "packets", tn[t]);
			sum += get(c, name);
			kv(j, tn[t], get(c, name));
		}
		kv(j, "total", sum);
		jsonw_obj_end(j);
	}

	uint64_t steps = get(c, "trav.node_steps"), tests = get(c, "isect.tri_tests");
	jsonw_key(j, "traversal");
	jsonw_obj_begin(j);
	kv(j, "kd_node_steps", steps);
	kv(j, "leaf_visits", get(c, "trav.leaf_visits"));
	kv(j, "empty_leaves", get(c, "trav.empty_leaves"));
	kv(j, "list_entries", get(c, "list.entries"));
	kv(j, "triangle_tests", tests);
	kv(j, "ray_triangle_tests", get(c, "isect.ray_tri_tests"));
	jsonw_knum(j, "trav_isect_ratio", ratio((double)steps, (double)tests));
	jsonw_knum(j, "design_ratio", 4.0);
	kv(j, "max_stack_depth", get(c, "trav.max_stack_depth"));
	kv(j, "stack_overflows", get(c, "trav.stack_overflows"));
	kv(j, "stack_refills", get(c, "trav.stack_refills"));
	jsonw_obj_end(j);

	/* seed 004's cone culling (chip.cone_cull; kernel-ref/cone.h) */
	uint64_t ct = get(c, "cone.tests"), cu = get(c, "cone.culled");
	jsonw_key(j, "cone_cull");
	jsonw_obj_begin(j);
	jsonw_kbool(j, "enabled", c->cfg.chip.cone_cull);
	kv(j, "cones", get(c, "cone.packets"));
	kv(j, "tests", ct);
	kv(j, "culled", cu);
	kv(j, "saved_ray_tests", get(c, "cone.saved_ray_tests"));
	jsonw_knum(j, "culled_share", ratio((double)cu, (double)ct));
	jsonw_obj_end(j);
}

/* One ray type's L1 figures: per L1 and in total, the line lookups, hits
 * and hit rate (hier_stats.ray_*). */
static void ray_type_l1(jsonw *j, const hier_stats *hs, int r)
{
	uint64_t look = 0, hit = 0;
	jsonw_key(j, "l1");
	jsonw_obj_begin(j);
	for (int t = 0; t <= MEM_NTYPES; t++) {
		uint64_t lk = t < MEM_NTYPES ? hs->ray_lookups[r][t] : look;
		uint64_t h = t < MEM_NTYPES ? hs->ray_hits[r][t] : hit;
		jsonw_key(j, t < MEM_NTYPES ? mem_type_name(t) : "total");
		jsonw_obj_begin(j);
		kv(j, "lookups", lk);
		kv(j, "hits", h);
		jsonw_knum(j, "hit_rate", ratio((double)h, (double)lk));
		jsonw_obj_end(j);
		look += lk;
		hit += h;
	}
	jsonw_obj_end(j);
}

/* The ray_types object (issue 32; docs/report.md): per packet type its
 * packets and rays, kd steps and triangle tests (per packet and per ray),
 * the units' issue cycles it took (and its share of them) and, with
 * caches, its L1 lookups and hit rates. */
static void json_ray_types(jsonw *j, const chip *c, const hier_stats *hs, int have_h)
{
	char name[96];
	double all = 0;
	for (int t = 0; t < PKT_NTYPES; t++)
		for (int k = 0; k < UNIT_NKINDS; k++)
			all += (double)*c->env.ct[t][TC_BUSY + k];
	jsonw_key(j, "ray_types");
	jsonw_obj_begin(j);
	for (int t = 0; t < PKT_NTYPES; t++) {
		uint64_t *const *ct = c->env.ct[t];
		snprintf(name, sizeof name, "packets.%s", pkt_type_name(t));
		uint64_t pk = get(c, name);
		snprintf(name, sizeof name, "rays.%s", pkt_type_name(t));
		uint64_t rays = get(c, name);
		jsonw_key(j, pkt_type_name(t));
		jsonw_obj_begin(j);
		kv(j, "packets", pk);
		kv(j, "rays", rays);
		kv(j, "kd_node_steps", *ct[TC_NODE_STEPS]);
		kv(j, "leaf_visits", *ct[TC_LEAF_VISITS]);
		kv(j, "list_entries", *ct[TC_LIST_ENTRIES]);
		kv(j, "triangle_tests", *ct[TC_TRI_TESTS]);
		kv(j, "ray_triangle_tests", *ct[TC_RAY_TRI_TESTS]);
		kv(j, "ray_kd_steps", *ct[TC_RAYS + UNIT_TRAV]);
		jsonw_knum(j, "kd_steps_per_packet", ratio((double)*ct[TC_NODE_STEPS], (double)pk));
		jsonw_knum(j, "triangle_tests_per_packet",
		           ratio((double)*ct[TC_TRI_TESTS], (double)pk));
		jsonw_knum(j, "kd_steps_per_ray",
		           ratio((double)*ct[TC_RAYS + UNIT_TRAV], (double)rays));
		jsonw_knum(j, "triangle_tests_per_ray",
		           ratio((double)*ct[TC_RAY_TRI_TESTS], (double)rays));
		double busy = 0;
		jsonw_key(j, "unit_busy_cycles");
		jsonw_obj_begin(j);
		for (int k = 0; k < UNIT_NKINDS; k++) {
			kv(j, unit_table[k].name, *ct[TC_BUSY + k]);
			busy += (double)*ct[TC_BUSY + k];
		}
		jsonw_obj_end(j);
		jsonw_knum(j, "busy_cycles_per_ray", ratio(busy, (double)rays));
		jsonw_knum(j, "busy_share", ratio(busy, all));
		if (have_h) {
			ray_type_l1(j, hs, t);
		} else {
			jsonw_key(j, "l1");
			jsonw_null(j);
		}
		jsonw_obj_end(j);
	}
	jsonw_obj_end(j);
}

/* The memory object: requests per requester type, stall cycles per unit
 * kind and the hierarchy's figures (hs, have_h: whether it has any). */
static void json_memory(jsonw *j, const chip *c, const hier_stats *hs, int have_h)
{
	const saar_config *g = &c->cfg;
	char name[96];
	jsonw_key(j, "memory");
	jsonw_obj_begin(j);
	jsonw_kstr(j, "model", cfg_enum_name(g, "memory.model"));
	jsonw_kint(j, "latency", g->memory.latency);
	static const char *const mk[4] = {"reads", "read_bytes", "writes", "write_bytes"};
	uint64_t tot_rd = 0, tot_b = 0;
	for (int t = 0; t < MEM_NTYPES; t++) {
		jsonw_key(j, mem_type_name(t));
		jsonw_obj_begin(j);
		for (int k = 0; k < 4; k++) {
			snprintf(name, sizeof name, "mem.%s.%s", mem_type_name(t), mk[k]);
			kv(j, mk[k], get(c, name));
		}
		snprintf(name, sizeof name, "mem.%s.reads", mem_type_name(t));
		tot_rd += get(c, name);
		snprintf(name, sizeof name, "mem.%s.read_bytes", mem_type_name(t));
		tot_b += get(c, name);
		jsonw_obj_end(j);
	}
	kv(j, "reads", tot_rd);
	kv(j, "read_bytes", tot_b);
	jsonw_knum(j, "read_bytes_per_frame", ratio((double)tot_b, c->frames_done));
	jsonw_key(j, "stall_cycles");
	jsonw_obj_begin(j);
	for (int k = 0; k < UNIT_NKINDS; k++) {
		double wait = stall_cycles(c, unit_table[k].mem); /* its reads' type */
		jsonw_key(j, chip_unit_name(k));
		if (wait < 0)
			jsonw_null(j);
		else
			jsonw_uint(j, (uint64_t)wait);
	}
	jsonw_obj_end(j);
	jsonw_key(j, "hierarchy");
	if (have_h)
		hier_write_json(hs, j);
	else
		jsonw_null(j);
	jsonw_obj_end(j);
}

/* The published SaarCOR table's columns (seed 002 Table 5), steady state;
 * the steady state's and each frame's memory figures. */
static void json_frames(jsonw *j, const chip *c)
{
	memfig m;
	fig_steady_state(c, &m);
	jsonw_key(j, "table");
	jsonw_obj_begin(j);
	jsonw_knum(j, "fps", m.fps);
	jsonw_knum(j, "sdram_mb_per_frame", m.sdram_mb);
	jsonw_knum(j, "pci_mb_per_frame", m.pci_mb);
	jsonw_obj_end(j);
	jsonw_key(j, "steady_state");
	memfig_json(j, &m);
	jsonw_key(j, "per_frame");
	jsonw_arr_begin(j);
	for (int f = 0; f < c->frames_done; f++) {
		fig_span(c, f, f + 1, &m);
		memfig_json(j, &m);
	}
	jsonw_arr_end(j);
}

static void json_caches(jsonw *j, const hier_stats *hs, int have_h)
{
	jsonw_key(j, "caches");
	if (!have_h) {
		jsonw_null(j);
		return;
	}
	jsonw_obj_begin(j);
	for (int t = 0; t < MEM_NTYPES; t++)
		cache_fields(j, mem_type_name(t), &hs->l1[t]);
	if (hs->vma_enabled) {
		cache_fields(j, "tag_cache", &hs->tag_cache);
		cache_fields(j, "l2", &hs->l2);
	}
	jsonw_obj_end(j);
}

/* The frame against kernel-ref (packet and single-ray), null without. */
static void json_check(jsonw *j, const report_info *ri)
{
	jsonw_key(j, "check");
	if (!ri->check || !ri->check->done) {
		jsonw_null(j);
		return;
	}
	jsonw_obj_begin(j);
	jsonw_kbool(j, "identical_8bit", ri->check->cmp.identical);
	jsonw_knum(j, "psnr", ri->check->cmp.psnr);
	kv(j, "differing_pixels", ri->check->cmp.differing_pixels);
	jsonw_kstr(j, "reference", ri->check->cached ? "cached" : "rendered");
	jsonw_key(j, "single_ray");
	jsonw_obj_begin(j);
	jsonw_kbool(j, "identical_8bit", ri->check->single.identical);
	jsonw_knum(j, "psnr", ri->check->single.psnr);
	kv(j, "differing_pixels", ri->check->single.differing_pixels);
	jsonw_kstr(j, "reference", ri->check->single_cached ? "cached" : "rendered");
	jsonw_obj_end(j);
	if (ri->check->replay_bad) { /* only then: other reports stay as they were */
		kv(j, "replay_bad_reads", ri->check->replay_bad);
		jsonw_kstr(j, "replay_bad_first", ri->check->replay_msg);
	}
	jsonw_obj_end(j);
}

/* The failed invariants and every registry counter. */
static void json_counters(jsonw *j, const report_info *ri)
{
	const chip *c = ri->c;
	jsonw_key(j, "invariants_failed");
	jsonw_arr_begin(j);
	for (int i = 0; ri->invariants && i < ri->invariants->n && i < RC_MAX; i++)
		jsonw_str(j, ri->invariants->msg[i]);
	jsonw_arr_end(j);

	jsonw_key(j, "counters");
	jsonw_obj_begin(j);
	for (size_t i = 0; i < c->st.n; i++)
		kv(j, c->st.e[i].name, *c->st.e[i].value);
	jsonw_obj_end(j);
}

/* The host's figures: times, caches used, memory. */
static void json_host(jsonw *j, const report_info *ri)
{
	const chip *c = ri->c;
	int checked = ri->check && ri->check->done;
	jsonw_key(j, "host");
	jsonw_obj_begin(j);
	jsonw_knum(j, "load_s", ri->load_ms / 1e3);
	/* of the load: the scene's kd-tree and memory image (for an animation,
	 * this frame's) */
	jsonw_knum(j, "kd_build_s", ri->w->kd_ms / 1e3);
	jsonw_knum(j, "image_build_s", ri->w->image_ms / 1e3);
	jsonw_knum(j, "sim_s", c->sim_ms / 1e3);
	jsonw_knum(j, "check_s", checked ? ri->check->check_ms / 1e3 : 0.0);
	jsonw_knum(j, "wall_s", ri->wall_ms / 1e3);
	jsonw_kstr(j, "world_cache", world_cache_name(ri->w->cache));
	world_cache_json(j, ri->w);
	jsonw_kstr(j, "packet_record", chip_rec_name(c->rec_state));
	jsonw_knum(j, "packet_record_s", c->rec_ms / 1e3);
	jsonw_kstr(j, "stored_warming", chip_warm_name(c->warm_state));
	jsonw_knum(j, "stored_warming_s", c->warm_ms / 1e3);
	jsonw_knum(j, "mem_estimate_mb", ri->mem_estimate_mb);
	jsonw_knum(j, "peak_rss_mb", (double)hm_peak_rss() / (1 << 20));
	jsonw_knum(j, "sim_cycles_per_s", ratio((double)chip_cycles(c), c->sim_ms / 1e3));
	jsonw_knum(j, "sim_to_ref_ratio", checked ? ratio(c->sim_ms, ri->check->ref_ms) : 0.0);
	jsonw_obj_end(j);
}

/* A uniform grid (issue 34; units/gridtrav.h): what the traversal unit
 * walked, the grid's image and the host's build. Absent for the kd-tree
 * (whose reports are as before). */
static void json_grid(jsonw *j, const chip *c)
{
	const grid *g = c->w->grid;
	if (!g)
		return;
	const grid_image *im = &c->gimg;
	jsonw_key(j, "grid");
	jsonw_obj_begin(j);
	grid_json_fields(j, g);
	jsonw_kuint(j, "cells_base", im->cells_base);
	jsonw_kuint(j, "refs_base", im->refs_base);
	jsonw_kuint(j, "macro_base", im->macro_base);
	jsonw_kuint(j, "grid_bytes", im->grid_bytes);
	jsonw_knum(j, "host_build_ms", g->build_ms);
	jsonw_obj_end(j);
}

/* A two-level scene (issue 33; units/toplevel.h): the scene's instances
 * and objects, the top level's work on the chip, and the host's update of
 * the frame (the top level's bytes over the host bus; chip.c
 * chip_update). Absent for single-tree scenes. */
static void json_two_level(jsonw *j, const chip *c)
{
	const tl_scene *t = c->w->tl;
	if (!t)
		return;
	double frame_s = ratio(1.0, fig_fps(c));
	/* the update per frame: the mean over the frames (one frame: its top
	 * level) */
	double ub = 0, ums = anim_mean_ms(c);
	for (int f = 0; f < c->frames_done; f++)
		ub += (double)c->frame_update[f];
	ub = ratio(ub, c->frames_done);
	jsonw_key(j, "two_level");
	jsonw_obj_begin(j);
	jsonw_kuint(j, "instances", t->ninst);
	jsonw_kuint(j, "objects", t->nobj);
	jsonw_kuint(j, "top_nodes", t->nnode);
	jsonw_kuint(j, "top_node_steps", get(c, "toplevel.node_steps"));
	jsonw_kuint(j, "instance_tests", get(c, "toplevel.instance_tests"));
	jsonw_kuint(j, "transformations", get(c, "xform.instances"));
	/* the unit's other ops: shaded packets moved back (units/rgs.c) */
	jsonw_kuint(j, "normal_transformations",
	            chip_rtp_sum(c, "xform.ops") - get(c, "xform.instances"));
	jsonw_kuint(j, "transformed_rays", chip_rtp_sum(c, "xform.rays"));
	jsonw_kuint(j, "map_reads", get(c, "toplevel.map_reads"));
	jsonw_kuint(j, "update_bytes", (uint64_t)llround(ub));
	jsonw_knum(j, "update_mb", ub / (1 << 20));
	jsonw_knum(j, "update_ms", ums);
	jsonw_knum(j, "fps_with_update", ratio(1.0, frame_s + ums * 1e-3));
	jsonw_knum(j, "host_top_level_ms", t->frame_ms);
	jsonw_knum(j, "host_bottom_level_ms", t->build_ms);
	/* a warm animation (chip_anim_update): each frame's update; frame 1's
	 * is the first top level (the objects were on the board before) */
	jsonw_kbool(j, "warm", c->between != NULL);
	jsonw_kint(j, "frames_checked_before_last", c->anim_checked);
	jsonw_kint(j, "frames_identical_before_last", c->anim_identical);
	jsonw_key(j, "per_frame");
	jsonw_arr_begin(j);
	for (int f = 0; f < c->frames_done; f++) {
		jsonw_obj_begin(j);
		jsonw_kint(j, "frame", f + 1);
		jsonw_kuint(j, "update_bytes", c->frame_update[f]);
		jsonw_kuint(j, "update_top_level_bytes", c->frame_update_top[f]);
		jsonw_kuint(j, "update_world_bytes", c->frame_update[f] - c->frame_update_top[f]);
		jsonw_knum(j, "update_mb", (double)c->frame_update[f] / (1 << 20));
		jsonw_knum(j, "update_ms", c->frame_update_ms[f]);
		jsonw_kuint(j, "stale_cache_lines", c->frame_stale[f]);
		jsonw_obj_end(j);
	}
	jsonw_arr_end(j);
	jsonw_obj_end(j);
}

int report_json(const char *path, const report_info *ri, diag *d)
{
	const chip *c = ri->c;
	jsonw jw, *j = &jw;
	if (jsonw_open(j, path, d))
		return -1;
	j->group = ri->group;
	jsonw_obj_begin(j);
	json_run(j, ri);
	json_units(j, c);
	json_threads(j, c);
	json_rays(j, c);
	hier_stats hs;
	int have_h = !hier_get_stats(&c->mem, &hs);
	if (have_h && hs.func_requests) /* the bytes of untimed stretches too */
		hs.run_ticks = chip_cycles(c) * hs.core_period;
	json_ray_types(j, c, &hs, have_h);
	kv_object(j, c, "skipped", skipped_map, sizeof skipped_map / sizeof *skipped_map);
	kv_object(j, c, "shading", shading_map, sizeof shading_map / sizeof *shading_map);
	json_memory(j, c, &hs, have_h);
	json_frames(j, c);
	json_two_level(j, c);
	json_grid(j, c);
	json_caches(j, &hs, have_h);
	json_check(j, ri);
	json_counters(j, ri);
	json_host(j, ri);
	jsonw_obj_end(j);
	return jsonw_close(j, d);
}

/* ---- CSV ---- */

/* One field, quoted when it holds a comma, quote or newline (RFC 4180). */
static void csv_str(FILE *f, const char *s, int last)
{
	if (strpbrk(s, ",\"\n")) {
		fputc('"', f);
		for (; *s; s++) {
			if (*s == '"')
				fputc('"', f);
			fputc(*s, f);
		}
		fputc('"', f);
	} else {
		fputs(s, f);
	}
	fputc(last ? '\n' : ',', f);
}

static void csv_num(FILE *f, double v)
{
	if (v < 0 || !isfinite(v))
		fputs(",", f); /* no such cache: empty field */
	else
		fprintf(f, "%.6g,", v);
}

/* The header: these, util_<name> of every unit kind (units/unit_table.h),
 * then the rest. */
static const char csv_head[] =
    "config,scene,view,width,height,frames,memory_model,chip.rtps,chip.threads_per_rtp,"
    "memory.l1.shade.size_kb,memory.l1.kd.size_kb,memory.l1.list.size_kb,"
    "memory.l1.tri.size_kb,memory.sdram.mb,memory.vma.enabled,memory.hostbus.preset,"
    "fps,";
static const char csv_tail[] =
    "hit_shade,hit_kd,hit_list,hit_tri,"
    "hit_tag_cache,hit_l2,sdram_mb_per_frame,pci_mb_per_frame,meta_share,"
    "sdram_row_hit_rate,sdram_utilisation,pci_utilisation,fidelity,fps_ci_lo,fps_ci_hi,"
    "fps_bound,bound_by,identical_8bit,host_sim_s,host_wall_s\n";

static const char *csv_header(void)
{
	static char h[sizeof csv_head + sizeof csv_tail + UNIT_NKINDS * 32];
	if (!*h) {
		int n = snprintf(h, sizeof h, "%s", csv_head);
		for (int k = 0; k < UNIT_NKINDS; k++)
			n += snprintf(h + n, sizeof h - (size_t)n, "util_%s,", unit_table[k].name);
		snprintf(h + n, sizeof h - (size_t)n, "%s", csv_tail);
	}
	return h;
}

/* Rows go under our header only: a file from another program, or from a
 * saarsim with other columns, would get rows its header misnames. */
static int csv_header_ok(const char *old, size_t nold)
{
	size_t nh = strlen(csv_header());
	return !nold || (nold >= nh && !memcmp(old, csv_header(), nh));
}

static int csv_not_ours(const char *path, diag *d)
{
	return diag_set(d, path, 1, 1,
	                "not a saarsim CSV with these columns (its first line is not the header "
	                "docs/report.md lists); give a new file");
}

/* The old contents of a CSV to append to: our header, then rows of as
 * many fields (RFC 4180: a quoted field may hold commas, quotes and line
 * breaks), the last one ended by a line break or not; blank lines are
 * passed over. A row cut short (a
 * run killed while another program wrote it, a foreign row) would make
 * every later row misread, so the file is refused, naming the line. */
static int csv_old_ok(const char *path, const char *old, size_t nold, diag *d)
{
	if (!csv_header_ok(old, nold))
		return csv_not_ours(path, d);
	int want = 1;
	for (const char *h = csv_header(); *h; h++)
		want += *h == ',';
	size_t i = strlen(csv_header());
	int line = 2;
	while (i < nold) {
		if (old[i] == '\n' || (old[i] == '\r' && i + 1 < nold && old[i + 1] == '\n')) {
			i += old[i] == '\r' ? 2 : 1; /* a blank line: no row */
			line++;
			continue;
		}
		int fields = 1, start = line, quoted = 0;
		for (; i < nold; i++) {
			char ch = old[i];
			if (quoted) {
				if (ch == '"' && i + 1 < nold && old[i + 1] == '"')
					i++;
				else if (ch == '"')
					quoted = 0;
				else if (ch == '\n')
					line++;
			} else if (ch == '"') {
				quoted = 1;
			} else if (ch == ',') {
				fields++;
			} else if (ch == '\n') {
				i++;
				line++;
				break;
			}
		}
		if (quoted || fields != want)
			return diag_set(d, path, start, 0,
			                "row has %d fields, the header %d%s (a damaged or foreign "
			                "row); give a new file",
			                fields, want, quoted ? " and an unclosed quote" : "");
	}
	return 0;
}

/* The contents of the CSV to append to into *old (malloc'd; NULL for a
 * new file); a path that is not a regular file is refused (fopen on a FIFO
 * would wait for a writer; a directory opens and seeks to a huge size). */
static int csv_read_old(const char *path, char **old, size_t *nold, diag *d)
{
	char why[256];
	*old = NULL;
	*nold = 0;
	int st = in_read_all(path, 0, old, nold, why, sizeof why);
	if (st == ENOENT)
		return 0; /* a new file */
	if (st == EIO)
		return diag_set(d, path, 0, 0, "%s", why);
	if (st)
		return diag_set(d, path, 0, 0, "cannot append a row: %s", in_strerror(st));
	return 0;
}

int report_csv_check(const char *path, diag *d)
{
	char *old;
	size_t nold;
	if (csv_read_old(path, &old, &nold, d))
		return -1;
	int rc = csv_old_ok(path, old, nold, d);
	free(old);
	return rc;
}

int report_csv_lock(const char *path)
{
	char dir[4096];
	const char *slash = strrchr(path, '/');
	if (!slash)
		snprintf(dir, sizeof dir, ".");
	else if (slash == path)
		snprintf(dir, sizeof dir, "/");
	else if ((size_t)(slash - path) < sizeof dir)
		snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
	else
		return -1;
	int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	if (fd < 0)
		return -1;
	while (flock(fd, LOCK_EX) < 0) {
		if (errno != EINTR) {
			close(fd);
			return -1;
		}
	}
	return fd;
}

void report_csv_unlock(int fd)
{
	if (fd >= 0)
		close(fd); /* releases the flock */
}

int report_csv(const char *path, const report_info *ri, diag *d)
{
	const chip *c = ri->c;
	const saar_config *g = &c->cfg;
	char *old;
	size_t nold;
	if (csv_read_old(path, &old, &nold, d))
		return -1;
	if (csv_old_ok(path, old, nold, d)) {
		free(old);
		return -1;
	}
	afile a;
	if (af_open(&a, path, "", 1)) {
		free(old);
		return af_diag(d, path);
	}
	FILE *f = a.f;
	if (nold) {
		fwrite(old, 1, nold, f);
		if (old[nold - 1] != '\n')
			fputc('\n', f);
	} else {
		fputs(csv_header(), f);
	}
	free(old);

	memfig m;
	fig_steady_state(c, &m);
	csv_str(f, g->name, 0);
	csv_str(f, ri->w->scene_label, 0);
	csv_str(f, ri->w->v.name, 0);
	fprintf(f, "%d,%d,%d,%s,%d,%d,%d,%d,%d,%d,%d,%d,%s,", g->frame.width, g->frame.height,
	        c->frames_done, cfg_enum_name(g, "memory.model"), g->chip.rtps,
	        g->chip.threads_per_rtp, g->memory.l1.shade.size_kb, g->memory.l1.kd.size_kb,
	        g->memory.l1.list.size_kb, g->memory.l1.tri.size_kb, g->memory.sdram.mb,
	        g->memory.vma.enabled ? 1 : 0, cfg_enum_name(g, "memory.hostbus.preset"));
	csv_num(f, m.fps);
	for (int k = 0; k < UNIT_NKINDS; k++)
		csv_num(f, fig_util(c, k, -1));
	for (int k = 0; k < HR_N; k++)
		csv_num(f, m.hit[k]);
	csv_num(f, m.sdram_mb);
	csv_num(f, m.pci_mb);
	csv_num(f, m.meta_share);
	csv_num(f, m.row_hit_rate);
	csv_num(f, m.sdram_util);
	csv_num(f, m.pci_util);
	fidfig x;
	fidfig_get(c, &x);
	csv_str(f, x.mode, 0);
	csv_num(f, x.fps_lo);
	csv_num(f, x.fps_hi);
	csv_num(f, x.fps_bound);
	csv_str(f, x.bound_by, 0);
	if (ri->check && ri->check->done) /* 1: the frame equals both references */
		fprintf(f, "%d,", ri->check->cmp.identical && ri->check->single.identical ? 1 : 0);
	else
		fputc(',', f);
	fprintf(f, "%.4f,%.4f\n", c->sim_ms / 1e3, ri->wall_ms / 1e3);
	if (af_commit_to(&a, ri->group))
		return af_diag(d, path);
	return 0;
}

int report_census(const char *path, const report_info *ri, diag *d)
{
	const chip *c = ri->c;
	afile a;
	if (af_open(&a, path, "", 1))
		return af_diag(d, path);
	FILE *f = a.f;
	fputs("frame,first_tile,tiles,cycles", f);
	for (int r = 0; r < RES_N; r++)
		fprintf(f, ",%s", chip_res_name(r));
	fputc('\n', f);
	int timed = c->fid.mode != CFG_FIDELITY_FUNCTIONAL;
	double per = (double)c->clk.period;
	for (int i = 0; i + 1 < c->ncensus; i++) {
		const chip_mark *m0 = &c->census[i], *m1 = &c->census[i + 1];
		if (m1->frame != m0->frame)
			continue; /* the frame's end mark starts no chunk */
		fprintf(f, "%d,%d,%d,", m0->frame + 1, m0->tile, m1->tile - m0->tile);
		if (timed)
			fprintf(f, "%.10g", (double)(m1->ticks - m0->ticks) / per);
		for (int r = 0; r < RES_N; r++)
			fprintf(f, ",%.10g", m1->dem[r] - m0->dem[r]);
		fputc('\n', f);
	}
	if (af_commit_to(&a, ri->group))
		return af_diag(d, path);
	return 0;
}
