/*
 * vma.c: the L2 virtual memory architecture (see vma.h).
 *
 * A read is split into pieces, one per L2 line it touches; each piece walks
 * meta lookup -> L2 lookup -> SDRAM data read or host-bus DMA, as engine
 * events. The tag cache and the on-board cache are timed caches
 * (mem/tcache.h): pieces waiting on an MSHR hang on its list; pieces
 * refused for lack of an MSHR wait in its FIFO and are retried when a fill
 * frees one. Pieces and requests come from free lists that grow in chunks,
 * so the steady state never allocates.
 */
#include "mem/vma.h"

#include <stdlib.h>
#include <string.h>

/* Both pooled records start with their free-list link (see pool_take). */
struct vma_req {
	vma_req *next;
	eng_handler done;
	void *ctx;
	uint64_t arg;
	uint32_t pending;
};

struct vma_piece {
	vma_piece *next;
	vma_req *req;
	uint64_t addr, line;
	uint8_t *dst; /* where the piece's bytes go; NULL: no data */
	uint32_t bytes;
	uint8_t type;
};

/* ---- free lists ---- */

typedef struct vchunk {
	struct vchunk *next;
} vchunk;

typedef struct vpool {
	vchunk *chunks;
	struct vlink *fp, *fr; /* free pieces, free requests */
} vpool;

#define VCHUNK 256

/* A pooled record's first member: its link in the free list. */
typedef struct vlink {
	struct vlink *next;
} vlink;

/* Takes a record of `size` bytes from the free list *head, growing the
 * pool by a chunk of VCHUNK records when it is empty (no malloc per
 * request). NULL when out of memory. */
static void *pool_take(vpool *P, vlink **head, size_t size)
{
	if (!*head) {
		vchunk *c = malloc(sizeof(vchunk) + VCHUNK * size);
		if (!c)
			return NULL;
		c->next = P->chunks;
		P->chunks = c;
		char *a = (char *)(c + 1);
		for (int i = 0; i < VCHUNK; i++) {
			vlink *l = (vlink *)(a + (size_t)i * size);
			l->next = *head;
			*head = l;
		}
	}
	vlink *l = *head;
	*head = l->next;
	l->next = NULL;
	return l;
}

static vma_piece *piece_alloc(vma *v)
{
	vpool *P = v->pool;
	return pool_take(P, &P->fp, sizeof(vma_piece));
}

static vma_req *req_alloc(vma *v)
{
	vpool *P = v->pool;
	return pool_take(P, &P->fr, sizeof(vma_req));
}

/* Returns a record to its free list. */
static void pool_give(vlink **head, void *rec)
{
	vlink *l = rec;
	l->next = *head;
	*head = l;
}

static void piece_release(vma *v, vma_piece *p)
{
	vpool *P = v->pool;
	pool_give(&P->fp, p);
}

static void req_release(vma *v, vma_req *r)
{
	vpool *P = v->pool;
	pool_give(&P->fr, r);
}

/* ---- setup ---- */

/* The on-board cache's parameters for sdram_bytes of on-board memory: as
 * many sets as fit beside their meta-data (0 sets: too small). */
static cache_params vma_l2_params(uint64_t sdram_bytes, const vma_params *p)
{
	uint64_t meta = (uint64_t)p->ways * VMA_META_BYTES_PER_LINE;
	uint64_t nsets = sdram_bytes / ((uint64_t)p->ways * p->line + meta);
	return (cache_params){
	    nsets * p->ways * p->line, p->ways, p->line, VMA_MSHRS, 0, 1, p->hash, p->repl};
}

static cache_params vma_tag_params(const vma_params *p)
{
	return (cache_params){
	    p->tag_cache_bytes, p->tag_cache_ways,  p->ways * VMA_META_BYTES_PER_LINE,
	    VMA_TAG_MSHRS,      p->tag_hit_latency, 1,
	    CACHE_HASH_NONE,    p->tag_repl};
}

/* 64-bit words of the dirty bits of n on-board lines. */
static size_t dirty_words(uint64_t n)
{
	return (size_t)((n + 63) / 64);
}

uint64_t vma_host_bytes(uint64_t sdram_bytes, const vma_params *p, uint64_t lines)
{
	if (p->ways < 1 || p->line < 1)
		return 0;
	cache_params lp = vma_l2_params(sdram_bytes, p), tp = vma_tag_params(p);
	uint64_t slots = lp.size_bytes / p->line;
	return cache_host_bytes(&lp) + dirty_words(slots) * 8 +
	       (lines ? cache_data_host_bytes(&lp, lines) : 0) +
	       (p->tag_cache_enabled ? cache_host_bytes(&tp) : 0);
}

int vma_check_params(const vma_params *p, diag *d)
{
	/* vma_check on a board of exactly one set with its meta-data (its
	 * ways and line are checked first) */
	return vma_check((uint64_t)p->ways * (p->line + VMA_META_BYTES_PER_LINE), p, d);
}

int vma_check(uint64_t sdram_bytes, const vma_params *p, diag *d)
{
	if (p->ways < 1 || p->line < 1)
		return diag_set(d, "config", 0, 0,
		                "memory.vma.ways and memory.vma.line must be >= 1");
	cache_params lp = vma_l2_params(sdram_bytes, p), tp = vma_tag_params(p);
	if (lp.size_bytes == 0)
		return diag_set(d, "config", 0, 0,
		                "memory.sdram.mb: on-board memory too small for one VMA set");
	if (cache_check(&lp, "memory.vma", d))
		return -1;
	return p->tag_cache_enabled ? cache_check(&tp, "memory.vma.tag_cache", d) : 0;
}

int vma_init(vma *v, eng *e, eng_clock core, memif *mi, hbus *hb, uint64_t sdram_bytes,
             const vma_params *p, mem_store *ms, diag *d)
{
	memset(v, 0, sizeof *v);
	v->e = e;
	v->core = core;
	v->mi = mi;
	v->hb = hb;
	v->p = *p;
	if (vma_check(sdram_bytes, p, d))
		return -1;
	v->meta_set_bytes = p->ways * VMA_META_BYTES_PER_LINE;
	cache_params lp = vma_l2_params(sdram_bytes, p);
	if (tcache_init(&v->l2, &lp, ms ? TC_DATA : 0, "memory.vma", d))
		return -1;
	v->meta_base = lp.size_bytes;
	if (p->tag_cache_enabled) {
		cache_params tp = vma_tag_params(p);
		if (tcache_init(&v->tag, &tp, 0, "memory.vma.tag_cache", d)) {
			vma_free(v);
			return -1;
		}
	}
	v->ms = ms;
	v->pool = calloc(1, sizeof(vpool));
	v->dirty = calloc(dirty_words(vma_capacity(v)), sizeof *v->dirty);
	if (!v->pool || !v->dirty) {
		vma_free(v);
		return diag_set(d, "config", 0, 0, "memory.vma: out of memory");
	}
	return 0;
}

void vma_free(vma *v)
{
	tcache_free(&v->l2);
	tcache_free(&v->tag);
	vpool *P = v->pool;
	if (P)
		for (vchunk *c = P->chunks, *n; c; c = n) {
			n = c->next;
			free(c);
		}
	free(P);
	free(v->dirty);
	v->pool = NULL;
	v->dirty = NULL;
}

uint64_t vma_capacity(const vma *v)
{
	return (uint64_t)v->l2.c.nsets * v->l2.c.p.ways;
}

/* ---- data ---- */

static int is_dirty(const vma *v, uint32_t slot)
{
	return (int)(v->dirty[slot / 64] >> (slot % 64) & 1);
}

static void set_dirty(vma *v, uint32_t slot, int on)
{
	if (on)
		v->dirty[slot / 64] |= 1ull << (slot % 64);
	else
		v->dirty[slot / 64] &= ~(1ull << (slot % 64));
}

/* The bytes of on-board line `slot` (allocated on its first fill); NULL
 * without data or out of memory. */
static uint8_t *line_data(vma *v, uint32_t slot)
{
	if (!v->ms)
		return NULL;
	uint8_t *d = cache_data(&v->l2.c, slot);
	if (!d)
		v->oom = 1;
	return d;
}

/* Copies bytes [addr, addr + n) of the on-board line in slot to dst. */
static void from_line(vma *v, uint32_t slot, uint64_t addr, uint32_t n, uint8_t *dst)
{
	const uint8_t *d = dst ? line_data(v, slot) : NULL;
	if (d)
		memcpy(dst, d + addr % v->p.line, n);
}

/* Line `line` fills slot, evicting `victim` (CACHE_INVALID: none): a
 * dirty victim's bytes go back to host memory, then the new line's bytes
 * come from host memory and it is clean. Returns whether the victim was
 * written back (counted here; its timing is the caller's). */
static int fill_slot(vma *v, uint32_t slot, uint64_t line, uint64_t victim)
{
	int wb = victim != CACHE_INVALID && is_dirty(v, slot);
	uint8_t *d = line_data(v, slot);
	if (wb) {
		v->s.writebacks++;
		v->s.writeback_bytes += v->p.line;
		if (d && ms_write(v->ms, victim * v->p.line, v->p.line, d))
			v->oom = 1;
	}
	set_dirty(v, slot, 0);
	if (d)
		ms_read(v->ms, line * v->p.line, v->p.line, d);
	return wb;
}

void vma_peek(const vma *v, uint64_t addr, uint32_t bytes, void *dst)
{
	uint8_t *o = dst;
	uint64_t end = addr + bytes;
	for (uint64_t a = addr; a < end;) {
		uint64_t line = a / v->p.line;
		uint64_t lend = (line + 1) * v->p.line;
		uint32_t n = (uint32_t)((end < lend ? end : lend) - a), slot;
		const uint8_t *d = NULL;
		if (v->ms && cache_probe(&v->l2.c, line, &slot))
			d = cache_data_at(&v->l2.c, slot);
		if (d)
			memcpy(o, d + a % v->p.line, n);
		else if (v->ms)
			ms_read(v->ms, a, n, o);
		else
			memset(o, 0, n);
		o += n;
		a += n;
	}
}

void vma_reload(vma *v, const uint64_t *sets)
{
	uint32_t W = v->l2.c.p.ways;
	int ns = (int)v->l2.c.nsets;
	for (int s = bits_next(sets, ns, 0); s < ns; s = bits_next(sets, ns, s + 1))
		for (uint32_t i = 0; i < W; i++) {
			uint32_t slot = (uint32_t)s * W + i;
			set_dirty(v, slot, 0);
			uint64_t line = v->l2.c.way[slot].tag;
			uint8_t *d = line == CACHE_INVALID ? NULL : line_data(v, slot);
			if (d)
				ms_read(v->ms, line * v->p.line, v->p.line, d);
		}
}

/* ---- the walk of one piece ---- */

static void meta_phase(vma *v, vma_piece *p, uint64_t t);
static void data_phase(vma *v, vma_piece *p, uint64_t t);

static void piece_finish(vma *v, vma_piece *p)
{
	vma_req *r = p->req;
	piece_release(v, p);
	if (--r->pending == 0) {
		eng_handler done = r->done;
		void *ctx = r->ctx;
		uint64_t arg = r->arg;
		req_release(v, r);
		if (done)
			done(v->e, ctx, arg);
	}
}

static void ev_piece_done(eng *e, void *ctx, uint64_t arg)
{
	piece_finish(ctx, (vma_piece *)(uintptr_t)arg);
}

static void ev_data_phase(eng *e, void *ctx, uint64_t arg)
{
	data_phase(ctx, (vma_piece *)(uintptr_t)arg, eng_now(e));
}

static uint64_t meta_addr(const vma *v, uint32_t set)
{
	return v->meta_base + (uint64_t)set * v->meta_set_bytes;
}

/* A piece refused for lack of a tag-cache MSHR, retried (tc_retry). */
static int meta_retry(void *ctx, void *who, uint64_t waited, uint64_t now)
{
	vma *v = ctx;
	v->s.stall_ticks += waited;
	meta_phase(v, who, now);
	return 0; /* an MSHR is free: it cannot be refused */
}

static void tag_filled(eng *e, void *ctx, uint64_t set)
{
	vma *v = ctx;
	uint64_t now = eng_now(e);
	int m;
	tc_wait *w = tcache_take(&v->tag, set, &m);
	cache_fill_mshr(&v->tag.c, set, m, NULL);
	for (vma_piece *p; (p = tcache_pop(&v->tag, &w));)
		data_phase(v, p, now);
	tcache_resume(&v->tag, now, meta_retry, v);
}

static void meta_phase(vma *v, vma_piece *p, uint64_t t)
{
	uint32_t set = cache_set_of(&v->l2.c, p->line);
	if (!v->p.tag_cache_enabled) {
		v->s.meta_reads++;
		v->s.meta_bytes += v->meta_set_bytes;
		memif_submit(v->mi, t, MEMIF_META, meta_addr(v, set), v->meta_set_bytes, 0,
		             ev_data_phase, v, (uintptr_t)p);
		return;
	}
	switch (tcache_lookup(&v->tag, set, v->meta_set_bytes, p, NULL, NULL)) {
	case CACHE_HIT:
		eng_schedule(v->e,
		             eng_next_edge(v->core, t) + v->p.tag_hit_latency * v->core.period,
		             ev_data_phase, v, (uintptr_t)p);
		break;
	case CACHE_MISS_NEW: /* p waits on the MSHR for the record */
		v->s.meta_reads++;
		v->s.meta_bytes += v->meta_set_bytes;
		memif_submit(v->mi, t, MEMIF_META, meta_addr(v, set), v->meta_set_bytes, 0,
		             tag_filled, v, set);
		break;
	case CACHE_MISS_MERGED:
		break;
	case CACHE_MSHR_FULL:
		tcache_stall(&v->tag, p, t);
		break;
	}
}

/* A piece refused for lack of an on-board-cache MSHR, retried. */
static int data_retry(void *ctx, void *who, uint64_t waited, uint64_t now)
{
	vma *v = ctx;
	v->s.stall_ticks += waited;
	data_phase(v, who, now);
	return 0; /* an MSHR is free: it cannot be refused */
}

static void dma_done(eng *e, void *ctx, uint64_t line)
{
	vma *v = ctx;
	uint64_t now = eng_now(e);
	int m;
	tc_wait *w = tcache_take(&v->l2, line, &m);
	uint64_t victim;
	uint32_t slot = cache_fill_mshr(&v->l2.c, line, m, &victim);
	uint32_t set = cache_set_of(&v->l2.c, line);
	if (fill_slot(v, slot, line, victim)) {
		/* the dirty victim leaves SDRAM for host memory */
		memif_submit(v->mi, now, MEMIF_FILL, (uint64_t)slot * v->p.line, v->p.line, 0, NULL,
		             NULL, 0);
		hbus_transfer(v->hb, now, v->p.line);
	}
	/* posted: the fetched line into its slot, its record into the meta-data
	 * (the tag cache, if it holds the record, is written through) */
	v->s.data_writes++;
	v->s.data_bytes += v->p.line;
	memif_submit(v->mi, now, MEMIF_FILL, (uint64_t)slot * v->p.line, v->p.line, 1, NULL, NULL,
	             0);
	v->s.meta_writes++;
	v->s.meta_bytes += v->meta_set_bytes;
	memif_submit(v->mi, now, MEMIF_META, meta_addr(v, set), v->meta_set_bytes, 1, NULL, NULL,
	             0);
	/* the requested bytes are forwarded from the DMA buffer */
	for (vma_piece *p; (p = tcache_pop(&v->l2, &w));) {
		from_line(v, slot, p->addr, p->bytes, p->dst);
		piece_finish(v, p);
	}
	tcache_resume(&v->l2, now, data_retry, v);
}

static void data_phase(vma *v, vma_piece *p, uint64_t t)
{
	uint32_t slot = 0;
	switch (tcache_lookup(&v->l2, p->line, p->bytes, p, NULL, &slot)) {
	case CACHE_HIT:
		v->s.data_reads++;
		v->s.data_bytes += p->bytes;
		from_line(v, slot, p->addr, p->bytes, p->dst);
		memif_submit(v->mi, t, p->type, (uint64_t)slot * v->p.line + p->addr % v->p.line,
		             p->bytes, 0, ev_piece_done, v, (uintptr_t)p);
		break;
	case CACHE_MISS_NEW: /* p waits on the MSHR for the line */
		v->s.host_fetches++;
		v->s.host_fetch_bytes += v->p.line;
		eng_schedule(v->e, hbus_transfer(v->hb, t, v->p.line), dma_done, v, p->line);
		break;
	case CACHE_MISS_MERGED:
		break;
	case CACHE_MSHR_FULL:
		tcache_stall(&v->l2, p, t);
		break;
	}
}

/* ---- entry points ---- */

int vma_read(vma *v, uint64_t t, int type, uint64_t addr, uint32_t bytes, void *dst,
             eng_handler done, void *ctx, uint64_t arg)
{
	vma_req *r = req_alloc(v);
	if (!r)
		return -1;
	*r = (vma_req){NULL, done, ctx, arg, 1};
	v->s.reads++;
	v->s.read_bytes += bytes;
	uint64_t end = addr + (bytes ? bytes : 1);
	for (uint64_t a = addr; a < end;) {
		uint64_t line = a / v->p.line;
		uint64_t lend = (line + 1) * v->p.line;
		uint32_t n = (uint32_t)((end < lend ? end : lend) - a);
		vma_piece *p = piece_alloc(v);
		if (!p)
			return -1;
		uint8_t *pd = dst ? (uint8_t *)dst + (a - addr) : NULL;
		*p = (vma_piece){NULL, r, a, line, pd, n, (uint8_t)type};
		r->pending++;
		meta_phase(v, p, t);
		a += n;
	}
	if (--r->pending == 0) { /* cannot happen: every piece ends in an event */
		req_release(v, r);
		if (done)
			eng_schedule(v->e, t, done, ctx, arg);
	}
	return 0;
}

/* The bytes [a, a + n) of a write (src at addr) into the on-board line
 * in slot, which becomes dirty and, as a read's hit would, the most
 * recent of its set for the replacement (the on-board cache replaces as
 * the L1s do, §4.2: a line just written stayed the least recent, and the
 * next fill of its set evicted it and paid its write-back), or around it
 * into host memory. */
static void write_data(vma *v, uint32_t slot, int on_board, uint64_t a, uint32_t n,
                       const uint8_t *src)
{
	if (on_board) {
		cache *c = &v->l2.c;
		cache_use(c, slot / c->p.ways, &c->way[slot]);
		set_dirty(v, slot, 1);
		uint8_t *d = src ? line_data(v, slot) : NULL;
		if (d)
			memcpy(d + a % v->p.line, src, n);
	} else if (src && v->ms && ms_write(v->ms, a, n, src))
		v->oom = 1;
}

/* A write's meta-data (§4.2: "parts of this meta data is required for
 * every memory access"): the set's record, from the tag cache if it holds
 * it (a write allocates no entry there and is no use of it: the tag
 * cache's counts stay one lookup per on-board read), else read from
 * SDRAM; and the record written back when the write makes its line dirty
 * (dirties). Timed (mi): the SDRAM accesses are posted at t; functional
 * (NULL): counted, their traffic made from the counts (hier_vma.c).
 * Returns -1 when the memory interface is out of memory. */
static int write_meta(vma *v, memif *mi, uint64_t t, uint64_t line, int dirties)
{
	uint32_t set = cache_set_of(&v->l2.c, line);
	for (int w = 0; w < 2; w++) {
		if (w ? !dirties : v->p.tag_cache_enabled && cache_probe(&v->tag.c, set, NULL))
			continue;
		*(w ? &v->s.meta_writes : &v->s.meta_reads) += 1;
		v->s.meta_bytes += v->meta_set_bytes;
		if (mi && memif_submit(mi, t, MEMIF_META, meta_addr(v, set), v->meta_set_bytes, w,
		                       NULL, NULL, 0))
			return -1;
	}
	return 0;
}

int vma_write(vma *v, uint64_t t, int type, uint64_t addr, uint32_t bytes, const void *src)
{
	v->s.writes++;
	v->s.write_bytes += bytes;
	uint64_t end = addr + (bytes ? bytes : 1);
	for (uint64_t a = addr; a < end;) {
		uint64_t line = a / v->p.line;
		uint64_t lend = (line + 1) * v->p.line;
		uint32_t n = (uint32_t)((end < lend ? end : lend) - a);
		uint32_t slot = 0;
		int on = cache_probe(&v->l2.c, line, &slot);
		if (write_meta(v, v->mi, t, line, on && !is_dirty(v, slot)))
			return -1;
		write_data(v, slot, on, a, n, src ? (const uint8_t *)src + (a - addr) : NULL);
		if (on) {
			v->s.data_writes++;
			v->s.data_bytes += n;
			if (memif_submit(v->mi, t, type, (uint64_t)slot * v->p.line + a % v->p.line,
			                 n, 1, NULL, NULL, 0))
				return -1;
		} else {
			v->s.host_writes++;
			v->s.host_write_bytes += n;
			hbus_transfer(v->hb, t, n);
		}
		a += n;
	}
	return 0;
}

void vma_access_func(vma *v, uint64_t addr, uint32_t bytes, int write, void *data)
{
	if (write) {
		v->s.writes++;
		v->s.write_bytes += bytes;
	} else {
		v->s.reads++;
		v->s.read_bytes += bytes;
	}
	uint64_t end = addr + (bytes ? bytes : 1);
	for (uint64_t a = addr; a < end;) {
		uint64_t line = a / v->p.line;
		uint64_t lend = (line + 1) * v->p.line;
		uint32_t n = (uint32_t)((end < lend ? end : lend) - a);
		uint8_t *pd = data ? (uint8_t *)data + (a - addr) : NULL;
		uint64_t at = a;
		a += n;
		if (write) {
			uint32_t slot = 0;
			int on = cache_probe(&v->l2.c, line, &slot);
			write_meta(v, NULL, 0, line, on && !is_dirty(v, slot));
			write_data(v, slot, on, at, n, pd);
			if (on) {
				v->s.data_writes++;
				v->s.data_bytes += n;
			} else {
				v->s.host_writes++;
				v->s.host_write_bytes += n;
			}
			continue;
		}
		uint32_t set = cache_set_of(&v->l2.c, line);
		if (!v->p.tag_cache_enabled ||
		    cache_access(&v->tag.c, (uint64_t)set * v->meta_set_bytes, v->meta_set_bytes)) {
			v->s.meta_reads++;
			v->s.meta_bytes += v->meta_set_bytes;
		}
		uint32_t slot;
		uint64_t victim;
		if (cache_lookup_func_at(&v->l2.c, line, n, &slot, &victim)) {
			v->s.data_reads++;
			v->s.data_bytes += n;
			if (pd && slot == CACHE_NO_SLOT) /* on its way: host memory's bytes */
				vma_peek(v, at, n, pd);
			else
				from_line(v, slot, at, n, pd);
		} else {
			v->s.host_fetches++;
			v->s.host_fetch_bytes += v->p.line;
			v->s.data_writes++;
			v->s.data_bytes += v->p.line;
			v->s.meta_writes++;
			v->s.meta_bytes += v->meta_set_bytes;
			fill_slot(v, slot, line, victim);
			from_line(v, slot, at, n, pd);
		}
	}
}
