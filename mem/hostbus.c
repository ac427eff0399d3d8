/*
 * hostbus.c: host-bus DMA timing and contention (see hostbus.h).
 */
#include "mem/hostbus.h"

#include <math.h>
#include <string.h>

int hbus_preset(const char *name, hbus_params *p)
{
	/* Latency: PCI target initial latency (16 clocks max, PCI 2.2) plus
	 * the host bridge's memory read; ~0.3 us assumed for all three. Burst:
	 * 32 data phases (a 128-byte line on 32-bit PCI is one burst). */
	static const struct {
		const char *name;
		hbus_params p;
	} presets[] = {
	    {"pci", {32, 33.0, 32, 300.0}},
	    {"pci66", {64, 66.0, 32, 300.0}},
	    {"agp", {32, 266.0, 32, 300.0}},
	};
	for (size_t i = 0; i < sizeof presets / sizeof presets[0]; i++)
		if (!strcmp(name, presets[i].name)) {
			*p = presets[i].p;
			return 0;
		}
	return -1;
}

int hbus_init(hbus *h, const hbus_params *p, diag *d)
{
	memset(h, 0, sizeof *h);
	if (p->width_bits < 8 || p->width_bits % 8 || !(p->clock_mhz > 0) || p->burst < 1 ||
	    !(p->latency_ns >= 0))
		return diag_set(
		    d, "config", 0, 0,
		    "memory.hostbus: width_bits must be a multiple of 8, clock_mhz > 0, "
		    "burst >= 1, latency_ns >= 0");
	h->p = *p;
	h->clk = eng_clock_mhz(p->clock_mhz);
	h->latency = (uint64_t)llround(p->latency_ns * 1000.0);
	return 0;
}

uint64_t hbus_duration(const hbus *h, uint32_t bytes)
{
	uint32_t bb = h->p.width_bits / 8;
	uint64_t phases = (bytes + bb - 1) / bb;
	if (!phases)
		phases = 1;
	uint64_t bursts = (phases + h->p.burst - 1) / h->p.burst;
	return bursts * h->latency + phases * h->clk.period;
}

uint64_t hbus_transfer(hbus *h, uint64_t t, uint32_t bytes)
{
	uint64_t start = eng_next_edge(h->clk, t > h->busy_until ? t : h->busy_until);
	uint64_t dur = hbus_duration(h, bytes);
	uint32_t bb = h->p.width_bits / 8;
	uint64_t phases = (bytes + bb - 1) / bb;
	h->s.transfers++;
	h->s.bytes += bytes;
	h->s.bursts += (phases + h->p.burst - 1) / h->p.burst;
	h->s.busy_ticks += dur;
	h->s.wait_ticks += start - t;
	h->busy_until = start + dur;
	if (h->obs) {
		mem_obs_ev ev = {MEM_OBS_HOSTBUS, 0, 0, 0, start, start + dur, 0, bytes, NULL};
		h->obs->fn(h->obs->ctx, &ev);
	}
	return h->busy_until;
}

double hbus_peak_bw(const hbus *h)
{
	return (double)(h->p.width_bits / 8) * 1e12 / (double)h->clk.period;
}
