/*
 * testutil.h: helpers shared by the Criterion tests.
 *
 * The shared benchmark scenes live outside the repository; tests that need
 * them call SCENE_OR_SKIP, which skips with a clear message when absent.
 * `make test` sets SAAR_SCENES (default ../shared/scenes) and SAAR_BIN (the
 * build folder with the programs).
 */
#ifndef SAAR_TESTS_TESTUTIL_H
#define SAAR_TESTS_TESTUTIL_H

#include <criterion/criterion.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "kernel-ref/image.h"
#include "kernel-ref/world.h"

/* 1 in a sanitizer build (make SANITIZE=1, which compiles the tests with
 * -fsanitize=address too): there a sanitizer's own report may come before
 * a program's one line. */
#ifdef __SANITIZE_ADDRESS__
#define TU_SANITIZE 1
#else
#define TU_SANITIZE 0
#endif

static inline const char *tu_scenes_dir(void)
{
	const char *d = getenv("SAAR_SCENES");
	return d && *d ? d : "../shared/scenes";
}

static inline const char *tu_bin_dir(void)
{
	const char *d = getenv("SAAR_BIN");
	return d && *d ? d : "build";
}

/* Fills buf with SAAR_SCENES/rel; skips the test when the file is absent. */
#define SCENE_OR_SKIP(buf, rel)                                                                    \
	do {                                                                                       \
		snprintf((buf), sizeof(buf), "%s/%s", tu_scenes_dir(), (rel));                     \
		if (access((buf), R_OK) != 0)                                                      \
			cr_skip_test("shared scene %s absent; skipping", (buf));                   \
	} while (0)

/* A world around the finished scene s (w takes it over): the kd-tree with
 * default parameters and the memory image, for tests that build scenes. */
static inline void tu_build_world(world *w, const scene *s)
{
	diag d;
	memset(w, 0, sizeof *w);
	w->s = *s;
	kd_params kp;
	kd_params_default(&kp);
	cr_assert_eq(kd_build(&w->kd, &w->s, &kp, &d), 0, "%s", d.msg);
	cr_assert_eq(mimg_build(&w->m, &w->s, &w->kd, &d), 0, "%s", d.msg);
}

/* A fresh temporary directory for a test's files (not removed: /tmp). */
/* A fresh folder for one test, inside the run's folder (tests/main.c makes
 * it, names it in SAARSIM_TEST_TMP and removes it after the run), else in
 * /tmp. */
static inline void tu_tmpdir(char *buf, size_t n)
{
	const char *run = getenv("SAARSIM_TEST_TMP");
	snprintf(buf, n, "%s/t-XXXXXX", run && *run ? run : "/tmp");
	if (!mkdtemp(buf))
		cr_assert_fail("mkdtemp failed");
}

/* Writes text to dir/name, returns the path in out. */
static inline void tu_write(char *out, size_t n, const char *dir, const char *name,
                            const char *text)
{
	snprintf(out, n, "%s/%s", dir, name);
	FILE *f = fopen(out, "w");
	cr_assert(f, "cannot write %s", out);
	fputs(text, f);
	fclose(f);
}

/* A malloc'd string: head, then unit n times, then tail (big generated
 * inputs: deep nesting, long lists). */
static inline char *tu_repeat(const char *head, const char *unit, size_t n, const char *tail)
{
	size_t h = strlen(head), u = strlen(unit), t = strlen(tail);
	char *s = malloc(h + u * n + t + 1);
	cr_assert(s, "out of memory");
	memcpy(s, head, h);
	for (size_t i = 0; i < n; i++)
		memcpy(s + h + u * i, unit, u);
	memcpy(s + h + u * n, tail, t + 1);
	return s;
}

/* The files in dir whose names start with prefix (a world cache's
 * "world-", "packets-"): how many there are, the last one's path in out. */
static inline int tu_find_files(const char *dir, const char *prefix, char *out, size_t n)
{
	DIR *dp = opendir(dir);
	cr_assert(dp, "cannot list %s", dir);
	int k = 0;
	struct dirent *e;
	while ((e = readdir(dp)))
		if (!strncmp(e->d_name, prefix, strlen(prefix))) {
			snprintf(out, n, "%s/%s", dir, e->d_name);
			k++;
		}
	closedir(dp);
	return k;
}

/* Damages file path in place: the byte at offset off gets mask xor'ed in. */
static inline void tu_flip_byte(const char *path, long off, int mask)
{
	FILE *f = fopen(path, "r+b");
	cr_assert(f, "cannot open %s", path);
	cr_assert_eq(fseek(f, off, SEEK_SET), 0);
	int ch = fgetc(f);
	cr_assert_neq(ch, EOF, "%s has no byte %ld", path, off);
	cr_assert_eq(fseek(f, off, SEEK_SET), 0);
	fputc(ch ^ mask, f);
	fclose(f);
}

/* Runs a shell command, returns its exit status (-1 if it did not exit). */
static inline int tu_run(const char *cmd)
{
	int st = system(cmd);
	if (st == -1 || !WIFEXITED(st))
		return -1;
	return WEXITSTATUS(st);
}

/* Captures what the test itself writes to stderr (a library's warning
 * line), so it is checked instead of landing in `make test`'s output:
 * tu_stderr_begin returns a token for tu_stderr_end, which restores stderr
 * and returns the text written meanwhile (static, up to 64 KB). */
typedef struct tu_capture {
	int saved;
	FILE *f;
} tu_capture;

static inline tu_capture tu_stderr_begin(void)
{
	tu_capture c;
	fflush(stderr);
	c.f = tmpfile();
	cr_assert(c.f, "tmpfile failed");
	c.saved = dup(2);
	dup2(fileno(c.f), 2);
	return c;
}

static inline const char *tu_stderr_end(tu_capture c)
{
	static char buf[1 << 16];
	fflush(stderr);
	dup2(c.saved, 2);
	close(c.saved);
	rewind(c.f);
	size_t n = fread(buf, 1, sizeof buf - 1, c.f);
	buf[n] = 0;
	fclose(c.f);
	return buf;
}

/* ---- command-line programs (rtref, saarsim, saarsim-replay) ---- */

/* A report checks itself (sim/reportcheck.h): saarsim prints one
 * "warning: report invariant failed: ..." line per violated invariant.
 * Fails the test when the file at path (a run's stderr) holds one; a
 * missing file holds none. Reads the file itself, so the callers' tu_slurp
 * buffers stay as they were. */
static inline void tu_no_invariant_failures(const char *path)
{
	FILE *f = fopen(path, "r");
	if (!f)
		return;
	char line[1024];
	while (fgets(line, sizeof line, f))
		if (strstr(line, "report invariant failed")) {
			fclose(f);
			cr_assert_fail("%s: %s", path, line);
		}
	fclose(f);
}

/* Runs SAAR_BIN/prog with args; stdout into dir/out, stderr into dir/err.
 * Returns the exit status. A run that reported a failed invariant fails
 * the test. */
static inline int tu_prog(const char *dir, const char *prog, const char *args)
{
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s/%s %s >%s/out 2>%s/err", tu_bin_dir(), prog, args, dir, dir);
	int rc = tu_run(cmd);
	snprintf(cmd, sizeof cmd, "%s/err", dir);
	tu_no_invariant_failures(cmd);
	return rc;
}

/* tu_prog with an environment assignment ("NAME=value") before it. */
static inline int tu_run_env(const char *env, const char *dir, const char *prog, const char *args)
{
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s %s/%s %s >%s/out 2>%s/err", env, tu_bin_dir(), prog, args,
	         dir, dir);
	int rc = tu_run(cmd);
	snprintf(cmd, sizeof cmd, "%s/err", dir);
	tu_no_invariant_failures(cmd);
	return rc;
}

static inline int tu_exists(const char *dir, const char *name)
{
	char p[1024];
	snprintf(p, sizeof p, "%s/%s", dir, name);
	struct stat sb;
	return stat(p, &sb) == 0;
}

/* Files in dir named name.<anything>: the temporaries an atomic write of
 * name leaves if it fails to clean up (kernel-ref/atomicfile.h names them
 * name.XXXXXX, plus an image's extension). */
static inline int tu_temps(const char *dir, const char *name)
{
	DIR *dp = opendir(dir);
	int n = 0;
	size_t k = strlen(name);
	for (struct dirent *e; dp && (e = readdir(dp));)
		n += strncmp(e->d_name, name, k) == 0 && e->d_name[k] == '.';
	if (dp)
		closedir(dp);
	return n;
}

/* dir/name's text (up to 1 MB) in one of two static buffers, so two files
 * can be held at once. */
static inline char *tu_slurp(const char *dir, const char *name)
{
	char p[1024];
	snprintf(p, sizeof p, "%s/%s", dir, name);
	FILE *f = fopen(p, "r");
	cr_assert(f, "cannot read %s", p);
	static char bufs[2][1 << 20];
	static int which;
	char *buf = bufs[which ^= 1];
	size_t n = fread(buf, 1, sizeof bufs[0] - 1, f);
	buf[n] = 0;
	fclose(f);
	return buf;
}

/* Writes a 64x64 image of noise (no format shrinks it to a few bytes) at
 * path, in the format its extension names, and cuts the file to half its
 * size: a damaged image for the readers to refuse. */
static inline void tu_write_cut_image(const char *path)
{
	enum { W = 64, H = 64 };
	static uint8_t px[W * H * 3];
	for (int i = 0; i < (int)sizeof px; i++)
		px[i] = (uint8_t)((i * 2654435761u) >> 24);
	diag d = {{0}};
	cr_assert_eq(img_write(path, W, H, px, NULL, NULL, &d), 0, "%s", d.msg);
	struct stat st;
	cr_assert_eq(stat(path, &st), 0);
	cr_assert_eq(truncate(path, st.st_size / 2), 0, "cannot cut %s", path);
}

/* Removes the whitespace outside strings from JSON text s, in place, so a
 * test can look for a compact fragment ("key":[1.0,2.0]) whatever the
 * writer's layout. Returns s. */
static inline char *tu_squeeze_json(char *s)
{
	char *o = s;
	int in = 0;
	for (const char *p = s; *p; p++) {
		if (in && *p == '\\' && p[1]) {
			*o++ = *p++;
			*o++ = *p;
			continue;
		}
		if (*p == '"')
			in = !in;
		if (in || !strchr(" \t\r\n", *p))
			*o++ = *p;
	}
	*o = 0;
	return s;
}

/* The number i (from 0) after "key": in JSON text s (its first
 * occurrence): the value itself when it is a number (i = 0), else the
 * i-th element of the array it opens. */
static inline double tu_json_nth(const char *s, const char *key, int i)
{
	char k[128];
	snprintf(k, sizeof k, "\"%s\":", key);
	const char *p = strstr(s, k);
	cr_assert(p, "no %s in the report", key);
	p += strlen(k);
	while (strchr(" \t\r\n[", *p) && *p)
		p++;
	for (int j = 0; j < i; j++) {
		char *e;
		strtod(p, &e);
		cr_assert(e != p, "%s: fewer than %d numbers", key, i + 1);
		for (p = e; *p && strchr(" \t\r\n,", *p); p++)
			;
	}
	char *e;
	double v = strtod(p, &e);
	cr_assert(e != p, "%s: no number at %d", key, i);
	return v;
}

/* The number after "key": in JSON text s (the first occurrence). */
static inline double tu_json_num(const char *s, const char *key)
{
	return tu_json_nth(s, key, 0);
}

/* dir/err must be exactly one line "prog: ..." containing what. */
static inline void tu_one_line(const char *dir, const char *prog, const char *what)
{
	char *buf = tu_slurp(dir, "err");
	cr_assert(*buf, "nothing on stderr");
	char *nl = strchr(buf, '\n');
	cr_assert(nl && nl[1] == 0, "stderr is not one line: %s", buf);
	size_t n = strlen(prog);
	cr_assert(!strncmp(buf, prog, n) && buf[n] == ':' && buf[n + 1] == ' ',
	          "stderr does not start with '%s: ': %s", prog, buf);
	cr_assert(strstr(buf, what), "stderr does not name '%s': %s", what, buf);
}

/* Writes len bytes to dir/name (NULs and all), returns the path in out. */
static inline void tu_write_bytes(char *out, size_t n, const char *dir, const char *name,
                                  const void *bytes, size_t len)
{
	snprintf(out, n, "%s/%s", dir, name);
	FILE *f = fopen(out, "wb");
	cr_assert(f, "cannot write %s", out);
	cr_assert_eq(fwrite(bytes, 1, len, f), len);
	fclose(f);
}

/* n bytes of noise from seed (the same every run): "random bytes". */
static inline void tu_noise(unsigned char *buf, size_t n, unsigned seed)
{
	unsigned x = seed * 2654435761u + 1;
	for (size_t i = 0; i < n; i++) {
		x = x * 1103515245u + 12345u;
		buf[i] = (unsigned char)(x >> 16);
	}
}

/* Seconds on the monotonic clock. */
static inline double tu_now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* dir/err ends with the line "prog: ..." containing what, and holds
 * nothing else but, in a sanitizer build, a sanitizer's report before it
 * (an importer process passes its report on before the program's line). */
static inline void tu_last_line(const char *dir, const char *prog, const char *what)
{
	if (!TU_SANITIZE) {
		tu_one_line(dir, prog, what);
		return;
	}
	char *buf = tu_slurp(dir, "err");
	size_t len = strlen(buf);
	cr_assert(len && buf[len - 1] == '\n', "stderr does not end in a line: %s", buf);
	buf[len - 1] = 0;
	char *last = strrchr(buf, '\n');
	last = last ? last + 1 : buf;
	size_t n = strlen(prog);
	cr_assert(!strncmp(last, prog, n) && last[n] == ':' && last[n + 1] == ' ',
	          "last line does not start with '%s: ': %s", prog, last);
	cr_assert(strstr(last, what), "last line does not name '%s': %s", what, last);
	if (last != buf)
		cr_assert(strstr(buf, "Sanitizer"), "lines before the last are no sanitizer's: %s",
		          buf);
}

#endif
