/*
 * sudoku.c: cooperative Sudoku sample patterns and Sudoku tiling (see
 * sudoku.h; seed 000 §4.1 and §4.2).
 */
#include "kernel-ref/sudoku.h"

/* Seed 000, Figure 14: the order-4 solution used for both the sample
 * patterns and the tiling. */
const uint8_t sudoku_grid[SUDOKU_N][SUDOKU_N] = {
    {9, 1, 3, 8, 13, 14, 10, 11, 2, 15, 12, 0, 5, 7, 6, 4},
    {11, 6, 5, 15, 3, 9, 2, 8, 10, 1, 4, 7, 14, 13, 0, 12},
    {0, 12, 14, 10, 7, 4, 6, 1, 5, 3, 9, 13, 15, 2, 8, 11},
    {2, 13, 4, 7, 12, 0, 15, 5, 14, 6, 8, 11, 1, 3, 10, 9},
    {10, 5, 2, 12, 15, 8, 11, 9, 4, 13, 6, 14, 7, 0, 1, 3},
    {7, 0, 9, 3, 5, 6, 13, 14, 1, 2, 10, 15, 11, 12, 4, 8},
    {8, 14, 11, 6, 1, 2, 3, 4, 9, 0, 7, 12, 13, 10, 15, 5},
    {4, 15, 13, 1, 0, 12, 7, 10, 3, 5, 11, 8, 2, 6, 9, 14},
    {6, 8, 0, 9, 10, 11, 4, 13, 7, 14, 15, 3, 12, 5, 2, 1},
    {12, 3, 15, 13, 2, 1, 14, 6, 0, 4, 5, 10, 8, 9, 11, 7},
    {5, 7, 1, 2, 8, 15, 12, 3, 11, 9, 13, 6, 0, 4, 14, 10},
    {14, 4, 10, 11, 9, 5, 0, 7, 8, 12, 1, 2, 6, 15, 3, 13},
    {1, 2, 7, 5, 14, 13, 8, 0, 15, 10, 3, 9, 4, 11, 12, 6},
    {15, 9, 8, 4, 6, 10, 5, 12, 13, 11, 0, 1, 3, 14, 7, 2},
    {13, 10, 6, 14, 11, 3, 1, 15, 12, 7, 2, 4, 9, 8, 5, 0},
    {3, 11, 12, 0, 4, 7, 9, 2, 6, 8, 14, 5, 10, 1, 13, 15},
};

/* An order-2 solution (every row, column and 2 x 2 quadrant holds 0..3
 * once), as the seed's Figure 12 illustrates. */
const uint8_t sudoku_grid2[4][4] = {
    {0, 1, 2, 3},
    {2, 3, 0, 1},
    {1, 0, 3, 2},
    {3, 2, 1, 0},
};

int sudoku_spp_ok(int spp)
{
	return spp == 1 || spp == 4 || spp == 16 || spp == 64;
}

/* dim / 16 where the offsets and orders below would repeat every 16
 * dimensions (n <= 16: 1, 4 and 16 samples), else 0: with 1, 4 and 16
 * samples dimension d + 16 (a glossy bounce, a 14th light) had been the
 * very points of dimension d (a light, the image plane); 64 samples never
 * repeated them and keep their points. */
static int dim_wrap(int dim, int spp)
{
	return spp <= 16 ? dim / 16 : 0;
}

int sudoku_pattern(uint32_t x, uint32_t y, int dim, int spp)
{
	/* each dimension reads the tiling at its own offset, a whole number
	 * of bordered blocks, so each 4x4 pixel block still takes all 16
	 * patterns (cooperative in every dimension) */
	uint32_t ox = 4u * (uint32_t)(dim % 4),
	         oy = 4u * (uint32_t)((dim + dim / 4 + dim_wrap(dim, spp)) % 4);
	int k = sudoku_grid[(y + oy) % SUDOKU_N][(x + ox) % SUDOKU_N];
	return spp == 4 ? k % 4 : k;
}

/* The column of row i of an n x n grid g (row stride n) that holds k. */
static int col_of(const uint8_t *g, int n, int i, int k)
{
	for (int c = 0; c < n; c++)
		if (g[i * n + c] == k)
			return c;
	return 0; /* never: every row holds every digit */
}

void sudoku_sample(uint32_t x, uint32_t y, int s, int dim, int spp, float *u, float *v)
{
	if (spp == 1 && dim == SUDOKU_DIM_IMAGE) { /* the pinhole frame's pixel centre */
		*u = *v = 0.5f;
		return;
	}
	/* the dimension's own order of its samples: s -> (a s + c) mod n, a odd */
	int n = spp == 1 ? SUDOKU_N : spp;
	int a = (2 * dim + 1) % n, c = (7 * dim + dim_wrap(dim, spp)) % n;
	int k = sudoku_pattern(x, y, dim, spp);
	int sp = (s * a + c) % n;
	if (spp == 1) {
		/* One sample per pixel: the 16 pixels of a 4x4 block (patterns
		 * 0..15) take one point each of the 16-point arrangement with one
		 * point in every row, every column and every 4x4 block of the
		 * lattice (row r, column 4 (r mod 4) + r / 4), the pixel's pattern
		 * picking its row in the dimension's own order: the block's
		 * points are spread as its patterns' are at 16 samples. (Sample 0
		 * of the pixel's pattern had put every pixel in one row: every
		 * lens sample on one ring, every light sample on one line off
		 * the light's centre, every glossy ray at one angle.) */
		int r = (k * a + c) % SUDOKU_N;
		*u = ((float)(4 * (r % 4) + r / 4) + 0.5f) / (float)SUDOKU_N;
		*v = ((float)r + 0.5f) / (float)SUDOKU_N;
		return;
	}
	if (n == 4) {
		int col = col_of(&sudoku_grid2[0][0], 4, sp, k);
		*u = ((float)col + 0.5f) / 4.0f;
		*v = ((float)sp + 0.5f) / 4.0f;
		return;
	}
	int i = sp % SUDOKU_N;
	k = (k + 4 * (sp / SUDOKU_N)) % SUDOKU_N; /* 64: patterns k, k+4, k+8, k+12 */
	int col = col_of(&sudoku_grid[0][0], SUDOKU_N, i, k);
	*u = ((float)col + 0.5f) / (float)SUDOKU_N;
	*v = ((float)i + 0.5f) / (float)SUDOKU_N;
}
