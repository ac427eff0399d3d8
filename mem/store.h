/*
 * store.h: the bytes behind the memory system (docs/memory.md, "Data").
 *
 * The memory holding the scene: on-board SDRAM without the VMA, host memory
 * with it (the on-board SDRAM is then the VMA's cache of it, mem/vma.h).
 * Addresses [0, image_size) hold the memory image (docs/memory-map.md),
 * everything above reads as zero until written (the stack spill area).
 *
 * The image is not copied: the store reads the image's own bytes (the
 * host's world, which kernel-ref renders its check frame from) until a
 * page is written; a written page is a private copy, 4 KB at a time. So a
 * spill write or a test that damages the board's copy of a triangle
 * changes what the chip reads back, never kernel-ref's image. Pages are
 * found through a two-level table (a 1 GB directory of 4 KB page
 * pointers), allocated as pages are first written: a run of a million
 * thread slots has 64 GB of spill addresses and touches none of them
 * unless its stack spills.
 */
#ifndef SAAR_MEM_STORE_H
#define SAAR_MEM_STORE_H

#include <stddef.h>
#include <stdint.h>

#define MS_PAGE_BITS 12u /* 4 KB pages */
#define MS_DIR_BITS  18u /* pages per directory: 1 GB */
#define MS_PAGE      (1u << MS_PAGE_BITS)

typedef struct mem_store mem_store;
struct mem_store {
	const uint8_t *image; /* the memory image's bytes, read in place */
	uint64_t image_size;
	uint8_t ***dir; /* per 1 GB: its page table (NULL: no page written) */
	uint64_t ndir;
	uint64_t pages; /* private pages */
	uint64_t low;   /* the lowest private page's address (UINT64_MAX: none) */
	int oom;        /* a write found no memory for its page (the write is lost) */
	/* Test hook: called after every write (the written range), so a test
	 * can damage what was stored (a spilled stack entry). NULL: none. */
	void (*on_write)(void *ctx, mem_store *s, uint64_t addr, uint32_t bytes);
	void *on_write_ctx;
};

/* A store over image[0, image_size) (not copied; it must outlive the
 * store) with addresses up to `space` (the end of the spill area). */
int ms_init(mem_store *s, const uint8_t *image, uint64_t image_size, uint64_t space);
void ms_free(mem_store *s);
/* Host bytes of the directory for `space` bytes of addresses, and of a
 * private page (sim/hostmem.c). */
uint64_t ms_host_bytes(uint64_t space, uint64_t pages);

/* Copies bytes [addr, addr + n) into dst; addresses past the store read as
 * zero. */
void ms_read_any(const mem_store *s, uint64_t addr, uint32_t n, void *dst);
/* The image's own bytes for [addr, addr + n) when the store reads them
 * there (inside the image, no byte in a written page), else NULL. A
 * write makes a private copy of its page and the host changes the image
 * only between frames (sim/chip.c, chip_anim_update), when no read is in
 * flight, so until the frame ends these bytes stay what ms_read returns
 * now: a reader may take them later (mem/hier.c, an L1 fill). */
static inline const uint8_t *ms_image_at(const mem_store *s, uint64_t addr, uint32_t n)
{
	if (addr < s->image_size && n <= s->image_size - addr && addr + n <= s->low)
		return s->image + addr;
	return NULL;
}
static inline void ms_read(const mem_store *s, uint64_t addr, uint32_t n, void *dst)
{
	/* the usual case: image bytes, no page written, within one page */
	const uint8_t *p = ms_image_at(s, addr, n);
	if (p && (addr & (MS_PAGE - 1)) + n <= MS_PAGE) {
		__builtin_memcpy(dst, p, n);
		return;
	}
	ms_read_any(s, addr, n, dst);
}
/* Stores n bytes of src at addr (addresses past the store are dropped);
 * src NULL: a write without data (a replayed spill), which changes
 * nothing. -1 when out of memory (s->oom is set). */
int ms_write(mem_store *s, uint64_t addr, uint32_t n, const void *src);

#endif
