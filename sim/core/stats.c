/*
 * stats.c: the stats registry (see stats.h). Linear name search: names are
 * looked up only when registering and reporting.
 */
#include "sim/core/stats.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BLOCK 256

void stats_init(stats *s)
{
	memset(s, 0, sizeof *s);
}

void stats_free(stats *s)
{
	for (size_t i = 0; i < s->nblocks; i++)
		free(s->blocks[i]);
	free(s->blocks);
	free(s->e);
	memset(s, 0, sizeof *s);
}

static stats_entry *find(const stats *s, const char *name)
{
	for (size_t i = 0; i < s->n; i++)
		if (!strcmp(s->e[i].name, name))
			return &s->e[i];
	return NULL;
}

uint64_t *stats_counter(stats *s, const char *name, const char *unit, const char *desc)
{
	stats_entry *old = find(s, name);
	if (old)
		return old->value;
	if (s->n == s->cap) {
		size_t cap = s->cap ? 2 * s->cap : 64;
		stats_entry *e = realloc(s->e, cap * sizeof *e);
		if (!e)
			return NULL;
		s->e = e;
		s->cap = cap;
	}
	if (s->nblocks == 0 || s->used == BLOCK) {
		uint64_t **b = realloc(s->blocks, (s->nblocks + 1) * sizeof *b);
		if (!b)
			return NULL;
		s->blocks = b;
		if (!(b[s->nblocks] = calloc(BLOCK, sizeof(uint64_t))))
			return NULL;
		s->nblocks++;
		s->used = 0;
	}
	stats_entry *e = &s->e[s->n++];
	snprintf(e->name, sizeof e->name, "%s", name);
	e->unit = unit ? unit : "";
	e->desc = desc ? desc : "";
	e->value = &s->blocks[s->nblocks - 1][s->used++];
	*e->value = 0;
	return e->value;
}

uint64_t stats_get(const stats *s, const char *name)
{
	const stats_entry *e = find(s, name);
	return e ? *e->value : 0;
}

void stats_reset(stats *s)
{
	for (size_t i = 0; i < s->n; i++)
		*s->e[i].value = 0;
}
