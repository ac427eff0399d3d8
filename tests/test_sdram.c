/*
 * test_sdram.c: SDRAM latencies exactly as the timing parameters say (row
 * hit, idle bank, row conflict with tRAS), data-bus serialization, address
 * mapping bit by bit; host-bus transfer time and contention; memif order
 * (fifo, round robin, FR-FCFS: ready banks and row hits first).
 */
#include <string.h>

#include "mem/hostbus.h"
#include "mem/memif.h"
#include "mem/sdram.h"
#include "tests/testutil.h"

static sdram_params std_params(void)
{
	/* 64 MB, 128 bit at 133 MHz, 4 banks, 8 KB rows, CL3 tRCD3 tRP3 tRAS6 */
	return (sdram_params){
	    64u << 20, 133.0, 128, 4, 8192, 3, 3, 3, 6, 1, SDRAM_MAP_ROW_BANK_COL};
}

Test(sdram, mapping_bits)
{
	sdram s;
	diag d;
	sdram_params p = std_params();
	cr_assert_eq(sdram_init(&s, &p, &d), 0, "%s", d.msg);
	uint32_t bank, col;
	uint64_t row;
	/* row:bank:col: col = bits 0-12, bank = bits 13-14, row = bits 15+ */
	sdram_decode(&s, (5ull << 15) | (2ull << 13) | 100, &bank, &row, &col);
	cr_assert_eq(col, 100);
	cr_assert_eq(bank, 2);
	cr_assert_eq(row, 5);
	p.mapping = SDRAM_MAP_BANK_ROW_COL; /* 64 MB / 4 banks / 8 KB = 2048 rows */
	cr_assert_eq(sdram_init(&s, &p, &d), 0);
	sdram_decode(&s, (3ull * 2048 + 7) * 8192 + 9, &bank, &row, &col);
	cr_assert_eq(bank, 3);
	cr_assert_eq(row, 7);
	cr_assert_eq(col, 9);
	cr_assert_eq(sdram_mapping_parse("row:bank:col"), SDRAM_MAP_ROW_BANK_COL);
	cr_assert_eq(sdram_mapping_parse("col:row"), -1);
}

Test(sdram, latencies_exact)
{
	sdram s;
	diag d;
	sdram_params p = std_params();
	cr_assert_eq(sdram_init(&s, &p, &d), 0);
	uint64_t T = s.t.clk.period;
	cr_assert_eq(T, 7519);
	cr_assert_eq(sdram_peak_bw(&s) > 2.12e9 && sdram_peak_bw(&s) < 2.13e9, 1);
	/* idle bank: tRCD + CL + beats; 36 bytes on 16-byte beats = 3 beats */
	uint64_t t0 = 100 * T;
	cr_assert_eq(sdram_access(&s, t0, 0, 36, 0, NULL), t0 + (3 + 3 + 3) * T);
	cr_assert_eq(s.s.row_empty, 1);
	/* row hit after the bus went idle: CL + beats */
	uint64_t t1 = 200 * T;
	cr_assert_eq(sdram_access(&s, t1, 64, 8, 0, NULL), t1 + (3 + 1) * T);
	cr_assert_eq(s.s.row_hits, 1);
	/* row conflict in bank 0 long after tRAS: tRP + tRCD + CL + beats */
	uint64_t t2 = 300 * T, other_row = 4ull << 15;
	cr_assert_eq(sdram_access(&s, t2, other_row, 16, 0, NULL), t2 + (3 + 3 + 3 + 1) * T);
	cr_assert_eq(s.s.row_conflicts, 1);
	/* an immediate conflict back to row 0 waits for tRAS of that ACT:
	 * ACT at t2+3T, PRE not before ACT+6T and the data end (t2+10T) */
	uint64_t t3 = t2 + 10 * T;
	uint64_t pre = t2 + 10 * T;
	cr_assert_eq(sdram_access(&s, t3, 0, 16, 0, NULL), pre + (3 + 3 + 3 + 1) * T);
	/* a request between edges starts at the next edge */
	uint64_t t4 = 500 * T + 1;
	cr_assert_eq(sdram_access(&s, t4, 16, 16, 0, NULL), 501 * T + (3 + 1) * T);
	/* writes: data with the column command */
	uint64_t t5 = 600 * T;
	cr_assert_eq(sdram_access(&s, t5, 32, 32, 1, NULL), t5 + 2 * T);
	cr_assert_eq(s.s.read_bytes, 36 + 8 + 16 + 16 + 16);
	cr_assert_eq(s.s.write_bytes, 32);
}

Test(sdram, burst_rounding)
{
	sdram s;
	diag d;
	sdram_params p = std_params();
	p.burst = 4;
	cr_assert_eq(sdram_init(&s, &p, &d), 0);
	cr_assert_eq(sdram_beats(&s, 8), 4);
	cr_assert_eq(sdram_beats(&s, 128), 8);
	cr_assert_eq(sdram_beats(&s, 129), 12);
}

Test(sdram, bus_serializes)
{
	sdram s;
	diag d;
	sdram_params p = std_params();
	cr_assert_eq(sdram_init(&s, &p, &d), 0);
	uint64_t T = s.t.clk.period, t = 10 * T;
	/* open rows in banks 0 and 1 first */
	sdram_access(&s, t, 0, 16, 0, NULL);
	sdram_access(&s, t, 1u << 13, 16, 0, NULL);
	t = 100 * T;
	/* four 128-byte row hits at once, two banks: 8 beats each, back to back */
	uint64_t first, end = 0;
	for (int i = 0; i < 4; i++) {
		uint64_t a = (uint64_t)(i & 1) << 13 | (uint64_t)(256 + 128 * i);
		end = sdram_access(&s, t, a, 128, 0, i == 0 ? &first : NULL);
	}
	cr_assert_eq(first, t + 3 * T);
	cr_assert_eq(end, t + 3 * T + 32 * T);
	cr_assert_eq(s.s.busy_ticks, (1 + 1 + 32) * T);
}

/* sdram_access_in (the bank and row decoded by the caller, the memory
 * interface at submit) against sdram_access (decoding itself), on random
 * reads and writes over few rows of every bank, some crossing a row
 * boundary, in both mappings: every end and first-beat tick and every
 * counter must agree. Fails when the known bank and row are used for the
 * later segments of a request crossing into the next row, or the decoded
 * ones are ignored in favour of another bank. */
Test(sdram, access_in_as_access)
{
	for (int map = 0; map < 2; map++) {
		sdram a, b;
		diag d;
		sdram_params p = std_params();
		p.mapping = map ? SDRAM_MAP_BANK_ROW_COL : SDRAM_MAP_ROW_BANK_COL;
		cr_assert_eq(sdram_init(&a, &p, &d), 0, "%s", d.msg);
		cr_assert_eq(sdram_init(&b, &p, &d), 0, "%s", d.msg);
		uint64_t rng = 777, t = 0;
		int crossed = 0;
		for (int i = 0; i < 5000; i++) {
			rng = rng * 6364136223846793005ull + 1442695040888963407ull;
			uint64_t r = rng >> 20;
			/* a column near the row's end half the time */
			uint64_t col0 = r >> 4 & 1 ? 8192 - (r >> 5) % 64 : (r >> 5) % 8192;
			uint64_t addr =
			    (r % 3) << (map ? 13 : 15) | (r >> 2 & 3) << (map ? 24 : 13) | col0;
			uint32_t bytes = 8u << (r >> 17 & 3);
			int write = (r >> 19 & 7) == 0;
			crossed += addr % 8192 + bytes > 8192;
			t += (r >> 22) % 20000;
			uint32_t bank, col;
			uint64_t row, fa, fb;
			sdram_decode(&b, addr, &bank, &row, &col);
			uint64_t ea = sdram_access(&a, t, addr, bytes, write, &fa);
			uint64_t eb = sdram_access_in(&b, t, addr, bytes, write, &fb, bank, row);
			cr_assert(ea == eb && fa == fb,
			          "access %d: %llu/%llu, decoded first: %llu/%llu", i,
			          (unsigned long long)ea, (unsigned long long)fa,
			          (unsigned long long)eb, (unsigned long long)fb);
		}
		cr_assert_gt(crossed, 10);
		cr_assert_eq(memcmp(&a.s, &b.s, sizeof a.s), 0);
		cr_assert_eq(memcmp(a.bank, b.bank, sizeof a.bank), 0);
		cr_assert_gt(a.s.row_hits, 100);
		cr_assert_gt(a.s.row_conflicts, 100);
	}
}

Test(hostbus, pci_transfer_time)
{
	hbus h;
	hbus_params p;
	diag d;
	cr_assert_eq(hbus_preset("pci", &p), 0);
	cr_assert_eq(hbus_init(&h, &p, &d), 0);
	uint64_t T = h.clk.period; /* 30303 ps */
	cr_assert_eq(T, 30303);
	/* 128 bytes on 32 bits = 32 data phases, one burst: 300 ns + 32 T */
	cr_assert_eq(hbus_duration(&h, 128), 300000 + 32 * T);
	/* 129 bytes: 33 phases, two bursts */
	cr_assert_eq(hbus_duration(&h, 129), 2 * 300000 + 33 * T);
	/* contention: the second transfer waits for the first */
	uint64_t a = hbus_transfer(&h, 0, 128), b = hbus_transfer(&h, 0, 128);
	cr_assert_eq(a, 300000 + 32 * T);
	uint64_t start2 = eng_next_edge(h.clk, a); /* transactions start on bus edges */
	cr_assert_eq(b, start2 + a);
	cr_assert_eq(h.s.bytes, 256);
	cr_assert_eq(h.s.busy_ticks, 2 * a);
	cr_assert_eq(h.s.wait_ticks, start2);
	cr_assert_eq(hbus_preset("pci66", &p), 0);
	cr_assert_eq(p.width_bits, 64);
	cr_assert_eq(hbus_preset("isa", &p), -1);
}

static uint64_t done_at[8];
static void note(eng *e, void *ctx, uint64_t arg)
{
	done_at[arg] = eng_now(e);
}

/* An engine, the standard SDRAM and a memory interface of one policy. */
typedef struct memif_rig {
	eng *e;
	sdram s;
	memif m;
} memif_rig;

static void rig_init(memif_rig *g, int policy)
{
	g->e = eng_create(16);
	diag d;
	sdram_params p = std_params();
	cr_assert_eq(sdram_init(&g->s, &p, &d), 0, "%s", d.msg);
	cr_assert_eq(memif_init(&g->m, g->e, &g->s, policy), 0);
}

static void rig_free(memif_rig *g)
{
	memif_free(&g->m);
	eng_destroy(g->e);
}

Test(memif, fifo_and_round_robin)
{
	for (int pol = 0; pol < 2; pol++) {
		memif_rig g;
		rig_init(&g, pol);
		memif *m = &g.m;
		/* three kd requests, then one shade request, all at tick 0 */
		for (int i = 0; i < 3; i++)
			memif_submit(m, 0, MEMIF_KD, 128 * (uint64_t)i, 128, 0, note, NULL,
			             (uint64_t)i);
		memif_submit(m, 0, MEMIF_SHADE, 4096, 128, 0, note, NULL, 3);
		eng_run(g.e, ENG_FOREVER);
		if (pol == MEMIF_FIFO) /* submission order */
			cr_assert(done_at[0] < done_at[1] && done_at[1] < done_at[2] &&
			          done_at[2] < done_at[3]);
		else /* shade gets its turn before the kd queue drains */
			cr_assert(done_at[3] < done_at[2], "rr: shade %llu kd2 %llu",
			          (unsigned long long)done_at[3], (unsigned long long)done_at[2]);
		cr_assert_eq(m->s.bytes[MEMIF_KD], 384);
		cr_assert_eq(g.s.s.read_bytes, 512);
		rig_free(&g);
	}
}

/* FR-FCFS: a younger request to an idle bank goes ahead of an older one
 * stuck behind a row conflict; fifo keeps the submission order. */
Test(memif, frfcfs_serves_a_ready_bank_first)
{
	uint64_t conflict_done[2], other_done[2];
	const int pols[2] = {MEMIF_FIFO, MEMIF_FRFCFS};
	for (int k = 0; k < 2; k++) {
		memif_rig g;
		rig_init(&g, pols[k]);
		memif *m = &g.m;
		memset(done_at, 0, sizeof done_at);
		/* row:bank:col: bank = bits 13-14, row = bits 15+ */
		uint64_t b0r1 = (1ull << 15) | (0ull << 13), b0r2 = (2ull << 15) | (0ull << 13);
		uint64_t b1r1 = (1ull << 15) | (1ull << 13);
		memif_submit(m, 0, MEMIF_KD, b0r1, 8, 0, note, NULL, 0); /* opens bank 0, row 1 */
		memif_submit(m, 0, MEMIF_KD, b0r2, 8, 0, note, NULL, 1); /* conflict in bank 0 */
		memif_submit(m, 0, MEMIF_SHADE, b1r1, 8, 0, note, NULL, 2); /* idle bank 1 */
		eng_run(g.e, ENG_FOREVER);
		conflict_done[k] = done_at[1];
		other_done[k] = done_at[2];
		cr_assert_eq(g.s.s.read_bytes, 24);
		rig_free(&g);
	}
	cr_assert_gt(other_done[0], conflict_done[0], "fifo: bank 1 waits for the conflict");
	cr_assert_lt(other_done[1], conflict_done[1], "frfcfs: bank 1 goes first");
	cr_assert_lt(other_done[1], other_done[0], "frfcfs serves bank 1 sooner than fifo");
	cr_assert_eq(memif_policy_parse("frfcfs"), MEMIF_FRFCFS);
}

/* Mistake: FR-FCFS ignores row hits and serves the oldest ready request
 * (plain FCFS). One requester's queue: a request opens bank 0's row 1, an
 * older one wants row 2 of the same bank (a row conflict), a younger one
 * row 1 again (a row hit); FR-FCFS serves the hit before the older
 * conflict, fifo in submission order. */
Test(memif, frfcfs_serves_row_hits_before_older_requests)
{
	uint64_t conflict_done[2], hit_done[2];
	const int pols[2] = {MEMIF_FIFO, MEMIF_FRFCFS};
	for (int k = 0; k < 2; k++) {
		memif_rig g;
		rig_init(&g, pols[k]);
		memif *m = &g.m;
		memset(done_at, 0, sizeof done_at);
		/* row:bank:col: bank = bits 13-14, row = bits 15+ */
		uint64_t r1 = 1ull << 15, r2 = 2ull << 15;
		memif_submit(m, 0, MEMIF_KD, r1, 8, 0, note, NULL, 0);      /* opens row 1 */
		memif_submit(m, 0, MEMIF_KD, r2, 8, 0, note, NULL, 1);      /* older: conflict */
		memif_submit(m, 0, MEMIF_KD, r1 + 64, 8, 0, note, NULL, 2); /* younger: hit */
		eng_run(g.e, ENG_FOREVER);
		conflict_done[k] = done_at[1];
		hit_done[k] = done_at[2];
		cr_assert_eq(g.s.s.reads, 3);
		cr_assert_eq(g.s.s.row_hits, (uint64_t)k, "policy %d: %llu row hits", pols[k],
		             (unsigned long long)g.s.s.row_hits);
		rig_free(&g);
	}
	cr_assert_gt(hit_done[0], conflict_done[0], "fifo: the hit waits for the older conflict");
	cr_assert_lt(hit_done[1], conflict_done[1], "frfcfs: the row hit goes first");
}

/* Mistake: the memory interface decodes a request's bank and row once, at
 * submit (a FR-FCFS pick compares them with every bank's open row), and
 * gets them wrong: every request taken for bank 0, or the row read with the
 * bank bits left in. Bank 1's row 1 is opened and closed out first; then
 * an older request to idle bank 0 and a younger row hit in bank 1 wait
 * together. The hit's data can start first (CAS only against ACTIVATE +
 * CAS), so FR-FCFS serves it first; with either mistake both look like
 * misses to an idle bank and the older one goes first. */
Test(memif, frfcfs_finds_the_open_row_of_the_right_bank)
{
	memif_rig g;
	rig_init(&g, MEMIF_FRFCFS);
	memif *m = &g.m;
	memset(done_at, 0, sizeof done_at);
	/* row:bank:col: bank = bits 13-14, row = bits 15+ */
	uint64_t b1r1 = (1ull << 15) | (1ull << 13), b0r5 = 5ull << 15;
	memif_submit(m, 0, MEMIF_KD, b1r1, 8, 0, note, NULL, 0); /* opens bank 1, row 1 */
	eng_run(g.e, ENG_FOREVER);
	uint64_t t = done_at[0] + 1000000; /* long after: bank 1 is ready for a CAS */
	memif_submit(m, t, MEMIF_KD, b0r5, 8, 0, note, NULL, 1);         /* older, idle bank 0 */
	memif_submit(m, t, MEMIF_SHADE, b1r1 + 64, 8, 0, note, NULL, 2); /* younger, row hit */
	eng_run(g.e, ENG_FOREVER);
	cr_assert_eq(g.s.s.row_hits, 1);
	cr_assert_lt(done_at[2], done_at[1],
	             "the row hit in bank 1 goes first: hit %llu, older %llu",
	             (unsigned long long)done_at[2], (unsigned long long)done_at[1]);
	rig_free(&g);
}

/* Mistake: the interface's count of queued requests (memif.queued, which
 * spares a dispatch that finds the SDRAM busy a scan of every queue) is
 * not taken down when a request issues: with the bus busy after the last
 * one, the dispatch re-arms for queues that are empty, an event more than
 * needed (the results stay the same; the report's event count and the
 * host time do not). Four requests to one row, all at tick 0: each
 * dispatch issues one and arms the next only while requests wait. */
Test(memif, no_dispatch_is_armed_for_empty_queues)
{
	memif_rig g;
	rig_init(&g, MEMIF_FRFCFS);
	memif *m = &g.m;
	memset(done_at, 0, sizeof done_at);
	for (int i = 0; i < 4; i++)
		memif_submit(m, 0, MEMIF_KD, 64 * (uint64_t)i, 64, 0, note, NULL, (uint64_t)i);
	eng_run(g.e, ENG_FOREVER);
	cr_assert_eq(m->queued, 0);
	cr_assert_eq(g.s.s.reads, 4);
	/* four completions; the dispatches: one per request, none after */
	cr_assert_eq(eng_events(g.e), 4 + 4, "%llu events", (unsigned long long)eng_events(g.e));
	rig_free(&g);
}

/* FR-FCFS keeps the window requests in one list per SDRAM bank, in submit
 * order (mem/memif.c). Mistake: a request that enters its queue's window
 * late (when one ahead of it issues) is put at the end of its bank's list,
 * behind younger requests of other queues, so oldest-first among equal
 * starts breaks. Seventeen kd requests (one more than the window) and then
 * one shade request, every one to another row of bank 0: each is a row
 * conflict with the same start, so all go in submit order and the
 * seventeenth kd request (entering the window after the first issues) goes
 * before the younger shade request. */
static uint64_t win_done[18];
static void win_note(eng *e, void *ctx, uint64_t arg)
{
	(void)ctx;
	win_done[arg] = eng_now(e);
}

Test(memif, frfcfs_request_entering_the_window_late_keeps_its_age)
{
	memif_rig g;
	rig_init(&g, MEMIF_FRFCFS);
	memif *m = &g.m;
	cr_assert_eq(MEMIF_FRFCFS_WINDOW, 16, "the test fills a window of 16");
	/* row:bank:col: bank = bits 13-14, row = bits 15+; all in bank 0 */
	for (uint64_t i = 0; i < 17; i++)
		memif_submit(m, 0, MEMIF_KD, (10 + i) << 15, 8, 0, win_note, NULL, i);
	memif_submit(m, 0, MEMIF_SHADE, 50ull << 15, 8, 0, win_note, NULL, 17);
	eng_run(g.e, ENG_FOREVER);
	cr_assert_eq(g.s.s.reads, 18);
	for (int i = 0; i < 17; i++)
		cr_assert_lt(win_done[i], win_done[i + 1], "request %d before %d: %llu %llu", i,
		             i + 1, (unsigned long long)win_done[i],
		             (unsigned long long)win_done[i + 1]);
	rig_free(&g);
}

/* FR-FCFS counts, per bank, the waiting requests to its open row, so that
 * a pick looks for a row hit only where there is one (mem/memif.c).
 * Mistake: a request submitted while its row is open is not counted, so
 * the pick takes the bank's oldest request instead of the hit. Two
 * requests open bank 0's row 1 and are served (the pick has counted row
 * 1's requests); long after, an older row conflict and a younger row hit
 * wait together: the hit goes first. */
Test(memif, frfcfs_counts_a_hit_submitted_while_its_row_is_open)
{
	memif_rig g;
	rig_init(&g, MEMIF_FRFCFS);
	memif *m = &g.m;
	memset(done_at, 0, sizeof done_at);
	uint64_t r1 = 1ull << 15, r2 = 2ull << 15;
	memif_submit(m, 0, MEMIF_KD, r1, 8, 0, note, NULL, 0);
	memif_submit(m, 0, MEMIF_KD, r1 + 64, 8, 0, note, NULL, 1);
	eng_run(g.e, ENG_FOREVER);
	cr_assert_eq(g.s.s.row_hits, 1);
	uint64_t t = done_at[1] + 1000000;
	memif_submit(m, t, MEMIF_KD, r2, 8, 0, note, NULL, 2);          /* older: conflict */
	memif_submit(m, t, MEMIF_SHADE, r1 + 128, 8, 0, note, NULL, 3); /* younger: hit */
	eng_run(g.e, ENG_FOREVER);
	cr_assert_eq(g.s.s.row_hits, 2);
	cr_assert_lt(done_at[3], done_at[2], "the row hit goes first: hit %llu, older %llu",
	             (unsigned long long)done_at[3], (unsigned long long)done_at[2]);
	rig_free(&g);
}

/* ---- FR-FCFS against the plain scan ----
 *
 * Mistake: the memory interface's per-bank lists (mem/memif.c) pick a
 * different request than FR-FCFS's rules say: a request entering its
 * queue's window late placed out of age order, a bank's count of open-row
 * requests gone stale, a request not yet ready taken, or the next
 * dispatch armed for the wrong tick. The reference below is the rule
 * written the simple way (each pick scans the first MEMIF_FRFCFS_WINDOW
 * requests of every queue, as the interface did before the lists), with
 * the same dispatch and arming; both run the same random submissions
 * (bursts longer than the window, a trickle of requests ready only later,
 * lone pairs whose second request waits for the dispatch the first arms;
 * reads and writes over few rows of every bank) on their own engine and
 * SDRAM, and every completion must come at the same tick, in the same
 * order, with the same number of events. */
enum { NSUB = 700, REFCAP = NSUB };

static uint64_t lcg_next(uint64_t *s)
{
	*s = *s * 6364136223846793005ull + 1442695040888963407ull;
	return *s >> 33;
}

typedef struct ref_item {
	uint64_t seq, ready, addr, row, arg;
	uint32_t bank, bytes;
	int write;
} ref_item;

typedef struct ref_mi {
	eng *e;
	sdram *sd;
	ref_item q[MEMIF_NREQ][REFCAP];
	uint32_t n[MEMIF_NREQ], max_n;
	uint64_t seq, queued, lead, armed_at, not_ready_seen;
	int armed;
	eng_handler done;
	void *done_ctx;
} ref_mi;

static void ref_dispatch(eng *e, void *ctx, uint64_t arg);

static void ref_arm(ref_mi *m, uint64_t when)
{
	if (when < eng_now(m->e))
		when = eng_now(m->e);
	if (m->armed && m->armed_at <= when)
		return;
	m->armed = 1;
	m->armed_at = when;
	eng_schedule(m->e, when, ref_dispatch, m, 0);
}

static int ref_pick(ref_mi *m, uint64_t now, uint64_t *next_ready, uint32_t *pos)
{
	const sdram_timing *T = &m->sd->t;
	int best = -1;
	uint64_t best_start = UINT64_MAX, best_seq = UINT64_MAX;
	*next_ready = UINT64_MAX;
	for (int r = 0; r < MEMIF_NREQ; r++) {
		uint32_t w = m->n[r] < MEMIF_FRFCFS_WINDOW ? m->n[r] : MEMIF_FRFCFS_WINDOW;
		for (uint32_t i = 0; i < w; i++) {
			const ref_item *it = &m->q[r][i];
			if (it->ready > now) {
				m->not_ready_seen++;
				if (it->ready < *next_ready)
					*next_ready = it->ready;
				continue;
			}
			const sdram_bank *k = &m->sd->bank[it->bank];
			uint64_t c = now > k->col_ok ? now : k->col_ok, st;
			if (k->open_row == it->row)
				st = c + T->cl;
			else if (k->open_row == SDRAM_NO_ROW)
				st = c + T->trcd + T->cl;
			else
				st = (c > k->pre_ok ? c : k->pre_ok) + T->trp + T->trcd + T->cl;
			if (st < best_start || (st == best_start && it->seq < best_seq)) {
				best = r;
				*pos = i;
				best_start = st;
				best_seq = it->seq;
			}
		}
	}
	return best;
}

static void ref_dispatch(eng *e, void *ctx, uint64_t arg)
{
	(void)arg;
	ref_mi *m = ctx;
	uint64_t now = eng_now(e);
	if (m->armed && m->armed_at == now)
		m->armed = 0;
	for (;;) {
		if (m->sd->bus_free > now + m->lead) {
			if (m->queued)
				ref_arm(m, m->sd->bus_free - m->lead);
			return;
		}
		uint64_t next_ready;
		uint32_t pos = 0;
		int r = ref_pick(m, now, &next_ready, &pos);
		if (r < 0) {
			if (next_ready != UINT64_MAX)
				ref_arm(m, next_ready);
			return;
		}
		ref_item it = m->q[r][pos];
		memmove(&m->q[r][pos], &m->q[r][pos + 1], (m->n[r] - pos - 1) * sizeof it);
		m->n[r]--;
		m->queued--;
		uint64_t done = sdram_access(m->sd, now, it.addr, it.bytes, it.write, NULL);
		eng_schedule(e, done, m->done, m->done_ctx, it.arg);
	}
}

static void ref_submit(ref_mi *m, uint64_t t, int r, uint64_t addr, uint32_t bytes, int write,
                       uint64_t arg)
{
	cr_assert_lt(m->n[r], REFCAP);
	if (t < eng_now(m->e))
		t = eng_now(m->e);
	uint32_t bank, col;
	uint64_t row;
	sdram_decode(m->sd, addr, &bank, &row, &col);
	m->q[r][m->n[r]++] = (ref_item){m->seq++, t, addr, row, arg, bank, bytes, write};
	if (m->n[r] > m->max_n)
		m->max_n = m->n[r];
	m->queued++;
	ref_arm(m, t);
}

/* One side of the comparison: its engine, SDRAM, and what completed when. */
typedef struct diff_side {
	eng *e;
	sdram s;
	memif m;     /* side 0 */
	ref_mi *ref; /* side 1 */
	uint64_t order[NSUB], at[NSUB];
	size_t n;
	const struct diff_load *load;
} diff_side;

typedef struct diff_load {
	uint64_t tick[NSUB], delay[NSUB], addr[NSUB];
	uint32_t bytes[NSUB];
	int req[NSUB], write[NSUB];
} diff_load;

static void diff_done(eng *e, void *ctx, uint64_t arg)
{
	diff_side *s = ctx;
	s->order[s->n] = arg;
	s->at[s->n++] = eng_now(e);
}

static void diff_sub(eng *e, void *ctx, uint64_t i)
{
	diff_side *s = ctx;
	const diff_load *l = s->load;
	uint64_t t = eng_now(e) + l->delay[i];
	if (s->ref)
		ref_submit(s->ref, t, l->req[i], l->addr[i], l->bytes[i], l->write[i], i);
	else
		cr_assert_eq(memif_submit(&s->m, t, l->req[i], l->addr[i], l->bytes[i], l->write[i],
		                          diff_done, s, i),
		             0);
}

Test(memif, frfcfs_picks_as_the_plain_scan_of_every_window)
{
	static diff_load l;
	static diff_side side[2];
	static ref_mi ref;
	uint64_t rng = 12345;
	for (int i = 0; i < NSUB; i++) {
		if (i < NSUB / 2) {
			/* bursts: groups of 40 share a tick and mostly a queue, more
			 * than the SDRAM serves before the next group */
			l.tick[i] = (uint64_t)(i / 40) * 150000 +
			            (i % 40 < 30 ? 0 : lcg_next(&rng) % 50000);
			l.req[i] = lcg_next(&rng) % 3 ? (int)(i / 40 % MEMIF_NREQ)
			                              : (int)(lcg_next(&rng) % MEMIF_NREQ);
			l.delay[i] = lcg_next(&rng) % 5 == 0 ? lcg_next(&rng) % 300000 : 0;
		} else if (i >= NSUB - 40) {
			/* last, pairs alone on the bus, ready 100 and 200 ns after they
			 * come: the second one's dispatch is the one the first one's
			 * dispatch arms (for the earliest tick a waiting request is
			 * ready) */
			l.tick[i] = 30000000 + (uint64_t)(i / 2) * 1000000;
			l.req[i] = (int)(lcg_next(&rng) % MEMIF_NREQ);
			l.delay[i] = i % 2 ? 200000 : 100000;
		} else {
			/* then a trickle, with many requests ready only later, so that
			 * picks meet them before they are ready */
			l.tick[i] = 4000000 + (uint64_t)i * 20000 + lcg_next(&rng) % 20000;
			l.req[i] = (int)(lcg_next(&rng) % MEMIF_NREQ);
			l.delay[i] = lcg_next(&rng) % 3 == 0 ? lcg_next(&rng) % 100000 : 0;
		}
		uint64_t row = lcg_next(&rng) % 6, bank = lcg_next(&rng) % 4;
		l.addr[i] = row << 15 | bank << 13 | (lcg_next(&rng) % 64) * 64;
		l.bytes[i] = 8u << (lcg_next(&rng) % 4);
		l.write[i] = lcg_next(&rng) % 8 == 0;
	}
	for (int k = 0; k < 2; k++) {
		diff_side *s = &side[k];
		memset(s, 0, sizeof *s);
		s->load = &l;
		s->e = eng_create(64);
		diag d;
		sdram_params p = std_params();
		cr_assert_eq(sdram_init(&s->s, &p, &d), 0, "%s", d.msg);
		if (k == 0) {
			cr_assert_eq(memif_init(&s->m, s->e, &s->s, MEMIF_FRFCFS), 0);
		} else {
			memset(&ref, 0, sizeof ref);
			ref = (ref_mi){.e = s->e,
			               .sd = &s->s,
			               .lead = s->s.t.trp + s->s.t.trcd + s->s.t.cl,
			               .done = diff_done,
			               .done_ctx = s};
			s->ref = &ref;
		}
		for (uint64_t i = 0; i < NSUB; i++)
			eng_schedule(s->e, l.tick[i], diff_sub, s, i);
		eng_run(s->e, ENG_FOREVER);
	}
	cr_assert_gt(ref.max_n, 2 * MEMIF_FRFCFS_WINDOW, "queues outgrow the window");
	cr_assert_gt(ref.not_ready_seen, 0,
	             "some requests wait in the window before they are ready");
	cr_assert_eq(side[0].n, (size_t)NSUB);
	cr_assert_eq(side[1].n, (size_t)NSUB);
	for (int i = 0; i < NSUB; i++)
		cr_assert(
		    side[0].order[i] == side[1].order[i] && side[0].at[i] == side[1].at[i],
		    "completion %d: request %llu at %llu, the plain scan: request %llu at %llu", i,
		    (unsigned long long)side[0].order[i], (unsigned long long)side[0].at[i],
		    (unsigned long long)side[1].order[i], (unsigned long long)side[1].at[i]);
	cr_assert_eq(eng_events(side[0].e), eng_events(side[1].e));
	cr_assert_eq(side[0].s.s.row_hits, side[1].s.s.row_hits);
	cr_assert_gt(side[0].s.s.row_hits, 0);
	memif_free(&side[0].m);
	for (int k = 0; k < 2; k++)
		eng_destroy(side[k].e);
}
