/*
 * vma.h: the virtual memory architecture (L2): on-board SDRAM as a cache of
 * host memory (seed 002 §4.2; Schmittler et al.).
 *
 * The chip addresses host memory. The on-board SDRAM holds a `ways`-way
 * set-associative cache of it with `line`-byte lines (4-way, 128 B
 * published) and address hashing (none | xor-fold) choosing the set. Its
 * tags and state are meta-data in SDRAM too, one record per set of
 * ways x 5 bytes (§4.2: 640 KB of meta-data manage 16 MB in 128-byte lines,
 * i.e. 5 bytes per line); looking them up and updating them are SDRAM
 * accesses of their own (requester MEMIF_META), counted apart from data.
 * An on-chip tag cache (an instance of mem/cache with one set record per
 * line; 64 KB published) caches the records; it can be disabled.
 *
 * SDRAM layout: data lines first (slot = set*ways + way, at slot*line), the
 * meta-data region after them. nsets = SDRAM bytes / (ways*line + record).
 *
 * One read (any size; split at L2 lines) runs, per L2 line:
 *   1. meta lookup: tag cache hit (hit_latency core cycles), or a META read
 *      of the record from SDRAM (tag cache miss, or no tag cache);
 *   2. L2 hit: a data read of the requested bytes from SDRAM;
 *      L2 miss: a DMA of the whole line over the host bus; the line is
 *      forwarded to the requester when the DMA completes and, posted, written
 *      into SDRAM (MEMIF_FILL) together with its updated record (META).
 * Misses to a line in flight merge (L2 MSHRs). Writes (stack spills) go to
 * SDRAM if the line is on board, which makes the line dirty, else around
 * it over the host bus. Evicting a dirty line writes it back: an SDRAM read
 * of the line (MEMIF_FILL) and a host-bus transfer; clean lines (the
 * read-only scene) are dropped.
 *
 * Data (docs/memory.md, "Data"): host memory is a mem_store; each on-board
 * line holds its bytes (the cache's data, mem/cache.h), copied from host
 * memory when its DMA completes and written back to it when it is evicted
 * dirty. A read's bytes come from the on-board line (taken at the tag
 * check on a hit, when the DMA lands on a miss).
 */
#ifndef SAAR_MEM_VMA_H
#define SAAR_MEM_VMA_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "mem/cache.h"
#include "mem/hostbus.h"
#include "mem/memif.h"
#include "mem/store.h"
#include "mem/tcache.h"
#include "sim/core/engine.h"

#define VMA_META_BYTES_PER_LINE 5u  /* 40 bits of tag + state per line, §4.2 */
#define VMA_MSHRS               32u /* outstanding line fetches; assumed */
#define VMA_TAG_MSHRS           16u /* outstanding meta-data reads; assumed */

typedef struct vma_params {
	uint32_t ways, line;
	int hash; /* enum cache_hash */
	int tag_cache_enabled;
	uint64_t tag_cache_bytes;
	uint32_t tag_cache_ways;
	uint32_t tag_hit_latency; /* core cycles */
	/* replacement of the on-board cache and of the tag cache (mem/repl.h;
	 * NULL: LRU) */
	const repl_policy *repl, *tag_repl;
} vma_params;

typedef struct vma_stats {
	uint64_t reads, read_bytes, writes, write_bytes;
	uint64_t meta_reads, meta_writes, meta_bytes; /* SDRAM meta-data traffic */
	/* SDRAM data traffic: on-board hits, writes and the fetched lines'
	 * fills; a dirty victim's read out of SDRAM is a write-back's
	 * (writebacks, writeback_bytes), not counted here */
	uint64_t data_reads, data_writes, data_bytes;
	uint64_t host_fetches, host_fetch_bytes; /* lines fetched over the host bus */
	uint64_t host_writes, host_write_bytes;  /* write-around */
	uint64_t stall_ticks;                    /* waited for a free MSHR */
	uint64_t writebacks, writeback_bytes;    /* dirty lines written back to host memory */
} vma_stats;

typedef struct vma_piece vma_piece;
typedef struct vma_req vma_req;

typedef struct vma {
	eng *e;
	eng_clock core;
	memif *mi;
	hbus *hb;
	vma_params p;
	tcache l2;  /* the on-board cache (timed; its tags and state are in SDRAM) */
	tcache tag; /* the on-chip tag cache (valid if p.tag_cache_enabled) */
	uint32_t meta_set_bytes;
	uint64_t meta_base; /* SDRAM address of the meta-data region */
	void *pool;         /* allocator of pieces and requests (vma.c) */
	uint64_t *dirty;    /* per on-board line (set * ways + way): written since its fill */
	mem_store *ms;      /* host memory's bytes; NULL: the VMA moves no data */
	int oom;            /* an on-board line found no memory for its bytes */
	vma_stats s;
} vma;

/* vma_init's checks of p for sdram_bytes of on-board memory, nothing
 * allocated: 0, or -1 with d set ("config: ..."). */
int vma_check(uint64_t sdram_bytes, const vma_params *p, diag *d);
/* vma_check's checks that need no on-board size: the ways, the line, the
 * replacement policies and the tag cache's geometry. For a config whose
 * stack has no VMA: its keys are checked all the same, so a bad value is
 * refused when it is set, not later when the VMA is turned on. */
int vma_check_params(const vma_params *p, diag *d);

/* Sizes the L2 from sdram_bytes; errors name the memory.vma keys. ms:
 * host memory's bytes (NULL: no data). */
int vma_init(vma *v, eng *e, eng_clock core, memif *mi, hbus *hb, uint64_t sdram_bytes,
             const vma_params *p, mem_store *ms, diag *d);
void vma_free(vma *v);
/* Lines the L2 holds (capacity = lines * line bytes). */
uint64_t vma_capacity(const vma *v);
/* Host bytes vma_init allocates for on-board memory of sdram_bytes with
 * parameters p: the on-board cache's tags, dirty bits and tag cache, and
 * with data the bytes of at most `lines` distinct host lines (0: no
 * data). */
uint64_t vma_host_bytes(uint64_t sdram_bytes, const vma_params *p, uint64_t lines);

/* A read of bytes at host address addr, issued at tick t (>= eng_now),
 * for requester type (MEM_*): done(e, ctx, arg) when all bytes are there,
 * in dst (NULL: no data). Returns -1 only when out of memory. */
int vma_read(vma *v, uint64_t t, int type, uint64_t addr, uint32_t bytes, void *dst,
             eng_handler done, void *ctx, uint64_t arg);
/* A posted write of src (NULL: no data). */
int vma_write(vma *v, uint64_t t, int type, uint64_t addr, uint32_t bytes, const void *src);

/* The same walk without time (immediate fills, no SDRAM or bus timing):
 * the counters move as in vma_read/vma_write. data: the bytes read into,
 * or written from (NULL: none). For functional processing and trace
 * replay. */
void vma_access_func(vma *v, uint64_t addr, uint32_t bytes, int write, void *data);
/* The bytes a read would return now (on board, else host memory), with
 * no change to anything. */
void vma_peek(const vma *v, uint64_t addr, uint32_t bytes, void *dst);
/* The on-board lines of the sets `sets` marks (a bitset) were put there
 * by cache_load (stored warming): their bytes from host memory, clean. */
void vma_reload(vma *v, const uint64_t *sets);

#endif
