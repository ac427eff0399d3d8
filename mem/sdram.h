/*
 * sdram.h: on-board SDRAM timing in its own clock domain.
 *
 * Models SDR SDRAM as on the standard SaarCOR board (seed 002 §4.7: 64 MB,
 * 128 bits at 133 MHz = 2 GB/s; the timings are PC133-like and assumed):
 * banks with one open row each (open-page policy: a row stays open until a
 * request to another row of the same bank), ACTIVATE/READ/WRITE/PRECHARGE
 * with tRCD, CL, tRP, tRAS, and one shared data bus on which transfers
 * serialize. Requests are served in the order sdram_access is called (the
 * memory interface, mem/memif.c, does the arbitration); each call returns
 * the tick its last data beat completes.
 *
 * As in DRAMsim3, timing derivation is apart from state: sdram_derive turns
 * the parameters into a table of tick delays once (sdram_timing); the sdram
 * object holds only bank state (open row, earliest column command, earliest
 * precharge) and the data bus's busy-until tick.
 *
 * Per segment (the part of a request inside one row), from the first SDRAM
 * edge c >= max(t, bank ready):
 *   row hit       column command at c
 *   bank idle     ACTIVATE at c, column at c + tRCD
 *   row conflict  PRECHARGE at p = max(c, ACT + tRAS, last data end),
 *                 ACTIVATE at p + tRP, column at ACT + tRCD
 *   data          reads from column + CL, writes with the column command,
 *                 but never before the data bus is free; beats =
 *                 ceil(bytes / bus bytes) rounded up to the burst length.
 * So on an idle bus a read row hit takes CL + beats cycles, a read to an
 * idle bank tRCD + CL + beats, a row conflict tRP + tRCD + CL + beats.
 * Not modelled (assumed negligible, documented in docs/memory.md): refresh,
 * tWR/tRRD/tCCD, command-bus conflicts.
 */
#ifndef SAAR_MEM_SDRAM_H
#define SAAR_MEM_SDRAM_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "mem/memport.h"
#include "sim/core/engine.h"

#define SDRAM_MAX_BANKS 64

enum sdram_map { SDRAM_MAP_ROW_BANK_COL, SDRAM_MAP_BANK_ROW_COL };

typedef struct sdram_params {
	uint64_t bytes;     /* capacity */
	double clock_mhz;   /* SDRAM clock */
	uint32_t bus_bits;  /* data bus width */
	uint32_t banks;     /* power of two */
	uint32_t row_bytes; /* bytes of one row of one bank across the bus; power of two */
	uint32_t cl, trcd, trp, tras; /* SDRAM cycles */
	uint32_t burst;               /* beats per column command (burst length) */
	int mapping;                  /* enum sdram_map: address bits, MSB to LSB */
} sdram_params;

#define SDRAM_BEATS_MEMO 129

/* Delays in ticks, computed once from the parameters. */
typedef struct sdram_timing {
	eng_clock clk;
	uint64_t cl, trcd, trp, tras;
	uint32_t bus_bytes;
	uint32_t col_bits, bank_bits; /* address decoding */
	/* sdram_beats of 0 .. SDRAM_BEATS_MEMO - 1 bytes, worked out once: the
	 * memory system's requests are lines of a few bytes, and the two
	 * divisions per request showed in the profile (docs/PERFORMANCE.md,
	 * "Target 2") */
	uint32_t beats_of[SDRAM_BEATS_MEMO];
} sdram_timing;

typedef struct sdram_bank {
	uint64_t open_row; /* SDRAM_NO_ROW when precharged */
	uint64_t act;      /* tick of the last ACTIVATE */
	uint64_t col_ok;   /* earliest next column command */
	uint64_t pre_ok;   /* earliest PRECHARGE (tRAS, end of data) */
} sdram_bank;

#define SDRAM_NO_ROW UINT64_MAX

typedef struct sdram_stats {
	uint64_t reads, writes, read_bytes, write_bytes;
	uint64_t row_hits, row_empty, row_conflicts; /* per segment */
	uint64_t busy_ticks;                         /* data bus occupied */
	uint64_t beats;
} sdram_stats;

typedef struct sdram {
	sdram_params p;
	sdram_timing t;
	sdram_bank bank[SDRAM_MAX_BANKS];
	uint64_t bus_free; /* data bus busy until */
	sdram_stats s;
	const mem_obs *obs; /* sees every data burst (memport.h); NULL: none */
} sdram;

/* Checks the parameters (errors name "memory.sdram") and derives timing. */
int sdram_derive(const sdram_params *p, sdram_timing *t, diag *d);
int sdram_init(sdram *s, const sdram_params *p, diag *d);
/* Parses "row:bank:col" / "bank:row:col"; -1 if unknown. */
int sdram_mapping_parse(const char *s);
const char *sdram_mapping_name(int m);

/* Decodes a byte address (taken modulo the capacity). Inline: the memory
 * interface decodes every request it is given. */
static inline void sdram_decode(const sdram *s, uint64_t addr, uint32_t *bank, uint64_t *row,
                                uint32_t *col)
{
	if (addr >= s->p.bytes) /* a division only where it changes addr */
		addr %= s->p.bytes;
	*col = (uint32_t)(addr & (s->p.row_bytes - 1));
	uint64_t hi = addr >> s->t.col_bits;
	if (s->p.mapping == SDRAM_MAP_BANK_ROW_COL) {
		uint64_t rows = s->p.bytes / s->p.banks / s->p.row_bytes;
		*row = hi % rows;
		*bank = (uint32_t)((hi / rows) & (s->p.banks - 1));
	} else {
		*bank = (uint32_t)(hi & (s->p.banks - 1));
		*row = hi >> s->t.bank_bits;
	}
}

/* One request issued at tick t: returns the tick its last beat ends.
 * *data_start (may be NULL) receives the tick its first beat starts. */
uint64_t sdram_access(sdram *s, uint64_t t, uint64_t addr, uint32_t bytes, int write,
                      uint64_t *data_start);
/* The same with addr's bank and row already decoded (sdram_decode's
 * answer: the memory interface decodes each request once, at submit). */
uint64_t sdram_access_in(sdram *s, uint64_t t, uint64_t addr, uint32_t bytes, int write,
                         uint64_t *data_start, uint32_t bank, uint64_t row);
/* Beats a transfer of bytes occupies (bus width, burst rounding). */
uint64_t sdram_beats(const sdram *s, uint32_t bytes);
/* Peak bandwidth in bytes per second. */
double sdram_peak_bw(const sdram *s);

#endif
