/*
 * rgs.c: ray generation and shading (see rgs.h).
 */
#include "units/rgs.h"

#include <stdlib.h>
#include <string.h>

static void enter(thr_ctx *t, packet *p)
{
	t->p = p;
	thr_enter(t, p->type, thr_rays(p));
}

static void gen_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	t->env->route.enter(t);
}

int rgs_primary(thr_ctx *t, int tx, int ty)
{
	packet *p = thr_pkt_alloc(t->env);
	if (!p)
		return -1;
	const cam_frame *cam = &t->env->cam;
	cam_sample_packet(cam, tx, ty, 0, p);
	enter(t, p);
	/* the tile's further samples (kernel-ref/drt.h) queue like children:
	 * a free thread takes each, and generates it with its own RGS op
	 * (rgs_secondary); a lost one the image check reports */
	for (int s = 1; s < cam->spp; s++) {
		cam_sample_packet(cam, tx, ty, s, &t->kids[0]);
		thr_spawn(t, 1, &t->kids[0], NULL);
	}
	thr_use(t, UNIT_RGS, (int)thr_rays(p), gen_done);
	return 0;
}

void rgs_secondary(thr_ctx *t, packet *p)
{
	enter(t, p);
	if (p->type == PKT_PRIMARY) /* a tile's further sample: generated now */
		thr_use(t, UNIT_RGS, (int)thr_rays(p), gen_done);
	else
		t->env->route.enter(t);
}

static void shadow_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_release(ctx);
}

/* Room for n packets in the queue (amortised growth; order kept). */
static int queue_room(thr_rtp *r, int n)
{
	if (n <= r->qcap)
		return 0;
	int cap = r->qcap ? 2 * r->qcap : 64;
	while (cap < n)
		cap *= 2;
	thr_qitem *q = malloc((size_t)cap * sizeof *q);
	if (!q)
		return -1;
	for (int i = 0; i < r->qn; i++)
		q[i] = r->q[(r->qhead + i) % r->qcap];
	free(r->q);
	r->q = q;
	r->qhead = 0;
	r->qcap = cap;
	return 0;
}

int rgs_spawn(thr_rtp *r, thr_qitem it)
{
	if (rgs_queue_put(r, it))
		return -1;
	thr_env *v = r->env;
	++*v->c[C_SPAWNED];
	if ((uint64_t)r->qn > *v->c[C_MAX_QUEUE])
		*v->c[C_MAX_QUEUE] = (uint64_t)r->qn;
	return 0;
}

int rgs_queue_len(const thr_rtp *r)
{
	return r->qn;
}

thr_qitem rgs_queue_at(const thr_rtp *r, int i)
{
	return r->q[(r->qhead + i) % r->qcap];
}

void rgs_queue_clear(thr_rtp *r)
{
	r->qn = 0;
	r->qhead = 0;
}

int rgs_queue_put(thr_rtp *r, thr_qitem it)
{
	if (queue_room(r, r->qn + 1))
		return -1;
	r->q[(r->qhead + r->qn++) % r->qcap] = it;
	return 0;
}

void rgs_spawned(thr_rtp *r)
{
	if (r->qn > 0)
		*r->env->c[C_QUEUED] += (uint64_t)r->qn;
}

int rgs_dequeue(thr_rtp *r, thr_qitem *it)
{
	if (r->qn == 0)
		return 0;
	*it = r->q[r->qhead];
	r->qhead = (r->qhead + 1) % r->qcap;
	r->qn--;
	return 1;
}

void rgs_dispatch(thr_rtp *r)
{
	for (int i = 0; i < r->nt && r->qn > 0 && r->nidle > 0; i++)
		if (r->t[i].state == THR_IDLE)
			r->env->on_free(&r->t[i]);
}

static void shade_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	/* out of memory: a child is lost and the image check says so */
	thr_spawn(t, t->made, t->kids, NULL);
	thr_release_shaded(t);
}

/* ---- shading through the memory ----
 *
 * The shader's reads depend on each other (the shading record names the
 * material, the material its textures, a header its texels), yet a packet
 * issues them all at once (docs/design.md, "A packet's life"). So a pass
 * of the shader first finds them: each read it makes is given the bytes
 * the memory system holds at that address then (mem_peek: the L1 line, or
 * the level below), and its results are kept, not made. The distinct
 * reads then go out as SHADE requests into `got`. When they are all in,
 * the kept results stand if every returned byte equals what the pass was
 * given: the shader is a function of its bytes, so decoding the returned
 * ones would give exactly these. Otherwise (the data changed on its way:
 * a damaged fill, a test) the shader runs again on the returned bytes, and
 * reads they lead to that were not made go out in a further round. */

/* The scene bytes a pass sees when none are to be had (out of memory). */
static const uint8_t no_bytes[MIMG_SHADE_BYTES];

/* The index of read (addr, bytes) in the pass's table, or -1; *h gets
 * its slot (for adding it). */
static int find_read(thr_env *v, const thr_shade *S, uint64_t addr, uint32_t bytes, uint32_t *h)
{
	const uint32_t mask = THR_HASH_SLOTS - 1;
	uint64_t key = addr << 8 | (bytes & 0xff);
	uint32_t i = (uint32_t)((key * 0x9E3779B97F4A7C15ull) >> 40) & mask;
	for (; v->hgen[i] == v->gen; i = (i + 1) & mask)
		if (v->hkey[i] == key && S->rd[v->hidx[i]].addr == addr &&
		    S->rd[v->hidx[i]].bytes == bytes)
			return (int)v->hidx[i];
	*h = i;
	return -1;
}

/* A fresh table holding the reads found so far (a pass starts). The
 * table keeps a quarter free: past that, reads are not merged (a damaged
 * scene's endless rounds only). */
static void table_reset(thr_env *v, const thr_shade *S)
{
	if (++v->gen == 0) { /* wrapped: forget all stamps */
		memset(v->hgen, 0, THR_HASH_SLOTS * sizeof *v->hgen);
		v->gen = 1;
	}
	for (uint32_t k = 0; k < S->n && k < THR_HASH_SLOTS * 3 / 4; k++) {
		uint32_t h;
		if (find_read(v, S, S->rd[k].addr, S->rd[k].bytes, &h) < 0) {
			v->hgen[h] = v->gen;
			v->hkey[h] = S->rd[k].addr << 8 | (S->rd[k].bytes & 0xff);
			v->hidx[h] = k;
		}
	}
}

/* Room for one more read of `bytes` bytes. */
static int shade_room(thr_shade *S, uint32_t bytes)
{
	if (S->n == S->capn) {
		uint32_t cap = S->capn ? 2 * S->capn : 64;
		thr_shread *r = realloc(S->rd, cap * sizeof *r);
		if (!r)
			return -1;
		S->rd = r;
		S->capn = cap;
	}
	if (S->used + bytes > S->cap) {
		uint32_t cap = S->cap ? 2 * S->cap : 4096;
		while (cap < S->used + bytes)
			cap *= 2;
		uint8_t *a = realloc(S->peek, cap), *b = a ? realloc(S->got, cap) : NULL;
		if (a)
			S->peek = a;
		if (!b)
			return -1;
		S->got = b;
		S->cap = cap;
	}
	return 0;
}

/* The shader's reader (shade_reader): a read already made this packet
 * gives the bytes of that read (returned, or given in the first pass); a
 * new one is added with the bytes memory holds now. */
static const void *chip_shade_read(void *ctx, uint64_t addr, uint32_t bytes, int region)
{
	(void)region;
	thr_ctx *t = ctx;
	thr_env *v = t->env;
	thr_shade *S = t->sh;
	S->reads++;
	uint32_t h = 0;
	int k = S->n < THR_HASH_SLOTS * 3 / 4 ? find_read(v, S, addr, bytes, &h) : -1;
	if (k >= 0)
		return (S->delivered ? S->got : S->peek) + S->rd[k].off;
	if (bytes > sizeof no_bytes || shade_room(S, bytes)) {
		if (bytes <= sizeof no_bytes)
			v->oom = 1; /* the frame fails */
		return no_bytes;
	}
	uint32_t off = S->used;
	if (S->n < THR_HASH_SLOTS * 3 / 4) {
		v->hgen[h] = v->gen;
		v->hkey[h] = addr << 8 | (bytes & 0xff);
		v->hidx[h] = S->n;
	}
	S->rd[S->n++] = (thr_shread){addr, bytes, off};
	S->used += bytes;
	mem_req r = {addr, bytes, MEM_SHADE, 0, (uint16_t)t->rtp->id, NULL, 0};
	mem_peek(v->mem, &r, S->peek + off);
	/* until its own read returns (a later round) */
	memcpy(S->got + off, S->peek + off, bytes);
	return S->peek + off;
}

/* One pass of the shader over the thread's packet: children into kids,
 * frame-buffer adds and counts kept. */
static void shade_pass(thr_ctx *t)
{
	thr_env *v = t->env;
	thr_shade *S = t->sh;
	shade_ctx sc = v->sc;
	sc.defer = &S->adds;
	memset(&S->cnt, 0, sizeof S->cnt);
	S->reads = 0;
	table_reset(v, S);
	shade_reader rd = {chip_shade_read, t};
	t->made = shade_packet_rd(&sc, &v->prec.shade, &rd, t->p, t->kids, t->nkids, &S->cnt);
}

/* Issues the reads found since the last were issued, one request each
 * (a packet's identical reads are one request). */
static void issue_reads(thr_ctx *t)
{
	thr_shade *S = t->sh;
	thr_count(t, C_SHADE_READS, S->reads);
	for (uint32_t i = S->issued; i < S->n; i++) {
		const thr_shread *r = &S->rd[i];
		thr_count(t, C_SHADE_REQUESTS, 1);
		thr_read(t, MEM_SHADE, r->addr, r->bytes, S->got + r->off);
	}
	S->issued = S->n;
}

static void normals_moved(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	thr_use(t, UNIT_RGS, (int)thr_rays(t->p), shade_done);
}

static void shade_fetched(thr_ctx *t)
{
	thr_env *v = t->env;
	thr_shade *S = t->sh;
	if (S->round++ > 0 || v->shade_redecode || (S->used && memcmp(S->peek, S->got, S->used))) {
		/* decode what the reads returned */
		S->delivered = 1;
		uint32_t had = S->n;
		shade_pass(t);
		if (S->n > had) { /* the returned bytes led to reads not made yet */
			S->reads = S->n - had;
			issue_reads(t);
			thr_wait_mem(t, shade_fetched);
			return;
		}
	}
	/* the pass's results are made */
	shade_adds_apply(&S->adds, v->sc.fb);
	thr_shade_count(t, &S->cnt);
	/* a two-level scene's hits: their corners and normals moved into the
	 * world by the transformation unit (Schmittler et al. GH 2004), one op
	 * of the hit rays, before the shader's op */
	if (v->sc.tl && S->cnt.hits) {
		thr_use(t, UNIT_XFORM, (int)S->cnt.hits, normals_moved);
		return;
	}
	thr_use(t, UNIT_RGS, (int)thr_rays(t->p), shade_done);
}

void rgs_finish(thr_ctx *t)
{
	thr_env *v = t->env;
	packet *p = t->p;
	if (p->type == PKT_SHADOW) {
		shade_counts add;
		memset(&add, 0, sizeof add);
		shade_shadow_done(&v->sc, p, &add);
		thr_shade_count(t, &add);
		thr_use(t, UNIT_RGS, (int)thr_rays(p), shadow_done);
		return;
	}
	if (!t->sh && !(t->sh = calloc(1, sizeof *t->sh))) {
		v->oom = 1; /* the frame fails; the packet is lost */
		thr_use(t, UNIT_RGS, (int)thr_rays(p), shadow_done);
		return;
	}
	thr_shade *S = t->sh;
	S->n = S->used = S->issued = 0;
	S->delivered = S->round = 0;
	shade_pass(t);
	issue_reads(t);
	thr_wait_mem(t, shade_fetched);
}
