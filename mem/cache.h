/*
 * cache.h: one generic set-associative cache with a replacement policy
 * (mem/repl.h; LRU by default) and MSHRs.
 *
 * Every cache of the chip is an instance of this module: the four L1s
 * (shading, kd-nodes, lists, triangles; seed 002 §4.1), the VMA tag cache
 * (§4.2) and, functionally, the VMA's L2 (on-board SDRAM as a 4-way cache of
 * host memory with 128-byte lines). Lines may be any size, 36 bytes included:
 * line index = addr / line_bytes, set = hash(line) mod nsets, and nsets need
 * not be a power of two.
 *
 * The module is the functional core only: which lines are present, which are
 * in flight and which way the policy evicts. Time lives in the timed cache
 * (mem/tcache.h) and its users (mem/hier.c, mem/vma.c): they call
 * cache_lookup when an access reaches the cache and
 * cache_fill when the line's data arrives from below. Between the two the
 * line occupies an MSHR; further misses to it merge; when all MSHRs are busy
 * a new miss gets CACHE_MSHR_FULL and changes nothing (the caller must retry
 * later, after some fill). That split lets a brute-force model be compared
 * access by access (tests/test_cache.c).
 *
 * Invariant: a line is never both present and in an MSHR; each set holds at
 * most `ways` valid lines, no two equal. LRU is exact (per-way use stamps);
 * other policies are chosen by cache_params.repl (mem/repl.h).
 * cache_lookup and cache_fill are O(ways + mshrs / 64 + the busy MSHRs in
 * the line's bucket) and never allocate.
 */
#ifndef SAAR_MEM_CACHE_H
#define SAAR_MEM_CACHE_H

#include <stddef.h>
#include <stdint.h>

#include "kernel-ref/bitset.h"
#include "kernel-ref/diag.h"
#include "mem/repl.h"
#include "sim/core/fastdiv.h"

enum cache_hash { CACHE_HASH_NONE, CACHE_HASH_XOR };

typedef struct cache_params {
	uint64_t size_bytes;     /* capacity of the data array */
	uint32_t ways;           /* associativity */
	uint32_t line_bytes;     /* any size >= 1 (36 for triangles) */
	uint32_t mshrs;          /* outstanding missed lines; 0 = unlimited in-flight is not
	                            allowed: every miss needs one, so mshrs >= 1 */
	uint32_t hit_latency;    /* core cycles; used by the timing wrapper */
	uint32_t ports;          /* accesses accepted per core cycle; timing wrapper */
	int hash;                /* enum cache_hash: how a line index picks its set */
	const repl_policy *repl; /* replacement (mem/repl.h); NULL: LRU */
} cache_params;

typedef enum cache_result {
	CACHE_HIT,         /* present; the policy saw the hit */
	CACHE_MISS_NEW,    /* absent; an MSHR was allocated: fetch the line, then cache_fill */
	CACHE_MISS_MERGED, /* absent but already in flight: wait for that fill */
	CACHE_MSHR_FULL,   /* absent and every MSHR busy: nothing changed, retry later */
} cache_result;

/* Counters. accesses = hits + misses; merges and mshr_full are not extra
 * accesses: merges <= misses, and a MSHR_FULL attempt is counted when it is
 * retried successfully (mshr_full counts the refusals). bytes = bytes the
 * accesses asked for; fill_bytes = lines fetched from below x line size. */
typedef struct cache_stats {
	uint64_t accesses, hits, misses, merges, mshr_full;
	uint64_t bytes, fills, fill_bytes, evictions;
	/* of accesses, hits and merges: those made by functional lookups
	 * (cache_lookup_func), where a line arrives at once, so an access a
	 * timed cache would merge into a fill in flight is a hit here
	 * (cache_timed_hits separates the two) */
	uint64_t func_accesses, func_hits, func_merges;
	/* timed hits and merges of regions whose counts a skip handed to the
	 * warming run (sampling.jump skip, sim/warming.h wm_skip): out of the
	 * counts above, but samples of the merge share all the same
	 * (cache_timed_hits) */
	uint64_t skip_hits, skip_merges;
} cache_stats;

/* cache_way (mem/repl.h): one way, its line and its replacement word side
 * by side, so a 4-way set is one 64-byte host cache line (two arrays made
 * every lookup touch two). */

/* Host bytes cache_init allocates for p (its way array, the policy's
 * per-set state and MSHRs): what a
 * run's memory estimate counts before it builds anything (sim/hostmem). */
uint64_t cache_host_bytes(const cache_params *p);

#define CACHE_MSHR_BUCKETS 64u /* a power of two */
#define CACHE_MSHR_NIL     UINT32_MAX

typedef struct cache {
	cache_params p;
	uint32_t nsets;
	uint32_t hash_bits; /* for xor-fold: bits of nsets rounded up */
	uint64_t set_mask;  /* nsets - 1 when nsets is a power of two, else 0 */
	int line_shift;     /* log2(line_bytes) when a power of two, else -1 */
	fastdiv line_div;   /* else line_bytes, and nsets, as divisors */
	fastdiv set_div;
	cache_way *way; /* nsets*ways, set by set, 64-byte aligned */
	uint64_t stamp;
	const repl_policy *rp;         /* p.repl, never NULL */
	uint8_t stamp_hit, stamp_fill; /* rp's inline stamp rules */
	uint64_t *rst;                 /* rp->set_words per set; NULL: none */
	uint64_t *mshr_line;           /* p.mshrs entries; CACHE_INVALID when free */
	uint32_t mshr_used;
	/* The busy MSHRs in chains by bucket of line number (mshr_head, then
	 * mshr_next; CACHE_MSHR_NIL ends a chain): cache_mshr_find walks its
	 * line's bucket only, never all MSHRs, which on a memory-bound frame
	 * are mostly busy (docs/PERFORMANCE.md, "Profile"). mshr_free holds
	 * one bit per free MSHR, so a miss takes the lowest free one from the
	 * first non-zero word instead of scanning the lines. */
	uint32_t mshr_head[CACHE_MSHR_BUCKETS];
	uint32_t *mshr_next; /* p.mshrs entries */
	uint64_t *mshr_free; /* (p.mshrs + 63) / 64 words */
	cache_stats s;
	/* sets changed since the last cache_dirty_clear, one bit each; NULL:
	 * not tracked (cache_track). Stored warming (sim/warming.h) restores
	 * only the sets of the on-board cache that a region or the checkpoints
	 * between changed: copying all of it took longer than the region */
	uint64_t *dirty;
	/* line data (cache_data_on; NULL: the cache holds tags only): per way
	 * 1 + the index of its line's bytes in a pool of chunks, 0 before the
	 * way first fills. The pool grows as ways fill, so a large cache of a
	 * small scene holds only the lines it was given */
	uint32_t *didx;
	uint8_t **dchunk;
	uint32_t dchunks, dcap, dused;
} cache;

#define CACHE_DCHUNK_BITS 10u /* lines per chunk of the data pool: 1024 */

#define CACHE_INVALID UINT64_MAX

/* cache_init's checks of p alone (nothing allocated): 0, or -1 with d
 * set ("config: WHAT: ..."). */
int cache_check(const cache_params *p, const char *what, diag *d);
/* Validates p (sizes >= 1, at least one set) and allocates. Errors name
 * `what` ("memory.l1.kd"). */
int cache_init(cache *c, const cache_params *p, const char *what, diag *d);
void cache_free(cache *c);
/* Empties every line and MSHR; keeps the counters. */
void cache_flush(cache *c);

/* Drops the lines holding any of bytes [addr, addr + n) (their data is
 * stale: the host wrote there between frames, issue 33); keeps the
 * counters. Returns how many were present. */
uint64_t cache_invalidate(cache *c, uint64_t addr, uint64_t n);

/* Gives the cache line data (docs/memory.md, "Data"): line_bytes per way,
 * beside the tags. -1 when out of memory. */
int cache_data_on(cache *c);
/* Host bytes of the data of a cache of p whose fills bring at most
 * `lines` distinct lines: the per-way index and the pool (each line can
 * land in any way of its set). */
uint64_t cache_data_host_bytes(const cache_params *p, uint64_t lines);
/* The bytes of the line in way `slot` (set * ways + way), given a pool
 * entry on its first fill; NULL when out of memory. Fillers write the
 * line here. */
uint8_t *cache_data(cache *c, uint32_t slot);
/* The same without allocating: NULL when the way never held a line. */
static inline uint8_t *cache_data_at(const cache *c, uint32_t slot)
{
	uint32_t i = c->didx[slot];
	if (!i--)
		return NULL;
	return c->dchunk[i >> CACHE_DCHUNK_BITS] +
	       (size_t)(i & ((1u << CACHE_DCHUNK_BITS) - 1)) * c->p.line_bytes;
}

/* Tracks the sets that change from now on (cache.dirty). -1 when out of
 * memory. */
int cache_track(cache *c);
static inline void cache_touch(cache *c, uint32_t set)
{
	if (c->dirty)
		bits_set(c->dirty, (int)set);
}
/* The policy's hit hook for way w of set (out of line: rare policies). */
void cache_repl_hit(cache *c, uint32_t set, uint32_t w);
/* Way w of set `set` is hit now: the policy sees it (LRU: the most recent
 * in LRU order, inline), and the set changed (every policy update goes
 * through here or cache_fill, so tracking sees it). */
static inline void cache_use(cache *c, uint32_t set, cache_way *w)
{
	if (c->stamp_hit)
		w->use = ++c->stamp;
	else if (c->rp->hit)
		cache_repl_hit(c, set, (uint32_t)(w - c->way - (size_t)set * c->p.ways));
	cache_touch(c, set);
}
void cache_dirty_clear(cache *c);

/* The state of sets [set0, set0 + n) in compact form, ways in order:
 * each way's line (UINT32_MAX when empty) and `ways` bytes per set of the
 * policy's state (its save hook; LRU: each way's rank in its set, 0 =
 * least recent), all its decisions need. -1 when a line index is
 * UINT32_MAX or more (nothing stored beyond it). */
int cache_save(const cache *c, uint32_t set0, uint32_t n, uint32_t *line, uint8_t *st);
/* Sets [set0, set0 + n) from cache_save's form (their MSHRs must be
 * free); hits and fills after it see the same policy decisions. */
void cache_load(cache *c, uint32_t set0, uint32_t n, const uint32_t *line, const uint8_t *st);

/* The cache's own checkpoint form of n sets (stored warming saves and
 * restores caches through it, never through their fields): the
 * cache_save form, lines then policy bytes, each part padded to 8 bytes.
 * cache_ckpt_bytes: its size; cache_ckpt_empty: the form of n empty sets;
 * save: -1 as cache_save; load: -1 (nothing changed) while a miss is in
 * flight (an MSHR is busy). */
size_t cache_ckpt_bytes(const cache *c, uint32_t n);
void cache_ckpt_empty(const cache *c, uint32_t n, void *buf);
int cache_ckpt_save(const cache *c, uint32_t set0, uint32_t n, void *buf);
int cache_ckpt_load(cache *c, uint32_t set0, uint32_t n, const void *buf);

static inline uint64_t cache_line_of(const cache *c, uint64_t addr)
{
	return c->line_shift >= 0 ? addr >> c->line_shift : fastdiv_div(c->line_div, addr);
}
uint32_t cache_set_fold(const cache *c, uint64_t line);
/* The set a line maps to (inline: every lookup starts here). */
static inline uint32_t cache_set_of(const cache *c, uint64_t line)
{
	if (c->p.hash == CACHE_HASH_NONE && c->set_mask)
		return (uint32_t)(line & c->set_mask);
	return cache_set_fold(c, line);
}

/* Is the line present (no policy or counter change)? */
int cache_probe(const cache *c, uint64_t line, uint32_t *slot);
/* The line's data arrived: frees its MSHR (if it had one), installs it in
 * an empty way (the lowest) or the policy's victim and returns its slot;
 * *victim receives the evicted line or CACHE_INVALID. Filling a present
 * line is a hit for the policy. */
uint32_t cache_fill(cache *c, uint64_t line, uint64_t *victim);
/* The chain of busy MSHRs (cache.mshr_head) a line's MSHR is in. */
static inline uint32_t cache_mshr_bucket(uint64_t line)
{
	return (uint32_t)((line ^ (line >> 6)) & (CACHE_MSHR_BUCKETS - 1));
}
/* The in-flight MSHR holding line, or -1 (inline: every timed lookup that
 * misses and every fill searches). */
static inline int cache_mshr_find(const cache *c, uint64_t line)
{
	for (uint32_t i = c->mshr_head[cache_mshr_bucket(line)]; i != CACHE_MSHR_NIL;
	     i = c->mshr_next[i])
		if (c->mshr_line[i] == line)
			return (int)i;
	return -1;
}

/* The way of set holding line, or -1. Four ways (every L1 of the
 * standard configs) are tested without a loop, and it is always inlined
 * (gcc had kept it a call): the search runs for every lookup and fill. */
static inline __attribute__((always_inline)) int cache_find_way(const cache *c, uint32_t set,
                                                                uint64_t line)
{
	const cache_way *s = c->way + (size_t)set * c->p.ways;
	if (c->p.ways == 4)
		return s[0].tag == line   ? 0
		       : s[1].tag == line ? 1
		       : s[2].tag == line ? 2
		       : s[3].tag == line ? 3
		                          : -1;
	for (uint32_t w = 0; w < c->p.ways; w++)
		if (s[w].tag == line)
			return (int)w;
	return -1;
}

/* Brings the set line maps to (its ways and, with data, their indices)
 * into the host's cache: a hint, nothing changes. */
static inline void cache_prefetch_set(const cache *c, uint64_t line)
{
	size_t s = (size_t)cache_set_of(c, line) * c->p.ways;
	__builtin_prefetch(c->way + s);
	if (c->didx)
		__builtin_prefetch(c->didx + s);
}

/* Takes the lowest free MSHR for line (one is free). */
static inline uint32_t cache_mshr_take(cache *c, uint64_t line)
{
	uint32_t w = 0;
	while (!c->mshr_free[w])
		w++;
	uint32_t i = w * 64 + (uint32_t)__builtin_ctzll(c->mshr_free[w]);
	c->mshr_free[w] &= c->mshr_free[w] - 1;
	c->mshr_line[i] = line;
	c->mshr_used++;
	uint32_t b = cache_mshr_bucket(line);
	c->mshr_next[i] = c->mshr_head[b];
	c->mshr_head[b] = i;
	return i;
}

/* One access to one line (an access spanning two lines is two lookups).
 * bytes is only counted. *mshr receives the MSHR index for MISS_NEW and
 * MISS_MERGED, *slot (set*ways+way) for HIT; either may be NULL. Inline,
 * with the way search and the MSHR take: every timed L1 line lookup runs
 * it. */
static inline cache_result cache_lookup(cache *c, uint64_t line, uint32_t bytes, int *mshr,
                                        uint32_t *slot)
{
	uint32_t set = cache_set_of(c, line);
	int w = cache_find_way(c, set, line);
	if (w >= 0) {
		size_t i = (size_t)set * c->p.ways + (size_t)w;
		cache_use(c, set, &c->way[i]);
		c->s.accesses++;
		c->s.hits++;
		c->s.bytes += bytes;
		if (slot)
			*slot = (uint32_t)i;
		return CACHE_HIT;
	}
	int m = cache_mshr_find(c, line);
	if (m >= 0) {
		c->s.accesses++;
		c->s.misses++;
		c->s.merges++;
		c->s.bytes += bytes;
		if (mshr)
			*mshr = m;
		return CACHE_MISS_MERGED;
	}
	if (c->mshr_used == c->p.mshrs) {
		c->s.mshr_full++;
		return CACHE_MSHR_FULL;
	}
	uint32_t i = cache_mshr_take(c, line);
	c->s.accesses++;
	c->s.misses++;
	c->s.bytes += bytes;
	if (mshr)
		*mshr = (int)i;
	return CACHE_MISS_NEW;
}

/* A set as the replacement policy sees it (mem/repl.h). */
static inline repl_set cache_set_view(const cache *c, uint32_t set)
{
	uint32_t W = c->p.ways;
	return (repl_set){c->way + (size_t)set * W,
	                  c->rst ? c->rst + (size_t)set * c->rp->set_words : NULL, W,
	                  (uint64_t *)&c->stamp};
}

/* Frees MSHR m (busy, holding line). */
static inline void cache_mshr_release(cache *c, uint64_t line, uint32_t m)
{
	uint32_t *p = &c->mshr_head[cache_mshr_bucket(line)];
	while (*p != m && *p != CACHE_MSHR_NIL)
		p = &c->mshr_next[*p];
	if (*p == m)
		*p = c->mshr_next[m];
	c->mshr_line[m] = CACHE_INVALID;
	c->mshr_used--;
	c->mshr_free[m / 64] |= 1ull << (m % 64);
}

/* The way a fill of set (ways s) takes: an empty way first (the lowest),
 * else the policy's victim (stamp policies: the smallest stamp). */
static inline __attribute__((always_inline)) uint32_t
cache_pick_victim(const cache *c, uint32_t set, const cache_way *s)
{
	uint32_t best = 0;
	if (!c->rp->victim && c->p.ways == 4) {
		/* unrolled (see cache_find_way): the first empty way, else the
		 * smallest stamp, the lowest way on ties */
		for (uint32_t i = 0; i < 4; i++)
			if (s[i].tag == CACHE_INVALID)
				return i;
		uint32_t b01 = s[1].use < s[0].use, b23 = 2 + (s[3].use < s[2].use);
		/* the last choice by a mask, not a branch: which pair holds
		 * the least recent way is as good as random to the host */
		uint32_t lo23 = (uint32_t)0 - (uint32_t)(s[b23].use < s[b01].use);
		return (b23 & lo23) | (b01 & ~lo23);
	}
	if (!c->rp->victim) {
		for (uint32_t i = 0; i < c->p.ways; i++) {
			if (s[i].tag == CACHE_INVALID)
				return i;
			if (s[i].use < s[best].use)
				best = i;
		}
		return best;
	}
	for (uint32_t i = 0; i < c->p.ways; i++)
		if (s[i].tag == CACHE_INVALID)
			return i;
	repl_set v = cache_set_view(c, set);
	return c->rp->victim(&v);
}

/* Installs line (absent, in no MSHR) in set: an empty way (the lowest)
 * or the policy's victim; returns its slot. Always inlined, with
 * pick_victim: gcc had kept it a call from every fill. */
static inline __attribute__((always_inline)) uint32_t
cache_fill_absent(cache *c, uint32_t set, uint64_t line, uint64_t *victim)
{
	size_t base = (size_t)set * c->p.ways;
	cache_way *s = c->way + base;
	uint32_t best = cache_pick_victim(c, set, s);
	if (s[best].tag != CACHE_INVALID) {
		c->s.evictions++;
		if (victim)
			*victim = s[best].tag;
	}
	s[best].tag = line;
	c->s.fills++;
	c->s.fill_bytes += c->p.line_bytes;
	if (c->stamp_fill)
		s[best].use = ++c->stamp;
	else if (c->rp->fill) {
		repl_set v = cache_set_view(c, set);
		c->rp->fill(&v, best);
	}
	cache_touch(c, set);
	return (uint32_t)(base + best);
}

/* cache_fill with the line's MSHR already known (cache_mshr_find's
 * answer, -1: none): what a timed fill that has just taken the MSHR's
 * waiters (tcache_take) calls, so the MSHRs are searched once per fill.
 * Inline, with the victim pick: every timed L1 fill runs it. */
static inline uint32_t cache_fill_mshr(cache *c, uint64_t line, int m, uint64_t *victim)
{
	if (m >= 0)
		cache_mshr_release(c, line, (uint32_t)m);
	if (victim)
		*victim = CACHE_INVALID;
	uint32_t set = cache_set_of(c, line);
	int w = cache_find_way(c, set, line);
	if (w >= 0) { /* present: a hit for the policy */
		size_t i = (size_t)set * c->p.ways + (size_t)w;
		cache_use(c, set, &c->way[i]);
		return (uint32_t)i;
	}
	return cache_fill_absent(c, set, line, victim);
}

static inline int cache_mshr_free(const cache *c)
{
	return c->mshr_used < c->p.mshrs;
}
/* Is a miss in flight (an MSHR busy)? */
static inline int cache_busy(const cache *c)
{
	return c->mshr_used > 0;
}

/* The hit half of cache_lookup, inline, for functional fast paths (replay):
 * if line is present it does exactly what cache_lookup does on a hit
 * (policy update, counters) and returns 1; otherwise it changes nothing and returns
 * 0, and the caller goes on with cache_lookup (and cache_fill). */
static inline int cache_try_hit(cache *c, uint64_t line, uint32_t bytes)
{
	uint32_t ways = c->p.ways;
	uint32_t set = cache_set_of(c, line);
	cache_way *s = c->way + (size_t)set * ways;
	for (uint32_t w = 0; w < ways; w++)
		if (s[w].tag == line) {
			cache_use(c, set, &s[w]);
			c->s.accesses++;
			c->s.hits++;
			c->s.bytes += bytes;
			return 1;
		}
	return 0;
}

/* Functional lookup of one line (no time): a hit, or a line already in
 * flight in an MSHR (counted as a merged miss; its fill is on its way), is 1;
 * otherwise the miss is counted and the line filled at once without an
 * MSHR, and the result is 0. Safe while timed misses are in flight. */
int cache_lookup_func(cache *c, uint64_t line, uint32_t bytes);
/* The same, telling where the line is: *slot its way when it is present
 * after the call (a hit, or the way the miss filled; CACHE_NO_SLOT when
 * only in flight in an MSHR), *victim the line the fill evicted
 * (CACHE_INVALID if none). */
int cache_lookup_func_at(cache *c, uint64_t line, uint32_t bytes, uint32_t *slot, uint64_t *victim);
#define CACHE_NO_SLOT UINT32_MAX
/* Functional access with an immediate fill (no time): what replay and the
 * reference tests use. Touches every line of [addr, addr+bytes); returns the
 * number of lines that missed (0 = hit). Never returns MSHR_FULL. */
uint32_t cache_access(cache *c, uint64_t addr, uint32_t bytes);

/* Between counter snapshots from (NULL: the start) and to: the share of
 * merges among the timed lookups that found their line present or
 * arriving (hits + merges, functional ones left out); 0 without any. A
 * functional lookup finds its line at once, so a timed cache would have
 * merged about this share of its hits into fills still in flight. */
double cache_timed_merge_share(const cache_stats *from, const cache_stats *to);

/* The hits between the snapshots as a timed cache would count them: the
 * timed lookups' own, and the functional hits less that share (*share,
 * may be NULL, gets it). sampled mode's hit rates (sim/report.c). */
double cache_timed_hits(const cache_stats *from, const cache_stats *to, double *share);

#endif
