/*
 * cache.c: the generic set-associative cache (see cache.h).
 *
 * Storage is one flat array of nsets*ways ways (tag and replacement word
 * side by side, set by set), the policy's per-set words if it has any, and
 * the MSHRs (their lines, bucket chains and free bitmask), allocated once
 * in cache_init. LRU keeps a 64-bit use
 * stamp per way: the victim is the way with the smallest stamp (empty ways
 * first), which is exact LRU and needs no list manipulation; 2^64 accesses
 * never wrap. Stamp policies (LRU, FIFO) are updated inline; others
 * through their hooks (mem/repl.h).
 */
#include "mem/cache.h"

#include <stdlib.h>
#include <string.h>

/* Words of the free-MSHR bitmask. */
static size_t mshr_words(uint32_t mshrs)
{
	return ((size_t)mshrs + 63) / 64;
}

int cache_check(const cache_params *p, const char *what, diag *d)
{
	if (p->ways < 1 || p->line_bytes < 1 || p->mshrs < 1 || p->ports < 1)
		return diag_set(d, "config", 0, 0, "%s: ways, line, mshrs and ports must be >= 1",
		                what);
	uint64_t per_set = (uint64_t)p->ways * p->line_bytes;
	if (p->size_bytes < per_set)
		return diag_set(d, "config", 0, 0,
		                "%s: %llu bytes cannot hold one set of %u ways x %u-byte lines",
		                what, (unsigned long long)p->size_bytes, p->ways, p->line_bytes);
	if (p->size_bytes / per_set > UINT32_MAX)
		return diag_set(d, "config", 0, 0, "%s: too many sets", what);
	const repl_policy *rp = p->repl ? p->repl : &repl_lru;
	if (rp->check && rp->check(p->ways))
		return diag_set(d, "config", 0, 0, "%s: replacement %s cannot manage %u ways (%s)",
		                what, rp->name, p->ways, rp->desc);
	return 0;
}

int cache_init(cache *c, const cache_params *p, const char *what, diag *d)
{
	memset(c, 0, sizeof *c);
	if (cache_check(p, what, d))
		return -1;
	const repl_policy *rp = p->repl ? p->repl : &repl_lru;
	c->p = *p;
	c->p.repl = c->rp = rp;
	c->stamp_hit = rp->stamp_hit;
	c->stamp_fill = rp->stamp_fill;
	c->nsets = (uint32_t)(p->size_bytes / ((uint64_t)p->ways * p->line_bytes));
	while (c->hash_bits < 63 && (1ull << c->hash_bits) < c->nsets)
		c->hash_bits++;
	c->set_mask = !(c->nsets & (c->nsets - 1)) ? c->nsets - 1 : 0;
	c->set_div = fastdiv_of(c->nsets);
	c->line_div = fastdiv_of(p->line_bytes);
	c->line_shift = -1;
	for (int b = 0; b < 32; b++)
		if (p->line_bytes == 1u << b)
			c->line_shift = b;
	/* whole 64-byte host lines: a 4-way set is exactly one */
	size_t bytes = (size_t)c->nsets * p->ways * sizeof(cache_way);
	c->way = aligned_alloc(64, (bytes + 63) / 64 * 64);
	c->mshr_line = malloc(p->mshrs * sizeof *c->mshr_line);
	c->mshr_next = malloc(p->mshrs * sizeof *c->mshr_next);
	c->mshr_free = malloc(mshr_words(p->mshrs) * sizeof *c->mshr_free);
	if (rp->set_words)
		c->rst = malloc((size_t)c->nsets * rp->set_words * sizeof *c->rst);
	if (!c->way || !c->mshr_line || !c->mshr_next || !c->mshr_free ||
	    (rp->set_words && !c->rst)) {
		cache_free(c);
		return diag_set(d, "config", 0, 0, "%s: out of memory", what);
	}
	cache_flush(c);
	return 0;
}

uint64_t cache_host_bytes(const cache_params *p)
{
	uint64_t per_set = (uint64_t)p->ways * p->line_bytes;
	uint64_t nsets = per_set ? p->size_bytes / per_set : 0;
	uint64_t words = p->repl ? p->repl->set_words : 0;
	return nsets * p->ways * sizeof(cache_way) + nsets * words * sizeof(uint64_t) +
	       (uint64_t)p->mshrs * (sizeof(uint64_t) + sizeof(uint32_t)) +
	       mshr_words(p->mshrs) * sizeof(uint64_t);
}

void cache_free(cache *c)
{
	free(c->way);
	free(c->mshr_line);
	free(c->mshr_next);
	free(c->mshr_free);
	free(c->rst);
	free(c->dirty);
	free(c->didx);
	for (uint32_t i = 0; i < c->dchunks; i++)
		free(c->dchunk[i]);
	free(c->dchunk);
	c->way = NULL;
	c->mshr_line = NULL;
	c->mshr_next = NULL;
	c->mshr_free = NULL;
	c->rst = NULL;
	c->dirty = NULL;
	c->didx = NULL;
	c->dchunk = NULL;
	c->dchunks = c->dcap = c->dused = 0;
}

int cache_data_on(cache *c)
{
	if (!c->didx)
		c->didx = calloc((size_t)c->nsets * c->p.ways, sizeof *c->didx);
	return c->didx ? 0 : -1;
}

uint64_t cache_data_host_bytes(const cache_params *p, uint64_t lines)
{
	uint64_t per_set = (uint64_t)p->ways * p->line_bytes;
	uint64_t slots = (per_set ? p->size_bytes / per_set : 0) * p->ways;
	uint64_t used = lines * p->ways < slots ? lines * p->ways : slots;
	uint64_t chunk = 1ull << CACHE_DCHUNK_BITS;
	used = (used + chunk - 1) / chunk * chunk;
	return slots * sizeof(uint32_t) + used * p->line_bytes;
}

uint8_t *cache_data(cache *c, uint32_t slot)
{
	uint8_t *d = cache_data_at(c, slot);
	if (d)
		return d;
	uint32_t i = c->dused, k = i >> CACHE_DCHUNK_BITS;
	if (k == c->dchunks) {
		if (k == c->dcap) {
			uint32_t cap = c->dcap ? 2 * c->dcap : 16;
			uint8_t **n = realloc(c->dchunk, cap * sizeof *n);
			if (!n)
				return NULL;
			c->dchunk = n;
			c->dcap = cap;
		}
		c->dchunk[k] = calloc((size_t)1 << CACHE_DCHUNK_BITS, c->p.line_bytes);
		if (!c->dchunk[k])
			return NULL;
		c->dchunks++;
	}
	c->dused++;
	c->didx[slot] = i + 1;
	return cache_data_at(c, slot);
}

int cache_track(cache *c)
{
	if (!c->dirty)
		c->dirty = calloc((size_t)bits_words((int)c->nsets), sizeof *c->dirty);
	return c->dirty ? 0 : -1;
}

void cache_dirty_clear(cache *c)
{
	if (c->dirty)
		memset(c->dirty, 0, (size_t)bits_words((int)c->nsets) * sizeof *c->dirty);
}

void cache_repl_hit(cache *c, uint32_t set, uint32_t w)
{
	repl_set v = cache_set_view(c, set);
	c->rp->hit(&v, w);
}

int cache_save(const cache *c, uint32_t set0, uint32_t n, uint32_t *line, uint8_t *st)
{
	uint32_t W = c->p.ways;
	for (uint32_t s = 0; s < n; s++) {
		repl_set v = cache_set_view(c, set0 + s);
		for (uint32_t i = 0; i < W; i++) {
			size_t k = (size_t)s * W + i;
			if (v.way[i].tag != CACHE_INVALID && v.way[i].tag >= UINT32_MAX)
				return -1;
			line[k] =
			    v.way[i].tag == CACHE_INVALID ? UINT32_MAX : (uint32_t)v.way[i].tag;
		}
		(c->rp->save ? c->rp->save : repl_stamp_save)(&v, st + (size_t)s * W);
	}
	return 0;
}

void cache_load(cache *c, uint32_t set0, uint32_t n, const uint32_t *line, const uint8_t *st)
{
	uint32_t W = c->p.ways;
	for (uint32_t s = 0; s < n; s++) {
		repl_set v = cache_set_view(c, set0 + s);
		for (uint32_t i = 0; i < W; i++) {
			size_t k = (size_t)s * W + i;
			v.way[i].tag = line[k] == UINT32_MAX ? CACHE_INVALID : line[k];
		}
		(c->rp->load ? c->rp->load : repl_stamp_load)(&v, st + (size_t)s * W);
	}
}

static size_t pad8(size_t n)
{
	return (n + 7) & ~(size_t)7;
}

size_t cache_ckpt_bytes(const cache *c, uint32_t n)
{
	size_t nw = (size_t)n * c->p.ways;
	return pad8(nw * 4) + pad8(nw);
}

void cache_ckpt_empty(const cache *c, uint32_t n, void *buf)
{
	size_t nw = (size_t)n * c->p.ways;
	memset(buf, 0, cache_ckpt_bytes(c, n));
	memset(buf, 0xff, nw * 4); /* UINT32_MAX: no line */
}

int cache_ckpt_save(const cache *c, uint32_t set0, uint32_t n, void *buf)
{
	size_t nw = (size_t)n * c->p.ways;
	uint8_t *b = buf;
	memset(b, 0, cache_ckpt_bytes(c, n));
	return cache_save(c, set0, n, (uint32_t *)(void *)b, b + pad8(nw * 4));
}

int cache_ckpt_load(cache *c, uint32_t set0, uint32_t n, const void *buf)
{
	if (c->mshr_used)
		return -1;
	size_t nw = (size_t)n * c->p.ways;
	const uint8_t *b = buf;
	cache_load(c, set0, n, (const uint32_t *)(const void *)b, b + pad8(nw * 4));
	return 0;
}

void cache_flush(cache *c)
{
	size_t n = (size_t)c->nsets * c->p.ways;
	for (size_t i = 0; i < n; i++)
		c->way[i] = (cache_way){CACHE_INVALID, 0};
	if (c->rst)
		memset(c->rst, 0, (size_t)c->nsets * c->rp->set_words * sizeof *c->rst);
	for (uint32_t i = 0; i < c->p.mshrs; i++)
		c->mshr_line[i] = CACHE_INVALID;
	c->mshr_used = 0;
	for (uint32_t b = 0; b < CACHE_MSHR_BUCKETS; b++)
		c->mshr_head[b] = CACHE_MSHR_NIL;
	size_t nw = mshr_words(c->p.mshrs);
	for (size_t w = 0; w < nw; w++) {
		uint32_t left = c->p.mshrs - (uint32_t)(w * 64);
		c->mshr_free[w] = left >= 64 ? UINT64_MAX : (1ull << left) - 1;
	}
}

uint64_t cache_invalidate(cache *c, uint64_t addr, uint64_t n)
{
	uint64_t dropped = 0;
	if (!n)
		return 0;
	for (uint64_t l = cache_line_of(c, addr), e = cache_line_of(c, addr + n - 1); l <= e; l++) {
		uint32_t set = cache_set_of(c, l);
		cache_way *s = c->way + (size_t)set * c->p.ways;
		for (uint32_t w = 0; w < c->p.ways; w++)
			if (s[w].tag == l) {
				s[w] = (cache_way){CACHE_INVALID, 0};
				dropped++;
				if (c->dirty)
					c->dirty[set >> 6] |= 1ull << (set & 63);
			}
	}
	return dropped;
}

/* XOR-fold: the line index folded onto itself in hash_bits-wide slices, so
 * strides that are multiples of nsets (regions 128-byte aligned, records of
 * equal size) spread over the sets instead of piling into one (seed 002 §4.2:
 * "address-hashing is used to reduce the probability of collisions").
 * cache_set_of calls this only for hashed caches and set counts that are
 * not a power of two. */
uint32_t cache_set_fold(const cache *c, uint64_t line)
{
	uint64_t h = line;
	if (c->p.hash == CACHE_HASH_XOR && c->hash_bits) {
		for (uint64_t x = line >> c->hash_bits; x; x >>= c->hash_bits)
			h ^= x;
	}
	return (uint32_t)(c->set_mask ? h & c->set_mask : fastdiv_mod(c->set_div, h));
}

int cache_probe(const cache *c, uint64_t line, uint32_t *slot)
{
	uint32_t set = cache_set_of(c, line);
	int w = cache_find_way(c, set, line);
	if (w >= 0 && slot)
		*slot = set * c->p.ways + (uint32_t)w;
	return w >= 0;
}

uint32_t cache_fill(cache *c, uint64_t line, uint64_t *victim)
{
	return cache_fill_mshr(c, line, cache_mshr_find(c, line), victim);
}

int cache_lookup_func_at(cache *c, uint64_t line, uint32_t bytes, uint32_t *slot, uint64_t *victim)
{
	uint32_t set = cache_set_of(c, line);
	int w = cache_find_way(c, set, line);
	c->s.accesses++;
	c->s.func_accesses++;
	c->s.bytes += bytes;
	*victim = CACHE_INVALID;
	if (w >= 0) {
		size_t i = (size_t)set * c->p.ways + (size_t)w;
		cache_use(c, set, &c->way[i]);
		c->s.hits++;
		c->s.func_hits++;
		*slot = (uint32_t)i;
		return 1;
	}
	c->s.misses++;
	if (cache_mshr_find(c, line) >= 0) {
		c->s.merges++;
		c->s.func_merges++;
		*slot = CACHE_NO_SLOT;
		return 1;
	}
	/* absent and in no MSHR: fill it here, without searching again */
	*slot = cache_fill_absent(c, set, line, victim);
	return 0;
}

int cache_lookup_func(cache *c, uint64_t line, uint32_t bytes)
{
	uint32_t slot;
	uint64_t victim;
	return cache_lookup_func_at(c, line, bytes, &slot, &victim);
}

uint32_t cache_access(cache *c, uint64_t addr, uint32_t bytes)
{
	uint64_t first = cache_line_of(c, addr);
	uint64_t last = cache_line_of(c, addr + (bytes ? bytes : 1) - 1);
	uint32_t missed = 0;
	for (uint64_t l = first; l <= last; l++) {
		/* bytes of this access that fall into line l */
		uint64_t lo = l * c->p.line_bytes, hi = lo + c->p.line_bytes;
		uint64_t a = addr > lo ? addr : lo, b = addr + bytes < hi ? addr + bytes : hi;
		uint32_t nb = b > a ? (uint32_t)(b - a) : 0;
		if (!cache_lookup_func(c, l, nb))
			missed++;
	}
	return missed;
}

/* Timed hits and merges between the snapshots, as doubles; returns the
 * merges' share of them (with the skips' timed hits and merges, which
 * the counts no longer hold), and the functional hits in *fh. */
static double timed_counts(const cache_stats *from, const cache_stats *to, double *th, double *fh)
{
	static const cache_stats zero;
	if (!from)
		from = &zero;
	double h = (double)(to->hits - from->hits), m = (double)(to->merges - from->merges);
	*fh = (double)(to->func_hits - from->func_hits);
	*th = h - *fh;
	double tm = m - (double)(to->func_merges - from->func_merges),
	       sm = (double)(to->skip_merges - from->skip_merges),
	       all = *th + tm + (double)(to->skip_hits - from->skip_hits) + sm;
	return all > 0 ? (tm + sm) / all : 0.0;
}

double cache_timed_merge_share(const cache_stats *from, const cache_stats *to)
{
	double th, fh;
	return timed_counts(from, to, &th, &fh);
}

double cache_timed_hits(const cache_stats *from, const cache_stats *to, double *share)
{
	double th, fh, r = timed_counts(from, to, &th, &fh);
	if (share)
		*share = r;
	return th + fh * (1.0 - r);
}
