/*
 * test_cache.c: mem/cache against a brute-force LRU reference, access for
 * access, on random traces and on a synthetic kd-tree walk (8-byte nodes,
 * depth-first layout, coherent rays), with power-of-two and 36-byte lines;
 * MSHR merging and refusal; functional lookups beside timed misses.
 */
#include <stdlib.h>
#include <string.h>

#include "mem/cache.h"
#include "tests/testutil.h"

/* The reference: per set, a plain array of lines in MRU-first order. */
typedef struct ref {
	uint32_t nsets, ways, line;
	uint64_t *l; /* nsets*ways, CACHE_INVALID = empty */
} ref;

static void ref_init(ref *r, uint64_t size, uint32_t ways, uint32_t line)
{
	r->nsets = (uint32_t)(size / ((uint64_t)ways * line));
	r->ways = ways;
	r->line = line;
	r->l = malloc((size_t)r->nsets * ways * sizeof *r->l);
	for (size_t i = 0; i < (size_t)r->nsets * ways; i++)
		r->l[i] = CACHE_INVALID;
}

/* 1 = hit. Moves the line to the front, evicting the last on a miss. */
static int ref_touch(ref *r, uint64_t line)
{
	uint64_t *s = r->l + (size_t)(line % r->nsets) * r->ways;
	uint32_t i = 0;
	while (i < r->ways && s[i] != line)
		i++;
	int hit = i < r->ways;
	if (!hit)
		i = r->ways - 1;
	memmove(s + 1, s, i * sizeof *s);
	s[0] = line;
	return hit;
}

static uint64_t rng = 88172645463325252ull;
static uint64_t xr(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return rng;
}

/* Runs addrs through cache and reference, line by line. */
static void compare(const uint64_t *addr, const uint32_t *bytes, size_t n, uint64_t size,
                    uint32_t ways, uint32_t line)
{
	cache c;
	diag d;
	cache_params p = {size, ways, line, 4, 1, 1, CACHE_HASH_NONE, NULL};
	cr_assert_eq(cache_init(&c, &p, "test", &d), 0, "%s", d.msg);
	ref r;
	ref_init(&r, size, ways, line);
	cr_assert_eq(c.nsets, r.nsets);
	uint64_t lines = 0, hits = 0;
	for (size_t i = 0; i < n; i++) {
		uint64_t first = addr[i] / line, last = (addr[i] + bytes[i] - 1) / line;
		for (uint64_t l = first; l <= last; l++) {
			int want = ref_touch(&r, l);
			cache_result got = cache_lookup(&c, l, 1, NULL, NULL);
			cr_assert_eq(got == CACHE_HIT, want,
			             "access %zu line %llu: cache %d, ref %d", i,
			             (unsigned long long)l, got, want);
			if (got != CACHE_HIT) {
				cr_assert_eq(got, CACHE_MISS_NEW);
				cache_fill(&c, l, NULL);
			}
			lines++;
			hits += want;
		}
	}
	cr_assert_eq(c.s.accesses, lines);
	cr_assert_eq(c.s.hits, hits);
	cr_assert_eq(c.s.hits + c.s.misses, c.s.accesses);
	cr_assert_eq(c.s.fill_bytes, (uint64_t)c.s.misses * line);
	cr_assert(hits > 0 && hits < lines, "trace should mix hits and misses");
	cache_free(&c);
	free(r.l);
}

static void random_trace(uint64_t size, uint32_t ways, uint32_t line, uint64_t span)
{
	enum { N = 200000 };
	uint64_t *a = malloc(N * sizeof *a);
	uint32_t *b = malloc(N * sizeof *b);
	for (size_t i = 0; i < N; i++) {
		/* a hot region and a cold one, sizes 1..2 lines: some accesses span two */
		uint64_t x = xr();
		a[i] = (x & 3) ? x % (span / 8) : (x >> 8) % span;
		b[i] = 1 + (uint32_t)((x >> 40) % (2 * line));
	}
	compare(a, b, N, size, ways, line);
	free(a);
	free(b);
}

Test(cache, random_pow2_lines)
{
	random_trace(64 << 10, 4, 8, 1 << 20);
	random_trace(4 << 10, 2, 64, 1 << 18);
	random_trace(1 << 10, 1, 16, 1 << 14); /* direct-mapped */
}

Test(cache, random_36_byte_lines)
{
	/* 144 KB / (4 x 36) = 1024 sets: the standard triangle cache */
	random_trace(144 << 10, 4, 36, 4 << 20);
	/* and a set count that is not a power of two (3 KB / (4 x 36) = 21) */
	random_trace(3 << 10, 4, 36, 1 << 16);
}

/* A kd-tree walk: nodes numbered depth first (left child = i + 1, right
 * child after the left subtree), 8 bytes each; coherent rays share most of
 * their path, and each leaf reads a few 36-byte triangles. */
Test(cache, kd_walk_trace)
{
	enum { DEPTH = 18, RAYS = 40000 };
	size_t cap = (size_t)RAYS * (DEPTH + 4), n = 0;
	uint64_t *a = malloc(cap * sizeof *a);
	uint32_t *b = malloc(cap * sizeof *b);
	uint64_t tri_base = ((uint64_t)8 << DEPTH << 1) + 128;
	uint64_t path = 0;
	for (int ray = 0; ray < RAYS; ray++) {
		/* neighbouring rays differ in the low bits of their path */
		if (ray % 64 == 0)
			path = xr();
		uint64_t p = path ^ (xr() & 0x7);
		uint64_t node = 0, sub = ((uint64_t)1 << (DEPTH + 1)) - 1;
		for (int d = 0; d < DEPTH; d++) {
			a[n] = node * 8;
			b[n++] = 8;
			sub = (sub - 1) / 2;
			node += (p >> (DEPTH - 1 - d)) & 1 ? 1 + sub : 1;
		}
		for (int k = 0; k < 3; k++) {
			a[n] = tri_base + ((node * 3 + (uint64_t)k) % 200000) * 36;
			b[n++] = 36;
		}
	}
	/* nodes and triangles through one cache each, as on the chip */
	size_t nn = 0, nt = 0;
	uint64_t *an = malloc(n * sizeof *an), *at = malloc(n * sizeof *at);
	uint32_t *bn = malloc(n * sizeof *bn), *bt = malloc(n * sizeof *bt);
	for (size_t i = 0; i < n; i++) {
		if (b[i] == 8) {
			an[nn] = a[i];
			bn[nn++] = 8;
		} else {
			at[nt] = a[i];
			bt[nt++] = 36;
		}
	}
	compare(an, bn, nn, 64 << 10, 4, 8);
	compare(at, bt, nt, 144 << 10, 4, 36);
	free(a), free(b), free(an), free(bn), free(at), free(bt);
}

Test(cache, line_index_and_sets)
{
	cache c;
	diag d;
	cache_params p = {144 << 10, 4, 36, 2, 1, 1, CACHE_HASH_NONE, NULL};
	cr_assert_eq(cache_init(&c, &p, "tri", &d), 0);
	cr_assert_eq(c.nsets, 1024);
	cr_assert_eq(cache_line_of(&c, 35), 0);
	cr_assert_eq(cache_line_of(&c, 36), 1);
	cr_assert_eq(cache_set_of(&c, 1025), 1);
	/* an access of 36 bytes at 18 spans lines 0 and 1 */
	cr_assert_eq(cache_access(&c, 18, 36), 2);
	cr_assert_eq(cache_access(&c, 0, 72), 0);
	cr_assert_eq(c.s.accesses, 4);
	cr_assert_eq(c.s.hits, 2);
	cache_free(&c);
}

Test(cache, mshr_merge_and_full)
{
	cache c;
	diag d;
	cache_params p = {1024, 2, 16, 2, 1, 1, CACHE_HASH_NONE, NULL};
	cr_assert_eq(cache_init(&c, &p, "t", &d), 0);
	int m1 = -1, m2 = -1, m3 = -1;
	cr_assert_eq(cache_lookup(&c, 5, 16, &m1, NULL), CACHE_MISS_NEW);
	cr_assert_eq(cache_lookup(&c, 5, 16, &m2, NULL), CACHE_MISS_MERGED);
	cr_assert_eq(m1, m2);
	cr_assert_eq(cache_lookup(&c, 9, 16, &m3, NULL), CACHE_MISS_NEW);
	cr_assert_neq(m3, m1);
	/* both MSHRs busy: a third line is refused and nothing changes */
	cr_assert_eq(cache_lookup(&c, 11, 16, NULL, NULL), CACHE_MSHR_FULL);
	cr_assert_eq(c.s.accesses, 3);
	cr_assert_eq(c.s.mshr_full, 1);
	/* but a merge still works while full */
	cr_assert_eq(cache_lookup(&c, 9, 16, NULL, NULL), CACHE_MISS_MERGED);
	cache_fill(&c, 5, NULL);
	cr_assert_eq(cache_mshr_find(&c, 5), -1);
	cr_assert_eq(cache_lookup(&c, 5, 16, NULL, NULL), CACHE_HIT);
	cr_assert_eq(cache_lookup(&c, 11, 16, NULL, NULL), CACHE_MISS_NEW);
	cr_assert_eq(c.s.merges, 2);
	cr_assert_eq(c.s.hits + c.s.misses, c.s.accesses);
	cache_free(&c);
}

/* The MSHRs against a plain scan of their lines (how cache.c found them
 * before the bucket chains and the free bitmask): random misses and fills
 * in random order over 100 MSHRs (two bitmask words), on few lines so
 * that merges, refusals and bucket collisions are frequent. Every lookup
 * must give the same result and MSHR index as the scan: a new miss the
 * lowest free MSHR. Fails when a release leaves the MSHR's free bit clear
 * (refused or a higher index too early), leaves it in its bucket's chain
 * (a merge into a freed MSHR), a miss takes another free MSHR than the
 * lowest, or the bitmask's second word is not searched. */
Test(cache, mshrs_as_a_plain_scan)
{
	enum { NM = 100 };
	cache c;
	diag d;
	cache_params p = {1 << 20, 4, 8, NM, 1, 1, CACHE_HASH_NONE, NULL};
	cr_assert_eq(cache_init(&c, &p, "t", &d), 0);
	uint64_t scan[NM];
	for (int i = 0; i < NM; i++)
		scan[i] = CACHE_INVALID;
	int busy = 0, news = 0, merges = 0, fulls = 0;
	for (int step = 0; step < 200000; step++) {
		/* phases of mostly misses (the MSHRs fill up) and of mostly
		 * fills */
		if (busy && xr() % 100 < (step / 3000 % 2 ? 70u : 15u)) {
			int k = (int)(xr() % NM);
			while (scan[k] == CACHE_INVALID)
				k = (k + 1) % NM;
			cache_fill_mshr(&c, scan[k], k, NULL);
			scan[k] = CACHE_INVALID;
			busy--;
			continue;
		}
		/* lines 64 apart share a bucket; flush now and then so that
		 * lines miss again */
		uint64_t line = (xr() % 160) * (xr() % 2 ? 64 : 1);
		if (step % 5000 == 0)
			cache_invalidate(&c, 0, 160 * 64 * 8);
		int m = -1;
		if (cache_probe(&c, line, NULL)) {
			cr_assert_eq(cache_lookup(&c, line, 8, &m, NULL), CACHE_HIT);
			continue;
		}
		int want = -1, lowest = -1;
		for (int i = NM - 1; i >= 0; i--) {
			if (scan[i] == line)
				want = i;
			if (scan[i] == CACHE_INVALID)
				lowest = i;
		}
		cache_result r = cache_lookup(&c, line, 8, &m, NULL);
		if (want >= 0) {
			cr_assert_eq(r, CACHE_MISS_MERGED, "step %d: line %llu in MSHR %d", step,
			             (unsigned long long)line, want);
			cr_assert_eq(m, want, "step %d", step);
			merges++;
		} else if (lowest < 0) {
			cr_assert_eq(r, CACHE_MSHR_FULL, "step %d", step);
			fulls++;
		} else {
			cr_assert_eq(r, CACHE_MISS_NEW, "step %d: line %llu", step,
			             (unsigned long long)line);
			cr_assert_eq(m, lowest, "step %d: the lowest free MSHR", step);
			scan[m] = line;
			busy++;
			news++;
		}
		cr_assert_eq(c.mshr_used, (uint32_t)busy);
	}
	cr_assert_gt(news, 1000);
	cr_assert_gt(merges, 1000);
	cr_assert_gt(fulls, 100);
	cr_log_info("%d new, %d merged, %d refused", news, merges, fulls);
	cache_free(&c);
}

/* Functional lookups while timed misses are in flight (a sampled region
 * handing its packets to a functional stretch): a line in an MSHR is on
 * its way (a merge, no fill), a missing one is filled at once without
 * taking an MSHR, even when every MSHR is busy; the timed fill that
 * arrives later finds its MSHR and its line. */
Test(cache, functional_lookup_beside_timed_misses)
{
	cache c;
	diag d;
	cache_params p = {1024, 2, 16, 2, 1, 1, CACHE_HASH_NONE, NULL};
	cr_assert_eq(cache_init(&c, &p, "t", &d), 0);
	int m1 = -1, m2 = -1;
	cr_assert_eq(cache_lookup(&c, 5, 16, &m1, NULL), CACHE_MISS_NEW);
	cr_assert_eq(cache_lookup(&c, 9, 16, &m2, NULL), CACHE_MISS_NEW);
	cr_assert_eq(cache_lookup_func(&c, 5, 16), 1, "in flight: on its way");
	cr_assert_eq(cache_mshr_find(&c, 5), m1, "the MSHR stays with the timed miss");
	cr_assert_not(cache_probe(&c, 5, NULL), "no fill before the timed one");
	cr_assert_eq(cache_lookup_func(&c, 11, 16), 0, "absent: a miss");
	cr_assert(cache_probe(&c, 11, NULL), "filled at once");
	cr_assert_eq(cache_mshr_find(&c, 11), -1, "without an MSHR");
	cr_assert_eq(cache_lookup_func(&c, 11, 16), 1);
	cache_fill(&c, 5, NULL);
	cr_assert_eq(cache_mshr_find(&c, 5), -1);
	cr_assert(cache_probe(&c, 5, NULL));
	/* 2 timed misses, 2 functional misses (one merged), 1 functional hit */
	cr_assert_eq(c.s.accesses, 5);
	cr_assert_eq(c.s.misses, 4);
	cr_assert_eq(c.s.merges, 1);
	cr_assert_eq(c.s.hits, 1);
	cr_assert_eq(c.s.mshr_full, 0);
	cache_free(&c);
}

Test(cache, xor_hash_spreads_strides)
{
	cache c;
	diag d;
	cache_params p = {128 * 4 * 256, 4, 128, 1, 1, 1, CACHE_HASH_XOR, NULL};
	cr_assert_eq(cache_init(&c, &p, "l2", &d), 0);
	/* lines 256 apart all map to set 0 without hashing */
	int used[256] = {0}, distinct = 0;
	for (uint64_t i = 0; i < 64; i++) {
		uint32_t s = cache_set_of(&c, i * 256);
		if (!used[s]++)
			distinct++;
	}
	cr_assert_gt(distinct, 32);
	cache_free(&c);
}

Test(cache, bad_params)
{
	cache c;
	diag d;
	cache_params p = {64, 4, 36, 1, 1, 1, CACHE_HASH_NONE, NULL};
	cr_assert_neq(cache_init(&c, &p, "memory.l1.tri", &d), 0);
	cr_assert(strstr(d.msg, "memory.l1.tri"), "%s", d.msg);
}
