/*
 * hier_vma.c: the memory level "vma" (mem/hier_level.h): the virtual
 * memory architecture (mem/vma.h; seed 002 §4.2), its tag cache and its
 * on-board cache of host memory, over the host bus (mem/hostbus.h). It
 * stands on "sdram", whose memory interface carries its meta-data, data
 * and fills.
 */
#include "mem/hier_level.h"

static int vmal_init(hier *h, const hier_params *hp, diag *d)
{
	if (hbus_init(&h->hb, &hp->hbus, d))
		return -1;
	if (vma_init(&h->v, h->e, h->core, &h->mi, &h->hb, hp->sdram.bytes, &hp->vma, h->ms, d))
		return -1;
	h->use_vma = 1;
	return 0;
}

static void vmal_free(hier *h)
{
	vma_free(&h->v);
}

static void vmal_read(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes, uint8_t *dst,
                      eng_handler cb, void *ctx, uint64_t arg)
{
	vma_read(&h->v, t, type, addr, bytes, dst, cb, ctx, arg);
}

static void vmal_write(hier *h, uint64_t t, int type, uint64_t addr, uint32_t bytes,
                       const void *src)
{
	vma_write(&h->v, t, type, addr, bytes, src);
}

static void vmal_peek(const hier *h, uint64_t addr, uint32_t bytes, uint8_t *dst)
{
	vma_peek(&h->v, addr, bytes, dst);
}

double hier_vma_merge_share(const hier *h)
{
	return h->use_vma ? cache_timed_merge_share(NULL, &h->v.l2.c.s) : 0;
}

/* The host-bus transfer of n bytes as functional traffic. */
static void func_hbus(hier *h, uint64_t transfers, uint64_t bytes)
{
	h->fhb.transfers += transfers;
	h->fhb.bytes += bytes;
	h->fhb.busy_ticks += hbus_duration(&h->hb, (uint32_t)bytes);
}

/* Without time: the VMA's functional walk, whose counter deltas become
 * SDRAM and host-bus traffic. */
static void vmal_func(hier *h, int type, uint64_t addr, uint32_t bytes, int write, uint8_t *data)
{
	vma_stats a = h->v.s;
	vma_access_func(&h->v, addr, bytes, write, data);
	const vma_stats *b = &h->v.s;
	uint32_t mb = h->v.meta_set_bytes;
	for (uint64_t i = a.meta_reads; i < b->meta_reads; i++)
		hier_func_sdram(h, MEMIF_META, mb, 0);
	for (uint64_t i = a.meta_writes; i < b->meta_writes; i++)
		hier_func_sdram(h, MEMIF_META, mb, 1);
	uint64_t fetches = b->host_fetches - a.host_fetches;
	uint64_t hw = b->host_writes - a.host_writes;
	/* a fetched line is written into SDRAM (FILL); the rest is data */
	uint64_t fill_bytes = fetches * h->v.p.line;
	uint64_t dr = b->data_reads - a.data_reads, dw = b->data_writes - a.data_writes - fetches;
	uint64_t db = b->data_bytes - a.data_bytes - fill_bytes;
	hier_func_sdram_n(h, MEMIF_FILL, fetches, fill_bytes, 1);
	if (dr + dw) {
		uint64_t t0 = h->fsd.busy_ticks;
		hier_func_sdram_n(h, type, dr + dw, db, dw > 0);
		if (!write && dr) {
			/* the reads are on-board-cache hits; a timed chip merges a
			 * share of them into fetches still on their way */
			h->fl2hit_ticks += h->fsd.busy_ticks - t0;
			h->fmerge_ticks +=
			    (double)(h->fsd.busy_ticks - t0) * hier_vma_merge_share(h);
		}
	}
	for (uint64_t i = 0; i < fetches; i++) {
		h->fhb.transfers++;
		h->fhb.bytes += h->v.p.line;
		h->fhb.busy_ticks += hbus_duration(&h->hb, h->v.p.line);
	}
	if (hw)
		func_hbus(h, hw, b->host_write_bytes - a.host_write_bytes);
	/* dirty lines written back: read out of SDRAM, over the host bus */
	for (uint64_t i = a.writebacks; i < b->writebacks; i++) {
		hier_func_sdram(h, MEMIF_FILL, h->v.p.line, 0);
		func_hbus(h, 1, h->v.p.line);
	}
}

static void vmal_stats(const hier *h, hier_stats *s)
{
	s->vma_enabled = 1;
	s->tag_cache = h->v.tag.c.s;
	s->l2 = h->v.l2.c.s;
	s->vma = h->v.s;
	s->hostbus = h->hb.s;
	s->hostbus.transfers += h->fhb.transfers;
	s->hostbus.bytes += h->fhb.bytes;
	s->hostbus_peak_bytes_per_s = hbus_peak_bw(&h->hb);
}

static size_t vmal_counters(hier *h, uint64_t **out, size_t n, size_t cap)
{
	n = hier_add_ptrs(out, n, cap, HIER_COUNTERS(h->v.s));
	n = hier_add_ptrs(out, n, cap, HIER_COUNTERS(h->v.tag.c.s));
	return hier_add_ptrs(out, n, cap, HIER_COUNTERS(h->v.l2.c.s));
}

static int vmal_failed(const hier *h)
{
	return h->v.oom || h->v.l2.oom || h->v.tag.oom;
}

static int vmal_caches(const hier *h, cache **k)
{
	if (!h->v.p.tag_cache_enabled)
		return 0;
	k[0] = (cache *)&h->v.tag.c;
	return 1;
}

static cache *vmal_bysets(hier *h)
{
	return &h->v.l2.c;
}

static void vmal_reload(hier *h, const uint64_t *sets)
{
	vma_reload(&h->v, sets);
}

const hlevel hier_vma_level = {
    .name = "vma",
    .on = "sdram",
    .host_addressed = 1,
    .init = vmal_init,
    .free = vmal_free,
    .read = vmal_read,
    .write = vmal_write,
    .func = vmal_func,
    .peek = vmal_peek,
    .stats = vmal_stats,
    .counters = vmal_counters,
    .failed = vmal_failed,
    .caches = vmal_caches,
    .bysets = vmal_bysets,
    .reload = vmal_reload,
};
