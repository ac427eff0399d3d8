/*
 * hier_params.h: the data of the "hierarchy" memport model (mem/hier.h):
 * what it is built from (hier_params, filled by sim/memconfig.c from the
 * config) and every counter it keeps (hier_stats, read by the report).
 * A header of its own so that the levels' interface (mem/hier_level.h)
 * and the hierarchy's (mem/hier.h) both stand on it and not on each
 * other.
 */
#ifndef SAAR_MEM_HIER_PARAMS_H
#define SAAR_MEM_HIER_PARAMS_H

#include <stdint.h>

#include "mem/cache.h"
#include "mem/hostbus.h"
#include "mem/memif.h"
#include "mem/memport.h"
#include "mem/sdram.h"
#include "mem/vma.h"

/* Every counter of the hierarchy, copied out by hier_get_stats. Ratios
 * (hit rates, utilisation) are derived by the report (sim/report_mem.h
 * hier_write_json), not counted. */
typedef struct hier_stats {
	int vma_enabled;
	uint64_t now_ticks; /* engine time when the stats were taken */
	/* the whole run's simulated time: 0 (the default) for now_ticks; set
	 * by the report when functional stretches did work the engine never
	 * timed (sampled: the estimated cycles, functional: the bound), so
	 * that the bandwidth divides every byte by the time they took */
	uint64_t run_ticks;
	uint64_t core_period;       /* ticks per core cycle */
	cache_stats l1[MEM_NTYPES]; /* per L1: accesses = hits + misses (lines) */
	uint64_t reads[MEM_NTYPES], read_bytes[MEM_NTYPES];
	uint64_t writes[MEM_NTYPES], write_bytes[MEM_NTYPES];
	uint64_t bypass_reads[MEM_NTYPES];      /* spill-area reads that skip the L1 */
	uint64_t wait_cycles[MEM_NTYPES];       /* sum over reads of issue -> data, core cycles */
	uint64_t mshr_stall_cycles[MEM_NTYPES]; /* time reads waited for a free MSHR */
	/* per L1, its line lookups (hits + misses) and hits by the ray type of
	 * the packet that asked (mem_req.ray; functional lookups count as the
	 * cache counts them: a line in flight is a merged miss) */
	uint64_t ray_lookups[MEM_RAY_TYPES][MEM_NTYPES], ray_hits[MEM_RAY_TYPES][MEM_NTYPES];
	memif_stats memif; /* per requester: shade kd list tri meta fill */
	sdram_stats sdram;
	double sdram_peak_bytes_per_s;
	/* with VMA */
	cache_stats tag_cache, l2;
	vma_stats vma;
	hbus_stats hostbus;
	double hostbus_peak_bytes_per_s;
	/* functional accesses (memport access_func; docs/fidelity.md): their
	 * traffic is included in the counts above; the data-bus time they
	 * would occupy (no row or queueing overheads) is kept apart here */
	uint64_t func_requests;
	uint64_t func_sdram_busy_ticks, func_hostbus_busy_ticks;
	/* of func_sdram_busy_ticks, the expected part a timed chip would not
	 * spend: on-board-cache hits it would merge into PCI fetches in flight */
	double func_sdram_merge_ticks;
	/* the timed data-bus busy time of regions whose counts a skip handed
	 * to the warming run (sampling.jump skip, hier_keep_shares): out of
	 * the counts above and the resource demand, but the regions' time on
	 * the buses all the same (the report's busy time and utilization) */
	uint64_t skipped_sdram_busy_ticks, skipped_hostbus_busy_ticks;
} hier_stats;

/* Everything the hierarchy is built from (sim/memconfig.h derives it from
 * the config's memory.* keys). */
typedef struct hier_params {
	cache_params l1[MEM_NTYPES]; /* the L1s, by request type */
	sdram_params sdram;
	int memif_policy; /* enum memif_policy */
	/* the levels, top first, by name: l1, [vma,] sdram (the L1s, the
	 * VMA's on-board cache of host memory, the memory interface and
	 * SDRAM); sim/memconfig.c names the stack memory.model and
	 * memory.vma.enabled give ("l1,sdram", "l1,vma,sdram") */
	char levels[48];
	vma_params vma;
	hbus_params hbus;
} hier_params;

#endif
