/*
 * tlflat.c: one tree over the flattened scene, triangles tested in their
 * objects' spaces: the exact reference for two-level trees (tlflat.h).
 */
#include "kernel-ref/tlflat.h"

#include "kernel-ref/isect.h"

#include <stdlib.h>
#include <string.h>

static ray_hit tracer_ray(const void *ctx, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c)
{
	return tl_flat_ray(ctx, o, d, tmax, any_hit, c);
}

/* Packets ray by ray: this tracer is a reference, not a fast path. Every
 * valid ray counts as entering. */
static uint64_t tracer_packet(const void *ctx, packet *p, trav_entry *stack, int stack_max,
                              trav_counts *c)
{
	(void)stack;
	(void)stack_max;
	for (uint64_t b = p->valid; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		ray_hit h = tl_flat_ray(ctx, v3(p->ox[i], p->oy[i], p->oz[i]),
		                        v3(p->dx[i], p->dy[i], p->dz[i]), p->tmax[i],
		                        p->type == PKT_SHADOW, c);
		p->t[i] = p->type == PKT_SHADOW && h.tri != PKT_NOHIT ? -INFINITY : h.t;
		p->tri[i] = h.tri;
		p->inst[i] = h.inst;
		p->bu[i] = h.bu;
		p->bv[i] = h.bv;
	}
	return p->valid;
}

int tl_flat_init(tl_flat *f, const tl_scene *t, const mimg *flat, diag *d)
{
	memset(f, 0, sizeof *f);
	uint32_t n = flat->ntris;
	uint32_t total = 0;
	for (uint32_t k = 0; k < t->ninst; k++)
		total += t->obj[t->inst[k].obj].ntris;
	if (total != n || t->world->ntris != n)
		return diag_set(d, "tlflat", 0, 0,
		                "the flattened scene has %u triangles, the instances %u", n, total);
	f->rec = malloc(((size_t)n + 1) * sizeof *f->rec);
	f->local = malloc(((size_t)n + 1) * sizeof *f->local);
	if (!f->rec || !f->local) {
		tl_flat_free(f);
		return diag_set(d, "tlflat", 0, 0, "out of memory for the flat reference");
	}
	for (uint32_t k = 0; k < t->ninst; k++) {
		const tl_inst *in = &t->inst[t->order[k]];
		const tl_object *ob = &t->obj[in->obj];
		/* the object's triangle j is the instance's j-th (tl_build) */
		for (uint32_t j = 0; j < ob->ntris; j++) {
			uint32_t g = t->gtri[in->first + j];
			f->rec[g] = k;
			f->local[g] = (uint32_t)mimg_tri_addr(&ob->m, j);
		}
	}
	f->t = t;
	f->flat = flat;
	f->tracer = (render_tracer){f, tracer_ray, tracer_packet, &t->shade};
	return 0;
}

void tl_flat_free(tl_flat *f)
{
	free(f->rec);
	free(f->local);
	memset(f, 0, sizeof *f);
}

/* One ray's walk: the ray in the object space of the record last met
 * (leaves mostly hold one object's triangles). */
typedef struct flat_ray {
	const tl_flat *f;
	float o[3], d[3], tmax;
	int any_hit;
	uint32_t rec; /* the record oo, od, ir are for; UINT32_MAX: none yet */
	vec3 oo, od;
	isect_ray ir;
} flat_ray;

static int flat_leaf(void *ctx, const uint32_t *list, uint32_t count, ray_hit *h)
{
	flat_ray *r = ctx;
	const tl_scene *t = r->f->t;
	for (uint32_t k = 0; k < count; k++) {
		uint32_t g = mimg_tri_index(r->f->flat, list[k]), rec = r->f->rec[g];
		const tl_inst *in = &t->inst[t->order[rec]];
		if (rec != r->rec) {
			tl_ray_to_object(in->inv, r->o, r->d, &r->oo, &r->od);
			r->ir = isect_prepare(r->od);
			r->rec = rec;
		}
		float tt, bu, bv;
		const float(*tv)[3] = mimg_tri_at(&t->obj[in->obj].m, r->f->local[g])->v;
		if (isect_tri(&r->ir, r->oo, tv, &tt, &bu, &bv) &&
		    isect_take(h, tt, bu, bv, (uint32_t)mimg_tri_addr(t->world, g), rec, r->any_hit,
		               r->tmax))
			return 1;
	}
	return 0;
}

ray_hit tl_flat_ray(const tl_flat *f, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c)
{
	flat_ray r = {f,          {o.x, o.y, o.z}, {d.x, d.y, d.z}, tmax, any_hit,
	              UINT32_MAX, v3(0, 0, 0),     v3(0, 0, 0),     {0}};
	return ray_trace_leaves(f->flat, o, d, tmax, c, flat_leaf, &r);
}
