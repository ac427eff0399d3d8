/*
 * twolevel.c: two-level trees over the rigid objects of an AFF scene
 * (twolevel.h; seed 002 §6).
 */
#include "kernel-ref/twolevel.h"

#include "kernel-ref/isect.h"
#include "kernel-ref/xform.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define TL_LEAF  2    /* instances per BVH leaf */
#define TL_WIDEN 1e-5 /* world boxes and slabs widened by this share of their size */

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* ---- bottom level ---- */

/* Instance in's scene: its triangles (the flattened scene's gtri[first..
 * first+n), each found in its mesh through tmesh) in its node's frame. */
static int inst_scene(const aff_scene *a, const uint32_t *gtri, const uint32_t *tmesh, uint32_t n,
                      scene *s, diag *d)
{
	scene_init(s, a->path);
	material m = material_default("object");
	scene_add_material(s, &m);
	for (uint32_t k = 0; k < n; k++) {
		const aff_mesh *me = &a->mesh[tmesh[gtri[k]]];
		const uint32_t *r = a->idx + 9 * (uint64_t)gtri[k];
		vec3 p[3];
		for (int c = 0; c < 3; c++) {
			const float *v = a->pv + 3 * (uint64_t)(me->v0 + r[c]);
			p[c] = v3(v[0], v[1], v[2]);
		}
		scene_add_triangle(s, p, NULL, NULL, 0);
	}
	return scene_finish(s, a->path, d);
}

static uint32_t hash_tris(const scene *s)
{
	const unsigned char *b = (const unsigned char *)s->v;
	uint32_t h = 2166136261u ^ s->ntris;
	for (size_t i = 0; i < 3 * (size_t)s->ntris * sizeof *s->v; i++)
		h = (h ^ b[i]) * 16777619u;
	return h;
}

/* The triangles of every transform node, grouped: t->gtri holds the
 * flattened scene's triangle indices node by node (mesh order within a
 * node; aff_flatten numbers the triangles in mesh order, so a mesh's
 * triangle k is index t0 + k), tmesh[g] the mesh of triangle g; one
 * instance per node with triangles. */
static int group_instances(tl_scene *t, const aff_scene *a, uint32_t *tmesh, diag *d)
{
	uint32_t nx = a->nxf + 1;
	uint32_t *start = calloc((size_t)nx + 1, sizeof *start);
	t->gtri = malloc(((size_t)a->ntris + 1) * sizeof *t->gtri);
	if (!start || !t->gtri) {
		free(start);
		return diag_set(d, a->path, 0, 0, "out of memory for the two-level trees");
	}
	for (uint32_t i = 0; i < a->nmesh; i++)
		start[a->mesh[i].xform + 2] += a->mesh[i].ntris;
	for (uint32_t x = 0; x < nx; x++) {
		t->ninst += start[x + 1] > 0;
		start[x + 1] += start[x];
	}
	t->inst = calloc((size_t)t->ninst + 1, sizeof *t->inst);
	if (!t->inst) {
		free(start);
		return diag_set(d, a->path, 0, 0, "out of memory for the two-level trees");
	}
	for (uint32_t x = 0, k = 0; x < nx; x++)
		if (start[x + 1] > start[x])
			t->inst[k++] = (tl_inst){.xform = (int32_t)x - 1, .first = start[x]};
	for (uint32_t i = 0; i < a->nmesh; i++) {
		const aff_mesh *me = &a->mesh[i];
		for (uint32_t k = 0; k < me->ntris; k++) {
			t->gtri[start[me->xform + 1]++] = me->t0 + k;
			tmesh[me->t0 + k] = i;
		}
	}
	free(start);
	return 0;
}

/* The object of instance k: an equal one built before (same triangles in
 * their own frames: hash, then compare), or a new one. kept[] holds the
 * distinct objects' scenes, slot[] (2^n, object + 1) their hashes. */
static int find_object(tl_scene *t, uint32_t k, scene *s, scene *kept, uint32_t *slot,
                       uint32_t *hashes, uint32_t cap, const kd_params *kp, diag *d)
{
	uint32_t h = hash_tris(s), i = h & (cap - 1);
	for (; slot[i]; i = (i + 1) & (cap - 1)) {
		const scene *o = &kept[slot[i] - 1];
		if (hashes[slot[i] - 1] == h && o->ntris == s->ntris &&
		    !memcmp(o->v, s->v, 3 * (size_t)s->ntris * sizeof *s->v)) {
			t->inst[k].obj = slot[i] - 1;
			scene_free(s);
			return 0;
		}
	}
	tl_object *ob = &t->obj[t->nobj];
	ob->ntris = s->ntris;
	if (kd_build(&ob->kd, s, kp, d) || mimg_build(&ob->m, s, &ob->kd, d)) {
		kd_free(&ob->kd);
		mimg_free(&ob->m);
		scene_free(s);
		return -1;
	}
	kept[t->nobj] = *s;
	hashes[t->nobj] = h;
	t->inst[k].obj = t->nobj++;
	slot[i] = t->nobj;
	return 0;
}

static ray_hit tracer_ray(const void *ctx, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c)
{
	return tl_ray_trace(ctx, o, d, tmax, any_hit, c);
}

static uint64_t tracer_packet(const void *ctx, packet *p, trav_entry *stack, int stack_max,
                              trav_counts *c)
{
	return tl_pkt_trace(ctx, p, stack, stack_max, c);
}

/* The objects of the grouped instances (group_instances). */
static int build_objects(tl_scene *t, const aff_scene *a, const uint32_t *tmesh,
                         const kd_params *kp, diag *d)
{
	uint32_t cap = 16;
	while (cap < 2 * (uint64_t)t->ninst + 2)
		cap *= 2;
	scene *kept = calloc((size_t)t->ninst + 1, sizeof *kept);
	uint32_t *slot = calloc(cap, sizeof *slot), *hashes = calloc(t->ninst + 1u, sizeof *hashes);
	t->obj = calloc((size_t)t->ninst + 1, sizeof *t->obj);
	t->order = calloc((size_t)t->ninst + 1, sizeof *t->order);
	t->node = calloc(2 * (size_t)t->ninst + 1, sizeof *t->node);
	t->xf = calloc((size_t)t->ninst + 1, SHADE_XF_BYTES);
	int rc = 0;
	if (!kept || !slot || !hashes || !t->obj || !t->order || !t->node || !t->xf)
		rc = diag_set(d, a->path, 0, 0, "out of memory for the two-level trees");
	for (uint32_t k = 0; !rc && k < t->ninst; k++) {
		uint32_t end = k + 1 < t->ninst ? t->inst[k + 1].first : a->ntris;
		scene s;
		rc =
		    inst_scene(a, t->gtri + t->inst[k].first, tmesh, end - t->inst[k].first, &s, d);
		if (rc)
			scene_free(&s);
		else
			rc = find_object(t, k, &s, kept, slot, hashes, cap, kp, d);
	}
	for (uint32_t k = 0; kept && k < t->nobj; k++)
		scene_free(&kept[k]);
	free(kept);
	free(slot);
	free(hashes);
	return rc ? -1 : 0;
}

int tl_build(tl_scene *t, const aff_scene *a, const kd_params *kp, diag *d)
{
	double t0 = now_ms();
	memset(t, 0, sizeof *t);
	uint32_t *tmesh = malloc(((size_t)a->ntris + 1) * sizeof *tmesh);
	int rc = tmesh ? group_instances(t, a, tmesh, d)
	               : diag_set(d, a->path, 0, 0, "out of memory for the two-level trees");
	if (!rc)
		rc = build_objects(t, a, tmesh, kp, d);
	free(tmesh);
	t->tracer = (render_tracer){t, tracer_ray, tracer_packet, &t->shade};
	t->build_ms = now_ms() - t0;
	if (rc)
		tl_free(t);
	return rc ? -1 : 0;
}

void tl_free(tl_scene *t)
{
	for (uint32_t k = 0; t->obj && k < t->nobj; k++) {
		kd_free(&t->obj[k].kd);
		mimg_free(&t->obj[k].m);
	}
	free(t->obj);
	free(t->inst);
	free(t->gtri);
	free(t->order);
	free(t->node);
	free(t->xf);
	memset(t, 0, sizeof *t);
}

/* ---- top level ---- */

/* The inverse of the affine map m (row-major 3x4). */
static void affine_inverse(const double m[12], double r[12])
{
	double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9],
	       i = m[10];
	double c0 = e * i - f * h, c1 = f * g - d * i, c2 = d * h - e * g;
	double det = a * c0 + b * c1 + c * c2, s = det != 0.0 ? 1.0 / det : 0.0;
	double inv[9] = {c0 * s, (c * h - b * i) * s, (b * f - c * e) * s,
	                 c1 * s, (a * i - c * g) * s, (c * d - a * f) * s,
	                 c2 * s, (b * g - a * h) * s, (a * e - b * d) * s};
	for (int row = 0; row < 3; row++) {
		for (int col = 0; col < 3; col++)
			r[4 * row + col] = inv[3 * row + col];
		r[4 * row + 3] =
		    -(inv[3 * row] * m[3] + inv[3 * row + 1] * m[7] + inv[3 * row + 2] * m[11]);
	}
}

/* The world box of local box b under m, widened by TL_WIDEN of its size
 * (and a little more than float's rounding of its coordinates). */
static aabb world_box(const double m[12], aabb b)
{
	double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
	for (int c = 0; c < 8; c++) {
		double p[3] = {c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y,
		               c & 4 ? b.hi.z : b.lo.z};
		for (int r = 0; r < 3; r++) {
			double w = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] +
			           m[4 * r + 3];
			lo[r] = fmin(lo[r], w);
			hi[r] = fmax(hi[r], w);
		}
	}
	double e = 0;
	for (int r = 0; r < 3; r++)
		e = fmax(e, fmax(hi[r] - lo[r], fmax(fabs(lo[r]), fabs(hi[r]))));
	e *= TL_WIDEN;
	return (aabb){v3((float)(lo[0] - e), (float)(lo[1] - e), (float)(lo[2] - e)),
	              v3((float)(hi[0] + e), (float)(hi[1] + e), (float)(hi[2] + e))};
}

static int g_axis; /* qsort's axis (tl_frame runs on one thread) */
static const tl_inst *g_inst;

static int cmp_centre(const void *x, const void *y)
{
	const aabb *a = &g_inst[*(const uint32_t *)x].box, *b = &g_inst[*(const uint32_t *)y].box;
	float ca = v3_get(a->lo, g_axis) + v3_get(a->hi, g_axis);
	float cb = v3_get(b->lo, g_axis) + v3_get(b->hi, g_axis);
	return ca < cb ? -1 : ca > cb;
}

/* Node k over order[first..first+n): a leaf, or split at the median of the
 * boxes' centres along the longest axis of the node's box. */
static void bvh_build(tl_scene *t, uint32_t k, uint32_t first, uint32_t n)
{
	tl_node *nd = &t->node[k];
	nd->box = aabb_empty();
	for (uint32_t i = first; i < first + n; i++)
		nd->box = aabb_union(nd->box, t->inst[t->order[i]].box);
	nd->first = first;
	nd->count = n;
	if (n <= TL_LEAF)
		return;
	vec3 ext = v3_sub(nd->box.hi, nd->box.lo);
	g_axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
	g_inst = t->inst;
	qsort(t->order + first, n, sizeof *t->order, cmp_centre);
	nd->count = 0;
	nd->left = t->nnode;
	t->nnode += 2;
	bvh_build(t, nd->left, first, n / 2);
	bvh_build(t, nd->left + 1, first + n / 2, n - n / 2);
}

int tl_frame(tl_scene *t, const aff_scene *a, double time, const mimg *world, diag *d)
{
	double t0 = now_ms();
	double *m = malloc(12 * ((size_t)a->nxf + 1) * sizeof *m);
	if (!m)
		return diag_set(d, a->path, 0, 0, "out of memory for the two-level trees");
	aff_matrices(a, time, m);
	static const double id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
	for (uint32_t k = 0; k < t->ninst; k++) {
		tl_inst *in = &t->inst[k];
		const double *w = in->xform >= 0 ? m + 12 * (size_t)in->xform : id;
		affine_inverse(w, in->inv);
		memcpy(in->fwd, w, sizeof in->fwd);
		xf_normal_matrix(w, in->nrm);
		in->box = world_box(w, t->obj[in->obj].m.bounds);
		t->order[k] = k;
	}
	free(m);
	t->nnode = 1;
	if (t->ninst)
		bvh_build(t, 0, 0, t->ninst);
	/* the shading transforms in record order; kernel-ref's shader finds
	 * them past the shading image */
	for (uint32_t k = 0; k < t->ninst; k++) {
		const tl_inst *in = &t->inst[t->order[k]];
		memcpy(t->xf + (size_t)k * SHADE_XF_BYTES, in->fwd, sizeof in->fwd);
		memcpy(t->xf + (size_t)k * SHADE_XF_BYTES + sizeof in->fwd, in->nrm,
		       sizeof in->nrm);
	}
	t->shade = (shade_tl){mimg_align_up(world->size, TL_ALIGN), SHADE_XF_BYTES, t->xf,
	                      (uint64_t)t->ninst * SHADE_XF_BYTES};
	t->world = world;
	t->frame_ms = now_ms() - t0;
	return 0;
}

/* ---- tracing ---- */

void tl_ray_to_object(const double inv[12], const float o[3], const float dir[3], vec3 *oo,
                      vec3 *od)
{
	const double *r = inv;
	double x[3], y[3];
	for (int k = 0; k < 3; k++) {
		x[k] = r[4 * k] * o[0] + r[4 * k + 1] * o[1] + r[4 * k + 2] * o[2] + r[4 * k + 3];
		y[k] = r[4 * k] * dir[0] + r[4 * k + 1] * dir[1] + r[4 * k + 2] * dir[2];
	}
	*oo = v3((float)x[0], (float)x[1], (float)x[2]);
	*od = v3((float)y[0], (float)y[1], (float)y[2]);
}

/* The ray (o, id = 1/d) meets box b within [0, tmax] (slabs widened; a
 * NaN slab, origin on a face with d parallel, leaves the axis open). */
static int box_hit(const aabb *b, const float o[3], const float id[3], float tmax)
{
	float tn = 0.0f, tf = tmax;
	const float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
	for (int a = 0; a < 3; a++) {
		float t0 = (lo[a] - o[a]) * id[a], t1 = (hi[a] - o[a]) * id[a];
		if (t0 != t0 || t1 != t1)
			continue;
		float n = fminf(t0, t1), f = fmaxf(t0, t1);
		n -= fabsf(n) * (float)TL_WIDEN;
		f += fabsf(f) * (float)TL_WIDEN;
		tn = n > tn ? n : tn;
		tf = f < tf ? f : tf;
	}
	return tn <= tf;
}

/* The address in the world image of local triangle address a of
 * instance in (object ob). */
static uint32_t world_addr(const tl_scene *t, const tl_inst *in, const tl_object *ob, uint32_t a)
{
	return (uint32_t)mimg_tri_addr(t->world, t->gtri[in->first + mimg_tri_index(&ob->m, a)]);
}

/* One instance for one ray: traced in object space with the best t so far
 * as its bound; *h keeps the better hit by the single tree's rule.
 * Returns 1 when a shadow ray (any) found an occluder. */
static int ray_inst(const tl_scene *t, uint32_t k, const float o[3], const float dir[3], int any,
                    ray_hit *h, trav_counts *c)
{
	const tl_inst *in = &t->inst[t->order[k]];
	vec3 oo, od;
	tl_ray_to_object(in->inv, o, dir, &oo, &od);
	const tl_object *ob = &t->obj[in->obj];
	ray_hit r = ray_trace(&ob->m, oo, od, h->t, any, c);
	if (r.tri == PKT_NOHIT)
		return 0;
	uint32_t g = world_addr(t, in, ob, r.tri);
	if (any) {
		h->t = r.t;
		h->tri = g;
		return 1;
	}
	if (isect_better(r.t, g, h->t, h->tri)) {
		r.tri = g;
		r.inst = k;
		*h = r;
	}
	return 0;
}

ray_hit tl_ray_trace(const tl_scene *t, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c)
{
	ray_hit h = {tmax, 0, 0, PKT_NOHIT, 0};
	const float of[3] = {o.x, o.y, o.z}, df[3] = {d.x, d.y, d.z};
	const float id[3] = {1.0f / d.x, 1.0f / d.y, 1.0f / d.z};
	uint32_t stack[64];
	int sp = 0;
	if (t->ninst)
		stack[sp++] = 0;
	while (sp > 0) {
		const tl_node *n = &t->node[stack[--sp]];
		if (!box_hit(&n->box, of, id, h.t))
			continue;
		if (n->count == 0) {
			stack[sp++] = n->left + 1;
			stack[sp++] = n->left;
			continue;
		}
		for (uint32_t k = n->first; k < n->first + n->count; k++) {
			const tl_inst *in = &t->inst[t->order[k]];
			if (box_hit(&in->box, of, id, h.t) &&
			    ray_inst(t, k, of, df, any_hit, &h, c))
				return h;
		}
	}
	return h;
}

uint64_t tl_pkt_box(const aabb *b, const packet *p, uint64_t mask)
{
	uint64_t r = 0;
	for (uint64_t m = mask; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		const float o[3] = {p->ox[i], p->oy[i], p->oz[i]};
		const float id[3] = {1.0f / p->dx[i], 1.0f / p->dy[i], 1.0f / p->dz[i]};
		float bound = p->type == PKT_SHADOW ? p->tmax[i] : p->t[i];
		if ((p->type != PKT_SHADOW || p->tri[i] == PKT_NOHIT) && box_hit(b, o, id, bound))
			r |= 1ull << i;
	}
	return r;
}

void tl_pkt_to_object(const double inv[12], const packet *p, uint64_t mask, packet *q)
{
	int shadow = p->type == PKT_SHADOW;
	memcpy(q, p, sizeof *q);
	q->valid = mask;
	for (uint64_t m = mask; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		const float o[3] = {p->ox[i], p->oy[i], p->oz[i]},
		            dir[3] = {p->dx[i], p->dy[i], p->dz[i]};
		vec3 oo, od;
		tl_ray_to_object(inv, o, dir, &oo, &od);
		q->ox[i] = oo.x;
		q->oy[i] = oo.y;
		q->oz[i] = oo.z;
		q->dx[i] = od.x;
		q->dy[i] = od.y;
		q->dz[i] = od.z;
		q->tmax[i] = shadow ? p->tmax[i] : p->t[i];
	}
}

void tl_pkt_merge(packet *p, const packet *q, uint64_t mask, const uint32_t *g, uint32_t inst)
{
	for (uint64_t m = mask; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		if (q->tri[i] == PKT_NOHIT)
			continue;
		if (p->type == PKT_SHADOW) {
			p->t[i] = -INFINITY; /* occluded, as the packet path marks it */
			p->tri[i] = g[i];
		} else if (isect_better(q->t[i], g[i], p->t[i], p->tri[i])) {
			p->t[i] = q->t[i];
			p->tri[i] = g[i];
			p->inst[i] = inst;
			p->bu[i] = q->bu[i];
			p->bv[i] = q->bv[i];
		}
	}
}

/* One instance for the rays `mask` of p: a copy of them moved into object
 * space, traced with the object's tree, the better hits taken back. */
static void pkt_inst(const tl_scene *t, uint32_t k, packet *p, uint64_t mask, packet *q,
                     trav_entry *stack, int stack_max, trav_counts *c)
{
	const tl_inst *in = &t->inst[t->order[k]];
	const tl_object *ob = &t->obj[in->obj];
	tl_pkt_to_object(in->inv, p, mask, q);
	pkt_trace(q, &ob->m, stack, stack_max, c);
	uint32_t g[PKT_RAYS];
	for (uint64_t m = mask; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		g[i] = q->tri[i] == PKT_NOHIT ? PKT_NOHIT : world_addr(t, in, ob, q->tri[i]);
	}
	tl_pkt_merge(p, q, mask, g, k);
}

typedef struct tl_entry {
	uint32_t node;
	uint64_t mask;
} tl_entry;

uint64_t tl_pkt_trace(const tl_scene *t, packet *p, trav_entry *stack, int stack_max,
                      trav_counts *c)
{
	for (uint64_t m = p->valid; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		p->t[i] = p->tmax[i];
		p->tri[i] = PKT_NOHIT;
	}
	if (!t->ninst)
		return 0;
	uint64_t entered = tl_pkt_box(&t->node[0].box, p, p->valid);
	packet q; /* the rays in an object's space */
	tl_entry stk[64];
	int sp = 0;
	stk[sp++] = (tl_entry){0, entered};
	while (sp > 0) {
		sp--;
		const tl_node *n = &t->node[stk[sp].node];
		uint64_t mask = tl_pkt_box(&n->box, p, stk[sp].mask);
		if (!mask)
			continue;
		if (n->count == 0) {
			stk[sp++] = (tl_entry){n->left + 1, mask};
			stk[sp++] = (tl_entry){n->left, mask};
			continue;
		}
		for (uint32_t k = n->first; k < n->first + n->count; k++) {
			const tl_inst *in = &t->inst[t->order[k]];
			uint64_t im = tl_pkt_box(&in->box, p, mask);
			if (im)
				pkt_inst(t, k, p, im, &q, stack, stack_max, c);
		}
	}
	return entered;
}
