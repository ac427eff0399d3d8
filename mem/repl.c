/*
 * repl.c: the built-in replacement policies and the registry (see repl.h).
 */
#include "mem/repl.h"

#include <stdio.h>
#include <string.h>

/* ---- stamp ranks: lru and fifo's checkpoint form ---- */

void repl_stamp_save(const repl_set *s, uint8_t *out)
{
	/* rank: the ways stamped before it (ways <= 64 fit a byte) */
	for (uint32_t i = 0; i < s->ways; i++) {
		uint32_t r = 0;
		for (uint32_t j = 0; j < s->ways; j++)
			r += s->way[j].use < s->way[i].use;
		out[i] = (uint8_t)r;
	}
}

void repl_stamp_load(repl_set *s, const uint8_t *in)
{
	for (uint32_t i = 0; i < s->ways; i++)
		s->way[i].use = in[i];
	/* later stamps must be newer than every restored one */
	if (*s->stamp < s->ways)
		*s->stamp = s->ways;
}

/* ---- lru and fifo: stamps only (cache.c keeps them inline) ---- */

const repl_policy repl_lru = {
    .name = "lru",
    .desc = "least recently used (exact; a use stamp per way)",
    .stamp_hit = 1,
    .stamp_fill = 1,
};

const repl_policy repl_fifo = {
    .name = "fifo",
    .desc = "first in, first out (a fill stamp per way; hits change nothing)",
    .stamp_fill = 1,
};

/* ---- plru: a binary tree of ways - 1 bits per set ---- */

/* Node k (1 = root; children 2k, 2k+1; way w is leaf ways + w) is bit k
 * of the set's word: 0 = the victim lies in the left half, 1 = right. */

static int plru_check(uint32_t ways)
{
	return ways && !(ways & (ways - 1)) ? 0 : -1;
}

/* Every node on w's path points away from w. */
static void plru_touch(repl_set *s, uint32_t w)
{
	uint64_t st = s->st[0];
	for (uint32_t k = s->ways + w; k > 1; k >>= 1) {
		uint32_t parent = k >> 1;
		if (k & 1) /* w is in the right half: the victim goes left */
			st &= ~(1ull << parent);
		else
			st |= 1ull << parent;
	}
	s->st[0] = st;
}

static uint32_t plru_victim(const repl_set *s)
{
	uint32_t k = 1;
	while (k < s->ways)
		k = 2 * k + (uint32_t)(s->st[0] >> k & 1);
	return k - s->ways;
}

static void plru_save(const repl_set *s, uint8_t *out)
{
	for (uint32_t i = 0; i < s->ways; i++)
		out[i] = i + 1 < s->ways ? (uint8_t)(s->st[0] >> (i + 1) & 1) : 0;
}

static void plru_load(repl_set *s, const uint8_t *in)
{
	uint64_t st = 0;
	for (uint32_t i = 0; i + 1 < s->ways; i++)
		st |= (uint64_t)(in[i] & 1) << (i + 1);
	s->st[0] = st;
}

const repl_policy repl_plru = {
    .name = "plru",
    .desc = "tree pseudo-LRU (ways - 1 bits per set; ways a power of two)",
    .set_words = 1,
    .check = plru_check,
    .hit = plru_touch,
    .fill = plru_touch,
    .victim = plru_victim,
    .save = plru_save,
    .load = plru_load,
};

/* ---- the registry ---- */

#define REPL_EXTRA 16

static const repl_policy *const builtin[] = {&repl_lru, &repl_plru, &repl_fifo};
#define NBUILTIN ((int)(sizeof builtin / sizeof *builtin))
static const repl_policy *extra[REPL_EXTRA];
static int nextra;

const repl_policy *repl_find(const char *name)
{
	for (int i = 0; i < NBUILTIN; i++)
		if (!strcmp(builtin[i]->name, name))
			return builtin[i];
	for (int i = 0; i < nextra; i++)
		if (!strcmp(extra[i]->name, name))
			return extra[i];
	return NULL;
}

int repl_register(const repl_policy *p)
{
	if (!p || !p->name || !*p->name || repl_find(p->name) || nextra == REPL_EXTRA)
		return -1;
	extra[nextra++] = p;
	return 0;
}

const char *repl_names(char *buf, size_t n)
{
	size_t at = 0;
	buf[0] = 0;
	for (int i = 0; i < NBUILTIN + nextra; i++) {
		const repl_policy *p = i < NBUILTIN ? builtin[i] : extra[i - NBUILTIN];
		int k = snprintf(buf + at, n - at, "%s%s", i ? ", " : "", p->name);
		if (k < 0 || (size_t)k >= n - at)
			break;
		at += (size_t)k;
	}
	return buf;
}
