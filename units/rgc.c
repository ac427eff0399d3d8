/*
 * rgc.c: tile order and hand-out (see rgc.h).
 */
#include "units/rgc.h"

#include <stdlib.h>
#include <string.h>

#include "kernel-ref/camera.h"

static uint64_t spread(uint32_t x)
{
	uint64_t v = x;
	v = (v | v << 16) & 0x0000FFFF0000FFFFull;
	v = (v | v << 8) & 0x00FF00FF00FF00FFull;
	v = (v | v << 4) & 0x0F0F0F0F0F0F0F0Full;
	v = (v | v << 2) & 0x3333333333333333ull;
	v = (v | v << 1) & 0x5555555555555555ull;
	return v;
}

typedef struct keyed {
	uint64_t key;
	uint32_t tile;
} keyed;

static int cmp_keyed(const void *a, const void *b)
{
	const keyed *x = a, *y = b;
	return x->key < y->key ? -1 : x->key > y->key;
}

int rgc_tiles(int width, int height)
{
	return ((width + TILE_W - 1) / TILE_W) * ((height + TILE_H - 1) / TILE_H);
}

int rgc_init(rgc *g, int width, int height, int order)
{
	memset(g, 0, sizeof *g);
	g->tiles_x = (width + TILE_W - 1) / TILE_W;
	g->tiles_y = (height + TILE_H - 1) / TILE_H;
	g->ntiles = g->tiles_x * g->tiles_y;
	g->order = malloc((size_t)g->ntiles * sizeof *g->order);
	if (!g->order)
		return -1;
	if (order != RGC_MORTON) {
		for (int i = 0; i < g->ntiles; i++)
			g->order[i] = (uint32_t)i;
		return 0;
	}
	keyed *k = malloc((size_t)g->ntiles * sizeof *k);
	if (!k)
		return -1;
	for (int i = 0; i < g->ntiles; i++) {
		uint32_t tx = (uint32_t)(i % g->tiles_x), ty = (uint32_t)(i / g->tiles_x);
		k[i] = (keyed){spread(tx) | spread(ty) << 1, (uint32_t)i};
	}
	qsort(k, (size_t)g->ntiles, sizeof *k, cmp_keyed);
	for (int i = 0; i < g->ntiles; i++)
		g->order[i] = k[i].tile;
	free(k);
	return 0;
}

void rgc_free(rgc *g)
{
	free(g->order);
	memset(g, 0, sizeof *g);
}

void rgc_reset(rgc *g)
{
	g->next = 0;
}

int rgc_next(rgc *g, int *tx, int *ty)
{
	if (g->next >= g->ntiles)
		return 0;
	uint32_t t = g->order[g->next++];
	*tx = (int)(t % (uint32_t)g->tiles_x);
	*ty = (int)(t / (uint32_t)g->tiles_x);
	return 1;
}
