/*
 * test_scripts.c: checks of the repository's shell scripts that their
 * own runs would find only at the end. The bench scripts share
 * scripts/bench-lib.sh (say, die, jget, bench_start, bench_end, ...); a
 * script that calls one of its functions without sourcing it runs its
 * measurements and then dies where it writes its section (bench-profile.sh
 * did after the library took over its last lines: 19 minutes of callgrind,
 * then "bench_end: not found"). The scripts are found beside the tests
 * (SAAR_ROOT, else the current folder: `make test` runs from the repo).
 */
#include "tests/testutil.h"

static const char *root(void)
{
	const char *r = getenv("SAAR_ROOT");
	return r && *r ? r : ".";
}

/* Every script under scripts/ that calls a function of bench-lib.sh
 * sources it (or is it). Catches a script left calling bench_end,
 * bench_start, bench_init, bench_min, bench_views, pct_err, md_head or
 * med_range after the lines it replaced were taken out, without the
 * library that defines them. */
Test(scripts, bench_library_functions_come_with_the_library)
{
	char dir[256], cmd[2048];
	tu_tmpdir(dir, sizeof dir);
	snprintf(
	    cmd, sizeof cmd,
	    "cd '%s' && n=0 && for f in scripts/*.sh; do "
	    "[ \"$f\" = scripts/bench-lib.sh ] && continue; "
	    "grep -qE '(^|[^_[:alnum:]])(bench_init|bench_start|bench_end|bench_min|"
	    "bench_views|pct_err|md_head|med_range)([^_[:alnum:]]|$)' \"$f\" || continue; "
	    "n=$((n + 1)); "
	    "grep -qE '^[[:space:]]*\\. .*bench-lib\\.sh\"?[[:space:]]*$' \"$f\" || echo \"$f\"; "
	    "done >'%s/out' && echo \"$n\" >'%s/n'",
	    root(), dir, dir);
	cr_assert_eq(tu_run(cmd), 0, "the scan failed");
	cr_assert_str_empty(tu_slurp(dir, "out"),
	                    "scripts calling bench-lib.sh's functions without sourcing it:\n%s",
	                    tu_slurp(dir, "out"));
	/* the scan found the scripts that use the library (else it shows nothing) */
	cr_assert_geq(atoi(tu_slurp(dir, "n")), 7, "only %s scripts use bench-lib.sh",
	              tu_slurp(dir, "n"));
}

/* A checker's summary "PREFIX N of M ...", the first from *at on: all
 * N of at least min things passed (a checker that found nothing to check
 * would pass saying nothing). *at moves past it, to a second summary of
 * the same output. */
static void all_of_at_least(const char **at, const char *prefix, int min, const char *what,
                            const char *out)
{
	size_t k = strlen(prefix);
	const char *n = strstr(*at, prefix);
	int ok = 0, all = 0;
	cr_assert(n && sscanf(n + k, "%d of %d", &ok, &all) == 2, "%s", out);
	cr_assert(ok == all && all >= min, "%d of %d %s:\n%s", ok, all, what, out);
	*at = n + k;
}

/* Runs the checker scripts/SCRIPT (readme-check.py, figures-check.py)
 * on the built programs and the shared scenes with ARGS, its stdout and
 * stderr in DIR/NAME; returns its exit status and, in *out, the output. */
static int run_checker(const char *script, const char *args, const char *dir, const char *name,
                       const char **out)
{
	char cmd[4096];
	snprintf(cmd, sizeof cmd,
	         "python3 '%s/scripts/%s' --bin '%s' --scenes '%s' %s >'%s/%s' 2>&1", root(),
	         script, tu_bin_dir(), tu_scenes_dir(), args, dir, name);
	int rc = tu_run(cmd);
	*out = tu_slurp(dir, name);
	return rc;
}

/* Every example of README.md prints what the page shows, and its
 * pictures are what the examples draw (scripts/readme-check.py: the
 * commands run in the page's order in a scratch folder; cycles, fps,
 * counts and checks compared exactly, the host's times masked; the marked
 * pictures compared pixel by pixel with what the examples wrote). Catches
 * an example left showing figures the model no longer gives (the Robots'
 * flat chip frames showed 387573 and 292769 cycles for a day after the
 * model gave 357572 and 271486), a changed output line, a command that no
 * longer runs, and a picture the tools no longer draw (the timeline
 * picture lacked the transformation unit's row). */
Test(scripts, readme_examples_print_what_the_readme_shows, .timeout = 900)
{
	char views[512], dir[256], args[600];
	SCENE_OR_SKIP(views, "views.yaml");
	tu_tmpdir(dir, sizeof dir);
	snprintf(args, sizeof args, "'%s/README.md'", root());
	const char *out;
	int rc = run_checker("readme-check.py", args, dir, "out", &out);
	cr_assert_eq(rc, 0, "README.md's examples differ from what they print:\n%s", out);
	/* it ran the page's examples (25 when written) and compared its
	 * pictures (3 when written) */
	const char *at = out;
	all_of_at_least(&at, "README.md: ", 20, "examples", out);
	all_of_at_least(&at, "README.md: ", 3, "pictures", out);
}

/* `make accel` (scripts/accel.sh, accel-doc.py) at a tiny size on one
 * view: it writes its document, whose kd-tree columns come from the plain
 * SAH tree the chip walks. Catches rtref's kd runs left on rtref's own
 * tree for the view's packets (docs/ACCEL.md's kd steps and tests per ray
 * came from it for a day after that tree became rtref's default: dragon2
 * at 128x96 1.83 steps and 46.9 tests per ray instead of the plain tree's
 * 9.1 and 1.73, set beside the grid's as if they were the same kd-tree),
 * and a document written from such a run. */
Test(scripts, accel_compares_the_plain_kd_tree, .timeout = 300)
{
	char views[512], dir[256], runs[300], cmd[4096];
	SCENE_OR_SKIP(views, "views.yaml");
	tu_tmpdir(dir, sizeof dir);
	snprintf(runs, sizeof runs, "%s/runs", dir);
	snprintf(cmd, sizeof cmd,
	         "ACCEL_SIZE=16x16 ACCEL_VIEWS=cornell ACCEL_TIMES=0 ACCEL_T4_VIEW=cornell "
	         "ACCEL_OUT='%s/runs' ACCEL_DOC='%s/ACCEL.md' SAAR_SCENES='%s' "
	         "sh '%s/scripts/accel.sh' '%s' >'%s/log' 2>&1",
	         dir, dir, tu_scenes_dir(), root(), tu_bin_dir(), dir);
	cr_assert_eq(tu_run(cmd), 0, "accel.sh failed:\n%s", tu_slurp(dir, "log"));
	const char *doc = tu_slurp(dir, "ACCEL.md");
	cr_assert(strstr(doc, "| cornell | 32 |"), "no cornell row in:\n%s", doc);
	cr_assert(strstr(doc, "Generated ") && strstr(doc, "; commit "),
	          "the document names no date, host or commit:\n%s", doc);
	/* each kd run's tree is the plain one */
	const char *kd[] = {"cornell-kd.json", "cornell-t4-kd.json", "robots-0-kd.json"};
	for (size_t i = 0; i < sizeof kd / sizeof *kd; i++) {
		const char *js = tu_slurp(runs, kd[i]);
		cr_assert(strstr(js, "\"footprint_from\": \"none\""), "%s: %s", kd[i], js);
	}
	/* and the document is not written from a run on rtref's own tree */
	snprintf(cmd, sizeof cmd,
	         "sed -i 's/\"footprint_from\": \"none\"/\"footprint_from\": \"view\"/' "
	         "'%s/cornell-kd.json' && "
	         "python3 '%s/scripts/accel-doc.py' '%s' '%s/A2.md' 16x16 cornell 0 cornell "
	         "64x64 >'%s/log2' 2>&1",
	         runs, root(), runs, dir, dir);
	cr_assert_eq(tu_run(cmd), 2, "accel-doc.py took a footprint tree's run:\n%s",
	             tu_slurp(dir, "log2"));
	cr_assert(strstr(tu_slurp(dir, "log2"), "plain SAH tree"), "%s", tu_slurp(dir, "log2"));
}

/* The generated documents' figures are what the program gives now
 * (scripts/figures-check.py): each generator writes, with its tables, a
 * line naming one or two of its runs and some of their report values, and
 * the check reruns them. Catches a model change whose documents were not
 * regenerated (NUMERICS.md showed the chip's pre-calibration fps for a
 * day: mutant 86 puts a stale figure back), and a check that lets a wrong
 * figure through (the doctored copy below). */
Test(scripts, documents_show_the_programs_figures, .timeout = 900)
{
	char views[512], dir[256], args[1200], cmd[2048];
	SCENE_OR_SKIP(views, "views.yaml");
	tu_tmpdir(dir, sizeof dir);
	snprintf(args, sizeof args, "--root '%s'", root());
	const char *out;
	int rc = run_checker("figures-check.py", args, dir, "out", &out);
	cr_assert_eq(rc, 0, "documents whose figures the program no longer gives:\n%s", out);
	/* it reran the generators' runs (16 when written: NUMERICS 2, DYNAMIC 2,
	 * ACCEL 2, DRT 1, VALIDATION 1, FIDELITY 3, CALIBRATION 2, PERFORMANCE 3) */
	const char *at = out;
	all_of_at_least(&at, "figures-check: ", 16, "runs", out);
	/* a figure changed (a digit put in front of DRT.md's fps) is found
	 * and named */
	snprintf(cmd, sizeof cmd,
	         "sed 's/ ; fps=/ ; fps=1/' '%s/docs/DRT.md' >'%s/DRT.md' && "
	         "! cmp -s '%s/docs/DRT.md' '%s/DRT.md'",
	         root(), dir, root(), dir);
	cr_assert_eq(tu_run(cmd), 0, "DRT.md has no fps to change");
	snprintf(args, sizeof args, "--root '%s' '%s/DRT.md'", root(), dir);
	rc = run_checker("figures-check.py", args, dir, "out2", &out);
	cr_assert_eq(rc, 1, "a changed fps was not found:\n%s", out);
	cr_assert(strstr(out, "fps shown ") && strstr(out, "0 of 1 runs"), "%s", out);
}

/* Runs cmd, extend-doc.py on a spoiled page or patch (its output in
 * dir/name): it must be refused (exit 1), naming want. */
static void extend_doc_refuses(const char *dir, const char *cmd, const char *name, const char *want,
                               const char *what)
{
	cr_assert_eq(tu_run(cmd), 1, "%s passed: %s", what, tu_slurp(dir, name));
	cr_assert(strstr(tu_slurp(dir, name), want), "%s", tu_slurp(dir, name));
}

/* docs/extending.md's unit-kind walk-through is the patch `make
 * extend-check` builds and runs (tests/extend/unit-clip.patch; the build
 * takes a minute, so `make test` checks only that the two agree,
 * scripts/extend-doc.py): every code line the page's example shows is a
 * line of the patch, and the patch changes only the page's three places.
 * Catches a page edited without its patch (the walk-through still showed
 * four unit kinds in its enum for weeks after the fifth, and a literal
 * SMP_COMP stopped its build unseen: a sixth kind is what it adds now),
 * and a patch that needs a file outside the three places. */
Test(scripts, extending_walkthrough_is_the_checked_patch)
{
	char dir[256], cmd[2048];
	tu_tmpdir(dir, sizeof dir);
	snprintf(cmd, sizeof cmd, "python3 '%s/scripts/extend-doc.py' >'%s/ok' 2>&1", root(), dir);
	const int rc = tu_run(cmd);
	const char *out = tu_slurp(dir, "ok");
	cr_assert_eq(rc, 0, "%s", out);
	const char *at = out;
	all_of_at_least(&at, "extend-doc: ", 20, "lines of the example", out);
	/* the same page with two kinds of the enum swapped: refused */
	snprintf(cmd, sizeof cmd,
	         "sed 's/UNIT_XFORM, UNIT_CLIP/UNIT_CLIP, UNIT_XFORM/' '%s/docs/extending.md' "
	         ">'%s/bad.md' && python3 '%s/scripts/extend-doc.py' --doc '%s/bad.md' "
	         ">'%s/bad' 2>&1",
	         root(), dir, root(), dir, dir);
	extend_doc_refuses(dir, cmd, "bad", "UNIT_CLIP, UNIT_XFORM", "a changed line");
	/* the patch with a fourth place (the config's file): refused */
	snprintf(cmd, sizeof cmd,
	         "{ cat '%s/tests/extend/unit-clip.patch'; printf '%%s\\n' "
	         "'--- a/sim/config.c' '+++ b/sim/config.c' '@@ -1 +1 @@' '-a' '+b'; } "
	         ">'%s/p' && python3 '%s/scripts/extend-doc.py' --patch '%s/p' >'%s/four' 2>&1",
	         root(), dir, root(), dir, dir);
	extend_doc_refuses(dir, cmd, "four", "sim/config.c", "a fourth place");
}
