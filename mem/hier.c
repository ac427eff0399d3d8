/*
 * hier.c: the "hierarchy" memport model (see hier.h).
 *
 * Each L1 is a cache (mem/cache.h) plus its timing wrapper here: a port
 * counter (ports accesses per core cycle), per-MSHR lists of the reads
 * waiting for that line, and a FIFO of reads refused for lack of an MSHR,
 * resumed in order when a fill frees one. A read (hreq) counts the lines it
 * still waits for; the guard count of 1 held while its lines are looked up
 * keeps it alive until the walk is done. hreq and wait records come from
 * free lists that grow in chunks: the steady state never allocates.
 *
 * Data (docs/memory.md, "Data"): with a store, every L1 way holds its
 * line's bytes (the cache's data). A read's bytes are copied from the line
 * at its lookup on a hit, and when its line fills on a miss; a miss reads
 * the whole line from below into its MSHR's buffer (SDRAM: the store;
 * with the VMA, the on-board line or its DMA), and the fill copies it into
 * the way. Bypass reads and writes move their bytes from and to the level
 * below directly.
 */
#include "mem/hier.h"

#include <stdlib.h>
#include <string.h>

typedef struct hreq hreq;
struct hreq {
	eng_handler done;
	void *ctx;
	uint64_t arg;
	uint64_t issue, ready, since;
	uint64_t next_line, last_line, addr;
	uint8_t *dst; /* where the bytes go; NULL: no data */
	uint32_t bytes, pending;
	uint8_t type;
	hreq *next;
};

typedef struct hwait hwait;
struct hwait {
	hreq *r;
	hwait *next;
};

typedef struct hier hier;

typedef struct hl1 {
	hier *h;
	int type;
	cache c;
	uint64_t port_cycle;
	uint32_t port_used;
	hwait **wait;  /* per MSHR */
	uint8_t *mbuf; /* per MSHR: the line being fetched (with data) */
	hreq *stall, *stall_tail;
} hl1;

typedef struct hchunk {
	struct hchunk *next;
} hchunk;

struct hier {
	eng *e;
	eng_clock core;
	uint64_t image_bytes;
	mem_store *ms; /* the board's bytes (host memory's with the VMA); NULL: no data */
	int oom;       /* a line found no memory for its bytes */
	hl1 l1[MEM_NTYPES];
	sdram sd;
	memif mi;
	int use_vma;
	vma v;
	hbus hb;
	hchunk *chunks;
	hreq *free_r;
	hwait *free_w;
	uint64_t reads[MEM_NTYPES], read_bytes[MEM_NTYPES];
	uint64_t writes[MEM_NTYPES], write_bytes[MEM_NTYPES];
	uint64_t bypass[MEM_NTYPES], wait_ticks[MEM_NTYPES], stall_ticks[MEM_NTYPES];
	/* traffic of functional accesses (hier_access_func): what the timed
	 * SDRAM, memory interface and host bus would have counted; busy_ticks
	 * are data-bus occupancy without row or queueing overheads */
	sdram_stats fsd;
	memif_stats fmi;
	hbus_stats fhb;
	uint64_t freqs;
	/* of fsd.busy_ticks: the expected part a timed chip would not spend,
	 * on-board-cache hits it would merge into a PCI fetch in flight (each
	 * such read's ticks times the share of merges among the timed
	 * accesses that found their line present or arriving, so far) */
	double fmerge_ticks;
	/* of fsd.busy_ticks: all reads that were on-board-cache hits (what
	 * fmerge_ticks takes its share of; stored warming applies the share
	 * to the checkpoints' traffic after the fact, sim/warming.h) */
	uint64_t fl2hit_ticks;
};

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

static hwait *wait_alloc(hier *h)
{
	if (!h->free_w) {
		hchunk *c = malloc(sizeof(hchunk) + HCHUNK * sizeof(hwait));
		if (!c)
			return NULL;
		c->next = h->chunks;
		h->chunks = c;
		hwait *a = (hwait *)(c + 1);
		for (int i = 0; i < HCHUNK; i++) {
			a[i].next = h->free_w;
			h->free_w = &a[i];
		}
	}
	hwait *w = h->free_w;
	h->free_w = w->next;
	return w;
}

/* ---- below the L1s ---- */

/* A read below the L1s into dst (NULL: no data). Without the VMA the
 * bytes are the store's at the address, taken when the read is issued:
 * only the reading thread writes what it reads (its spill area) and its
 * writes go in when issued, so they are the bytes SDRAM returns. */
static void lower_read(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes, uint8_t *dst,
                       eng_handler cb, void *ctx, uint64_t arg)
{
	if (h->use_vma) {
		vma_read(&h->v, t, type, addr, bytes, dst, cb, ctx, arg);
		return;
	}
	if (dst)
		ms_read(h->ms, addr, bytes, dst);
	memif_submit(&h->mi, t, type, addr, bytes, 0, cb, ctx, arg);
}

/* The bytes below the L1s now, without any change (hier_peek). */
static void lower_peek(const hier *h, uint64_t addr, uint32_t bytes, uint8_t *dst)
{
	if (h->use_vma)
		vma_peek(&h->v, addr, bytes, dst);
	else if (h->ms)
		ms_read(h->ms, addr, bytes, dst);
	else
		memset(dst, 0, bytes);
}

/* The bytes of L1 way `slot` (given on its first fill); NULL without data
 * or out of memory. */
static uint8_t *l1_data(hier *h, hl1 *l, uint32_t slot)
{
	if (!h->ms)
		return NULL;
	uint8_t *d = cache_data(&l->c, slot);
	if (!d)
		h->oom = 1;
	return d;
}

/* Copies q's bytes inside L1 line `line` (in way slot) to q's buffer. */
static void deliver(hier *h, hl1 *l, hreq *q, uint64_t line, uint32_t slot)
{
	const uint8_t *d = cache_data_at(&l->c, slot);
	if (!d && !(d = l1_data(h, l, slot)))
		return;
	uint32_t lb = l->c.p.line_bytes;
	uint64_t lo = line * lb, end = q->addr + q->bytes;
	uint64_t a = q->addr > lo ? q->addr : lo, b = end < lo + lb ? end : lo + lb;
	memcpy(q->dst + (a - q->addr), d + (a - lo), (size_t)(b - a));
}

/* ---- reads ---- */

static void finish(hier *h, hreq *q)
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

/* Looks up q's remaining lines at tick t. Returns 0 when every line is
 * either present or awaited, 1 when refused for lack of an MSHR (q keeps
 * its place: next_line is the refused line). */
static int walk(hl1 *l, hreq *q, uint64_t t)
{
	hier *h = l->h;
	uint32_t lb = l->c.p.line_bytes;
	for (; q->next_line <= q->last_line; q->next_line++) {
		uint64_t line = q->next_line;
		uint64_t lo = line * lb, hi = lo + lb, end = q->addr + q->bytes;
		uint64_t a = q->addr > lo ? q->addr : lo, b = end < hi ? end : hi;
		int m = -1;
		uint32_t slot = 0;
		switch (cache_lookup(&l->c, line, (uint32_t)(b - a), &m, &slot)) {
		case CACHE_HIT:
			/* the bytes leave the array at the tag check */
			if (q->dst)
				deliver(h, l, q, line, slot);
			break;
		case CACHE_MISS_NEW:
			lower_read(h, t, l->type, lo, lb, h->ms ? l->mbuf + (size_t)m * lb : NULL,
			           l1_filled, l, line);
			/* fall through */
		case CACHE_MISS_MERGED: {
			hwait *w = wait_alloc(h);
			w->r = q;
			w->next = l->wait[m];
			l->wait[m] = w;
			q->pending++;
			break;
		}
		case CACHE_MSHR_FULL:
			return 1;
		}
	}
	return 0;
}

static void l1_filled(eng *e, void *ctx, uint64_t line)
{
	hl1 *l = ctx;
	hier *h = l->h;
	uint64_t now = eng_now(e);
	int m = cache_mshr_find(&l->c, line);
	hwait *w = m >= 0 ? l->wait[m] : NULL;
	if (m >= 0)
		l->wait[m] = NULL;
	uint32_t slot = cache_fill(&l->c, line, NULL);
	uint8_t *d = m >= 0 ? l1_data(h, l, slot) : NULL;
	if (d) /* the line arrived in the MSHR's buffer */
		memcpy(d, l->mbuf + (size_t)m * l->c.p.line_bytes, l->c.p.line_bytes);
	while (w) {
		hwait *n = w->next;
		hreq *q = w->r;
		if (q->dst)
			deliver(h, l, q, line, slot);
		w->next = h->free_w;
		h->free_w = w;
		if (--q->pending == 0)
			finish(h, q);
		w = n;
	}
	/* resume refused reads in order while MSHRs are free */
	while (l->stall && cache_mshr_free(&l->c)) {
		hreq *q = l->stall;
		if (walk(l, q, now))
			break; /* stays at the head */
		l->stall = q->next;
		if (!l->stall)
			l->stall_tail = NULL;
		h->stall_ticks[q->type] += now - q->since;
		if (--q->pending == 0) /* the guard */
			finish(h, q);
	}
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
		const void *src = h->ms ? r->data : NULL;
		if (h->use_vma)
			vma_write(&h->v, now, type, r->addr, r->bytes, src);
		else {
			if (src && ms_write(h->ms, r->addr, r->bytes, src))
				h->oom = 1;
			memif_submit(&h->mi, now, type, r->addr, r->bytes, 1, NULL, NULL, 0);
		}
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
	*q = (hreq){.done = done,
	            .ctx = ctx,
	            .arg = arg,
	            .issue = now,
	            .ready = now,
	            .since = now,
	            .addr = r->addr,
	            .dst = dst,
	            .bytes = bytes,
	            .pending = 1,
	            .type = (uint8_t)type};
	if (r->addr >= h->image_bytes) {
		h->bypass[type]++;
		lower_read(h, now, type, r->addr, bytes, dst, l1_bypass_done, h, (uintptr_t)q);
		return;
	}
	hl1 *l = &h->l1[type];
	/* the port: ports accesses per core cycle, in arrival order */
	uint64_t cyc = (now + h->core.period - 1) / h->core.period;
	if (cyc > l->port_cycle) {
		l->port_cycle = cyc;
		l->port_used = 0;
	}
	if (l->port_used == l->c.p.ports) {
		l->port_cycle++;
		l->port_used = 0;
	}
	l->port_used++;
	uint64_t start = l->port_cycle * h->core.period;
	q->ready = start + (uint64_t)l->c.p.hit_latency * h->core.period;
	q->next_line = r->addr / l->c.p.line_bytes;
	q->last_line = (r->addr + bytes - 1) / l->c.p.line_bytes;
	/* reads refused earlier go first: a new read never overtakes them */
	if (l->stall || walk(l, q, start)) {
		q->since = start;
		q->next = NULL;
		if (l->stall_tail)
			l->stall_tail->next = q;
		else
			l->stall = q;
		l->stall_tail = q;
		return;
	}
	if (--q->pending == 0)
		finish(h, q);
}

/* ---- functional accesses (no time) ---- */

/* One SDRAM access of bytes as the memory interface would submit it. */
static void func_sdram(hier *h, int requester, uint32_t bytes, int write)
{
	if (write) {
		h->fsd.writes++;
		h->fsd.write_bytes += bytes;
		h->fmi.writes[requester]++;
	} else {
		h->fsd.reads++;
		h->fsd.read_bytes += bytes;
		h->fmi.reads[requester]++;
	}
	h->fmi.bytes[requester] += bytes;
	uint64_t beats = sdram_beats(&h->sd, bytes);
	h->fsd.beats += beats;
	h->fsd.busy_ticks += eng_cycles_to_ticks(h->sd.t.clk, beats);
}

/* n SDRAM accesses moving `bytes` together (the VMA counts sums only). */
static void func_sdram_n(hier *h, int requester, uint64_t n, uint64_t bytes, int write)
{
	for (uint64_t i = 0; i < n; i++) {
		uint64_t b = bytes / n + (i < bytes % n);
		func_sdram(h, requester, (uint32_t)b, write);
	}
}

/* The share of on-board-cache hits a timed chip merges into fetches on
 * their way, from the on-board cache's counts so far; 0 without the VMA. */
static double merge_share(const hier *h)
{
	return h->use_vma ? cache_timed_merge_share(NULL, &h->v.l2.s) : 0;
}

/* Below the L1s without time: SDRAM directly, or the VMA's functional walk
 * whose counter deltas become SDRAM and host-bus traffic. data: the bytes
 * read into or written from (NULL: none). */
static void func_lower(hier *h, int type, uint64_t addr, uint32_t bytes, int write, uint8_t *data)
{
	if (!h->use_vma) {
		func_sdram(h, type, bytes, write);
		if (data && write) {
			if (ms_write(h->ms, addr, bytes, data))
				h->oom = 1;
		} else if (data)
			ms_read(h->ms, addr, bytes, data);
		return;
	}
	vma_stats a = h->v.s;
	vma_access_func(&h->v, addr, bytes, write, data);
	const vma_stats *b = &h->v.s;
	uint32_t mb = h->v.meta_set_bytes;
	for (uint64_t i = a.meta_reads; i < b->meta_reads; i++)
		func_sdram(h, MEMIF_META, mb, 0);
	for (uint64_t i = a.meta_writes; i < b->meta_writes; i++)
		func_sdram(h, MEMIF_META, mb, 1);
	uint64_t fetches = b->host_fetches - a.host_fetches;
	uint64_t hw = b->host_writes - a.host_writes;
	/* a fetched line is written into SDRAM (FILL); the rest is data */
	uint64_t fill_bytes = fetches * h->v.p.line;
	uint64_t dr = b->data_reads - a.data_reads, dw = b->data_writes - a.data_writes - fetches;
	uint64_t db = b->data_bytes - a.data_bytes - fill_bytes;
	func_sdram_n(h, MEMIF_FILL, fetches, fill_bytes, 1);
	if (dr + dw) {
		uint64_t t0 = h->fsd.busy_ticks;
		func_sdram_n(h, type, dr + dw, db, dw > 0);
		if (!write && dr) {
			/* the reads are on-board-cache hits; a timed chip merges a
			 * share of them into fetches still on their way */
			h->fl2hit_ticks += h->fsd.busy_ticks - t0;
			h->fmerge_ticks += (double)(h->fsd.busy_ticks - t0) * merge_share(h);
		}
	}
	for (uint64_t i = 0; i < fetches; i++) {
		h->fhb.transfers++;
		h->fhb.bytes += h->v.p.line;
		h->fhb.busy_ticks += hbus_duration(&h->hb, h->v.p.line);
	}
	if (hw) {
		uint64_t wb = b->host_write_bytes - a.host_write_bytes;
		h->fhb.transfers += hw;
		h->fhb.bytes += wb;
		h->fhb.busy_ticks += hbus_duration(&h->hb, (uint32_t)wb);
	}
	/* dirty lines written back: read out of SDRAM, over the host bus */
	for (uint64_t i = a.writebacks; i < b->writebacks; i++) {
		func_sdram(h, MEMIF_FILL, h->v.p.line, 0);
		h->fhb.transfers++;
		h->fhb.bytes += h->v.p.line;
		h->fhb.busy_ticks += hbus_duration(&h->hb, h->v.p.line);
	}
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
	cache *c = &l->c;
	uint32_t lb = c->p.line_bytes;
	uint64_t first = cache_line_of(c, r->addr), end = r->addr + bytes;
	/* most reads fit one line: no second division (36-byte lines) */
	uint64_t last = end <= (first + 1) * lb ? first : cache_line_of(c, end - 1);
	for (uint64_t line = first; line <= last; line++) {
		uint64_t lo = line * lb, hi = lo + lb;
		uint64_t a = r->addr > lo ? r->addr : lo, b = end < hi ? end : hi;
		uint32_t slot;
		uint64_t victim;
		int hit = cache_lookup_func_at(c, line, (uint32_t)(b - a), &slot, &victim);
		if (!h->ms) {
			if (!hit)
				func_lower(h, type, lo, lb, 0, NULL);
			continue;
		}
		if (slot == CACHE_NO_SLOT) {
			/* a timed fill is on its way: the bytes it brings */
			if (data)
				lower_peek(h, a, (uint32_t)(b - a), data + (a - r->addr));
			continue;
		}
		uint8_t *d = l1_data(h, l, slot);
		if (!hit) /* the line fills from below at once */
			func_lower(h, type, lo, lb, 0, d);
		if (d && data)
			memcpy(data + (a - r->addr), d + (a - lo), (size_t)(b - a));
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
	const cache *c = &h->l1[r->type].c;
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
	return h->oom || h->v.oom || (h->ms && h->ms->oom);
}

static void hier_destroy(void *impl)
{
	hier *h = impl;
	for (int t = 0; t < MEM_NTYPES; t++) {
		cache_free(&h->l1[t].c);
		free(h->l1[t].wait);
		free(h->l1[t].mbuf);
	}
	if (h->use_vma)
		vma_free(&h->v);
	memif_free(&h->mi);
	for (hchunk *c = h->chunks, *n; c; c = n) {
		n = c->next;
		free(c);
	}
	free(h);
}

static const memport_model hier_model = {"hierarchy",      hier_access, hier_destroy,
                                         hier_access_func, hier_peek,   hier_failed};

/* ---- construction ---- */

static const cfg_l1 *l1_cfg(const saar_config *cfg, int t)
{
	switch (t) {
	case MEM_SHADE:
		return &cfg->memory.l1.shade;
	case MEM_KD:
		return &cfg->memory.l1.kd;
	case MEM_LIST:
		return &cfg->memory.l1.list;
	default:
		return &cfg->memory.l1.tri;
	}
}

cache_params hier_l1_params(const saar_config *cfg, int type)
{
	const cfg_l1 *c = l1_cfg(cfg, type);
	return (cache_params){
	    (uint64_t)c->size_kb << 10, (uint32_t)c->ways,  (uint32_t)c->line, (uint32_t)c->mshrs,
	    (uint32_t)c->hit_latency,   (uint32_t)c->ports, CACHE_HASH_NONE};
}

vma_params hier_vma_params(const saar_config *cfg)
{
	const __typeof__(cfg->memory.vma) *v = &cfg->memory.vma;
	return (vma_params){(uint32_t)v->ways,
	                    (uint32_t)v->line,
	                    v->hash == CFG_HASH_NONE ? CACHE_HASH_NONE : CACHE_HASH_XOR,
	                    v->tag_cache_enabled,
	                    (uint64_t)v->tag_cache_kb << 10,
	                    (uint32_t)v->tag_cache_ways,
	                    (uint32_t)v->tag_cache_latency};
}

void hier_hbus_params(const saar_config *cfg, hbus_params *hp)
{
	static const char *const pn[] = {"pci", "pci66", "agp"};
	const __typeof__(cfg->memory.hostbus) *b = &cfg->memory.hostbus;
	hbus_preset(pn[b->preset], hp);
	if (b->width_bits > 0)
		hp->width_bits = (uint32_t)b->width_bits;
	if (b->clock_mhz > 0)
		hp->clock_mhz = b->clock_mhz;
	if (b->burst > 0)
		hp->burst = (uint32_t)b->burst;
	if (b->latency_ns >= 0)
		hp->latency_ns = b->latency_ns;
}

int mem_init_hier(memport *p, eng *e, eng_clock core, const saar_config *cfg, uint64_t image_bytes,
                  mem_store *store, diag *d)
{
	memset(p, 0, sizeof *p);
	const __typeof__(cfg->memory) *M = &cfg->memory;
	uint64_t sd_bytes = (uint64_t)M->sdram.mb << 20;
	if (!M->vma.enabled && image_bytes > sd_bytes)
		return diag_set(d, "config", 0, 0,
		                "the memory image (%.1f MB) does not fit in on-board memory "
		                "(memory.sdram.mb = %d); enable the virtual memory architecture "
		                "(configs/saarcor-vma.yaml, memory.vma.enabled: true) or raise "
		                "memory.sdram.mb",
		                (double)image_bytes / (1 << 20), M->sdram.mb);
	hier *h = calloc(1, sizeof *h);
	if (!h)
		return diag_set(d, "config", 0, 0, "out of memory");
	h->e = e;
	h->core = core;
	h->image_bytes = image_bytes;
	h->ms = store;
	for (int t = 0; t < MEM_NTYPES; t++) {
		char what[32];
		snprintf(what, sizeof what, "memory.l1.%s", mem_type_name(t));
		cache_params cp = hier_l1_params(cfg, t);
		h->l1[t].h = h;
		h->l1[t].type = t;
		if (cache_init(&h->l1[t].c, &cp, what, d))
			goto fail;
		h->l1[t].wait = calloc(cp.mshrs, sizeof *h->l1[t].wait);
		if (store)
			h->l1[t].mbuf = malloc((size_t)cp.mshrs * cp.line_bytes);
		if (!h->l1[t].wait || (store && (!h->l1[t].mbuf || cache_data_on(&h->l1[t].c)))) {
			diag_set(d, "config", 0, 0, "out of memory");
			goto fail;
		}
	}
	sdram_params sp = {sd_bytes,
	                   M->sdram.clock_mhz,
	                   (uint32_t)M->sdram.bus_bits,
	                   (uint32_t)M->sdram.banks,
	                   (uint32_t)M->sdram.row_bytes,
	                   (uint32_t)M->sdram.cl,
	                   (uint32_t)M->sdram.trcd,
	                   (uint32_t)M->sdram.trp,
	                   (uint32_t)M->sdram.tras,
	                   (uint32_t)M->sdram.burst,
	                   M->sdram.mapping == CFG_SDRAM_BANK_ROW_COL ? SDRAM_MAP_BANK_ROW_COL
	                                                              : SDRAM_MAP_ROW_BANK_COL};
	if (sdram_init(&h->sd, &sp, d))
		goto fail;
	/* the config's policy names are memif's own */
	int pol = memif_policy_parse(cfg_enum_name(cfg, "memory.memif.policy"));
	if (memif_init(&h->mi, e, &h->sd, pol < 0 ? MEMIF_FIFO : pol)) {
		diag_set(d, "config", 0, 0, "out of memory");
		goto fail;
	}
	if (M->vma.enabled) {
		hbus_params hp;
		hier_hbus_params(cfg, &hp);
		if (hbus_init(&h->hb, &hp, d))
			goto fail;
		vma_params vp = hier_vma_params(cfg);
		if (vma_init(&h->v, e, core, &h->mi, &h->hb, sd_bytes, &vp, store, d))
			goto fail;
		h->use_vma = 1;
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
	s->vma_enabled = h->use_vma;
	s->now_ticks = eng_now(h->e);
	s->core_period = h->core.period;
	for (int t = 0; t < MEM_NTYPES; t++) {
		s->l1[t] = h->l1[t].c.s;
		s->reads[t] = h->reads[t];
		s->read_bytes[t] = h->read_bytes[t];
		s->writes[t] = h->writes[t];
		s->write_bytes[t] = h->write_bytes[t];
		s->bypass_reads[t] = h->bypass[t];
		s->wait_cycles[t] = h->wait_ticks[t] / h->core.period;
		s->mshr_stall_cycles[t] = h->stall_ticks[t] / h->core.period;
	}
	s->memif = h->mi.s;
	s->sdram = h->sd.s;
	/* functional traffic joins the counts; its busy time stays apart */
	for (int r = 0; r < MEMIF_NREQ; r++) {
		s->memif.reads[r] += h->fmi.reads[r];
		s->memif.writes[r] += h->fmi.writes[r];
		s->memif.bytes[r] += h->fmi.bytes[r];
	}
	s->sdram.reads += h->fsd.reads;
	s->sdram.writes += h->fsd.writes;
	s->sdram.read_bytes += h->fsd.read_bytes;
	s->sdram.write_bytes += h->fsd.write_bytes;
	s->sdram.beats += h->fsd.beats;
	s->func_requests = h->freqs;
	s->func_sdram_busy_ticks = h->fsd.busy_ticks;
	s->func_sdram_merge_ticks = h->fmerge_ticks;
	s->func_hostbus_busy_ticks = h->fhb.busy_ticks;
	s->sdram_peak_bytes_per_s = sdram_peak_bw(&h->sd);
	if (h->use_vma) {
		s->tag_cache = h->v.tag.s;
		s->l2 = h->v.l2.s;
		s->vma = h->v.s;
		s->hostbus = h->hb.s;
		s->hostbus.transfers += h->fhb.transfers;
		s->hostbus.bytes += h->fhb.bytes;
		s->hostbus_peak_bytes_per_s = hbus_peak_bw(&h->hb);
	}
	return 0;
}

/* ---- stored warming (sim/warming.h) ---- */

void hier_caches(memport *p, cache *l1[MEM_NTYPES], cache **tag, cache **l2)
{
	hier *h = p->impl;
	for (int t = 0; t < MEM_NTYPES; t++)
		l1[t] = &h->l1[t].c;
	*tag = h->use_vma && h->v.p.tag_cache_enabled ? &h->v.tag : NULL;
	*l2 = h->use_vma ? &h->v.l2 : NULL;
}

void hier_reload(memport *p, const uint64_t *l2sets)
{
	hier *h = p->impl;
	if (!h->ms)
		return;
	if (h->use_vma && l2sets)
		vma_reload(&h->v, l2sets);
	for (int t = 0; t < MEM_NTYPES; t++) {
		hl1 *l = &h->l1[t];
		uint32_t lb = l->c.p.line_bytes;
		size_t n = (size_t)l->c.nsets * l->c.p.ways;
		for (size_t i = 0; i < n; i++) {
			uint64_t line = l->c.way[i].tag;
			uint8_t *d = line == CACHE_INVALID ? NULL : l1_data(h, l, (uint32_t)i);
			if (d)
				lower_peek(h, line * lb, lb, d);
		}
	}
}

/* Adds the n 64-bit counters of a stats struct to out (every field of
 * these structs is a uint64_t counter). */
#define COUNTERS(st) (uint64_t *)&(st), sizeof(st) / sizeof(uint64_t)
_Static_assert(sizeof(cache_stats) % 8 == 0 && sizeof(sdram_stats) % 8 == 0 &&
                   sizeof(memif_stats) % 8 == 0 && sizeof(hbus_stats) % 8 == 0 &&
                   sizeof(vma_stats) % 8 == 0,
               "stats structs hold uint64_t counters only");

static size_t add_ptrs(uint64_t **out, size_t n, size_t cap, uint64_t *a, size_t k)
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
		n = add_ptrs(out, n, cap, arr[i], MEM_NTYPES);
	for (int t = 0; t < MEM_NTYPES; t++)
		n = add_ptrs(out, n, cap, COUNTERS(h->l1[t].c.s));
	n = add_ptrs(out, n, cap, COUNTERS(h->fsd));
	n = add_ptrs(out, n, cap, COUNTERS(h->fmi));
	n = add_ptrs(out, n, cap, COUNTERS(h->fhb));
	n = add_ptrs(out, n, cap, &h->freqs, 1);
	n = add_ptrs(out, n, cap, &h->fl2hit_ticks, 1);
	if (h->use_vma) {
		n = add_ptrs(out, n, cap, COUNTERS(h->v.s));
		n = add_ptrs(out, n, cap, COUNTERS(h->v.tag.s));
		n = add_ptrs(out, n, cap, COUNTERS(h->v.l2.s));
	}
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

double hier_merge_share(const memport *p)
{
	return hier_is(p) ? merge_share(p->impl) : 0;
}

/* ---- JSON ---- */

static double ratio(uint64_t a, uint64_t b)
{
	return b ? (double)a / (double)b : 0.0;
}

static void cache_json(jsonw *w, const char *key, const cache_stats *c)
{
	jsonw_key(w, key);
	jsonw_obj_begin(w);
	jsonw_kuint(w, "accesses", c->accesses);
	jsonw_kuint(w, "hits", c->hits);
	jsonw_kuint(w, "misses", c->misses);
	jsonw_knum(w, "hit_rate", ratio(c->hits, c->accesses));
	jsonw_kuint(w, "mshr_merges", c->merges);
	jsonw_kuint(w, "mshr_full", c->mshr_full);
	jsonw_kuint(w, "bytes", c->bytes);
	jsonw_kuint(w, "fills", c->fills);
	jsonw_kuint(w, "fill_bytes", c->fill_bytes);
	jsonw_kuint(w, "evictions", c->evictions);
	jsonw_obj_end(w);
}

void hier_write_json(const hier_stats *s, jsonw *w)
{
	double secs = (double)s->now_ticks * 1e-12;
	jsonw_obj_begin(w);
	jsonw_kstr(w, "model", "hierarchy");
	jsonw_kbool(w, "vma_enabled", s->vma_enabled);
	jsonw_knum(w, "elapsed_s", secs);

	jsonw_key(w, "l1");
	jsonw_obj_begin(w);
	for (int t = 0; t < MEM_NTYPES; t++) {
		jsonw_key(w, mem_type_name(t));
		jsonw_obj_begin(w);
		jsonw_kuint(w, "reads", s->reads[t]);
		jsonw_kuint(w, "read_bytes", s->read_bytes[t]);
		jsonw_kuint(w, "writes", s->writes[t]);
		jsonw_kuint(w, "write_bytes", s->write_bytes[t]);
		jsonw_kuint(w, "bypass_reads", s->bypass_reads[t]);
		jsonw_kuint(w, "wait_cycles", s->wait_cycles[t]);
		jsonw_kuint(w, "mshr_stall_cycles", s->mshr_stall_cycles[t]);
		cache_json(w, "cache", &s->l1[t]);
		jsonw_obj_end(w);
	}
	jsonw_obj_end(w);

	uint64_t meta = s->memif.reads[MEMIF_META] + s->memif.writes[MEMIF_META], all = 0;
	jsonw_key(w, "memif");
	jsonw_obj_begin(w);
	for (int r = 0; r < MEMIF_NREQ; r++) {
		all += s->memif.reads[r] + s->memif.writes[r];
		jsonw_key(w, memif_requester_name(r));
		jsonw_obj_begin(w);
		jsonw_kuint(w, "reads", s->memif.reads[r]);
		jsonw_kuint(w, "writes", s->memif.writes[r]);
		jsonw_kuint(w, "bytes", s->memif.bytes[r]);
		jsonw_kuint(w, "queue_cycles", s->memif.queue_ticks[r] / s->core_period);
		jsonw_obj_end(w);
	}
	jsonw_obj_end(w);

	const sdram_stats *d = &s->sdram;
	uint64_t rows = d->row_hits + d->row_empty + d->row_conflicts;
	jsonw_key(w, "sdram");
	jsonw_obj_begin(w);
	jsonw_kuint(w, "reads", d->reads);
	jsonw_kuint(w, "writes", d->writes);
	jsonw_kuint(w, "read_bytes", d->read_bytes);
	jsonw_kuint(w, "write_bytes", d->write_bytes);
	jsonw_kuint(w, "bytes", d->read_bytes + d->write_bytes);
	jsonw_kuint(w, "meta_accesses", meta);
	jsonw_kuint(w, "data_accesses", all - meta);
	jsonw_knum(w, "meta_share", ratio(meta, all));
	jsonw_kuint(w, "row_hits", d->row_hits);
	jsonw_kuint(w, "row_empty", d->row_empty);
	jsonw_kuint(w, "row_conflicts", d->row_conflicts);
	jsonw_knum(w, "row_hit_rate", ratio(d->row_hits, rows));
	jsonw_kuint(w, "busy_ns", d->busy_ticks / 1000);
	jsonw_knum(w, "utilization", ratio(d->busy_ticks, s->now_ticks));
	double run_s = s->run_ticks ? (double)s->run_ticks * 1e-12 : secs;
	jsonw_knum(w, "bandwidth_gb_s",
	           run_s > 0 ? (double)(d->read_bytes + d->write_bytes) / run_s / 1e9 : 0.0);
	jsonw_knum(w, "peak_gb_s", s->sdram_peak_bytes_per_s / 1e9);
	jsonw_obj_end(w);

	if (s->vma_enabled) {
		const vma_stats *v = &s->vma;
		jsonw_key(w, "vma");
		jsonw_obj_begin(w);
		cache_json(w, "tag_cache", &s->tag_cache);
		cache_json(w, "l2", &s->l2);
		jsonw_kuint(w, "meta_reads", v->meta_reads);
		jsonw_kuint(w, "meta_writes", v->meta_writes);
		jsonw_kuint(w, "meta_bytes", v->meta_bytes);
		jsonw_kuint(w, "data_reads", v->data_reads);
		jsonw_kuint(w, "data_writes", v->data_writes);
		jsonw_kuint(w, "data_bytes", v->data_bytes);
		jsonw_kuint(w, "host_fetches", v->host_fetches);
		jsonw_kuint(w, "host_fetch_bytes", v->host_fetch_bytes);
		jsonw_kuint(w, "host_writes", v->host_writes);
		jsonw_kuint(w, "host_write_bytes", v->host_write_bytes);
		jsonw_kuint(w, "writebacks", v->writebacks);
		jsonw_kuint(w, "writeback_bytes", v->writeback_bytes);
		jsonw_kuint(w, "mshr_stall_cycles", v->stall_ticks / s->core_period);
		jsonw_obj_end(w);
		const hbus_stats *b = &s->hostbus;
		jsonw_key(w, "hostbus");
		jsonw_obj_begin(w);
		jsonw_kuint(w, "transfers", b->transfers);
		jsonw_kuint(w, "bytes", b->bytes);
		jsonw_kuint(w, "busy_ns", b->busy_ticks / 1000);
		jsonw_knum(w, "utilization", ratio(b->busy_ticks, s->now_ticks));
		jsonw_knum(w, "peak_mb_s", s->hostbus_peak_bytes_per_s / 1e6);
		jsonw_obj_end(w);
	}
	jsonw_obj_end(w);
}
