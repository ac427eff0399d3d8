/*
 * memconfig.h: the builder that turns the config's memory.* keys into the
 * parameter structs of mem/ (which includes no config schema): the L1s'
 * cache_params, the VMA's, the host bus's and the whole hierarchy's, with
 * replacement policies looked up by name (mem/repl.h).
 */
#ifndef SAAR_SIM_MEMCONFIG_H
#define SAAR_SIM_MEMCONFIG_H

#include "kernel-ref/diag.h"
#include "mem/hier.h"
#include "sim/config.h"

/* The parameters of the L1 of request type `type` (MEM_*), the VMA and
 * the host bus (preset, then the overriding keys). A replacement name no
 * policy is registered under gives repl NULL (LRU); memcfg_hier reports
 * it as an error. */
cache_params hier_l1_params(const saar_config *cfg, int type);
/* The accesses per core cycle of that L1 (its ports), without building
 * its parameters (the sampled estimator's demand asks per chunk). */
int memcfg_l1_ports(const saar_config *cfg, int type);
vma_params hier_vma_params(const saar_config *cfg);
void hier_hbus_params(const saar_config *cfg, hbus_params *p);
/* The memory stack the config names, top first, into buf: memory.levels,
 * or from memory.model and memory.vma.enabled "fixed" (one latency for
 * every access), "l1,sdram" or "l1,vma,sdram". */
const char *memcfg_levels(const saar_config *cfg, char *buf, size_t n);
/* All of the hierarchy's parameters; -1 with d set when a replacement
 * key names no registered policy. */
int memcfg_hier(const saar_config *cfg, hier_params *hp, diag *d);
/* Every check of the memory keys that building the memory makes and
 * that needs no scene (the image's fit on board is checked with the
 * world): the stack memory.levels names ("fixed" alone, or one
 * hier_init builds), the replacement policies, every cache's geometry,
 * the SDRAM's and the host bus's parameters and, with the VMA, its
 * on-board cache. 0, or -1 with d set: "config: KEY ..." where KEY is
 * the key or the section ("memory.l1.kd") at fault (memcfg_validate
 * names where its value came from). */
int memcfg_check(const saar_config *cfg, diag *d);
/* Every check of a config that needs no scene: cfg_validate_at (the
 * cross-key checks), then memcfg_check, its error named by where the
 * value at fault came from (cfg_blame; o NULL: "config: ..."). saarsim
 * and saarsim-replay call it once every override is set. */
int memcfg_validate(const saar_config *cfg, const cfg_origin *o, diag *d);
/* memcfg_hier, then hier_init (mem/hier.h). */
int mem_init_hier(memport *p, eng *e, eng_clock core, const saar_config *cfg, uint64_t image_bytes,
                  mem_store *store, diag *d);

#endif
