/*
 * world.h: everything a frame needs before tracing starts, built the same
 * way for rtref and saarsim: the scene (file, embedded default), the view
 * (views file, flags or the default), the kd-tree and the memory image,
 * through the world cache when one is given (worldcache.h), and kernel-ref's
 * reference frame of it for checks. Also parses the command-line flags that pick them, so both
 * programs accept exactly the same scene/view/camera flags.
 */
#ifndef SAAR_KREF_WORLD_H
#define SAAR_KREF_WORLD_H

#include "kernel-ref/diag.h"
#include "kernel-ref/grid.h"
#include "kernel-ref/jsonw.h"
#include "kernel-ref/kdtree.h"
#include "kernel-ref/memimage.h"
#include "kernel-ref/render.h"
#include "kernel-ref/scene.h"
#include "kernel-ref/view.h"
#include "kernel-ref/worldcache.h"

typedef struct world_opts {
	const char *scene; /* path, or NULL: from the view, else embedded default */
	const char *views; /* views file */
	const char *view;  /* view name in it */
	int have_eye, have_lookat, have_up, have_fov;
	camera cam;  /* flags override the view's camera */
	int nlights; /* --light flags (replace the view's lights) */
	light lights[VIEW_MAX_LIGHTS];
	int no_lights;     /* --no-lights */
	drt_params drt;    /* --spp --aperture --focus --light-size --gloss --motion */
	unsigned have_drt; /* which of them were given (bit i: the i-th flag) */
	/* which of them came from saarsim's drt.* config keys instead (a
	 * problem is then named by the key, drt.<name>, not the flag) */
	unsigned drt_from_config;
	kd_params kd;
	/* rtref's own tree (view_kd in world.c): with fp_packet > 0 the
	 * footprint of kd is a packet fp_packet pixels wide on an image
	 * fp_height pixels high, seen from the view's eye at the scene's
	 * centre, when the view is known before the scene loads (a views
	 * file, or the embedded scene's default view); kd.footprint else.
	 * kd_footprint_given: --kd-footprint was given (rtref then takes it) */
	int fp_packet, fp_height, kd_footprint_given;
	/* --world-cache DIR (or "off"), or NULL: the default folder, from the
	 * environment (wc_choose in worldcache.h) */
	const char *cache_dir;
	long cache_max_mb; /* --world-cache-max MB (0: no cap), or -1: wc_cap's default */
	/* AFF scenes (aff.h): --anim-time T (default 0) and --anim-fps F;
	 * frame i of a multi-frame run is at anim_time + i / anim_fps */
	int have_anim_time, have_anim_fps;
	double anim_time, anim_fps;
	int two_level; /* --two-level: trace through twolevel.h's trees (AFF, kernel-ref) */
	/* --accel kd|grid: the acceleration structure rtref traces (WORLD_ACCEL_*);
	 * grid: a uniform grid (grid.h) rebuilt with every world, parameters gp
	 * (--grid-lambda, --grid-macro, --grid-packet, --grid-mailbox) */
	int accel;
	grid_params gp;
	const char *grid_flag; /* the last --grid-* flag given, or NULL (world_opts_check) */
	uint64_t given;        /* world_parse_arg's flags of one value seen so far (a bit each) */
} world_opts;

enum { WORLD_ACCEL_KD, WORLD_ACCEL_GRID };

/* What the world cache did for this world (host.world_cache). */
enum { WORLD_CACHE_OFF, WORLD_CACHE_HIT, WORLD_CACHE_STORED, WORLD_CACHE_UNSTORED };
const char *world_cache_name(int status);

typedef struct world {
	scene s;
	view v;
	kdtree kd;
	mimg m;
	char scene_label[1024]; /* what the reports call the scene */
	int view_changed;       /* camera or light flags changed the view (reports describe it) */
	double load_ms, kd_ms, image_ms;
	/* WORLD_CACHE_*. On a hit, s and kd hold their figures only (counts,
	 * bounds; the arrays are NULL: nothing after the build reads them)
	 * and m is whole. */
	int cache;
	/* The world cache's folder in use (cache_path), or NULL: none (off,
	 * or a default folder that could not be made or written: cache_note
	 * says why). cache_from: WC_FROM_* (where the folder's name came
	 * from); cache_cap: the cap on its entries in bytes (0: none). */
	const char *cache_dir;
	char cache_path[4096];
	int cache_from;
	uint64_t cache_cap;
	char cache_note[sizeof(diag)];
	uint32_t
	    image_crc; /* with a cache: CRC-32 of m's bytes (frame keys name the image by it) */
	char cache_prog[64]; /* this program's identity in cache keys */
	/* An AFF scene: the file as read (kept for other times) and the time
	 * s is flattened at; NULL for every other scene. */
	struct aff_scene *aff;
	double anim_time;
	/* With --two-level: the objects' trees (built once) and the instances
	 * at anim_time; the render_opts.tracer for the frame is tl->tracer,
	 * and kd is then a depth-1 tree (m serves only for shading; s is then
	 * in the instances' own frames, aff_flatten_local, and s, kd and m
	 * stay the same at every time). */
	struct tl_scene *tl;
	/* With --accel grid: the grid over m, rebuilt with it (the frame's
	 * render_opts.tracer is grid->tracer); grid->build_ms its build. */
	struct grid *grid;
} world;

void world_opts_default(world_opts *o);

/* If argv[*i] is a scene/view/camera/kd flag, consumes it (and its value),
 * advances *i and returns 1; returns 0 if it is not one of ours; -1 with
 * diag on a bad value. Flags: --scene P, --views F, --view N, --eye x,y,z,
 * --lookat x,y,z, --up x,y,z, --fov deg, --light x,y,z (repeatable),
 * --no-lights, --spp n, --aperture f, --focus f, --light-size f, --gloss f,
 * --motion x,y,z (override the view's drt), --kd-cost-trav f, --kd-cost-isect f, --kd-max-depth n,
 * --kd-leaf-size n, --kd-empty-bonus f, --kd-footprint f, --world-cache DIR|off,
 * --world-cache-max MB. */
int world_parse_arg(world_opts *o, int argc, char **argv, int *i, diag *d);

/* The world flags that contradict each other once every flag is parsed
 * (and, for saarsim, the config read: chip.accel grid is --accel grid): a
 * --grid-* flag without the grid. -1 with d set ("--grid-packet: ..."). The
 * parser itself refuses --no-lights with --light. */
int world_opts_check(const world_opts *o, diag *d);

/* rtref's own tree (kernel-ref.md, "rtref's own tree"), after the flags
 * are parsed: unless --kd-footprint named a footprint, the footprint of
 * rtref's primary packet (TILE_W pixels on an image height pixels high)
 * where the view is known before the scene loads, KD_RTREF_FOOTPRINT
 * where it is not. rtref and the Embree harness (scripts/embree_bench.c)
 * call it, so that both trace the same tree. */
void world_opts_packet_tree(world_opts *o, int height);

/* Usage lines for those flags. */
extern const char world_usage[];

/* Command-line helpers shared by rtref and saarsim. Errors go through d
 * ("FLAG: message"); cli_bad prints "prog: msg" as the one stderr line and
 * returns DIAG_EXIT for main to return. */
int cli_parse_int(const char *flag, const char *s, long lo, long hi, long *out, diag *d);
/* "WxH", each 1..16384, digits only: no blank, sign or other byte (flag
 * --size in messages). */
int cli_parse_size(const char *s, int *w, int *h, diag *d);
int cli_bad(const char *prog, const char *msg);
/* The output of frame i of an animation of `frames` frames: path itself
 * for one frame (or "-"), else path with "-NNNN" (i, four digits or more)
 * before its extension ("out.png" -> "out-0003.png"); buf holds it. */
const char *cli_frame_path(const char *path, int frames, int i, char *buf, size_t n);
/* Frames 1 .. frames - 1 of an animation's numbered output (frame 0 the
 * caller reserves, which checks the folder all of them share): each path
 * that exists already must be writable as atomicfile.h writes (not a
 * folder, device or FIFO), so a frame's output fails before any frame runs
 * instead of after the frames before it. -1 with d set (af_diag's line). */
int cli_check_frame_paths(const char *path, int frames, diag *d);
/* Output path p as the file it names, into out: its folder's real path
 * and its last name (the file need not exist yet), so two spellings of
 * one file ("a.csv", "./a.csv", a link to the folder) compare equal. */
void cli_output_key(const char *p, char *out, size_t n);

/* The checks world_load makes that need no scene: --view with --views,
 * --anim-time, --anim-fps and --two-level on an AFF scene (by its name),
 * and the camera and drt flags over the view where it is known before
 * the scene loads (a views file's, read here, or the embedded scene's
 * default), else what the flags decide alone. saarsim --dry-run. 0, or
 * -1 with d set, as world_load's message. */
int world_check(const world_opts *o, diag *d);
int world_load(world *w, const world_opts *o, diag *d);

/* An AFF world moved to time t: the scene flattened again at t, the view
 * (the file's camera at t, unless a views file gave one; camera and
 * light flags applied again), the kd-tree and the memory image rebuilt.
 * -1 with d when w is not an AFF world or a step fails. */
int world_set_time(world *w, const world_opts *o, double t, diag *d);

/* The time of frame i: o->anim_time + i / o->anim_fps (anim_time alone
 * without --anim-fps). */
double world_frame_time(const world_opts *o, int i);

/* kernel-ref's frame of w's view with options o as 8-bit sRGB (width x
 * height x 3 bytes into rgb) and its counts into st: from the world cache
 * when w has one and it holds this frame (*cached = 1), else rendered
 * (and stored there; a failed store is a warning). */
/* wc_put into w's cache folder after making room under its cap
 * (wc_make_room); -1 with diag when the entry alone passes the cap or the
 * store fails. */
int world_cache_put(const world *w, const char *file, const char *key, const wc_files *f,
                    const wc_part *parts, int nparts, const void *tail, size_t ntail, diag *d);

/* Whether the world's cache folder was chosen by default (no
 * --world-cache flag: SAARSIM_CACHE_DIR, XDG_CACHE_HOME or HOME). */
int world_cache_is_default(const world *w);

/* The report's keys on the world cache's folder (host.world_cache_*):
 * dir (the folder in use, else null), default (chosen without the flag),
 * from (wc_from_name), max_mb (its cap; 0: none) and note (why a
 * default folder is not in use; "" when it is). */
void world_cache_json(jsonw *j, const world *w);

int world_reference_rgb8(const world *w, const render_opts *o, uint8_t *rgb, render_stats *st,
                         int *cached, diag *d);
void world_free(world *w);

#endif
