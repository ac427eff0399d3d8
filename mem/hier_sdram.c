/*
 * hier_sdram.c: the memory level "sdram" (mem/hier_level.h): the memory
 * interface arbitrating the requesters (mem/memif.h; seed 002 §4.1, "one
 * unified memory interface") in front of the SDRAM (mem/sdram.h; §4.7).
 * The bottom of every hierarchy stack.
 */
#include <string.h>

#include "mem/hier_level.h"

static int sdram_level_init(hier *h, const hier_params *hp, diag *d)
{
	if (sdram_init(&h->sd, &hp->sdram, d))
		return -1;
	if (memif_init(&h->mi, h->e, &h->sd, hp->memif_policy))
		return diag_set(d, "config", 0, 0, "out of memory");
	return 0;
}

static void sdram_level_free(hier *h)
{
	memif_free(&h->mi);
}

/* A read's bytes are the store's, taken when the read is issued: only the
 * reading thread writes what it reads (its spill area) and its writes go
 * in when issued, so they are the bytes SDRAM returns. An L1 miss that
 * fills from the image (mem/hier.c, walk) reads without bytes (dst NULL):
 * the request to the memory interface alone. */
static __attribute__((noinline)) void sdram_read_bytes(hier *h, uint64_t t, int type, uint64_t addr,
                                                       uint32_t bytes, uint8_t *dst, eng_handler cb,
                                                       void *ctx, uint64_t arg)
{
	ms_read(h->ms, addr, bytes, dst);
	memif_submit(&h->mi, t, type, addr, bytes, 0, cb, ctx, arg);
}

/* The read with bytes is out of line: most reads are L1 misses to image
 * lines (no bytes), and this way they go on to memif_submit by a plain
 * jump, without saving registers around a copy they never make. */
static void sdram_read(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes, uint8_t *dst,
                       eng_handler cb, void *ctx, uint64_t arg)
{
	if (dst) {
		sdram_read_bytes(h, t, type, addr, bytes, dst, cb, ctx, arg);
		return;
	}
	memif_submit(&h->mi, t, type, addr, bytes, 0, cb, ctx, arg);
}

static void sdram_write(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes,
                        const void *src)
{
	if (src && ms_write(h->ms, addr, bytes, src))
		h->oom = 1;
	memif_submit(&h->mi, t, type, addr, bytes, 1, NULL, NULL, 0);
}

void hier_func_sdram(hier *h, int requester, uint32_t bytes, int write)
{
	if (write) {
		h->fsd.writes++;
		h->fsd.write_bytes += bytes;
		h->fmi.writes[requester]++;
	} else {
		h->fsd.reads++;
		h->fsd.read_bytes += bytes;
		h->fmi.reads[requester]++;
	}
	h->fmi.bytes[requester] += bytes;
	uint64_t beats = sdram_beats(&h->sd, bytes);
	h->fsd.beats += beats;
	h->fsd.busy_ticks += eng_cycles_to_ticks(h->sd.t.clk, beats);
}

void hier_func_sdram_n(hier *h, int requester, uint64_t n, uint64_t bytes, int write)
{
	for (uint64_t i = 0; i < n; i++) {
		uint64_t b = bytes / n + (i < bytes % n);
		hier_func_sdram(h, requester, (uint32_t)b, write);
	}
}

static void sdram_func(hier *h, int type, uint64_t addr, uint32_t bytes, int write, uint8_t *data)
{
	hier_func_sdram(h, type, bytes, write);
	if (data && write) {
		if (ms_write(h->ms, addr, bytes, data))
			h->oom = 1;
	} else if (data)
		ms_read(h->ms, addr, bytes, data);
}

static void sdram_peek(const hier *h, uint64_t addr, uint32_t bytes, uint8_t *dst)
{
	if (h->ms)
		ms_read(h->ms, addr, bytes, dst);
	else
		memset(dst, 0, bytes);
}

/* The timed counts, with the functional traffic joining them (its busy
 * time stays apart: func_sdram_busy_ticks). */
static void sdram_stats_of(const hier *h, hier_stats *s)
{
	s->memif = h->mi.s;
	s->sdram = h->sd.s;
	for (int r = 0; r < MEMIF_NREQ; r++) {
		s->memif.reads[r] += h->fmi.reads[r];
		s->memif.writes[r] += h->fmi.writes[r];
		s->memif.bytes[r] += h->fmi.bytes[r];
	}
	s->sdram.reads += h->fsd.reads;
	s->sdram.writes += h->fsd.writes;
	s->sdram.read_bytes += h->fsd.read_bytes;
	s->sdram.write_bytes += h->fsd.write_bytes;
	s->sdram.beats += h->fsd.beats;
	s->func_sdram_busy_ticks = h->fsd.busy_ticks;
	s->sdram_peak_bytes_per_s = sdram_peak_bw(&h->sd);
}

const hlevel hier_sdram_level = {
    .name = "sdram",
    .init = sdram_level_init,
    .free = sdram_level_free,
    .read = sdram_read,
    .write = sdram_write,
    .func = sdram_func,
    .peek = sdram_peek,
    .stats = sdram_stats_of,
};
