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

#include "sim/modes/modes.h"

#define OBS_MAXINST    1000
#define OBS_TID_THREAD 100000
#define OBS_TID_L1     1000000

/* What the sink saw of a thread's current unit op. */
typedef struct tl_thr {
	int kind, rays, ptype;
	uint64_t req; /* tick requested */
} tl_thr;

struct obs_timeline {
	thr_sink s; /* first: the sink functions get &s */
	chip *c;
	FILE *f;
	uint64_t t0, t1; /* window in ticks (t1 UINT64_MAX: open) */
	uint64_t period;
	uint64_t max, n, dropped;
	tl_thr *th;      /* per thread (gid) */
	uint64_t *ufree; /* per RTP, kind, instance: the tick the timeline's op on it ends */
	int *ubase;      /* per RTP and kind: index of its instance 0 in ufree */
	mem_obs mo;
	int mem_on;
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
static int take(obs_timeline *o, uint64_t a)
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
static void span(obs_timeline *o, const char *name, int pid, int tid, uint64_t a, uint64_t b)
{
	fprintf(o->f, ",\n{\"ph\":\"X\",\"name\":\"%s\",\"pid\":%d,\"tid\":%d,\"ts\":", name, pid,
	        tid);
	put_cyc(o->f, a, o->period);
	fputs(",\"dur\":", o->f);
	put_cyc(o->f, b - a, o->period);
}

static void meta(obs_timeline *o, const char *what, int pid, int tid, const char *name, int sort)
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
	obs_timeline *o = (obs_timeline *)s;
	tl_thr *h = &o->th[t->gid];
	h->kind = kind;
	h->rays = rays;
	h->req = eng_now(t->env->e);
	s->inner->op->use(s->inner, t, kind, rays, done);
}

static void o_count(thr_sink *s, thr_ctx *t, int id, uint64_t n)
{
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
	((obs_timeline *)s)->th[t->gid].ptype = type;
	s->inner->op->enter(s->inner, t, type, rays);
}

static int o_spawn(thr_sink *s, thr_ctx *t, int n, const packet *kids, const int32_t *ids)
{
	return s->inner->op->spawn(s->inner, t, n, kids, ids);
}

static void o_release(thr_sink *s, thr_ctx *t, int shaded)
{
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
	obs_timeline *o = t->env->state_ctx;
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

static void state_span(obs_timeline *o, thr_ctx *t, uint64_t now)
{
	if (t->state == THR_IDLE || now <= t->since)
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
	obs_timeline *o = ctx;
	state_span(o, t, eng_now(t->env->e));
}

/* ---- memory ---- */

static void tl_mem(void *ctx, const mem_obs_ev *ev)
{
	obs_timeline *o = ctx;
	if (!take(o, ev->t0))
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

obs_timeline *obs_timeline_start(chip *c, FILE *f, uint64_t c0, uint64_t c1, uint64_t max_events,
                                 diag *d)
{
	if (c->cfg.fidelity != CFG_FIDELITY_CYCLE) {
		diag_set(d, "--timeline", 0, 0, "needs --fidelity cycle (this run's is %s)",
		         c->cfg.fidelity == CFG_FIDELITY_SAMPLED ? "sampled" : "functional");
		return NULL;
	}
	obs_timeline *o = calloc(1, sizeof *o);
	int nu = 0;
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++)
			nu += c->rtp[r].u[k].count;
	if (o) {
		o->th = calloc((size_t)(c->nrtp * c->tpr), sizeof *o->th);
		o->ufree = calloc((size_t)nu, sizeof *o->ufree);
		o->ubase = calloc((size_t)(c->nrtp * UNIT_NKINDS), sizeof *o->ubase);
	}
	if (!o || !o->th || !o->ufree || !o->ubase) {
		if (o) {
			free(o->th);
			free(o->ufree);
			free(o->ubase);
		}
		free(o);
		diag_set(d, "--timeline", 0, 0, "out of memory");
		return NULL;
	}
	o->c = c;
	o->f = f;
	o->period = c->clk.period;
	o->t0 = c0 > UINT64_MAX / o->period ? UINT64_MAX : c0 * o->period;
	o->t1 = c1 > UINT64_MAX / o->period ? UINT64_MAX : c1 * o->period;
	o->max = max_events;
	nu = 0;
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++) {
			o->ubase[r * UNIT_NKINDS + k] = nu;
			nu += c->rtp[r].u[k].count;
		}
	/* the tracks' names and order: units first, then threads */
	fputs("{\"displayTimeUnit\":\"ns\",\"traceEvents\":[\n{\"ph\":\"M\",\"name\":"
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
	return o;
}

int obs_timeline_end(obs_timeline *o, uint64_t *written, uint64_t *dropped)
{
	chip *c = o->c;
	uint64_t now = eng_now(c->e);
	for (int r = 0; r < c->nrtp; r++)
		for (int t = 0; t < c->tpr; t++)
			state_span(o, &c->rtp[r].t[t], now);
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
	        "],\"events\":%" PRIu64 ",\"max_events\":%" PRIu64 ",\"dropped_events\":%" PRIu64
	        ",\"capped\":%s}}\n",
	        o->n, o->max, o->dropped, o->dropped ? "true" : "false");
	/* the observers off */
	mode_observe(&c->md, NULL);
	for (int r = 0; r < c->nrtp; r++)
		for (int k = 0; k < UNIT_NKINDS; k++)
			c->rtp[r].u[k].on_start = thr_on_start;
	c->env.on_state = o->old_state;
	c->env.state_ctx = o->old_state_ctx;
	if (o->mem_on)
		mem_observe(&c->mem, NULL);
	if (written)
		*written = o->n;
	if (dropped)
		*dropped = o->dropped;
	int bad = ferror(o->f) ? -1 : 0;
	free(o->th);
	free(o->ufree);
	free(o->ubase);
	free(o);
	return bad;
}
