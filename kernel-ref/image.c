/*
 * image.c: image.h on the OpenImageIO plugin (image_plugin.h).
 *
 * Owns what is the same for every format: argument checks, the 8-bit
 * conversion of a float-only buffer, the temporary file and its rename, and
 * diagnostics. The plugin is found beside the running program (the build
 * folder), else in ../lib/saarsim/ from it (make install), else where
 * SAAR_IMAGE_PLUGIN points, and opened on the first image read or write.
 */
#include "kernel-ref/image.h"

#include <dlfcn.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/image_plugin.h"
#include "kernel-ref/infile.h"

/* Opens the plugin. RTLD_NODELETE keeps it mapped after dlclose, so the next
 * call's dlopen is a lookup, not a second 0.3 s load, and no handle has to
 * live in a global. Returns the handle and fills *p (and, when used is not
 * NULL, the plugin file's path), or NULL with d set. */
static void *plugin_open_at(const img_plugin **p, const char *file, char *used, size_t nused,
                            diag *d)
{
	char exe[PATH_MAX], path[2][PATH_MAX + 64], why[512] = "";
	int n = 0;
	const char *env = getenv("SAAR_IMAGE_PLUGIN");
	if (env && *env)
		snprintf(path[n++], sizeof path[0], "%s", env);
	else {
		ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
		if (len > 0) {
			exe[len] = '\0';
			char *slash = strrchr(exe, '/');
			if (slash)
				*slash = '\0';
			snprintf(path[n++], sizeof path[0], "%s/%s", exe, IMG_PLUGIN_FILE);
			snprintf(path[n++], sizeof path[0], "%s/../lib/saarsim/%s", exe,
			         IMG_PLUGIN_FILE);
		}
	}
	for (int i = 0; i < n; i++) {
		void *h = dlopen(path[i], RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
		if (!h) {
			if (!why[0] || access(path[i], F_OK) == 0)
				snprintf(why, sizeof why, "%s", dlerror());
			continue;
		}
		const img_plugin *(*entry)(void);
		*(void **)&entry = dlsym(h, IMG_PLUGIN_ENTRY);
		*p = entry ? entry() : NULL;
		if (*p && (*p)->abi == IMG_PLUGIN_ABI) {
			if (used)
				snprintf(used, nused, "%s", path[i]);
			return h;
		}
		snprintf(why, sizeof why, "%.400s: not a saarsim image plugin of ABI %d", path[i],
		         IMG_PLUGIN_ABI);
		dlclose(h);
	}
	if (!n)
		snprintf(why, sizeof why, "cannot find the running program's folder");
	diag_set(d, file, 0, 0, "image support (%s) not found: %s", IMG_PLUGIN_FILE, why);
	return NULL;
}

static void *plugin_open(const img_plugin **p, const char *file, diag *d)
{
	return plugin_open_at(p, file, NULL, 0, d);
}

int img_plugin_path(char *out, size_t n, diag *d)
{
	const img_plugin *p;
	void *lib = plugin_open_at(&p, "image support", out, n, d);
	if (!lib)
		return -1;
	dlclose(lib);
	return 0;
}

static const char *ext_of(const char *path, char *buf, size_t cap)
{
	const char *slash = strrchr(path, '/');
	const char *dot = strrchr(slash ? slash : path, '.');
	size_t i = 0;
	for (const char *s = dot ? dot + 1 : ""; *s && i + 1 < cap; s++)
		buf[i++] = (char)(*s >= 'A' && *s <= 'Z' ? *s - 'A' + 'a' : *s);
	buf[i] = '\0';
	return buf;
}

/* What one image file holds: RGB (8-bit and/or float pixels) or one
 * float channel (y non-NULL). */
typedef struct img_job {
	int w, h;
	const uint8_t *rgb8;
	const float *rgbf, *y;
} img_job;

/* Writes j to path through the plugin: a temporary beside it with the
 * same extension (the plugin picks the format by it), renamed into place
 * (now, or with group g). The one open-write-commit path both writers share. */
static int write_job(const char *path, const img_job *j, af_group *g, diag *d)
{
	const img_plugin *p;
	void *lib = plugin_open(&p, path, d);
	if (!lib)
		return -1;
	char ext[32], sfx[34], err[512] = "";
	ext_of(path, ext, sizeof ext);
	int rc = -1;
	afile a;
	snprintf(sfx, sizeof sfx, ".%s", ext);
	if (af_open(&a, path, sfx, 0)) {
		diag_set(d, path, 0, 0, "cannot write image: %s", strerror(errno));
		goto out;
	}
	/* the plugin reads the file back (a write cut short): libpng's
	 * default handler prints "libpng error: ..." itself */
	int quiet = diag_quiet_begin();
	int wr = j->y ? p->write_y32f(a.tmp, ext, j->w, j->h, j->y, err, sizeof err)
	              : p->write_rgb(a.tmp, ext, j->w, j->h, j->rgb8, j->rgbf, err, sizeof err);
	diag_quiet_end(quiet);
	if (wr != 0) {
		af_abort(&a);
		diag_set(d, path, 0, 0, "cannot write image: %s", err);
		goto out;
	}
	if (af_commit_to(&a, g)) {
		diag_set(d, path, 0, 0, "cannot write image: %s", strerror(errno));
		goto out;
	}
	rc = 0;
out:
	dlclose(lib);
	return rc;
}

int img_write(const char *path, int w, int h, const uint8_t *rgb8, const float *rgbf, af_group *g,
              diag *d)
{
	if (w <= 0 || h <= 0 || (!rgb8 && !rgbf))
		return diag_set(d, path, 0, 0, "cannot write a %dx%d image without pixels", w, h);
	uint8_t *conv = NULL;
	if (!rgb8) {
		/* only a float buffer, but the format may be 8-bit: clamp and
		 * quantise here */
		size_t n = (size_t)w * (size_t)h * 3;
		if (!(conv = malloc(n)))
			return diag_set(d, path, 0, 0, "cannot write image: out of memory");
		for (size_t i = 0; i < n; i++) {
			float v = rgbf[i];
			v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;
			conv[i] = (uint8_t)(v * 255.0f + 0.5f);
		}
		rgb8 = conv;
	}
	img_job j = {w, h, rgb8, rgbf, NULL};
	int rc = write_job(path, &j, g, d);
	free(conv);
	return rc;
}

int img_write_values(const char *path, int w, int h, const float *v, af_group *g, diag *d)
{
	if (w <= 0 || h <= 0 || !v)
		return diag_set(d, path, 0, 0, "cannot write a %dx%d image without pixels", w, h);
	img_job j = {w, h, NULL, NULL, v};
	return write_job(path, &j, g, d);
}

/* The formats the programs write (--out, --heatmap: their --help lists
 * them). Others OpenImageIO would write are refused before the run:
 * libjpeg's default error handler, which OpenImageIO's JPEG writer keeps,
 * ends the process with status 1 on a failed write. */
static int out_format(const char *path, diag *d)
{
	static const char *const ok[] = {"png", "exr", "ppm", "tif", "tiff"};
	char ext[32];
	ext_of(path, ext, sizeof ext);
	for (size_t i = 0; i < sizeof ok / sizeof *ok; i++)
		if (!strcmp(ext, ok[i]))
			return 0;
	if (!*ext)
		return diag_set(d, path, 0, 0,
		                "cannot write image: no extension to name its format (.png, .exr, "
		                ".ppm or .tif)");
	return diag_set(d, path, 0, 0,
	                "cannot write image: '.%s' is not a format written here (.png, .exr, "
	                ".ppm or .tif)",
	                ext);
}

int img_can_write(const char *path, diag *d)
{
	if (out_format(path, d))
		return -1;
	const img_plugin *p;
	void *lib = plugin_open(&p, path, d);
	if (!lib)
		return -1;
	char err[512] = "";
	int rc = p->can_write(path, err, sizeof err);
	if (rc != 0)
		diag_set(d, path, 0, 0, "cannot write image: %s", err);
	dlclose(lib);
	return rc ? -1 : 0;
}

/* A path naming a folder ("out/", or an existing folder) is refused as
 * such, before any other check. */
static int not_a_folder(const char *path, diag *d)
{
	size_t n = strlen(path);
	struct stat st;
	if ((n && path[n - 1] == '/') || (stat(path, &st) == 0 && S_ISDIR(st.st_mode)))
		return diag_set(d, path, 0, 0,
		                "cannot write image: it names a folder, not a file (give a name "
		                "such as %s%sframe.png)",
		                path, n && path[n - 1] == '/' ? "" : "/");
	return 0;
}

static int reserve_temp(const char *path, diag *d)
{
	char ext[32], sfx[34];
	snprintf(sfx, sizeof sfx, ".%s", ext_of(path, ext, sizeof ext));
	return af_reserve(path, sfx, d);
}

int img_reserve(const char *path, diag *d)
{
	if (not_a_folder(path, d) || img_can_write(path, d))
		return -1;
	return reserve_temp(path, d);
}

int img_reserve_file(const char *path, diag *d)
{
	return not_a_folder(path, d) || out_format(path, d) ? -1 : reserve_temp(path, d);
}

int img_read_rgba8(const char *path, int *w, int *h, uint8_t **rgba, diag *d)
{
	*rgba = NULL;
	const img_plugin *p;
	void *lib = plugin_open(&p, path, d);
	if (!lib)
		return -1;
	/* the plugin opens it by name: a FIFO would block it */
	int st = in_check(path);
	if (st) {
		dlclose(lib);
		return diag_set(d, path, 0, 0, "cannot read image: %s", in_strerror(st));
	}
	char err[512] = "";
	/* libpng's default handler prints "libpng error: ..." itself */
	int quiet = diag_quiet_begin();
	int rc = p->read_rgba8(path, w, h, rgba, err, sizeof err);
	diag_quiet_end(quiet);
	if (rc != 0)
		diag_set(d, path, 0, 0, "cannot read image: %s", err);
	dlclose(lib);
	return rc ? -1 : 0;
}
