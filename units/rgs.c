/*
 * rgs.c: ray generation and shading (see rgs.h).
 */
#include "rgs.h"

#include <stdlib.h>
#include <string.h>

#include "traversal.h"

void rgs_enter_count(thr_ctx *t, int type, uint64_t rays)
{
	thr_env *v = t->env;
	t->age = v->next_age++;
	++*v->c[C_PKT_PRIMARY + type];
	*v->c[C_RAYS_PRIMARY + type] += rays;
	memset(t->raddr, 0, sizeof t->raddr);
	memset(t->rbytes, 0, sizeof t->rbytes);
	thr_rec(t, PR_ENTER, 2, (uint64_t)type, rays);
}

static void enter(thr_ctx *t, packet *p)
{
	t->p = p;
	rgs_enter_count(t, p->type, thr_rays(p));
}

static void gen_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	tu_begin(ctx);
}

int rgs_primary(thr_ctx *t, int tx, int ty)
{
	packet *p = thr_pkt_alloc(t->env);
	if (!p)
		return -1;
	cam_primary_packet(&t->env->cam, tx, ty, p);
	enter(t, p);
	thr_use(t, UNIT_RGS, (int)thr_rays(p), gen_done);
	return 0;
}

void rgs_secondary(thr_ctx *t, packet *p)
{
	enter(t, p);
	tu_begin(t);
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
	if (queue_room(r, r->qn + 1))
		return -1;
	r->q[(r->qhead + r->qn++) % r->qcap] = it;
	thr_env *v = r->env;
	++*v->c[C_SPAWNED];
	if ((uint64_t)r->qn > *v->c[C_MAX_QUEUE])
		*v->c[C_MAX_QUEUE] = (uint64_t)r->qn;
	return 0;
}

int rgs_queue_set(thr_rtp *r, const thr_qitem *it, int n)
{
	r->qn = 0;
	r->qhead = 0;
	if (queue_room(r, n))
		return -1;
	for (int i = 0; i < n; i++)
		r->q[i] = it[i];
	r->qn = n;
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
	if (r->env->func) /* functional processing hands out work itself */
		return;
	for (int i = 0; i < r->nt && r->qn > 0 && r->nidle > 0; i++)
		if (r->t[i].state == THR_IDLE)
			r->env->on_free(&r->t[i]);
}

static void shade_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	thr_env *v = t->env;
	thr_rtp *r = t->rtp;
	thr_rec(t, PR_SPAWN, 1, (uint64_t)t->made, 0);
	for (int k = 0; k < t->made; k++) {
		packet *p = thr_pkt_alloc(v);
		int32_t id = v->rec_out ? pr_new_kid(v->rec_out, t->rec, k) : -1;
		if (v->rec_out)
			pr_put_u(v->rec_out, t->rec, (uint64_t)(id < 0 ? 0 : id));
		/* out of memory: the packet is lost and the image check says so */
		if (!p || rgs_spawn(r, (thr_qitem){p, id})) {
			if (p)
				thr_pkt_free(v, p);
			if (v->rec_out)
				v->rec_out->failed = 1;
			continue;
		}
		memcpy(p, &t->kids[k], sizeof *p);
	}
	rgs_spawned(r);
	thr_release(t);
	rgs_dispatch(r);
}

static void shade_fetched(thr_ctx *t)
{
	thr_use(t, UNIT_RGS, (int)thr_rays(t->p), shade_done);
}

/* Issues the packet's logged reads, one request per distinct (addr, bytes). */
static void issue_reads(thr_ctx *t)
{
	thr_env *v = t->env;
	const shade_log *log = &v->log;
	const uint32_t mask = THR_HASH_SLOTS - 1;
	if (++v->gen == 0) { /* wrapped: forget all stamps */
		memset(v->hgen, 0, THR_HASH_SLOTS * sizeof *v->hgen);
		v->gen = 1;
	}
	thr_count(t, C_SHADE_READS, log->n);
	for (uint32_t i = 0; i < log->n; i++) {
		const shade_read *rd = &log->e[i];
		uint64_t key = rd->addr << 8 | (rd->bytes & 0xff);
		uint32_t h = (uint32_t)((key * 0x9E3779B97F4A7C15ull) >> 40) & mask;
		int dup = 0;
		while (v->hgen[h] == v->gen) {
			if (v->hkey[h] == key) {
				dup = 1;
				break;
			}
			h = (h + 1) & mask;
		}
		if (dup)
			continue;
		v->hgen[h] = v->gen;
		v->hkey[h] = key;
		thr_count(t, C_SHADE_REQUESTS, 1);
		thr_read(t, MEM_SHADE, rd->addr, rd->bytes);
	}
}

/* Records what shading added to the shade counts since `before`. */
static void rec_shade(thr_ctx *t, const shade_counts *before)
{
	const uint64_t *a = (const uint64_t *)before, *b = (const uint64_t *)&t->env->sh;
	for (size_t i = 0; i < sizeof(shade_counts) / sizeof(uint64_t); i++)
		if (b[i] != a[i])
			thr_rec(t, PR_SHADE, 2, (uint64_t)i, b[i] - a[i]);
}

void rgs_finish(thr_ctx *t)
{
	thr_env *v = t->env;
	packet *p = t->p;
	/* recording: what shading adds to the shade counts goes in the stream */
	shade_counts before;
	if (v->rec_out)
		before = v->sh;
	if (p->type == PKT_SHADOW) {
		shade_shadow_done(&v->sc, p, &v->sh);
		if (v->rec_out)
			rec_shade(t, &before);
		thr_use(t, UNIT_RGS, (int)thr_rays(p), shadow_done);
		return;
	}
	v->log.n = 0;
	t->made = shade_packet_fp(&v->sc, &v->prec.shade, p, t->kids, t->nkids, &v->log, &v->sh);
	if (v->rec_out)
		rec_shade(t, &before);
	issue_reads(t);
	thr_wait_mem(t, shade_fetched);
}
