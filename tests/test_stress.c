/*
 * test_stress.c: the fast part of the numerical stress suite (issue 7).
 * `make stress` runs larger versions and writes docs/NUMERICS.md. Every
 * count asserted zero here is one that must stay zero.
 */
#include "stress.h"
#include "testutil.h"

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

Test(stress, random_rays_vs_double_precision)
{
	stress_result r = stress_random(200000, 7);
	zero(r);
	/* ties exist but are rare: a handful per 100k at most */
	cr_assert_lt(r.ties, r.rays / 1000, "%llu ties", (unsigned long long)r.ties);
}
