/*
 * hostmem.c: the run's host memory estimate and limit (hostmem.h).
 *
 * A config inside every key's range can still ask for more memory than the
 * host has: a thousand RTPs of a thousand threads (each slot holds a
 * 64-entry traversal stack of 64 rays, its children's packets and a share
 * of the packet pool: about 50 KB), L1s of a gigabyte (16 bytes of tag and
 * LRU stamp per line), or through the VMA a 64 GB board (the on-board
 * cache's tags, an eighth of its size at 128-byte lines). Such a run is
 * refused before anything is built, naming the keys, instead of paging the
 * machine to a halt or ending in an out-of-memory kill halfway through a
 * sweep. The estimate is an upper bound of what the run allocates: the
 * stack and pool parts are reserved in full although a frame rarely
 * touches them all.
 */
#include "sim/hostmem.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "kernel-ref/framebuf.h"
#include "kernel-ref/gridimage.h"
#include "kernel-ref/gridwalk.h"
#include "kernel-ref/packet.h"
#include "mem/cache.h"
#include "mem/store.h"
#include "mem/vma.h"
#include "sim/chip.h"
#include "sim/memconfig.h"
#include "units/thread.h"

/* Resident bytes of this process now (/proc/self/statm), 0 if unknown. */
static uint64_t resident_bytes(void)
{
	FILE *f = fopen("/proc/self/statm", "r");
	unsigned long long size = 0, res = 0;
	if (f) {
		if (fscanf(f, "%llu %llu", &size, &res) != 2)
			res = 0;
		fclose(f);
	}
	long pg = sysconf(_SC_PAGESIZE);
	return (uint64_t)res * (uint64_t)(pg > 0 ? pg : 4096);
}

uint64_t hm_peak_rss(void)
{
	struct rusage ru;
	if (getrusage(RUSAGE_SELF, &ru) != 0)
		return 0;
	return (uint64_t)ru.ru_maxrss << 10; /* KB on Linux */
}

void hm_estimate(const saar_config *cfg, const world *w, hm_est *e)
{
	memset(e, 0, sizeof *e);
	e->part[HM_LOADED] = resident_bytes();
	uint64_t slots = (uint64_t)cfg->chip.rtps * (uint64_t)cfg->chip.threads_per_rtp;
	uint64_t nkids = (uint64_t)w->v.nlights + 2;
	/* every slot: its context (zeroed by chip_create) and the schedule's
	 * per-slot arrays. A slot that gets packets also touches its stack
	 * (as deep as the kd-tree), its children's packets and the packet
	 * pool's share at its high-water mark (its packet and its children
	 * queued); no more slots get packets than the frame has tiles and
	 * children of tiles. Stack pages past the tree's depth are reserved
	 * but never touched, so they are not counted; but an idle slot's stack
	 * and children allocations each touch the page their allocator header
	 * sits in (measured: a million idle slots take 14 GB, not 5). */
	uint64_t depth = (uint64_t)(w->kd.depth > 0 ? w->kd.depth : PKT_STACK_MAX) + 1;
	if (depth > PKT_STACK_MAX)
		depth = PKT_STACK_MAX;
	uint64_t ntiles = (((uint64_t)cfg->frame.width + TILE_W - 1) / TILE_W) *
	                  (((uint64_t)cfg->frame.height + TILE_H - 1) / TILE_H);
	uint64_t busy = ntiles * (1 + nkids) < slots ? ntiles * (1 + nkids) : slots;
	uint64_t idle_slot = sizeof(thr_ctx) + 4 * sizeof(void *) + 2 * 4096;
	uint64_t busy_slot = depth * sizeof(trav_entry) + nkids * sizeof(packet) +
	                     (1 + nkids) * (sizeof(packet) + sizeof(void *));
	/* its data buffers: shading's (two copies of a packet's records,
	 * about 8 KB each, and its list of reads) and, when the stack spills
	 * (chip.stack_depth below the tree's depth), the spilled entries read
	 * back and its spill area's pages in the memory's store */
	busy_slot += sizeof(thr_shade) + 2 * 8192 + 64 * sizeof(thr_shread);
	/* a two-level scene: the chip's own image (kernel-ref/tlimage.h), a
	 * copy chip_create makes, and each busy slot's top-level walk */
	uint64_t image_bytes = w->tl ? tli_size(w->tl, &w->m) : w->m.size;
	if (w->tl)
		busy_slot += sizeof(thr_tl);
	/* a uniform grid: the chip's image (kernel-ref/gridimage.h), a copy
	 * chip_create makes, and each busy slot's walk (units/gridtrav.c) */
	if (w->grid) {
		image_bytes = gimg_size(w->grid, &w->m);
		busy_slot += sizeof(grid_walk) + sizeof(grid_ask) + 64;
	}
	uint64_t image = (image_bytes + 4095) / 4096 * 4096;
	uint64_t space = image + slots * PKT_STACK_MAX * THR_SPILL_STRIDE, spill_pages = 0;
	if ((uint64_t)cfg->chip.stack_depth < depth) {
		busy_slot += PKT_STACK_MAX * THR_STACK_ENTRY_BYTES;
		spill_pages = busy * (PKT_STACK_MAX * THR_SPILL_STRIDE / MS_PAGE + 1);
	}
	e->part[HM_THREADS] = slots * idle_slot + busy * busy_slot +
	                      ms_host_bytes(space, spill_pages) +
	                      (w->tl || w->grid ? image_bytes : 0);
	for (int k = 0; k < UNIT_NKINDS; k++)
		e->part[HM_THREADS] +=
		    (uint64_t)cfg->chip.rtps *
		    thr_unit_host_bytes(chip_unit_cfg(cfg, k)->count, cfg->chip.threads_per_rtp);
	if (cfg->memory.model == CFG_MEM_HIERARCHY) {
		/* the lines' bytes: at most the image's lines are ever filled
		 * into an L1; the on-board cache also takes spill lines */
		for (int t = 0; t < MEM_NTYPES; t++) {
			cache_params cp = hier_l1_params(cfg, t);
			e->part[HM_L1] +=
			    cache_host_bytes(&cp) + (uint64_t)cp.mshrs * cp.line_bytes +
			    cache_data_host_bytes(&cp, image_bytes / cp.line_bytes + 1);
		}
		if (cfg->memory.vma.enabled) {
			vma_params vp = hier_vma_params(cfg);
			uint64_t bytes = image_bytes + spill_pages * MS_PAGE;
			e->part[HM_VMA] = vma_host_bytes((uint64_t)cfg->memory.sdram.mb << 20, &vp,
			                                 bytes / vp.line + 1);
		}
	}
	/* the chip's frame buffer, kernel-ref's for the check, and both
	 * frames in 8 bits for the comparison and the image */
	uint64_t px = (uint64_t)cfg->frame.width * (uint64_t)cfg->frame.height;
	framebuf *fb = NULL;
	e->part[HM_FRAME] = px * (2 * 3 * sizeof *fb->acc + 2 * 3);
	for (int p = 0; p < HM_NPARTS; p++)
		e->total += e->part[p];
}

int hm_limit_mb(const char *value, uint64_t *mb, diag *d)
{
	const char *who = "--host-mem-limit";
	if (!value) {
		value = getenv("SAARSIM_HOST_MEM_MB");
		who = "SAARSIM_HOST_MEM_MB";
		if (!value) {
			*mb = HM_DEFAULT_MB;
			return 0;
		}
	}
	char *end;
	errno = 0;
	unsigned long long v = strtoull(value, &end, 10);
	if (!*value || *value < '0' || *value > '9' || *end || errno || v < 1 || v > (1ull << 30))
		return diag_set(
		    d, who, 0, 0,
		    "'%.40s' is not a memory limit in MB (a whole number, 1 to 1073741824)", value);
	*mb = v;
	return 0;
}

int hm_check(const hm_est *e, uint64_t limit_mb, diag *d)
{
	if (e->total <= limit_mb << 20)
		return 0;
	static const char *const what[HM_NPARTS] = {
	    "program and world already loaded", "thread slots (chip.rtps x chip.threads_per_rtp)",
	    "L1 caches (memory.l1.*.size_kb)", "VMA on-board cache (memory.sdram.mb)",
	    "frame buffers (frame.width x frame.height)"};
	/* the parts from the largest down, those above 5% of the total */
	char parts[768] = "";
	size_t n = 0;
	int done[HM_NPARTS] = {0};
	for (int k = 0; k < HM_NPARTS; k++) {
		int best = -1;
		for (int p = 0; p < HM_NPARTS; p++)
			if (!done[p] && (best < 0 || e->part[p] > e->part[best]))
				best = p;
		done[best] = 1;
		if (e->part[best] * 20 < e->total)
			break;
		int m = snprintf(parts + n, sizeof parts - n, "%s%s %.0f MB", n ? ", " : "",
		                 what[best], (double)e->part[best] / (1 << 20));
		if (m < 0 || (size_t)m >= sizeof parts - n)
			break;
		n += (size_t)m;
	}
	return diag_set(d, "host memory", 0, 0,
	                "the run needs about %.0f MB (%s), over the limit of %llu MB; "
	                "--host-mem-limit MB or SAARSIM_HOST_MEM_MB raises it",
	                (double)e->total / (1 << 20), parts, (unsigned long long)limit_mb);
}
