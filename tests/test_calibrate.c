/*
 * test_calibrate.c: scripts/calibrate.sh refuses what it must not do
 * before it runs anything: a published key among the knobs (the fit may
 * move assumed values only), and bad input (one line, exit 2). The search
 * itself is `make calibrate` (docs/calibration.md), too long for a test.
 */
#include "tests/testutil.h"

#include <string.h>

/* Runs calibrate.sh with env and args; returns its exit status and leaves
 * its stderr in err. */
static int calibrate(const char *env, const char *args, char *err, size_t n)
{
	char dir[256], views[512], cmd[4096], errf[600];
	tu_tmpdir(dir, sizeof dir);
	/* a views file of its own: the refusals come before any scene is read */
	snprintf(views, sizeof views, "%s/views.yaml", dir);
	FILE *f = fopen(views, "w");
	cr_assert(f);
	fputs("views: {}\n", f);
	fclose(f);
	snprintf(errf, sizeof errf, "%s/err", dir);
	snprintf(
	    cmd, sizeof cmd,
	    "SAARSIM='%s/saarsim' SAAR_SCENES='%s' %s sh scripts/calibrate.sh --out '%s/out' %s "
	    ">/dev/null 2>'%s'",
	    tu_bin_dir(), dir, env, dir, args, errf);
	int rc = tu_run(cmd);
	f = fopen(errf, "r");
	cr_assert(f);
	size_t got = fread(err, 1, n - 1, f);
	err[got] = 0;
	fclose(f);
	return rc;
}

static int lines(const char *s)
{
	int n = 0;
	for (; *s; s++)
		n += *s == '\n';
	return n;
}

/* Catches: a published value (here the clock, seed 002 §4.7) taken into
 * the fit; only keys --list-config calls assumed (or calibrated) may move. */
Test(calibrate, refuses_a_published_knob)
{
	char err[2048];
	int rc = calibrate("CAL_KNOBS='chip.clock_mhz 400,533'", "", err, sizeof err);
	cr_assert_eq(rc, 2, "exit %d: %s", rc, err);
	cr_assert_eq(lines(err), 1, "%s", err);
	cr_assert(strstr(err, "chip.clock_mhz") && strstr(err, "not an assumed"), "%s", err);
	/* a key moved together with an assumed one is checked too */
	rc = calibrate("CAL_KNOBS='chip.isect.width+memory.l1.tri.size_kb 4+144,8+288'", "", err,
	               sizeof err);
	cr_assert_eq(rc, 2, "exit %d: %s", rc, err);
	cr_assert(strstr(err, "memory.l1.tri.size_kb"), "%s", err);
}

/* Catches: bad input running a half-hour search, or failing with a
 * screenful instead of one line and exit 2. */
Test(calibrate, bad_input_one_line_exit_2)
{
	static const char *const bad[] = {"--size 512", "--check-size 0x10", "--rounds 0",
	                                  "-j x",       "--no-such-option",  "--out"};
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		char err[2048];
		int rc = calibrate("", bad[i], err, sizeof err);
		cr_assert_eq(rc, 2, "%s: exit %d: %s", bad[i], rc, err);
		cr_assert_eq(lines(err), 1, "%s: %s", bad[i], err);
	}
}
