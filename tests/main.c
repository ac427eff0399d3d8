/*
 * main.c: the test runner. Criterion's own, plus an account of skipped
 * tests: its summary line counts only tests that ran, so 25 tests that
 * skipped for want of the shared scenes were invisible. After the run this
 * prints how many tests skipped and which, with their reasons; and when the
 * shared scenes are present (SAAR_SCENES names a folder that exists) a
 * skipped test fails the run, since then nothing has a reason to skip.
 *
 * Every folder a test makes (tu_tmpdir), and every temporary the programs
 * and scripts it starts make under $TMPDIR, lives in one folder per run,
 * removed when the run ends: before, each run left its test folders in
 * /tmp (after a few days of runs, 36,000 folders and 75 GB filled the
 * disk). SAARSIM_KEEP_TEST_TMP=1 keeps it (its path is printed) for a
 * look at a failed test's files.
 */
#define _XOPEN_SOURCE 700 /* nftw */
#include <criterion/criterion.h>
#include <criterion/hooks.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "tests/testutil.h"

static size_t nskipped;

ReportHook(POST_ALL)(struct criterion_global_stats *stats)
{
	nskipped = 0;
	for (struct criterion_suite_stats *s = stats->suites; s; s = s->next)
		for (struct criterion_test_stats *t = s->tests; t; t = t->next)
			/* a test left out by --filter is "skipped" with no
			 * reason; cr_skip_test always gives one */
			if (t->test_status == CR_STATUS_SKIPPED && t->message) {
				if (!nskipped)
					fputs("[SKIP] skipped tests:\n", stderr);
				nskipped++;
				fprintf(stderr, "[SKIP]   %s::%s%s%s\n", t->test->category,
				        t->test->name, t->message ? ": " : "",
				        t->message ? t->message : "");
			}
	fprintf(stderr, "[====] Skipped: %zu\n", nskipped);
}

static int rm_entry(const char *path, const struct stat *st, int flag, struct FTW *f)
{
	(void)st;
	(void)flag;
	(void)f;
	remove(path); /* best effort: go on past what cannot go */
	return 0;
}

/* The run's folder for tu_tmpdir and $TMPDIR; NULL when none can be made
 * (tests then use /tmp as before). */
static const char *run_tmp(char *buf, size_t n)
{
	const char *base = getenv("TMPDIR");
	snprintf(buf, n, "%s/saarsim-tests-XXXXXX", base && *base ? base : "/tmp");
	if (!mkdtemp(buf))
		return NULL;
	setenv("SAARSIM_TEST_TMP", buf, 1);
	setenv("TMPDIR", buf, 1);
	return buf;
}

int main(int argc, char *argv[])
{
	char tmpbuf[4096];
	const char *tmp = run_tmp(tmpbuf, sizeof tmpbuf);
	/* Every run the tests make (in process, and saarsim, rtref and the
	 * scripts they start) is without a world cache unless the test names
	 * one (--world-cache DIR, or SAARSIM_CACHE_DIR in tu_run_env): the
	 * default folder would write into the user's home (CI's may be
	 * unwritable or absent) and carry entries from one test, or one run
	 * of the suite, into the next. Overwritten, so the caller's own
	 * setting cannot change what a test tests. */
	setenv("SAARSIM_CACHE_DIR", "off", 1);
	struct criterion_test_set *tests = criterion_initialize();
	int result = 0;
	if (criterion_handle_args(argc, argv, true))
		result = !criterion_run_all_tests(tests);
	criterion_finalize(tests);
	if (tmp) {
		const char *keep = getenv("SAARSIM_KEEP_TEST_TMP");
		if (keep && *keep && strcmp(keep, "0"))
			fprintf(stderr, "[====] test files kept in %s\n", tmp);
		else
			nftw(tmp, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
	}
	struct stat st;
	const char *scenes = tu_scenes_dir();
	if (nskipped && stat(scenes, &st) == 0 && S_ISDIR(st.st_mode)) {
		fprintf(stderr,
		        "[FAIL] %zu tests skipped although the shared scenes are at %s: none may "
		        "skip there\n",
		        nskipped, scenes);
		result = 1;
	}
	return result;
}
