/*
 * sdram.c: SDRAM bank state and data-bus timing (see sdram.h).
 *
 * sdram_derive is the only place parameters become delays; sdram_access
 * only walks bank state. All times are engine ticks (ps) on SDRAM edges.
 */
#include "mem/sdram.h"

#include <string.h>

static int is_pow2(uint64_t x)
{
	return x && !(x & (x - 1));
}

static uint32_t log2u(uint64_t x)
{
	uint32_t n = 0;
	while ((1ull << n) < x)
		n++;
	return n;
}

int sdram_mapping_parse(const char *s)
{
	if (!strcmp(s, "row:bank:col"))
		return SDRAM_MAP_ROW_BANK_COL;
	if (!strcmp(s, "bank:row:col"))
		return SDRAM_MAP_BANK_ROW_COL;
	return -1;
}

const char *sdram_mapping_name(int m)
{
	return m == SDRAM_MAP_BANK_ROW_COL ? "bank:row:col" : "row:bank:col";
}

/* Data beats of a request of `bytes`: whole bus widths (at least one),
 * rounded up to whole bursts. */
static uint64_t beats_of(uint32_t bus_bytes, uint32_t burst, uint32_t bytes)
{
	uint64_t beats = (bytes + bus_bytes - 1) / bus_bytes;
	if (!beats)
		beats = 1;
	return (beats + burst - 1) / burst * burst;
}

int sdram_derive(const sdram_params *p, sdram_timing *t, diag *d)
{
	memset(t, 0, sizeof *t);
	if (!(p->clock_mhz > 0))
		return diag_set(d, "config", 0, 0, "memory.sdram.clock_mhz must be > 0");
	if (p->bus_bits < 8 || p->bus_bits % 8)
		return diag_set(d, "config", 0, 0,
		                "memory.sdram.bus_bits must be a multiple of 8, got %u",
		                p->bus_bits);
	if (!is_pow2(p->banks) || p->banks > SDRAM_MAX_BANKS)
		return diag_set(d, "config", 0, 0,
		                "memory.sdram.banks must be a power of two <= %d, got %u",
		                SDRAM_MAX_BANKS, p->banks);
	if (!is_pow2(p->row_bytes) || p->row_bytes < p->bus_bits / 8)
		return diag_set(
		    d, "config", 0, 0,
		    "memory.sdram.row_bytes must be a power of two >= the bus width, got %u",
		    p->row_bytes);
	if (p->burst < 1)
		return diag_set(d, "config", 0, 0, "memory.sdram.burst must be >= 1");
	if (p->bytes < (uint64_t)p->banks * p->row_bytes)
		return diag_set(d, "config", 0, 0,
		                "memory.sdram.mb: capacity below one row per bank");
	t->clk = eng_clock_mhz(p->clock_mhz);
	t->cl = eng_cycles_to_ticks(t->clk, p->cl);
	t->trcd = eng_cycles_to_ticks(t->clk, p->trcd);
	t->trp = eng_cycles_to_ticks(t->clk, p->trp);
	t->tras = eng_cycles_to_ticks(t->clk, p->tras);
	t->bus_bytes = p->bus_bits / 8;
	t->col_bits = log2u(p->row_bytes);
	t->bank_bits = log2u(p->banks);
	for (uint32_t n = 0; n < SDRAM_BEATS_MEMO; n++)
		t->beats_of[n] = (uint32_t)beats_of(t->bus_bytes, p->burst, n);
	return 0;
}

int sdram_init(sdram *s, const sdram_params *p, diag *d)
{
	memset(s, 0, sizeof *s);
	s->p = *p;
	if (sdram_derive(p, &s->t, d))
		return -1;
	for (uint32_t b = 0; b < SDRAM_MAX_BANKS; b++)
		s->bank[b].open_row = SDRAM_NO_ROW;
	return 0;
}

uint64_t sdram_beats(const sdram *s, uint32_t bytes)
{
	if (bytes < SDRAM_BEATS_MEMO)
		return s->t.beats_of[bytes];
	return beats_of(s->t.bus_bytes, s->p.burst, bytes);
}

double sdram_peak_bw(const sdram *s)
{
	return (double)s->t.bus_bytes * 1e12 / (double)s->t.clk.period;
}

static uint64_t max64(uint64_t a, uint64_t b)
{
	return a > b ? a : b;
}

/* One row's worth of a request, to bank b's row `row` (addr's). Always
 * inlined: sdram_access_in's one-row path runs it for nearly every
 * request. */
static inline __attribute__((always_inline)) uint64_t segment(sdram *s, uint64_t t, uint64_t addr,
                                                              uint32_t bytes, int write,
                                                              uint64_t *first, uint32_t b,
                                                              uint64_t row)
{
	const sdram_timing *T = &s->t;
	sdram_bank *k = &s->bank[b];
	uint64_t c = eng_next_edge(T->clk, max64(t, k->col_ok));
	uint64_t colcmd;
	int how = MEM_OBS_ROW_HIT;
	if (k->open_row == row) {
		s->s.row_hits++;
		colcmd = c;
	} else {
		uint64_t act = c;
		if (k->open_row == SDRAM_NO_ROW) {
			s->s.row_empty++;
			how = MEM_OBS_ROW_EMPTY;
		} else {
			s->s.row_conflicts++;
			how = MEM_OBS_ROW_CONFLICT;
			uint64_t pre = eng_next_edge(T->clk, max64(c, k->pre_ok));
			act = pre + T->trp;
		}
		k->open_row = row;
		k->act = act;
		colcmd = act + T->trcd;
	}
	uint64_t beats = sdram_beats(s, bytes);
	uint64_t len = eng_cycles_to_ticks(T->clk, beats);
	uint64_t lat = write ? 0 : T->cl;
	uint64_t data = max64(colcmd + lat, s->bus_free); /* the bus serializes */
	uint64_t end = data + len;
	s->bus_free = end;
	s->s.busy_ticks += len;
	s->s.beats += beats;
	/* The next column command to this bank may follow once this burst has
	 * been issued (seamless bursts); precharge waits for tRAS and the data. */
	k->col_ok = data - lat + len;
	k->pre_ok = max64(k->act + T->tras, end);
	if (first)
		*first = data;
	if (s->obs) {
		mem_obs_ev ev = {MEM_OBS_SDRAM, how, (int)b, write, data, end, addr, bytes, NULL};
		s->obs->fn(s->obs->ctx, &ev);
	}
	return end;
}

/* A request's read or write and its bytes in the stats. */
static inline void count_request(sdram *s, uint32_t bytes, int write)
{
	if (write) {
		s->s.writes++;
		s->s.write_bytes += bytes;
	} else {
		s->s.reads++;
		s->s.read_bytes += bytes;
	}
}

/* sdram_access and sdram_access_in: b0 and row0 are addr's bank and row
 * when known (known = 1); later segments start a row of their own. */
static uint64_t access(sdram *s, uint64_t t, uint64_t addr, uint32_t bytes, int write,
                       uint64_t *data_start, int known, uint32_t b0, uint64_t row0)
{
	count_request(s, bytes, write);
	uint64_t end = t, first = UINT64_MAX;
	uint32_t left = bytes ? bytes : 1;
	while (left) {
		/* split at row boundaries: each segment stays in one row */
		/* row_bytes is a power of two (sdram_derive) */
		uint32_t in_row = s->p.row_bytes - (uint32_t)(addr & (s->p.row_bytes - 1));
		uint32_t n = left < in_row ? left : in_row;
		uint32_t b = b0, col;
		uint64_t row = row0, f;
		if (!known)
			sdram_decode(s, addr, &b, &row, &col);
		known = 0;
		end = segment(s, t, addr, n, write, &f, b, row);
		if (f < first)
			first = f;
		addr += n;
		left -= n;
	}
	if (data_start)
		*data_start = first;
	return end;
}

uint64_t sdram_access(sdram *s, uint64_t t, uint64_t addr, uint32_t bytes, int write,
                      uint64_t *data_start)
{
	return access(s, t, addr, bytes, write, data_start, 0, 0, 0);
}

uint64_t sdram_access_in(sdram *s, uint64_t t, uint64_t addr, uint32_t bytes, int write,
                         uint64_t *data_start, uint32_t bank, uint64_t row)
{
	/* a request inside one row (every L1 line that does not cross a row
	 * boundary): access's one segment, without its loop */
	uint32_t in_row = s->p.row_bytes - (uint32_t)(addr & (s->p.row_bytes - 1));
	if (bytes == 0 || bytes > in_row)
		return access(s, t, addr, bytes, write, data_start, 1, bank, row);
	count_request(s, bytes, write);
	return segment(s, t, addr, bytes, write, data_start, bank, row);
}
