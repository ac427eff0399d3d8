/*
 * test_repl.c: the replacement policies (mem/repl.h) against brute-force
 * models access by access, their known victim sequences, their checkpoint
 * round trip, and the registry: a policy registered here by name and
 * selected through a config key decides the L1's evictions.
 */
#include <stdlib.h>
#include <string.h>

#include "mem/cache.h"
#include "mem/repl.h"
#include "sim/config.h"
#include "sim/memconfig.h"
#include "tests/testutil.h"

/* ---- the brute-force reference: one model per policy, written apart ---- */

enum { R_LRU, R_PLRU, R_FIFO };

typedef struct rset {
	uint64_t line[64];
	uint32_t order[64]; /* LRU and FIFO: way indices, oldest first */
	uint32_t n;         /* valid ways in order */
	uint8_t node[64];   /* PLRU: node k (1..ways-1): 1 = the victim is in the right half */
} rset;

typedef struct rcache {
	int kind;
	uint32_t nsets, ways;
	rset *s;
} rcache;

static void rc_init(rcache *r, int kind, uint32_t nsets, uint32_t ways)
{
	r->kind = kind;
	r->nsets = nsets;
	r->ways = ways;
	r->s = calloc(nsets, sizeof *r->s);
	for (uint32_t i = 0; i < nsets; i++)
		for (uint32_t w = 0; w < 64; w++)
			r->s[i].line[w] = CACHE_INVALID;
}

/* Moves way w to the newest end of the order list. */
static void order_newest(rset *s, uint32_t w)
{
	uint32_t i = 0;
	while (i < s->n && s->order[i] != w)
		i++;
	if (i == s->n)
		s->n++;
	else
		memmove(s->order + i, s->order + i + 1, (s->n - 1 - i) * sizeof *s->order);
	s->order[s->n - 1] = w;
}

/* The tree, by bisection of [lo, hi): every node on w's path points to
 * the other half. */
static void plru_ref_touch(rset *s, uint32_t ways, uint32_t w)
{
	uint32_t lo = 0, hi = ways, k = 1;
	while (hi - lo > 1) {
		uint32_t mid = (lo + hi) / 2;
		if (w < mid) {
			s->node[k] = 1;
			k = 2 * k;
			hi = mid;
		} else {
			s->node[k] = 0;
			k = 2 * k + 1;
			lo = mid;
		}
	}
}

static uint32_t plru_ref_victim(const rset *s, uint32_t ways)
{
	uint32_t lo = 0, hi = ways, k = 1;
	while (hi - lo > 1) {
		uint32_t mid = (lo + hi) / 2;
		if (s->node[k]) {
			k = 2 * k + 1;
			lo = mid;
		} else {
			k = 2 * k;
			hi = mid;
		}
	}
	return lo;
}

/* 1 on a hit; on a miss *victim gets the evicted line (CACHE_INVALID). */
static int rc_touch(rcache *r, uint64_t line, uint64_t *victim)
{
	rset *s = &r->s[line % r->nsets];
	*victim = CACHE_INVALID;
	for (uint32_t w = 0; w < r->ways; w++)
		if (s->line[w] == line) {
			if (r->kind == R_LRU)
				order_newest(s, w);
			if (r->kind == R_PLRU)
				plru_ref_touch(s, r->ways, w);
			return 1;
		}
	uint32_t w = 0;
	while (w < r->ways && s->line[w] != CACHE_INVALID)
		w++;
	if (w == r->ways) /* full: the policy's victim */
		w = r->kind == R_PLRU ? plru_ref_victim(s, r->ways) : s->order[0];
	*victim = s->line[w];
	s->line[w] = line;
	if (r->kind == R_PLRU)
		plru_ref_touch(s, r->ways, w);
	else
		order_newest(s, w);
	return 0;
}

static const repl_policy *pol_of(int kind)
{
	return kind == R_LRU ? &repl_lru : kind == R_PLRU ? &repl_plru : &repl_fifo;
}

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static uint64_t xr(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return rng;
}

static void cache_of(cache *c, const repl_policy *p, uint32_t nsets, uint32_t ways)
{
	diag d;
	cache_params cp = {(uint64_t)nsets * ways * 16, ways, 16, 4, 1, 1, CACHE_HASH_NONE, p};
	cr_assert_eq(cache_init(c, &cp, "test", &d), 0, "%s", d.msg);
	cr_assert_eq(c->nsets, nsets);
}

/* One access through the cache: 1 on a hit; the miss fills at once. */
static int touch(cache *c, uint64_t line, uint64_t *victim)
{
	*victim = CACHE_INVALID;
	cache_result got = cache_lookup(c, line, 1, NULL, NULL);
	if (got == CACHE_HIT)
		return 1;
	cr_assert_eq(got, CACHE_MISS_NEW);
	cache_fill(c, line, victim);
	return 0;
}

/* Catches any policy that decides differently from its plain model: a
 * PLRU bit flipped the wrong way, FIFO reordering on hits, a victim
 * chosen before the empty ways. */
static void compare_policy(int kind, uint32_t ways, uint32_t lines)
{
	uint32_t nsets = 8;
	cache c;
	cache_of(&c, pol_of(kind), nsets, ways);
	rcache r;
	rc_init(&r, kind, nsets, ways);
	uint64_t hits = 0;
	for (int i = 0; i < 50000; i++) {
		/* a skewed mix: a hot few lines and a wide tail */
		uint64_t line = xr() % 4 ? xr() % (nsets * ways) : xr() % (nsets * lines);
		uint64_t vg, vr;
		int want = rc_touch(&r, line, &vr), got = touch(&c, line, &vg);
		cr_assert_eq(got, want, "%s %u ways, access %d line %llu: cache %d, ref %d",
		             pol_of(kind)->name, ways, i, (unsigned long long)line, got, want);
		cr_assert_eq(vg, vr, "%s access %d: evicted %llu, ref %llu", pol_of(kind)->name, i,
		             (unsigned long long)vg, (unsigned long long)vr);
		hits += want;
	}
	cr_assert_gt(hits, 1000);
	cr_assert_lt(hits, 49000);
	cache_free(&c);
	free(r.s);
}

Test(repl, lru_matches_reference)
{
	for (uint32_t w = 1; w <= 8; w++)
		compare_policy(R_LRU, w, 3 * w);
}

Test(repl, plru_matches_reference)
{
	for (uint32_t w = 1; w <= 16; w *= 2)
		compare_policy(R_PLRU, w, 3 * w);
}

Test(repl, fifo_matches_reference)
{
	for (uint32_t w = 1; w <= 8; w++)
		compare_policy(R_FIFO, w, 3 * w);
}

/* The victim of fills A B C D, a hit on A, then E into one 4-way set. */
static uint64_t victim_after_hit(const repl_policy *p)
{
	cache c;
	cache_of(&c, p, 1, 4);
	uint64_t v;
	for (uint64_t l = 1; l <= 4; l++)
		touch(&c, l, &v);
	cr_assert_eq(touch(&c, 1, &v), 1);
	cr_assert_eq(touch(&c, 5, &v), 0);
	cache_free(&c);
	return v;
}

/* Known sequences, each telling the three policies apart: LRU evicts B
 * (least recent), FIFO evicts A (first in; the hit does not save it), tree
 * PLRU evicts C (the root points away from A's half, the right node away
 * from D). Catches FIFO updating on hits, PLRU degenerating into LRU or
 * pointing its bits towards the used way. */
Test(repl, known_victims)
{
	cr_assert_eq(victim_after_hit(&repl_lru), 2);
	cr_assert_eq(victim_after_hit(&repl_fifo), 1);
	cr_assert_eq(victim_after_hit(&repl_plru), 3);
}

/* PLRU on 8 ways filled 0..7 in order: every fill points each node on its
 * path away, so the victims of the next misses sweep the tree 0, 4, 2, 6,
 * 1, 5, 3, 7 (each miss steers away from the previous one). */
Test(repl, plru_victim_sequence)
{
	cache c;
	cache_of(&c, &repl_plru, 1, 8);
	uint64_t v;
	for (uint64_t l = 0; l < 8; l++)
		touch(&c, 100 + l, &v);
	static const uint64_t want[] = {0, 4, 2, 6, 1, 5, 3, 7};
	for (int i = 0; i < 8; i++) {
		cr_assert_eq(touch(&c, 200 + (uint64_t)i, &v), 0);
		cr_assert_eq(v, 100 + want[i], "miss %d evicted %llu", i, (unsigned long long)v);
	}
	cache_free(&c);
}

/* Save, load into a cache that did other work, go on: both decide alike.
 * Catches a policy whose state is not in the checkpoint (PLRU's tree bits
 * lost, FIFO's fill order taken for LRU order). */
static void round_trip(const repl_policy *p, uint32_t ways)
{
	uint32_t nsets = 16;
	cache a, b;
	cache_of(&a, p, nsets, ways);
	cache_of(&b, p, nsets, ways);
	uint64_t v, vb;
	for (int i = 0; i < 20000; i++) {
		touch(&a, xr() % (nsets * ways * 2), &v);
		touch(&b, xr() % (nsets * ways * 3), &v);
	}
	size_t n = (size_t)nsets * ways;
	uint32_t *line = malloc(n * sizeof *line);
	uint8_t *st = malloc(n);
	cr_assert_eq(cache_save(&a, 0, nsets, line, st), 0);
	cache_load(&b, 0, nsets, line, st);
	for (int i = 0; i < 20000; i++) {
		uint64_t l = xr() % (nsets * ways * 2);
		int ha = touch(&a, l, &v), hb = touch(&b, l, &vb);
		cr_assert_eq(ha, hb, "%s %u ways: access %d after the load", p->name, ways, i);
		cr_assert_eq(v, vb, "%s: access %d evicted %llu vs %llu", p->name, i,
		             (unsigned long long)v, (unsigned long long)vb);
	}
	free(line);
	free(st);
	cache_free(&a);
	cache_free(&b);
}

Test(repl, save_load_round_trip)
{
	round_trip(&repl_lru, 4);
	round_trip(&repl_lru, 3);
	round_trip(&repl_fifo, 4);
	round_trip(&repl_fifo, 5);
	round_trip(&repl_plru, 4);
	round_trip(&repl_plru, 8);
}

Test(repl, plru_refuses_odd_ways)
{
	cache c;
	diag d;
	cache_params cp = {3 * 16 * 4, 3, 16, 4, 1, 1, CACHE_HASH_NONE, &repl_plru};
	cr_assert_neq(cache_init(&c, &cp, "memory.l1.kd", &d), 0);
	cr_assert(strstr(d.msg, "memory.l1.kd") && strstr(d.msg, "plru"), "%s", d.msg);
}

/* ---- the registry ---- */

/* A test-only policy: always evicts way 0 (no state at all). */
static uint32_t evict0_victim(const repl_set *s)
{
	(void)s;
	return 0;
}
static const repl_policy evict0 = {
    .name = "test-evict0",
    .desc = "always way 0 (tests/test_repl.c)",
    .victim = evict0_victim,
};

static void register_evict0(void)
{
	if (!repl_find("test-evict0"))
		cr_assert_eq(repl_register(&evict0), 0);
	cr_assert_eq(repl_find("test-evict0"), &evict0);
}

Test(repl, registry_finds_and_refuses)
{
	cr_assert_eq(repl_find("lru"), &repl_lru);
	cr_assert_eq(repl_find("plru"), &repl_plru);
	cr_assert_eq(repl_find("fifo"), &repl_fifo);
	cr_assert_null(repl_find("nosuch"));
	register_evict0();
	cr_assert_eq(repl_register(&evict0), -1, "a name is registered once");
	repl_policy dup = repl_lru;
	cr_assert_eq(repl_register(&dup), -1, "built-in names are taken");
	char names[256];
	cr_assert(strstr(repl_names(names, sizeof names), "test-evict0"), "%s", names);
}

/* The kd L1's hits on R rounds of 5 lines of one set, read functionally,
 * with memory.l1.kd.replacement set to name. */
static uint64_t kd_hits_cyclic(const char *name, int rounds)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	char set[96];
	snprintf(set, sizeof set, "memory.l1.kd.replacement=%s", name);
	cr_assert_eq(cfg_set(&cfg, set, &d), 0, "%s", d.msg);
	eng *e = eng_create(16);
	memport mp;
	cr_assert_eq(mem_init_hier(&mp, e, eng_clock_mhz(533), &cfg, 4 << 20, NULL, &d), 0, "%s",
	             d.msg);
	cache_params kp = hier_l1_params(&cfg, MEM_KD);
	uint64_t nsets = kp.size_bytes / ((uint64_t)kp.ways * kp.line_bytes);
	for (int r = 0; r < rounds; r++)
		for (uint64_t k = 0; k < 5; k++) {
			mem_req q = {k * nsets * kp.line_bytes, 8, MEM_KD, 0, 0, NULL, 0};
			mem_access_func(&mp, &q);
		}
	hier_stats s;
	cr_assert_eq(hier_get_stats(&mp, &s), 0);
	mem_free(&mp);
	eng_destroy(e);
	return s.l1[MEM_KD].hits;
}

/* Five lines cycled through a 4-way set: LRU misses every time, while a
 * policy that always evicts way 0 thrashes only that way and keeps the
 * other three (3 hits a round after the first). Catches the config key
 * not reaching the cache (the registry ignored, LRU used regardless). */
Test(repl, test_policy_selected_by_config_key)
{
	register_evict0();
	cr_assert_eq(kd_hits_cyclic("lru", 10), 0);
	cr_assert_eq(kd_hits_cyclic("test-evict0", 10), 3 * 9);
}

Test(repl, unknown_policy_name_is_an_error)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	cr_assert_eq(cfg_set(&cfg, "memory.vma.enabled=true", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&cfg, "memory.vma.tag_cache_replacement=nosuch", &d), 0, "%s", d.msg);
	eng *e = eng_create(16);
	memport mp;
	cr_assert_neq(mem_init_hier(&mp, e, eng_clock_mhz(533), &cfg, 4 << 20, NULL, &d), 0);
	cr_assert(strstr(d.msg, "memory.vma.tag_cache_replacement") && strstr(d.msg, "nosuch") &&
	              strstr(d.msg, "plru"),
	          "%s", d.msg);
	eng_destroy(e);
}

/* ---- the hierarchy saves and restores its caches itself ---- */

/* n functional reads of random kd and triangle addresses below 256 KB. */
static void random_reads(memport *mp, int n)
{
	for (int i = 0; i < n; i++) {
		int t = i % 2 ? MEM_KD : MEM_TRI;
		mem_req q = {xr() % (256 << 10), t == MEM_KD ? 8 : 36, (uint8_t)t, 0, 0, NULL, 0};
		mem_access_func(mp, &q);
	}
}

/* Two hierarchies with policy `name` in every L1: b does other work,
 * then loads a's checkpoint; the same reads after it hit alike. Catches a
 * level that leaves a cache or a policy's state out of its checkpoint. */
static void hier_round_trip(const char *name)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	static const char *const l1[] = {"shade", "kd", "list", "tri"};
	for (int t = 0; t < 4; t++) {
		char set[96];
		snprintf(set, sizeof set, "memory.l1.%s.replacement=%s", l1[t], name);
		cr_assert_eq(cfg_set(&cfg, set, &d), 0, "%s", d.msg);
	}
	eng *e = eng_create(16);
	memport a, b;
	cr_assert_eq(mem_init_hier(&a, e, eng_clock_mhz(533), &cfg, 4 << 20, NULL, &d), 0, "%s",
	             d.msg);
	cr_assert_eq(mem_init_hier(&b, e, eng_clock_mhz(533), &cfg, 4 << 20, NULL, &d), 0, "%s",
	             d.msg);
	random_reads(&a, 200000);
	random_reads(&b, 100000);
	size_t n = hier_ckpt_bytes(&a);
	cr_assert_eq(n, hier_ckpt_bytes(&b));
	cr_assert_gt(n, 0);
	void *buf = malloc(n);
	cr_assert_eq(hier_ckpt_save(&a, buf), 0);
	cr_assert_eq(hier_ckpt_load(&b, buf), 0);
	hier_stats sa0, sb0, sa, sb;
	hier_get_stats(&a, &sa0);
	hier_get_stats(&b, &sb0);
	uint64_t seed = rng;
	random_reads(&a, 100000);
	rng = seed;
	random_reads(&b, 100000);
	hier_get_stats(&a, &sa);
	hier_get_stats(&b, &sb);
	for (int t = 0; t < MEM_NTYPES; t++) {
		cr_assert_eq(sa.l1[t].hits - sa0.l1[t].hits, sb.l1[t].hits - sb0.l1[t].hits,
		             "%s: L1 %d hits differ after the load", name, t);
		cr_assert_eq(sa.l1[t].evictions - sa0.l1[t].evictions,
		             sb.l1[t].evictions - sb0.l1[t].evictions);
	}
	cr_assert_gt(sa.l1[MEM_KD].evictions - sa0.l1[MEM_KD].evictions, 0);
	free(buf);
	mem_free(&a);
	mem_free(&b);
	eng_destroy(e);
}

Test(repl, hierarchy_checkpoint_round_trip)
{
	hier_round_trip("lru");
	hier_round_trip("plru");
	hier_round_trip("fifo");
}

/* R rounds of 5 reads whose lines share one set of the on-board cache
 * (onboard) or one set of the tag cache (else), on a 1 MB board with a 1 KB
 * tag cache, every read past the L1s (image size 0); returns that cache's
 * hits, with key set to name. */
static uint64_t vma_hits_cyclic(const char *key, const char *name, int onboard, int rounds)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	static const char *const sets[] = {"memory.vma.enabled=true", "memory.sdram.mb=1",
	                                   "memory.vma.hash=none", "memory.vma.tag_cache_kb=1"};
	for (size_t i = 0; i < sizeof sets / sizeof *sets; i++)
		cr_assert_eq(cfg_set(&cfg, sets[i], &d), 0, "%s", d.msg);
	char set[96];
	snprintf(set, sizeof set, "%s=%s", key, name);
	cr_assert_eq(cfg_set(&cfg, set, &d), 0, "%s", d.msg);
	eng *e = eng_create(16);
	memport mp;
	cr_assert_eq(mem_init_hier(&mp, e, eng_clock_mhz(533), &cfg, 0, NULL, &d), 0, "%s", d.msg);
	cache *l2 = hier_onboard(&mp), *l1[MEM_NTYPES], *tag, *ob;
	hier_caches(&mp, l1, &tag, &ob);
	cr_assert(l2 && tag && l2 == ob);
	/* the on-board set of line l is l mod its sets; the tag cache's line
	 * is that set, its set the set mod the tag cache's sets */
	uint64_t stride = onboard ? l2->nsets : tag->nsets;
	for (int r = 0; r < rounds; r++)
		for (uint64_t k = 0; k < 5; k++) {
			mem_req q = {(onboard ? 3 * l2->nsets + k * stride : k * stride) * 128,
			             8,
			             MEM_KD,
			             0,
			             0,
			             NULL,
			             0};
			mem_access_func(&mp, &q);
		}
	hier_stats s;
	cr_assert_eq(hier_get_stats(&mp, &s), 0);
	mem_free(&mp);
	eng_destroy(e);
	return onboard ? s.l2.hits : s.tag_cache.hits;
}

/* The VMA's keys reach its caches: five lines cycled through one 4-way set
 * of the on-board cache (memory.vma.replacement) or of the tag cache
 * (memory.vma.tag_cache_replacement) miss every time under LRU and hit 3
 * times a round under the way-0 policy. Catches a key read into the wrong
 * cache or not at all. */
Test(repl, vma_keys_reach_their_caches)
{
	register_evict0();
	const char *ob = "memory.vma.replacement", *tg = "memory.vma.tag_cache_replacement";
	cr_assert_eq(vma_hits_cyclic(ob, "lru", 1, 8), 0);
	cr_assert_eq(vma_hits_cyclic(ob, "test-evict0", 1, 8), 3 * 7);
	cr_assert_eq(vma_hits_cyclic(tg, "lru", 0, 8), 0);
	cr_assert_eq(vma_hits_cyclic(tg, "test-evict0", 0, 8), 3 * 7);
}
