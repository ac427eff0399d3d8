/*
 * hostbus.h: the host bus (PCI/AGP) over which the VMA fetches lines.
 *
 * Seed 002 §4.2/§4.7: the VMA reads scene data from host memory "by DMA
 * transfers via the PCI or AGP bus"; the standard board uses "a standard
 * PCI-bus" (32 bit, 33 MHz). A transfer of n bytes is split into bursts of
 * at most `burst` data phases; every burst pays `latency` (arbitration,
 * address phase, host-memory read latency; assumed) and then one bus clock
 * per data phase. One transfer at a time: a transfer starts when the bus is
 * free (busy-until), so contention queues transfers in call order.
 */
#ifndef SAAR_MEM_HOSTBUS_H
#define SAAR_MEM_HOSTBUS_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "mem/memport.h"
#include "sim/core/engine.h"

typedef struct hbus_params {
	uint32_t width_bits;
	double clock_mhz; /* data phases per microsecond (AGP 4x: 266) */
	uint32_t burst;   /* data phases per bus transaction */
	double latency_ns;
} hbus_params;

typedef struct hbus_stats {
	uint64_t transfers, bytes, bursts, busy_ticks, wait_ticks;
} hbus_stats;

typedef struct hbus {
	hbus_params p;
	eng_clock clk;
	uint64_t latency; /* ticks per transaction */
	uint64_t busy_until;
	hbus_stats s;
	const mem_obs *obs; /* sees every transfer (memport.h); NULL: none */
} hbus;

/* Presets by name: "pci" (32/33), "pci66" (64/66), "agp" (32-bit AGP 4x,
 * 266 MT/s); -1 if unknown. */
int hbus_preset(const char *name, hbus_params *p);
int hbus_init(hbus *h, const hbus_params *p, diag *d);
/* Ticks one transfer of bytes takes on an idle bus. */
uint64_t hbus_duration(const hbus *h, uint32_t bytes);
/* A DMA transfer requested at tick t: returns the tick it completes. */
uint64_t hbus_transfer(hbus *h, uint64_t t, uint32_t bytes);
double hbus_peak_bw(const hbus *h); /* bytes per second */

#endif
