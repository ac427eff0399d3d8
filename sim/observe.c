/*
 * observe.c: the timeline (see observe.h; docs/observe.md).
 *
 * Track ids (Chrome trace events: pid = process, tid = track):
 *   pid r (RTP r)   tid 1 + kind * OBS_MAXINST + instance: a unit
 *                   tid OBS_TID_THREAD + thread id: a thread's states
 *   pid nrtp        tid 1: SDRAM data bus; tid 2: host bus
 *   ("memory")      tid OBS_TID_L1 * (1 + type) + MSHR: L1 misses
 * ts and dur are core cycles (the viewers show them as microseconds).
 */
#include "sim/observe.h"

#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/camera.h"
#include "kernel-ref/image.h"
#include "sim/modes/modes.h"

#define OBS_MAXINST    1000
#define OBS_TID_THREAD 100000
#define OBS_TID_L1     1000000

/* What the sink saw of a thread: its current unit op, its packet. */
typedef struct tl_thr {
	int kind, rays, ptype;
	uint64_t req;         /* tick requested */
	int tile;             /* the packet's tile (-1: none) */
	uint64_t steps, tris; /* the packet's kd steps and triangle tests so far */
} tl_thr;

/* The heat maps' sums: per tile (ticks of thread time, of it waiting for
 * memory; L1 lookup misses) and per pixel (kd steps, triangle tests). */
typedef struct heat {
	int w, h, tx, ty;
	uint64_t *cyc, *stall, *miss, unattributed;
	double *kd, *tri;
} heat;

struct obs {
	thr_sink s; /* first: the sink functions get &s */
	chip *c;
	FILE *f;         /* the timeline; NULL: none */
	heat *hm;        /* NULL: no heat maps */
	uint64_t t0, t1; /* window in ticks (t1 UINT64_MAX: open) */
	uint64_t period;
	uint64_t max, n, dropped;
	tl_thr *th;      /* per thread (gid) */
	uint64_t *ufree; /* per RTP, kind, instance: the tick the timeline's op on it ends */
	int *ubase;      /* per RTP and kind: index of its instance 0 in ufree */
	mem_obs mo;
	int mem_on, on; /* the memory observer is set; every observer is */
	void *old_state_ctx;
	void (*old_state)(void *ctx, thr_ctx *t, int to);
};

/* ---- writing ---- */

/* A tick as core cycles: an integer on a core edge, else 3 decimals. */
static void put_cyc(FILE *f, uint64_t ticks, uint64_t period)
{
	if (ticks % period == 0)
		fprintf(f, "%" PRIu64, ticks / period);
	else
		fprintf(f, "%.3f", (double)ticks / (double)period);
}

/* Is an event starting at tick a in the window? Counts it against the cap;
 * 0: leave it out. */
static int take(obs *o, uint64_t a)
{
	if (a < o->t0 || a >= o->t1)
		return 0;
	if (o->n >= o->max) {
		o->dropped++;
		return 0;
	}
	o->n++;
	return 1;
}

/* The head of a complete event ("X") [a, b) ticks; args follow. */
static void span(obs *o, const char *name, int pid, int tid, uint64_t a, uint64_t b)
{
	fprintf(o->f, ",\n{\"ph\":\"X\",\"name\":\"%s\",\"pid\":%d,\"tid\":%d,\"ts\":", name, pid,
	        tid);
	put_cyc(o->f, a, o->period);
	fputs(",\"dur\":", o->f);
	put_cyc(o->f, b - a, o->period);
}

static void meta(obs *o, const char *what, int pid, int tid, const char *name, int sort)
{
	fprintf(o->f,
	        ",\n{\"ph\":\"M\",\"name\":\"%s_name\",\"pid\":%d,\"tid\":%d,\"args\":{\"name\":\"%"
	        "s\"}}",
	        what, pid, tid, name);
	fprintf(o->f,
	        ",\n{\"ph\":\"M\",\"name\":\"%s_sort_index\",\"pid\":%d,\"tid\":%d,\"args\":{"
	        "\"sort_index\":%d}}",
	        what, pid, tid, sort);
}

/* ---- the observer sink: each op's kind, rays and request tick ---- */

static void o_read(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes, void *dst)
{
	s->inner->op->read(s->inner, t, type, addr, bytes, dst);
}

static void o_write(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes,
                    const void *src)
{
	s->inner->op->write(s->inner, t, type, addr, bytes, src);
}

static int o_wait(thr_sink *s, thr_ctx *t, void (*cont)(thr_ctx *t))
{
	return s->inner->op->wait(s->inner, t, cont);
}

static void o_use(thr_sink *s, thr_ctx *t, int kind, int rays, eng_handler done)
{
	obs *o = (obs *)s;
	tl_thr *h = &o->th[t->gid];
	h->kind = kind;
	h->rays = rays;
	h->req = eng_now(t->env->e);
	s->inner->op->use(s->inner, t, kind, rays, done);
}

static void o_count(thr_sink *s, thr_ctx *t, int id, uint64_t n)
{
	tl_thr *h = &((obs *)s)->th[t->gid];
	if (id == C_NODE_STEPS)
		h->steps += n;
	else if (id == C_TRI_TESTS)
		h->tris += n;
	s->inner->op->count(s->inner, t, id, n);
}

static void o_count_max(thr_sink *s, thr_ctx *t, int id, uint64_t v)
{
	s->inner->op->count_max(s->inner, t, id, v);
}

static void o_shade(thr_sink *s, thr_ctx *t, const shade_counts *add)
{
	s->inner->op->shade(s->inner, t, add);
}

static void o_enter(thr_sink *s, thr_ctx *t, int type, uint64_t rays)
{
	obs *o = (obs *)s;
	tl_thr *h = &o->th[t->gid];
	h->ptype = type;
	h->steps = h->tris = 0;
	h->tile = -1;
	if (o->hm && t->p && t->p->valid) {
		uint32_t px = t->p->pixel[__builtin_ctzll(t->p->valid)];
		int x = (int)(px % (uint32_t)o->hm->w), y = (int)(px / (uint32_t)o->hm->w);
		h->tile = (y / TILE_H) * o->hm->tx + x / TILE_W;
	}
	s->inner->op->enter(s->inner, t, type, rays);
}

static int o_spawn(thr_sink *s, thr_ctx *t, int n, const packet *kids, const int32_t *ids)
{
	return s->inner->op->spawn(s->inner, t, n, kids, ids);
}

/* The packet's kd steps and triangle tests, shared evenly by its rays'
 * pixels. */
static void o_release(thr_sink *s, thr_ctx *t, int shaded)
{
	obs *o = (obs *)s;
	tl_thr *h = &o->th[t->gid];
	if (o->hm && t->p && t->p->valid && (h->steps || h->tris)) {
		int nv = thr_pop(t->p->valid);
		double ks = (double)h->steps / nv, ts = (double)h->tris / nv;
		for (uint64_t m = t->p->valid; m; m &= m - 1) {
			uint32_t px = t->p->pixel[__builtin_ctzll(m)];
			o->hm->kd[px] += ks;
			o->hm->tri[px] += ts;
		}
		h->steps = h->tris = 0;
	}
	s->inner->op->release(s->inner, t, shaded);
}

static const thr_sink_ops tl_ops = {o_read,      o_write, o_wait,  o_use,   o_count,
                                    o_count_max, o_shade, o_enter, o_spawn, o_release};

/* ---- the units' issue (thr_unit.on_start) ---- */

/* The op of thread ctx issues now: at the unit's next edge, on the
 * instance whose free tick start() just set (of those, one the timeline
 * has not already given an op ending there). */
static void tl_on_start(void *ctx, uint64_t arg)
{
	thr_ctx *t = ctx;
	obs *o = t->env->state_ctx;
	if (!o->f) {
		thr_on_start(ctx, arg);
		return;
	}
	const tl_thr *h = &o->th[t->gid];
	thr_unit *u = &t->rtp->u[h->kind];
	uint64_t a = eng_next_edge(u->clk, eng_now(u->e));
	uint64_t issue = thr_unit_issue(u, h->rays);
	uint64_t b = a + eng_cycles_to_ticks(u->clk, issue);
	uint64_t *uf = o->ufree + o->ubase[t->rtp->id * UNIT_NKINDS + h->kind];
	int inst = 0;
	for (int i = 0; i < u->count; i++)
		if (u->free_at[i] == b && uf[i] <= a) {
			inst = i;
			break;
		}
	uf[inst] = b;
	if (take(o, a)) {
		span(o, chip_unit_name(h->kind), t->rtp->id, 1 + h->kind * OBS_MAXINST + inst, a,
		     b);
		fprintf(o->f,
		        ",\"args\":{\"thread\":%d,\"rays\":%d,\"kind\":\"%s\",\"instance\":%d,"
		        "\"issue_cycles\":%" PRIu64 ",\"latency\":%d,\"waited\":",
		        t->id, h->rays, chip_unit_name(h->kind), inst, issue, u->latency);
		put_cyc(o->f, a - h->req, o->period);
		fputs("}}", o->f);
	}
	thr_on_start(ctx, arg);
}

/* ---- threads' states ---- */

static void state_span(obs *o, thr_ctx *t, uint64_t now)
{
	if (t->state == THR_IDLE || now <= t->since)
		return;
	int tile = o->th[t->gid].tile;
	if (o->hm && tile >= 0) {
		o->hm->cyc[tile] += now - t->since;
		if (t->state == THR_WAIT_MEM)
			o->hm->stall[tile] += now - t->since;
	}
	if (!o->f)
		return;
	/* the span's part inside the window */
	uint64_t a = t->since > o->t0 ? t->since : o->t0, b = now < o->t1 ? now : o->t1;
	if (a >= b || !take(o, a))
		return;
	span(o, chip_state_name(t->state), t->rtp->id, OBS_TID_THREAD + t->id, a, b);
	fprintf(o->f, ",\"args\":{\"thread\":%d,\"packet\":\"%s\"}}", t->id,
	        pkt_type_name(o->th[t->gid].ptype));
}

static void tl_on_state(void *ctx, thr_ctx *t, int to)
{
	(void)to;
	obs *o = ctx;
	state_span(o, t, eng_now(t->env->e));
}

/* ---- memory ---- */

static void tl_mem(void *ctx, const mem_obs_ev *ev)
{
	obs *o = ctx;
	if (ev->kind == MEM_OBS_L1_LOOKUP_MISS) {
		const thr_ctx *t = ev->who;
		int tile = t ? o->th[t->gid].tile : -1;
		if (!o->hm)
			return;
		if (tile >= 0)
			o->hm->miss[tile]++;
		else
			o->hm->unattributed++;
		return;
	}
	if (!o->f || !take(o, ev->t0))
		return;
	int pid = o->c->nrtp;
	static const char *const l1_miss_name[MEM_NTYPES] = {"shade miss", "kd miss", "list miss",
	                                                     "tri miss"};
	if (ev->kind == MEM_OBS_L1_MISS) {
		span(o, l1_miss_name[ev->type], pid, OBS_TID_L1 * (1 + ev->type) + ev->id, ev->t0,
		     ev->t1);
		fprintf(o->f, ",\"args\":{\"l1\":\"%s\",\"mshr\":%d,\"addr\":%" PRIu64 "}}",
		        mem_type_name(ev->type), ev->id, ev->addr);
	} else if (ev->kind == MEM_OBS_SDRAM) {
		static const char *const row[] = {"row_hit", "row_empty", "row_conflict"};
		span(o, ev->write ? "write" : "read", pid, 1, ev->t0, ev->t1);
		fprintf(o->f,
		        ",\"args\":{\"bank\":%d,\"row\":\"%s\",\"bytes\":%u,\"addr\":%" PRIu64 "}}",
		        ev->id, row[ev->type], ev->bytes, ev->addr);
	} else {
		span(o, "dma", pid, 2, ev->t0, ev->t1);
		fprintf(o->f, ",\"args\":{\"bytes\":%u}}", ev->bytes);
	}
}

/* ---- start and end ---- */

int obs_parse_window(const char *flag, const char *s, uint64_t *c0, uint64_t *c1, diag *d)
{
	const char *colon = strchr(s, ':');
	if (!colon)
		return diag_set(d, flag, 0, 0, "'%s': expected C0:C1 (cycles, C0 < C1)", s);
	*c0 = 0;
	*c1 = UINT64_MAX;
	char *end;
	if (colon != s) {
		if (*s < '0' || *s > '9')
			goto bad;
		errno = 0;
		unsigned long long v = strtoull(s, &end, 10);
		if (errno || end != colon)
			goto bad;
		*c0 = v;
	}
	if (colon[1]) {
		if (colon[1] < '0' || colon[1] > '9')
			goto bad;
		errno = 0;
		unsigned long long v = strtoull(colon + 1, &end, 10);
		if (errno || *end)
			goto bad;
		*c1 = v;
	}
	if (*c0 >= *c1)
		goto bad;
	return 0;
bad:
	return diag_set(d, flag, 0, 0, "'%s': expected C0:C1 (cycles, C0 < C1)", s);
}

/* The timeline's head: the tracks' names and order (units, then threads;
 * the memory process last). */
static void tl_head(obs *o)
{
	chip *c = o->c;
	FILE *f = o->f;
	fputs("{\"traceEvents\":[\n{\"ph\":\"M\",\"name\":"
	      "\"process_name\",\"pid\":0,\"args\":{\"name\":\"RTP 0\"}}",
	      f);
	char name[64];
	for (int r = 0; r < c->nrtp; r++) {
		snprintf(name, sizeof name, "RTP %d", r);
		if (r)
			fprintf(f,
			        ",\n{\"ph\":\"M\",\"name\":\"process_name\",\"pid\":%d,\"args\":{"
			        "\"name\":\"%s\"}}",
			        r, name);
		fprintf(f,
		        ",\n{\"ph\":\"M\",\"name\":\"process_sort_index\",\"pid\":%d,\"args\":{"
		        "\"sort_index\":%d}}",
		        r, r);
		for (int k = 0; k < UNIT_NKINDS; k++)
			for (int i = 0; i < c->rtp[r].u[k].count; i++) {
				snprintf(name, sizeof name, "%s %d", chip_unit_name(k), i);
				meta(o, "thread", r, 1 + k * OBS_MAXINST + i, name,
				     1 + k * OBS_MAXINST + i);
			}
		for (int t = 0; t < c->tpr; t++) {
			snprintf(name, sizeof name, "thread %d", t);
			meta(o, "thread", r, OBS_TID_THREAD + t, name, OBS_TID_THREAD + t);
		}
	}
	int pm = c->nrtp;
	fprintf(f,
	        ",\n{\"ph\":\"M\",\"name\":\"process_name\",\"pid\":%d,\"args\":{\"name\":"
	        "\"memory\"}},\n{\"ph\":\"M\",\"name\":\"process_sort_index\",\"pid\":%d,"
	        "\"args\":{\"sort_index\":%d}}",
	        pm, pm, pm);
	meta(o, "thread", pm, 1, "SDRAM data bus", 1);
	meta(o, "thread", pm, 2, "host bus", 2);
	for (int t = 0; t < MEM_NTYPES; t++) {
		snprintf(name, sizeof name, "L1 %s misses", mem_type_name(t));
		meta(o, "thread", pm, OBS_TID_L1 * (1 + t), name, OBS_TID_L1 * (1 + t));
	}
}

static void heat_free(heat *h)
{
	if (!h)
		return;
	free(h->cyc);
	free(h->stall);
	free(h->miss);
	free(h->kd);
	free(h->tri);
	free(h);
}

static heat *heat_new(const chip *c)
{
	heat *h = calloc(1, sizeof *h);
	if (!h)
		return NULL;
	h->w = c->cfg.frame.width;
	h->h = c->cfg.frame.height;
	h->tx = c->g.tiles_x;
	h->ty = c->g.tiles_y;
	size_t nt = (size_t)h->tx * (size_t)h->ty, np = (size_t)h->w * (size_t)h->h;
	h->cyc = calloc(nt, sizeof *h->cyc);
	h->stall = calloc(nt, sizeof *h->stall);
	h->miss = calloc(nt, sizeof *h->miss);
	h->kd = calloc(np, sizeof *h->kd);
	h->tri = calloc(np, sizeof *h->tri);
	if (!h->cyc || !h->stall || !h->miss || !h->kd || !h->tri) {
		heat_free(h);
		return NULL;
	}
	return h;
}

/* The chip as it was without the observers. */
static void obs_free_hooks(obs *o)
{
	if (!o->on)
		return;
	chip *c = o->c;
	mode_observe(&c->md, NULL);
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++)
			c->rtp[r].u[k].on_start = thr_on_start;
	c->env.on_state = o->old_state;
	c->env.state_ctx = o->old_state_ctx;
	if (o->mem_on)
		mem_observe(&c->mem, NULL);
	o->on = 0;
}

void obs_free(obs *o)
{
	if (!o)
		return;
	obs_free_hooks(o);
	heat_free(o->hm);
	free(o->th);
	free(o->ufree);
	free(o->ubase);
	free(o);
}

obs *obs_start(chip *c, const obs_opts *p, const char *flag, diag *d)
{
	if (c->cfg.fidelity != CFG_FIDELITY_CYCLE) {
		diag_set(d, flag, 0, 0, "needs --fidelity cycle (this run's is %s)",
		         c->cfg.fidelity == CFG_FIDELITY_SAMPLED ? "sampled" : "functional");
		return NULL;
	}
	obs *o = calloc(1, sizeof *o);
	int nu = 0;
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++)
			nu += c->rtp[r].u[k].count;
	if (o) {
		o->c = c;
		o->th = calloc((size_t)(c->nrtp * c->tpr), sizeof *o->th);
		o->ufree = calloc((size_t)nu, sizeof *o->ufree);
		o->ubase = calloc((size_t)(c->nrtp * UNIT_NKINDS), sizeof *o->ubase);
		o->hm = p->heat ? heat_new(c) : NULL;
	}
	if (!o || !o->th || !o->ufree || !o->ubase || (p->heat && !o->hm)) {
		obs_free(o);
		diag_set(d, flag, 0, 0, "out of memory");
		return NULL;
	}
	for (int i = 0; i < c->nrtp * c->tpr; i++)
		o->th[i].tile = -1;
	o->f = p->tl;
	o->period = c->clk.period;
	o->t0 = p->c0 > UINT64_MAX / o->period ? UINT64_MAX : p->c0 * o->period;
	o->t1 = p->c1 > UINT64_MAX / o->period ? UINT64_MAX : p->c1 * o->period;
	o->max = p->max;
	nu = 0;
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++) {
			o->ubase[r * UNIT_NKINDS + k] = nu;
			nu += c->rtp[r].u[k].count;
		}
	if (o->f)
		tl_head(o);
	/* the observers */
	o->s.op = &tl_ops;
	mode_observe(&c->md, &o->s);
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++)
			c->rtp[r].u[k].on_start = tl_on_start;
	o->old_state = c->env.on_state;
	o->old_state_ctx = c->env.state_ctx;
	c->env.on_state = tl_on_state;
	c->env.state_ctx = o;
	o->mo = (mem_obs){tl_mem, o};
	o->mem_on = mem_observe(&c->mem, &o->mo) == 0;
	o->on = 1;
	return o;
}

int obs_finish(obs *o, uint64_t *written, uint64_t *dropped)
{
	chip *c = o->c;
	uint64_t now = eng_now(c->e);
	for (int r = 0; r < c->nrtp; r++)
		for (int t = 0; t < c->tpr; t++) {
			thr_ctx *th = &c->rtp[r].t[t];
			state_span(o, th, now);
		}
	int bad = 0;
	if (o->f) {
		fprintf(o->f,
		        "\n],\n\"otherData\":{\"cycle_unit\":\"core cycle\",\"period_ps\":%" PRIu64
		        ",\"rtps\":%d,\"threads_per_rtp\":%d,\"window\":[",
		        o->period, c->nrtp, c->tpr);
		put_cyc(o->f, o->t0, o->period);
		fputc(',', o->f);
		if (o->t1 == UINT64_MAX)
			fputs("null", o->f);
		else
			put_cyc(o->f, o->t1, o->period);
		fprintf(o->f,
		        "],\"events\":%" PRIu64 ",\"max_events\":%" PRIu64
		        ",\"dropped_events\":%" PRIu64 ",\"capped\":%s}}\n",
		        o->n, o->max, o->dropped, o->dropped ? "true" : "false");
		bad = ferror(o->f) ? -1 : 0;
		o->f = NULL; /* written: the caller closes it */
	}
	if (written)
		*written = o->n;
	if (dropped)
		*dropped = o->dropped;
	/* the observers off; the heat maps stay for obs_heat_write */
	obs_free_hooks(o);
	return bad;
}

/* ---- heat maps ---- */

const char *const obs_heat_files[] = {"cycles.exr",    "cycles.png",    "mem_stall.exr",
                                      "mem_stall.png", "l1_misses.exr", "l1_misses.png",
                                      "kd_steps.exr",  "kd_steps.png",  "tri_tests.exr",
                                      "tri_tests.png", "heatmap.json",  NULL};

/* viridis at 0, 1/4, 1/2, 3/4, 1 */
static void colour(double v, uint8_t *rgb)
{
	static const uint8_t stop[5][3] = {
	    {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
	if (!(v > 0))
		v = 0;
	if (v > 1)
		v = 1;
	double x = v * 4;
	int i = x >= 4 ? 3 : (int)x;
	double f = x - i;
	for (int k = 0; k < 3; k++)
		rgb[k] = (uint8_t)(stop[i][k] + (stop[i + 1][k] - stop[i][k]) * f + 0.5);
}

/* A 3x5 font for the colour bar's numbers: rows top down, 3 bits each. */
static const char glyph_chars[] = "0123456789.-+e";
static const uint8_t glyph[][5] = {
    {7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7}, {5, 5, 7, 1, 1},
    {7, 4, 7, 1, 7}, {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7},
    {0, 0, 0, 0, 2}, {0, 0, 7, 0, 0}, {0, 2, 7, 2, 0}, {0, 7, 7, 4, 7}};

#define GS 2 /* font scale */

/* Draws text at (x, y) in white, each glyph 3 x 5 cells of GS pixels. */
static void text(uint8_t *img, int w, int h, int x, int y, const char *s)
{
	for (; *s; s++, x += 4 * GS) {
		const char *g = strchr(glyph_chars, *s);
		if (!g)
			continue;
		const uint8_t *rows = glyph[g - glyph_chars];
		for (int r = 0; r < 5 * GS; r++)
			for (int col = 0; col < 3 * GS; col++) {
				int px = x + col, py = y + r;
				if (px < 0 || py < 0 || px >= w || py >= h)
					continue;
				if (rows[r / GS] & (4 >> (col / GS)))
					memset(img + ((size_t)py * (size_t)w + (size_t)px) * 3, 255,
					       3);
			}
	}
}

/* One map: its values (n x m, per tile or per pixel) as EXR (the raw
 * values, one 32-bit float channel Y) and as false-colour PNG at the
 * frame's size (an integer multiple, at least 256 pixels wide) with a
 * colour bar from 0 to bar_top below it. */
static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return x < y ? -1 : x > y;
}

/* The value at the colour bar's top: the 99th percentile of the map's
 * values, so that a few hot tiles or pixels do not leave the rest dark
 * (larger values saturate); the maximum when that is 0. */
static double bar_top(const double *v, size_t n, double mx)
{
	double *s = malloc(n * sizeof *s);
	if (!s)
		return mx;
	memcpy(s, v, n * sizeof *s);
	qsort(s, n, sizeof *s, cmp_double);
	double top = s[(n - 1) * 99 / 100];
	free(s);
	return top > 0 ? top : mx;
}

static int write_map(const heat *hm, const char *dir, const char *name, const double *v,
                     int per_tile, double *total, double *vmax, double *vtop, af_group *g, diag *d)
{
	int n = per_tile ? hm->tx : hm->w, m = per_tile ? hm->ty : hm->h;
	size_t cnt = (size_t)n * (size_t)m;
	double mx = 0, sum = 0;
	for (size_t i = 0; i < cnt; i++) {
		sum += v[i];
		if (v[i] > mx)
			mx = v[i];
	}
	*total = sum;
	*vmax = mx;
	double top = *vtop = bar_top(v, cnt, mx);
	char path[4200];
	int rc = -1;
	float *f = malloc(cnt * sizeof *f);
	uint8_t *c8 = malloc(cnt * 3);
	int k = hm->w >= 256 ? 1 : (256 + hm->w - 1) / hm->w;
	int pw = hm->w * k, bar = 8 + 12 + 4 + 5 * GS + 6, ph = hm->h * k + bar;
	uint8_t *png = calloc((size_t)pw * (size_t)ph, 3);
	if (!f || !c8 || !png) {
		diag_set(d, "--heatmap", 0, 0, "out of memory");
		goto out;
	}
	for (size_t i = 0; i < cnt; i++) {
		f[i] = (float)v[i];
		colour(top > 0 ? v[i] / top : 0, c8 + 3 * i);
	}
	snprintf(path, sizeof path, "%s/%s.exr", dir, name);
	if (img_write_values(path, n, m, f, g, d))
		goto out;
	for (int y = 0; y < hm->h * k; y++)
		for (int x = 0; x < pw; x++) {
			int px = x / k, py = y / k;
			size_t i = per_tile ? (size_t)(py / TILE_H) * (size_t)hm->tx +
			                          (size_t)(px / TILE_W)
			                    : (size_t)py * (size_t)hm->w + (size_t)px;
			memcpy(png + ((size_t)y * (size_t)pw + (size_t)x) * 3, c8 + 3 * i, 3);
		}
	/* the colour bar: 0 at the left, top at the right */
	int y0 = hm->h * k + 8, x0 = 4, x1 = pw - 4;
	for (int y = y0; y < y0 + 12; y++)
		for (int x = x0; x < x1; x++)
			colour((double)(x - x0) / (double)(x1 - x0 - 1 > 0 ? x1 - x0 - 1 : 1),
			       png + ((size_t)y * (size_t)pw + (size_t)x) * 3);
	char lab[32];
	text(png, pw, ph, x0, y0 + 16, "0");
	snprintf(lab, sizeof lab, "%.4g", top);
	text(png, pw, ph, x1 - (int)strlen(lab) * 4 * GS + GS, y0 + 16, lab);
	snprintf(path, sizeof path, "%s/%s.png", dir, name);
	if (img_write(path, pw, ph, png, NULL, g, d))
		goto out;
	rc = 0;
out:
	free(f);
	free(c8);
	free(png);
	return rc;
}

int obs_heat_write(const obs *o, const char *dir, af_group *g, diag *d)
{
	const heat *hm = o->hm;
	size_t nt = (size_t)hm->tx * (size_t)hm->ty;
	double *tv[3];
	for (int i = 0; i < 3; i++)
		tv[i] = malloc(nt * sizeof **tv);
	int rc = -1;
	if (!tv[0] || !tv[1] || !tv[2]) {
		diag_set(d, "--heatmap", 0, 0, "out of memory");
		goto out;
	}
	double per = (double)o->period;
	for (size_t i = 0; i < nt; i++) {
		tv[0][i] = (double)hm->cyc[i] / per;
		tv[1][i] = (double)hm->stall[i] / per;
		tv[2][i] = (double)hm->miss[i];
	}
	static const struct {
		const char *name, *unit;
		int per_tile;
	} maps[5] = {
	    {"cycles", "thread cycles on the tile's packets (running or waiting)", 1},
	    {"mem_stall", "thread cycles waiting for memory", 1},
	    {"l1_misses", "L1 lookup misses (new and merged)", 1},
	    {"kd_steps", "kd-tree node steps, each packet's shared by its rays", 0},
	    {"tri_tests", "triangle tests, each packet's shared by its rays", 0},
	};
	const double *vals[5] = {tv[0], tv[1], tv[2], hm->kd, hm->tri};
	double total[5], vmax[5], vtop[5];
	for (int i = 0; i < 5; i++)
		if (write_map(hm, dir, maps[i].name, vals[i], maps[i].per_tile, &total[i], &vmax[i],
		              &vtop[i], g, d))
			goto out;
	char path[4200];
	snprintf(path, sizeof path, "%s/heatmap.json", dir);
	afile a;
	if (af_open(&a, path, "", 1)) {
		af_diag(d, path);
		goto out;
	}
	fprintf(a.f,
	        "{\"width\":%d,\"height\":%d,\"tile_width\":%d,\"tile_height\":%d,\"tiles_x\":%d,"
	        "\"tiles_y\":%d,\"period_ps\":%" PRIu64 ",\"l1_misses_unattributed\":%" PRIu64
	        ",\"maps\":{",
	        hm->w, hm->h, TILE_W, TILE_H, hm->tx, hm->ty, o->period, hm->unattributed);
	for (int i = 0; i < 5; i++)
		fprintf(a.f,
		        "%s\n\"%s\":{\"per\":\"%s\",\"what\":\"%s\",\"exr\":\"%s.exr\",\"png\":"
		        "\"%s.png\",\"total\":%.17g,\"max\":%.17g,\"png_top\":%.17g}",
		        i ? "," : "", maps[i].name, maps[i].per_tile ? "tile" : "pixel",
		        maps[i].unit, maps[i].name, maps[i].name, total[i], vmax[i], vtop[i]);
	fputs("}}\n", a.f);
	if (af_commit_to(&a, g)) {
		af_diag(d, path);
		goto out;
	}
	rc = 0;
out:
	for (int i = 0; i < 3; i++)
		free(tv[i]);
	return rc;
}
