/*
 * memif.c: arbitration of requesters onto SDRAM (see memif.h).
 *
 * One dispatch event at a time: at its tick it issues every request it may
 * (SDRAM look-ahead permitting, one pick per iteration by policy), then
 * re-arms for the earliest tick something can go next.
 */
#include "mem/memif.h"

#include <stdlib.h>
#include <string.h>

int memif_policy_parse(const char *s)
{
	if (!strcmp(s, "fifo"))
		return MEMIF_FIFO;
	if (!strcmp(s, "round_robin"))
		return MEMIF_ROUND_ROBIN;
	if (!strcmp(s, "frfcfs"))
		return MEMIF_FRFCFS;
	return -1;
}

const char *memif_requester_name(int r)
{
	static const char *const n[MEMIF_NREQ] = {"shade", "kd", "list", "tri", "meta", "fill"};
	return r >= 0 && r < MEMIF_NREQ ? n[r] : "?";
}

int memif_init(memif *m, eng *e, sdram *sd, int policy)
{
	memset(m, 0, sizeof *m);
	m->e = e;
	m->sd = sd;
	m->policy = policy;
	m->last = MEMIF_NREQ - 1;
	/* issue far enough ahead that a row miss (precharge, activate, CAS) in
	 * one bank overlaps the data transfer of another: the SDRAM model keeps
	 * per-bank state and serializes the data bus itself */
	m->lead = sd->t.trp + sd->t.trcd + sd->t.cl;
	for (int r = 0; r < MEMIF_NREQ; r++) {
		m->q[r].cap = 64;
		m->q[r].q = malloc(64 * sizeof(memif_item));
		if (!m->q[r].q) {
			memif_free(m);
			return -1;
		}
	}
	return 0;
}

void memif_free(memif *m)
{
	for (int r = 0; r < MEMIF_NREQ; r++) {
		free(m->q[r].q);
		m->q[r].q = NULL;
	}
}

static void dispatch(eng *e, void *ctx, uint64_t arg);

static void arm(memif *m, uint64_t when)
{
	if (when < eng_now(m->e))
		when = eng_now(m->e);
	if (m->armed && m->armed_at <= when)
		return;
	/* An earlier need than the queued dispatch: queue another one; the
	 * later one finds nothing or re-arms (harmless, deterministic). */
	m->armed = 1;
	m->armed_at = when;
	eng_schedule(m->e, when, dispatch, m, 0);
}

/* The requester to serve now, or -1; *next_ready: earliest head not ready. */
static int pick(memif *m, uint64_t now, uint64_t *next_ready)
{
	int best = -1;
	*next_ready = UINT64_MAX;
	for (int i = 0; i < MEMIF_NREQ; i++) {
		int r = m->policy == MEMIF_ROUND_ROBIN ? (m->last + 1 + i) % MEMIF_NREQ : i;
		memif_queue *q = &m->q[r];
		if (!q->n)
			continue;
		const memif_item *it = &q->q[q->head];
		if (it->ready > now) {
			if (it->ready < *next_ready)
				*next_ready = it->ready;
			continue;
		}
		if (m->policy == MEMIF_ROUND_ROBIN)
			return r;
		if (best < 0 || it->seq < m->q[best].q[m->q[best].head].seq)
			best = r;
	}
	return best;
}

/* When the data of a request to one bank could start if issued at `now`:
 * the bank's open row decides between CAS only (hit), ACTIVATE + CAS
 * (the bank is precharged) and PRECHARGE + ACTIVATE + CAS (the same rules
 * as sdram.c's segment(), bus aside). All but the row comparison depends on
 * the bank alone, so one pick works it out once per bank it meets. */
typedef struct bank_start {
	uint64_t open_row, hit, miss;
} bank_start;

static void bank_start_at(const sdram *sd, uint32_t b, uint64_t now, bank_start *o)
{
	const sdram_bank *k = &sd->bank[b];
	uint64_t c = now > k->col_ok ? now : k->col_ok;
	o->open_row = k->open_row;
	o->hit = c + sd->t.cl;
	if (k->open_row == SDRAM_NO_ROW) {
		o->miss = c + sd->t.trcd + sd->t.cl;
	} else {
		uint64_t pre = c > k->pre_ok ? c : k->pre_ok;
		o->miss = pre + sd->t.trp + sd->t.trcd + sd->t.cl;
	}
}

/* FR-FCFS: over the first MEMIF_FRFCFS_WINDOW ready requests of every
 * queue, the one whose data can start soonest (oldest on ties). Returns the
 * requester (-1 if none is ready) and its offset from the queue head.
 * This scan is the simulator's hottest loop on memory-bound views
 * (docs/PERFORMANCE.md, "Profile"): the bank and row come decoded with the
 * item and each bank's start times are worked out once per pick. */
static int pick_frfcfs(memif *m, uint64_t now, uint64_t *next_ready, uint32_t *pos)
{
	int best = -1;
	uint64_t best_start = UINT64_MAX, best_seq = UINT64_MAX;
	bank_start bs[SDRAM_MAX_BANKS];
	uint64_t known = 0; /* banks whose bs[] entry is filled in */
	*next_ready = UINT64_MAX;
	for (int r = 0; r < MEMIF_NREQ; r++) {
		const memif_queue *q = &m->q[r];
		uint32_t w = q->n < MEMIF_FRFCFS_WINDOW ? q->n : MEMIF_FRFCFS_WINDOW;
		uint32_t mask = q->cap - 1;
		for (uint32_t i = 0; i < w; i++) {
			const memif_item *it = &q->q[(q->head + i) & mask];
			if (it->ready > now) {
				if (it->ready < *next_ready)
					*next_ready = it->ready;
				continue;
			}
			uint32_t b = it->bank;
			if (!(known >> b & 1)) {
				bank_start_at(m->sd, b, now, &bs[b]);
				known |= 1ull << b;
			}
			uint64_t st = bs[b].open_row == it->row ? bs[b].hit : bs[b].miss;
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

/* Takes the item `pos` places after the head out of q, keeping the order
 * of the others (the ones before it move up one slot). */
static memif_item take(memif_queue *q, uint32_t pos)
{
	uint32_t mask = q->cap - 1;
	memif_item it = q->q[(q->head + pos) & mask];
	for (uint32_t i = pos; i > 0; i--)
		q->q[(q->head + i) & mask] = q->q[(q->head + i - 1) & mask];
	q->head = (q->head + 1) & mask;
	q->n--;
	return it;
}

static void dispatch(eng *e, void *ctx, uint64_t arg)
{
	(void)arg;
	memif *m = ctx;
	uint64_t now = eng_now(e);
	if (m->armed && m->armed_at == now)
		m->armed = 0;
	for (;;) {
		uint64_t next_ready;
		if (m->sd->bus_free > now + m->lead) {
			/* SDRAM busy: come back when issuing makes sense */
			if (m->queued)
				arm(m, m->sd->bus_free - m->lead);
			return;
		}
		uint32_t pos = 0;
		int r = m->policy == MEMIF_FRFCFS ? pick_frfcfs(m, now, &next_ready, &pos)
		                                  : pick(m, now, &next_ready);
		if (r < 0) {
			if (next_ready != UINT64_MAX)
				arm(m, next_ready);
			return;
		}
		memif_item it = take(&m->q[r], pos);
		m->queued--;
		m->last = r;
		m->s.queue_ticks[r] += now - it.ready;
		uint64_t done = sdram_access(m->sd, now, it.addr, it.bytes, it.write, NULL);
		if (!it.write)
			m->s.latency_ticks[r] += done - it.ready;
		if (it.done)
			eng_schedule(e, done, it.done, it.ctx, it.arg);
	}
}

int memif_submit(memif *m, uint64_t t, int requester, uint64_t addr, uint32_t bytes, int write,
                 eng_handler done, void *ctx, uint64_t arg)
{
	memif_queue *q = &m->q[requester];
	if (q->n == q->cap) {
		memif_item *nq = malloc(2 * (size_t)q->cap * sizeof *nq);
		if (!nq)
			return -1;
		for (uint32_t i = 0; i < q->n; i++)
			nq[i] = q->q[(q->head + i) & (q->cap - 1)];
		free(q->q);
		q->q = nq;
		q->head = 0;
		q->cap *= 2;
	}
	if (t < eng_now(m->e))
		t = eng_now(m->e);
	uint32_t bank, col;
	uint64_t row;
	sdram_decode(m->sd, addr, &bank, &row, &col);
	q->q[(q->head + q->n) & (q->cap - 1)] = (memif_item){
	    m->seq++, t, addr, row, bytes, (uint16_t)bank, (uint8_t)write, done, ctx, arg};
	q->n++;
	m->queued++;
	if (write)
		m->s.writes[requester]++;
	else
		m->s.reads[requester]++;
	m->s.bytes[requester] += bytes;
	arm(m, t);
	return 0;
}
