/*
 * test_stress.c: the fast part of the numerical stress suite (issue 7).
 * `make stress` runs larger versions and writes docs/NUMERICS.md. Every
 * count asserted zero here is one that must stay zero.
 */
#include "kernel-ref/stress.h"
#include "tests/testutil.h"

static void zero(stress_result r)
{
	cr_assert_gt(r.rays, 0, "%s: no rays traced", r.name);
	cr_assert_neq(r.measured, 0, "%s: the case must say which counts it measures", r.name);
	cr_assert_eq(r.leaked, 0, "%s: %llu of %llu rays leaked", r.name,
	             (unsigned long long)r.leaked, (unsigned long long)r.rays);
	cr_assert_eq(r.acne, 0, "%s: %llu self-intersections", r.name, (unsigned long long)r.acne);
	cr_assert_eq(r.disagree, 0, "%s: %llu disagreements with double precision", r.name,
	             (unsigned long long)r.disagree);
	cr_assert_eq(r.mismatch, 0, "%s: %llu packet/single or thread-count mismatches", r.name,
	             (unsigned long long)r.mismatch);
}

Test(stress, closed_sphere_across_scales, .timeout = 300)
{
	const double scales[] = {1e-4, 1e-2, 1, 1e2, 1e4, 1e6};
	for (size_t k = 0; k < sizeof scales / sizeof *scales; k++)
		zero(stress_sphere(scales[k], 0, 64));
}

Test(stress, closed_sphere_far_from_origin, .timeout = 300)
{
	/* at 1e5 a float step is 2^-7; radii from 1 up keep the mesh resolvable */
	const double scales[] = {1, 1e2, 1e4};
	for (size_t k = 0; k < sizeof scales / sizeof *scales; k++)
		zero(stress_sphere(scales[k], 1e5, 64));
}

Test(stress, closed_spd_tetra_across_scales, .timeout = 300)
{
	const double scales[] = {1e-4, 1, 1e6};
	for (size_t k = 0; k < sizeof scales / sizeof *scales; k++)
		zero(stress_spd_tetra(scales[k], 0, 64));
	zero(stress_spd_tetra(1e2, 1e5, 64));
}

Test(stress, no_shadow_acne, .timeout = 300)
{
	zero(stress_acne(1, 0, 64));
	zero(stress_acne(1e-3, 0, 64));
	zero(stress_acne(1e4, 1e5, 64));
}

Test(stress, rays_at_vertices_and_edges)
{
	zero(stress_vertices_edges(16));
}

Test(stress, flat_cells_and_signed_zero_directions)
{
	zero(stress_flat_axis_parallel(16));
}

Test(stress, degenerate_duplicate_and_deep_trees, .timeout = 300)
{
	zero(stress_degenerate(64));
}

/* The full run's 5,000,000 rays (make stress), not a sample: the one ray
 * a miscompiled reference traced from another origin (GCC 12.2's SLP
 * vectorizer, tests/test_compiler.c; mutant 85) was the 4,426,048th, and
 * 200,000 rays had never reached it. */
Test(stress, random_rays_vs_double_precision, .timeout = 120)
{
	stress_result r = stress_random(5000000, 7);
	zero(r);
	/* ties exist but are rare: a handful per 100k at most */
	cr_assert_lt(r.ties, r.rays / 1000, "%llu ties", (unsigned long long)r.ties);
}

/* The table `make stress` publishes, at its full sizes (256x256 rays per
 * case, 5,000,000 random rays; about 2 s): saarsim-stress exits 0 only
 * when every must-be-zero column sums to zero. Catches what only the full
 * run's rays reach: the tests above trace 64x64 (the random case's
 * miscompiled reference showed at its 4,426,048th ray: mutant 85). */
Test(stress, full_table_keeps_the_must_be_zero_columns_at_zero, .timeout = 300)
{
	char dir[256], cmd[1024];
	tu_tmpdir(dir, sizeof dir);
	snprintf(cmd, sizeof cmd, "%s/saarsim-stress --no-precision >%s/out 2>&1", tu_bin_dir(),
	         dir);
	int rc = tu_run(cmd);
	const char *out = tu_slurp(dir, "out");
	cr_assert_eq(rc, 0, "saarsim-stress's full table has a must-be-zero count:\n%s", out);
	cr_assert(strstr(out, ", full run (256x256 views).") &&
	              strstr(out, "Total of the must-be-zero columns: 0."),
	          "%s", out);
}

/* A views file given to saarsim-stress that does not load (or one view in
 * it that does not) is bad input before the long run: one line, exit 2,
 * no document (it printed a line, left the views out and exited 0). */
Test(stress, bad_views_file_is_refused_first)
{
	char dir[256], p[512], args[2048];
	tu_tmpdir(dir, sizeof dir);
	const char *files[][2] = {
	    {"views:\n  a: 1\n", "view 'a' must be a mapping"},
	    {"views:\n  a:\n    camera: {eye: [0, 0, 5], lookat: [0, 0, 5], up: [0, 1, 0], fov: "
	     "45}\n",
	     "same point"},
	};
	for (int i = 0; i < 2; i++) {
		tu_write(p, sizeof p, dir, "v.yaml", files[i][0]);
		snprintf(args, sizeof args, "--quick --views %s --out %s/n.md", p, dir);
		cr_assert_eq(tu_prog(dir, "saarsim-stress", args), 2, "case %d", i);
		tu_one_line(dir, "saarsim-stress", files[i][1]);
		cr_assert_not(tu_exists(dir, "n.md"));
	}
	snprintf(args, sizeof args, "--quick --views %s/none.yaml --out %s/n.md", dir, dir);
	cr_assert_eq(tu_prog(dir, "saarsim-stress", args), 2);
	tu_one_line(dir, "saarsim-stress", "cannot open views file");
}

/* Without --out the stress tool writes nothing: it rewrote
 * docs/NUMERICS.md and docs/precision.png relative to the folder it was
 * run in. With --out it splices its tables into that document only. */
Test(stress, writes_only_the_document_asked_for)
{
	char dir[256], sub[512], p[1024], cmd[4096];
	tu_tmpdir(dir, sizeof dir);
	snprintf(sub, sizeof sub, "%s/docs", dir);
	cr_assert_eq(mkdir(sub, 0755), 0);
	tu_write(p, sizeof p, sub, "NUMERICS.md", "precious\n");
	snprintf(cmd, sizeof cmd, "cd %s && %s/saarsim-stress --quick --no-precision >out 2>err",
	         dir, tu_bin_dir());
	cr_assert_eq(tu_run(cmd), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_str_eq(tu_slurp(sub, "NUMERICS.md"), "precious\n", "the document was rewritten");
	cr_assert(strstr(tu_slurp(dir, "out"), "| case |"), "no table on stdout");
	tu_write(p, sizeof p, dir, "n.md",
	         "a\n<!-- BEGIN stress -->\nold\n<!-- END stress -->\nb\n");
	snprintf(cmd, sizeof cmd, "--quick --no-precision --out %s", p);
	cr_assert_eq(tu_prog(dir, "saarsim-stress", cmd), 0, "%s", tu_slurp(dir, "err"));
	const char *n = tu_slurp(dir, "n.md");
	cr_assert(strstr(n, "| case |") && !strstr(n, "old") && !strncmp(n, "a\n", 2),
	          "the document was not spliced: %s", n);
}

/* --help prints the usage on stdout and exits 0 in every program (the
 * replay and stress tools exited 2). */
Test(stress, every_program_has_help)
{
	char dir[256];
	tu_tmpdir(dir, sizeof dir);
	const char *progs[] = {"rtref", "saarsim", "saarsim-replay", "saarsim-stress"};
	for (int i = 0; i < 4; i++) {
		cr_assert_eq(tu_prog(dir, progs[i], "--help"), 0, "%s --help", progs[i]);
		cr_assert(strstr(tu_slurp(dir, "out"), "usage: "), "%s: no usage", progs[i]);
		cr_assert_str_eq(tu_slurp(dir, "err"), "", "%s wrote to stderr", progs[i]);
	}
}
