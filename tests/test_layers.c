/*
 * test_layers.c: scripts/layers.py, the layering check `make test` runs
 * (docs/design-layers.md). Each test builds a small tree in a temporary
 * folder and runs the script on it with --root: a forbidden include, a
 * folderless include, a circle of three modules, mem/ including the config
 * schema, the one-file exception of units/ not widening to its folder, and
 * a clean tree that uses every allowed include passing. The last test runs
 * the check on the repository itself. The script is found beside the tests
 * (SAAR_ROOT, else the current folder: `make test` runs from the repo).
 */
#include "tests/testutil.h"

#include <errno.h>

static char dir[256];

static const char *root(void)
{
	const char *r = getenv("SAAR_ROOT");
	return r && *r ? r : ".";
}

static void setup(void)
{
	tu_tmpdir(dir, sizeof dir);
}

TestSuite(layers, .init = setup);

/* Writes text to dir/rel, making rel's folders first. */
static void put(const char *rel, const char *text)
{
	char path[1024], out[1024];
	snprintf(path, sizeof path, "%s/%s", dir, rel);
	for (char *s = path + strlen(dir) + 1; (s = strchr(s, '/')); s++) {
		*s = 0;
		cr_assert(mkdir(path, 0755) == 0 || errno == EEXIST, "mkdir %s", path);
		*s = '/';
	}
	tu_write(out, sizeof out, dir, rel, text);
}

/* Runs the check (args after the script, e.g. "--root DIR") with stdout in
 * dir/out and stderr in dir/err; returns the exit status. */
static int layers(const char *args)
{
	char cmd[2048];
	snprintf(cmd, sizeof cmd, "python3 '%s/scripts/layers.py' %s >'%s/out' 2>'%s/err'", root(),
	         args, dir, dir);
	return tu_run(cmd);
}

static int check_tree(void)
{
	char args[512];
	snprintf(args, sizeof args, "--root '%s'", dir);
	return layers(args);
}

/* The lines of dir/out. */
static int out_lines(void)
{
	int n = 0;
	for (const char *s = tu_slurp(dir, "out"); *s; s++)
		n += *s == '\n';
	return n;
}

/* A tree that passes: every layer with an include it may make. */
static void clean_tree(void)
{
	put("kernel-ref/diag.h", "#include <stdio.h>\n");
	put("kernel-ref/jsonw.h", "#include \"kernel-ref/diag.h\"\n");
	put("kernel-ref/rtref.c",
	    "#include \"kernel-ref/jsonw.h\"\nint main(void) { return 0; }\n");
	put("sim/core/engine.h", "#include \"kernel-ref/diag.h\"\n");
	put("mem/memport.h", "#include \"sim/core/engine.h\"\n");
	put("mem/cache.h", "#include \"mem/memport.h\"\n");
	put("mem/cache.c",
	    "#include \"mem/cache.h\"\n/* an old line:\n#include \"sim/config.h\"\n */\n"
	    "// #include \"units/thread.h\"\n"
	    "static const char *s = \"#include \\\"sim/config.h\\\"\";\n");
	put("units/thread.h", "#include \"mem/memport.h\"\n#include \"kernel-ref/diag.h\"\n");
	put("units/thread.c", "#include \"units/thread.h\"\n#include \"sim/core/engine.h\"\n");
	put("traces/pktrec.h", "#include \"mem/cache.h\"\n");
	put("sim/config.h", "#include \"kernel-ref/jsonw.h\"\n");
	put("sim/modes/timed.c", "#include \"units/thread.h\"\n#include \"traces/pktrec.h\"\n"
	                         "#include \"sim/config.h\"\n");
	put("sim/main.c", "#include \"sim/config.h\"\n#include \"units/thread.h\"\n"
	                  "int main(void) { return 0; }\n");
	put("traces/replay.c", "#include \"sim/config.h\"\nint main(void) { return 0; }\n");
	/* tests/ and scripts/ are exempt */
	put("tests/t.c", "#include \"cache.h\"\n#include \"sim/main.c\"\n");
}

/* Catches: a check that flags allowed includes (the one-file exception
 * units/ -> mem/memport.h, programs above every layer, sim/modes/ as sim/,
 * includes inside comments and strings, the exempt tests/) or fails on a
 * clean tree for any other reason. */
Test(layers, clean_tree_passes)
{
	clean_tree();
	cr_assert_eq(check_tree(), 0, "%s%s", tu_slurp(dir, "out"), tu_slurp(dir, "err"));
	cr_assert_str_empty(tu_slurp(dir, "out"));
}

/* Catches: kernel-ref reaching up into the memory hierarchy unnoticed. */
Test(layers, kernel_ref_including_mem_fails)
{
	clean_tree();
	put("kernel-ref/shade.c", "#include <math.h>\n\n#include \"mem/cache.h\"\n");
	cr_assert_eq(check_tree(), 1);
	const char *o = tu_slurp(dir, "out");
	cr_assert(strstr(o, "kernel-ref/shade.c:3: kernel-ref/ must not include mem/cache.h"), "%s",
	          o);
	cr_assert_eq(out_lines(), 1, "%s", o);
}

/* Catches: a bare "cache.h" (found beside the includer, not by -I.)
 * passing; the message names the file it meant. */
Test(layers, folderless_include_fails)
{
	clean_tree();
	put("mem/hier.c", "#include \"cache.h\"\n");
	cr_assert_eq(check_tree(), 1);
	const char *o = tu_slurp(dir, "out");
	cr_assert(strstr(o, "mem/hier.c:1: #include \"cache.h\" does not name its folder "
	                    "(write \"mem/cache.h\")"),
	          "%s", o);
	cr_assert_eq(out_lines(), 1, "%s", o);
}

/* Catches: a circle through three modules (each include allowed by the
 * table) passing, or reported without its members in order. The edges go
 * through both a .c and a .h file: a module is x.c with x.h. */
Test(layers, circle_of_three_modules_fails)
{
	clean_tree();
	put("units/a.h", "#include \"units/thread.h\"\n");
	put("units/a.c", "#include \"units/a.h\"\n#include \"units/b.h\"\n");
	put("units/b.h", "#include \"units/c.h\"\n");
	put("units/c.h", "");
	put("units/c.c", "#include \"units/c.h\"\n#include \"units/a.h\"\n");
	cr_assert_eq(check_tree(), 1);
	const char *o = tu_slurp(dir, "out");
	cr_assert(strstr(o, "units/a.c:2: include circle units/a -> units/b -> units/c -> units/a"),
	          "%s", o);
	cr_assert_eq(out_lines(), 1, "%s", o);
}

/* Catches: the memory hierarchy reading the YAML config schema again
 * (issue 30: components own their parameters). */
Test(layers, mem_including_sim_config_fails)
{
	clean_tree();
	put("mem/hier.h", "#include \"mem/cache.h\"\n#include \"sim/config.h\"\n");
	cr_assert_eq(check_tree(), 1);
	const char *o = tu_slurp(dir, "out");
	cr_assert(strstr(o, "mem/hier.h:2: mem/ must not include sim/config.h"), "%s", o);
	cr_assert_eq(out_lines(), 1, "%s", o);
}

/* Catches: the one-file exception units/ -> mem/memport.h read as all of
 * mem/, and the report writer allowed below sim/. */
Test(layers, units_beyond_memport_fail)
{
	clean_tree();
	put("units/list.c", "#include \"mem/cache.h\"\n#include \"kernel-ref/jsonw.h\"\n");
	cr_assert_eq(check_tree(), 1);
	const char *o = tu_slurp(dir, "out");
	cr_assert(strstr(o, "units/list.c:1: units/ must not include mem/cache.h"), "%s", o);
	cr_assert(strstr(o, "units/list.c:2: units/ must not include kernel-ref/jsonw.h"), "%s", o);
	cr_assert_eq(out_lines(), 2, "%s", o);
}

/* Catches: bad use taken for a pass or a failure (exit 2, one line). */
Test(layers, bad_use_exits_2)
{
	cr_assert_eq(layers("--bogus"), 2);
	cr_assert_eq(layers("--long 0"), 2);
	char args[512];
	snprintf(args, sizeof args, "--root '%s'", dir); /* holds none of the folders */
	cr_assert_eq(layers(args), 2);
	cr_assert(strstr(tu_slurp(dir, "err"), "holds none of"));
}

/* Catches: --long missing a long function, counting it short, or listing
 * one at the limit (a macro's braces and a struct do not count). */
Test(layers, long_lists_functions_over_the_limit)
{
	put("sim/x.c", "#define M do { } while (0)\n"
	               "struct s {\n\tint a;\n};\n"
	               "static int f(int a)\n{\n\tif (a) {\n\t\ta++;\n\t}\n\treturn a;\n}\n");
	char args[512];
	snprintf(args, sizeof args, "--root '%s' --long 6", dir);
	cr_assert_eq(layers(args), 1);
	cr_assert_str_eq(tu_slurp(dir, "out"), "sim/x.c:5: f: 7 lines\n");
	snprintf(args, sizeof args, "--root '%s' --long 7", dir);
	cr_assert_eq(layers(args), 0);
	cr_assert_str_empty(tu_slurp(dir, "out"));
}

/* The repository itself passes. Catches: any forbidden include or circle
 * in the real tree (make test also runs the script before the suite). */
Test(layers, repository_passes)
{
	char args[512];
	snprintf(args, sizeof args, "--root '%s'", root());
	cr_assert_eq(layers(args), 0, "the repository breaks its layers:\n%s",
	             tu_slurp(dir, "out"));
}
