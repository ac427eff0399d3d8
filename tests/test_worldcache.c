/*
 * test_worldcache.c: the world cache (--world-cache DIR, worldcache.h).
 * A cached world is the built one (same memory image, figures and default
 * light); a changed MTL or texture, other kd parameters, a damaged or
 * truncated file all miss and rebuild; a folder that cannot hold the cache
 * is bad input (exit 2, one line); saarsim's second run takes the world
 * and kernel-ref's frame from the cache and reports the same results.
 */
#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <time.h>

#include "kernel-ref/image.h"
#include "kernel-ref/image_plugin.h"
#include "kernel-ref/world.h"
#include "kernel-ref/worldcache.h"
#include "tests/testutil.h"

/* A textured quad: OBJ + MTL + a 2x2 PNG, in dir. */
static void write_scene(const char *dir, const char *kd, char *obj, size_t n)
{
	char p[512], text[512];
	uint8_t px[2 * 2 * 3] = {255, 0, 0, 0, 0, 255, 0, 0, 255, 255, 0, 0};
	diag d;
	snprintf(p, sizeof p, "%s/checker.png", dir);
	cr_assert_eq(img_write(p, 2, 2, px, NULL, NULL, &d), 0, "%s", d.msg);
	snprintf(text, sizeof text, "newmtl tex\nKd %s\nmap_Kd checker.png\n", kd);
	tu_write(p, sizeof p, dir, "quad.mtl", text);
	tu_write(obj, n, dir, "quad.obj",
	         "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
	         "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tex\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
}

/* Sets dir/name's modification time `ahead` seconds from now, so a
 * rewrite within the same clock tick still counts as a change. */
static void touch_ahead(const char *dir, const char *name, int ahead)
{
	char p[512];
	snprintf(p, sizeof p, "%s/%s", dir, name);
	struct timespec ts[2];
	clock_gettime(CLOCK_REALTIME, &ts[0]);
	ts[0].tv_sec += ahead;
	ts[1] = ts[0];
	cr_assert_eq(utimensat(AT_FDCWD, p, ts, 0), 0, "cannot touch %s", p);
}

/* A fresh folder dir holding the textured quad (path in obj) and the
 * name of a cache folder in it (not made yet). */
static void fresh_scene(char *dir, size_t ndir, char *cache, size_t ncache, char *obj, size_t nobj)
{
	tu_tmpdir(dir, ndir);
	snprintf(cache, ncache, "%s/cache", dir);
	write_scene(dir, "1 1 1", obj, nobj);
}

/* With eye_x > 0: a view's footprint (a packet 0.01 wide seen from
 * (eye_x, 0, 0)) instead of the fraction. */
static int load_view_fp(world *w, const char *obj, const char *cache, float footprint, float eye_x)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = obj;
	o.cache_dir = cache;
	o.kd.footprint = footprint;
	if (eye_x > 0) {
		o.kd.fp_angle = 0.01f;
		o.kd.fp_eye[0] = eye_x;
	}
	diag d;
	int rc = world_load(w, &o, &d);
	cr_assert_eq(rc, 0, "%s", d.msg);
	return w->cache;
}

static int load_fp(world *w, const char *obj, const char *cache, float empty_bonus, float footprint)
{
	world_opts o;
	world_opts_default(&o);
	o.scene = obj;
	o.cache_dir = cache;
	if (empty_bonus >= 0)
		o.kd.empty_bonus = empty_bonus;
	o.kd.footprint = footprint;
	diag d;
	int rc = world_load(w, &o, &d);
	cr_assert_eq(rc, 0, "%s", d.msg);
	return w->cache;
}

static int load(world *w, const char *obj, const char *cache, float empty_bonus)
{
	return load_fp(w, obj, cache, empty_bonus, 0);
}

/* The cached world w equals the built world b in everything used after
 * the build. */
static void same_world(const world *w, const world *b)
{
	cr_assert_eq(w->m.size, b->m.size);
	cr_assert_eq(memcmp(w->m.bytes, b->m.bytes, (size_t)b->m.size), 0, "memory images differ");
	cr_assert_eq(memcmp(w->m.base, b->m.base, sizeof b->m.base), 0);
	cr_assert_eq(w->m.ntris, b->m.ntris);
	cr_assert_eq(w->s.ntris, b->s.ntris);
	cr_assert_eq(w->kd.nnodes, b->kd.nnodes);
	cr_assert_eq(w->kd.nleaves, b->kd.nleaves);
	cr_assert_eq(w->kd.depth, b->kd.depth);
	cr_assert_eq(memcmp(&w->s.bounds, &b->s.bounds, sizeof b->s.bounds), 0);
	cr_assert_eq(memcmp(&w->v.lights[0], &b->v.lights[0], sizeof b->v.lights[0]), 0,
	             "the default light is placed the same");
	cr_assert_str_eq(w->scene_label, b->scene_label);
}

/* The one world-*.bin in dir, into out; returns how many there are. */
static int world_files(const char *dir, char *out, size_t n)
{
	return tu_find_files(dir, "world-", out, n);
}

Test(worldcache, hit_is_the_built_world)
{
	char dir[256], cache[300], obj[512];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	world b, w1, w2;
	cr_assert_eq(load(&b, obj, NULL, -1), WORLD_CACHE_OFF);
	cr_assert_eq(load(&w1, obj, cache, -1), WORLD_CACHE_STORED, "first run builds and stores");
	cr_assert_eq(load(&w2, obj, cache, -1), WORLD_CACHE_HIT);
	same_world(&w1, &b);
	same_world(&w2, &b);
	cr_assert_null(w2.kd.nodes, "a hit keeps figures only");
	world_free(&b);
	world_free(&w1);
	world_free(&w2);
}

/* w, just stored after a miss, is the world a build without the cache
 * makes, and the next load of obj is a hit; frees w. */
static void stored_is_built_then_hit(world *w, const char *obj, const char *cache)
{
	world b;
	load(&b, obj, NULL, -1);
	same_world(w, &b);
	world_free(&b);
	world_free(w);
	cr_assert_eq(load(w, obj, cache, -1), WORLD_CACHE_HIT);
	world_free(w);
}

Test(worldcache, changed_source_files_miss)
{
	char dir[256], cache[300], obj[512], p[512];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	world w;
	load(&w, obj, cache, -1);
	uint32_t white = wc_crc(w.m.bytes, w.m.size);
	world_free(&w);
	/* the MTL changes: a new diffuse colour, so a new memory image */
	tu_write(p, sizeof p, dir, "quad.mtl", "newmtl tex\nKd 0.5 0.25 1\nmap_Kd checker.png\n");
	touch_ahead(dir, "quad.mtl", 5);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED, "a changed MTL is a miss");
	cr_assert_neq(wc_crc(w.m.bytes, w.m.size), white);
	stored_is_built_then_hit(&w, obj, cache);
	/* the texture changes */
	uint8_t px[2 * 2 * 3] = {0};
	diag d;
	snprintf(p, sizeof p, "%s/checker.png", dir);
	cr_assert_eq(img_write(p, 2, 2, px, NULL, NULL, &d), 0, "%s", d.msg);
	touch_ahead(dir, "checker.png", 10);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED, "a changed texture is a miss");
	world_free(&w);
}

/* An MTL the OBJ names but that is missing when the world is built (the
 * import goes on with default materials) is watched for appearing: once
 * it is there, the cached world is not reused (a new memory image, the
 * one a build without the cache makes), and then that one is. Catches a
 * missing file left out of the watched files: the world of default
 * materials was reused after the MTL appeared, and the frame kept its
 * old colours while both checks, rendering from the same stale world,
 * said identical. */
Test(worldcache, a_missing_file_that_appears_misses)
{
	char dir[256], cache[300], obj[512], p[512], mtl[512];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	snprintf(mtl, sizeof mtl, "%s/quad.mtl", dir);
	snprintf(p, sizeof p, "%s/quad.mtl.away", dir);
	cr_assert_eq(rename(mtl, p), 0);
	world w;
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED, "stored without its MTL");
	uint32_t plain = wc_crc(w.m.bytes, w.m.size);
	world_free(&w);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_HIT, "still missing: a hit");
	world_free(&w);
	cr_assert_eq(rename(p, mtl), 0);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED, "the MTL appeared: a miss");
	cr_assert_neq(wc_crc(w.m.bytes, w.m.size), plain, "the MTL's colours are in the image");
	stored_is_built_then_hit(&w, obj, cache);
}

/* More names than the import's process can pass back (65536: here 9000
 * missing MTLs, each looked for under eight names) leave the world
 * unstored rather than unwatched. Catches the names past the limit
 * dropped in silence (the world stored, its file list short). */
Test(worldcache, names_past_the_limit_are_not_stored)
{
	char dir[256], cache[300], obj[512];
	tu_tmpdir(dir, sizeof dir);
	snprintf(cache, sizeof cache, "%s/cache", dir);
	size_t cap = 9000 * 24 + 64, n = 0;
	char *text = malloc(cap);
	cr_assert(text);
	for (int k = 0; k < 9000; k++)
		n += (size_t)snprintf(text + n, cap - n, "mtllib a%d.mtl\n", k);
	snprintf(text + n, cap - n, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
	tu_write(obj, sizeof obj, dir, "many.obj", text);
	free(text);
	world w;
	tu_capture capt = tu_stderr_begin();
	int st = load(&w, obj, cache, -1);
	const char *err = tu_stderr_end(capt);
	cr_assert_eq(st, WORLD_CACHE_UNSTORED, "stored with names unwatched");
	cr_assert(strstr(err, "a source file could not be recorded"), "%s", err);
	world_free(&w);
}

/* The reference frame's cached render carries its counts as well as its
 * image: a render with cone culling or by the interval walk counts other
 * work for the same image, so each has its own entry, and a plain render
 * keeps its key. Catches the key without them (a cached reference of
 * another walk handed its counts, and its time, to the check). */
Test(worldcache, reference_frames_of_other_walks_have_their_own_entries)
{
	char dir[256], cache[300], obj[512];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	world w;
	load(&w, obj, cache, -1);
	render_opts o;
	render_opts_default(&o);
	o.width = o.height = 16;
	o.threads = 1;
	uint8_t rgb[16 * 16 * 3];
	render_stats st;
	diag d;
	int cached;
	for (int k = 0; k < 3; k++) {
		o.cone_cull = k == 1;
		o.frustum = k == 2;
		for (int again = 0; again < 2; again++) {
			cr_assert_eq(world_reference_rgb8(&w, &o, rgb, &st, &cached, &d), 0, "%s",
			             d.msg);
			cr_assert_eq(cached, again, "walk %d, %s", k, again ? "again" : "first");
		}
	}
	world_free(&w);
}

/* The texels come through the image plugin, a file apart from the
 * program: a rebuilt plugin (here a copy whose time moves on) misses. */
Test(worldcache, rebuilt_image_plugin_misses)
{
	char dir[256], cache[300], obj[512], plug[PATH_MAX], copy[600], cmd[PATH_MAX + 700];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	diag d;
	cr_assert_eq(img_plugin_path(plug, sizeof plug, &d), 0, "%s", d.msg);
	snprintf(copy, sizeof copy, "%s/%s", dir, IMG_PLUGIN_FILE);
	snprintf(cmd, sizeof cmd, "cp '%s' '%s'", plug, copy);
	cr_assert_eq(tu_run(cmd), 0);
	setenv("SAAR_IMAGE_PLUGIN", copy, 1);
	world w;
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED);
	world_free(&w);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_HIT);
	world_free(&w);
	touch_ahead(dir, IMG_PLUGIN_FILE, 10);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED, "a rebuilt plugin is a miss");
	world_free(&w);
}

Test(worldcache, kd_parameters_have_their_own_entry)
{
	char dir[256], cache[300], obj[512], f[600];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	world w;
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED);
	world_free(&w);
	cr_assert_eq(load(&w, obj, cache, 0.5f), WORLD_CACHE_STORED);
	world_free(&w);
	cr_assert_eq(world_files(cache, f, sizeof f), 2);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_HIT);
	world_free(&w);
	cr_assert_eq(load(&w, obj, cache, 0.5f), WORLD_CACHE_HIT);
	world_free(&w);
	/* the packet footprint (rtref's tree against the chip's) too */
	cr_assert_eq(load_fp(&w, obj, cache, -1, KD_RTREF_FOOTPRINT), WORLD_CACHE_STORED);
	world_free(&w);
	cr_assert_eq(world_files(cache, f, sizeof f), 3);
	cr_assert_eq(load_fp(&w, obj, cache, -1, KD_RTREF_FOOTPRINT), WORLD_CACHE_HIT);
	world_free(&w);
	/* and a view's footprint by its eye (rtref's tree for another view) */
	cr_assert_eq(load_view_fp(&w, obj, cache, 0, 5), WORLD_CACHE_STORED);
	world_free(&w);
	cr_assert_eq(load_view_fp(&w, obj, cache, 0, 7), WORLD_CACHE_STORED);
	world_free(&w);
	cr_assert_eq(world_files(cache, f, sizeof f), 5);
	cr_assert_eq(load_view_fp(&w, obj, cache, 0, 5), WORLD_CACHE_HIT);
	world_free(&w);
}

Test(worldcache, damaged_or_truncated_file_misses)
{
	char dir[256], cache[300], obj[512], f[600];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	world b, w;
	load(&b, obj, cache, -1);
	cr_assert_eq(world_files(cache, f, sizeof f), 1);
	struct stat st;
	cr_assert_eq(stat(f, &st), 0);
	/* one bit flipped in the memory image */
	tu_flip_byte(f, (long)st.st_size - 64, 1);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED, "a damaged file is a miss");
	same_world(&w, &b);
	world_free(&w);
	cr_assert_eq(truncate(f, st.st_size - 9), 0);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED, "a truncated file is a miss");
	same_world(&w, &b);
	world_free(&w);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_HIT);
	world_free(&w);
	world_free(&b);
}

/* wc_get_mapped hands the tail where it lies in the file, 64-byte
 * aligned (a packet record is used in place); a flipped byte in the
 * head (here a part) or in the tail is a miss. */
Test(worldcache, mapped_tail_is_aligned_and_checked)
{
	char dir[256], f[600];
	tu_tmpdir(dir, sizeof dir);
	snprintf(f, sizeof f, "%s/obj.bin", dir);
	uint8_t part[13], tail[1000], got[13];
	for (size_t i = 0; i < sizeof tail; i++)
		tail[i] = (uint8_t)(i * 7 + 1);
	memset(part, 0x42, sizeof part);
	diag d;
	wc_part pp = {part, sizeof part}, gp = {got, sizeof got};
	cr_assert_eq(wc_put(f, "key", NULL, &pp, 1, tail, sizeof tail, &d), 0, "%s", d.msg);
	const void *t;
	size_t n;
	wc_map m;
	cr_assert_eq(wc_get_mapped(f, "key", &gp, 1, &t, &n, &m), 1);
	cr_assert_eq(n, sizeof tail);
	cr_assert_eq((uintptr_t)t % 64, 0, "the tail is 64-byte aligned");
	cr_assert_eq(memcmp(t, tail, n), 0);
	cr_assert_eq(memcmp(got, part, sizeof part), 0);
	wc_unmap(&m);
	cr_assert_null(m.base);
	cr_assert_eq(wc_get_mapped(f, "other key", &gp, 1, &t, &n, &m), 0);
	cr_assert_null(m.base, "a miss keeps nothing mapped");
	struct stat st;
	cr_assert_eq(stat(f, &st), 0);
	/* magic, key length and key, file count, then the part */
	long part_at = 8 + 4 + 3 + 4, tail_at = st.st_size - 16 - (long)sizeof tail;
	cr_assert_eq(tail_at, 64);
	tu_flip_byte(f, part_at + 4, 1);
	cr_assert_eq(wc_get_mapped(f, "key", &gp, 1, &t, &n, &m), 0, "a damaged head");
	for (size_t i = 0; i < sizeof got; i++)
		cr_assert_eq(got[i], 0, "a miss zeroes the parts");
	tu_flip_byte(f, part_at + 4, 1);
	cr_assert_eq(wc_get_mapped(f, "key", &gp, 1, &t, &n, &m), 1, "flipped back");
	wc_unmap(&m);
	tu_flip_byte(f, tail_at + 500, 0x10);
	cr_assert_eq(wc_get_mapped(f, "key", &gp, 1, &t, &n, &m), 0, "a damaged tail");
}

Test(worldcache, procedural_scene_keeps_its_view)
{
	char dir[256];
	tu_tmpdir(dir, sizeof dir);
	world_opts o;
	world_opts_default(&o);
	o.scene = "spd:tetra:3";
	o.cache_dir = dir;
	world a, b;
	diag d;
	cr_assert_eq(world_load(&a, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(world_load(&b, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(a.cache, WORLD_CACHE_STORED);
	cr_assert_eq(b.cache, WORLD_CACHE_HIT);
	cr_assert_eq(memcmp(&a.v.cam, &b.v.cam, sizeof a.v.cam), 0, "the scene's standard view");
	same_world(&b, &a);
	world_free(&a);
	world_free(&b);
}

/* ---- through saarsim ---- */

static char cdir[256];

static void setup(void)
{
	tu_tmpdir(cdir, sizeof cdir);
}

TestSuite(worldcache_cli, .init = setup);

Test(worldcache_cli, folder_that_cannot_hold_the_cache_is_bad_input)
{
	char p[512], args[1024];
	tu_write(p, sizeof p, cdir, "plain", "not a folder\n");
	snprintf(args, sizeof args, "--size 16x16 --world-cache %s --out %s/f.png", p, cdir);
	cr_assert_eq(tu_prog(cdir, "saarsim", args), 2);
	tu_one_line(cdir, "saarsim", p);
	cr_assert_not(tu_exists(cdir, "f.png"));
	snprintf(args, sizeof args, "--size 16x16 --world-cache %s/no/such/dir", cdir);
	cr_assert_eq(tu_prog(cdir, "saarsim", args), 2);
	tu_one_line(cdir, "saarsim", "cannot create");
}

/* The report's results: its text from "fps" up to "check", and from
 * "counters" up to "host" (not the config, the same by construction, the
 * check, whose "reference" differs, or host times). */
static char *results(const char *json)
{
	const char *a = strstr(json, "\"fps\""), *b = strstr(json, "\"check\"");
	const char *c = strstr(json, "\"counters\""), *e = strstr(json, "\"host\"");
	cr_assert(a && b && c && e && a < b && b < c && c < e);
	size_t n1 = (size_t)(b - a), n2 = (size_t)(e - c);
	char *r = malloc(n1 + n2 + 1);
	memcpy(r, a, n1);
	memcpy(r + n1, c, n2);
	r[n1 + n2] = 0;
	return r;
}

Test(worldcache_cli, second_run_takes_world_and_frame_from_the_cache)
{
	char args[1024];
	const char *run = "--scene spd:balls:2 --size 48x32 --set chip.rtps=2 --fidelity sampled "
	                  "--sample-rate 0.2";
	snprintf(args, sizeof args, "%s --out %s/a.ppm --report %s/a.json", run, cdir, cdir);
	cr_assert_eq(tu_prog(cdir, "saarsim", args), 0, "%s", tu_slurp(cdir, "err"));
	snprintf(args, sizeof args, "%s --world-cache %s/c --report %s/b.json", run, cdir, cdir);
	cr_assert_eq(tu_prog(cdir, "saarsim", args), 0, "%s", tu_slurp(cdir, "err"));
	cr_assert(strstr(tu_slurp(cdir, "out"), "world cache: stored"), "%s",
	          tu_slurp(cdir, "out"));
	snprintf(args, sizeof args, "%s --world-cache %s/c --out %s/c.ppm --report %s/c.json", run,
	         cdir, cdir, cdir);
	cr_assert_eq(tu_prog(cdir, "saarsim", args), 0, "%s", tu_slurp(cdir, "err"));
	char *out = tu_slurp(cdir, "out");
	cr_assert(strstr(out, "world cache: hit") && strstr(out, "its frame from the world cache"),
	          "%s", out);
	char *a = results(tu_slurp(cdir, "a.json")), *c = results(tu_slurp(cdir, "c.json"));
	cr_assert(strstr(tu_slurp(cdir, "a.json"), "\"reference\": \"rendered\""));
	char *cj = tu_slurp(cdir, "c.json");
	cr_assert(strstr(cj, "\"reference\": \"cached\"") &&
	          strstr(cj, "\"identical_8bit\": true"));
	cr_assert(strstr(cj, "\"world_cache\": \"hit\""));
	/* both references came from the cache (the single-ray frame has its own entry) */
	cr_assert(strstr(tu_squeeze_json(cj), "\"reference\":\"cached\",\"single_ray\":{"
	                                      "\"identical_8bit\":true,\"psnr\":null,"
	                                      "\"differing_pixels\":0,\"reference\":\"cached\"}"),
	          "%s", cj);
	cr_assert_str_eq(a, c, "results differ with the cache");
	free(a);
	free(c);
	char cmd[1024];
	snprintf(cmd, sizeof cmd, "cmp -s %s/a.ppm %s/c.ppm", cdir, cdir);
	cr_assert_eq(tu_run(cmd), 0, "the frames differ");
	/* another size: the world hits, the frame is rendered */
	snprintf(args, sizeof args,
	         "--scene spd:balls:2 --size 40x32 --set chip.rtps=2 --world-cache %s/c "
	         "--report %s/d.json",
	         cdir, cdir);
	cr_assert_eq(tu_prog(cdir, "saarsim", args), 0, "%s", tu_slurp(cdir, "err"));
	char *dj = tu_slurp(cdir, "d.json");
	cr_assert(strstr(dj, "\"world_cache\": \"hit\"") &&
	          strstr(dj, "\"reference\": \"rendered\""));
}

/* ---- the default folder (no --world-cache flag) and its cap ---- */

/* The folder comes from the flag, else SAARSIM_CACHE_DIR, else an
 * absolute XDG_CACHE_HOME plus /saarsim, else HOME plus /.cache/saarsim;
 * "off" (flag or variable) turns it off; empty variables count as unset.
 * Mistakes caught: the variables consulted in another order (XDG before
 * SAARSIM_CACHE_DIR, HOME before XDG), the flag losing to a variable, a
 * relative XDG_CACHE_HOME taken (the spec says ignore it), "off" taken
 * as a folder named off, an empty SAARSIM_CACHE_DIR taken as the current
 * folder. */
Test(worldcache, default_folder_follows_the_environment_in_order)
{
	char out[256];
	setenv("SAARSIM_CACHE_DIR", "/s", 1);
	setenv("XDG_CACHE_HOME", "/x", 1);
	setenv("HOME", "/h", 1);
	cr_assert_eq(wc_choose("/f", out, sizeof out), WC_FROM_FLAG);
	cr_assert_str_eq(out, "/f");
	cr_assert_eq(wc_choose(NULL, out, sizeof out), WC_FROM_ENV);
	cr_assert_str_eq(out, "/s");
	setenv("SAARSIM_CACHE_DIR", "", 1);
	cr_assert_eq(wc_choose(NULL, out, sizeof out), WC_FROM_XDG);
	cr_assert_str_eq(out, "/x/saarsim");
	setenv("XDG_CACHE_HOME", "relative", 1);
	cr_assert_eq(wc_choose(NULL, out, sizeof out), WC_FROM_HOME);
	cr_assert_str_eq(out, "/h/.cache/saarsim");
	unsetenv("XDG_CACHE_HOME");
	cr_assert_eq(wc_choose(NULL, out, sizeof out), WC_FROM_HOME);
	unsetenv("HOME");
	cr_assert_eq(wc_choose(NULL, out, sizeof out), WC_FROM_NONE);
	cr_assert_str_eq(out, "");
	setenv("SAARSIM_CACHE_DIR", "off", 1);
	setenv("HOME", "/h", 1);
	cr_assert_eq(wc_choose(NULL, out, sizeof out), WC_FROM_OFF);
	cr_assert_eq(wc_choose("off", out, sizeof out), WC_FROM_OFF);
	cr_assert_eq(wc_choose("/f", out, sizeof out), WC_FROM_FLAG, "the flag wins over off");
}

/* An entry of size bytes in dir, last used `age` seconds ago. */
static void aged_entry(const char *dir, const char *name, size_t size, int age)
{
	char p[512];
	snprintf(p, sizeof p, "%s/%s", dir, name);
	FILE *f = fopen(p, "wb");
	cr_assert(f);
	for (size_t i = 0; i < size; i++)
		fputc('x', f);
	fclose(f);
	touch_ahead(dir, name, -age);
}

/* A store that would pass the cap removes the least recently used
 * entries first, only as many as it must, and only the cache's own
 * (KIND-HASH.bin); an entry larger than the cap is refused. Mistakes
 * caught: evicting the newest first (the entry just used goes), evicting
 * everything, removing files that are not entries, no cap at all. */
Test(worldcache, cap_evicts_least_recently_used_first)
{
	char dir[64];
	tu_tmpdir(dir, sizeof dir);
	aged_entry(dir, "world-00000000000000a1.bin", 400, 300);  /* oldest */
	aged_entry(dir, "frame-00000000000000a2.bin", 400, 200);  /* next */
	aged_entry(dir, "packets-00000000000000a3.bin", 400, 10); /* recent */
	aged_entry(dir, "notes.txt", 4000, 1000);                 /* not ours */
	/* 1200 bytes held, cap 1600: 600 more need 200 freed: one entry */
	cr_assert_eq(wc_make_room(dir, 600, 1600), 0);
	cr_assert_not(tu_exists(dir, "world-00000000000000a1.bin"), "the oldest stayed");
	cr_assert(tu_exists(dir, "frame-00000000000000a2.bin"), "more was evicted than needed");
	cr_assert(tu_exists(dir, "packets-00000000000000a3.bin"), "the recent one went");
	cr_assert(tu_exists(dir, "notes.txt"), "a file that is no entry went");
	cr_assert_eq(wc_make_room(dir, 2000, 1600), -1, "an entry above the cap was accepted");
	cr_assert_eq(wc_make_room(dir, 1 << 30, 0), 0, "cap 0 is no cap");
	cr_assert(tu_exists(dir, "frame-00000000000000a2.bin"));
}

/* A hit marks its entry used, so the cap keeps what runs read. Mistake
 * caught: a hit not touching its file (a world read at every run, stored
 * long ago, is evicted first). */
Test(worldcache, hit_marks_the_entry_used)
{
	char dir[256], cache[300], obj[512], p[700];
	fresh_scene(dir, sizeof dir, cache, sizeof cache, obj, sizeof obj);
	world w;
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_STORED);
	world_free(&w);
	cr_assert_eq(tu_find_files(cache, "world-", p, sizeof p), 1);
	const char *name = strrchr(p, '/') + 1;
	touch_ahead(cache, name, -1000);
	struct stat a, b;
	cr_assert_eq(stat(p, &a), 0);
	cr_assert_eq(load(&w, obj, cache, -1), WORLD_CACHE_HIT);
	world_free(&w);
	cr_assert_eq(stat(p, &b), 0);
	cr_assert_gt(b.st_mtime, a.st_mtime + 500, "the hit left the entry's time as it was");
}

/* Without the flag a run caches in the default folder (here HOME's, the
 * variables before it empty); SAARSIM_CACHE_DIR=off and --world-cache off
 * write nothing; the report names the folder and says it was the
 * default. saarsim and rtref alike (world_opts). Mistakes caught: the
 * default not applied (nothing under HOME), off ignored (a folder made
 * anyway, or one named "off"), the report not saying where. */
Test(worldcache_cli, default_folder_is_used_and_off_turns_it_off)
{
	char env[1024], args[1024], dir[512];
	const char *home_env = "SAARSIM_CACHE_DIR= XDG_CACHE_HOME=";
	snprintf(env, sizeof env, "%s HOME=%s/h", home_env, cdir);
	snprintf(args, sizeof args, "--scene spd:tetra:1 --size 16x16 --report %s/r.json", cdir);
	cr_assert_eq(tu_run_env(env, cdir, "saarsim", args), 0, "%s", tu_slurp(cdir, "err"));
	snprintf(dir, sizeof dir, "%s/h/.cache/saarsim", cdir);
	char p[1200];
	cr_assert_eq(tu_find_files(dir, "world-", p, sizeof p), 1, "nothing in the default folder");
	char *r = tu_squeeze_json(tu_slurp(cdir, "r.json"));
	char want[1200];
	snprintf(want, sizeof want, "\"world_cache_dir\":\"%s\"", dir);
	cr_assert(strstr(r, want) && strstr(r, "\"world_cache_default\":true") &&
	              strstr(r, "\"world_cache_from\":\"HOME\"") &&
	              strstr(r, "\"world_cache\":\"stored\""),
	          "%s", r);
	snprintf(args, sizeof args, "--scene spd:tetra:1 --size 16x16 --stats %s/s.json", cdir);
	cr_assert_eq(tu_run_env(env, cdir, "rtref", args), 0, "%s", tu_slurp(cdir, "err"));
	r = tu_squeeze_json(tu_slurp(cdir, "s.json"));
	/* rtref's own entry (a key names its program) beside saarsim's */
	cr_assert(strstr(r, want) && strstr(r, "\"world_cache\":\"stored\""), "rtref: %s", r);
	cr_assert_eq(tu_find_files(dir, "world-", p, sizeof p), 2, "rtref stored elsewhere");

	/* off, by the variable and by the flag: nothing made */
	snprintf(env, sizeof env, "SAARSIM_CACHE_DIR=off HOME=%s/h2", cdir);
	snprintf(args, sizeof args, "--scene spd:tetra:1 --size 16x16 --report %s/o.json", cdir);
	cr_assert_eq(tu_run_env(env, cdir, "saarsim", args), 0);
	cr_assert_not(tu_exists(cdir, "h2"), "SAARSIM_CACHE_DIR=off made a folder");
	snprintf(env, sizeof env, "%s HOME=%s/h3", home_env, cdir);
	snprintf(args, sizeof args,
	         "--scene spd:tetra:1 --size 16x16 --world-cache off --report %s/o.json", cdir);
	cr_assert_eq(tu_run_env(env, cdir, "saarsim", args), 0);
	cr_assert_not(tu_exists(cdir, "h3"), "--world-cache off made the default folder");
	r = tu_squeeze_json(tu_slurp(cdir, "o.json"));
	cr_assert(strstr(r, "\"world_cache\":\"off\"") && strstr(r, "\"world_cache_dir\":null"),
	          "%s", r);
}

/* A default folder that cannot be made is no error: the run completes
 * without a cache and the report (and one warning line) says why; the
 * same folder named by --world-cache stays bad input (exit 2, one line).
 * Mistakes caught: the default's failure stopping the run (a read-only
 * or absent home would break every run), an explicit folder's failure
 * passed over silently. */
Test(worldcache_cli, unusable_default_folder_is_no_error_but_explicit_one_is)
{
	char env[1024], args[1024], p[512];
	tu_write(p, sizeof p, cdir, "plain", "not a folder\n");
	/* HOME is a file: HOME/.cache cannot be made */
	snprintf(env, sizeof env, "SAARSIM_CACHE_DIR= XDG_CACHE_HOME= HOME=%s", p);
	snprintf(args, sizeof args,
	         "--scene spd:tetra:1 --size 16x16 --report %s/r.json --out %s/f.ppm", cdir, cdir);
	cr_assert_eq(tu_run_env(env, cdir, "saarsim", args), 0, "%s", tu_slurp(cdir, "err"));
	cr_assert(tu_exists(cdir, "f.ppm"));
	const char *err = tu_slurp(cdir, "err");
	cr_assert(!strncmp(err, "warning: world cache off: ", 26) && strchr(err, '\n')[1] == 0,
	          "not one warning line: %s", err);
	char *r = tu_squeeze_json(tu_slurp(cdir, "r.json"));
	cr_assert(strstr(r, "\"world_cache\":\"off\"") &&
	              strstr(r, "\"world_cache_from\":\"HOME\"") &&
	              strstr(r, "cannot create the folder"),
	          "%s", r);
	snprintf(args, sizeof args, "--scene spd:tetra:1 --size 16x16 --world-cache %s/.cache/x",
	         p);
	cr_assert_eq(tu_prog(cdir, "saarsim", args), 2);
	tu_one_line(cdir, "saarsim", "cannot create");
	cr_assert_eq(tu_prog(cdir, "rtref", args), 2);
	tu_one_line(cdir, "rtref", "cannot create");
}
