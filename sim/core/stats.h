/*
 * stats.h: the stats registry: named counters registered once.
 *
 * Registering returns a uint64_t * that stays valid until stats_free, so
 * the hot path increments a counter without any name lookup. Names are
 * dotted ("rtp0.trav.ops", "mem.kd.reads") and carry a unit and a
 * description; ratios are computed by the reporter, not stored. Counters
 * live in fixed-size blocks, so registering never moves earlier ones.
 */
#ifndef SAAR_SIM_STATS_H
#define SAAR_SIM_STATS_H

#include <stddef.h>
#include <stdint.h>

typedef struct stats_entry {
	char name[64];
	const char *unit, *desc; /* static strings */
	uint64_t *value;
} stats_entry;

typedef struct stats {
	stats_entry *e;
	size_t n, cap;
	uint64_t **blocks;
	size_t nblocks, used; /* counters used in the last block */
} stats;

void stats_init(stats *s);
void stats_free(stats *s);
/* Registers a counter (zeroed); name is copied (at most 63 chars). Returns
 * NULL when out of memory. Registering an existing name returns its counter. */
uint64_t *stats_counter(stats *s, const char *name, const char *unit, const char *desc);
/* The counter's value, 0 if no such name. */
uint64_t stats_get(const stats *s, const char *name);
/* Sets every counter to 0. */
void stats_reset(stats *s);

#endif
