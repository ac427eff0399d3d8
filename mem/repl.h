/*
 * repl.h: cache replacement policies behind one small interface, chosen by
 * name from a registry.
 *
 * A policy decides which way of a full set a fill evicts (mem/cache.h
 * fills empty ways first, lowest index first, whatever the policy: the
 * valid bits of real tag arrays). It sees the hits and fills of each set
 * and keeps its own state: per-way stamps in the cache's way array and/or
 * set_words 64-bit words per set. Built in:
 *
 *   lru   exact least recently used (a use stamp per way; the default,
 *         what the L1s, the tag cache and the on-board cache always had)
 *   plru  tree pseudo-LRU (ways - 1 bits per set, a power of two ways:
 *         each node points to the half that was used less recently; the
 *         usual hardware approximation of LRU)
 *   fifo  first in, first out (a fill stamp per way; hits change nothing)
 *
 * Speed: lru and fifo are pure stamp policies (stamp_hit, stamp_fill, no
 * hooks), which cache.c updates inline; only policies with hooks pay for
 * an indirect call.
 *
 * Checkpoints (stored warming): a set's policy state is saved as `ways`
 * bytes (lru and fifo: each way's rank in stamp order, 0 = oldest; plru:
 * byte i = tree node i's bit), which load turns back into the same
 * decisions.
 *
 * More policies: fill a repl_policy and repl_register it before the cache
 * is built (docs/extending.md); the config keys
 * memory.l1.<type>.replacement, memory.vma.replacement and
 * memory.vma.tag_cache_replacement name it.
 */
#ifndef SAAR_MEM_REPL_H
#define SAAR_MEM_REPL_H

#include <stddef.h>
#include <stdint.h>

/* One way of a cache: its line and a 64-bit word of replacement state
 * side by side, so a 4-way set is one 64-byte host cache line. */
typedef struct cache_way {
	uint64_t tag; /* line index; CACHE_INVALID when empty */
	uint64_t use; /* stamp policies: the stamp (larger = newer); free for others */
} cache_way;

/* What a policy hook sees of one set. */
typedef struct repl_set {
	cache_way *way;  /* the set's ways */
	uint64_t *st;    /* the set's set_words words of policy state */
	uint32_t ways;   /* associativity */
	uint64_t *stamp; /* the cache's stamp counter (++*stamp: a new stamp) */
} repl_set;

typedef struct repl_policy {
	const char *name; /* the config value that selects it */
	const char *desc; /* one line for errors and docs */
	/* pure stamp behaviour kept inline by cache.c: a hit (stamp_hit)
	 * and/or a fill (stamp_fill) gives the way a new stamp; with victim
	 * NULL the victim is the way with the smallest stamp (lowest index
	 * on ties) */
	uint8_t stamp_hit, stamp_fill;
	uint32_t set_words; /* 64-bit words of per-set state (0: none) */
	/* 0 when the policy can manage `ways` ways (NULL: any) */
	int (*check)(uint32_t ways);
	/* way w of a set was hit (hit) or filled (fill); NULL: the stamp
	 * rules above or nothing */
	void (*hit)(repl_set *s, uint32_t w);
	void (*fill)(repl_set *s, uint32_t w);
	/* the way a fill of the full set s evicts; NULL: smallest stamp */
	uint32_t (*victim)(const repl_set *s);
	/* the set's state as s->ways bytes, and back; NULL: stamp ranks */
	void (*save)(const repl_set *s, uint8_t *out);
	void (*load)(repl_set *s, const uint8_t *in);
} repl_policy;

extern const repl_policy repl_lru, repl_plru, repl_fifo;

/* The policy registered under name (built-ins first); NULL if none. */
const repl_policy *repl_find(const char *name);
/* Adds p to the registry (p must outlive every cache using it). -1 when
 * its name is taken, empty or the table (16 extra policies) is full. */
int repl_register(const repl_policy *p);
/* The registered names, comma separated, into buf (for error messages). */
const char *repl_names(char *buf, size_t n);

/* The stamp-rank form used when save/load are NULL: out[i] = the number
 * of ways with a smaller stamp than way i; load gives way i stamp in[i]
 * and keeps *stamp beyond every restored stamp. */
void repl_stamp_save(const repl_set *s, uint8_t *out);
void repl_stamp_load(repl_set *s, const uint8_t *in);

#endif
