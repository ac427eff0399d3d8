/*
 * report.c: text summary and JSON report (see report.h, docs/report.md).
 */
#include "report.h"

#include <math.h>
#include <string.h>

static double ratio(double a, double b)
{
	return b > 0 ? a / b : 0.0;
}

static uint64_t get(const chip *c, const char *name)
{
	return stats_get(&c->st, name);
}

/* Unit utilisation: issue cycles / (cycles x units of that kind on the chip). */
static double util(const chip *c, int kind, uint64_t busy)
{
	const cfg_unit *u[UNIT_NKINDS] = {&c->cfg.chip.rgs, &c->cfg.chip.trav, &c->cfg.chip.list,
	                                  &c->cfg.chip.isect};
	return ratio((double)busy, (double)chip_cycles(c) * u[kind]->count * c->nrtp);
}

static double fps(const chip *c)
{
	double cyc = ratio((double)chip_cycles(c), c->frames_done);
	return ratio(c->cfg.chip.clock_mhz * 1e6, cyc);
}

void report_text(FILE *f, const report_info *ri)
{
	const chip *c = ri->c;
	const saar_config *g = &c->cfg;
	char sfx[64];
	uint64_t cyc = chip_cycles(c);
	fprintf(f, "saarsim: %s, view %s, %dx%d, %d frame%s, config %s\n", ri->w->scene_label,
	        ri->w->v.name, g->frame.width, g->frame.height, c->frames_done,
	        c->frames_done == 1 ? "" : "s", g->name);
	fprintf(f, "  chip: %d RTPs x %d threads at %g MHz, memory %s %d cycles\n", g->chip.rtps,
	        g->chip.threads_per_rtp, g->chip.clock_mhz, cfg_enum_name(g, "memory.model"),
	        g->memory.latency);
	fprintf(f, "  cycles per frame %.0f = %.2f fps\n", ratio((double)cyc, c->frames_done),
	        fps(c));
	fputs("  units:", f);
	for (int k = 0; k < UNIT_NKINDS; k++) {
		snprintf(sfx, sizeof sfx, "%s.busy_cycles", chip_unit_name(k));
		fprintf(f, " %s %.1f%%", chip_unit_name(k), 100 * util(c, k, chip_rtp_sum(c, sfx)));
	}
	fputs("\n  threads:", f);
	double tot = 0, occ[THR_NSTATES];
	for (int s = 0; s < THR_NSTATES; s++) {
		snprintf(sfx, sizeof sfx, "threads.%s_ps", chip_state_name(s));
		tot += occ[s] = (double)chip_rtp_sum(c, sfx);
	}
	for (int s = 0; s < THR_NSTATES; s++)
		fprintf(f, " %s %.1f%%", chip_state_name(s), 100 * ratio(occ[s], tot));
	uint64_t steps = get(c, "trav.node_steps"), tests = get(c, "isect.tri_tests");
	fprintf(f,
	        "\n  rays: %llu primary, %llu shadow, %llu reflection, %llu refraction; "
	        "%llu kd steps, %llu triangle tests (%.2f:1), %llu stack overflows\n",
	        (unsigned long long)get(c, "rays.primary"),
	        (unsigned long long)get(c, "rays.shadow"),
	        (unsigned long long)get(c, "rays.reflection"),
	        (unsigned long long)get(c, "rays.refraction"), (unsigned long long)steps,
	        (unsigned long long)tests, ratio((double)steps, (double)tests),
	        (unsigned long long)get(c, "trav.stack_overflows"));
	if (ri->check && ri->check->done)
		fprintf(f, "  check vs kernel-ref: %s (PSNR %.2f dB, %llu differing pixels)\n",
		        ri->check->cmp.identical ? "identical" : "DIFFERENT", ri->check->cmp.psnr,
		        (unsigned long long)ri->check->cmp.differing_pixels);
	fprintf(f, "  host: %.3f s simulating (%.3g cycles/s), %.3f s loading\n", c->sim_ms / 1e3,
	        ratio((double)cyc, c->sim_ms / 1e3), ri->load_ms / 1e3);
}

static void kv(jsonw *j, const char *k, uint64_t v)
{
	jsonw_kuint(j, k, v);
}

int report_json(const char *path, const report_info *ri, diag *d)
{
	const chip *c = ri->c;
	const world *w = ri->w;
	const saar_config *g = &c->cfg;
	uint64_t cyc = chip_cycles(c);
	char name[96];
	jsonw jw, *j = &jw;
	if (jsonw_open(j, path, d))
		return -1;
	jsonw_obj_begin(j);
	jsonw_kstr(j, "program", "saarsim");
	jsonw_key(j, "config");
	cfg_write_json(g, j);
	jsonw_kstr(j, "scene", w->scene_label);
	jsonw_kstr(j, "view", w->v.name);
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
	jsonw_obj_end(j);
	kv(j, "memory_image_bytes", w->m.size);

	kv(j, "frames", (uint64_t)c->frames_done);
	jsonw_key(j, "cycles_per_frame");
	jsonw_arr_begin(j);
	for (int f = 0; f < c->frames_done; f++)
		jsonw_uint(j, c->frame_cycles[f]);
	jsonw_arr_end(j);
	kv(j, "cycles", cyc);
	jsonw_knum(j, "clock_mhz", g->chip.clock_mhz);
	jsonw_knum(j, "fps", fps(c));
	kv(j, "events", c->events);

	jsonw_key(j, "units");
	jsonw_obj_begin(j);
	const cfg_unit *uc[UNIT_NKINDS] = {&g->chip.rgs, &g->chip.trav, &g->chip.list,
	                                   &g->chip.isect};
	for (int k = 0; k < UNIT_NKINDS; k++) {
		const char *un = chip_unit_name(k);
		jsonw_key(j, un);
		jsonw_obj_begin(j);
		jsonw_kint(j, "units", (int64_t)uc[k]->count * c->nrtp);
		snprintf(name, sizeof name, "%s.ops", un);
		kv(j, "ops", chip_rtp_sum(c, name));
		snprintf(name, sizeof name, "%s.rays", un);
		kv(j, "rays", chip_rtp_sum(c, name));
		snprintf(name, sizeof name, "%s.busy_cycles", un);
		uint64_t busy = chip_rtp_sum(c, name);
		kv(j, "busy_cycles", busy);
		jsonw_knum(j, "utilisation", util(c, k, busy));
		jsonw_key(j, "per_rtp_utilisation");
		jsonw_arr_begin(j);
		for (int r = 0; r < c->nrtp; r++) {
			snprintf(name, sizeof name, "rtp%d.%s.busy_cycles", r, un);
			jsonw_num(j, ratio((double)get(c, name), (double)cyc * uc[k]->count));
		}
		jsonw_arr_end(j);
		jsonw_obj_end(j);
	}
	jsonw_obj_end(j);

	jsonw_key(j, "threads");
	jsonw_obj_begin(j);
	jsonw_kint(j, "contexts", (int64_t)c->nrtp * c->tpr);
	double occ[THR_NSTATES], tot = 0;
	for (int s = 0; s < THR_NSTATES; s++) {
		snprintf(name, sizeof name, "threads.%s_ps", chip_state_name(s));
		tot += occ[s] = (double)chip_rtp_sum(c, name);
	}
	for (int s = 0; s < THR_NSTATES; s++)
		jsonw_knum(j, chip_state_name(s), ratio(occ[s], tot));
	jsonw_obj_end(j);

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

	jsonw_key(j, "skipped");
	jsonw_obj_begin(j);
	kv(j, "box_miss_packets", get(c, "skip.box_miss_packets"));
	kv(j, "box_miss_rays", get(c, "skip.box_miss_rays"));
	kv(j, "shadow_rays_no_lights", get(c, "skip.shadow_no_light"));
	kv(j, "shadow_rays_light_behind", get(c, "skip.shadow_light_behind"));
	kv(j, "packets_without_secondary", get(c, "skip.no_secondary"));
	kv(j, "rays_cut_by_depth", get(c, "skip.depth_cut"));
	kv(j, "untextured_hits", get(c, "skip.untextured_hits"));
	jsonw_obj_end(j);

	jsonw_key(j, "shading");
	jsonw_obj_begin(j);
	kv(j, "hits", get(c, "shade.hits"));
	kv(j, "misses", get(c, "shade.misses"));
	kv(j, "texel_reads", get(c, "shade.texel_reads"));
	kv(j, "shadow_rays_occluded", get(c, "shade.shadow_occluded"));
	kv(j, "shadow_rays_lit", get(c, "shade.shadow_lit"));
	kv(j, "reads_logged", get(c, "rgs.shade_reads"));
	kv(j, "requests", get(c, "rgs.shade_requests"));
	kv(j, "spawned_packets", get(c, "rgs.spawned_packets"));
	kv(j, "max_queue", get(c, "rgs.max_queue"));
	jsonw_obj_end(j);

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
	jsonw_obj_end(j);

	jsonw_key(j, "check");
	if (ri->check && ri->check->done) {
		jsonw_obj_begin(j);
		jsonw_kbool(j, "identical_8bit", ri->check->cmp.identical);
		jsonw_knum(j, "psnr", ri->check->cmp.psnr);
		kv(j, "differing_pixels", ri->check->cmp.differing_pixels);
		jsonw_obj_end(j);
	} else {
		jsonw_null(j);
	}

	jsonw_key(j, "counters");
	jsonw_obj_begin(j);
	for (size_t i = 0; i < c->st.n; i++)
		kv(j, c->st.e[i].name, *c->st.e[i].value);
	jsonw_obj_end(j);

	jsonw_key(j, "host");
	jsonw_obj_begin(j);
	jsonw_knum(j, "load_s", ri->load_ms / 1e3);
	jsonw_knum(j, "sim_s", c->sim_ms / 1e3);
	jsonw_knum(j, "check_s", ri->check && ri->check->done ? ri->check->ref_ms / 1e3 : 0.0);
	jsonw_knum(j, "wall_s", ri->wall_ms / 1e3);
	jsonw_knum(j, "sim_cycles_per_s", ratio((double)cyc, c->sim_ms / 1e3));
	jsonw_knum(j, "sim_to_ref_ratio",
	           ri->check && ri->check->done ? ratio(c->sim_ms, ri->check->ref_ms) : 0.0);
	jsonw_obj_end(j);
	jsonw_obj_end(j);
	return jsonw_close(j, d);
}
