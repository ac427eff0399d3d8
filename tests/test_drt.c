/*
 * test_drt.c: distribution ray tracing (seed 000; kernel-ref/drt.h,
 * kernel-ref/sudoku.h): the Sudoku patterns and tiling, the thin lens,
 * area lights, glossy reflection, motion blur, samples per pixel, the
 * packets, the views-file and flag checks, and the chip's frame against
 * kernel-ref's. Each test names the mistake it catches; the oracles are
 * computed in double where they can be.
 */
#include "kernel-ref/cone.h"
#include "kernel-ref/drt.h"
#include "kernel-ref/spd.h"
#include "kernel-ref/sudoku.h"
#include "tests/chiptest.h"

/* ---- the Sudoku patterns (seed 000 §4) ---- */

/* Mistake: a typo in the transcription of the seed's Figure 14 (a digit
 * twice in a row, column or bordered block), or an order-2 grid that is
 * not a Sudoku: the patterns would no longer be Latin squares. */
Test(drt, the_grids_are_sudoku_solutions)
{
	for (int i = 0; i < SUDOKU_N; i++) {
		unsigned row = 0, col = 0, blk = 0;
		for (int j = 0; j < SUDOKU_N; j++) {
			row |= 1u << sudoku_grid[i][j];
			col |= 1u << sudoku_grid[j][i];
			blk |= 1u << sudoku_grid[(i / 4) * 4 + j / 4][(i % 4) * 4 + j % 4];
		}
		cr_assert_eq(row, 0xffffu, "row %d", i);
		cr_assert_eq(col, 0xffffu, "column %d", i);
		cr_assert_eq(blk, 0xffffu, "block %d", i);
	}
	for (int i = 0; i < 4; i++) {
		unsigned row = 0, col = 0, q = 0;
		for (int j = 0; j < 4; j++) {
			row |= 1u << sudoku_grid2[i][j];
			col |= 1u << sudoku_grid2[j][i];
			q |= 1u << sudoku_grid2[(i / 2) * 2 + j / 2][(i % 2) * 2 + j % 2];
		}
		cr_assert(row == 15 && col == 15 && q == 15, "order-2 line %d", i);
	}
}

/* The cell of the n x n lattice a sample lies in, checked to be its
 * centre (the cooperative patterns sit on the lattice). */
static void cell(float u, float v, int n, int *cx, int *cy)
{
	double x = (double)u * n - 0.5, y = (double)v * n - 0.5;
	*cx = (int)lround(x);
	*cy = (int)lround(y);
	cr_assert(fabs(x - *cx) < 1e-6 && fabs(y - *cy) < 1e-6, "(%g, %g) is off the lattice", u,
	          v);
	cr_assert(*cx >= 0 && *cx < n && *cy >= 0 && *cy < n);
}

/* Mistake: a pixel's samples are not a Latin square stratified in 2D (two
 * samples in one row, column or block: col_of or the permutation of the
 * samples wrong), or the 16 pixels of a 4x4 block do not cooperate (their
 * samples merged are not the whole 256-point lattice: a tiling that
 * repeats a pattern). Every dimension, every pixel of a 16x16 tile. */
Test(drt, patterns_are_latin_and_cooperative)
{
	for (int dim = 0; dim < 24; dim++)
		for (int by = 0; by < 16; by += 4)
			for (int bx = 0; bx < 16; bx += 4) {
				uint8_t seen[16][16] = {{0}};
				for (int p = 0; p < 16; p++) {
					uint32_t x = (uint32_t)(bx + p % 4),
					         y = (uint32_t)(by + p / 4);
					unsigned rows = 0, cols = 0, blks = 0;
					for (int s = 0; s < 16; s++) {
						float u, v;
						int cx, cy;
						sudoku_sample(x, y, s, dim, 16, &u, &v);
						cell(u, v, 16, &cx, &cy);
						rows |= 1u << cy;
						cols |= 1u << cx;
						blks |= 1u << (cy / 4 * 4 + cx / 4);
						seen[cy][cx]++;
					}
					cr_assert(rows == 0xffff && cols == 0xffff &&
					              blks == 0xffff,
					          "dim %d pixel (%u,%u): not a Sudoku pattern", dim,
					          x, y);
				}
				for (int i = 0; i < 256; i++)
					cr_assert_eq(
					    seen[i / 16][i % 16], 1,
					    "dim %d block (%d,%d): lattice point %d used %d times",
					    dim, bx, by, i, seen[i / 16][i % 16]);
			}
}

/* Mistake: 4 or 64 samples per pixel that repeat a point or leave the
 * Latin arrangement (4: one per row and column of the 4x4 grid and per
 * quadrant; 64: four patterns, so four per row and column of the 16x16
 * lattice, no point twice). */
Test(drt, four_and_sixty_four_samples_are_stratified)
{
	for (int dim = 0; dim < 8; dim++)
		for (uint32_t y = 0; y < 16; y++)
			for (uint32_t x = 0; x < 16; x++) {
				unsigned rows = 0, cols = 0, q = 0;
				for (int s = 0; s < 4; s++) {
					float u, v;
					int cx, cy;
					sudoku_sample(x, y, s, dim, 4, &u, &v);
					cell(u, v, 4, &cx, &cy);
					rows |= 1u << cy;
					cols |= 1u << cx;
					q |= 1u << (cy / 2 * 2 + cx / 2);
				}
				cr_assert(rows == 15 && cols == 15 && q == 15,
				          "4 spp, pixel (%u,%u)", x, y);
				uint8_t seen[16][16] = {{0}}, nr[16] = {0}, nc[16] = {0};
				for (int s = 0; s < 64; s++) {
					float u, v;
					int cx, cy;
					sudoku_sample(x, y, s, dim, 64, &u, &v);
					cell(u, v, 16, &cx, &cy);
					cr_assert_eq(seen[cy][cx]++, 0, "64 spp: a point twice");
					nr[cy]++;
					nc[cx]++;
				}
				for (int i = 0; i < 16; i++)
					cr_assert(nr[i] == 4 && nc[i] == 4, "64 spp, pixel (%u,%u)",
					          x, y);
			}
}

/* Mistake: one sample per pixel the same row of the lattice in every
 * pixel (sample 0 of each pixel's pattern: every lens sample on one ring,
 * every area-light point on one line off the light's centre, every
 * glossy ray at one angle; the frame biased, not noisy). The 16 pixels of
 * every 4x4 block take 16 points with one in every row, column and 4x4
 * block of the lattice, in every dimension but the image plane's (the
 * pixel centre). */
Test(drt, one_sample_per_pixel_spreads_every_dimension)
{
	for (int dim = SUDOKU_DIM_LENS; dim < SUDOKU_DIM_GLOSS + 16; dim++)
		for (int by = 0; by < 16; by += 4)
			for (int bx = 0; bx < 16; bx += 4) {
				unsigned rows = 0, cols = 0, blks = 0;
				for (int p = 0; p < 16; p++) {
					float u, v;
					int cx, cy;
					sudoku_sample((uint32_t)(bx + p % 4),
					              (uint32_t)(by + p / 4), 0, dim, 1, &u, &v);
					cell(u, v, 16, &cx, &cy);
					rows |= 1u << cy;
					cols |= 1u << cx;
					blks |= 1u << (cy / 4 * 4 + cx / 4);
				}
				cr_assert(
				    rows == 0xffff && cols == 0xffff && blks == 0xffff,
				    "1 spp, dim %d, block (%d,%d): rows %04x cols %04x blocks %04x",
				    dim, bx, by, rows, cols, blks);
			}
}

/* Mistake: two dimensions of one ray the very same points (the tiling
 * offsets and sample orders repeated every 16 dimensions with 1, 4 and 16
 * samples: a glossy bounce took the points of a light, a 14th light those
 * of the image plane). Every pair of the 35 dimensions, at every sample
 * count, over a 16x16 tile. */
Test(drt, dimensions_are_not_the_same_points)
{
	static const int spps[] = {1, 4, 16, 64};
	for (int k = 0; k < 4; k++)
		for (int d1 = 0; d1 < SUDOKU_DIM_GLOSS + 16; d1++)
			for (int d2 = d1 + 1; d2 < SUDOKU_DIM_GLOSS + 16; d2++) {
				int same = 1;
				for (uint32_t y = 0; y < 16 && same; y++)
					for (uint32_t x = 0; x < 16 && same; x++)
						for (int s = 0; s < spps[k] && same; s++) {
							float u1, v1, u2, v2;
							sudoku_sample(x, y, s, d1, spps[k], &u1,
							              &v1);
							sudoku_sample(x, y, s, d2, spps[k], &u2,
							              &v2);
							same = u1 == u2 && v1 == v2;
						}
				cr_assert(!same, "%d spp: dimensions %d and %d are the same points",
				          spps[k], d1, d2);
			}
}

/* Mistake: one sample per pixel off the pixel centre on the image plane
 * (the default frame would change), or a sampler whose answer depends on
 * the order it is asked in (state: a random generator, a counter), which
 * would make a still view scintillate from frame to frame (seed §4). */
Test(drt, samples_are_stable_and_one_is_the_centre)
{
	float u, v;
	sudoku_sample(5, 9, 0, SUDOKU_DIM_IMAGE, 1, &u, &v);
	cr_assert(u == 0.5f && v == 0.5f);
	float first[64][2];
	for (int s = 0; s < 64; s++)
		sudoku_sample(3, 7, s, SUDOKU_DIM_LENS, 64, &first[s][0], &first[s][1]);
	for (int s = 63; s >= 0; s--) {
		sudoku_sample(11, 2, s, SUDOKU_DIM_TIME, 64, &u, &v); /* other calls between */
		sudoku_sample(3, 7, s, SUDOKU_DIM_LENS, 64, &u, &v);
		cr_assert(u == first[s][0] && v == first[s][1], "sample %d changed", s);
	}
}

/* ---- frames ---- */

static uint8_t *frame(const world *w, const view *v, int size, int threads, render_stats *st)
{
	render_opts o;
	render_opts_default(&o);
	o.width = o.height = size;
	o.threads = threads;
	framebuf fb;
	cr_assert_eq(fb_init(&fb, size, size), 0);
	render_stats own;
	diag d;
	cr_assert_eq(render_frame(&w->m, v, &o, &fb, st ? st : &own, &d), 0, "%s", d.msg);
	uint8_t *rgb = malloc((size_t)size * size * 3);
	fb_to_rgb8(&fb, rgb, NULL);
	fb_free(&fb);
	return rgb;
}

static void assert_same(const uint8_t *a, const uint8_t *b, int size, const char *what)
{
	img_cmp c = img_compare(a, b, size, size);
	cr_assert(c.identical, "%s: %llu pixels differ", what,
	          (unsigned long long)c.differing_pixels);
}

static void room(world *w)
{
	tu_load_world(w, NULL, NULL, NULL);
}

static const drt_params all_on = {16, 0.8f, 18.0f, 1.5f, 300.0f, {0.3f, 0.1f, 0}};

/* Mistake: a frame that depends on the order its packets run in or on
 * the frame before (stateful samples): every effect on, one thread twice
 * and three threads give the same frame. */
Test(drt, a_still_view_renders_the_same_frame)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	uint8_t *a = frame(&w, &w.v, 48, 1, NULL), *b = frame(&w, &w.v, 48, 1, NULL),
	        *c = frame(&w, &w.v, 48, 3, NULL);
	assert_same(a, b, 48, "the same view twice");
	assert_same(a, c, 48, "three threads");
	free(a);
	free(b);
	free(c);
	world_free(&w);
}

/* Mistake: the thin lens is not exactly the pinhole at aperture 0 (say
 * the direction taken as (eye + f d) - eye, which rounds differently
 * from d), or the focus distance leaks into a pinhole ray. */
Test(drt, aperture_zero_is_the_pinhole)
{
	world w;
	room(&w);
	w.v.drt.spp = 16;
	uint8_t *pin = frame(&w, &w.v, 40, 1, NULL);
	w.v.drt.aperture = 0;
	w.v.drt.focus = 7.25f;
	uint8_t *lens = frame(&w, &w.v, 40, 1, NULL);
	assert_same(pin, lens, 40, "aperture 0, focus 7.25");
	free(pin);
	free(lens);
	world_free(&w);
}

/* Mistake: lens rays that do not meet the pinhole ray of their image
 * sample on the focal plane (focus measured along the ray instead of the
 * view direction, l / f with the wrong sign), or a lens of the diameter
 * for its radius (r = aperture sqrt(v) instead of aperture sqrt(v) / 2).
 * Oracle in double: the pinhole point eye + f (w + px u + py v). */
Test(drt, lens_rays_meet_on_the_focal_plane)
{
	view v;
	view_default(&v);
	v.drt = (drt_params){16, 2.0f, 12.0f, 0, 0, {0, 0, 0}};
	cam_frame c;
	cam_setup_view(&c, &v, 64, 48);
	packet p;
	double maxr = 0;
	for (int s = 0; s < 16; s++) {
		cam_sample_packet(&c, 2, 3, s, &p);
		cr_assert_eq(p.sample, s);
		for (int lane = 0; lane < 64; lane++) {
			int x = 2 * 8 + lane % 8, y = 3 * 8 + lane / 8;
			float su, sv;
			sudoku_sample((uint32_t)x, (uint32_t)y, s, SUDOKU_DIM_IMAGE, 16, &su, &sv);
			double px = (2.0 * (x + (double)su) / 64 - 1) * c.sx,
			       py = (1.0 - 2.0 * (y + (double)sv) / 48) * c.sy;
			double f = 12.0, P[3], o[3] = {p.ox[lane], p.oy[lane], p.oz[lane]},
			       d[3] = {p.dx[lane], p.dy[lane], p.dz[lane]};
			double e[3] = {c.eye.x, c.eye.y, c.eye.z}, W[3] = {c.w.x, c.w.y, c.w.z},
			       U[3] = {c.u.x, c.u.y, c.u.z}, V[3] = {c.v.x, c.v.y, c.v.z};
			double ow = 0, dw = 0, r2 = 0;
			for (int k = 0; k < 3; k++) {
				P[k] = e[k] + f * (W[k] + px * U[k] + py * V[k]);
				ow += (o[k] - e[k]) * W[k];
				dw += d[k] * W[k];
				r2 += (o[k] - e[k]) * (o[k] - e[k]);
			}
			cr_assert(fabs(ow) < 1e-5, "the lens point is off the lens plane");
			maxr = fmax(maxr, sqrt(r2));
			double t = (f - ow) / dw, err = 0;
			for (int k = 0; k < 3; k++)
				err = fmax(err, fabs(o[k] + t * d[k] - P[k]));
			cr_assert(err < 1e-4 * f, "sample %d lane %d misses the focal point by %g",
			          s, lane, err);
		}
	}
	cr_assert(maxr <= 1.0 + 1e-5, "a lens point %g from the centre (radius 1)", maxr);
	cr_assert(maxr > 0.8, "lens points only within %g of the centre (radius 1)", maxr);
}

/* Mistake: an area light of size 0 whose points are not the point light
 * (moved off it, say by u instead of u - 1/2 with the square's edges
 * still applied), so soft shadows could not shrink to hard ones. Every
 * sample's point is the light's, bit for bit, for each of its lights. */
Test(drt, light_size_zero_is_the_point_light)
{
	world w;
	room(&w);
	cr_assert(w.v.nlights > 0, "the room has no light");
	w.v.drt.spp = 4;
	w.v.drt.light_size = 0;
	w.v.drt.gloss = 0;
	drt_shade ds;
	drt_shade_setup(&ds, &w.v.drt, w.v.cam.up, 40);
	for (int l = 0; l < w.v.nlights; l++)
		for (int s = 0; s < 4; s++)
			for (uint32_t px = 0; px < 40 * 40; px += 77) {
				vec3 q = drt_light_point(&ds, w.v.lights[l].pos, px, s, l);
				cr_assert(!memcmp(&q, &w.v.lights[l].pos, sizeof q),
				          "size 0 moved light %d (pixel %u, sample %d)", l, px, s);
			}
	world_free(&w);
}

/* Mistake: light points off the square (not centred on the light: u
 * instead of u - 1/2; not across the up vector) or the square the wrong
 * size. Oracle in double: each pixel's 16 points lie in the square of
 * side 2 around the light in the plane across up, their mean is the
 * light (the pattern's columns and rows are a permutation), and they
 * reach its corners' cells. */
Test(drt, area_light_points_cover_the_square)
{
	drt_params p = {16, 0, 0, 2.0f, 0, {0, 0, 0}};
	drt_shade ds;
	vec3 up = v3(0, 0, 3);
	drt_shade_setup(&ds, &p, up, 32);
	vec3 c = v3(1, 2, 5);
	for (uint32_t px = 0; px < 32 * 32; px += 37) {
		double m[3] = {0, 0, 0}, ext = 0;
		for (int s = 0; s < 16; s++) {
			vec3 q = drt_light_point(&ds, c, px, s, 1);
			double d[3] = {(double)q.x - c.x, (double)q.y - c.y, (double)q.z - c.z};
			cr_assert(fabs(d[2]) < 1e-6, "light point off the plane across up");
			cr_assert(fabs(d[0]) <= 1.0 + 1e-6 && fabs(d[1]) <= 1.0 + 1e-6,
			          "light point (%g, %g) outside the square", d[0], d[1]);
			ext = fmax(ext, fmax(fabs(d[0]), fabs(d[1])));
			for (int k = 0; k < 3; k++)
				m[k] += d[k] / 16;
		}
		cr_assert(fabs(m[0]) < 1e-6 && fabs(m[1]) < 1e-6, "mean (%g, %g) is not the light",
		          m[0], m[1]);
		cr_assert(ext > 0.9, "points reach only %g of the half side 1", ext);
	}
}

/* Mistake: the Phong lobe upside down (cos(theta) = u^(n+1) instead of
 * u^(1/(n+1))), so a huge exponent scatters instead of approaching the
 * mirror; or a lobe not around the mirror direction. Oracles in double:
 * with n = 1e6 every direction is within the lobe's angle for the
 * smallest sample, sqrt(2 ln(32) / (n + 1)), of the mirror; with n = 32
 * the mean cos(theta) over the 16 x 16 lattice is (n + 1) / (n + 2)
 * within 1%. */
Test(drt, huge_gloss_approaches_the_mirror)
{
	vec3 r = v3_norm(v3(0.3f, -0.5f, 0.8f));
	double bound = sqrt(2.0 * log(32.0) / (1e6 + 1)) * 1.01, mean = 0;
	for (int i = 0; i < 16; i++)
		for (int j = 0; j < 16; j++) {
			float u1 = ((float)i + 0.5f) / 16, u2 = ((float)j + 0.5f) / 16;
			vec3 g = drt_glossy_dir(r, 1e6f, u1, u2);
			double cg = ((double)g.x * r.x + (double)g.y * r.y + (double)g.z * r.z) /
			            sqrt((double)g.x * g.x + (double)g.y * g.y + (double)g.z * g.z);
			cr_assert(acos(fmin(1.0, cg)) <= bound, "%g rad from the mirror (bound %g)",
			          acos(fmin(1.0, cg)), bound);
			vec3 h = drt_glossy_dir(r, 32.0f, u1, u2);
			mean += ((double)h.x * r.x + (double)h.y * r.y + (double)h.z * r.z) / 256;
		}
	cr_assert(fabs(mean - 33.0 / 34.0) < 0.01 * 33.0 / 34.0, "mean cos %g, expected %g", mean,
	          33.0 / 34.0);
	/* near the first axis the frame switches (seed §3.3): still unit */
	vec3 g = drt_glossy_dir(v3(1, 0, 0), 10.0f, 0.3f, 0.6f);
	cr_assert(fabs(v3_len(g) - 1.0f) < 1e-5f);
}

/* A closed sphere of one colour around the camera, no lights: every
 * primary ray hits it, so every pixel is 0.15 Ka. */
static void inside_sphere(world *w)
{
	scene s;
	scene_init(&s, "sphere");
	material m = material_default("grey");
	m.ka = m.kd = v3(0.6f, 0.4f, 0.2f);
	uint32_t k = scene_add_material(&s, &m);
	spd_add_sphere(&s, v3(0, 0, 0), 50.0f, 24, k);
	diag d;
	cr_assert_eq(scene_finish(&s, "sphere", &d), 0, "%s", d.msg);
	tu_build_world(w, &s);
	view_default(&w->v);
	w->v.cam = (camera){v3(0, 0, 0), v3(0, 0, -1), v3(0, 1, 0), 60};
	w->v.nlights = 0;
	w->v.lights_given = 1;
}

/* Mistake: the average over samples is wrong (a weight of 1 instead of
 * 1/spp: a frame spp times too bright; a weight applied twice; samples
 * lost). Oracle: a constant scene stays the same constant at every spp,
 * with every camera effect on. */
Test(drt, samples_average_a_constant_scene_to_itself)
{
	world w;
	inside_sphere(&w);
	uint8_t *one = frame(&w, &w.v, 24, 1, NULL);
	for (int i = 3; i < 24 * 24 * 3; i += 3)
		cr_assert(!memcmp(one, one + i, 3), "the one-sample frame is not constant");
	static const int spps[] = {4, 16, 64};
	for (int k = 0; k < 3; k++) {
		w.v.drt = (drt_params){spps[k], 3.0f, 20.0f, 0, 0, {1.0f, 2.0f, 0}};
		render_stats st;
		uint8_t *many = frame(&w, &w.v, 24, 1, &st);
		cr_assert_eq(st.rays[PKT_PRIMARY], (uint64_t)24 * 24 * spps[k]);
		cr_assert_eq(st.packets[PKT_PRIMARY], (uint64_t)9 * spps[k]);
		assert_same(one, many, 24, "a constant scene");
		free(many);
	}
	free(one);
	world_free(&w);
}

/* Mistake: a secondary packet that mixes samples or loses its parent's
 * sample index (its shadow rays would all take sample 0's light point:
 * hard shadows at any light size), or holds rays of another tile or
 * type (seed §3: 64 rays of one type from one tile). */
Test(drt, packets_hold_one_type_and_sample_of_one_tile)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	cam_frame c;
	cam_setup_view(&c, &w.v, 64, 64);
	drt_shade ds;
	drt_shade_setup(&ds, &w.v.drt, w.v.cam.up, 64);
	framebuf fb;
	cr_assert_eq(fb_init(&fb, 64, 64), 0);
	shade_ctx sc = {&w.m, w.v.lights, w.v.nlights, 3, v3(0, 0, 0), &fb, NULL, &ds, NULL};
	/* aligned_alloc wants sizes that are multiples of the alignment */
#define A64(n) (((n) + 63) & ~(size_t)63)
	trav_entry *stack = aligned_alloc(64, A64(PKT_STACK_MAX * sizeof(trav_entry)));
	packet *p = aligned_alloc(64, A64(sizeof(packet))),
	       *kids = aligned_alloc(64, A64((size_t)(w.v.nlights + 2) * sizeof(packet)));
#undef A64
	shade_counts cnt = {0};
	for (int s = 0; s < 16; s += 5) {
		cam_sample_packet(&c, 3, 4, s, p);
		cr_assert_eq(__builtin_popcountll(p->valid), 64);
		pkt_trace(p, &w.m, stack, PKT_STACK_MAX, NULL);
		int n = shade_packet(&sc, p, kids, w.v.nlights + 2, NULL, &cnt);
		cr_assert_gt(n, 0);
		for (int k = 0; k < n; k++) {
			cr_assert_eq(kids[k].sample, s, "child %d lost the sample", k);
			for (uint64_t b = kids[k].valid; b; b &= b - 1) {
				uint32_t px = kids[k].pixel[__builtin_ctzll(b)];
				cr_assert(px % 64 / 8 == 3 && px / 64 / 8 == 4,
				          "a ray of another tile");
			}
			cr_assert(k == 0 || kids[k].type >= kids[k - 1].type);
		}
	}
	free(stack);
	free(p);
	free(kids);
	fb_free(&fb);
	world_free(&w);
}

/* Mistake: motion blur that is not a blur over the shutter: the camera
 * moved by the whole displacement at every time (a shifted frame), or
 * not at all. Oracle: with motion m each primary ray starts at eye + t m,
 * t a stratified time in [0, 1) whose 16 samples per pixel average 1/2;
 * and a frame with motion differs from the still one. */
Test(drt, motion_moves_the_camera_over_the_shutter)
{
	view v;
	view_default(&v);
	v.drt = (drt_params){16, 0, 0, 0, 0, {2.0f, 0, -1.0f}};
	cam_frame c;
	cam_setup_view(&c, &v, 32, 32);
	packet p;
	double sum[64] = {0};
	for (int s = 0; s < 16; s++) {
		cam_sample_packet(&c, 1, 2, s, &p);
		for (int lane = 0; lane < 64; lane++) {
			double t = ((double)p.ox[lane] - c.eye.x) / 2.0;
			cr_assert(t >= 0 && t < 1, "time %g outside the shutter", t);
			cr_assert(fabs(((double)p.oz[lane] - c.eye.z) + t) < 1e-5,
			          "origin off the motion's line");
			sum[lane] += t / 16;
		}
	}
	for (int lane = 0; lane < 64; lane++)
		cr_assert(fabs(sum[lane] - 0.5) < 1e-5, "mean time %g, not 1/2", sum[lane]);
	/* and the frame loop uses it: a render whose camera is set up
	 * without the view's motion draws the still frame */
	world w;
	room(&w);
	w.v.drt.spp = 16;
	uint8_t *still = frame(&w, &w.v, 32, 1, NULL);
	w.v.drt.motion = v3(0.5f, 0, 0);
	uint8_t *moved = frame(&w, &w.v, 32, 1, NULL);
	cr_assert(memcmp(still, moved, 32 * 32 * 3), "motion (0.5, 0, 0) left the frame still");
	free(still);
	free(moved);
	world_free(&w);
}

/* ---- input ---- */

/* Mistake: a bad DRT value taken (or crashing) instead of one line and
 * exit status 2, in a views file (file:line:col at the value) or a flag. */
Test(drt, bad_values_are_refused)
{
	char dir[64], vf[512];
	tu_tmpdir(dir, sizeof dir);
	static const struct {
		const char *drt, *what;
	} bad[] = {
	    {"{spp: 3}", ":4:16: spp must be 1, 4, 16 or 64"},
	    {"{spp: 16.5}", ":4:16: spp must be"},
	    {"{aperture: -1}", ":4:21: aperture must be"},
	    {"{gloss: 0.5}", ":4:18: gloss must be 0"},
	    {"{light_size: .nan}", "not a finite number"},
	    {"{motion: [1, 2]}", "motion must have exactly 3 numbers"},
	    {"{focus: 1e10}", "focus must be"},
	    {"{blur: 1}", "unknown key 'blur'"},
	    {"[16]", "drt of view 'v' must be a mapping"},
	};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		char text[512];
		snprintf(
		    text, sizeof text,
		    "views:\n  v:\n    camera: {eye: [5, 5, 22], lookat: [5, 5, 0], up: [0, 1, "
		    "0], fov: 45}\n    drt: %s\n",
		    bad[k].drt);
		tu_write(vf, sizeof vf, dir, "v.yaml", text);
		char args[1024];
		snprintf(args, sizeof args, "--views %s --view v --size 8x8", vf);
		cr_assert_eq(tu_prog(dir, "rtref", args), 2, "%s", bad[k].drt);
		tu_one_line(dir, "rtref", bad[k].what);
	}
	static const struct {
		const char *args, *what;
	} flags[] = {
	    {"--spp 5", "--spp: spp must be 1, 4, 16 or 64"},
	    {"--spp x", "--spp: expected an integer"},
	    {"--aperture -1", "--aperture: -1 is out of range"},
	    {"--gloss 0.25", "--gloss: gloss must be 0"},
	    {"--motion 1,2", "--motion: expected X,Y,Z"},
	    {"--light-size inf", "--light-size: expected a number"},
	};
	for (size_t k = 0; k < sizeof flags / sizeof *flags; k++) {
		char args[256];
		snprintf(args, sizeof args, "%s --size 8x8", flags[k].args);
		cr_assert_eq(tu_prog(dir, "rtref", args), 2, "%s", flags[k].args);
		tu_one_line(dir, "rtref", flags[k].what);
		cr_assert_eq(tu_prog(dir, "saarsim", args), 2, "%s", flags[k].args);
		tu_one_line(dir, "saarsim", flags[k].what);
	}
}

/* ---- the benchmark views ---- */

/* Mistake: configs/drt-views.yaml naming a scene that does not resolve
 * (a procedural spd: name taken as a path under configs/, a shared scene
 * at the wrong relative path or copied into the repository), or a view
 * with an effect left off. Every view has all five effects at 16 spp,
 * and the billiard view renders (its DRT frame differs from its pinhole
 * frame). */
Test(drt, the_drt_views_file_has_every_effect)
{
	static const char *const names[] = {"billiard-drt", "cornell-drt", "conference-drt"};
	for (int k = 0; k < 3; k++) {
		view v;
		diag d;
		cr_assert_eq(view_load(&v, "configs/drt-views.yaml", names[k], &d), 0, "%s", d.msg);
		const drt_params *p = &v.drt;
		cr_assert(p->spp == 16 && p->aperture > 0 && p->light_size > 0 && p->gloss > 0 &&
		              v3_len(p->motion) > 0,
		          "%s: an effect is off", names[k]);
		if (k == 0) {
			cr_assert_str_eq(v.scene, "spd:billiard");
			continue;
		}
		cr_assert(strstr(v.scene, "configs/../../shared/scenes/") == v.scene,
		          "%s: the scene %s is not the shared one", names[k], v.scene);
		char rel[1024];
		SCENE_OR_SKIP(rel, strstr(v.scene, "scenes/") + strlen("scenes/"));
		cr_assert_eq(access(v.scene, R_OK), 0, "%s: %s is not there", names[k], v.scene);
	}
	world w;
	tu_load_world(&w, NULL, "configs/drt-views.yaml", "billiard-drt");
	cr_assert_str_eq(w.s.name, "spd:billiard");
	uint8_t *a = frame(&w, &w.v, 32, 2, NULL);
	w.v.drt = (drt_params){0};
	uint8_t *b = frame(&w, &w.v, 32, 2, NULL);
	cr_assert(!img_compare(a, b, 32, 32).identical, "the DRT frame is the pinhole frame");
	free(a);
	free(b);
	world_free(&w);
}

/* ---- the chip (issue 32 item 2) ---- */

/* Runs the chip on w at size x size with fidelity fid and checks its
 * frame and its rays per type against kernel-ref's. */
static void chip_matches(const world *w, int size, int fid, const char *what)
{
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = size;
	c.fidelity = fid;
	render_stats st;
	uint8_t *ref = tu_reference(w, &c, &st);
	free(ref);
	chip *ch = tu_run_chip(w, &c);
	tu_assert_identical(ch, what);
	for (int t = 0; t < PKT_NTYPES; t++) {
		char nm[64];
		snprintf(nm, sizeof nm, "rays.%s", pkt_type_name(t));
		cr_assert_eq(stats_get(&ch->st, nm), st.rays[t], "%s: %s", what, nm);
	}
	cr_assert_eq(stats_get(&ch->st, "trav.node_steps"), st.trav.node_steps, "%s", what);
	chip_destroy(ch);
}

/* Mistakes: the chip generating only a tile's first sample (the other
 * spp - 1 primary packets lost: a dark frame, too few primary rays), its
 * camera set up as a pinhole (cam_setup instead of cam_setup_view: no
 * depth of field, no motion), its shader without the area lights and
 * gloss (sc.drt unset). A 16-spp frame with every effect on is kernel-
 * ref's, pixel for pixel, on the embedded room in cycle and functional
 * fidelity. */
Test(drt, chip_frame_equals_kernel_ref)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	chip_matches(&w, 24, CFG_FIDELITY_CYCLE, "room, cycle");
	chip_matches(&w, 24, CFG_FIDELITY_FUNCTIONAL, "room, functional");
	world_free(&w);
}

/* The same on the billiard table and a shared scene, the DRT views of
 * configs/drt-views.yaml (issue 32: "renders identically on the chip and
 * in kernel-ref, on the billiard scene and on a shared scene"). */
Test(drt, chip_frame_equals_kernel_ref_on_the_drt_views)
{
	char rel[1024];
	SCENE_OR_SKIP(rel, "cornell_box/CornellBox.obj");
	static const char *const names[] = {"billiard-drt", "cornell-drt"};
	for (int k = 0; k < 2; k++) {
		world w;
		tu_load_world(&w, NULL, "configs/drt-views.yaml", names[k]);
		chip_matches(&w, 24, CFG_FIDELITY_CYCLE, names[k]);
		world_free(&w);
	}
}

/* ---- the figures per ray type (issue 32 item 2) ---- */

/* The chip's counts of packets of type t against kernel-ref's, which
 * splits its own traversal counts by the type of the packet it traces
 * (render_stats.trav_type). With caches, each kd-node step is one L1 kd
 * lookup and each packet-triangle test one L1 tri lookup (an 8-byte node
 * and a 36-byte record never straddle a line), so the L1 lookups by ray
 * type must equal the type's own steps and tests. */
static void types_match(const world *w, int fid, const char *what)
{
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = 24;
	c.fidelity = fid;
	render_stats st;
	free(tu_reference(w, &c, &st));
	chip *ch = tu_run_chip(w, &c);
	hier_stats hs;
	cr_assert_eq(hier_get_stats(&ch->mem, &hs), 0, "%s: the default memory has L1s", what);
	int shadow_seen = 0;
	for (int t = 0; t < PKT_NTYPES; t++) {
		uint64_t *const *ct = ch->env.ct[t];
		const trav_counts *k = &st.trav_type[t];
		const char *tn = pkt_type_name(t);
		cr_assert_eq(*ct[TC_NODE_STEPS], k->node_steps, "%s: %s kd steps", what, tn);
		cr_assert_eq(*ct[TC_LEAF_VISITS], k->leaf_visits, "%s: %s leaves", what, tn);
		/* kernel-ref counts a leaf's entries as its tests; the chip
		 * tests them in turn and a shadow packet stops when every ray
		 * is occluded, so only the entries compare for shadows */
		cr_assert_eq(*ct[TC_LIST_ENTRIES], k->tri_tests, "%s: %s list entries", what, tn);
		if (t == PKT_SHADOW) {
			cr_assert_leq(*ct[TC_TRI_TESTS], k->tri_tests, "%s: %s tests", what, tn);
			cr_assert_leq(*ct[TC_RAY_TRI_TESTS], k->ray_tri_tests, "%s: %s", what, tn);
		} else {
			cr_assert_eq(*ct[TC_TRI_TESTS], k->tri_tests, "%s: %s tests", what, tn);
			cr_assert_eq(*ct[TC_RAY_TRI_TESTS], k->ray_tri_tests, "%s: %s ray tests",
			             what, tn);
		}
		cr_assert_eq(hs.ray_lookups[t][MEM_KD], k->node_steps, "%s: %s kd lookups", what,
		             tn);
		cr_assert_eq(hs.ray_lookups[t][MEM_TRI], *ct[TC_TRI_TESTS], "%s: %s tri lookups",
		             what, tn);
		/* a type with packets took RGS cycles (generation or shading) */
		cr_assert_eq(*ct[TC_BUSY + UNIT_RGS] > 0, st.packets[t] > 0, "%s: %s RGS cycles",
		             what, tn);
		shadow_seen |= t == PKT_SHADOW && k->node_steps > 0;
	}
	cr_assert(shadow_seen, "%s: the view has shadow packets that traverse", what);
	chip_destroy(ch);
}

/* Mistakes: a count made under the wrong packet type (a shadow packet's
 * kd steps or triangle tests counted as primary: the type not set as a
 * packet enters, or a type counter indexed by the counter's id), or an
 * L1 lookup tagged with the wrong ray type (the read's tag not taken from
 * the thread's packet). The split is compared with kernel-ref's own,
 * made per traced packet, in cycle and functional fidelity, on the room
 * with every effect on (primary, shadow and glossy reflection packets). */
Test(drt, counts_by_ray_type_equal_kernel_ref)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	types_match(&w, CFG_FIDELITY_CYCLE, "room, cycle");
	types_match(&w, CFG_FIDELITY_FUNCTIONAL, "room, functional");
	world_free(&w);
}

/* Mistake: a unit's issue cycles or an L1's hits left out of the split in
 * one mode (the functional sink not counting them by type): the report's
 * invariant (the split adds up to the totals) fails. Checked directly on
 * a spoiled figure, then on a sampled run. */
Test(drt, the_split_adds_up_to_the_totals)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = 24;
	c.fidelity = CFG_FIDELITY_SAMPLED;
	chip *ch = tu_run_chip(&w, &c); /* its invariants hold */
	rc_figs f;
	rc_list l;
	cr_assert_eq(rc_figs_get(ch, &f), 0);
	cr_assert_eq(rc_check(&f, &l), 0, "%s", l.msg[0]);
	f.by_type[TC_BUSY + UNIT_ISECT]--;
	cr_assert_geq(rc_check(&f, &l), 1, "a lost issue cycle is seen");
	f.by_type[TC_BUSY + UNIT_ISECT]++;
	f.h.ray_hits[PKT_SHADOW][MEM_TRI]++;
	cr_assert_geq(rc_check(&f, &l), 1, "an extra hit is seen");
	rc_figs_free(&f);
	chip_destroy(ch);
	world_free(&w);
}

/* ---- cone culling (seed 004; issue 32 item 4) ---- */

/* The ray p + t d (t >= 0) meets triangle tr, in double (Moller-Trumbore
 * with a tolerance that counts grazing hits as hits). */
static int ray_meets(const double *o, const double *d, const mimg_tri *tr)
{
	double e1[3], e2[3], s[3], pv[3], qv[3];
	for (int k = 0; k < 3; k++) {
		e1[k] = (double)tr->v[1][k] - tr->v[0][k];
		e2[k] = (double)tr->v[2][k] - tr->v[0][k];
		s[k] = o[k] - tr->v[0][k];
	}
	pv[0] = d[1] * e2[2] - d[2] * e2[1];
	pv[1] = d[2] * e2[0] - d[0] * e2[2];
	pv[2] = d[0] * e2[1] - d[1] * e2[0];
	double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
	if (fabs(det) < 1e-12)
		return 0;
	double u = (s[0] * pv[0] + s[1] * pv[1] + s[2] * pv[2]) / det;
	qv[0] = s[1] * e1[2] - s[2] * e1[1];
	qv[1] = s[2] * e1[0] - s[0] * e1[2];
	qv[2] = s[0] * e1[1] - s[1] * e1[0];
	double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
	double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
	return u >= -1e-6 && v >= -1e-6 && u + v <= 1 + 1e-6 && t >= -1e-6;
}

static double urand(uint64_t *s)
{
	*s = *s * 6364136223846793005ull + 1442695040888963407ull;
	return (double)(*s >> 11) / 9007199254740992.0;
}

/* Mistakes: a cone that does not hold every ray (the apex left at the
 * origins' centroid, ignoring their spread: lens and area-light rays
 * start apart; the half angle taken from one ray only; the sphere test's
 * sign or the triangle's radius wrong): some culled triangle is met by a
 * ray of the packet. 2000 random packets (spread origins, directions in a
 * random lobe) against triangles near them, the hits checked in double;
 * and culling must happen (a cone that culls nothing passes trivially). */
Test(drt, cone_culls_only_triangles_no_ray_meets)
{
	uint64_t seed = 12345;
	int culled = 0, kept = 0;
	for (int it = 0; it < 2000; it++) {
		packet p;
		pkt_clear(&p, PKT_PRIMARY, 0);
		double spread = urand(&seed) * 0.5, lobe = urand(&seed) * 0.6;
		for (int i = 0; i < PKT_RAYS; i++) {
			p.ox[i] = (float)((urand(&seed) - 0.5) * spread);
			p.oy[i] = (float)((urand(&seed) - 0.5) * spread);
			p.oz[i] = (float)((urand(&seed) - 0.5) * spread);
			p.dx[i] = (float)((urand(&seed) - 0.5) * lobe);
			p.dy[i] = (float)((urand(&seed) - 0.5) * lobe);
			p.dz[i] = 1.0f;
		}
		p.valid = ~0ull;
		pkt_cone c;
		cone_build(&c, &p, p.valid);
		cr_assert(!c.all, "a lobe of %g spreads less than CONE_MAX_PHI", lobe);
		for (int k = 0; k < 20; k++) {
			mimg_tri tr;
			double cx = (urand(&seed) - 0.5) * 6, cy = (urand(&seed) - 0.5) * 6,
			       cz = urand(&seed) * 6 - 1, sz = urand(&seed) * 0.5;
			for (int j = 0; j < 3; j++) {
				tr.v[j][0] = (float)(cx + (urand(&seed) - 0.5) * sz);
				tr.v[j][1] = (float)(cy + (urand(&seed) - 0.5) * sz);
				tr.v[j][2] = (float)(cz + (urand(&seed) - 0.5) * sz);
			}
			if (!cone_culls_tri(&c, &tr)) {
				kept++;
				continue;
			}
			culled++;
			for (int i = 0; i < PKT_RAYS; i++) {
				double o[3] = {p.ox[i], p.oy[i], p.oz[i]},
				       d[3] = {p.dx[i], p.dy[i], p.dz[i]};
				cr_assert(!ray_meets(o, d, &tr),
				          "packet %d: culled triangle %d is met by ray %d", it, k,
				          i);
			}
		}
	}
	cr_assert(culled > 1000 && kept > 1000, "culled %d, kept %d", culled, kept);
}

/* The chip's frame and kernel-ref's with cone culling on w (cycle or
 * functional fidelity): the chip's cone counts equal kernel-ref's, and
 * the frame equals the one without culling. Returns the triangles
 * culled. */
static uint64_t cone_run(const world *w, int fid, const char *what)
{
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = 24;
	c.fidelity = fid;
	render_stats st;
	uint8_t *off = tu_reference(w, &c, NULL);
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = 24;
	ro.max_depth = c.shading.max_depth;
	ro.cone_cull = 1;
	framebuf fb;
	diag d;
	cr_assert_eq(fb_init(&fb, 24, 24), 0);
	cr_assert_eq(render_frame(&w->m, &w->v, &ro, &fb, &st, &d), 0, "%s", d.msg);
	uint8_t *on = malloc(24 * 24 * 3);
	cr_assert(on);
	fb_to_rgb8(&fb, on, NULL);
	fb_free(&fb);
	cr_assert(!memcmp(on, off, 24 * 24 * 3), "%s: kernel-ref's frame changes with culling",
	          what);
	c.chip.cone_cull = true;
	chip *ch = tu_run_chip(w, &c);
	tu_assert_identical(ch, what);
	uint64_t culled = stats_get(&ch->st, "cone.culled");
	cr_assert_eq(culled, st.trav.cone_culled, "%s: triangles culled", what);
	cr_assert_eq(stats_get(&ch->st, "cone.saved_ray_tests"), st.trav.cone_saved_ray_tests,
	             "%s: ray tests saved", what);
	/* every packet that entered the box built a cone; every triangle a
	 * packet reached was tested against it */
	cr_assert_eq(stats_get(&ch->st, "cone.tests"),
	             stats_get(&ch->st, "isect.tri_tests") + culled, "%s: cone tests", what);
	chip_destroy(ch);
	free(on);
	free(off);
	return culled;
}

/* Mistakes: culling that changes the image (a non-conservative cone on
 * the chip or in kernel-ref, or the chip testing the cone against the
 * wrong triangle record), the chip culling other triangles than kernel-
 * ref (its cone built from all valid rays instead of those that entered
 * the box, or from the packet before it was clipped), and the cone tests
 * not counted where they are made. On the room with every effect on and
 * on the billiard table, cycle and functional fidelity. */
Test(drt, cone_culling_keeps_the_image)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	uint64_t n = cone_run(&w, CFG_FIDELITY_CYCLE, "room, cycle");
	n += cone_run(&w, CFG_FIDELITY_FUNCTIONAL, "room, functional");
	world_free(&w);
	tu_load_world(&w, NULL, "configs/drt-views.yaml", "billiard-drt");
	n += cone_run(&w, CFG_FIDELITY_CYCLE, "billiard, cycle");
	world_free(&w);
	cr_assert(n > 0, "culling happened");
}

/* Mistake: the cone test charged as a ray op (64 rays' issue cycles on a
 * masked chip) or not at all, or the cone's build not charged to the RGS:
 * with culling on, the intersection unit's busy cycles are the packet
 * tests' plus one cycle per cone test, and the RGS's grow by one op of
 * the entering rays per packet. */
Test(drt, cone_costs_are_charged_to_their_units)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = 16;
	c.fidelity = CFG_FIDELITY_FUNCTIONAL;
	chip *a = tu_run_chip(&w, &c);
	c.chip.cone_cull = true;
	chip *b = tu_run_chip(&w, &c);
	uint64_t ia = 0, ib = 0, ra = 0, rb = 0;
	for (int r = 0; r < a->nrtp; r++) {
		ia += *a->rtp[r].u[UNIT_ISECT].busy;
		ib += *b->rtp[r].u[UNIT_ISECT].busy;
		ra += *a->rtp[r].u[UNIT_RGS].busy;
		rb += *b->rtp[r].u[UNIT_RGS].busy;
	}
	uint64_t per = thr_unit_issue(&a->rtp[0].u[UNIT_ISECT], PKT_RAYS);
	uint64_t culled = stats_get(&b->st, "cone.culled");
	cr_assert_eq(ib, ia - culled * per + stats_get(&b->st, "cone.tests"), "isect busy cycles");
	cr_assert_eq(rb,
	             ra + stats_get(&b->st, "cone.packets") *
	                      thr_unit_issue(&a->rtp[0].u[UNIT_RGS], PKT_RAYS),
	             "RGS busy cycles");
	chip_destroy(a);
	chip_destroy(b);
	world_free(&w);
}

/* ---- sampled fidelity (issue 32 item 5) ---- */

/* Mistakes: a tile's further samples lost beyond a fixed count (the spawn
 * or the RTP queue sized for 16 samples: planted, 4096 pixels differ), or
 * lost between the sampled mode's regions and functional stretches (they
 * queue at the RTP like children). 64 samples per pixel with every effect
 * on, units of 8 tiles so the frame is estimated (not every tile
 * detailed): the frame is kernel-ref's and every primary ray is counted. */
Test(drt, sampled_fidelity_with_many_samples)
{
	world w;
	room(&w);
	w.v.drt = all_on;
	w.v.drt.spp = 64;
	saar_config c;
	cfg_defaults(&c);
	c.frame.width = c.frame.height = 64;
	c.fidelity = CFG_FIDELITY_SAMPLED;
	/* 8 threads, so that 3 units of 8 tiles and their warm-ups leave
	 * tiles to estimate (a unit holds a tile per thread at least) */
	c.chip.threads_per_rtp = 2;
	c.sampling.rate = 0.1;
	c.sampling.unit_tiles = 8;
	c.sampling.warmup_tiles = 2;
	c.sampling.min_units = 3;
	chip *ch = tu_run_chip(&w, &c);
	cr_assert(!ch->fid.exact, "the frame is estimated, not every tile detailed");
	tu_assert_identical(ch, "room, 64 spp, sampled");
	cr_assert_eq(stats_get(&ch->st, "rays.primary"), 64u * 64u * 64u, "every sample traced");
	chip_destroy(ch);
	world_free(&w);
}
