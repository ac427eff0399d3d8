/*
 * hier_level.h: the inside of the "hierarchy" memport model (mem/hier.h),
 * shared by its files only: the hierarchy's state and the interface of a
 * memory level below the L1s.
 *
 * The memory system is a stack of levels named top first (hier_params
 * levels, memory.levels): the L1s ("l1", the hierarchy's own top, in
 * mem/hier.c) and the levels below them, each a component behind
 * `hlevel` chosen by name from `hier_levels` (mem/hier.c):
 *
 *   "sdram"  the memory interface and SDRAM (mem/hier_sdram.c; seed 002
 *            §4.1, §4.7): the bottom of every stack
 *   "vma"    the virtual memory architecture, its tag cache and on-board
 *            cache of host memory, standing on "sdram" (mem/hier_vma.c;
 *            §4.2)
 *
 * A level answers a timed read, a posted write, a functional access and a
 * peek; fills in its part of the stats and of the counters stored warming
 * carries; names the caches checkpoints hold (they save and restore
 * themselves, mem/cache.h cache_ckpt_*); and builds and frees itself.
 * Docs: docs/memory.md "Levels", docs/extending.md.
 */
#ifndef SAAR_MEM_HIER_LEVEL_H
#define SAAR_MEM_HIER_LEVEL_H

#include "mem/hier_params.h"
#include "mem/tcache.h"

typedef struct hreq hreq;
struct hreq {
	eng_handler done;
	void *ctx;
	uint64_t arg;
	uint64_t issue, ready;
	uint64_t next_line, last_line, addr;
	uint8_t *dst; /* where the bytes go; NULL: no data */
	uint32_t bytes, pending;
	uint8_t type;
	uint8_t ray; /* mem_req.ray */
	hreq *next;
};

typedef struct hier hier;
typedef struct hlevel hlevel;

typedef struct hl1 {
	hier *h;
	int type;
	tcache t; /* the cache, its MSHRs' waiters, stall FIFO and port */
	/* per MSHR, with a store and SDRAM below: the image bytes its line
	 * fills from (ms_image_at at the miss; NULL: the line came into the
	 * MSHR's buffer, t.mbuf) */
	const uint8_t **msrc;
} hl1;

typedef struct hchunk {
	struct hchunk *next;
} hchunk;

#define HIER_MAXLEVELS 4

struct hier {
	eng *e;
	eng_clock core;
	uint64_t image_bytes;
	mem_store *ms; /* the board's bytes (host memory's with the VMA); NULL: no data */
	int oom;       /* a line found no memory for its bytes */
	hl1 l1[MEM_NTYPES];
	/* the levels below the L1s, top first (stack[0] serves L1 misses) */
	const hlevel *stack[HIER_MAXLEVELS];
	int nstack;
	sdram sd; /* "sdram" */
	memif mi;
	int use_vma; /* "vma" */
	vma v;
	hbus hb;
	hchunk *chunks;
	hreq *free_r;
	/* an observer of the timing (memport.h mem_observe; NULL: none) and,
	 * while one is set, per L1 and MSHR the tick its miss was sent below */
	const mem_obs *obs;
	uint64_t *miss_t0[MEM_NTYPES];
	uint64_t reads[MEM_NTYPES], read_bytes[MEM_NTYPES];
	uint64_t writes[MEM_NTYPES], write_bytes[MEM_NTYPES];
	uint64_t bypass[MEM_NTYPES], wait_ticks[MEM_NTYPES], stall_ticks[MEM_NTYPES];
	/* L1 line lookups (hits and misses, as the cache counts them) and
	 * hits, by the ray type of the asking packet (mem_req.ray) */
	uint64_t ray_lookups[MEM_RAY_TYPES][MEM_NTYPES], ray_hits[MEM_RAY_TYPES][MEM_NTYPES];
	/* traffic of functional accesses (hier_access_func): what the timed
	 * SDRAM, memory interface and host bus would have counted; busy_ticks
	 * are data-bus occupancy without row or queueing overheads */
	sdram_stats fsd;
	memif_stats fmi;
	hbus_stats fhb;
	uint64_t freqs;
	/* of fsd.busy_ticks: the expected part a timed chip would not spend,
	 * on-board-cache hits it would merge into a PCI fetch in flight (each
	 * such read's ticks times the share of merges among the timed
	 * accesses that found their line present or arriving, so far) */
	double fmerge_ticks;
	/* of fsd.busy_ticks: all reads that were on-board-cache hits (what
	 * fmerge_ticks takes its share of; stored warming applies the share
	 * to the checkpoints' traffic after the fact, sim/warming.h) */
	uint64_t fl2hit_ticks;
	/* a skip (hier_keep_shares): the caches' counts (by
	 * hier_skip_caches) and the buses' timed busy time at the last mark,
	 * and the busy time the skips handed over (hier_stats.skipped_*) */
	cache_stats skip_mark[MEM_NTYPES + 2];
	uint64_t kept_sd_busy, kept_hb_busy, mark_sd_busy, mark_hb_busy;
};

/* One level below the L1s. Every hook but the four accesses may be NULL
 * (nothing to do). */
struct hlevel {
	const char *name;
	/* the level it stands on directly (NULL: the bottom of the stack) */
	const char *on;
	/* it addresses host memory: the image need not fit on board */
	int host_addressed;
	/* builds it (the levels below it are built) and frees it (also after
	 * a failed or partial build: its state is zeroed before) */
	int (*init)(hier *h, const hier_params *hp, diag *d);
	void (*free)(hier *h);
	/* a timed read into dst (NULL: no data), cb(ctx, arg) when the bytes
	 * are there; a posted write of src (NULL: no data); the same without
	 * time (its traffic into the functional counters); the bytes a read
	 * would return now, changing nothing */
	void (*read)(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes, uint8_t *dst,
	             eng_handler cb, void *ctx, uint64_t arg);
	void (*write)(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes,
	              const void *src);
	void (*func)(hier *h, int type, uint64_t addr, uint32_t bytes, int write, uint8_t *data);
	void (*peek)(const hier *h, uint64_t addr, uint32_t bytes, uint8_t *dst);
	/* its part of hier_stats; its counters (hier_counter_ptrs: out may be
	 * NULL; returns n plus its count); a line found no memory */
	void (*stats)(const hier *h, hier_stats *s);
	size_t (*counters)(hier *h, uint64_t **out, size_t n, size_t cap);
	int (*failed)(const hier *h);
	/* checkpoints: the caches it has stored whole (into k; returns how
	 * many), the cache stored by changed set (NULL: none), and after a
	 * restore the bytes of the lines of sets `sets` of that cache */
	int (*caches)(const hier *h, cache **k);
	cache *(*bysets)(hier *h);
	void (*reload)(hier *h, const uint64_t *sets);
};

extern const hlevel hier_sdram_level, hier_vma_level;

/* The level l stands on in h's stack (NULL: l is the bottom or absent):
 * where a level sends what it cannot answer itself. */
const hlevel *hier_below(const hier *h, const hlevel *l);

/* One SDRAM access of bytes as the memory interface would submit it,
 * counted as functional traffic; n of them moving `bytes` together. */
void hier_func_sdram(hier *h, int requester, uint32_t bytes, int write);
void hier_func_sdram_n(hier *h, int requester, uint64_t n, uint64_t bytes, int write);
/* The share of on-board-cache hits a timed chip merges into fetches on
 * their way, from the on-board cache's counts so far; 0 without the VMA. */
double hier_vma_merge_share(const hier *h);

/* Appends pointers to k 64-bit counters at a to out (NULL: counts only). */
size_t hier_add_ptrs(uint64_t **out, size_t n, size_t cap, uint64_t *a, size_t k);
/* A stats struct as (pointer, count) for hier_add_ptrs (every field of
 * these structs is a uint64_t counter). */
#define HIER_COUNTERS(st) (uint64_t *)&(st), sizeof(st) / sizeof(uint64_t)

#endif
