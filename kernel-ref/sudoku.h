/*
 * sudoku.h: stable cooperative sample patterns and their Sudoku tiling
 * (Boulos et al., Interactive Distribution Ray Tracing, seed 000 §4).
 *
 * The order-4 Sudoku solution of the seed's Figure 14 (16 x 16 cells,
 * digits 0..15, each once per row, column and bordered 4 x 4 block) is
 * used twice:
 *  - patterns (§4.1): digit k's 16 cells form a Latin-square pattern that
 *    is stratified in 2D; sample i of pattern k is the cell of row i that
 *    holds k, at its centre ((c + 0.5) / 16, (i + 0.5) / 16). The 16
 *    patterns merged are the regular 256-point lattice ("cooperative
 *    sudoku");
 *  - tiling (§4.2): pixel (x, y) takes pattern S[y mod 16][x mod 16], so
 *    16 x 16-pixel tiles, each 4 x 4 block of pixels using all 16 patterns.
 * 4 samples per pixel use an order-2 solution's four 4-sample patterns in
 * the same way (pattern S[..] mod 4: each 4 x 4 pixel block of the tiling
 * holds each of them four times); 64 merge four order-4 patterns (k, k+4,
 * k+8, k+12); 1 sample per pixel takes, in the non-image dimensions, one
 * point of a 16-point arrangement with one point in every row, column and
 * 4 x 4 block of the lattice, its pattern picking which (so a 4 x 4 pixel
 * block's points are spread as at 16 samples), and the pixel centre on the
 * image plane (so a one-sample frame is today's pinhole frame).
 *
 * Every dimension of a ray's sample (image plane, lens, time, each light,
 * glossy reflection per depth) takes its own pattern: the tiling is read
 * at an offset and the samples in a permuted order that depend on the
 * dimension (with 1, 4 and 16 samples also on dim / 16: dimensions 16
 * apart would otherwise repeat), so the dimensions of one ray are not the
 * same point. A
 * sample is a pure function of (pixel, sample index, dimension, spp): the
 * same for any frame, thread count or schedule (stable for a still view,
 * §4: no scintillation).
 */
#ifndef SAAR_KREF_SUDOKU_H
#define SAAR_KREF_SUDOKU_H

#include <stdint.h>

#define SUDOKU_N 16 /* order 4: 16 x 16 cells */

/* The seed's Figure 14 solution, row by row. */
extern const uint8_t sudoku_grid[SUDOKU_N][SUDOKU_N];
/* The order-2 solution used for 4 samples per pixel. */
extern const uint8_t sudoku_grid2[4][4];

/* Sample dimensions (the first of each kind; a light or a glossy depth
 * adds its index). */
enum {
	SUDOKU_DIM_IMAGE = 0,
	SUDOKU_DIM_LENS = 1,
	SUDOKU_DIM_TIME = 2,
	SUDOKU_DIM_LIGHT = 3, /* + light index (< 16) */
	SUDOKU_DIM_GLOSS = 19 /* + reflection depth */
};

/* Is spp a supported sample count (1, 4, 16, 64)? */
int sudoku_spp_ok(int spp);

/* The pattern pixel (x, y) uses in dimension dim (0..15; with 4 samples
 * per pixel 0..3). */
int sudoku_pattern(uint32_t x, uint32_t y, int dim, int spp);

/* Sample s (0 <= s < spp) of pixel (x, y) in dimension dim, a point of
 * [0, 1)^2 into *u, *v. */
void sudoku_sample(uint32_t x, uint32_t y, int s, int dim, int spp, float *u, float *v);

#endif
