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
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

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

/* A fresh temporary directory for a test's files (not removed: /tmp). */
static inline void tu_tmpdir(char *buf, size_t n)
{
	snprintf(buf, n, "/tmp/saarsim-test-XXXXXX");
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

/* Runs a shell command, returns its exit status (-1 if it did not exit). */
static inline int tu_run(const char *cmd)
{
	int st = system(cmd);
	if (st == -1 || !WIFEXITED(st))
		return -1;
	return WEXITSTATUS(st);
}

#endif
