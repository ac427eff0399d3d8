/*
 * warming.h: stored warming (sampling.warming: stored; docs/fidelity.md,
 * "Stored warming"): the functional chip's state at checkpoints through
 * the frame, written once by a warming run and restored by sampled runs,
 * which then simulate only their detailed regions.
 *
 * A warming run is functional processing of the whole frame replaying the
 * packet record (traces/pktrec.h), stopped at every `g_light` tiles handed
 * out. There it writes a light checkpoint: the resource demand so far
 * (chip_demand) and every counter functional processing moves (the stats
 * registry, the memory port's counts, shade_counts, the hierarchy's
 * counters). Once in every `g_full` tiles it also writes a full checkpoint:
 * each thread slot's packet stream and where in it the slot stopped, the
 * RTP queues, the L1s and VMA tag cache whole, and the sets of the VMA
 * on-board cache changed since the full checkpoint before (that cache is
 * 64 MB on board; a copy per checkpoint would be most of the file).
 *
 * Full checkpoint k sits at k x g_full plus a jitter on the light grid
 * below g_full, fixed by k (wm_full_tile; none for k = 0). On a grid of
 * plain multiples every region would start at the same place in the tile
 * order's blocks (192 tiles: three Morton blocks of 8x8 tiles on
 * Conference), and its unit would always sample the same few positions:
 * that biased the estimates there (docs/fidelity.md); the jitter spreads the positions
 * as a systematic sample's are.
 *
 * A sampled run restores the full checkpoint where a region starts: the
 * caches, slots and queues become the warming run's there, and every
 * counter gains what the warming run counted between the last region's
 * end (a light checkpoint) and this start. Regions therefore start on
 * full checkpoints and end on the light grid. The on-board cache is rolled
 * forward through the diffs into a warm image kept by the reader, and
 * only the sets a diff or the region changed are copied into the chip.
 *
 * With done records (sampling.jump drain or mixed; their own file) the
 * warming run also splits its counts by tile: every step's counts go to
 * the tile its packet descends from (wm_attr), and the done record at a
 * light checkpoint holds the work of the tiles before it, whenever the
 * warming run did it. A sampled run that drained a region's packets (every
 * tile before the checkpoint finished) adds from there only the work of
 * the tiles after them; from the plain light record it would count again
 * what the warming run's packets in flight there still had to do.
 *
 * The file format is this build's own (its key names the program, the
 * frame and every config key functional processing reads); a file that
 * does not match the chip is rebuilt.
 */
#ifndef SAAR_SIM_WARMING_H
#define SAAR_SIM_WARMING_H

#include <stddef.h>
#include <stdint.h>

#include "mem/memport.h"
#include "sim/config.h"
#include "units/unit_table.h"

struct chip;

/* Full checkpoints per frame (about: one in each 1/WM_FULL_PER_FRAME of
 * it, rounded to the light grid); the config's text states it. */
#define WM_FULL_PER_FRAME CFG_WARM_FULL_PER_FRAME

/* Resource demands per light checkpoint (chip.h RES_N: the unit kinds,
 * the L1s, SDRAM and host bus). */
#define WM_NDEM (UNIT_NKINDS + MEM_NTYPES + 2)

/* The tile of full checkpoint k (below the tile count or not): k x g_full
 * plus its jitter, a multiple of g_light below g_full (g_full a multiple
 * of g_light). */
int wm_full_tile(int g_light, int g_full, int k);
/* Whether a full checkpoint sits at tile (wm_full_tile of tile / g_full). */
int wm_is_full(int g_light, int g_full, int tile);

/* ---- writing (the warming run) ---- */

typedef struct wm_writer {
	int frames, ntiles, g_light, g_full, nlight, nfull;
	size_t ncnt, lsize;
	uint64_t **cnt; /* the chip's counters */
	uint8_t *light; /* frames x nlight records of lsize bytes */
	uint64_t *foff; /* frames x nfull offsets into full */
	uint8_t *full;  /* full checkpoints, appended */
	size_t nfullb, capfull;
	/* the work of each tile's packets (wm_attr): per frame and light
	 * bucket (tiles [b g_light, (b + 1) g_light) in hand-out order), the
	 * on-board-cache hit ticks and every counter they moved; the values
	 * at the last attribution; per tile (row-major), its hand-out index */
	uint64_t *done, *snap;
	int32_t *handout;
	const int32_t *from; /* the packet record's parents (pktrec.from) */
	uint32_t npk;
	int32_t *tile_of; /* per stream: its primary's tile (-1: damaged chain) */
	/* per frame and light checkpoint, the hand-out index of the oldest
	 * tile in flight (wm_oldest); per tile (row-major), its hand-out
	 * index in the RGC's order */
	int32_t *oldest, *pos;
	/* the counters as runs of adjacent ones (cnt[at..at+n) at src[0..n)):
	 * wm_attr reads them as arrays, not pointer by pointer */
	struct wm_run {
		const uint64_t *src;
		uint32_t at, n;
	} * runs;
	size_t nruns;
	int failed;
} wm_writer;

/* For chip c (functional, replaying a packet record; every slot's
 * packet must be a replayed one): checkpoints every g_light tiles and
 * every g_full (a multiple of g_light) in full; done: also the done
 * records (wm_attr, wm_demand_done). -1 when out of memory or the chip's
 * caches cannot be stored. */
int wm_writer_init(wm_writer *w, struct chip *c, int g_light, int g_full, int done);
/* A light checkpoint at hand-out index tile of frame (tile: a multiple
 * of g_light, or the frame's tile count), dem: chip_demand now. */
void wm_put_light(wm_writer *w, struct chip *c, int frame, int tile, const double *dem);
/* A full checkpoint at tile (wm_is_full, below the tile count); the
 * chip's slots must be stopped between steps. */
void wm_put_full(wm_writer *w, struct chip *c, int frame, int tile);
/* Packet stream rec, a tile's primary packet, was handed out as index
 * `at` of the frame. */
void wm_attr_take(wm_writer *w, struct chip *c, int32_t rec, int at);
/* What the chip counted since the last attribution goes to the tile of
 * packet stream rec (its primary's, through the record's parents; rec < 0:
 * nobody's, it stays with the next). The warming run's functional
 * driver (mode_func_range) calls it after every hand-out and step. */
void wm_attr(wm_writer *w, struct chip *c, int32_t rec);
/* The stored form, one malloc'd block. -1 when out of memory. */
int wm_writer_finish(wm_writer *w, struct chip *c, void **out, size_t *n);
void wm_writer_free(wm_writer *w);

/* ---- reading (sampled runs) ---- */

typedef struct wm {
	const uint8_t *b;
	size_t n;
	int frames, ntiles, g_light, g_full, nlight, nfull;
	size_t ncnt, lsize;
	uint64_t **cnt;  /* the chip's counters */
	uint8_t *is_max; /* per counter: a maximum, not a sum */
	int has_done;    /* the done records are stored (wm_demand_done) */
	uint64_t *prev;  /* the counters at the last region's end */
	uint64_t prev_l2hit;
	uint64_t oldest_at; /* the oldest-tile section (wm_oldest) */
	/* the counters a skip takes back (wm_skip), and their values at the
	 * chip's last restore (wm_mark), with the merge ticks then */
	uint64_t **sk, *mark;
	size_t nsk;
	double mark_merge;
	/* the on-board cache at the last full checkpoint applied (each set
	 * in its own checkpoint form, l2set bytes), sets to copy into the
	 * chip at the next restore, and that checkpoint */
	uint8_t *l2img;
	size_t l2set;
	uint64_t *l2pend;
	int next_full;
} wm;

/* Takes a stored block for chip c (kept by the caller until wm_close).
 * -1 when it does not fit the chip (damaged, other geometry) or out of
 * memory. */
int wm_open(wm *r, const void *b, size_t n, struct chip *c);
void wm_close(wm *r);
/* The light checkpoint at tile of frame (on the light grid, or the tile
 * count): the demand so far (WM_NDEM) and *l2hit, the on-board-cache hit
 * ticks so far. */
const double *wm_demand(const wm *r, int frame, int tile, uint64_t *l2hit);
/* As wm_demand, but of the work of the tiles before tile, whenever the
 * warming run did it (their packets in flight at the checkpoint
 * finished): the warming run's counts split by tile (wm_attr). */
const double *wm_demand_done(const wm *r, int frame, int tile, uint64_t *l2hit);
/* Whether the warming run had finished every packet of the tiles before
 * tile `at` by the light checkpoint at tile x: its counts at x hold all
 * of their work (wm_demand_done's counts at `at`), counter by counter. */
int wm_done_by(const wm *r, int frame, int at, int x);
/* The hand-out index of the oldest tile whose packets the warming run
 * still had in flight at the light checkpoint at tile of frame (tile when
 * it had none): it had finished every packet of the tiles before `at` by
 * then when this is at least `at`. */
int wm_oldest(const wm *r, int frame, int tile);
/* Chip c took the warming run's state (a restore, or the frame's start):
 * the values of the counters a skip takes back, kept. */
void wm_mark(wm *r, struct chip *c);
/* A skip (sampling.jump skip): the chip's work since its last wm_mark,
 * which the light checkpoint at tile of frame followed, is handed to the
 * warming run. The counters functional processing moves, and the timed
 * models' traffic (hier_traffic_ptrs), go back to their marked values, and
 * the next restore adds what the warming run counted from the checkpoint
 * at tile on: from one restore to the next the counts are the warming
 * run's. The timing's own counts (waits, stalls, row hits) stay. */
void wm_skip(wm *r, struct chip *c, int frame, int tile);
/* A region ended at tile (on the light grid): the next restore adds what
 * the warming run counted from there; done: the chip finished every
 * packet of the tiles before it (a drain), and the next restore adds only
 * the work of the tiles from there on (wm_demand_done's counts). */
void wm_region_end(wm *r, int frame, int tile, int done);
/* The tile of the last full checkpoint at or before tile (0 for tiles
 * before the first jittered one), and of the first at or after it (the
 * tile count when there is none). */
int wm_full_below(const wm *r, int tile);
int wm_full_above(const wm *r, int tile);
/* Sets chip c (no event pending, every MSHR free) to the full checkpoint
 * at tile of frame (wm_full_below of it, at or after the last one
 * restored);
 * merge_share: of the warming run's on-board-cache hit ticks since the
 * last region's end, the share a timed chip merges
 * (hier_stats.func_sdram_merge_ticks). -1 when the block is damaged. */
int wm_restore(wm *r, struct chip *c, int frame, int tile, double merge_share);

#endif
