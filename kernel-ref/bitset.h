/*
 * bitset.h: sets of small integer ids as arrays of 64-bit words, for the
 * places that look up the next member without scanning every id: a
 * unit's round-robin waiters (units/thread.c), functional processing's
 * live thread slots (sim/chip.c func_range) and a cache's changed sets
 * (mem/cache.h, sim/warming.c).
 */
#ifndef SAAR_BITSET_H
#define SAAR_BITSET_H

#include <stdint.h>

/* Words holding n ids. */
static inline int bits_words(int n)
{
	return (n + 63) / 64;
}

static inline void bits_set(uint64_t *w, int i)
{
	w[i >> 6] |= 1ull << (i & 63);
}

static inline void bits_clear(uint64_t *w, int i)
{
	w[i >> 6] &= ~(1ull << (i & 63));
}

/* Members among ids 0..n-1. */
static inline int bits_count(const uint64_t *w, int n)
{
	int c = 0;
	for (int k = 0; k < bits_words(n); k++)
		c += __builtin_popcountll(w[k]);
	return c;
}

/* The first member at `from` or after it among ids 0..n-1; n when none.
 * Words are read as the search goes, so a member added ahead of a walk
 * during it is found. */
static inline int bits_next(const uint64_t *w, int n, int from)
{
	if (from >= n)
		return n;
	int k = from >> 6, nw = bits_words(n);
	uint64_t b = w[k] & (~0ull << (from & 63));
	while (!b) {
		if (++k >= nw)
			return n;
		b = w[k];
	}
	return (k << 6) + __builtin_ctzll(b);
}

#endif
