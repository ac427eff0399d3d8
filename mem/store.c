/*
 * store.c: the bytes behind the memory system (see store.h).
 */
#include "mem/store.h"

#include <stdlib.h>
#include <string.h>

#define DIR_SPAN  (MS_PAGE_BITS + MS_DIR_BITS)
#define DIR_PAGES (1u << MS_DIR_BITS)

int ms_init(mem_store *s, const uint8_t *image, uint64_t image_size, uint64_t space)
{
	memset(s, 0, sizeof *s);
	s->image = image;
	s->image_size = image_size;
	s->low = UINT64_MAX;
	if (space < image_size)
		space = image_size;
	s->ndir = (space + (1ull << DIR_SPAN) - 1) >> DIR_SPAN;
	s->dir = calloc(s->ndir ? s->ndir : 1, sizeof *s->dir);
	return s->dir ? 0 : -1;
}

void ms_free(mem_store *s)
{
	for (uint64_t d = 0; s->dir && d < s->ndir; d++) {
		if (!s->dir[d])
			continue;
		for (uint32_t i = 0; i < DIR_PAGES; i++)
			free(s->dir[d][i]);
		free(s->dir[d]);
	}
	free(s->dir);
	memset(s, 0, sizeof *s);
}

uint64_t ms_host_bytes(uint64_t space, uint64_t pages)
{
	uint64_t ndir = (space + (1ull << DIR_SPAN) - 1) >> DIR_SPAN;
	uint64_t tables = pages < ndir ? pages : ndir;
	return ndir * sizeof(void *) + tables * DIR_PAGES * sizeof(void *) + pages * MS_PAGE;
}

/* The private page holding addr, or NULL (the image's bytes, or zeros). */
static inline uint8_t *page_of(const mem_store *s, uint64_t addr)
{
	uint64_t d = addr >> DIR_SPAN;
	if (d >= s->ndir || !s->dir[d])
		return NULL;
	return s->dir[d][(addr >> MS_PAGE_BITS) & (DIR_PAGES - 1)];
}

/* Bytes [addr, addr + n) of one page: the private copy, else the image,
 * zero past it. */
static void read_in_page(const mem_store *s, uint64_t addr, uint32_t n, uint8_t *dst)
{
	const uint8_t *pg = page_of(s, addr);
	if (pg) {
		memcpy(dst, pg + (addr & (MS_PAGE - 1)), n);
		return;
	}
	uint32_t have = 0;
	if (addr < s->image_size)
		have = s->image_size - addr < n ? (uint32_t)(s->image_size - addr) : n;
	if (have)
		memcpy(dst, s->image + addr, have);
	if (have < n)
		memset(dst + have, 0, n - have);
}

void ms_read_any(const mem_store *s, uint64_t addr, uint32_t n, void *dst)
{
	uint8_t *o = dst;
	while (n) {
		uint32_t room = MS_PAGE - (uint32_t)(addr & (MS_PAGE - 1)), k = n < room ? n : room;
		if (addr > UINT64_MAX - k) { /* past every address: zeros */
			memset(o, 0, n);
			return;
		}
		read_in_page(s, addr, k, o);
		addr += k;
		o += k;
		n -= k;
	}
}

/* The private page of addr, made from the image's bytes (or zeros) on
 * the first write; NULL past the store or out of memory. */
static uint8_t *own_page(mem_store *s, uint64_t addr)
{
	uint64_t d = addr >> DIR_SPAN;
	if (d >= s->ndir)
		return NULL;
	if (!s->dir[d] && !(s->dir[d] = calloc(DIR_PAGES, sizeof **s->dir)))
		return NULL;
	uint8_t **slot = &s->dir[d][(addr >> MS_PAGE_BITS) & (DIR_PAGES - 1)];
	if (!*slot) {
		uint8_t *pg = malloc(MS_PAGE);
		if (!pg)
			return NULL;
		read_in_page(s, addr & ~(uint64_t)(MS_PAGE - 1), MS_PAGE, pg);
		*slot = pg;
		s->pages++;
		if ((addr & ~(uint64_t)(MS_PAGE - 1)) < s->low)
			s->low = addr & ~(uint64_t)(MS_PAGE - 1);
	}
	return *slot;
}

int ms_write(mem_store *s, uint64_t addr, uint32_t n, const void *src)
{
	if (!src)
		return 0;
	const uint8_t *in = src;
	uint64_t a = addr;
	for (uint32_t left = n; left;) {
		uint32_t room = MS_PAGE - (uint32_t)(a & (MS_PAGE - 1)),
		         k = left < room ? left : room;
		if (a >> DIR_SPAN >= s->ndir)
			break; /* past the store: dropped */
		uint8_t *pg = own_page(s, a);
		if (!pg) {
			s->oom = 1;
			return -1;
		}
		memcpy(pg + (a & (MS_PAGE - 1)), in, k);
		a += k;
		in += k;
		left -= k;
	}
	if (s->on_write)
		s->on_write(s->on_write_ctx, s, addr, n);
	return 0;
}
