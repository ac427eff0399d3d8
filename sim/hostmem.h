/*
 * hostmem.h: the host memory a run will take, estimated before the chip is
 * built, and the limit a run is refused past (docs/design.md, "Host memory
 * limit"). The parts mirror what chip_create and the memory models
 * allocate, counted from the config alone (cache_host_bytes,
 * vma_host_bytes, thr_unit_host_bytes); what is already in memory (the
 * program and the loaded world) is read from the process.
 */
#ifndef SAAR_SIM_HOSTMEM_H
#define SAAR_SIM_HOSTMEM_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/world.h"
#include "sim/config.h"

/* The parts of an estimate, bytes. */
enum hm_part { HM_LOADED, HM_THREADS, HM_L1, HM_VMA, HM_FRAME, HM_NPARTS };

typedef struct hm_est {
	uint64_t part[HM_NPARTS];
	uint64_t total;
} hm_est;

/* The default limit: 4 GiB (HM_DEFAULT_MB). */
#define HM_DEFAULT_MB 4096

/* Fills e for config cfg on world w (loaded). */
void hm_estimate(const saar_config *cfg, const world *w, hm_est *e);

/* The limit in MB: value (a --host-mem-limit argument) if non-NULL, else
 * the environment's SAARSIM_HOST_MEM_MB, else HM_DEFAULT_MB. -1 with d
 * naming the flag or variable on a value that is not a whole number of MB
 * in [1, 2^30]. */
int hm_limit_mb(const char *value, uint64_t *mb, diag *d);

/* 0 when e is within limit_mb; else -1 with one line in d: the estimate,
 * the limit, the parts that drive it with the keys that size them, and how
 * to raise the limit. */
int hm_check(const hm_est *e, uint64_t limit_mb, diag *d);

/* The process's peak resident memory so far, bytes (getrusage). */
uint64_t hm_peak_rss(void);

#endif
