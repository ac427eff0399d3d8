/*
 * hier.h: the memport model "hierarchy": SaarCOR's memory system.
 *
 * Wiring (seed 002 §4.1, §4.2, §4.7; docs/memory.md):
 *
 *   units --mem_access--> L1 of the request's type (shade, kd, list, tri;
 *   each shared by all units of that type across all RTPs)
 *     hit:  data after hit_latency core cycles (ports accesses per cycle)
 *     miss: MSHR (merge / wait when full) -> line read below
 *   below, without VMA: memif (arbitration) -> SDRAM at the same address
 *   below, with VMA:    vma (tag cache -> SDRAM meta-data; SDRAM data or
 *                       host-bus DMA) -> memif -> SDRAM
 *
 * Writes (stack spills) are posted and bypass the L1s (write-around; the
 * spilled entry is read back once). Reads at or above image_bytes (the
 * spill area the chip places after the memory image) bypass the L1s too.
 * A read is answered at max(hit time, arrival of its last missing line).
 *
 * With a store (mem/store.h) the bytes travel too: the store is SDRAM's
 * contents (host memory's with the VMA), every L1 way and on-board line
 * holds its line's bytes, and a read's bytes are those of the lines it
 * found or filled (docs/memory.md, "Data").
 */
#ifndef SAAR_MEM_HIER_H
#define SAAR_MEM_HIER_H

#include <stddef.h>
#include <stdint.h>

#include "kernel-ref/diag.h"
#include "mem/cache.h"
#include "mem/hier_params.h"
#include "mem/hostbus.h"
#include "mem/memif.h"
#include "mem/memport.h"
#include "mem/sdram.h"
#include "mem/store.h"
#include "mem/vma.h"
#include "sim/core/engine.h"

/* Builds the hierarchy from hp and installs it in p (as mem_init_fixed
 * does). core is the chip clock. image_bytes: size of the memory image;
 * without VMA it must fit in on-board memory, else a one-line error
 * suggesting configs/saarcor-vma.yaml. store: the bytes (SDRAM's without
 * the VMA, host memory's with it; NULL: addresses only, as trace replay).
 * Returns 0, or -1 with d set. */
int hier_init(memport *p, eng *e, eng_clock core, const hier_params *hp, uint64_t image_bytes,
              mem_store *store, diag *d);
/* hier_init's check of the stack hp->levels names ("l1,vma,sdram"),
 * nothing built: 0, or -1 with d set ("config: memory.levels ..."). */
int hier_check_levels(const char *spec, diag *d);
/* Is p a hierarchy model? */
int hier_is(const memport *p);
/* Copies every counter; -1 if p is not a hierarchy. */
int hier_get_stats(const memport *p, hier_stats *s);
/* Checkpoints (stored warming, sim/warming.h): the hierarchy saves and
 * restores its caches itself, each in its own form (cache_ckpt_save; the
 * replacement policy saves its per-set state). hier_ckpt_bytes: the bytes
 * of the caches a checkpoint holds whole (the four L1s, the tag cache if
 * enabled; 0 without a hierarchy); save them to buf, or load them from it
 * (-1: a miss in flight, or not a hierarchy). The on-board cache is too
 * large to store whole: hier_onboard gives it (NULL without the VMA), and
 * checkpoints store its changed sets by cache_ckpt_save. */
size_t hier_ckpt_bytes(const memport *p);
int hier_ckpt_save(const memport *p, void *buf);
int hier_ckpt_load(memport *p, const void *buf);
cache *hier_onboard(memport *p);
/* The caches whose state functional processing moves (the four L1s; with
 * the VMA its tag cache, NULL when disabled, and on-board cache, else
 * both NULL; for tests); pointers to every counter
 * functional processing moves (out may be NULL; returns how many there
 * are, at most cap written); the ticks of on-board-cache hits among
 * functional SDRAM reads; and adding to the merged part of them
 * (hier_stats.func_sdram_merge_ticks). */
void hier_caches(memport *p, cache *l1[MEM_NTYPES], cache **tag, cache **l2);
/* After cache_load put lines in the caches (stored warming): their bytes
 * from the level below, on-board lines of the sets l2sets marks (a
 * bitset; NULL: none) from host memory, clean, then every L1 line. */
void hier_reload(memport *p, const uint64_t *l2sets);
size_t hier_counter_ptrs(memport *p, uint64_t **out, size_t cap);
/* The timed models' traffic counts that the functional counters of
 * hier_counter_ptrs stand for in functional processing: the memory
 * interface's and SDRAM's requests, bytes, beats and data-bus busy time,
 * the host bus's transfers, bytes and busy time (the resource demand
 * counts both kinds; not the timing's own: row hits, queueing, waits).
 * A sampled jump that skips (sampling.jump skip, sim/warming.h wm_skip)
 * takes them back with the counters it hands to the warming run. out
 * NULL: counts only. */
size_t hier_traffic_ptrs(memport *p, uint64_t **out, size_t cap);
/* Of hier_counter_ptrs, those a skip keeps: the reads' waits and MSHR
 * stalls (only timed reads move them; a sampled run scales its regions'
 * waits to the estimated cycles) and the caches' skip_hits and
 * skip_merges (hier_keep_shares). */
size_t hier_kept_ptrs(memport *p, uint64_t **out, size_t cap);
uint64_t hier_l2hit_ticks(const memport *p);
void hier_add_merge_ticks(memport *p, double ticks);
/* The share of on-board-cache hits a timed chip merges into fetches on
 * their way, from the on-board cache's counts so far (the factor on
 * func_sdram_merge_ticks); 0 without the VMA or without a hierarchy. */
double hier_merge_share(const memport *p);
/* A skip (sim/warming.h wm_skip) hands the counts since the chip's last
 * restore to the warming run. hier_mark_shares (called at the restore)
 * notes the caches' counts and the buses' timed busy time;
 * hier_keep_shares, before the counts go back, adds every cache's timed
 * hits and merges since then to its skip_hits and skip_merges (so the
 * merge shares, hier_merge_share and the estimated hit rates, still count
 * every region's) and the busy time to hier_stats.skipped_*. */
void hier_mark_shares(memport *p);
void hier_keep_shares(memport *p);

#endif
