/*
 * gridimage.c: the chip's memory image of a uniform grid (see
 * gridimage.h).
 */
#include "kernel-ref/gridimage.h"

#include <stdlib.h>

static uint64_t ncells(const grid *g)
{
	return (uint64_t)g->n[0] * (uint64_t)g->n[1] * (uint64_t)g->n[2];
}

static uint64_t nmacro(const grid *g)
{
	return g->macro ? (uint64_t)g->mn[0] * (uint64_t)g->mn[1] * (uint64_t)g->mn[2] : 0;
}

/* The bases of the parts after world's bytes; the image's size. */
static uint64_t layout(const grid *g, const mimg *world, grid_image *im)
{
	im->cells_base = mimg_align_up(world->size, GIMG_ALIGN);
	im->refs_base =
	    mimg_align_up(im->cells_base + (ncells(g) + 1) * GIMG_CELL_BYTES, GIMG_ALIGN);
	im->macro_base =
	    mimg_align_up(im->refs_base + (uint64_t)g->nrefs * GIMG_REF_BYTES, GIMG_ALIGN);
	return im->macro_base + nmacro(g) * GIMG_FLAG_BYTES;
}

uint64_t gimg_size(const grid *g, const mimg *world)
{
	grid_image im;
	return layout(g, world, &im);
}

int gimg_build(grid_image *im, const grid *g, const mimg *world, diag *d)
{
	memset(im, 0, sizeof *im);
	im->size = layout(g, world, im);
	im->grid_bytes = im->size - im->cells_base;
	if (im->size > SIZE_MAX || !(im->bytes = calloc(1, (size_t)im->size)))
		return diag_set(d, "grid", 0, 0, "out of memory for the grid's image (%llu bytes)",
		                (unsigned long long)im->size);
	memcpy(im->bytes, world->bytes, world->size);
	/* uint32 little-endian, as the host is (docs/memory-map.md, Rules) */
	memcpy(im->bytes + im->cells_base, g->first, (ncells(g) + 1) * GIMG_CELL_BYTES);
	memcpy(im->bytes + im->refs_base, g->refs, (size_t)g->nrefs * GIMG_REF_BYTES);
	if (g->macro)
		memcpy(im->bytes + im->macro_base, g->macro, nmacro(g));
	return 0;
}

void gimg_free(grid_image *im)
{
	free(im->bytes);
	memset(im, 0, sizeof *im);
}
