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
 * after the checks that need no world (every argument, the config with
 * every memory check, the output formats, the CSV's columns, and
 * world_check: the scene and view flags, the camera and drt flags over the
 * view where it is known before the scene loads): exit 0 if they pass, no
 * scene loaded (a views file is read), nothing written (scripts/sweep
 * checks its common arguments with it, once per target).
 * An AFF scene with --anim-fps F makes --frames N an animation: N chip
 * runs at times T + i/F, each checked, each with numbered outputs
 * (run_frame; docs/views.md "Flags").
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/image.h"
#include "kernel-ref/world.h"
#include "sim/chip.h"
#include "sim/config.h"
#include "sim/hostmem.h"
#include "sim/memconfig.h"
#include "sim/observe.h"
#include "sim/report.h"
#include "sim/reportcheck.h"

static void usage(FILE *f)
{
	fprintf(
	    f, "usage: saarsim [options]\n"
	       "  --config FILE         hardware config (YAML; default: built-in saarcor-std)\n"
	       "  --set KEY=VALUE       override one config key (repeatable)\n"
	       "  --size WxH            frame size (sets frame.width and frame.height)\n"
	       "  --frames N            frames of the same view, memory kept warm (frame.frames);\n"
	       "                        with --anim-fps (AFF scene): N animation frames, one chip\n"
	       "                        run each, outputs numbered FILE-0000.png, ...; with\n"
	       "                        --two-level one warm chip runs them all (the host's\n"
	       "                        update written between frames; every frame's image\n"
	       "                        numbered, one report)\n"
	       "  --anim-cold           --two-level animation: a new (cold) chip per frame\n"
	       "  --out FILE            write the frame (.png, .exr, .ppm, .tif)\n"
	       "  --report FILE.json    write the JSON report (docs/report.md)\n"
	       "  --csv FILE            append one CSV row (a header first if FILE is new)\n"
	       "  --trace-mem FILE.gz   record every memory request (traces/memtrace.h)\n"
	       "  --timeline FILE.json  activity timeline, Chrome trace events for Perfetto\n"
	       "                        (cycle fidelity; docs/observe.md)\n"
	       "  --timeline-window C0:C1  only the events starting in cycles [C0, C1)\n"
	       "  --timeline-max-events N  cap on the timeline's events (default 1000000)\n"
	       "  --heatmap DIR         heat maps per tile and pixel, EXR and PNG (cycle\n"
	       "                        fidelity; docs/observe.md)\n"
	       "  --census FILE.csv     cycles and resource demand of every chunk of tiles\n"
	       "                        (cycle and functional; docs/fidelity.md)\n"
	       "  --fidelity MODE       cycle | sampled | functional (docs/fidelity.md)\n"
	       "  --sample-rate R       sampled: share of tiles measured (sampling.rate)\n"
	       "  --unit-tiles N        sampled: tiles per measured unit (sampling.unit_tiles)\n"
	       "  --warmup-tiles N      sampled: detailed warm-up tiles (sampling.warmup_tiles)\n"
	       "  --no-check            skip the comparison with kernel-ref\n"
	       "  --quiet               no progress line (shown on a terminal after 2 s)\n"
	       "  --host-mem-limit MB   refuse a run estimated to need more host memory\n"
	       "                        (default SAARSIM_HOST_MEM_MB, else 4096)\n"
	       "  --dry-run             every check that needs no scene (arguments, config,\n"
	       "                        camera and drt flags over a views file's or the\n"
	       "                        embedded scene's view), then exit (no scene loaded,\n"
	       "                        nothing run or written)\n"
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

/* The progress line (docs/observe.md): once the run has simulated for
 * `after` ms (SAARSIM_PROGRESS_AFTER_MS, default 2000), one line on
 * stderr, rewritten at most every 250 ms, cleared at the end; only when
 * stderr is a terminal and --quiet is not given. */
typedef struct progress {
	double t0, after, last;
	int shown;
	const chip *c;
} progress;

static void show_progress(void *ctx, int frame, int done, int total)
{
	progress *p = ctx;
	double now = now_ms(), el = now - p->t0;
	if (el < p->after || (p->shown && now - p->last < 250.0))
		return;
	p->last = now;
	int frames = p->c->cfg.frame.frames;
	double all = (double)frames * total, got = (double)frame * total + done;
	double cycles = (double)eng_now(p->c->e) / (double)p->c->clk.period;
	double left = got > 0 ? el / 1000.0 * (all - got) / got : 0;
	fprintf(stderr,
	        "\r\033[Ksaarsim: frame %d/%d, %d/%d tiles, %.4g cycles, %.3g cycles/s, %.0f s "
	        "left",
	        frame + 1, frames, done, total, cycles, el > 0 ? cycles / (el / 1000.0) : 0, left);
	fflush(stderr);
	p->shown = 1;
}

static void progress_clear(progress *p)
{
	if (p->shown)
		fputs("\r\033[K", stderr);
	p->shown = 0;
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
	                                   {"--kd-empty-bonus", "kdtree.empty_bonus"},
	                                   {"--kd-footprint", "kdtree.footprint"}};
	for (size_t i = 0; i < sizeof f / sizeof *f; i++)
		if (!strcmp(a, f[i][0]))
			return f[i][1];
	return NULL;
}

/* The flags without a value: their index in this list, -1 for others. */
static int bare_flag(const char *a)
{
	static const char *const bare_flags[] = {"--no-check", "--list-config", "--config-doc",
	                                         "--dry-run",  "--quiet",       "--anim-cold"};
	for (int k = 0; k < (int)(sizeof bare_flags / sizeof *bare_flags); k++)
		if (!strcmp(a, bare_flags[k]))
			return k;
	return -1;
}

/* The shorthand flag's "key=value" through the config, the whole value
 * (cfg_set refuses one too long), its messages naming the flag. */
static int set_key(saar_config *cfg, const char *flag, const char *value, cfg_origin *o, diag *d)
{
	const char *key = key_flag(flag);
	size_t n = strlen(key) + strlen(value) + 2;
	char *kv = malloc(n);
	if (!kv)
		return diag_set(d, flag, 0, 0, "out of memory");
	snprintf(kv, n, "%s=%s", key, value);
	int rc = cfg_set_at(cfg, flag, kv, o, d);
	free(kv);
	return rc;
}

/* The command line as the first pass reads it. */
typedef struct cli {
	world_opts wo; /* the world flags (rtref's) */
	const char *config, *out, *report, *size, *frames;
	const char *csv, *trace, *census, *mem_limit;
	const char *timeline, *tl_window, *tl_max, *heatmap;
	uint64_t tl_c0, tl_c1, tl_cap;
	int check, list, doc, dry, quiet, anim_cold;
	int warm; /* a warm two-level animation: frame.frames animation frames, one chip */
	const char *warm_out; /* then --out as given; out names the last frame */
} cli;

/* The first pass: every argument checked, the world flags into a->wo, the
 * files and bare flags into a; --set and the shorthand key flags wait for
 * the config file (config_from_args). Returns -1 to go on, else the exit
 * status (0 after --help). */
static int parse_args(int argc, char **argv, cli *a, diag *d)
{
	memset(a, 0, sizeof *a);
	world_opts_default(&a->wo);
	a->check = 1;
	for (int i = 1; i < argc;) {
		int r = key_flag(argv[i]) ? 0 : world_parse_arg(&a->wo, argc, argv, &i, d);
		if (r < 0)
			return cli_bad("saarsim", d->msg);
		if (r > 0)
			continue;
		const char *f = argv[i];
		if (!strcmp(f, "-h") || !strcmp(f, "--help")) {
			usage(stdout);
			return 0;
		}
		int b = bare_flag(f);
		if (b >= 0) {
			int *set[] = {&a->check, &a->list,  &a->doc,
			              &a->dry,   &a->quiet, &a->anim_cold}; /* bare_flags' order */
			*set[b] = b != 0;
			i++;
			continue;
		}
		if (i + 1 >= argc) {
			fprintf(stderr,
			        "saarsim: %s: unknown option or missing value (see --help)\n", f);
			return DIAG_EXIT;
		}
		/* saarsim's options of one value: a second would silently drop
		 * the first (--set and the key flags are applied in order) */
		const struct {
			const char *flag, **slot;
		} one[] = {{"--config", &a->config},
		           {"--size", &a->size},
		           {"--out", &a->out},
		           {"--report", &a->report},
		           {"--frames", &a->frames},
		           {"--csv", &a->csv},
		           {"--trace-mem", &a->trace},
		           {"--census", &a->census},
		           {"--host-mem-limit", &a->mem_limit},
		           {"--timeline", &a->timeline},
		           {"--timeline-window", &a->tl_window},
		           {"--timeline-max-events", &a->tl_max},
		           {"--heatmap", &a->heatmap}};
		size_t k = 0, n = sizeof one / sizeof *one;
		while (k < n && strcmp(f, one[k].flag))
			k++;
		if (k < n && *one[k].slot) {
			fprintf(stderr, "saarsim: %s given twice (it takes one value)\n", f);
			return DIAG_EXIT;
		}
		if (k < n)
			*one[k].slot = argv[i + 1];
		else if (strcmp(f, "--set") && !key_flag(f)) {
			fprintf(stderr, "saarsim: %s: unknown option (see --help)\n", f);
			return DIAG_EXIT;
		} /* --set and the key flags: applied in order once the file is read */
		i += 2;
	}
	return -1;
}

/* --set and the shorthand key flags, in their order on the command line;
 * *sampling_flag: the last sampling one (--sample-rate, --unit-tiles, ...).
 * The first pass accepted every argument, so this walk sees the same
 * option/value pairs: world flags are skipped by the same parser. */
static int set_flags(int argc, char **argv, saar_config *cfg, cfg_origin *o,
                     const char **sampling_flag, diag *d)
{
	world_opts skip;
	world_opts_default(&skip);
	*sampling_flag = NULL;
	for (int i = 1; i < argc;) {
		if (!key_flag(argv[i]) && world_parse_arg(&skip, argc, argv, &i, d) > 0)
			continue;
		const char *a = argv[i];
		if (bare_flag(a) >= 0) {
			i++;
			continue;
		}
		if (!strcmp(a, "--set") && cfg_set_at(cfg, "--set", argv[i + 1], o, d))
			return -1;
		if (key_flag(a) && set_key(cfg, a, argv[i + 1], o, d))
			return -1;
		if (key_flag(a) && !strncmp(key_flag(a), "sampling.", 9))
			*sampling_flag = a;
		i += 2;
	}
	return 0;
}

/* The observers' flags: a window or cap needs a timeline, which needs
 * cycle fidelity. */
static int observe_args(cli *a, const saar_config *cfg, diag *d)
{
	a->tl_c0 = 0;
	a->tl_c1 = UINT64_MAX;
	a->tl_cap = OBS_TL_MAX_EVENTS;
	if (!a->timeline && (a->tl_window || a->tl_max))
		return diag_set(d, a->tl_window ? "--timeline-window" : "--timeline-max-events", 0,
		                0, "needs --timeline FILE.json");
	if (a->tl_window &&
	    obs_parse_window("--timeline-window", a->tl_window, &a->tl_c0, &a->tl_c1, d))
		return -1;
	long cap;
	if (a->tl_max && cli_parse_int("--timeline-max-events", a->tl_max, 1, 1000000000L, &cap, d))
		return -1;
	if (a->tl_max)
		a->tl_cap = (uint64_t)cap;
	if ((a->timeline || a->heatmap) && cfg->fidelity != CFG_FIDELITY_CYCLE)
		return diag_set(d, a->timeline ? "--timeline" : "--heatmap", 0, 0,
		                "needs --fidelity cycle (this run's is %s)",
		                cfg->fidelity == CFG_FIDELITY_SAMPLED ? "sampled" : "functional");
	return 0;
}

/* The drt.* keys that are set go to the world as their flags would
 * (world_parse_arg: the same parsing, and the same range checks with the
 * view), unless the flag itself was given: the flag wins. */
static int drt_from_config(const saar_config *cfg, world_opts *wo, diag *d)
{
	/* in the order of world_opts.have_drt's bits (kernel-ref/world.c) */
	const struct {
		const char *key, *flag, *val;
	} k[] = {{"drt.spp", "--spp", cfg->drt.spp},
	         {"drt.aperture", "--aperture", cfg->drt.aperture},
	         {"drt.focus", "--focus", cfg->drt.focus},
	         {"drt.light_size", "--light-size", cfg->drt.light_size},
	         {"drt.gloss", "--gloss", cfg->drt.gloss},
	         {"drt.motion", "--motion", cfg->drt.motion}};
	for (int i = 0; i < 6; i++) {
		if (!*k[i].val || (wo->have_drt & (1u << i)))
			continue;
		char *argv[] = {(char *)k[i].flag, (char *)k[i].val};
		int at = 0;
		diag e = {{0}};
		if (world_parse_arg(wo, 2, argv, &at, &e) != 1) {
			/* named by the key: "drt.motion: expected X,Y,Z, ..." */
			size_t n = strlen(k[i].flag);
			const char *why =
			    strncmp(e.msg, k[i].flag, n) || strncmp(e.msg + n, ": ", 2)
			        ? e.msg
			        : e.msg + n + 2;
			return diag_set(d, k[i].key, 0, 0, "%s", why);
		}
		wo->drt_from_config |= 1u << i;
	}
	return 0;
}

/* The config: defaults, file, --set and the key flags, --size, --frames;
 * validated; the host memory limit into *limit_mb and the kd-tree keys into
 * a->wo. Returns -1 to go on, else the exit status. */
static int config_from_args(int argc, char **argv, cli *a, saar_config *cfg, uint64_t *limit_mb,
                            diag *d)
{
	/* where each value came from: a later check names it */
	static cfg_origin origin;
	memset(&origin, 0, sizeof origin);
	if (a->config ? cfg_load_at(cfg, a->config, &origin, d) : (cfg_defaults(cfg), 0))
		return cli_bad("saarsim", d->msg);
	const char *sampling_flag;
	if (set_flags(argc, argv, cfg, &origin, &sampling_flag, d))
		return cli_bad("saarsim", d->msg);
	/* a sampling flag on a run that does not sample would be ignored
	 * without a word */
	if (sampling_flag && cfg->fidelity != CFG_FIDELITY_SAMPLED) {
		fprintf(stderr,
		        "saarsim: %s: applies only to sampled runs (--fidelity sampled); this "
		        "run's fidelity is %s\n",
		        sampling_flag,
		        cfg->fidelity == CFG_FIDELITY_CYCLE ? "cycle" : "functional");
		return DIAG_EXIT;
	}
	if (a->size && cli_parse_size(a->size, &cfg->frame.width, &cfg->frame.height, d))
		return cli_bad("saarsim", d->msg);
	/* --two-level (issue 33 item 3, units/toplevel.h): kernel-ref's
	 * two-level tracer has neither reduced formats nor cone culling, and
	 * sampled runs' packet records are not kept for AFF worlds */
	if (a->wo.two_level && cfg->fidelity == CFG_FIDELITY_SAMPLED)
		return cli_bad("saarsim", "--two-level: cycle or functional fidelity only");
	if (a->wo.two_level && cfg->chip.cone_cull)
		return cli_bad("saarsim", "--two-level: no chip.cone_cull (kernel-ref's two-level "
		                          "tracer does not cull by cone)");
	/* chip.accel grid or --accel grid (the same): the world builds the
	 * grid, the chip walks it (units/gridtrav.h) */
	if (a->wo.accel == WORLD_ACCEL_GRID)
		cfg->chip.accel = CFG_ACCEL_GRID;
	if (cfg->chip.accel == CFG_ACCEL_GRID)
		a->wo.accel = WORLD_ACCEL_GRID;
	if (world_opts_check(&a->wo, d))
		return cli_bad("saarsim", d->msg);
	if (a->wo.accel == WORLD_ACCEL_GRID && a->wo.two_level)
		return cli_bad("saarsim", "--accel grid: not with --two-level (one or the other)");
	/* kernel-ref's grid tracer has neither cones nor reduced formats (its
	 * rays alone take the full-precision single-ray test) */
	if (a->wo.accel == WORLD_ACCEL_GRID && cfg->chip.cone_cull)
		return cli_bad("saarsim", "--accel grid: no chip.cone_cull");
	if (a->wo.accel == WORLD_ACCEL_GRID &&
	    (cfg->chip.fp.trav.exp != 8 || cfg->chip.fp.trav.mant != 23 ||
	     cfg->chip.fp.isect.exp != 8 || cfg->chip.fp.isect.mant != 23))
		return cli_bad("saarsim",
		               "--accel grid: chip.fp trav and isect full precision only");
	long nframes;
	if (a->frames) {
		if (cli_parse_int("--frames", a->frames, 1, 1000000, &nframes, d))
			return cli_bad("saarsim", d->msg);
		cfg->frame.frames = (int)nframes;
	}
	if (memcfg_validate(cfg, &origin, d))
		return cli_bad("saarsim", d->msg);
	if (hm_limit_mb(a->mem_limit, limit_mb, d))
		return cli_bad("saarsim", d->msg);
	if (observe_args(a, cfg, d))
		return cli_bad("saarsim", d->msg);
	if (drt_from_config(cfg, &a->wo, d))
		return cli_bad("saarsim", d->msg);
	a->wo.kd.cost_trav = (float)cfg->kdtree.cost_trav;
	a->wo.kd.cost_isect = (float)cfg->kdtree.cost_isect;
	a->wo.kd.max_depth = cfg->kdtree.max_depth;
	a->wo.kd.leaf_size = cfg->kdtree.leaf_size;
	a->wo.kd.empty_bonus = (float)cfg->kdtree.empty_bonus;
	a->wo.kd.footprint = (float)cfg->kdtree.footprint;
	return -1;
}

/* d's message with the flag in front ("--timeline: path: ..."); -1. */
static int flag_first(const char *flag, diag *d)
{
	char m[sizeof d->msg];
	snprintf(m, sizeof m, "%s", d->msg);
	return diag_set(d, flag, 0, 0, "%s", m);
}

/* --heatmap's file i (obs_heat_files) in folder dir, into path; 1 when it
 * is a picture (written through the image plugin), 0 for its JSON. */
static int heat_file(char *path, size_t n, const char *dir, int i)
{
	snprintf(path, n, "%s/%s", dir, obs_heat_files[i]);
	return strcmp(strrchr(obs_heat_files[i], '.'), ".json") != 0;
}

/* --heatmap's folder, made here if missing and removed, if still empty,
 * at exit or on SIGINT/SIGTERM/SIGHUP after its files' temporaries
 * (af_made_dir): a failed or interrupted run leaves no folder. */
static int reserve_heatmap(const char *dir, diag *d)
{
	struct stat st;
	if (!*dir)
		return diag_set(d, "--heatmap", 0, 0, "an empty folder name");
	if (stat(dir, &st)) {
		if (errno != ENOENT || mkdir(dir, 0777))
			return diag_set(d, "--heatmap", 0, 0, "%s: cannot make the folder: %s", dir,
			                strerror(errno));
		af_made_dir(dir);
	} else if (!S_ISDIR(st.st_mode))
		return diag_set(d, "--heatmap", 0, 0, "%s: not a folder", dir);
	char path[4200];
	for (int i = 0; obs_heat_files[i]; i++)
		if (heat_file(path, sizeof path, dir, i) ? img_reserve_file(path, d)
		                                         : af_reserve(path, "", d))
			return flag_first("--heatmap", d);
	return 0;
}

/* The image formats of --out and --heatmap's pictures: checked once the
 * scene is imported, still before the run (img_reserve_file in image.h:
 * the plugin's libraries start threads, and the importer forks). */
static int check_image_formats(const cli *a, diag *d)
{
	if (a->out && img_can_write(a->out, d))
		return -1;
	char path[4200];
	for (int i = 0; a->heatmap && obs_heat_files[i]; i++)
		if (heat_file(path, sizeof path, a->heatmap, i) && img_can_write(path, d))
			return flag_first("--heatmap", d);
	return 0;
}

/* Two output options naming one file: each writes its temporary and the
 * last rename wins, so one output is silently lost (--csv and --census
 * on one path kept the CSV alone). Every file a run writes counts: an
 * animation's numbered frames and reports (nout, nrep of them) and the
 * files --heatmap writes into its folder (--out hm/cycles.png was
 * replaced by the heat map). */
static int outputs_distinct(const cli *a, int nout, int nrep, diag *d)
{
	typedef struct {
		const char *flag;
		char key[8192];
	} ofile;
	int nheat = 0;
	while (a->heatmap && obs_heat_files[nheat])
		nheat++;
	size_t cap = (size_t)nout + (size_t)nrep + 4 + (size_t)nheat, n = 0;
	ofile *f = malloc(cap * sizeof *f);
	if (!f)
		return diag_set(d, "saarsim", 0, 0, "out of memory");
	char buf[8192];
	/* in the order of the options' listing: --out, --csv, --report,
	 * --census, --trace-mem, --timeline, --heatmap */
	const char *one[][2] = {{"--csv", a->csv},
	                        {"--census", a->census},
	                        {"--trace-mem", a->trace},
	                        {"--timeline", a->timeline}};
	for (int i = 0; a->out && strcmp(a->out, "-") && i < nout; i++) {
		f[n].flag = "--out";
		cli_output_key(cli_frame_path(a->out, nout, i, buf, sizeof buf), f[n++].key,
		               sizeof f[0].key);
	}
	for (int k = 0; k < 4; k++) {
		if (k == 1) /* --report after --csv */
			for (int i = 0; a->report && strcmp(a->report, "-") && i < nrep; i++) {
				f[n].flag = "--report";
				cli_output_key(cli_frame_path(a->report, nrep, i, buf, sizeof buf),
				               f[n++].key, sizeof f[0].key);
			}
		if (one[k][1] && strcmp(one[k][1], "-")) {
			f[n].flag = one[k][0];
			cli_output_key(one[k][1], f[n++].key, sizeof f[0].key);
		}
	}
	for (int i = 0; i < nheat; i++) {
		f[n].flag = "--heatmap";
		heat_file(buf, sizeof buf, a->heatmap, i);
		cli_output_key(buf, f[n++].key, sizeof f[0].key);
	}
	int rc = 0;
	for (size_t i = 0; i < n && !rc; i++)
		for (size_t j = 0; j < i && !rc; j++)
			if (!strcmp(f[i].key, f[j].key))
				rc =
				    diag_set(d, f[i].key, 0, 0,
				             "%s and %s name the same file (each would replace the "
				             "other's)",
				             f[j].flag, f[i].flag);
	free(f);
	return rc;
}

/* Every output's temporary is made now (two outputs on one file were
 * refused before: outputs_distinct), so a missing or read-only folder or
 * a CSV of other columns fails before the run, not after it (af_reserve);
 * so does a census the run cannot keep, before the world loads. An image
 * format the plugin cannot write fails once the scene is imported, still
 * before the run (check_image_formats). */
static int reserve_outputs(const cli *a, const saar_config *cfg, diag *d)
{
	if (a->out && img_reserve_file(a->out, d))
		return -1;
	if (a->csv && (report_csv_check(a->csv, d) || af_reserve(a->csv, "", d)))
		return -1;
	if (a->report && strcmp(a->report, "-") && af_reserve(a->report, "", d))
		return -1;
	if (a->census && af_reserve(a->census, "", d))
		return -1;
	if (a->trace && af_reserve(a->trace, "", d))
		return -1;
	if (a->timeline && af_reserve(a->timeline, "", d))
		return flag_first("--timeline", d);
	if (a->heatmap && reserve_heatmap(a->heatmap, d))
		return -1;
	if (a->census && chip_census_check(cfg, d))
		return -1;
	return 0;
}

/* Runs the chip with the memory trace (written under the temporary name
 * trace_tmp, renamed once the run succeeded) and the census on, then
 * checks the frame against kernel-ref unless --no-check. */
static int simulate(chip *c, const cli *a, afile *trace_tmp, afile *tl_tmp, obs **ob,
                    chip_check *chk, diag *d)
{
	if (a->timeline && af_open(tl_tmp, a->timeline, "", 1))
		return af_diag(d, a->timeline);
	if (a->timeline || a->heatmap) {
		obs_opts op = {a->timeline ? tl_tmp->f : NULL, a->tl_c0, a->tl_c1, a->tl_cap,
		               a->heatmap != NULL};
		if (!(*ob = obs_start(c, &op, a->timeline ? "--timeline" : "--heatmap", d)))
			return -1;
	}
	if (a->trace) {
		if (af_open(trace_tmp, a->trace, "", 0)) {
			af_diag(d, a->trace);
			return -1;
		}
		if (chip_trace_mem(c, trace_tmp->tmp, a->trace, d))
			return -1;
	}
	if (a->census && chip_census_on(c, d))
		return -1;
	if (chip_run(c, d))
		return -1;
	if (*ob) {
		uint64_t n, dropped;
		if (obs_finish(*ob, &n, &dropped))
			return af_diag(d, a->timeline);
		if (dropped)
			fprintf(stderr,
			        "saarsim: --timeline: capped at %llu events, %llu more left out "
			        "(narrow --timeline-window or raise --timeline-max-events)\n",
			        (unsigned long long)n, (unsigned long long)dropped);
	}
	if (chip_trace_close(c, d) || (a->check && chip_check_frame(c, chk, d)))
		return -1;
	return 0;
}

/* The report checks itself: a counter that stopped counting shows, one
 * warning line per failed invariant. */
static void check_report(const chip *c, rc_list *inv)
{
	report_check(c, inv);
	for (int i = 0; i < inv->n && i < RC_MAX; i++)
		fprintf(stderr, "warning: report invariant failed: %s\n", inv->msg[i]);
	if (inv->n > RC_MAX)
		fprintf(stderr, "warning: report invariant failed: %d more\n", inv->n - RC_MAX);
}

/* Every output is written complete under a temporary name first and all
 * are renamed into place together once the last one (the CSV with its new
 * row) is done: a run that fails on any leaves the files at all the output
 * paths as they were. Then the summary on stdout. Returns the exit status. */
static int write_outputs(const cli *a, report_info *ri, afile *trace_tmp, afile *tl_tmp,
                         const obs *ob, double t_start, diag *d)
{
	static af_group outs; /* 24 files of PATH_MAX names: not on the stack */
	memset(&outs, 0, sizeof outs);
	int csv_lock = -1;
	ri->group = &outs;
	if (a->out && fb_write(&ri->c->fb, a->out, &outs, d))
		goto fail;
	/* once, for the JSON and the CSV alike (the CSV's was taken again
	 * after the heat maps and the timeline: a later time) */
	ri->wall_ms = now_ms() - t_start;
	if (a->report && report_json(a->report, ri, d))
		goto fail;
	if (a->census && report_census(a->census, ri, d))
		goto fail;
	if (a->trace) {
		int bad = af_commit_to(trace_tmp, &outs);
		trace_tmp->tmp[0] = 0; /* in the group, or removed */
		if (bad) {
			af_diag(d, a->trace);
			goto fail;
		}
	}
	if (a->heatmap && obs_heat_write(ob, a->heatmap, &outs, d))
		goto fail;
	if (a->timeline) {
		int bad = af_commit_to(tl_tmp, &outs);
		tl_tmp->tmp[0] = 0;
		if (bad) {
			af_diag(d, a->timeline);
			goto fail;
		}
	}
	/* other runs appending to the same CSV wait from here until our
	 * rename is done, so no row is lost */
	if (a->csv)
		csv_lock = report_csv_lock(a->csv);
	if (a->csv && report_csv(a->csv, ri, d))
		goto fail;
	if (af_group_commit(&outs, d))
		goto fail;
	report_csv_unlock(csv_lock);
	report_text(stdout, ri);
	return 0;
fail:
	af_group_abort(&outs);
	report_csv_unlock(csv_lock);
	return cli_bad("saarsim", d->msg);
}

/* One run of the chip: frame i of an animation (the world loaded for
 * frame 0, moved to its time after), or the only one. The world stays
 * with the caller. Returns the exit status. */
/* A warm two-level animation (issue 33 item 4): before frame f, the frame
 * that ended is checked against kernel-ref (its line printed) and written
 * (--out FILE: FILE-NNNN, numbered as a cold animation's; the last frame
 * is written with the report), the world moves to frame f's time and the
 * chip's image takes the host's update (chip_anim_update). The last frame
 * is checked as every run's is. */
typedef struct warm_ctx {
	const cli *a;
	world *w;
	const char *out; /* the user's --out (unnumbered), or NULL */
	int frames;
} warm_ctx;

/* Frame f - 1's image, numbered, written and committed at once: a run
 * that fails later keeps the frames before it, as a cold animation does. */
static int warm_write(const warm_ctx *x, const chip *c, int f, diag *d)
{
	if (!x->out || !strcmp(x->out, "-"))
		return 0;
	char buf[4096];
	af_group g = {0};
	const char *p = cli_frame_path(x->out, x->frames, f - 1, buf, sizeof buf);
	if (fb_write(&c->fb, p, &g, d) || af_group_commit(&g, d)) {
		af_group_abort(&g);
		return -1;
	}
	return 0;
}

static int warm_between(chip *c, int f, void *ctx, diag *d)
{
	warm_ctx *x = ctx;
	if (x->a->check) {
		chip_check chk;
		if (chip_check_frame(c, &chk, d))
			return -1;
		c->anim_checked++;
		c->anim_identical += chk.cmp.identical && chk.single.identical;
		printf("  frame %d (%s): check vs kernel-ref: packets %s (%llu differing pixels), "
		       "single rays %s\n",
		       f, x->w->scene_label, chk.cmp.identical ? "identical" : "DIFFERENT",
		       (unsigned long long)chk.cmp.differing_pixels,
		       chk.single.identical ? "identical" : "DIFFERENT");
		fflush(stdout);
	}
	if (warm_write(x, c, f, d))
		return -1;
	if (world_set_time(x->w, &x->a->wo, world_frame_time(&x->a->wo, f), d))
		return -1;
	return chip_anim_update(c, f, d);
}

static int run_frame(const cli *a, const saar_config *cfg, world *w, int i, uint64_t limit_mb,
                     double t_start, diag *d)
{
	double t0 = now_ms();
	if (i == 0 ? world_load(w, &a->wo, d) || check_image_formats(a, d)
	           : world_set_time(w, &a->wo, world_frame_time(&a->wo, i), d))
		return cli_bad("saarsim", d->msg);
	double load_ms = now_ms() - t0;
	/* a config inside every key's range can still want more memory than
	 * the host has: refuse it before building anything */
	hm_est mem;
	hm_estimate(cfg, w, &mem);
	if (hm_check(&mem, limit_mb, d))
		return cli_bad("saarsim", d->msg);
	chip *c = chip_create(cfg, w, d);
	if (!c)
		return cli_bad("saarsim", d->msg);
	warm_ctx wx = {a, w, a->warm_out, cfg->frame.frames};
	if (a->warm) {
		c->between = warm_between;
		c->between_ctx = &wx;
	}
	const char *after = getenv("SAARSIM_PROGRESS_AFTER_MS");
	progress pr = {now_ms(), after && *after ? atof(after) : 2000.0, 0, 0, c};
	if (isatty(STDERR_FILENO) && !a->quiet) {
		c->progress = show_progress;
		c->progress_ctx = &pr;
	}
	chip_check chk;
	memset(&chk, 0, sizeof chk);
	static afile trace_tmp, tl_tmp;
	trace_tmp.tmp[0] = 0; /* "" while none is open */
	tl_tmp.tmp[0] = 0;
	obs *ob = NULL;
	int bad = simulate(c, a, &trace_tmp, &tl_tmp, &ob, &chk, d);
	progress_clear(&pr);
	char rbad[320];
	if (!bad && !a->check && chip_replay_bad(c, rbad, sizeof rbad))
		fprintf(stderr, "warning: %s\n", rbad); /* with the check, its line says it */
	int rc;
	if (bad) {
		rc = cli_bad("saarsim", d->msg);
	} else {
		static rc_list inv;
		check_report(c, &inv);
		report_info ri = {c, w,    a->check ? &chk : NULL,        load_ms,
		                  0, NULL, (double)mem.total / (1 << 20), &inv};
		rc = write_outputs(a, &ri, &trace_tmp, &tl_tmp, ob, t_start, d);
	}
	obs_free(ob);
	chip_destroy(c);
	if (trace_tmp.tmp[0])
		af_abort(&trace_tmp);
	if (tl_tmp.tmp[0])
		af_abort(&tl_tmp);
	return rc;
}

int main(int argc, char **argv)
{
	double t_start = now_ms();
	static cli a;
	diag d = {{0}};
	int rc = parse_args(argc, argv, &a, &d);
	if (rc >= 0)
		return rc;
	if (a.list || a.doc) {
		if (a.list)
			cfg_list(stdout);
		if (a.doc)
			cfg_write_markdown(stdout);
		return 0;
	}
	saar_config cfg;
	uint64_t limit_mb;
	rc = config_from_args(argc, argv, &a, &cfg, &limit_mb, &d);
	if (rc >= 0)
		return rc;
	/* an animation (--anim-fps, AFF scene): --frames N are N animation
	 * times, each a chip run of its own (the chip's frame.frames repeat
	 * one memory image; the animated chip is issue 33's item 3) */
	int nanim = a.wo.have_anim_fps ? cfg.frame.frames : 1;
	if (a.anim_cold && !(a.wo.two_level && nanim > 1))
		return cli_bad("saarsim", "--anim-cold: for a --two-level animation (--anim-fps, "
		                          "--frames N > 1) only");
	/* a two-level animation runs warm: one chip, frame.frames animation
	 * frames (chip_anim_update between them) */
	a.warm = a.wo.two_level && nanim > 1 && !a.anim_cold;
	if (a.warm)
		nanim = 1;
	else if (a.wo.have_anim_fps)
		cfg.frame.frames = 1;
	if (nanim > 1 && (a.trace || a.timeline || a.heatmap || a.census))
		return cli_bad("saarsim",
		               "--anim-fps with --frames N: --trace-mem, --timeline, "
		               "--heatmap and --census take one frame (use --anim-time)");
	cli fa = a;
	char ob[4096], rb[4096];
	fa.out = cli_frame_path(a.out, a.warm ? cfg.frame.frames : nanim, 0, ob, sizeof ob);
	fa.report = cli_frame_path(a.report, nanim, 0, rb, sizeof rb);
	if (outputs_distinct(&a, a.warm ? cfg.frame.frames : nanim, nanim, &d) ||
	    reserve_outputs(&fa, &cfg, &d))
		return cli_bad("saarsim", d.msg);
	/* the other frames' numbered files too, before any frame runs */
	if (cli_check_frame_paths(a.out, a.warm ? cfg.frame.frames : nanim, &d) ||
	    cli_check_frame_paths(a.report, nanim, &d))
		return cli_bad("saarsim", d.msg);
	/* no scene import: what world_load would refuse without the scene
	 * (the views file is read), and the formats now */
	if (a.dry)
		return world_check(&a.wo, &d) || check_image_formats(&fa, &d)
		           ? cli_bad("saarsim", d.msg)
		           : 0;
	world w;
	memset(&w, 0, sizeof w);
	rc = 0;
	for (int i = 0; i < nanim && !rc; i++) {
		fa.out = cli_frame_path(a.out, nanim, i, ob, sizeof ob);
		fa.report = cli_frame_path(a.report, nanim, i, rb, sizeof rb);
		if (a.warm && a.out && strcmp(a.out, "-")) {
			fa.warm_out = a.out;
			fa.out = cli_frame_path(a.out, cfg.frame.frames, cfg.frame.frames - 1, ob,
			                        sizeof ob);
		}
		/* each cold frame's wall time is its own (the second's held the
		 * first's); the first's holds the start of the process too */
		rc = run_frame(&fa, &cfg, &w, i, limit_mb, i ? now_ms() : t_start, &d);
	}
	world_free(&w);
	return rc;
}
