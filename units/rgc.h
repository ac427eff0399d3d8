/*
 * rgc.h: the ray-generation controller (SaarCOR seed 002 §4.1: "the RGC
 * tells each RGS which primary rays to generate").
 *
 * Cuts the frame into 8x8 tiles (one 64-ray packet each) and hands them
 * out, one per request, in scanline or Morton (Z-curve over tile
 * coordinates) order. The chip asks whenever a thread slot of an RTP is
 * free and that RTP has no secondary packet waiting.
 */
#ifndef SAAR_UNITS_RGC_H
#define SAAR_UNITS_RGC_H

#include <stdint.h>

typedef struct rgc {
	int tiles_x, tiles_y, ntiles, next;
	uint32_t *order; /* tile indices (ty * tiles_x + tx) in hand-out order */
} rgc;

/* Tiles of a width x height frame (partial tiles at the edges count):
 * what rgc_init cuts, for callers that plan before there is an RGC. */
int rgc_tiles(int width, int height);
/* Hand-out orders (chip.tile_order). */
enum rgc_order { RGC_SCANLINE, RGC_MORTON };

/* order: enum rgc_order. -1 when out of memory. */
int rgc_init(rgc *g, int width, int height, int order);
void rgc_free(rgc *g);
/* Starts a new frame. */
void rgc_reset(rgc *g);
/* The next tile; 0 when all are handed out. */
int rgc_next(rgc *g, int *tx, int *ty);

#endif
