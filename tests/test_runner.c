/*
 * test_runner.c: the test runner's account of skipped tests (tests/main.c).
 * Criterion's summary counted only tests that ran, so tests skipped for
 * want of the shared scenes were invisible; and with the scenes present no
 * test may skip. The runner is run on one scene test with the scenes
 * absent (a missing folder: the skip is counted and named, the run passes)
 * and with a scenes folder that lacks the file (the skip fails the run).
 */
#include "tests/testutil.h"

Test(runner, skips_are_counted_and_named)
{
	char dir[256], cmd[4096];
	tu_tmpdir(dir, sizeof dir);
	const char *filter = "--filter 'view/scene_without_view_is_framed_by_its_box'";
	/* the runner must not take itself for one of its own sandboxed
	 * workers (Criterion's worker variables are left out) */
	snprintf(
	    cmd, sizeof cmd,
	    "env -u BXFI_MAP -u IS_SANDBOX SAAR_SCENES=%s/none %s/saarsim-tests %s >%s/out 2>&1",
	    dir, tu_bin_dir(), filter, dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", tu_slurp(dir, "out"));
	const char *out = tu_slurp(dir, "out");
	cr_assert(strstr(out, "[====] Skipped: 1\n"), "%s", out);
	cr_assert(strstr(out, "view::scene_without_view_is_framed_by_its_box: shared scene"),
	          "the skipped test is not named: %s", out);
	/* the scenes folder exists but lacks the file: the skip fails */
	snprintf(cmd, sizeof cmd,
	         "env -u BXFI_MAP -u IS_SANDBOX SAAR_SCENES=%s %s/saarsim-tests %s >%s/out 2>&1",
	         dir, tu_bin_dir(), filter, dir);
	cr_assert_neq(tu_run(cmd), 0, "a skip passed with the scenes present");
	cr_assert(strstr(tu_slurp(dir, "out"), "1 tests skipped although the shared scenes are at"),
	          "%s", tu_slurp(dir, "out"));
}

/* A test that provokes a library warning checks it instead of letting it
 * land in `make test`'s output (a stray "warning: sampling.warming stored
 * needs --world-cache" line sat among the results). */
Test(runner, no_stray_warning_lines)
{
	char dir[256], cmd[4096];
	tu_tmpdir(dir, sizeof dir);
	snprintf(cmd, sizeof cmd,
	         "env -u BXFI_MAP -u IS_SANDBOX %s/saarsim-tests --filter "
	         "'warming/without_a_world_cache_the_stretches_run' >%s/out 2>&1",
	         tu_bin_dir(), dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", tu_slurp(dir, "out"));
	cr_assert_not(strstr(tu_slurp(dir, "out"), "warning:"), "%s", tu_slurp(dir, "out"));
}

/* A run's test folders and the temporaries of what its tests start go
 * into one folder under $TMPDIR, removed when the run ends. Mistake
 * caught: test folders left in /tmp (tu_tmpdir made them there and
 * nothing removed them: 36,000 folders, 75 GB, a full disk). The runner
 * is run with TMPDIR set to an empty folder, on a test that makes a
 * folder and starts saarsim: the folder must be empty again after. */
Test(runner, test_folders_are_removed_after_the_run, .timeout = 120)
{
	char dir[256], cmd[4096];
	tu_tmpdir(dir, sizeof dir);
	snprintf(cmd, sizeof cmd,
	         "mkdir %s/tmp && env -u BXFI_MAP -u IS_SANDBOX TMPDIR=%s/tmp "
	         "%s/saarsim-tests --filter 'chip_twolevel/saarsim_flag' >%s/out 2>&1",
	         dir, dir, tu_bin_dir(), dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", tu_slurp(dir, "out"));
	snprintf(cmd, sizeof cmd, "test -z \"$(ls -A %s/tmp)\"", dir);
	cr_assert_eq(tu_run(cmd), 0, "the run left files in its TMPDIR: %s",
	             (snprintf(cmd, sizeof cmd, "ls -A %s/tmp > %s/ls 2>&1", dir, dir), tu_run(cmd),
	              tu_slurp(dir, "ls")));
}

/* `make fuzz` compiles the library with clang under -Werror, which
 * refuses what gcc's `make test` build accepts: a unit-table initialiser
 * one field short (clang's -Wmissing-field-initializers) broke `make fuzz`
 * for weeks unseen. `make fuzz-syntax` checks every source `make fuzz`
 * compiles with its compiler and flags, without building; where clang is
 * not installed it checks nothing and says so (there is no `make fuzz` to
 * break there). Run from the repository (SAAR_ROOT, else the current
 * folder: `make test` runs from it), outside make test's job server. */
Test(runner, fuzz_build_sources_compile_with_clang, .timeout = 300)
{
	char dir[256], cmd[4096];
	tu_tmpdir(dir, sizeof dir);
	const char *root = getenv("SAAR_ROOT");
	snprintf(cmd, sizeof cmd,
	         "env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -s -C '%s' fuzz-syntax >%s/out 2>&1",
	         root && *root ? root : ".", dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", tu_slurp(dir, "out"));
}
