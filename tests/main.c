/*
 * main.c: the test runner. Criterion's own, plus an account of skipped
 * tests: its summary line counts only tests that ran, so 25 tests that
 * skipped for want of the shared scenes were invisible. After the run this
 * prints how many tests skipped and which, with their reasons; and when the
 * shared scenes are present (SAAR_SCENES names a folder that exists) a
 * skipped test fails the run, since then nothing has a reason to skip.
 */
#include <criterion/criterion.h>
#include <criterion/hooks.h>
#include <stdio.h>
#include <stdlib.h>
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

int main(int argc, char *argv[])
{
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
