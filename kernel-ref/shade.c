/*
 * shade.c: the fixed SaarCOR shader and secondary rays (see shade.h).
 *
 * Secondary-ray origins follow pbrt's robust spawning: the hit point is
 * recomputed from barycentrics with a conservative error bound
 * (gamma(7) * sum |b_i p_i|), moved along the geometric normal by that
 * bound to the side the new ray leaves on, and rounded one ulp further
 * away. No magic epsilon: the origin is provably on the right side of the
 * triangle's plane, so a secondary ray cannot hit its own surface.
 */
#include "kernel-ref/shade.h"
#include "kernel-ref/simd.h"

#include "kernel-ref/sudoku.h"
#include "kernel-ref/xform.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define GAMMA7 (7.0f * 0x1p-24f / (1.0f - 7.0f * 0x1p-24f))

static void log_read(shade_log *log, uint64_t addr, uint32_t bytes, int region)
{
	if (!log)
		return;
	if (log->n < log->cap)
		log->e[log->n++] = (shade_read){addr, bytes, (uint32_t)region};
	else
		log->dropped++;
}

/* kernel-ref's reader: the memory image itself (addresses past it read
 * as zero) and a two-level scene's shading transforms, every read logged. */
typedef struct mimg_rd {
	const mimg *m;
	const shade_tl *tl;
	shade_log *log;
} mimg_rd;

static const void *mimg_read(void *ctx, uint64_t addr, uint32_t bytes, int region)
{
	static const uint8_t zero[MIMG_SHADE_BYTES];
	const mimg_rd *r = ctx;
	log_read(r->log, addr, bytes, region);
	const shade_tl *tl = r->tl;
	if (tl && tl->bytes && addr >= tl->base && addr - tl->base <= tl->size &&
	    bytes <= tl->size - (addr - tl->base))
		return tl->bytes + (addr - tl->base);
	if (addr > r->m->size || bytes > r->m->size - addr || bytes > sizeof zero)
		return zero;
	return r->m->bytes + addr;
}

/* Reads `bytes` bytes at addr through the reader into out. */
static void rd_get(const shade_reader *rd, uint64_t addr, uint32_t bytes, int region, void *out)
{
	memcpy(out, rd->read(rd->ctx, addr, bytes, region), bytes);
}

/* Nearest texel with repeat wrapping; returns RGB in [0,1]. Reads the
 * texture header (into *th) and the texel. */
static vec3 texel(const shade_reader *rdr, const mimg *m, int tex, vec2 uv, float du, float dv,
                  shade_counts *cnt, mimg_texhdr *th)
{
	uint64_t hdr_addr = m->base[MIMG_TEXHDR] + (uint64_t)MIMG_TEXHDR_BYTES * (uint32_t)tex;
	rd_get(rdr, hdr_addr, MIMG_TEXHDR_BYTES, MIMG_TEXHDR, th);
	float u = uv.u + du, v = uv.v + dv;
	u -= floorf(u);
	v -= floorf(v);
	int x = (int)(u * (float)th->w), y = (int)((1.0f - v) * (float)th->h);
	x = x < 0 ? 0 : x >= (int)th->w ? (int)th->w - 1 : x;
	y = y < 0 ? 0 : y >= (int)th->h ? (int)th->h - 1 : y;
	uint64_t a = th->texel_addr + 4ull * ((uint64_t)y * th->w + (uint64_t)x);
	uint8_t px[4];
	rd_get(rdr, a, 4, MIMG_TEXELS, px);
	cnt->texel_reads++;
	return v3(px[0] / 255.0f, px[1] / 255.0f, px[2] / 255.0f);
}

/* A frame-buffer add, or kept for later (shade_ctx.defer). */
static void add(const shade_ctx *c, uint32_t pixel, vec3 col)
{
	shade_adds *d = c->defer;
	if (!d) {
		fb_add(c->fb, pixel, col.x, col.y, col.z);
		return;
	}
	if (d->n < PKT_RAYS)
		d->e[d->n++] = (shade_add){pixel, col.x, col.y, col.z};
}

void shade_adds_apply(const shade_adds *d, framebuf *fb)
{
	for (uint32_t i = 0; i < d->n; i++)
		fb_add(fb, d->e[i].pixel, d->e[i].r, d->e[i].g, d->e[i].b);
}

static vec3 arr3(const float *f)
{
	return v3(f[0], f[1], f[2]);
}

/* nextafterf(x, +-INFINITY), exactly, without a call into libm: the
 * neighbouring float towards s > 0 (up) or s < 0 (down); x when s is 0.
 * (A libm call from here cost as much as the rest of the shader where
 * the caller left wide vector registers in use.) */
static inline float next_toward(float x, float s)
{
	if (s > 0)
		return x == -INFINITY ? -FLT_MAX : fp_next_up(x);
	if (s < 0)
		return x == INFINITY ? FLT_MAX : fp_next_down(x);
	return x;
}

/* Robust origin for a ray leaving the surface in direction d. */
static vec3 spawn_origin(vec3 p, vec3 err, vec3 ng, vec3 d)
{
	float off = fabsf(ng.x) * err.x + fabsf(ng.y) * err.y + fabsf(ng.z) * err.z;
	vec3 o = v3_scale(ng, off);
	if (v3_dot(d, ng) < 0.0f)
		o = v3_scale(o, -1.0f);
	vec3 q = v3_add(p, o);
	q.x = next_toward(q.x, o.x);
	q.y = next_toward(q.y, o.y);
	q.z = next_toward(q.z, o.z);
	return q;
}

/* Rounds to the shading format; full precision (NULL) passes through. */
static inline float rnd(const fpfmt *f, float x)
{
	return f ? fp_round(f, x) : x;
}
static inline vec3 rnd3(const fpfmt *f, vec3 v)
{
	return f ? v3(fp_round(f, v.x), fp_round(f, v.y), fp_round(f, v.z)) : v;
}

static void put_ray(packet *q, int lane, vec3 o, vec3 d, float tmax, uint32_t pixel, vec3 w)
{
	q->ox[lane] = o.x;
	q->oy[lane] = o.y;
	q->oz[lane] = o.z;
	q->dx[lane] = d.x;
	q->dy[lane] = d.y;
	q->dz[lane] = d.z;
	q->tmax[lane] = tmax;
	q->pixel[lane] = pixel;
	q->wr[lane] = w.x;
	q->wg[lane] = w.y;
	q->wb[lane] = w.z;
	q->valid |= 1ull << lane;
}

int shade_packet(const shade_ctx *c, const packet *p, packet *out, int max_out, shade_log *log,
                 shade_counts *cnt)
{
	return shade_packet_fp(c, NULL, p, out, max_out, log, cnt);
}

static int shade_packet_in(const shade_ctx *c, const fpfmt *fp, const shade_reader *rdr,
                           const packet *p, packet *out, int max_out, shade_counts *cnt, int lean);

int shade_packet_fp(const shade_ctx *c, const fpfmt *fp, const packet *p, packet *out, int max_out,
                    shade_log *log, shade_counts *cnt)
{
	mimg_rd r = {c->m, c->tl, log};
	shade_reader rd = {mimg_read, &r};
	return shade_packet_in(c, fp, &rd, p, out, max_out, cnt, !log && !c->tl);
}

/* A hit's surface as the shader uses it: the records the reader gave, the
 * triangle's corners, the hit point with its error bound, both normals
 * (face-forwarded towards the viewer) and the texture coordinates. */
typedef struct hit {
	mimg_shade sh;
	mimg_mat mt;
	vec3 p0, p1, p2;
	vec3 hp, err, ng, ns;
	vec2 uv;
	int entering;
} hit;

/* Where the rays spawned from one packet go: a shadow packet per light
 * (nl of them), one reflection and one refraction packet. */
typedef struct spawn {
	packet *shadow, *refl, *refr;
	int nl, can_recurse;
} spawn;

/* Planted mistakes for tests (docs/TESTING.md "Checks that can fail");
 * programs leave it at 0. SHADE_FAULT_NO_NORMAL_XF: a two-level hit's
 * shading normals are left in object space (the normal transform
 * skipped). SHADE_FAULT_LEAN_NO_TEXTURE: the lean lane leaves out the
 * map_Kd texel; SHADE_FAULT_LEAN_NO_CLAMP: the lean adds convert to
 * fixed point without fb_fixed's clamp; SHADE_FAULT_LEAN_MEMO_TEXTURED:
 * a textured hit's result is reused for the next lane on its triangle
 * (whose texel differs); SHADE_FAULT_LEAN_ONE_WEIGHT: the lean adds take
 * the first lane's weight for every lane (lean_adds' per-slot sums where
 * the lanes' weights differ). */
int shade_fault;

/* A two-level hit (shade_ctx.tl): instance k's shading transform (read in
 * SHADE_XF_READS pieces of at most 48 bytes), then the triangle's corners
 * and shading normals moved by it into the world, as aff_flatten places
 * them (xform.h; scene_finish's renormalisation). */
static void to_world(const shade_reader *rdr, const shade_tl *tl, uint32_t k, mimg_tri *tr,
                     mimg_shade *sh)
{
	double x[21];
	uint64_t a = tl->base + (uint64_t)k * tl->stride;
	/* logged as tree data (MIMG_NODES): the top level's records lie past
	 * the shading image's regions */
	for (uint32_t off = 0; off < SHADE_XF_BYTES; off += 48) {
		uint32_t n = SHADE_XF_BYTES - off < 48 ? SHADE_XF_BYTES - off : 48;
		rd_get(rdr, a + off, n, MIMG_NODES, (uint8_t *)x + off);
	}
	const double *fwd = x, *nm = x + 12;
	for (int c = 0; c < 3; c++) {
		vec3 v = xf_point(fwd, tr->v[c]);
		tr->v[c][0] = v.x;
		tr->v[c][1] = v.y;
		tr->v[c][2] = v.z;
	}
	if (shade_fault == SHADE_FAULT_NO_NORMAL_XF)
		return;
	vec3 p0 = arr3(tr->v[0]), p1 = arr3(tr->v[1]), p2 = arr3(tr->v[2]);
	vec3 fn = v3_cross(v3_sub(p1, p0), v3_sub(p2, p0));
	float fl = v3_len(fn);
	fn = fl > 0.0f ? v3_scale(fn, 1.0f / fl) : v3(0, 0, 1);
	for (int c = 0; c < 3; c++) {
		vec3 n = xf_normal(nm, sh->n[c]);
		float l = v3_len(n);
		n = (isfinite(l) && l > 0.0f) ? v3_scale(n, 1.0f / l) : fn;
		sh->n[c][0] = n.x;
		sh->n[c][1] = n.y;
		sh->n[c][2] = n.z;
	}
}

/* Reads lane i's records (triangle, shading, material, in that order, and
 * on a two-level scene its instance's shading transform) and computes its
 * corners and texture coordinates; hit_geometry computes the rest. */
static void hit_surface(const shade_reader *rdr, const shade_ctx *c, const packet *p, int i, vec3 d,
                        hit *h)
{
	const mimg *m = c->m;
	uint32_t ta = p->tri[i], tri = mimg_tri_index(m, ta);
	mimg_tri trd;
	rd_get(rdr, ta, MIMG_TRI_BYTES, MIMG_TRIS, &trd);
	rd_get(rdr, mimg_shade_addr(m, tri), MIMG_SHADE_BYTES, MIMG_SHADE, &h->sh);
	rd_get(rdr, mimg_mat_addr(m, h->sh.mat), MIMG_MAT_BYTES, MIMG_MATS, &h->mt);
	if (c->tl)
		to_world(rdr, c->tl, p->inst[i], &trd, &h->sh);
	h->p0 = arr3(trd.v[0]);
	h->p1 = arr3(trd.v[1]);
	h->p2 = arr3(trd.v[2]);
	const mimg_shade *sh = &h->sh;
	float b1 = p->bu[i], b2 = p->bv[i], b0 = 1.0f - b1 - b2;
	h->uv = (vec2){b0 * sh->uv[0][0] + b1 * sh->uv[1][0] + b2 * sh->uv[2][0],
	               b0 * sh->uv[0][1] + b1 * sh->uv[1][1] + b2 * sh->uv[2][1]};
	h->hp = h->err = h->ng = h->ns = v3(0, 0, 0);
	h->entering = 0;
}

/* The rest of the hit: the hit point from the barycentrics with its error
 * bound, both normals (face-forwarded towards the viewer) and the facing.
 * Only shadow rays, secondary rays and bump mapping use them, so a lane
 * that spawns no ray and has no bump map skips it (the same pixels). */
static void hit_geometry(const packet *p, int i, vec3 d, hit *h)
{
	const mimg_shade *sh = &h->sh;
	float b1 = p->bu[i], b2 = p->bv[i], b0 = 1.0f - b1 - b2;
	vec3 p0 = h->p0, p1 = h->p1, p2 = h->p2;
	h->hp = v3_add(v3_add(v3_scale(p0, b0), v3_scale(p1, b1)), v3_scale(p2, b2));
	h->err = v3_scale(v3_add(v3_add(v3(fabsf(b0 * p0.x), fabsf(b0 * p0.y), fabsf(b0 * p0.z)),
	                                v3(fabsf(b1 * p1.x), fabsf(b1 * p1.y), fabsf(b1 * p1.z))),
	                         v3(fabsf(b2 * p2.x), fabsf(b2 * p2.y), fabsf(b2 * p2.z))),
	                  GAMMA7);
	vec3 ng = v3_norm(v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)));
	vec3 ns = v3_norm(v3_add(v3_add(v3_scale(arr3(sh->n[0]), b0), v3_scale(arr3(sh->n[1]), b1)),
	                         v3_scale(arr3(sh->n[2]), b2)));
	h->entering = v3_dot(d, ng) < 0.0f;
	/* face-forward both normals towards the viewer */
	if (!h->entering)
		ng = v3_scale(ng, -1.0f);
	if (v3_dot(ns, ng) < 0.0f)
		ns = v3_scale(ns, -1.0f);
	h->ng = ng;
	h->ns = ns;
}

/* Bump mapping: tilts h->ns by the height texture's slope along the
 * triangle's uv tangent frame (three texel reads). */
static void bump(const shade_reader *rdr, const mimg *m, hit *h, shade_counts *cnt)
{
	const mimg_shade *sh = &h->sh;
	const mimg_mat *mt = &h->mt;
	mimg_texhdr th;
	/* the offsets are one texel of the header h0's read brings */
	vec3 h0 = texel(rdr, m, mt->tex_bump, h->uv, 0, 0, cnt, &th);
	float du = 1.0f / (float)th.w, dv = 1.0f / (float)th.h;
	vec3 hu = texel(rdr, m, mt->tex_bump, h->uv, du, 0, cnt, &th);
	vec3 hv = texel(rdr, m, mt->tex_bump, h->uv, 0, dv, cnt, &th);
	float l0 = (h0.x + h0.y + h0.z) / 3, lu = (hu.x + hu.y + hu.z) / 3,
	      lv = (hv.x + hv.y + hv.z) / 3;
	/* tangent frame from the triangle's uv parametrisation */
	vec3 e1 = v3_sub(h->p1, h->p0), e2 = v3_sub(h->p2, h->p0);
	float u1 = sh->uv[1][0] - sh->uv[0][0], v1 = sh->uv[1][1] - sh->uv[0][1];
	float u2 = sh->uv[2][0] - sh->uv[0][0], v2 = sh->uv[2][1] - sh->uv[0][1];
	float det = u1 * v2 - v1 * u2;
	if (det != 0.0f && isfinite(1.0f / det)) {
		vec3 dpdu =
		    v3_norm(v3_scale(v3_sub(v3_scale(e1, v2), v3_scale(e2, v1)), 1.0f / det));
		vec3 dpdv =
		    v3_norm(v3_scale(v3_sub(v3_scale(e2, u1), v3_scale(e1, u2)), 1.0f / det));
		vec3 nb =
		    v3_sub(h->ns, v3_scale(v3_add(v3_scale(dpdu, lu - l0), v3_scale(dpdv, lv - l0)),
		                           mt->bump_scale));
		if (v3_len(nb) > 0.0f && v3_dot(nb, h->ng) > 0.0f)
			h->ns = v3_norm(nb);
	}
}

/* The surface's diffuse and ambient colours (kd, ka) with its colour
 * texture, and the bumped shading normal, rounded to the shading format. */
static void textures(const shade_reader *rdr, const mimg *m, const fpfmt *fq, hit *h,
                     shade_counts *cnt, vec3 *kd, vec3 *ka)
{
	const mimg_mat *mt = &h->mt;
	*kd = arr3(mt->kd);
	*ka = arr3(mt->ka);
	if (mt->tex_kd >= 0) {
		mimg_texhdr th;
		vec3 tx = texel(rdr, m, mt->tex_kd, h->uv, 0, 0, cnt, &th);
		*kd = v3_mul(*kd, tx);
		*ka = v3_mul(*ka, tx);
	}
	if (mt->tex_bump >= 0)
		bump(rdr, m, h, cnt);
	if (mt->tex_kd < 0 && mt->tex_bump < 0)
		cnt->untextured_hits++;
	h->ns = rnd3(fq, h->ns);
}

/* Shadow rays from lane i: one per light the surface faces, carrying the
 * light's diffuse and specular term (weight wl, diffuse colour kd). */
static void shadow_rays(const shade_ctx *c, const fpfmt *fq, const hit *h, const spawn *sp, int i,
                        uint32_t pixel, int sample, vec3 d, vec3 kd, vec3 wl, float kl,
                        shade_counts *cnt)
{
	const mimg_mat *mt = &h->mt;
	vec3 ns = h->ns, ng = h->ng;
	if (c->nlights == 0 && kl > 0.0f)
		cnt->shadow_skip_nolight++;
	if (sp->nl == 0 || kl <= 0.0f)
		return;
	vec3 vdir = v3_scale(v3_norm(d), -1.0f);
	for (int l = 0; l < sp->nl; l++) {
		vec3 lp = c->lights[l].pos;
		if (c->drt) /* the light's point for this sample (seed 000 §3.2) */
			lp = drt_light_point(c->drt, lp, pixel, sample, l);
		vec3 L = v3_sub(lp, h->hp);
		vec3 ld = v3_norm(L);
		float ndl = rnd(fq, v3_dot(ns, ld));
		if (ndl <= 0.0f || v3_dot(ng, L) <= 0.0f) {
			cnt->shadow_skip_facing++;
			continue;
		}
		vec3 r = v3_sub(v3_scale(ns, 2.0f * ndl), ld);
		float rv = v3_dot(r, vdir);
		float spec = rnd(fq, rv > 0.0f ? powf(rv, mt->ns > 0.0f ? mt->ns : 1.0f) : 0.0f);
		vec3 col = v3_add(v3_scale(kd, ndl), v3_scale(arr3(mt->ks), spec));
		col = rnd3(fq, v3_mul(v3_mul(col, wl), c->lights[l].color));
		vec3 o = spawn_origin(h->hp, h->err, ng, L);
		put_ray(&sp->shadow[l], i, o, v3_sub(lp, o), 1.0f, pixel, col);
		cnt->shadow_rays_made++;
	}
}

/* The reflection and refraction rays from lane i (weights w*kr, w*kt);
 * a total internal reflection adds the refracted weight to the reflected. */
static void secondary_rays(const shade_ctx *c, const fpfmt *fq, const hit *h, const spawn *sp,
                           int i, const packet *p, vec3 d, vec3 w, float kr, float kt)
{
	uint32_t pixel = p->pixel[i];
	vec3 ns = h->ns, ng = h->ng;
	vec3 rd = v3_sub(d, v3_scale(ns, 2.0f * v3_dot(d, ns)));
	if (v3_dot(rd, ng) <= 0.0f) /* shading normal bent it under: use the true one */
		rd = v3_sub(d, v3_scale(ng, 2.0f * v3_dot(d, ng)));
	if (c->drt && c->drt->gloss > 0.0f) {
		/* glossy: a Phong lobe around the mirror direction (seed 000
		 * §3.3); a direction under the surface keeps the mirror one */
		float u1, u2;
		const drt_shade *g = c->drt;
		sudoku_sample(pixel % g->width, pixel / g->width, p->sample,
		              SUDOKU_DIM_GLOSS + p->depth, g->spp, &u1, &u2);
		vec3 gd = drt_glossy_dir(rd, g->gloss, u1, u2);
		if (v3_dot(gd, ng) > 0.0f)
			rd = gd;
	}
	rd = rnd3(fq, rd); /* spawn_origin picks its side from the rounded rd */
	vec3 wr = rnd3(fq, v3_scale(w, kr));
	if (kt > 0.0f) {
		float eta = h->entering ? 1.0f / h->mt.ni : h->mt.ni;
		float ci = -v3_dot(v3_norm(d), ns);
		float k = 1.0f - eta * eta * (1.0f - ci * ci);
		vec3 td = k >= 0.0f
		              ? v3_add(v3_scale(v3_norm(d), eta), v3_scale(ns, eta * ci - sqrtf(k)))
		              : v3(0, 0, 0);
		td = rnd3(fq, td);
		if (k < 0.0f || v3_dot(td, ng) >= 0.0f) {
			wr = rnd3(fq, v3_add(wr, v3_scale(w, kt))); /* total internal reflection */
		} else {
			vec3 o = spawn_origin(h->hp, h->err, ng, td);
			put_ray(sp->refr, i, o, td, INFINITY, pixel, rnd3(fq, v3_scale(w, kt)));
		}
	}
	if (wr.x > 0.0f || wr.y > 0.0f || wr.z > 0.0f) {
		vec3 o = spawn_origin(h->hp, h->err, ng, rd);
		put_ray(sp->refl, i, o, rd, INFINITY, pixel, wr);
	}
}

/* Shades lane i of p: background on a miss; else the ambient term now and
 * the shadow, reflection and refraction rays into sp. */
static void shade_lane(const shade_ctx *c, const fpfmt *fq, const shade_reader *rdr,
                       const packet *p, int i, const spawn *sp, shade_counts *cnt)
{
	vec3 w = v3(p->wr[i], p->wg[i], p->wb[i]);
	vec3 d = v3(p->dx[i], p->dy[i], p->dz[i]);
	if (p->tri[i] == PKT_NOHIT) {
		cnt->misses++;
		vec3 bg = rnd3(fq, v3_mul(w, c->background));
		add(c, p->pixel[i], bg);
		return;
	}
	cnt->hits++;
	hit h;
	hit_surface(rdr, c, p, i, d, &h);
	float kr = h.mt.reflect, kt = h.mt.transmit;
	float kl = 1.0f - kr - kt;
	if (kl < 0.0f)
		kl = 0.0f;
	if ((sp->nl > 0 && kl > 0.0f) || ((kr > 0.0f || kt > 0.0f) && sp->can_recurse) ||
	    h.mt.tex_bump >= 0)
		hit_geometry(p, i, d, &h);
	vec3 kd, ka;
	textures(rdr, c->m, fq, &h, cnt, &kd, &ka);

	vec3 wl = v3_scale(w, kl);
	vec3 amb = rnd3(fq, v3_scale(v3_mul(wl, ka), SHADE_AMBIENT));
	add(c, p->pixel[i], amb);
	shadow_rays(c, fq, &h, sp, i, p->pixel[i], p->sample, d, kd, wl, kl, cnt);

	if (kr <= 0.0f && kt <= 0.0f)
		return;
	if (!sp->can_recurse) {
		cnt->depth_cut += (kr > 0.0f) + (kt > 0.0f);
		return;
	}
	secondary_rays(c, fq, &h, sp, i, p, d, w, kr, kt);
}

/* A record of the image at addr straight from its bytes, as mimg_read
 * gives it; 0 where mimg_read would give zeros (past the image). */
static int lean_get(const mimg *m, uint64_t addr, uint32_t bytes, void *out)
{
	if (addr > m->size || bytes > m->size - addr)
		return 0;
	memcpy(out, m->bytes + addr, bytes);
	return 1;
}

/* shade_lane for a hit that spawns no ray (no shadow packets, and no
 * reflection or refraction: none in the material, or the depth cut) and
 * has no bump map, read from kernel-ref's image without a log (full
 * precision, a single tree): the same pixel add and counts, from the two
 * records and the operations that decide them (the ambient term of
 * textures and shade_lane, the uv of hit_surface), without the hit's
 * geometry, the reader's calls and the records' copies a spawning lane
 * needs; the add is left to lean_adds, which gets kl and ka. Returns 0,
 * having done nothing, for a lane it does not cover. */
static int shade_lane_lean(const shade_ctx *c, const shade_reader *rdr, const packet *p, int i,
                           const spawn *sp, shade_counts *cnt, float *klo, vec3 *kao, int *cut)
{
	const mimg *m = c->m;
	uint32_t ta = p->tri[i];
	mimg_shade sh;
	mimg_mat mt;
	if (ta == PKT_NOHIT ||
	    !lean_get(m, mimg_shade_addr(m, mimg_tri_index(m, ta)), MIMG_SHADE_BYTES, &sh))
		return 0;
	if (!lean_get(m, mimg_mat_addr(m, sh.mat), MIMG_MAT_BYTES, &mt) || mt.tex_bump >= 0)
		return 0;
	float kr = mt.reflect, kt = mt.transmit;
	if ((kr > 0.0f || kt > 0.0f) && sp->can_recurse)
		return 0;
	cnt->hits++;
	vec3 ka = arr3(mt.ka);
	if (mt.tex_kd >= 0) {
		float b1 = p->bu[i], b2 = p->bv[i], b0 = 1.0f - b1 - b2;
		vec2 uv = {b0 * sh.uv[0][0] + b1 * sh.uv[1][0] + b2 * sh.uv[2][0],
		           b0 * sh.uv[0][1] + b1 * sh.uv[1][1] + b2 * sh.uv[2][1]};
		mimg_texhdr th;
		vec3 tx = texel(rdr, m, mt.tex_kd, uv, 0, 0, cnt, &th);
		if (shade_fault != SHADE_FAULT_LEAN_NO_TEXTURE)
			ka = v3_mul(ka, tx);
	} else
		cnt->untextured_hits++;
	int untextured = mt.tex_kd < 0;
	float kl = 1.0f - kr - kt;
	if (kl < 0.0f)
		kl = 0.0f;
	*klo = kl;
	*kao = ka;
	*cut = (kr > 0.0f) + (kt > 0.0f);
	if (c->nlights == 0 && kl > 0.0f)
		cnt->shadow_skip_nolight++;
	cnt->depth_cut += (uint64_t)*cut;
	return untextured ? 2 : 1;
}

/* fb_fixed in SIMD_W lanes: the same operations (a sum below 2^31
 * converts to the same integer through int32 as through uint64). */
static inline iv fixed_v(fv c)
{
	iv pos = c > fv_set1(0.0f);
	fv x = shade_fault == SHADE_FAULT_LEAN_NO_CLAMP
	           ? c
	           : fv_sel(c > fv_set1(FB_MAX_CONTRIB), fv_set1(FB_MAX_CONTRIB), c);
	x = x * fv_set1((float)(1u << FB_FRAC_BITS)) + fv_set1(0.5f);
	return __builtin_convertvector(x, iv) & pos;
}

/* fb_fixed for one value, as fixed_v's lanes (the planted clamp-less
 * conversion too, here without the int32 overflow). */
static inline uint64_t fixed_s(float c)
{
	if (shade_fault != SHADE_FAULT_LEAN_NO_CLAMP)
		return fb_fixed(c);
	return c > 0.0f && c < 0x1p43f ? (uint64_t)(c * (float)(1u << FB_FRAC_BITS) + 0.5f) : 0;
}

/* A lean packet's lit lanes: each lane's slot, and per slot the kl and ka
 * shade_lane_lean gave (lanes on one untextured triangle share a slot). */
typedef struct lean_tab {
	uint8_t slot[PKT_RAYS];
	int n;
	float kl[PKT_RAYS], ka[3][PKT_RAYS];
} lean_tab;

/* The frame-buffer adds of a lean packet's misses (shade_lane's
 * background, w * background) and lean hits (shade_lane_lean's ambient
 * term, ((w kl) ka) SHADE_AMBIENT), SIMD_W lanes at a time, then each
 * lane's three fixed-point words added into its pixel: for packets whose
 * lanes carry different weights (lean_adds takes the others). */
static void lean_adds_lanes(const shade_ctx *c, const packet *p, uint64_t miss, uint64_t lit,
                            const lean_tab *t)
{
	int32_t fx[3][PKT_RAYS];
	float kl[PKT_RAYS] = {0}, ka[3][PKT_RAYS] = {{0}};
	for (uint64_t b = lit; b; b &= b - 1) {
		int i = __builtin_ctzll(b), s = t->slot[i];
		kl[i] = t->kl[s];
		for (int k = 0; k < 3; k++)
			ka[k][i] = t->ka[k][s];
	}
	const float *w[3] = {p->wr, p->wg, p->wb};
	const float bg[3] = {c->background.x, c->background.y, c->background.z};
	for (int g = 0; g < PKT_RAYS / SIMD_W; g++) {
		if (!grp_bits(miss | lit, g))
			continue;
		int o = SIMD_W * g;
		iv ish = iv_from_bits(grp_bits(lit, g));
		fv l = fv_load(kl + o);
		for (int k = 0; k < 3; k++) {
			fv wk = fv_load(w[k] + o);
			fv h = ((wk * l) * fv_load(ka[k] + o)) * fv_set1(SHADE_AMBIENT);
			iv f = fixed_v(fv_sel(ish, h, wk * fv_set1(bg[k])));
			memcpy(fx[k] + o, &f, sizeof f);
		}
	}
	for (uint64_t b = miss | lit; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		uint64_t *a = c->fb->acc + 3 * (uint64_t)p->pixel[i];
		a[0] += (uint64_t)fx[0][i];
		a[1] += (uint64_t)fx[1][i];
		a[2] += (uint64_t)fx[2][i];
	}
}

/* The lanes of mask whose weight is not lane f's (compared as floats: a
 * zero of either sign adds nothing either way, a NaN weight differs). */
static uint64_t other_weights(const packet *p, uint64_t mask, int f)
{
	const float *w[3] = {p->wr, p->wg, p->wb};
	uint64_t other = 0;
	for (int g = 0; g < PKT_RAYS / SIMD_W; g++) {
		int o = SIMD_W * g;
		iv same = iv_set1(-1);
		for (int k = 0; k < 3; k++)
			same &= fv_load(w[k] + o) == fv_set1(w[k][f]);
		other |= (uint64_t)(~iv_bits(same) & grp_bits(mask, g)) << o;
	}
	return shade_fault == SHADE_FAULT_LEAN_ONE_WEIGHT ? 0 : other;
}

/* lean_adds_lanes when every lane of miss | lit has one weight (a
 * primary packet's): the same sums, worked out once per slot and once for
 * the misses, then added lane by lane. */
static void lean_adds(const shade_ctx *c, const packet *p, uint64_t miss, uint64_t lit,
                      const lean_tab *t)
{
	uint64_t all = miss | lit;
	if (!all)
		return;
	int f = __builtin_ctzll(all);
	if (other_weights(p, all, f)) {
		lean_adds_lanes(c, p, miss, lit, t);
		return;
	}
	const float w[3] = {p->wr[f], p->wg[f], p->wb[f]};
	const float bg[3] = {c->background.x, c->background.y, c->background.z};
	uint64_t fx[PKT_RAYS][3], fm[3];
	for (int k = 0; k < 3; k++)
		fm[k] = fixed_s(w[k] * bg[k]);
	for (int s = 0; s < t->n; s++)
		for (int k = 0; k < 3; k++)
			fx[s][k] = fixed_s(((w[k] * t->kl[s]) * t->ka[k][s]) * SHADE_AMBIENT);
	for (uint64_t b = miss; b; b &= b - 1) {
		uint64_t *a = c->fb->acc + 3 * (uint64_t)p->pixel[__builtin_ctzll(b)];
		a[0] += fm[0];
		a[1] += fm[1];
		a[2] += fm[2];
	}
	for (uint64_t b = lit; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		const uint64_t *x = fx[t->slot[i]];
		uint64_t *a = c->fb->acc + 3 * (uint64_t)p->pixel[i];
		a[0] += x[0];
		a[1] += x[1];
		a[2] += x[2];
	}
}

/* The valid lanes of p without a hit. */
static uint64_t miss_lanes(const packet *p)
{
	uint64_t miss = 0;
	for (int g = 0; g < PKT_RAYS / SIMD_W; g++) {
		int o = SIMD_W * g;
		iv tri;
		memcpy(&tri, p->tri + o, sizeof tri);
		miss |=
		    (uint64_t)(iv_bits(tri == iv_set1((int32_t)PKT_NOHIT)) & grp_bits(p->valid, g))
		    << o;
	}
	return miss;
}

/* shade_packet_in's lean packet: the hits of p each by shade_lane_lean
 * into a slot of t, or by shade_lane where it does not cover them or the
 * packet spawns shadow packets; returns the lean lanes. The slot of an
 * untextured lean hit serves the later lanes on its triangle, which have
 * the same kl, ka and counts (neighbouring rays mostly do): the last
 * one's and up to LEAN_MEMO others' are looked up; their lanes' counts are
 * summed here. */
#define LEAN_MEMO 8
static uint64_t lean_hits(const shade_ctx *c, const shade_reader *rdr, const packet *p,
                          const spawn *sp, shade_counts *cnt, uint64_t hits, lean_tab *t)
{
	uint64_t lit = 0, memo = 0, nolight = 0, cuts = 0;
	uint32_t last = PKT_NOHIT, mtri[LEAN_MEMO];
	uint8_t mslot[LEAN_MEMO], scut[PKT_RAYS], snolight[PKT_RAYS];
	int ls = 0, nm = 0;
	t->n = 0;
	for (uint64_t b = hits; b; b &= b - 1) {
		int i = __builtin_ctzll(b), cut;
		uint32_t tri = p->tri[i];
		int s = tri == last ? ls : -1;
		for (int q = 0; s < 0 && q < nm; q++)
			s = mtri[q] == tri ? mslot[q] : -1;
		if (s >= 0) {
			t->slot[i] = (uint8_t)s;
			memo++;
			nolight += snolight[s];
			cuts += scut[s];
			lit |= 1ull << i;
			last = tri;
			ls = s;
			continue;
		}
		float kl;
		vec3 a;
		int r = sp->nl == 0 ? shade_lane_lean(c, rdr, p, i, sp, cnt, &kl, &a, &cut) : 0;
		if (!r) {
			shade_lane(c, NULL, rdr, p, i, sp, cnt);
			continue;
		}
		s = t->n++;
		t->kl[s] = kl;
		t->ka[0][s] = a.x;
		t->ka[1][s] = a.y;
		t->ka[2][s] = a.z;
		t->slot[i] = (uint8_t)s;
		if (r == 2 || shade_fault == SHADE_FAULT_LEAN_MEMO_TEXTURED) {
			scut[s] = (uint8_t)cut;
			snolight[s] = c->nlights == 0 && kl > 0.0f;
			last = tri;
			ls = s;
			if (nm < LEAN_MEMO) {
				mtri[nm] = tri;
				mslot[nm++] = (uint8_t)s;
			}
		}
		lit |= 1ull << i;
	}
	cnt->hits += memo;
	cnt->untextured_hits += memo;
	cnt->shadow_skip_nolight += nolight;
	cnt->depth_cut += cuts;
	return lit;
}

/* shade_packet_rd; lean: the reader is kernel-ref's image without a log
 * and the records are a single tree's (shade_packet_fp), so lanes that
 * spawn nothing may take shade_lane_lean. */
static int shade_packet_in(const shade_ctx *c, const fpfmt *fp, const shade_reader *rdr,
                           const packet *p, packet *out, int max_out, shade_counts *cnt, int lean)
{
	if (c->defer)
		c->defer->n = 0;
	const fpfmt *fq = fp && !fp->full ? fp : NULL;
	int nl = c->nlights < max_out - 2 ? c->nlights : max_out - 2;
	spawn sp = {out, out + nl, out + nl + 1, nl, p->depth < c->max_depth};
	for (int l = 0; l < nl; l++)
		pkt_clear(&sp.shadow[l], PKT_SHADOW, p->depth);
	if (sp.can_recurse) {
		pkt_clear(sp.refl, PKT_REFLECT, p->depth + 1);
		pkt_clear(sp.refr, PKT_REFRACT, p->depth + 1);
	} else /* they stay empty, and compacting drops them */
		sp.refl->valid = sp.refr->valid = 0;
	for (int l = 0; l < nl + 2; l++)
		out[l].sample = p->sample; /* children keep the pixels' sample */
	if (lean && !fq && !c->defer && c->fb) {
		/* misses and lean hits: adds in lean_adds */
		lean_tab t;
		uint64_t miss = miss_lanes(p);
		uint64_t lit = lean_hits(c, rdr, p, &sp, cnt, p->valid & ~miss, &t);
		cnt->misses += (uint64_t)__builtin_popcountll(miss);
		lean_adds(c, p, miss, lit, &t);
	} else
		for (uint64_t b = p->valid; b; b &= b - 1)
			shade_lane(c, fq, rdr, p, __builtin_ctzll(b), &sp, cnt);
	if (!sp.refl->valid && !sp.refr->valid && p->type != PKT_SHADOW)
		cnt->secondary_skip++;
	/* compact: keep only packets that carry rays */
	int k = 0;
	for (int l = 0; l < nl + 2; l++) {
		if (!out[l].valid)
			continue;
		out[l].n = PKT_RAYS;
		if (k != l)
			out[k] = out[l];
		k++;
	}
	return k;
}

int shade_packet_rd(const shade_ctx *c, const fpfmt *fp, const shade_reader *rdr, const packet *p,
                    packet *out, int max_out, shade_counts *cnt)
{
	return shade_packet_in(c, fp, rdr, p, out, max_out, cnt, 0);
}

void shade_shadow_done(const shade_ctx *c, const packet *p, shade_counts *cnt)
{
	for (uint64_t b = p->valid; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		if (p->tri[i] != PKT_NOHIT) {
			cnt->shadow_hits++;
			continue;
		}
		cnt->shadow_lit++;
		fb_add(c->fb, p->pixel[i], p->wr[i], p->wg[i], p->wb[i]);
	}
}
