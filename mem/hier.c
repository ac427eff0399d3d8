/*
 * hier.c: the "hierarchy" memport model (see hier.h).
 *
 * Each L1 is a timed cache (mem/tcache.h): its port (ports accesses per
 * core cycle), per-MSHR lists of the reads waiting for that line, and a
 * FIFO of reads refused for lack of an MSHR, resumed in order when a fill
 * frees one. A read (hreq) counts the lines it still waits for; the guard
 * count of 1 held while its lines are looked up keeps it alive until the
 * walk is done. hreq records come from a free list that grows in chunks:
 * the steady state never allocates.
 *
 * Data (docs/memory.md, "Data"): with a store, every L1 way holds its
 * line's bytes (the cache's data). A read's bytes are copied from the line
 * at its lookup on a hit, and when its line fills on a miss; a miss reads
 * the whole line from below into its MSHR's buffer (SDRAM: the store;
 * with the VMA, the on-board line or its DMA), and the fill copies it into
 * the way. With SDRAM below, a line of the image that no write has
 * touched (ms_image_at) skips the buffer: the fill copies the image's
 * bytes into the way, the bytes the miss would have read (they cannot
 * change while it is in flight), in one copy instead of two and long
 * after the miss's prefetch (walk) brought them into the host's cache,
 * where the copy at the miss waited for them (docs/PERFORMANCE.md,
 * "Target 2"); hits and merged misses read no image bytes, so nothing
 * else is prefetched. Bypass reads and writes move their bytes from and
 * to the level below directly.
 */
#include "mem/hier.h"
#include "mem/hier_level.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- free lists ---- */

#define HCHUNK 256

static hreq *req_alloc(hier *h)
{
	if (!h->free_r) {
		hchunk *c = malloc(sizeof(hchunk) + HCHUNK * sizeof(hreq));
		if (!c)
			return NULL;
		c->next = h->chunks;
		h->chunks = c;
		hreq *a = (hreq *)(c + 1);
		for (int i = 0; i < HCHUNK; i++) {
			a[i].next = h->free_r;
			h->free_r = &a[i];
		}
	}
	hreq *r = h->free_r;
	h->free_r = r->next;
	return r;
}

/* ---- below the L1s: the levels, by name ---- */

/* The levels a stack may name below the L1s (mem/hier_level.h). */
static const hlevel *const hier_levels[] = {&hier_sdram_level, &hier_vma_level};

static const hlevel *hlevel_find(const char *name, size_t n)
{
	for (size_t i = 0; i < sizeof hier_levels / sizeof *hier_levels; i++)
		if (strlen(hier_levels[i]->name) == n && !strncmp(hier_levels[i]->name, name, n))
			return hier_levels[i];
	return NULL;
}

const hlevel *hier_below(const hier *h, const hlevel *l)
{
	for (int i = 0; i + 1 < h->nstack; i++)
		if (h->stack[i] == l)
			return h->stack[i + 1];
	return NULL;
}

/* A read below the L1s: the level under them. */
static void lower_read(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes, uint8_t *dst,
                       eng_handler cb, void *ctx, uint64_t arg)
{
	h->stack[0]->read(h, t, type, addr, bytes, dst, cb, ctx, arg);
}

/* The bytes below the L1s now, without any change (hier_peek). */
static void lower_peek(const hier *h, uint64_t addr, uint32_t bytes, uint8_t *dst)
{
	h->stack[0]->peek(h, addr, bytes, dst);
}

/* The bytes of L1 way `slot` (given on its first fill); NULL without data
 * or out of memory. */
static inline uint8_t *l1_data(hier *h, hl1 *l, uint32_t slot)
{
	if (!h->ms)
		return NULL;
	uint8_t *d = cache_data_at(&l->t.c, slot); /* most ways have theirs */
	if (!d && !(d = cache_data(&l->t.c, slot)))
		h->oom = 1;
	return d;
}

/* Copies q's bytes inside L1 line `line` (in way slot) to q's buffer.
 * Always inlined, like finish: gcc had kept both calls from each read's
 * hit, fill and completion. */
static inline __attribute__((always_inline)) void deliver(hier *h, hl1 *l, hreq *q, uint64_t line,
                                                          uint32_t slot)
{
	const uint8_t *d = cache_data_at(&l->t.c, slot);
	if (!d && !(d = l1_data(h, l, slot)))
		return;
	uint32_t lb = l->t.c.p.line_bytes;
	uint64_t lo = line * lb, end = q->addr + q->bytes;
	uint64_t a = q->addr > lo ? q->addr : lo, b = end < lo + lb ? end : lo + lb;
	memcpy(q->dst + (a - q->addr), d + (a - lo), (size_t)(b - a));
}

/* ---- reads ---- */

static inline __attribute__((always_inline)) void finish(hier *h, hreq *q)
{
	uint64_t now = eng_now(h->e);
	uint64_t when = eng_next_edge(h->core, now);
	if (q->ready > when)
		when = q->ready;
	h->wait_ticks[q->type] += when - q->issue;
	if (q->done)
		eng_schedule(h->e, when, q->done, q->ctx, q->arg);
	q->next = h->free_r;
	h->free_r = q;
}

static void l1_filled(eng *e, void *ctx, uint64_t line);

/* One L1 line lookup of L1 `type` by a packet of ray type ray - 1
 * (mem_req.ray), a hit or not. */
static inline void ray_count(hier *h, int ray, int type, int hit)
{
	if (ray > MEM_RAY_TYPES)
		return;
	h->ray_lookups[ray - 1][type]++;
	h->ray_hits[ray - 1][type] += (uint64_t)hit;
}

/* Looks up q's remaining lines at tick t. Returns 0 when every line is
 * either present or awaited, 1 when refused for lack of an MSHR (q keeps
 * its place: next_line is the refused line). */
static int walk(hl1 *l, hreq *q, uint64_t t)
{
	hier *h = l->h;
	uint32_t lb = l->t.c.p.line_bytes;
	for (; q->next_line <= q->last_line; q->next_line++) {
		uint64_t line = q->next_line;
		uint64_t lo = line * lb, hi = lo + lb, end = q->addr + q->bytes;
		uint64_t a = q->addr > lo ? q->addr : lo, b = end < hi ? end : hi;
		int m = -1;
		uint32_t slot = 0;
		cache_result r = tcache_lookup(&l->t, line, (uint32_t)(b - a), q, &m, &slot);
		if (q->ray && r != CACHE_MSHR_FULL)
			ray_count(h, q->ray, l->type, r == CACHE_HIT);
		switch (r) {
		case CACHE_HIT:
			/* the bytes leave the array at the tag check */
			if (q->dst)
				deliver(h, l, q, line, slot);
			break;
		case CACHE_MISS_NEW: {
			if (h->obs)
				h->miss_t0[l->type][m] = t;
			/* an image line fills from the image: nothing to read now */
			const uint8_t *img = l->msrc ? ms_image_at(h->ms, lo, lb) : NULL;
			if (l->msrc)
				l->msrc[m] = img;
			if (img) { /* in the host's cache by the time it fills */
				__builtin_prefetch(img);
				__builtin_prefetch(img + lb - 1);
			}
			/* the level below reads the bytes into the MSHR's buffer,
			 * or (an image line) only makes the request */
			lower_read(h, t, l->type, lo, lb,
			           h->ms && !img ? l->t.mbuf + (size_t)m * lb : NULL, l1_filled, l,
			           line);
		}
			/* fall through */
		case CACHE_MISS_MERGED: /* q waits on the MSHR */
			q->pending++;
			if (h->obs) {
				mem_obs_ev ev = {MEM_OBS_L1_LOOKUP_MISS,
				                 l->type,
				                 r == CACHE_MISS_MERGED,
				                 0,
				                 t,
				                 t,
				                 lo,
				                 lb,
				                 q->ctx};
				h->obs->fn(h->obs->ctx, &ev);
			}
			break;
		case CACHE_MSHR_FULL:
			return 1;
		}
	}
	return 0;
}

/* A read refused for lack of an MSHR, retried after a fill (tc_retry). */
static int l1_retry(void *ctx, void *who, uint64_t waited, uint64_t now)
{
	hl1 *l = ctx;
	hreq *q = who;
	if (walk(l, q, now))
		return 1; /* stays at the head */
	l->h->stall_ticks[q->type] += waited;
	if (--q->pending == 0) /* the guard */
		finish(l->h, q);
	return 0;
}

static void l1_filled(eng *e, void *ctx, uint64_t line)
{
	hl1 *l = ctx;
	hier *h = l->h;
	uint64_t now = eng_now(e);
	/* the set was last looked at when the line missed, long ago: its
	 * tags and data indices come in together, not one after the other */
	cache_prefetch_set(&l->t.c, line);
	int m;
	tc_wait *w = tcache_take(&l->t, line, &m);
	uint32_t slot = cache_fill_mshr(&l->t.c, line, m, NULL);
	uint8_t *d = m >= 0 ? l1_data(h, l, slot) : NULL;
	if (d) { /* the line: the image's bytes, or those in the MSHR's buffer */
		uint32_t lb = l->t.c.p.line_bytes;
		const uint8_t *src = l->msrc ? l->msrc[m] : NULL;
		memcpy(d, src ? src : l->t.mbuf + (size_t)m * lb, lb);
	}
	if (h->obs && m >= 0) {
		uint32_t lb = l->t.c.p.line_bytes;
		mem_obs_ev ev = {MEM_OBS_L1_MISS, l->type, m,   0, h->miss_t0[l->type][m], now,
		                 line * lb,       lb,      NULL};
		h->obs->fn(h->obs->ctx, &ev);
	}
	for (hreq *q; (q = tcache_pop(&l->t, &w));) {
		if (q->dst)
			deliver(h, l, q, line, slot);
		if (--q->pending == 0)
			finish(h, q);
	}
	/* resume refused reads in order while MSHRs are free */
	tcache_resume(&l->t, now, l1_retry, l);
}

static void l1_bypass_done(eng *e, void *ctx, uint64_t arg)
{
	hreq *q = (hreq *)(uintptr_t)arg;
	finish(ctx, q);
}

static void hier_access(void *impl, const mem_req *r, eng_handler done, void *ctx, uint64_t arg)
{
	hier *h = impl;
	uint64_t now = eng_now(h->e);
	int type = r->type;
	if (r->write) {
		/* posted: the bytes go in now (write-around: the L1s never
		 * hold the spill area) */
		h->writes[type]++;
		h->write_bytes[type] += r->bytes;
		h->stack[0]->write(h, now, type, r->addr, r->bytes, h->ms ? r->data : NULL);
		if (done) /* posted: a waiting caller gets its answer at once */
			eng_schedule(h->e, eng_next_edge(h->core, now), done, ctx, arg);
		return;
	}
	h->reads[type]++;
	h->read_bytes[type] += r->bytes;
	hreq *q = req_alloc(h);
	if (!q)
		return; /* out of memory: the unit never hears back (cannot happen in practice) */
	uint32_t bytes = r->bytes ? r->bytes : 1;
	uint8_t *dst = h->ms && r->bytes ? r->data : NULL;
	/* field by field: every one is set below or here, so no zeroing of
	 * the whole record first (next_line, last_line and the free list's
	 * next are set before they are read) */
	q->done = done;
	q->ctx = ctx;
	q->arg = arg;
	q->issue = now;
	q->ready = now;
	q->addr = r->addr;
	q->dst = dst;
	q->bytes = bytes;
	q->pending = 1;
	q->type = (uint8_t)type;
	q->ray = r->ray;
	if (r->addr >= h->image_bytes) {
		h->bypass[type]++;
		lower_read(h, now, type, r->addr, bytes, dst, l1_bypass_done, h, (uintptr_t)q);
		return;
	}
	hl1 *l = &h->l1[type];
	/* the port: ports accesses per core cycle, in arrival order */
	uint64_t start = tcache_port(&l->t, now, h->core);
	q->ready = start + (uint64_t)l->t.c.p.hit_latency * h->core.period;
	q->next_line = cache_line_of(&l->t.c, r->addr);
	q->last_line = cache_line_of(&l->t.c, r->addr + bytes - 1);
	/* reads refused earlier go first: a new read never overtakes them */
	if (l->t.stall || walk(l, q, start)) {
		tcache_stall(&l->t, q, start);
		return;
	}
	if (--q->pending == 0)
		finish(h, q);
}

/* ---- functional accesses (no time) ---- */

/* Below the L1s without time (data: the bytes read into or written from;
 * NULL: none). */
static void func_lower(hier *h, int type, uint64_t addr, uint32_t bytes, int write, uint8_t *data)
{
	h->stack[0]->func(h, type, addr, bytes, write, data);
}

/* hier_access_func's lookup of one L1 line, `line`, holding bytes [a, b)
 * of read r (data: where they go; NULL: nowhere). */
static inline __attribute__((always_inline)) void
func_line(hier *h, hl1 *l, const mem_req *r, uint8_t *data, uint64_t line, uint64_t a, uint64_t b)
{
	cache *c = &l->t.c;
	uint32_t lb = c->p.line_bytes, slot;
	uint64_t lo = line * lb, victim;
	int hit = cache_lookup_func_at(c, line, (uint32_t)(b - a), &slot, &victim);
	if (r->ray) /* a line in flight is a merged miss (cache_lookup_func) */
		ray_count(h, r->ray, l->type, hit && slot != CACHE_NO_SLOT);
	if (!h->ms) {
		if (!hit)
			func_lower(h, l->type, lo, lb, 0, NULL);
		return;
	}
	if (slot == CACHE_NO_SLOT) {
		/* a timed fill is on its way: the bytes it brings */
		if (data)
			lower_peek(h, a, (uint32_t)(b - a), data + (a - r->addr));
		return;
	}
	uint8_t *d = l1_data(h, l, slot);
	if (!hit) /* the line fills from below at once */
		func_lower(h, l->type, lo, lb, 0, d);
	if (d && data)
		memcpy(data + (a - r->addr), d + (a - lo), (size_t)(b - a));
}

/* The functional twin of hier_access: the same L1 lookups, line by line,
 * with the fill applied at once. Timed misses may still be in flight (a
 * sampled region hands its packets to a functional stretch without
 * draining): a line in an MSHR counts as on its way (cache_lookup_func),
 * so nothing waits and hits and misses follow from the line order alone. */
static void hier_access_func(void *impl, const mem_req *r)
{
	hier *h = impl;
	int type = r->type;
	uint8_t *data = h->ms && r->bytes ? r->data : NULL;
	h->freqs++;
	if (r->write) {
		h->writes[type]++;
		h->write_bytes[type] += r->bytes;
		func_lower(h, type, r->addr, r->bytes, 1, data);
		return;
	}
	h->reads[type]++;
	h->read_bytes[type] += r->bytes;
	uint32_t bytes = r->bytes ? r->bytes : 1;
	if (r->addr >= h->image_bytes) {
		h->bypass[type]++;
		func_lower(h, type, r->addr, bytes, 0, data);
		return;
	}
	hl1 *l = &h->l1[type];
	const cache *c = &l->t.c;
	uint32_t lb = c->p.line_bytes;
	uint64_t first = cache_line_of(c, r->addr), end = r->addr + bytes;
	/* most reads fit one line: no second division (36-byte lines), and
	 * the read's bytes are the line's part */
	if (end <= (first + 1) * lb) {
		func_line(h, l, r, data, first, r->addr, end);
		return;
	}
	uint64_t last = cache_line_of(c, end - 1);
	for (uint64_t line = first; line <= last; line++) {
		uint64_t lo = line * lb, hi = lo + lb;
		func_line(h, l, r, data, line, r->addr > lo ? r->addr : lo, end < hi ? end : hi);
	}
}

/* The bytes a read would return now: the L1 line where present, else the
 * level below; nothing changes. */
static void hier_peek(void *impl, const mem_req *r, void *dst)
{
	const hier *h = impl;
	uint8_t *o = dst;
	if (r->addr >= h->image_bytes) {
		lower_peek(h, r->addr, r->bytes, o);
		return;
	}
	const cache *c = &h->l1[r->type].t.c;
	uint32_t lb = c->p.line_bytes;
	uint64_t end = r->addr + r->bytes;
	for (uint64_t a = r->addr; a < end;) {
		uint64_t line = cache_line_of(c, a), lo = line * lb;
		uint32_t n = (uint32_t)((end < lo + lb ? end : lo + lb) - a), slot;
		const uint8_t *d = NULL;
		if (h->ms && cache_probe(c, line, &slot))
			d = cache_data_at(c, slot);
		if (d)
			memcpy(o + (a - r->addr), d + (a - lo), n);
		else
			lower_peek(h, a, n, o + (a - r->addr));
		a += n;
	}
}

static int hier_failed(const void *impl)
{
	const hier *h = impl;
	int oom = h->oom || (h->ms && h->ms->oom);
	for (int t = 0; t < MEM_NTYPES; t++)
		oom |= h->l1[t].t.oom;
	for (int i = 0; i < h->nstack; i++)
		if (h->stack[i]->failed)
			oom |= h->stack[i]->failed(h);
	return oom;
}

static void hier_destroy(void *impl)
{
	hier *h = impl;
	for (int t = 0; t < MEM_NTYPES; t++)
		tcache_free(&h->l1[t].t);
	for (int i = 0; i < h->nstack; i++)
		if (h->stack[i]->free)
			h->stack[i]->free(h);
	for (hchunk *c = h->chunks, *n; c; c = n) {
		n = c->next;
		free(c);
	}
	for (int t = 0; t < MEM_NTYPES; t++) {
		free(h->miss_t0[t]);
		free(h->l1[t].msrc);
	}
	free(h);
}

/* The observer reaches the L1s, the SDRAM and the host bus. A miss in
 * flight when it is set shows from the tick it was set. */
static void hier_observe(void *impl, const mem_obs *o)
{
	hier *h = impl;
	for (int t = 0; o && t < MEM_NTYPES; t++) {
		if (h->miss_t0[t])
			continue;
		h->miss_t0[t] = malloc(h->l1[t].t.c.p.mshrs * sizeof *h->miss_t0[t]);
		if (!h->miss_t0[t]) {
			h->oom = 1;
			return;
		}
		for (uint32_t i = 0; i < h->l1[t].t.c.p.mshrs; i++)
			h->miss_t0[t][i] = eng_now(h->e);
	}
	h->obs = o;
	h->sd.obs = o;
	h->hb.obs = o;
}

static const memport_model hier_model = {"hierarchy", hier_access, hier_destroy, hier_access_func,
                                         hier_peek,   hier_failed, hier_observe};

/* ---- construction ---- */

/* The level names a stack may use, comma separated, into buf. */
static const char *level_names(char *buf, size_t n)
{
	size_t at = (size_t)snprintf(buf, n, "l1");
	for (size_t i = 0; i < sizeof hier_levels / sizeof *hier_levels && at < n; i++)
		at += (size_t)snprintf(buf + at, n - at, ", %s", hier_levels[i]->name);
	return buf;
}

/* The stack, top first ("l1,vma,sdram"): the L1s on top (the report's
 * checks take every read past them for a stack refill, so a stack
 * without them is refused), then the levels below them, each standing on
 * the one its `on` names, the last on nothing. -1 with d set when the
 * names do not stack. */
static int parse_stack(const hlevel **stack, int *nstack, const char *spec, diag *d)
{
	char names[128];
	int l1 = 0, n = 0;
	for (const char *p = spec; *p;) {
		p += strspn(p, ", ");
		size_t k = strcspn(p, ", ");
		if (!k)
			break;
		const hlevel *l = NULL;
		if (k == 2 && !strncmp(p, "l1", 2) && !n && !l1)
			l1 = 1;
		else if (n < HIER_MAXLEVELS && (l = hlevel_find(p, k)))
			stack[n++] = l;
		else
			return diag_set(d, "config", 0, 0,
			                "memory.levels '%s': '%.*s' is no level here (levels: %s; "
			                "l1 only on top)",
			                spec, (int)k, p, level_names(names, sizeof names));
		p += k;
	}
	*nstack = n;
	int ok = l1 && n > 0 && !stack[n - 1]->on;
	for (int i = 0; ok && i + 1 < n; i++)
		ok = stack[i]->on && !strcmp(stack[i]->on, stack[i + 1]->name);
	if (!ok)
		return diag_set(
		    d, "config", 0, 0,
		    "memory.levels '%s' does not stack: top first, l1, then levels each "
		    "standing on the next (vma on sdram), the last on nothing (sdram)",
		    spec);
	return 0;
}

int hier_check_levels(const char *spec, diag *d)
{
	const hlevel *stack[HIER_MAXLEVELS];
	int n;
	return parse_stack(stack, &n, spec, d);
}

/* -1 with d set when the image cannot be addressed: no level of the
 * stack addresses host memory and the image does not fit on board. */
static int image_fits(const hier *h, const hier_params *hp, uint64_t image_bytes, diag *d)
{
	for (int i = 0; i < h->nstack; i++)
		if (h->stack[i]->host_addressed)
			return 0;
	if (image_bytes <= hp->sdram.bytes)
		return 0;
	return diag_set(d, "config", 0, 0,
	                "the memory image (%.1f MB) does not fit in on-board memory "
	                "(memory.sdram.mb = %d); enable the virtual memory architecture "
	                "(configs/saarcor-vma.yaml, memory.vma.enabled: true) or raise "
	                "memory.sdram.mb",
	                (double)image_bytes / (1 << 20), (int)(hp->sdram.bytes >> 20));
}

int hier_init(memport *p, eng *e, eng_clock core, const hier_params *hp, uint64_t image_bytes,
              mem_store *store, diag *d)
{
	memset(p, 0, sizeof *p);
	hier *h = calloc(1, sizeof *h);
	if (!h)
		return diag_set(d, "config", 0, 0, "out of memory");
	if (parse_stack(h->stack, &h->nstack, hp->levels, d) || image_fits(h, hp, image_bytes, d)) {
		free(h);
		return -1;
	}
	h->e = e;
	h->core = core;
	h->image_bytes = image_bytes;
	h->ms = store;
	for (int t = 0; t < MEM_NTYPES; t++) {
		char what[32];
		snprintf(what, sizeof what, "memory.l1.%s", mem_type_name(t));
		const cache_params cp = hp->l1[t];
		h->l1[t].h = h;
		h->l1[t].type = t;
		if (tcache_init(&h->l1[t].t, &cp, store ? TC_DATA | TC_MBUF : 0, what, d))
			goto fail;
	}
	/* bottom up: each level stands on the ones below it */
	for (int i = h->nstack - 1; i >= 0; i--)
		if (h->stack[i]->init && h->stack[i]->init(h, hp, d))
			goto fail;
	/* SDRAM right below the L1s reads the store when a miss is sent:
	 * image lines may fill from the image instead (walk, l1_filled) */
	for (int t = 0; store && h->stack[0] == &hier_sdram_level && t < MEM_NTYPES; t++) {
		hl1 *l = &h->l1[t];
		if (!(l->msrc = calloc(l->t.c.p.mshrs, sizeof *l->msrc))) {
			diag_set(d, "config", 0, 0, "out of memory");
			goto fail;
		}
	}
	p->model = &hier_model;
	p->impl = h;
	return 0;
fail:
	hier_destroy(h);
	return -1;
}

int hier_is(const memport *p)
{
	return p->model == &hier_model;
}

int hier_get_stats(const memport *p, hier_stats *s)
{
	memset(s, 0, sizeof *s);
	if (!hier_is(p))
		return -1;
	const hier *h = p->impl;
	s->now_ticks = eng_now(h->e);
	s->core_period = h->core.period;
	for (int t = 0; t < MEM_NTYPES; t++) {
		s->l1[t] = h->l1[t].t.c.s;
		s->reads[t] = h->reads[t];
		s->read_bytes[t] = h->read_bytes[t];
		s->writes[t] = h->writes[t];
		s->write_bytes[t] = h->write_bytes[t];
		s->bypass_reads[t] = h->bypass[t];
		s->wait_cycles[t] = h->wait_ticks[t] / h->core.period;
		s->mshr_stall_cycles[t] = h->stall_ticks[t] / h->core.period;
		for (int r = 0; r < MEM_RAY_TYPES; r++) {
			s->ray_lookups[r][t] = h->ray_lookups[r][t];
			s->ray_hits[r][t] = h->ray_hits[r][t];
		}
	}
	s->func_requests = h->freqs;
	s->func_sdram_merge_ticks = h->fmerge_ticks;
	s->func_hostbus_busy_ticks = h->fhb.busy_ticks;
	s->skipped_sdram_busy_ticks = h->kept_sd_busy;
	s->skipped_hostbus_busy_ticks = h->kept_hb_busy;
	for (int i = 0; i < h->nstack; i++)
		if (h->stack[i]->stats)
			h->stack[i]->stats(h, s);
	return 0;
}

/* ---- stored warming (sim/warming.h) ---- */

void hier_caches(memport *p, cache *l1[MEM_NTYPES], cache **tag, cache **l2)
{
	hier *h = p->impl;
	for (int t = 0; t < MEM_NTYPES; t++)
		l1[t] = &h->l1[t].t.c;
	*tag = h->use_vma && h->v.p.tag_cache_enabled ? &h->v.tag.c : NULL;
	*l2 = h->use_vma ? &h->v.l2.c : NULL;
}

#define HIER_MAXCACHES (MEM_NTYPES + 8)

/* The caches a checkpoint holds whole, in order (the L1s, then each
 * level's, top down); returns how many. */
static int whole_caches(const hier *h, cache **k)
{
	int n = 0;
	for (int t = 0; t < MEM_NTYPES; t++)
		k[n++] = (cache *)&h->l1[t].t.c;
	for (int i = 0; i < h->nstack; i++)
		if (h->stack[i]->caches)
			n += h->stack[i]->caches(h, k + n);
	return n;
}

size_t hier_ckpt_bytes(const memport *p)
{
	if (!hier_is(p))
		return 0;
	cache *k[HIER_MAXCACHES];
	size_t b = 0;
	for (int i = 0, n = whole_caches(p->impl, k); i < n; i++)
		b += cache_ckpt_bytes(k[i], k[i]->nsets);
	return b;
}

int hier_ckpt_save(const memport *p, void *buf)
{
	if (!hier_is(p))
		return -1;
	cache *k[HIER_MAXCACHES];
	uint8_t *b = buf;
	for (int i = 0, n = whole_caches(p->impl, k); i < n; i++) {
		if (cache_ckpt_save(k[i], 0, k[i]->nsets, b))
			return -1;
		b += cache_ckpt_bytes(k[i], k[i]->nsets);
	}
	return 0;
}

int hier_ckpt_load(memport *p, const void *buf)
{
	if (!hier_is(p))
		return -1;
	cache *k[HIER_MAXCACHES];
	int n = whole_caches(p->impl, k);
	for (int i = 0; i < n; i++)
		if (cache_busy(k[i]))
			return -1;
	const uint8_t *b = buf;
	for (int i = 0; i < n; i++) {
		cache_ckpt_load(k[i], 0, k[i]->nsets, b);
		b += cache_ckpt_bytes(k[i], k[i]->nsets);
	}
	return 0;
}

cache *hier_onboard(memport *p)
{
	hier *h = hier_is(p) ? p->impl : NULL;
	for (int i = 0; h && i < h->nstack; i++)
		if (h->stack[i]->bysets)
			return h->stack[i]->bysets(h);
	return NULL;
}

void hier_reload(memport *p, const uint64_t *l2sets)
{
	hier *h = p->impl;
	if (!h->ms)
		return;
	/* bottom up: each level's lines from the one below */
	for (int i = h->nstack - 1; i >= 0; i--)
		if (h->stack[i]->reload && l2sets)
			h->stack[i]->reload(h, l2sets);
	for (int t = 0; t < MEM_NTYPES; t++) {
		hl1 *l = &h->l1[t];
		uint32_t lb = l->t.c.p.line_bytes;
		size_t n = (size_t)l->t.c.nsets * l->t.c.p.ways;
		for (size_t i = 0; i < n; i++) {
			uint64_t line = l->t.c.way[i].tag;
			uint8_t *d = line == CACHE_INVALID ? NULL : l1_data(h, l, (uint32_t)i);
			if (d)
				lower_peek(h, line * lb, lb, d);
		}
	}
}

_Static_assert(sizeof(cache_stats) % 8 == 0 && sizeof(sdram_stats) % 8 == 0 &&
                   sizeof(memif_stats) % 8 == 0 && sizeof(hbus_stats) % 8 == 0 &&
                   sizeof(vma_stats) % 8 == 0,
               "stats structs hold uint64_t counters only");

size_t hier_add_ptrs(uint64_t **out, size_t n, size_t cap, uint64_t *a, size_t k)
{
	for (size_t i = 0; i < k; i++, n++)
		if (out && n < cap)
			out[n] = a + i;
	return n;
}

size_t hier_counter_ptrs(memport *p, uint64_t **out, size_t cap)
{
	hier *h = p->impl;
	size_t n = 0;
	uint64_t *arr[] = {h->reads,  h->read_bytes, h->writes,     h->write_bytes,
	                   h->bypass, h->wait_ticks, h->stall_ticks};
	for (size_t i = 0; i < sizeof arr / sizeof *arr; i++)
		n = hier_add_ptrs(out, n, cap, arr[i], MEM_NTYPES);
	for (int t = 0; t < MEM_NTYPES; t++)
		n = hier_add_ptrs(out, n, cap, HIER_COUNTERS(h->l1[t].t.c.s));
	for (int r = 0; r < MEM_RAY_TYPES; r++) {
		n = hier_add_ptrs(out, n, cap, h->ray_lookups[r], MEM_NTYPES);
		n = hier_add_ptrs(out, n, cap, h->ray_hits[r], MEM_NTYPES);
	}
	n = hier_add_ptrs(out, n, cap, HIER_COUNTERS(h->fsd));
	n = hier_add_ptrs(out, n, cap, HIER_COUNTERS(h->fmi));
	n = hier_add_ptrs(out, n, cap, HIER_COUNTERS(h->fhb));
	n = hier_add_ptrs(out, n, cap, &h->freqs, 1);
	n = hier_add_ptrs(out, n, cap, &h->fl2hit_ticks, 1);
	for (int i = 0; i < h->nstack; i++)
		if (h->stack[i]->counters)
			n = h->stack[i]->counters(h, out, n, cap);
	return n;
}

size_t hier_traffic_ptrs(memport *p, uint64_t **out, size_t cap)
{
	hier *h = p->impl;
	size_t n = 0;
	n = hier_add_ptrs(out, n, cap, h->mi.s.reads, MEMIF_NREQ);
	n = hier_add_ptrs(out, n, cap, h->mi.s.writes, MEMIF_NREQ);
	n = hier_add_ptrs(out, n, cap, h->mi.s.bytes, MEMIF_NREQ);
	uint64_t *sd[] = {&h->sd.s.reads,       &h->sd.s.writes, &h->sd.s.read_bytes,
	                  &h->sd.s.write_bytes, &h->sd.s.beats,  &h->sd.s.busy_ticks,
	                  &h->hb.s.transfers,   &h->hb.s.bytes,  &h->hb.s.busy_ticks};
	for (size_t i = 0; i < sizeof sd / sizeof *sd; i++)
		n = hier_add_ptrs(out, n, cap, sd[i], 1);
	return n;
}

uint64_t hier_l2hit_ticks(const memport *p)
{
	return ((const hier *)p->impl)->fl2hit_ticks;
}

void hier_add_merge_ticks(memport *p, double ticks)
{
	((hier *)p->impl)->fmerge_ticks += ticks;
}

/* The caches whose timed hits and merges a skip keeps (hier_keep_shares),
 * into k; returns how many (at most MEM_NTYPES + 2). */
static int skip_caches(hier *h, cache **k)
{
	int n = 0;
	for (int t = 0; t < MEM_NTYPES; t++)
		k[n++] = &h->l1[t].t.c;
	if (h->use_vma) {
		if (h->v.p.tag_cache_enabled)
			k[n++] = &h->v.tag.c;
		k[n++] = &h->v.l2.c;
	}
	return n;
}

void hier_mark_shares(memport *p)
{
	hier *h = p->impl;
	cache *k[MEM_NTYPES + 2];
	for (int i = 0, n = skip_caches(h, k); i < n; i++)
		h->skip_mark[i] = k[i]->s;
	h->mark_sd_busy = h->sd.s.busy_ticks;
	h->mark_hb_busy = h->hb.s.busy_ticks;
}

void hier_keep_shares(memport *p)
{
	hier *h = p->impl;
	cache *k[MEM_NTYPES + 2];
	for (int i = 0, n = skip_caches(h, k); i < n; i++) {
		cache_stats *b = &k[i]->s;
		const cache_stats *a = &h->skip_mark[i];
		b->skip_hits += (b->hits - b->func_hits) - (a->hits - a->func_hits);
		b->skip_merges += (b->merges - b->func_merges) - (a->merges - a->func_merges);
	}
	h->kept_sd_busy += h->sd.s.busy_ticks - h->mark_sd_busy;
	h->kept_hb_busy += h->hb.s.busy_ticks - h->mark_hb_busy;
}

size_t hier_kept_ptrs(memport *p, uint64_t **out, size_t cap)
{
	hier *h = p->impl;
	size_t n = hier_add_ptrs(out, 0, cap, h->wait_ticks, MEM_NTYPES);
	n = hier_add_ptrs(out, n, cap, h->stall_ticks, MEM_NTYPES);
	cache *k[MEM_NTYPES + 2];
	for (int i = 0, m = skip_caches(h, k); i < m; i++) {
		n = hier_add_ptrs(out, n, cap, &k[i]->s.skip_hits, 1);
		n = hier_add_ptrs(out, n, cap, &k[i]->s.skip_merges, 1);
	}
	return n;
}

double hier_merge_share(const memport *p)
{
	return hier_is(p) ? hier_vma_merge_share(p->impl) : 0;
}
