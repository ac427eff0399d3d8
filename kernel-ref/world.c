/*
 * world.c: scene + view + kd-tree + memory image set-up (see world.h).
 */
#include "kernel-ref/world.h"

#include "kernel-ref/aff.h"
#include "kernel-ref/atomicfile.h"
#include "kernel-ref/image.h"
#include "kernel-ref/spd.h"
#include "kernel-ref/twolevel.h"
#include "kernel-ref/worldcache.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

const char world_usage[] =
    "  --scene PATH          scene file (.obj .ply .stl .3ds .gltf .glb .dae, .gz ok; limits:\n"
    "                        SAARSIM_IMPORT_CPU_S, SAARSIM_IMPORT_MEM_MB) or a procedural scene\n"
    "                        spd:balls|tetra|mount|rings|cornell|billiard[:SIZE[:TESS]]\n"
    "                        (docs/spd.md), or an animated BART scene (.aff, docs/views.md\n"
    "                        \"AFF scenes\"); default: the view's scene, else the embedded\n"
    "                        Cornell-like room\n"
    "  --anim-time T         AFF scene: the animation time to render (default 0)\n"
    "  --anim-fps F          AFF scene: frames per second of animation time; frame i of a\n"
    "                        multi-frame run (--frames N) is at T + i/F\n"
    "  --two-level           AFF scene: trace through a kd-tree per rigid object (built\n"
    "                        once) under a tree of instances rebuilt per frame; saarsim:\n"
    "                        a transformation unit, animations on one warm chip\n"
    "  --accel kd|grid       trace the kd-tree (default) or a uniform grid rebuilt with\n"
    "                        every frame (seed 003; the same image; saarsim: chip.accel)\n"
    "  --grid-lambda F --grid-macro N --grid-packet 1|4|8 --grid-mailbox 0|1 --grid-cull 0|1\n"
    "                        the grid: cells per triangle (5), macrocell side (6, 0: none),\n"
    "                        rays per frustum side (8; 1: single rays), mailboxing (1),\n"
    "                        frustum culling (1); with the grid only\n"
    "  --views FILE --view N camera and lights from a views file (format: docs/views.md)\n"
    "  --eye X,Y,Z --lookat X,Y,Z --up X,Y,Z --fov DEG   camera (override the view)\n"
    "  --light X,Y,Z         point light (repeatable; replaces the view's lights)\n"
    "  --no-lights           no lights: no shadow rays (not with --light)\n"
    "  --spp N (1|4|16|64) --aperture F --focus F --light-size F --gloss F --motion X,Y,Z\n"
    "                        distribution ray tracing (override the view's drt; docs/views.md)\n"
    "  --kd-cost-trav F --kd-cost-isect F --kd-max-depth N --kd-leaf-size N --kd-empty-bonus F\n"
    "  --kd-footprint F      kd-tree SAH for packets F times the scene's diagonal\n"
    "                        wide; 0: the plain SAH (saarsim's default; rtref's is\n"
    "                        its view's packet: docs/kernel-ref.md)\n"
    "  --world-cache DIR|off keep built worlds (scene, kd-tree, memory image), reference\n"
    "                        frames, packet records and warming runs in DIR and reuse them\n"
    "                        while the program and scene files are unchanged; default:\n"
    "                        $SAARSIM_CACHE_DIR (a folder or off), else\n"
    "                        $XDG_CACHE_HOME/saarsim, else $HOME/.cache/saarsim; off: none\n"
    "  --world-cache-max MB  cap on the folder's entries, least recently used removed\n"
    "                        first (default $SAARSIM_CACHE_MAX_MB, else 4096; 0: no cap)\n";

void world_opts_default(world_opts *o)
{
	memset(o, 0, sizeof *o);
	kd_params_default(&o->kd);
	grid_params_default(&o->gp);
	o->cache_max_mb = -1;
}

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static int parse_vec(const char *flag, const char *s, vec3 *v, diag *d)
{
	float f[3];
	const char *p = s;
	for (int k = 0; k < 3; k++) {
		char *end;
		errno = 0;
		f[k] = strtof(p, &end);
		if (end == p || errno || !isfinite(f[k]))
			return diag_set(d, flag, 0, 0,
			                "expected three finite numbers X,Y,Z, got '%s'", s);
		p = end;
		if (k < 2) {
			if (*p != ',')
				return diag_set(d, flag, 0, 0, "expected X,Y,Z, got '%s'", s);
			p++;
		}
	}
	if (*p)
		return diag_set(d, flag, 0, 0, "trailing characters in '%s'", s);
	*v = v3(f[0], f[1], f[2]);
	return 0;
}

static int parse_num(const char *flag, const char *s, double lo, double hi, double *out, diag *d)
{
	char *end;
	errno = 0;
	double x = strtod(s, &end);
	if (end == s || *end || errno || !isfinite(x))
		return diag_set(d, flag, 0, 0, "expected a number, got '%s'", s);
	if (x < lo || x > hi)
		return diag_set(d, flag, 0, 0, "%s is out of range [%g, %g]", s, lo, hi);
	*out = x;
	return 0;
}

/* The distribution ray tracing flags, in the order of world_opts.have_drt's
 * bits; their ranges are checked with the view (drt_problem). */
static const char *const drt_flags[] = {"--spp",        "--aperture", "--focus",
                                        "--light-size", "--gloss",    "--motion"};

/* Flag a with value v if it is a DRT flag: 1 (taken), -1 (bad), 0 (not one). */
static int drt_flag(world_opts *o, const char *a, const char *v, diag *d)
{
	int k = 0;
	while (k < 6 && strcmp(a, drt_flags[k]))
		k++;
	if (k == 6)
		return 0;
	o->have_drt |= 1u << k;
	double x;
	long n;
	float *f[] = {NULL, &o->drt.aperture, &o->drt.focus, &o->drt.light_size, &o->drt.gloss};
	if (k == 0) {
		if (cli_parse_int(a, v, 1, 64, &n, d))
			return -1;
		o->drt.spp = (int)n;
	} else if (k == 5) {
		if (parse_vec(a, v, &o->drt.motion, d))
			return -1;
	} else {
		if (parse_num(a, v, 0, DRT_SIZE_MAX, &x, d))
			return -1;
		*f[k] = (float)x;
	}
	return 1;
}

/* --anim-time T (any finite time within 1e9) or --anim-fps F. */
static int anim_arg(world_opts *o, const char *a, const char *v, diag *d)
{
	int fps = !strcmp(a, "--anim-fps");
	if (parse_num(a, v, fps ? 1e-6 : -1e9, fps ? 1e6 : 1e9, fps ? &o->anim_fps : &o->anim_time,
	              d))
		return -1;
	*(fps ? &o->have_anim_fps : &o->have_anim_time) = 1;
	return 0;
}

/* --accel and the --grid-* flags. */
static int grid_flag(world_opts *o, const char *a, const char *v, diag *d)
{
	long n;
	double x;
	if (strcmp(a, "--accel"))
		o->grid_flag = a;
	if (!strcmp(a, "--accel")) {
		if (strcmp(v, "kd") && strcmp(v, "grid"))
			return diag_set(d, a, 0, 0, "expected kd or grid, got '%s'", v);
		o->accel = !strcmp(v, "grid") ? WORLD_ACCEL_GRID : WORLD_ACCEL_KD;
	} else if (!strcmp(a, "--grid-lambda")) {
		if (parse_num(a, v, 1e-3, 1e3, &x, d))
			return -1;
		o->gp.lambda = x;
	} else if (!strcmp(a, "--grid-macro")) {
		if (cli_parse_int(a, v, 0, 64, &n, d))
			return -1;
		o->gp.macro = (int)n;
	} else if (!strcmp(a, "--grid-packet")) {
		if (cli_parse_int(a, v, 1, 8, &n, d))
			return -1;
		if (n != 1 && n != 4 && n != 8)
			return diag_set(d, a, 0, 0, "expected 1, 4 or 8, got '%s'", v);
		o->gp.packet = (int)n;
	} else {
		if (cli_parse_int(a, v, 0, 1, &n, d))
			return -1;
		*(!strcmp(a, "--grid-cull") ? &o->gp.cull : &o->gp.mailbox) = (int)n;
	}
	return 0;
}

int world_parse_arg(world_opts *o, int argc, char **argv, int *i, diag *d)
{
	const char *a = argv[*i];
	static const char *const with_value[] = {"--scene",
	                                         "--views",
	                                         "--view",
	                                         "--eye",
	                                         "--lookat",
	                                         "--up",
	                                         "--fov",
	                                         "--light",
	                                         "--kd-cost-trav",
	                                         "--kd-cost-isect",
	                                         "--kd-max-depth",
	                                         "--kd-leaf-size",
	                                         "--kd-empty-bonus",
	                                         "--kd-footprint",
	                                         "--world-cache",
	                                         "--world-cache-max",
	                                         "--spp",
	                                         "--aperture",
	                                         "--focus",
	                                         "--light-size",
	                                         "--gloss",
	                                         "--motion",
	                                         "--anim-time",
	                                         "--anim-fps",
	                                         "--accel",
	                                         "--grid-lambda",
	                                         "--grid-macro",
	                                         "--grid-packet",
	                                         "--grid-mailbox",
	                                         "--grid-cull"};
	int takes = 0;
	for (size_t k = 0; k < sizeof with_value / sizeof *with_value; k++)
		if (strcmp(a, with_value[k]) == 0) {
			takes = 1;
			/* one value each, given once: a second was a silent
			 * override of the first (--light repeats; the --kd-* flags
			 * are saarsim's --set of their keys, the last one winning) */
			int repeats = !strcmp(a, "--light") || !strncmp(a, "--kd-", 5);
			if (!repeats && (o->given & (1ull << k)))
				return diag_set(d, a, 0, 0, "given twice (it takes one value)");
			o->given |= 1ull << k;
		}
	if (!takes) {
		if (strcmp(a, "--no-lights") == 0 || strcmp(a, "--two-level") == 0) {
			if (a[2] == 'n' && o->nlights)
				return diag_set(d, a, 0, 0,
				                "not with --light (no lights, or these)");
			*(a[2] == 'n' ? &o->no_lights : &o->two_level) = 1;
			(*i)++;
			return 1;
		}
		return 0;
	}
	if (*i + 1 >= argc)
		return diag_set(d, a, 0, 0, "missing value");
	const char *v = argv[*i + 1];
	*i += 2;
	double x;
	long n;
	int dk = drt_flag(o, a, v, d);
	if (dk)
		return dk;
	if (!strncmp(a, "--accel", 7) || !strncmp(a, "--grid-", 7))
		return grid_flag(o, a, v, d) ? -1 : 1;
	if (!strcmp(a, "--scene"))
		o->scene = v;
	else if (!strcmp(a, "--views"))
		o->views = v;
	else if (!strcmp(a, "--view"))
		o->view = v;
	else if (!strcmp(a, "--world-cache"))
		o->cache_dir = v;
	else if (!strcmp(a, "--world-cache-max")) {
		if (cli_parse_int(a, v, 0, WC_MAX_MB, &n, d))
			return -1;
		o->cache_max_mb = n;
	} else if (!strncmp(a, "--anim-", 7))
		return anim_arg(o, a, v, d) ? -1 : 1;
	else if (!strcmp(a, "--eye")) {
		o->have_eye = 1;
		return parse_vec(a, v, &o->cam.eye, d) ? -1 : 1;
	} else if (!strcmp(a, "--lookat")) {
		o->have_lookat = 1;
		return parse_vec(a, v, &o->cam.lookat, d) ? -1 : 1;
	} else if (!strcmp(a, "--up")) {
		o->have_up = 1;
		return parse_vec(a, v, &o->cam.up, d) ? -1 : 1;
	} else if (!strcmp(a, "--fov")) {
		if (parse_num(a, v, 1e-3, 179.9, &x, d))
			return -1;
		o->have_fov = 1;
		o->cam.fov_deg = (float)x;
	} else if (!strcmp(a, "--light")) {
		if (o->no_lights)
			return diag_set(d, a, 0, 0, "not with --no-lights (these lights, or none)");
		if (o->nlights == VIEW_MAX_LIGHTS)
			return diag_set(d, a, 0, 0, "at most %d lights", VIEW_MAX_LIGHTS);
		o->lights[o->nlights].color = v3(1, 1, 1);
		if (parse_vec(a, v, &o->lights[o->nlights].pos, d))
			return -1;
		o->nlights++;
	} else if (!strcmp(a, "--kd-cost-trav")) {
		if (parse_num(a, v, KD_COST_MIN, KD_COST_MAX, &x, d))
			return -1;
		o->kd.cost_trav = (float)x;
	} else if (!strcmp(a, "--kd-cost-isect")) {
		if (parse_num(a, v, KD_COST_MIN, KD_COST_MAX, &x, d))
			return -1;
		o->kd.cost_isect = (float)x;
	} else if (!strcmp(a, "--kd-max-depth")) {
		if (cli_parse_int(a, v, 0, KD_DEPTH_MAX, &n, d))
			return -1;
		o->kd.max_depth = (int)n;
	} else if (!strcmp(a, "--kd-leaf-size")) {
		if (cli_parse_int(a, v, KD_LEAF_MIN, KD_LEAF_MAX, &n, d))
			return -1;
		o->kd.leaf_size = (int)n;
	} else if (!strcmp(a, "--kd-empty-bonus")) {
		if (parse_num(a, v, 0, KD_BONUS_MAX, &x, d))
			return -1;
		o->kd.empty_bonus = (float)x;
	} else if (!strcmp(a, "--kd-footprint")) {
		if (parse_num(a, v, 0, KD_FOOTPRINT_MAX, &x, d))
			return -1;
		o->kd.footprint = (float)x;
		o->kd_footprint_given = 1;
	}
	return 1;
}

int world_opts_check(const world_opts *o, diag *d)
{
	if (o->grid_flag && o->accel != WORLD_ACCEL_GRID)
		return diag_set(d, o->grid_flag, 0, 0,
		                "applies to the grid only (--accel grid); this run traces the "
		                "kd-tree");
	return 0;
}

const char *world_cache_name(int status)
{
	static const char *const names[] = {"off", "hit", "stored", "not stored"};
	return status >= 0 && status < 4 ? names[status] : "?";
}

/* The world's own kd-tree parameters: with --two-level the image serves
 * shading only (the two-level trees trace), so one leaf is enough; it also
 * keeps the image's layout the same at every time (a split would move
 * the regions after the tree), which a warm chip's update needs. */
static const kd_params *world_kd(const world_opts *o)
{
	static _Thread_local kd_params one;
	if (!o->two_level)
		return &o->kd;
	one = o->kd;
	one.max_depth = 1;
	one.leaf_size = INT_MAX; /* the root is a leaf */
	return &one;
}

/* --accel grid: the grid over the world's image (again after every
 * rebuild of the image: the grid's lists name its triangles). */
static int world_grid(world *w, const world_opts *o, diag *d)
{
	if (o->two_level)
		return diag_set(d, "--accel", 0, 0,
		                "grid: not with --two-level (one or the other)");
	if (w->grid)
		grid_free(w->grid);
	else if (!(w->grid = calloc(1, sizeof *w->grid)))
		return diag_set(d, "--accel", 0, 0, "out of memory");
	return grid_build(w->grid, &w->m, &o->gp, d);
}

/* --two-level: the objects' trees, once, and the instances at the
 * world's time. */
static int two_level_build(world *w, const world_opts *o, diag *d)
{
	if (!(w->tl = calloc(1, sizeof *w->tl)))
		return diag_set(d, "--two-level", 0, 0, "out of memory");
	if (tl_build(w->tl, w->aff, &o->kd, d))
		return -1;
	return tl_frame(w->tl, w->aff, w->anim_time, &w->m, d);
}

/* Frames the view on the scene's box at time t: the world's own scene's,
 * or with two_level (whose scene is in object space) that of the scene
 * flattened at t. */
static int frame_bbox(world *w, int two_level, double t, diag *d)
{
	if (!two_level) {
		view_frame_bbox(&w->v, w->s.bounds);
		return 0;
	}
	scene s;
	if (aff_flatten(w->aff, t, 0, &s, d))
		return -1;
	view_frame_bbox(&w->v, s.bounds);
	scene_free(&s);
	return 0;
}

/* An AFF scene read and flattened at o's time (--two-level: in its
 * instances' own frames, aff_flatten_local, the same at every time); its
 * own view (if the file has one) to *sv, *has_view set. */
static int load_aff(world *w, const world_opts *o, const char *path, view *sv, int *has_view,
                    diag *d)
{
	if (!(w->aff = calloc(1, sizeof *w->aff)))
		return diag_set(d, path, 0, 0, "out of memory");
	w->anim_time = world_frame_time(o, 0);
	if (aff_load(w->aff, path, NULL, NULL, d) ||
	    (o->two_level ? aff_flatten_local(w->aff, 1, &w->s, d)
	                  : aff_flatten(w->aff, w->anim_time, 1, &w->s, d)))
		return -1;
	int r = aff_view(w->aff, w->anim_time, sv, d);
	*has_view = r > 0;
	return r < 0 ? -1 : 0;
}

/* Imports or generates the scene at path (NULL: the embedded one); a
 * procedural scene's own view goes to *sv. Files read go to f. */
static int load_scene(world *w, const char *path, view *sv, wc_files *f, diag *d)
{
	if (spd_is(path))
		return spd_generate(&w->s, sv, path, d);
	if (path) {
		if (scene_load_files(&w->s, path, f ? wc_files_add : NULL, f, d))
			return -1;
		for (uint32_t i = 0; f && i < w->s.ntexs; i++)
			wc_files_add(f, w->s.texs[i].path);
		/* the texels came through the image plugin, a file of its own:
		 * a rebuilt plugin must not meet the texels of the old one */
		char plug[PATH_MAX];
		diag pd;
		if (f && w->s.ntexs && !img_plugin_path(plug, sizeof plug, &pd))
			wc_files_add(f, plug);
		return 0;
	}
	scene_default(&w->s);
	return 0;
}

/* The parts of a world the cache keeps, in their stored order: figures of
 * the scene and the kd-tree (their arrays are not stored), the memory
 * image's header, the procedural view and the image's CRC; the image
 * bytes are the tail. */
enum { WORLD_PARTS = 5 };
static void world_parts(wc_part p[WORLD_PARTS], scene *s, kdtree *kd, mimg *m, view *sv,
                        uint32_t *crc)
{
	p[0] = (wc_part){s, sizeof *s};
	p[1] = (wc_part){kd, sizeof *kd};
	p[2] = (wc_part){m, sizeof *m};
	p[3] = (wc_part){sv, sizeof *sv};
	p[4] = (wc_part){crc, sizeof *crc};
}

/* The view: from --views/--view, else the default. */
static int load_view(world *w, const world_opts *o, diag *d)
{
	if (o->view && !o->views)
		return diag_set(d, "--view", 0, 0, "needs --views FILE");
	if (o->views) {
		if (!o->view)
			return diag_set(d, "--views", 0, 0, "needs --view NAME");
		if (view_load(&w->v, o->views, o->view, d))
			return -1;
	} else {
		view_default(&w->v);
	}
	return 0;
}

/* The world cache's folder (wc_choose): w->cache_dir set when there is
 * one to use. A folder named by --world-cache that cannot be made or
 * written is an error; a default one is not (the run goes on without a
 * cache, cache_note and a warning say why): a default must not stop a run
 * in a read-only home. */
static int cache_open(world *w, const world_opts *o, diag *d)
{
	w->cache_from = wc_choose(o->cache_dir, w->cache_path, sizeof w->cache_path);
	if (w->cache_from == WC_FROM_OFF)
		return 0;
	if (w->cache_from == WC_FROM_NONE) {
		if (o->cache_dir)
			return diag_set(d, "--world-cache", 0, 0, "folder name too long");
		snprintf(w->cache_note, sizeof w->cache_note, "%s",
		         "no default folder: SAARSIM_CACHE_DIR, XDG_CACHE_HOME and HOME are unset "
		         "(or the name is too long)");
		return 0;
	}
	if (wc_cap(o->cache_max_mb, &w->cache_cap, d))
		return -1;
	diag e;
	int dflt = w->cache_from != WC_FROM_FLAG;
	if (wc_prepare(w->cache_path, dflt, w->cache_prog, sizeof w->cache_prog, &e)) {
		if (!dflt) {
			*d = e;
			return -1;
		}
		snprintf(w->cache_note, sizeof w->cache_note, "%s", e.msg);
		fprintf(stderr,
		        "warning: world cache off: %s (the default folder, from %s; "
		        "--world-cache DIR or SAARSIM_CACHE_DIR picks another, off turns it off)\n",
		        e.msg, wc_from_name(w->cache_from));
		return 0;
	}
	w->cache_dir = w->cache_path;
	return 0;
}

int world_cache_is_default(const world *w)
{
	return w->cache_from != WC_FROM_FLAG;
}

void world_cache_json(jsonw *j, const world *w)
{
	jsonw_key(j, "world_cache_dir");
	if (w->cache_dir)
		jsonw_str(j, w->cache_dir);
	else
		jsonw_null(j);
	jsonw_kbool(j, "world_cache_default", world_cache_is_default(w));
	jsonw_kstr(j, "world_cache_from", wc_from_name(w->cache_from));
	jsonw_knum(j, "world_cache_max_mb", (double)(w->cache_cap >> 20));
	jsonw_kstr(j, "world_cache_note", w->cache_note);
}

int world_cache_put(const world *w, const char *file, const char *key, const wc_files *f,
                    const wc_part *parts, int nparts, const void *tail, size_t ntail, diag *d)
{
	/* the head: the key, the files' names and the parts (a bound) */
	uint64_t need = ntail + strlen(key) + 4096;
	for (int i = 0; i < nparts; i++)
		need += parts[i].n;
	for (int i = 0; f && i < f->n; i++)
		need += strlen(f->path[i]) + 32;
	if (wc_make_room(w->cache_dir, need, w->cache_cap))
		return diag_set(d, file, 0, 0,
		                "world cache: not stored: the entry (%.1f MB) alone passes the "
		                "folder's cap (%llu MB; --world-cache-max, SAARSIM_CACHE_MAX_MB)",
		                (double)need / (1 << 20), (unsigned long long)(w->cache_cap >> 20));
	return wc_put(file, key, f, parts, nparts, tail, ntail, d);
}

/* The world cache's file (cfile) and key (*ckey, malloc'd) for the scene
 * at path; the stored world into parts and w->m.bytes when there is one
 * (w->cache = WORLD_CACHE_HIT). Nothing without a folder. */
static int cache_lookup(world *w, const world_opts *o, const kd_params *kp, const char *path,
                        wc_part *parts, char *cfile, size_t ncfile, char **ckey, diag *d)
{
	if (cache_open(w, o, d))
		return -1;
	if (!w->cache_dir)
		return 0;
	if (!(*ckey = wc_world_key(w->cache_prog, path, kp)))
		return diag_set(d, w->cache_dir, 0, 0, "--world-cache: out of memory");
	if (wc_file(cfile, ncfile, w->cache_dir, "world", *ckey))
		return diag_set(d, w->cache_dir, 0, 0, "--world-cache: folder name too long");
	void *bytes;
	size_t n;
	if (wc_get(cfile, *ckey, parts, WORLD_PARTS, &bytes, &n)) {
		if (n == w->m.size) {
			w->m.bytes = bytes;
			w->cache = WORLD_CACHE_HIT;
		} else {
			free(bytes);
			memset(&w->s, 0, sizeof w->s);
			memset(&w->kd, 0, sizeof w->kd);
			memset(&w->m, 0, sizeof w->m);
		}
	}
	return 0;
}

/* The camera flags (--eye, --lookat, --up, --fov) over camera c. */
static void cam_flags(const world_opts *o, camera *c)
{
	if (o->have_eye)
		c->eye = o->cam.eye;
	if (o->have_lookat)
		c->lookat = o->cam.lookat;
	if (o->have_up)
		c->up = o->cam.up;
	if (o->have_fov)
		c->fov_deg = o->cam.fov_deg;
}

/* The drt flags over the view's p, checked (drt_problem); a problem is
 * named by the flag, or by the drt.* key that stood for it. */
static int drt_flags_over(drt_params *p, const world_opts *o, diag *d)
{
	const drt_params *q = &o->drt;
	unsigned h = o->have_drt;
	p->spp = h & 1 ? q->spp : p->spp;
	p->aperture = h & 2 ? q->aperture : p->aperture;
	p->focus = h & 4 ? q->focus : p->focus;
	p->light_size = h & 8 ? q->light_size : p->light_size;
	p->gloss = h & 16 ? q->gloss : p->gloss;
	p->motion = h & 32 ? q->motion : p->motion;
	const char *key, *prob = drt_problem(p, &key);
	if (prob) { /* the flag of the key (the views file's name for it) */
		static const char *const keys[] = {"spp",        "aperture", "focus",
		                                   "light_size", "gloss",    "motion"};
		int k = 0;
		while (k < 5 && strcmp(keys[k], key))
			k++;
		char key_name[32];
		snprintf(key_name, sizeof key_name, "drt.%s", keys[k]);
		return diag_set(d, o->drt_from_config & (1u << k) ? key_name : drt_flags[k], 0, 0,
		                "%s", prob);
	}
	return 0;
}

/* The camera and light flags override the view. */
static int apply_view_flags(world *w, const world_opts *o, diag *d)
{
	cam_flags(o, &w->v.cam);
	if (o->have_eye || o->have_lookat || o->have_up || o->have_fov) {
		if (camera_validate(&w->v.cam, "--eye/--lookat/--up/--fov", d))
			return -1;
		snprintf(w->v.name, sizeof w->v.name, "%s", "custom");
		w->view_changed = 1;
	}
	if (o->nlights) {
		w->v.nlights = o->nlights;
		memcpy(w->v.lights, o->lights, sizeof o->lights);
		w->v.lights_given = 1;
		w->view_changed = 1;
	}
	if (o->have_drt) {
		if (drt_flags_over(&w->v.drt, o, d))
			return -1;
		w->view_changed = 1;
	}
	view_place_default_light(&w->v, &w->s);
	if (o->no_lights) {
		w->v.nlights = 0;
		w->view_changed = 1;
	}
	return 0;
}

/* Stores the built world in the cache (cfile, ckey; files: the scene's
 * files it depends on). A cache that cannot be written costs the next run
 * time, not this run its result: a warning, and on. */
static void cache_store(world *w, view *sv, const char *cfile, const char *ckey,
                        const wc_files *files)
{
	/* stored without the arrays: copies with them zeroed */
	scene s0 = w->s;
	s0.v = s0.n = NULL;
	s0.uv = NULL;
	s0.mat = NULL;
	s0.mats = NULL;
	s0.texs = NULL;
	kdtree k0 = w->kd;
	k0.nodes = NULL;
	k0.list = NULL;
	mimg m0 = w->m;
	m0.bytes = NULL;
	w->image_crc = wc_crc(w->m.bytes, w->m.size);
	wc_part put[WORLD_PARTS];
	world_parts(put, &s0, &k0, &m0, sv, &w->image_crc);
	diag wd;
	w->cache = WORLD_CACHE_STORED;
	if (world_cache_put(w, cfile, ckey, files, put, WORLD_PARTS, w->m.bytes, (size_t)w->m.size,
	                    &wd)) {
		fprintf(stderr, "warning: %s\n", wd.msg);
		w->cache = WORLD_CACHE_UNSTORED;
	}
}

void world_opts_packet_tree(world_opts *o, int height)
{
	if (o->kd_footprint_given)
		return;
	o->kd.footprint = KD_RTREF_FOOTPRINT;
	o->fp_packet = TILE_W;
	o->fp_height = height;
}

/* rtref's own tree (world_opts.fp_packet): the kd parameters with the
 * footprint of a primary packet of the final view, camera flags applied,
 * so that the world cache keys the tree by it (kdtree.c, "Packet
 * footprint"; docs/kernel-ref.md). A packet fp_packet pixels wide on an
 * image fp_height high spans fp_packet * 2 tan(fov/2) / fp_height
 * radians (the camera's vertical field of view, square pixels). The view
 * is known before the scene loads when it comes from a views file or is
 * the embedded scene's default. A scene file without a views file is
 * framed by its box (view_frame_bbox): its field of view is known
 * (VIEW_FRAME_FOV or --fov), its eye only after the import unless --eye
 * gives it, so the eye is left NaN here, which keys the cache by the rule
 * (the file's box decides the eye), and set by fp_framed_eye once the
 * view is framed. Else (a view brought by a procedural or AFF scene) the
 * parameters as given. */
static kd_params view_kd(const world *w, const world_opts *o, const char *path)
{
	kd_params k = o->kd;
	if (o->fp_packet <= 0 || o->fp_height <= 0)
		return k;
	camera c = w->v.cam;
	int framed = path && !o->views;
	if (framed && (spd_is(path) || aff_is(path)))
		return k;
	if (framed) {
		c.fov_deg = (float)VIEW_FRAME_FOV;
		c.eye = v3(NAN, NAN, NAN);
	}
	cam_flags(o, &c);
	double a = o->fp_packet * 2.0 * tan(c.fov_deg * (M_PI / 360.0)) / o->fp_height;
	if (!(a > 0 && a <= KD_FP_ANGLE_MAX))
		return k;
	k.fp_angle = (float)a;
	k.fp_eye[0] = c.eye.x;
	k.fp_eye[1] = c.eye.y;
	k.fp_eye[2] = c.eye.z;
	return k;
}

/* view_kd's footprint for a framed scene file: the eye of the view as
 * framed (w->v, flags applied) where view_kd left it NaN. */
static void fp_framed_eye(kd_params *k, const world *w)
{
	if (k->fp_angle > 0 && isnan(k->fp_eye[0])) {
		k->fp_eye[0] = w->v.cam.eye.x;
		k->fp_eye[1] = w->v.cam.eye.y;
		k->fp_eye[2] = w->v.cam.eye.z;
	}
}

/* A scene a views file named that fails to load: its message (which
 * names the scene) after the place of the view's `scene:` value, so the
 * user sees which file and line to fix. */
static int view_scene_failed(const world *w, const world_opts *o, diag *d)
{
	int line, col;
	if (o->scene || !o->views || !w->v.scene[0] ||
	    view_scene_at(o->views, o->view, &line, &col))
		return -1;
	char m[sizeof d->msg + 8];
	snprintf(m, sizeof m, "scene %s", d->msg);
	return diag_set(d, o->views, line, col, "%s", m);
}

/* The unit axis least along v: v x it is at least 0.8 |v| long. */
static vec3 axis_across(vec3 v)
{
	float x = fabsf(v.x), y = fabsf(v.y), z = fabsf(v.z);
	return x <= y && x <= z ? v3(1, 0, 0) : y <= z ? v3(0, 1, 0) : v3(0, 0, 1);
}

/* The camera flags when the view is not known before the scene loads:
 * what they decide alone (eye and lookat apart, up not zero, up across
 * the direction when all three are given, fov), the rest of the camera
 * made up so that it passes. */
static int cam_flags_alone(const world_opts *o, diag *d)
{
	camera c;
	memset(&c, 0, sizeof c);
	c.fov_deg = o->have_fov ? o->cam.fov_deg : 60.0f;
	c.up = o->have_up ? o->cam.up : v3(0, 1, 0);
	if (o->have_eye && o->have_lookat) {
		c.eye = o->cam.eye;
		c.lookat = o->cam.lookat;
		if (!o->have_up)
			c.up = axis_across(v3_sub(c.lookat, c.eye));
	} else {
		c.eye = v3(0, 0, 0);
		c.lookat = axis_across(c.up);
	}
	return camera_validate(&c, "--eye/--lookat/--up/--fov", d);
}

int world_check(const world_opts *o, diag *d)
{
	static view v; /* the view: large, and only ever one check at a time */
	memset(&v, 0, sizeof v);
	int known = 1; /* the view is known before the scene loads */
	if (o->view && !o->views)
		return diag_set(d, "--view", 0, 0, "needs --views FILE");
	if (o->views && !o->view)
		return diag_set(d, "--views", 0, 0, "needs --view NAME");
	if (o->views) {
		if (view_load(&v, o->views, o->view, d))
			return -1;
	} else if (!o->scene) {
		view_default(&v);
	} else {
		known = 0;
	}
	const char *path = o->scene ? o->scene : (o->views && v.scene[0]) ? v.scene : NULL;
	if ((o->have_anim_time || o->have_anim_fps || o->two_level) && !aff_is(path))
		return diag_set(d,
		                o->have_anim_time  ? "--anim-time"
		                : o->have_anim_fps ? "--anim-fps"
		                                   : "--two-level",
		                0, 0, "needs an AFF scene (--scene FILE.aff)");
	if (o->have_eye || o->have_lookat || o->have_up || o->have_fov) {
		if (!known && cam_flags_alone(o, d))
			return -1;
		camera c = v.cam;
		cam_flags(o, &c);
		if (known && camera_validate(&c, "--eye/--lookat/--up/--fov", d))
			return -1;
	}
	/* the view's drt where it is known, else none (each flag alone) */
	return o->have_drt ? drt_flags_over(&v.drt, o, d) : 0;
}

int world_load(world *w, const world_opts *o, diag *d)
{
	memset(w, 0, sizeof *w);
	double t0 = now_ms();
	if (load_view(w, o, d))
		return -1;
	const char *path = o->scene ? o->scene : (o->views && w->v.scene[0]) ? w->v.scene : NULL;
	int spd = spd_is(path), aff = aff_is(path), aff_has_view = 0;
	if ((o->have_anim_time || o->have_anim_fps || o->two_level) && !aff)
		return diag_set(d,
		                o->have_anim_time  ? "--anim-time"
		                : o->have_anim_fps ? "--anim-fps"
		                                   : "--two-level",
		                0, 0, "needs an AFF scene (--scene FILE.aff)");
	wc_files files = {0};
	char cfile[PATH_MAX], *ckey = NULL;
	view sv;
	memset(&sv, 0, sizeof sv);
	wc_part parts[WORLD_PARTS];
	world_parts(parts, &w->s, &w->kd, &w->m, &sv, &w->image_crc);
	/* an AFF world is not cached: it is rebuilt per animation time */
	kd_params kp = view_kd(w, o, path);
	if (!aff && cache_lookup(w, o, &kp, path, parts, cfile, sizeof cfile, &ckey, d)) {
		free(ckey);
		return view_scene_failed(w, o, d);
	}
	if (aff ? load_aff(w, o, path, &sv, &aff_has_view, d)
	        : !w->cache && load_scene(w, path, &sv, w->cache_dir ? &files : NULL, d)) {
		view_scene_failed(w, o, d);
		goto fail;
	}
	/* a procedural scene brings its standard view, an AFF scene its
	 * camera at the time, unless a views file gave one */
	if ((spd || aff_has_view) && !o->views)
		w->v = sv;
	/* a scene file without a view: framed by its bounding box (the
	 * embedded room's camera showed a model as a few pixels) */
	if (path && !spd && !aff_has_view && !o->views &&
	    frame_bbox(w, o->two_level, w->anim_time, d))
		goto fail;
	if (aff)
		snprintf(w->scene_label, sizeof w->scene_label, "%.990s@t=%g", path, w->anim_time);
	else
		snprintf(w->scene_label, sizeof w->scene_label, "%s", path ? path : w->s.name);
	w->load_ms = now_ms() - t0;
	if (apply_view_flags(w, o, d))
		goto fail;
	if (w->cache != WORLD_CACHE_HIT) {
		fp_framed_eye(&kp, w);
		t0 = now_ms();
		if (kd_build(&w->kd, &w->s, aff ? world_kd(o) : &kp, d))
			goto fail;
		w->kd_ms = now_ms() - t0;
		t0 = now_ms();
		if (mimg_build(&w->m, &w->s, &w->kd, d))
			goto fail;
		w->image_ms = now_ms() - t0;
		if (w->cache_dir && !aff)
			cache_store(w, &sv, cfile, ckey, &files);
	}
	if (o->two_level && two_level_build(w, o, d))
		goto fail;
	if (o->accel == WORLD_ACCEL_GRID && world_grid(w, o, d))
		goto fail;
	wc_files_free(&files);
	free(ckey);
	if (w->kd.nbudget_leaves) /* also from the cache: each run says so */
		fprintf(stderr,
		        "warning: %s: the kd-tree build ran out of its work budget (%u leaves cut "
		        "short): the triangles overlap heavily; the tree is correct but slower to "
		        "trace than SAH would make it (kdtree.budget_leaves in the report)\n",
		        w->s.name, w->kd.nbudget_leaves);
	return 0;
fail:
	wc_files_free(&files);
	free(ckey);
	world_free(w);
	return -1;
}

/* The reference frame's key: the frame's (wc_frame_key), and what else
 * changes the stored render's counts though not its image: cone culling,
 * the interval walk and another tracer than the kd-tree (the grid with
 * its parameters). A frame without any keeps the key it had. malloc'd;
 * NULL when out of memory. */
static char *reference_key(const world *w, const render_opts *o)
{
	char *fk = wc_frame_key(w->cache_prog, w->image_crc, w->m.size, &w->v, o);
	if (!fk || (!o->cone_cull && !o->frustum && !o->tracer))
		return fk;
	char more[256];
	const grid *g = w->grid && o->tracer == &w->grid->tracer ? w->grid : NULL;
	int m = snprintf(more, sizeof more, "reference cone %d frustum %d tracer %s", o->cone_cull,
	                 o->frustum,
	                 !o->tracer ? "kd"
	                 : g        ? "grid"
	                            : "two-level");
	if (g)
		m += snprintf(more + m, sizeof more - (size_t)m, " %a %d %d %d %d", g->p.lambda,
		              g->p.macro, g->p.packet, g->p.mailbox, g->p.cull);
	size_t n = strlen(fk) + (size_t)m + 2;
	char *key = malloc(n);
	if (key)
		snprintf(key, n, "%s%s\n", fk, more);
	free(fk);
	return key;
}

int world_reference_rgb8(const world *w, const render_opts *o, uint8_t *rgb, render_stats *st,
                         int *cached, diag *d)
{
	size_t n = (size_t)o->width * (size_t)o->height * 3;
	char file[PATH_MAX], *key = NULL;
	*cached = 0;
	if (w->cache_dir && (key = reference_key(w, o)) &&
	    wc_file(file, sizeof file, w->cache_dir, "frame", key)) {
		free(key);
		key = NULL;
	}
	wc_part parts[] = {{st, sizeof *st}};
	const void *t;
	size_t nt;
	wc_map map;
	if (key && wc_get_mapped(file, key, parts, 1, &t, &nt, &map)) {
		int hit = nt == n;
		if (hit)
			memcpy(rgb, t, n);
		wc_unmap(&map);
		if (hit) {
			free(key);
			*cached = 1;
			return 0;
		}
	}
	framebuf ref;
	if (fb_init(&ref, o->width, o->height)) {
		free(key);
		return diag_set(d, "kernel-ref", 0, 0, "out of memory for the reference frame");
	}
	int rc = render_frame(&w->m, &w->v, o, &ref, st, d);
	if (!rc) {
		fb_to_rgb8(&ref, rgb, NULL);
		diag wd;
		if (key && world_cache_put(w, file, key, NULL, parts, 1, rgb, n, &wd))
			fprintf(stderr, "warning: %s\n", wd.msg);
	}
	fb_free(&ref);
	free(key);
	return rc;
}

void world_free(world *w)
{
	mimg_free(&w->m);
	kd_free(&w->kd);
	scene_free(&w->s);
	if (w->aff) {
		aff_free(w->aff);
		free(w->aff);
		w->aff = NULL;
	}
	if (w->tl) {
		tl_free(w->tl);
		free(w->tl);
		w->tl = NULL;
	}
	if (w->grid) {
		grid_free(w->grid);
		free(w->grid);
		w->grid = NULL;
	}
}

double world_frame_time(const world_opts *o, int i)
{
	return o->anim_time + (o->have_anim_fps ? (double)i / o->anim_fps : 0.0);
}

int world_set_time(world *w, const world_opts *o, double t, diag *d)
{
	if (!w->aff)
		return diag_set(d, "--anim-time", 0, 0, "needs an AFF scene (--scene FILE.aff)");
	double t0 = now_ms();
	w->anim_time = t;
	/* two-level: the shading image is the same at every time; only the
	 * top level moves */
	if (!w->tl) {
		mimg_free(&w->m);
		kd_free(&w->kd);
		scene_free(&w->s);
		if (aff_flatten(w->aff, t, 1, &w->s, d))
			return -1;
	}
	view sv;
	int r = aff_view(w->aff, t, &sv, d);
	if (r < 0)
		return -1;
	if (!o->views) {
		if (r)
			w->v = sv;
		else if (frame_bbox(w, w->tl != NULL, t, d))
			return -1;
	}
	snprintf(w->scene_label, sizeof w->scene_label, "%.990s@t=%g", w->aff->path, t);
	w->load_ms = now_ms() - t0;
	w->view_changed = 0;
	if (apply_view_flags(w, o, d))
		return -1;
	if (w->tl) {
		w->kd_ms = w->image_ms = 0;
		return tl_frame(w->tl, w->aff, t, &w->m, d);
	}
	t0 = now_ms();
	if (kd_build(&w->kd, &w->s, world_kd(o), d))
		return -1;
	w->kd_ms = now_ms() - t0;
	t0 = now_ms();
	if (mimg_build(&w->m, &w->s, &w->kd, d))
		return -1;
	w->image_ms = now_ms() - t0;
	if (w->grid && world_grid(w, o, d))
		return -1;
	return 0;
}

/* ---- command-line helpers ---- */

int cli_parse_int(const char *flag, const char *s, long lo, long hi, long *out, diag *d)
{
	char *end;
	errno = 0;
	long v = strtol(s, &end, 10);
	if (end == s || *end || errno)
		return diag_set(d, flag, 0, 0, "expected an integer, got '%s'", s);
	if (v < lo || v > hi)
		return diag_set(d, flag, 0, 0, "%ld is out of range [%ld, %ld]", v, lo, hi);
	*out = v;
	return 0;
}

/* A side of --size: digits only (strtol would take leading blanks and a
 * sign, so " 64x64" and "+64x64" were accepted and "64x64 " refused), at
 * most 9 of them (no overflow); -1 when there are none. */
static long size_side(const char *s, const char **end)
{
	long v = 0;
	int n = 0;
	while (*s >= '0' && *s <= '9' && n < 9) {
		v = v * 10 + (*s++ - '0');
		n++;
	}
	*end = s;
	return n ? v : -1;
}

int cli_parse_size(const char *s, int *w, int *h, diag *d)
{
	const char *end;
	long a = size_side(s, &end);
	if (a < 0 || (*end != 'x' && *end != 'X'))
		return diag_set(d, "--size", 0, 0, "expected WxH, got '%s'", s);
	long b = size_side(end + 1, &end);
	if (b < 0 || *end)
		return diag_set(d, "--size", 0, 0, "expected WxH, got '%s'", s);
	if (a < 1 || a > 16384 || b < 1 || b > 16384)
		return diag_set(d, "--size", 0, 0, "%s is out of range (1..16384 each)", s);
	*w = (int)a;
	*h = (int)b;
	return 0;
}

const char *cli_frame_path(const char *path, int frames, int i, char *buf, size_t n)
{
	if (!path || frames <= 1 || !strcmp(path, "-"))
		return path;
	const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
	if (!dot || (slash && dot < slash))
		dot = path + strlen(path);
	snprintf(buf, n, "%.*s-%04d%s", (int)(dot - path), path, i, dot);
	return buf;
}

void cli_output_key(const char *p, char *out, size_t n)
{
	char dirpart[4096], real[4096];
	const char *slash = strrchr(p, '/');
	snprintf(dirpart, sizeof dirpart, "%.*s", slash ? (int)(slash - p) + 1 : 1,
	         slash ? p : ".");
	if (!realpath(dirpart, real))
		snprintf(real, sizeof real, "%s", dirpart);
	snprintf(out, n, "%s/%s", real, slash ? slash + 1 : p);
}

int cli_check_frame_paths(const char *path, int frames, diag *d)
{
	char buf[4096];
	struct stat st;
	for (int i = 1; path && strcmp(path, "-") && i < frames; i++) {
		const char *p = cli_frame_path(path, frames, i, buf, sizeof buf);
		afile a;
		if (lstat(p, &st) != 0)
			continue; /* made by the write, in frame 0's folder */
		if (af_open(&a, p, "", 0))
			return af_diag(d, p);
		af_abort(&a);
	}
	return 0;
}

int cli_bad(const char *prog, const char *msg)
{
	fprintf(stderr, "%s: %s\n", prog, msg);
	return DIAG_EXIT;
}
