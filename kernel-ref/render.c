/*
 * render.c: the reference packet tracer's frame loop (see render.h).
 */
#include "kernel-ref/render.h"
#include "kernel-ref/cone.h"
#include "kernel-ref/frustum.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined(__x86_64__) || defined(__i386__)
#include <x86intrin.h>
#endif

const char *pkt_type_name(int type)
{
	static const char *const names[PKT_NTYPES] = {"primary", "shadow", "reflection",
	                                              "refraction"};
	return type >= 0 && type < PKT_NTYPES ? names[type] : "?";
}

void render_opts_default(render_opts *o)
{
	memset(o, 0, sizeof *o);
	o->width = 512;
	o->height = 512;
	o->threads = 1;
	o->max_depth = 3;
	o->shadows = 1;
	o->background = v3(0.05f, 0.05f, 0.08f);
}

typedef struct job {
	const mimg *m;
	const render_opts *o;
	shade_ctx sc;
	drt_shade drt;
	cam_frame cam;
	int tiles_x, ntiles;
	atomic_int next;
} job;

typedef struct worker {
	job *j;
	render_stats st;
	packet *work; /* depth-first work stack of packets */
	int cap;
	packet *kids; /* shade_packet's output, copied onto the work stack */
	int nkids;
	trav_entry *stack;
	uint64_t trace_ticks; /* now_ticks inside traversal, summed */
	pthread_t tid;
} worker;

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* A cheap clock for the two readings around every packet's traversal
 * (render_stats.trace_ms): the time-stamp counter on x86, whose ticks a
 * worker converts to ms by the wall time of its whole run (a clock_gettime
 * per reading was 1.5% of a primary frame); elsewhere nanoseconds. */
static inline uint64_t now_ticks(void)
{
#if defined(__x86_64__) || defined(__i386__)
	return __rdtsc();
#else
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
#endif
}

/* Traces one packet with the single-ray path (for checking), through the
 * image's tree or another tracer (tr). */
static void trace_single(const mimg *m, packet *p, trav_counts *c, const pkt_precision *prec,
                         const render_tracer *tr)
{
	for (uint64_t b = p->valid; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		vec3 o = v3(p->ox[i], p->oy[i], p->oz[i]), d = v3(p->dx[i], p->dy[i], p->dz[i]);
		int any = p->type == PKT_SHADOW;
		ray_hit h = tr ? tr->ray(tr->ctx, o, d, p->tmax[i], any, c)
		               : ray_trace_fp(m, o, d, p->tmax[i], any, c, prec);
		p->t[i] = h.t;
		p->tri[i] = h.tri;
		p->inst[i] = h.inst;
		p->bu[i] = h.bu;
		p->bv[i] = h.bv;
	}
}

/* a += b - sub (sub NULL: a += b), every counter of trav_counts but the
 * stack depth (a maximum, merged by the caller): one list of the fields
 * for the per-type split and the workers' merge (a field left out of one
 * of three hand-written lists lost the workers' cone savings per type). */
_Static_assert(sizeof(trav_counts) == 7 * sizeof(uint64_t), "trav_add: add the new field");
static void trav_add(trav_counts *a, const trav_counts *b, const trav_counts *sub)
{
	const trav_counts z = {0};
	if (!sub)
		sub = &z;
	a->node_steps += b->node_steps - sub->node_steps;
	a->leaf_visits += b->leaf_visits - sub->leaf_visits;
	a->tri_tests += b->tri_tests - sub->tri_tests;
	a->ray_tri_tests += b->ray_tri_tests - sub->ray_tri_tests;
	a->cone_culled += b->cone_culled - sub->cone_culled;
	a->cone_saved_ray_tests += b->cone_saved_ray_tests - sub->cone_saved_ray_tests;
}

/* The frame-buffer words of p's pixels fetched ahead into the second
 * level cache while p is traced, for its shading's adds (a row of eight
 * lanes is a tile row: three or four lines; the 24 MB buffer at 1024x1024
 * is far from the first levels when a tile's adds come). Always inlined:
 * gcc 12 took a function of prefetches alone for one without effects and
 * dropped its call. */
static inline __attribute__((always_inline)) void fb_fetch_ahead(const framebuf *fb,
                                                                 const packet *p)
{
	for (int r = 0; r < PKT_RAYS; r += TILE_W) {
		if (!((p->valid >> r) & ((1ull << TILE_W) - 1)))
			continue;
		const char *a = (const char *)(fb->acc + 3 * (uint64_t)p->pixel[r]);
		for (int k = 0; k < 3 * TILE_W * 8; k += 64)
			__builtin_prefetch(a + k, 1, 1);
		__builtin_prefetch(a + 3 * TILE_W * 8 - 1, 1, 1);
	}
}

/* Traces sample s of a tile: its primary packet and, depth first, every
 * packet it spawns. */
static void do_sample(worker *w, int tile, int s)
{
	job *j = w->j;
	int n = 0;
	cam_sample_packet(&j->cam, tile % j->tiles_x, tile / j->tiles_x, s, &w->work[n++]);
	while (n > 0) {
		packet *p = &w->work[--n];
		int nrays = __builtin_popcountll(p->valid);
		w->st.rays[p->type] += (uint64_t)nrays;
		w->st.packets[p->type]++;
		if (j->sc.fb)
			fb_fetch_ahead(j->sc.fb, p);
		uint64_t t0 = now_ticks();
		const render_tracer *tr = j->o->tracer;
		trav_counts before = w->st.trav;
		if (j->o->single_ray) {
			trace_single(j->m, p, &w->st.trav, j->o->prec, tr);
		} else {
			/* two-level trees trace through their own tracer (no cone
			 * culling there); the image's kd-tree may cull by cone */
			uint64_t entered =
			    tr ? tr->packet(tr->ctx, p, w->stack, PKT_STACK_MAX, &w->st.trav)
			    : j->o->frustum
			        ? fru_trace(p, j->m, w->stack, PKT_STACK_MAX, &w->st.trav,
			                    j->o->prec, j->o->cone_cull)
			        : pkt_trace_cone(p, j->m, w->stack, PKT_STACK_MAX, &w->st.trav,
			                         j->o->prec, j->o->cone_cull);
			/* rays that miss the scene box skip traversal */
			w->st.box_miss_rays += (uint64_t)__builtin_popcountll(p->valid & ~entered);
			w->st.box_miss_packets += entered == 0;
		}
		w->trace_ticks += now_ticks() - t0;
		trav_add(&w->st.trav_type[p->type], &w->st.trav, &before);
		if (p->type == PKT_SHADOW) {
			shade_shadow_done(&j->sc, p, &w->st.shade);
			continue;
		}
		/* children go on top of the work stack, in p's slot and above */
		int made = shade_packet_fp(&j->sc, j->o->prec ? &j->o->prec->shade : NULL, p,
		                           w->kids, w->nkids, NULL, &w->st.shade);
		for (int k = 0; k < made && n < w->cap; k++)
			w->work[n++] = w->kids[k];
	}
}

/* A tile: its spp samples, one primary packet each (drt.h). */
static void do_tile(worker *w, int tile)
{
	for (int s = 0; s < w->j->cam.spp; s++)
		do_sample(w, tile, s);
}

static void *worker_main(void *arg)
{
	worker *w = arg;
	double ms0 = now_ms();
	uint64_t k0 = now_ticks();
	for (;;) {
		int t = atomic_fetch_add(&w->j->next, 1);
		if (t >= w->j->ntiles)
			break;
		do_tile(w, t);
	}
	double ms = now_ms() - ms0;
	uint64_t k = now_ticks() - k0;
	w->st.trace_ms = k > 0 ? (double)w->trace_ticks * (ms / (double)k) : 0.0;
	return NULL;
}

/* aligned_alloc wants the size to be a multiple of the alignment. */
static void *alloc64(size_t n)
{
	return aligned_alloc(64, (n + 63) & ~(size_t)63);
}

static void add_stats(render_stats *a, const render_stats *b)
{
	for (int t = 0; t < PKT_NTYPES; t++) {
		a->rays[t] += b->rays[t];
		a->packets[t] += b->packets[t];
		trav_add(&a->trav_type[t], &b->trav_type[t], NULL);
	}
	a->box_miss_packets += b->box_miss_packets;
	a->box_miss_rays += b->box_miss_rays;
	a->trace_ms += b->trace_ms;
	trav_add(&a->trav, &b->trav, NULL);
	if (b->trav.max_sp > a->trav.max_sp)
		a->trav.max_sp = b->trav.max_sp;
	/* shade_counts is all uint64_t counters: add them field by field */
	const uint64_t *bs = (const uint64_t *)&b->shade;
	uint64_t *as = (uint64_t *)&a->shade;
	for (size_t k = 0; k < sizeof a->shade / sizeof(uint64_t); k++)
		as[k] += bs[k];
}

int render_frame(const mimg *m, const view *v, const render_opts *o, framebuf *fb, render_stats *st,
                 diag *d)
{
	double t0 = now_ms();
	job j;
	memset(&j, 0, sizeof j);
	j.m = m;
	j.o = o;
	j.sc.m = m;
	j.sc.lights = v->lights;
	j.sc.nlights = o->shadows ? v->nlights : 0;
	j.sc.max_depth = o->max_depth;
	j.sc.background = o->background;
	j.sc.fb = fb;
	j.sc.tl = o->tracer ? o->tracer->shade : NULL;
	cam_setup_view(&j.cam, v, o->width, o->height);
	if (!drt_is_off(&v->drt)) {
		drt_shade_setup(&j.drt, &v->drt, v->cam.up, (uint32_t)o->width);
		j.sc.drt = &j.drt;
	}
	j.tiles_x = (o->width + TILE_W - 1) / TILE_W;
	j.ntiles = j.tiles_x * ((o->height + TILE_H - 1) / TILE_H);
	atomic_init(&j.next, 0);
	int nt = o->threads;
	worker *ws = calloc((size_t)nt, sizeof *ws);
	/* depth-first: at most (nlights + 2) children per level, plus the root */
	int cap = (o->max_depth + 2) * (v->nlights + 2) + 1;
	int rc = 0;
	for (int i = 0; i < nt && ws; i++) {
		ws[i].j = &j;
		ws[i].cap = cap;
		ws[i].work = alloc64((size_t)cap * sizeof(packet));
		ws[i].nkids = v->nlights + 2;
		ws[i].kids = alloc64((size_t)ws[i].nkids * sizeof(packet));
		ws[i].stack = alloc64(PKT_STACK_MAX * sizeof(trav_entry));
		if (!ws[i].work || !ws[i].stack || !ws[i].kids)
			rc = -1;
	}
	if (!ws || rc) {
		rc = diag_set(d, "render", 0, 0, "out of memory for %d threads", nt);
	} else if (nt == 1) {
		worker_main(&ws[0]);
	} else {
		int started = 0;
		for (int i = 0; i < nt; i++) {
			if (pthread_create(&ws[i].tid, NULL, worker_main, &ws[i]) != 0)
				break;
			started++;
		}
		if (started == 0)
			worker_main(&ws[0]);
		for (int i = 0; i < started; i++)
			pthread_join(ws[i].tid, NULL);
	}
	memset(st, 0, sizeof *st);
	for (int i = 0; ws && i < nt; i++) {
		add_stats(st, &ws[i].st);
		free(ws[i].work);
		free(ws[i].kids);
		free(ws[i].stack);
	}
	free(ws);
	st->render_ms = now_ms() - t0;
	return rc;
}
