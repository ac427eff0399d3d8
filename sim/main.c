/*
 * main.c: the saarsim command line.
 *
 *   saarsim [--config FILE] [scene/view flags] [--size WxH] [--frames N]
 *           [--out frame.png] [--report report.json] [--csv FILE]
 *           [--trace-mem FILE.gz] [--census FILE.csv] [--set key=value ...]
 *           [--no-check] [--dry-run]
 *           [--list-config] [--config-doc]
 *
 * Loads the config (built-in defaults = configs/saarcor-std.yaml, then the
 * file, then --set, --size and --frames), the world (the same flags as
 * rtref), runs the chip, checks the (last) frame against kernel-ref, prints
 * a summary and writes the frame, the JSON report, the memory trace and one
 * CSV row. Bad input: one line "saarsim: ..." on stderr, exit status 2, no
 * output file changed (each is written to a temporary file, and all are
 * renamed into place together once every one is complete). --dry-run stops
 * after the checks that need no world (every argument, the config, the
 * output formats, the CSV's columns): exit 0 if they pass, nothing loaded
 * or written (scripts/sweep checks its pass-through arguments with it).
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/image.h"
#include "kernel-ref/world.h"
#include "sim/chip.h"
#include "sim/config.h"
#include "sim/hostmem.h"
#include "sim/report.h"
#include "sim/reportcheck.h"

static void usage(FILE *f)
{
	fprintf(f,
	        "usage: saarsim [options]\n"
	        "  --config FILE         hardware config (YAML; default: built-in saarcor-std)\n"
	        "  --set KEY=VALUE       override one config key (repeatable)\n"
	        "  --size WxH            frame size (sets frame.width and frame.height)\n"
	        "  --frames N            frames of the same view, memory kept warm (frame.frames)\n"
	        "  --out FILE            write the frame (.png, .exr, .ppm, .tif)\n"
	        "  --report FILE.json    write the JSON report (docs/report.md)\n"
	        "  --csv FILE            append one CSV row (a header first if FILE is new)\n"
	        "  --trace-mem FILE.gz   record every memory request (traces/memtrace.h)\n"
	        "  --census FILE.csv     cycles and resource demand of every chunk of tiles\n"
	        "                        (cycle and functional; docs/fidelity.md)\n"
	        "  --fidelity MODE       cycle | sampled | functional (docs/fidelity.md)\n"
	        "  --sample-rate R       sampled: share of tiles measured (sampling.rate)\n"
	        "  --unit-tiles N        sampled: tiles per measured unit (sampling.unit_tiles)\n"
	        "  --warmup-tiles N      sampled: detailed warm-up tiles (sampling.warmup_tiles)\n"
	        "  --no-check            skip the comparison with kernel-ref\n"
	        "  --host-mem-limit MB   refuse a run estimated to need more host memory\n"
	        "                        (default SAARSIM_HOST_MEM_MB, else 4096)\n"
	        "  --dry-run             check the arguments and the config, then exit (no scene\n"
	        "                        loaded, nothing run or written)\n"
	        "  --list-config         print every config key and exit\n"
	        "  --config-doc          print docs/config.md and exit\n");
	fputs(world_usage, f);
}

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

typedef struct progress {
	double t0;
	int shown;
} progress;

static void show_progress(void *ctx, int frame, int done, int total)
{
	progress *p = ctx;
	if (now_ms() - p->t0 < 1000.0)
		return;
	fprintf(stderr, "\rsaarsim: frame %d: %d/%d tiles", frame + 1, done, total);
	p->shown = 1;
}

/* The config key a shorthand flag sets, NULL if a is not one: the
 * fidelity flags (saarsim's own) and the kd-tree flags (the world flags
 * rtref shares; here they go through the config like --set, in order with
 * it, so the config's ranges and types apply). */
static const char *key_flag(const char *a)
{
	static const char *const f[][2] = {{"--fidelity", "fidelity"},
	                                   {"--sample-rate", "sampling.rate"},
	                                   {"--unit-tiles", "sampling.unit_tiles"},
	                                   {"--warmup-tiles", "sampling.warmup_tiles"},
	                                   {"--kd-cost-trav", "kdtree.cost_trav"},
	                                   {"--kd-cost-isect", "kdtree.cost_isect"},
	                                   {"--kd-max-depth", "kdtree.max_depth"},
	                                   {"--kd-leaf-size", "kdtree.leaf_size"},
	                                   {"--kd-empty-bonus", "kdtree.empty_bonus"}};
	for (size_t i = 0; i < sizeof f / sizeof *f; i++)
		if (!strcmp(a, f[i][0]))
			return f[i][1];
	return NULL;
}

/* The flags without a value: their index in this list, -1 for others. */
static int bare_flag(const char *a)
{
	static const char *const bare_flags[] = {"--no-check", "--list-config", "--config-doc",
	                                         "--dry-run"};
	for (int k = 0; k < (int)(sizeof bare_flags / sizeof *bare_flags); k++)
		if (!strcmp(a, bare_flags[k]))
			return k;
	return -1;
}

/* The shorthand flag's "key=value" through the config, the whole value
 * (cfg_set refuses one too long), its messages naming the flag. */
static int set_key(saar_config *cfg, const char *flag, const char *value, diag *d)
{
	const char *key = key_flag(flag);
	size_t n = strlen(key) + strlen(value) + 2;
	char *kv = malloc(n);
	if (!kv)
		return diag_set(d, flag, 0, 0, "out of memory");
	snprintf(kv, n, "%s=%s", key, value);
	int rc = cfg_set_as(cfg, flag, kv, d);
	free(kv);
	return rc;
}

int main(int argc, char **argv)
{
	double t_start = now_ms();
	world_opts wo;
	world_opts_default(&wo);
	const char *config = NULL, *out = NULL, *report = NULL, *size = NULL, *frames = NULL;
	const char *csv = NULL, *trace = NULL, *census = NULL, *mem_limit = NULL;
	int check = 1, list = 0, doc = 0, dry = 0;
	diag d = {{0}};
	for (int i = 1; i < argc;) {
		int r = key_flag(argv[i]) ? 0 : world_parse_arg(&wo, argc, argv, &i, &d);
		if (r < 0)
			return cli_bad("saarsim", d.msg);
		if (r > 0)
			continue;
		const char *a = argv[i];
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
			usage(stdout);
			return 0;
		}
		int b = bare_flag(a);
		if (b >= 0) {
			int *set[] = {&check, &list, &doc, &dry}; /* bare_flags' order */
			*set[b] = b != 0;
			i++;
			continue;
		}
		if (i + 1 >= argc) {
			fprintf(stderr,
			        "saarsim: %s: unknown option or missing value (see --help)\n", a);
			return DIAG_EXIT;
		}
		const char *v = argv[i + 1];
		if (!strcmp(a, "--config"))
			config = v;
		else if (!strcmp(a, "--set") || key_flag(a))
			; /* applied below, in order, once the config file is read */
		else if (!strcmp(a, "--size"))
			size = v;
		else if (!strcmp(a, "--out"))
			out = v;
		else if (!strcmp(a, "--report"))
			report = v;
		else if (!strcmp(a, "--frames"))
			frames = v;
		else if (!strcmp(a, "--csv"))
			csv = v;
		else if (!strcmp(a, "--trace-mem"))
			trace = v;
		else if (!strcmp(a, "--census"))
			census = v;
		else if (!strcmp(a, "--host-mem-limit"))
			mem_limit = v;
		else {
			fprintf(stderr, "saarsim: %s: unknown option (see --help)\n", a);
			return DIAG_EXIT;
		}
		i += 2;
	}
	if (list || doc) {
		if (list)
			cfg_list(stdout);
		if (doc)
			cfg_write_markdown(stdout);
		return 0;
	}

	/* the config: defaults, file, --set, --size, kd-tree flags */
	saar_config cfg;
	if (config ? cfg_load(&cfg, config, &d) : (cfg_defaults(&cfg), 0))
		return cli_bad("saarsim", d.msg);
	/* the first pass accepted every argument, so this walk sees the same
	 * option/value pairs: world flags are skipped by the same parser */
	world_opts skip;
	world_opts_default(&skip);
	const char *sampling_flag = NULL; /* the last --sample-rate, --unit-tiles, ... */
	for (int i = 1; i < argc;) {
		if (!key_flag(argv[i]) && world_parse_arg(&skip, argc, argv, &i, &d) > 0)
			continue;
		const char *a = argv[i];
		if (bare_flag(a) >= 0) {
			i++;
			continue;
		}
		if (!strcmp(a, "--set") && cfg_set(&cfg, argv[i + 1], &d))
			return cli_bad("saarsim", d.msg);
		if (key_flag(a) && set_key(&cfg, a, argv[i + 1], &d))
			return cli_bad("saarsim", d.msg);
		if (key_flag(a) && !strncmp(key_flag(a), "sampling.", 9))
			sampling_flag = a;
		i += 2;
	}
	/* a sampling flag on a run that does not sample would be ignored
	 * without a word */
	if (sampling_flag && cfg.fidelity != CFG_FIDELITY_SAMPLED) {
		fprintf(stderr,
		        "saarsim: %s: applies only to sampled runs (--fidelity sampled); this "
		        "run's fidelity is %s\n",
		        sampling_flag, cfg.fidelity == CFG_FIDELITY_CYCLE ? "cycle" : "functional");
		return DIAG_EXIT;
	}
	if (size && cli_parse_size(size, &cfg.frame.width, &cfg.frame.height, &d))
		return cli_bad("saarsim", d.msg);
	long nframes;
	if (frames) {
		if (cli_parse_int("--frames", frames, 1, 1000000, &nframes, &d))
			return cli_bad("saarsim", d.msg);
		cfg.frame.frames = (int)nframes;
	}
	if (cfg_validate(&cfg, &d))
		return cli_bad("saarsim", d.msg);
	uint64_t limit_mb;
	if (hm_limit_mb(mem_limit, &limit_mb, &d))
		return cli_bad("saarsim", d.msg);
	wo.kd.cost_trav = (float)cfg.kdtree.cost_trav;
	wo.kd.cost_isect = (float)cfg.kdtree.cost_isect;
	wo.kd.max_depth = cfg.kdtree.max_depth;
	wo.kd.leaf_size = cfg.kdtree.leaf_size;
	wo.kd.empty_bonus = (float)cfg.kdtree.empty_bonus;

	/* every output's temporary is made now, so an unwritable --out
	 * format, a missing or read-only folder or a CSV of other columns
	 * fails before the run, not after it (af_reserve) */
	if (out && img_reserve(out, &d))
		return cli_bad("saarsim", d.msg);
	if (csv && (report_csv_check(csv, &d) || af_reserve(csv, "", &d)))
		return cli_bad("saarsim", d.msg);
	if (report && strcmp(report, "-") && af_reserve(report, "", &d))
		return cli_bad("saarsim", d.msg);
	if (census && af_reserve(census, "", &d))
		return cli_bad("saarsim", d.msg);
	if (trace && af_reserve(trace, "", &d))
		return cli_bad("saarsim", d.msg);
	/* so does a census the run cannot keep, before the world loads */
	if (census && chip_census_check(&cfg, &d))
		return cli_bad("saarsim", d.msg);
	if (dry)
		return 0;
	double t0 = now_ms();
	world w;
	if (world_load(&w, &wo, &d))
		return cli_bad("saarsim", d.msg);
	double load_ms = now_ms() - t0;
	/* a config inside every key's range can still want more memory than
	 * the host has: refuse it before building anything */
	hm_est mem;
	hm_estimate(&cfg, &w, &mem);
	if (hm_check(&mem, limit_mb, &d)) {
		world_free(&w);
		return cli_bad("saarsim", d.msg);
	}
	chip *c = chip_create(&cfg, &w, &d);
	if (!c) {
		world_free(&w);
		return cli_bad("saarsim", d.msg);
	}
	progress pr = {now_ms(), 0};
	if (isatty(STDERR_FILENO)) {
		c->progress = show_progress;
		c->progress_ctx = &pr;
	}
	int rc = 0;
	chip_check chk;
	memset(&chk, 0, sizeof chk);
	/* the trace is written under a temporary name, renamed once the run
	 * succeeded (trace_tmp.tmp is "" while none is open) */
	afile trace_tmp;
	trace_tmp.tmp[0] = 0;
	if (trace) {
		if (af_open(&trace_tmp, trace, "", 0)) {
			af_diag(&d, trace);
			rc = cli_bad("saarsim", d.msg);
			goto done;
		}
		if (chip_trace_mem(c, trace_tmp.tmp, &d)) {
			rc = cli_bad("saarsim", d.msg);
			goto done;
		}
	}
	if (census && chip_census_on(c, &d)) {
		rc = cli_bad("saarsim", d.msg);
		goto done;
	}
	if (chip_run(c, &d) || chip_trace_close(c, &d) ||
	    (check && chip_check_frame(c, &chk, &d))) {
		rc = cli_bad("saarsim", d.msg);
		goto done;
	}
	if (pr.shown)
		fputc('\n', stderr);
	/* the report checks itself: a counter that stopped counting shows */
	static rc_list inv;
	report_check(c, &inv);
	for (int i = 0; i < inv.n && i < RC_MAX; i++)
		fprintf(stderr, "warning: report invariant failed: %s\n", inv.msg[i]);
	if (inv.n > RC_MAX)
		fprintf(stderr, "warning: report invariant failed: %d more\n", inv.n - RC_MAX);
	/* every output is written complete under a temporary name first and
	 * all are renamed into place together once the last one (the CSV
	 * with its new row) is done: a run that fails on any leaves the
	 * files at all the output paths as they were */
	af_group outs = {0};
	int csv_lock = -1;
	if (out && fb_write(&c->fb, out, &outs, &d))
		goto fail;
	report_info ri = {c,
	                  &w,
	                  check ? &chk : NULL,
	                  load_ms,
	                  now_ms() - t_start,
	                  &outs,
	                  (double)mem.total / (1 << 20),
	                  &inv};
	if (report && report_json(report, &ri, &d))
		goto fail;
	if (census && report_census(census, &ri, &d))
		goto fail;
	if (trace) {
		int bad = af_commit_to(&trace_tmp, &outs);
		trace_tmp.tmp[0] = 0; /* in the group, or removed */
		if (bad) {
			af_diag(&d, trace);
			goto fail;
		}
	}
	ri.wall_ms = now_ms() - t_start;
	/* other runs appending to the same CSV wait from here until our
	 * rename is done, so no row is lost */
	if (csv)
		csv_lock = report_csv_lock(csv);
	if (csv && report_csv(csv, &ri, &d))
		goto fail;
	if (af_group_commit(&outs, &d))
		goto fail;
	report_csv_unlock(csv_lock);
	report_text(stdout, &ri);
	goto done;
fail:
	af_group_abort(&outs);
	report_csv_unlock(csv_lock);
	rc = cli_bad("saarsim", d.msg);
done:
	chip_destroy(c);
	if (trace_tmp.tmp[0])
		af_abort(&trace_tmp);
	world_free(&w);
	return rc;
}
