/*
 * gridimage.h: the chip's memory image of a uniform grid (grid.h;
 * docs/memory-map.md, "Uniform grid").
 *
 * The frame's image (memimage.h) comes first, unchanged: the grid's lists
 * name its triangle records and the shader reads its records as for the
 * kd-tree. After it, each part on a 4 KB boundary:
 *
 *  - the cells' list offsets: ncells + 1 uint32, cell c's entries are list
 *    entries [off[c], off[c + 1]) (cells in grid_cell order);
 *  - the cell lists: nrefs uint32, each a triangle record's address;
 *  - the macrocell flags: one byte per block (grid.h's order), 1 when a
 *    cell of the block holds a triangle; none without macrocells.
 *
 * Little-endian as the host is. The chip's registers (grid_regs) hold the
 * three bases and the grid's header (resolution, box, scale, margin,
 * parameters): the grid unit reads everything else.
 */
#ifndef SAAR_KREF_GRIDIMAGE_H
#define SAAR_KREF_GRIDIMAGE_H

#include <stdint.h>
#include <string.h>

#include "kernel-ref/grid.h"

#define GIMG_ALIGN      4096u
#define GIMG_CELL_BYTES 4u /* one list offset; a cell's range is two (8 bytes) */
#define GIMG_REF_BYTES  4u
#define GIMG_FLAG_BYTES 1u

typedef struct grid_image {
	uint8_t *bytes;
	uint64_t size;
	uint64_t cells_base; /* the list offsets */
	uint64_t refs_base;  /* the cell lists */
	uint64_t macro_base; /* the macrocell flags (0 bytes without macrocells) */
	uint64_t grid_bytes; /* the grid's parts: the per-frame update of an animation */
} grid_image;

/* The image of g (built over world) after world's bytes; -1 (diag) when out
 * of memory. */
int gimg_build(grid_image *im, const grid *g, const mimg *world, diag *d);
void gimg_free(grid_image *im);
/* The size gimg_build's image would have (nothing allocated). */
uint64_t gimg_size(const grid *g, const mimg *world);

/* A cell's range as the 8 bytes at cells_base + 4 c return it. */
static inline void gimg_cell_decode(const uint8_t *b, uint32_t *first, uint32_t *end)
{
	memcpy(first, b, 4);
	memcpy(end, b + 4, 4);
}

#endif
