/*
 * grid.c: the uniform grid's per-frame build and its macrocells (seed 003
 * §3 and §2.4; see grid.h).
 */
#include "kernel-ref/grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

void grid_params_default(grid_params *p)
{
	p->lambda = 5.0;
	p->macro = 6;
	p->packet = 8;
	p->mailbox = 1;
	p->cull = 1;
}

static ray_hit tracer_ray(const void *ctx, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c)
{
	grid_counts gc = {0};
	ray_hit h = grid_ray_trace(ctx, o, d, tmax, any_hit, c ? &gc : NULL);
	if (c)
		grid_counts_add(c, &gc);
	return h;
}

static uint64_t tracer_packet(const void *ctx, packet *p, trav_entry *stack, int stack_max,
                              trav_counts *c)
{
	grid_counts gc = {0};
	uint64_t e = grid_pkt_trace(ctx, p, stack, stack_max, c ? &gc : NULL);
	if (c)
		grid_counts_add(c, &gc);
	return e;
}

void grid_counts_add(trav_counts *t, const grid_counts *c)
{
	t->node_steps += c->slices;
	t->leaf_visits += c->cells;
	t->tri_tests += c->tri_tests;
	t->ray_tri_tests += c->ray_tri_tests;
}

/* The resolution by the lambda heuristic (§3): cubic cells, lambda N of
 * them. A flat box (a single plane of triangles) gets one cell across. */
static void grid_resolution(grid *g, const double ext[3], uint32_t ntris, double lambda)
{
	double emax = fmax(ext[0], fmax(ext[1], ext[2]));
	double vol = 1.0;
	int live = 0;
	for (int a = 0; a < 3; a++)
		if (ext[a] > emax * 1e-3) {
			vol *= ext[a];
			live++;
		}
	/* the cell side s: (lambda N) cells of s^live fill the live extents */
	double cells = fmax(1.0, lambda * (double)ntris);
	double s = live ? pow(vol / cells, 1.0 / live) : 1.0;
	for (int a = 0; a < 3; a++) {
		double k = ext[a] > emax * 1e-3 && s > 0 ? ext[a] / s : 1.0;
		g->n[a] = k < 1.0 ? 1 : k > GRID_MAX_RES ? GRID_MAX_RES : (int)k;
	}
}

/* The cells a triangle's box overlaps, widened by eps cells. */
static void tri_cells(const grid *g, const mimg_tri *t, int lo[3], int hi[3])
{
	for (int a = 0; a < 3; a++) {
		double mn = fmin(t->v[0][a], fmin(t->v[1][a], t->v[2][a]));
		double mx = fmax(t->v[0][a], fmax(t->v[1][a], t->v[2][a]));
		double l = floor((mn - g->lo[a]) * g->scale[a] - g->eps);
		double h = floor((mx - g->lo[a]) * g->scale[a] + g->eps);
		lo[a] = l < 0 ? 0 : l >= g->n[a] ? g->n[a] - 1 : (int)l;
		hi[a] = h < 0 ? 0 : h >= g->n[a] ? g->n[a] - 1 : (int)h;
	}
}

/* Counting pass: references per cell into first[c + 1]; the total. */
static uint64_t count_refs(const grid *g, uint32_t *first)
{
	uint64_t total = 0;
	for (uint32_t i = 0; i < g->m->ntris; i++) {
		int lo[3], hi[3];
		tri_cells(g, mimg_tri_at(g->m, (uint32_t)mimg_tri_addr(g->m, i)), lo, hi);
		total += (uint64_t)(hi[0] - lo[0] + 1) * (uint64_t)(hi[1] - lo[1] + 1) *
		         (uint64_t)(hi[2] - lo[2] + 1);
		if (!first)
			continue;
		for (int z = lo[2]; z <= hi[2]; z++)
			for (int y = lo[1]; y <= hi[1]; y++)
				for (int x = lo[0]; x <= hi[0]; x++)
					first[grid_cell(g, x, y, z) + 1]++;
	}
	return total;
}

/* Filling pass: every triangle's address into its cells, in triangle
 * order (a cell's list is sorted by address). */
static void fill_refs(grid *g, uint32_t *fill)
{
	for (uint32_t i = 0; i < g->m->ntris; i++) {
		uint32_t addr = (uint32_t)mimg_tri_addr(g->m, i);
		int lo[3], hi[3];
		tri_cells(g, mimg_tri_at(g->m, addr), lo, hi);
		for (int z = lo[2]; z <= hi[2]; z++)
			for (int y = lo[1]; y <= hi[1]; y++)
				for (int x = lo[0]; x <= hi[0]; x++)
					g->refs[fill[grid_cell(g, x, y, z)]++] = addr;
	}
}

/* The macrocell flags (§2.4): a block is occupied when any cell is. */
static int build_macro(grid *g)
{
	int m = g->p.macro;
	if (m <= 0)
		return 0;
	for (int a = 0; a < 3; a++)
		g->mn[a] = (g->n[a] + m - 1) / m;
	g->macro = calloc((size_t)g->mn[0] * (size_t)g->mn[1] * (size_t)g->mn[2], 1);
	if (!g->macro)
		return -1;
	for (int z = 0; z < g->n[2]; z++)
		for (int y = 0; y < g->n[1]; y++)
			for (int x = 0; x < g->n[0]; x++) {
				uint32_t c = grid_cell(g, x, y, z);
				if (g->first[c + 1] > g->first[c])
					g->macro[((z / m) * g->mn[1] + y / m) * g->mn[0] + x / m] =
					    1;
			}
	return 0;
}

/* The box, resolution and error margin. The margin covers the rounding of
 * the grid coordinates and of the triangle test's hit (both far below a
 * thousandth of a cell at the resolutions the heuristic gives). */
static void grid_frame(grid *g, double lambda)
{
	const aabb *b = &g->m->bounds;
	double lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
	double ext[3], emax = 0, amax = 0;
	for (int a = 0; a < 3; a++) {
		ext[a] = hi[a] - lo[a];
		emax = fmax(emax, ext[a]);
		amax = fmax(amax, fmax(fabs(lo[a]), fabs(hi[a])));
	}
	if (!(emax > 0))
		emax = 1.0;
	grid_resolution(g, ext, g->m->ntris, lambda);
	double smax = 0;
	for (int a = 0; a < 3; a++) {
		/* a flat axis gets a slab of a thousandth of the largest extent */
		double pad = ext[a] > emax * 1e-3 ? 0.0 : emax * 1e-3;
		g->lo[a] = lo[a] - pad;
		g->scale[a] = g->n[a] / (ext[a] + 2 * pad);
		smax = fmax(smax, g->scale[a]);
	}
	g->eps = 1e-3 + 1e-5 * amax * smax;
}

int grid_build(grid *g, const mimg *m, const grid_params *p, diag *d)
{
	double t0 = now_ms();
	memset(g, 0, sizeof *g);
	g->p = *p;
	g->m = m;
	g->tracer = (render_tracer){g, tracer_ray, tracer_packet, NULL};
	double lambda = p->lambda;
	uint64_t total;
	/* overlapping triangles can reference far more cells than lambda N:
	 * a coarser grid until the references fit */
	for (;;) {
		grid_frame(g, lambda);
		total = count_refs(g, NULL);
		if (total <= GRID_MAX_REFS || lambda < 1e-6)
			break;
		lambda *= 0.5;
	}
	if (total > GRID_MAX_REFS)
		return diag_set(d, "grid", 0, 0, "%llu triangle references exceed the limit",
		                (unsigned long long)total);
	uint32_t ncell = (uint32_t)g->n[0] * (uint32_t)g->n[1] * (uint32_t)g->n[2];
	g->first = calloc((size_t)ncell + 1, sizeof *g->first);
	g->refs = malloc((size_t)(total ? total : 1) * sizeof *g->refs);
	uint32_t *fill = malloc((size_t)ncell * sizeof *fill);
	if (!g->first || !g->refs || !fill) {
		free(fill);
		grid_free(g);
		return diag_set(d, "grid", 0, 0, "out of memory for %u cells", ncell);
	}
	count_refs(g, g->first);
	for (uint32_t c = 0; c < ncell; c++)
		g->first[c + 1] += g->first[c];
	memcpy(fill, g->first, (size_t)ncell * sizeof *fill);
	g->nrefs = (uint32_t)total;
	fill_refs(g, fill);
	free(fill);
	if (build_macro(g)) {
		grid_free(g);
		return diag_set(d, "grid", 0, 0, "out of memory for the macrocells");
	}
	g->build_ms = now_ms() - t0;
	return 0;
}

void grid_free(grid *g)
{
	free(g->first);
	free(g->refs);
	free(g->macro);
	g->first = g->refs = NULL;
	g->macro = NULL;
}

void grid_json_fields(jsonw *j, const grid *g)
{
	jsonw_key(j, "resolution");
	jsonw_arr_begin(j);
	for (int a = 0; a < 3; a++)
		jsonw_int(j, g->n[a]);
	jsonw_arr_end(j);
	jsonw_knum(j, "lambda", g->p.lambda);
	jsonw_kint(j, "macro", g->p.macro);
	jsonw_kint(j, "packet", g->p.packet);
	jsonw_kint(j, "mailbox", g->p.mailbox);
	jsonw_kint(j, "cull", g->p.cull);
	jsonw_kuint(j, "references", g->nrefs);
}
