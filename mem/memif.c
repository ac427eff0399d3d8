/*
 * memif.c: arbitration of requesters onto SDRAM (see memif.h).
 *
 * One dispatch event at a time: at its tick it issues every request it may
 * (SDRAM look-ahead permitting, one pick per iteration by policy), then
 * re-arms for the earliest tick something can go next.
 */
#include "mem/memif.h"

#include <stddef.h>
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

/* Links pool items [from, to) into the free list in index order. */
static void link_free(memif *m, uint32_t from, uint32_t to)
{
	for (uint32_t i = from; i < to; i++)
		m->pool[i].qnext = i + 1 < to ? i + 1 : m->free_head;
	if (from < to)
		m->free_head = from;
}

static int grow(memif *m)
{
	uint32_t want = m->cap ? 2 * m->cap : 64;
	if (want > MEMIF_NIL / 2)
		return -1;
	memif_item *p = realloc(m->pool, (size_t)want * sizeof *p);
	if (!p)
		return -1;
	m->pool = p;
	link_free(m, m->cap, want);
	m->cap = want;
	return 0;
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
	m->free_head = MEMIF_NIL;
	for (int r = 0; r < MEMIF_NREQ; r++)
		m->q[r] = (memif_queue){{MEMIF_NIL, MEMIF_NIL}, 0, 0, MEMIF_NIL};
	for (int b = 0; b < SDRAM_MAX_BANKS; b++) {
		m->bank[b] = (memif_list){MEMIF_NIL, MEMIF_NIL};
	}
	if (grow(m)) {
		memif_free(m);
		return -1;
	}
	return 0;
}

void memif_free(memif *m)
{
	free(m->pool);
	m->pool = NULL;
	m->cap = 0;
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
	/* Right behind another dispatch of its tick, with no event between
	 * (the one armed before, left queued when an earlier need armed
	 * another), a dispatch does nothing: it would find the state the first
	 * left, in which the first already issued all it could and armed what
	 * follows. It is counted, not queued (a tenth of dragon2's events:
	 * docs/PERFORMANCE.md, "Target 2"). */
	eng_schedule_or_idle(m->e, when, dispatch, m, 0);
}

/* fifo and round_robin: the requester to serve now (its queue head), or
 * -1; *next_ready: earliest head not ready. */
static int pick(const memif *m, uint64_t now, uint64_t *next_ready)
{
	int best = -1;
	*next_ready = UINT64_MAX;
	for (int i = 0; i < MEMIF_NREQ; i++) {
		int r = m->policy == MEMIF_ROUND_ROBIN ? (m->last + 1 + i) % MEMIF_NREQ : i;
		const memif_queue *q = &m->q[r];
		if (!q->n)
			continue;
		const memif_item *it = &m->pool[q->l.head];
		if (it->ready > now) {
			if (it->ready < *next_ready)
				*next_ready = it->ready;
			continue;
		}
		if (m->policy == MEMIF_ROUND_ROBIN)
			return r;
		if (best < 0 || it->seq < m->pool[m->q[best].l.head].seq)
			best = r;
	}
	return best;
}

/* When the data of a request to one bank could start if issued at `now`:
 * the bank's open row decides between CAS only (hit), ACTIVATE + CAS
 * (the bank is precharged) and PRECHARGE + ACTIVATE + CAS (the same rules
 * as sdram.c's segment(), bus aside). All but the row comparison depends on
 * the bank alone, so one pick works it out once per bank it meets; the
 * miss only when a miss may be the bank's pick. */
typedef struct bank_start {
	uint64_t open_row, hit, miss;
} bank_start;

/* Bank b's best window item at `now` under FR-FCFS, or MEMIF_NIL if none
 * is ready (*start: when its data could start). Every item of the bank
 * starts at bs->hit (its row is open) or at bs->miss >= bs->hit, so the
 * smallest (start, seq) is the oldest ready row hit when hit < miss and
 * one is queued, else the oldest ready item: the walk, in submit order,
 * stops at the first ready hit, or at the first ready item when no hit can
 * beat it. Items not ready lower *next_ready (complete when none is ready).
 * hits_win: a hit beats an older miss and one may be queued (bank_pick). */
static uint32_t bank_best(memif *m, uint32_t b, const bank_start *bs, int hits_win, uint64_t now,
                          uint64_t *start, uint64_t *next_ready)
{
	uint32_t cand = MEMIF_NIL;
	for (uint32_t i = m->bank[b].head; i != MEMIF_NIL; i = m->pool[i].bnext) {
		const memif_item *it = &m->pool[i];
		if (it->ready > now) {
			if (it->ready < *next_ready)
				*next_ready = it->ready;
			continue;
		}
		if (it->row == bs->open_row) {
			if (cand == MEMIF_NIL || hits_win) {
				*start = bs->hit;
				return i;
			}
			continue;
		}
		if (cand == MEMIF_NIL) {
			cand = i;
			*start = bs->miss;
			if (!hits_win)
				break;
		}
	}
	return cand;
}

_Static_assert(MEMIF_NREQ *MEMIF_FRFCFS_WINDOW <= UINT8_MAX, "memif.rowcnt counts in bytes");

/* The constant parts of a pick's start times (SDRAM timing, in ticks). */
typedef struct pick_lat {
	uint64_t cl, rcd_cl, rp_rcd_cl;
} pick_lat;

/* Bank b's best item as bank_best picks it, or MEMIF_NIL (none ready, or
 * its row hits could not start before best_start); *start as there.
 * Before the walk, the two picks nearly every bank ends with, decided
 * from its oldest item alone (the window's items are nearly always ready:
 * they are submitted for eng_now): a ready row hit (nothing in the bank
 * starts sooner, and it is the oldest), and a ready miss when no hit can
 * beat it (the oldest ready item). Always inlined into the pick's loop. */
static inline __attribute__((always_inline)) uint32_t
bank_pick(memif *m, uint32_t b, const pick_lat *pl, uint64_t now, uint64_t best_start,
          uint64_t *start, uint64_t *next_ready)
{
	const sdram_bank *k = &m->sd->bank[b];
	uint64_t c = now > k->col_ok ? now : k->col_ok;
	bank_start bs = {k->open_row, c + pl->cl, 0};
	if (bs.hit > best_start) /* not even its row hits start soon enough */
		return MEMIF_NIL;
	uint32_t i = m->bank[b].head;
	const memif_item *it = &m->pool[i];
	int ready = it->ready <= now;
	if (ready && it->row == bs.open_row) {
		*start = bs.hit;
		return i;
	}
	if (bs.open_row == SDRAM_NO_ROW) {
		bs.miss = c + pl->rcd_cl;
	} else {
		uint64_t pre = c > k->pre_ok ? c : k->pre_ok;
		bs.miss = pre + pl->rp_rcd_cl;
	}
	/* a hit beats an older miss; with no item in the open row's slot of
	 * rowcnt there is no hit (else perhaps one: the walk goes on past the
	 * first ready miss and finds out, the same pick either way) */
	int hits_win = bs.open_row != SDRAM_NO_ROW &&
	               m->rowcnt[b][bs.open_row & (MEMIF_ROW_SLOTS - 1)] && bs.hit < bs.miss;
	if (ready && !hits_win) {
		*start = bs.miss;
		return i;
	}
	return bank_best(m, b, &bs, hits_win, now, start, next_ready);
}

/* FR-FCFS: over the first MEMIF_FRFCFS_WINDOW requests of every queue,
 * the ready one whose data can start soonest (oldest on ties). Returns the
 * item (MEMIF_NIL if none is ready). This pick is the simulator's hottest
 * loop on memory-bound views (docs/PERFORMANCE.md, "Profile"): the window
 * items are kept in one list per bank, in submit order, so each bank's
 * best comes from bank_pick without looking at every request, and a bank
 * whose row hits cannot start as soon as the best so far is skipped. */
static uint32_t pick_frfcfs(memif *m, uint64_t now, uint64_t *next_ready)
{
	uint32_t best = MEMIF_NIL;
	uint64_t best_start = UINT64_MAX, best_seq = UINT64_MAX;
	const sdram_timing *T = &m->sd->t;
	pick_lat pl = {T->cl, T->trcd + T->cl, T->trp + T->trcd + T->cl};
	*next_ready = UINT64_MAX;
	for (uint64_t used = m->banks_used; used; used &= used - 1) {
		uint32_t b = (uint32_t)__builtin_ctzll(used);
		uint64_t st = 0;
		uint32_t i = bank_pick(m, b, &pl, now, best_start, &st, next_ready);
		if (i == MEMIF_NIL)
			continue;
		/* the better of the two by (start, seq) without a branch: which
		 * bank's request wins is as good as random to the host's branch
		 * predictor (two mispredictions a pick) */
		uint64_t seq = m->pool[i].seq;
		uint64_t take =
		    (uint64_t)((st < best_start) | ((st == best_start) & (seq < best_seq)));
		uint64_t keep = take - 1; /* all ones: keep the best so far */
		best = (uint32_t)((i & ~keep) | (best & keep));
		best_start = (st & ~keep) | (best_start & keep);
		best_seq = (seq & ~keep) | (best_seq & keep);
	}
	return best;
}

/* Appends item i to a queue list (bank = 0) or a bank list (bank = 1). */
static void list_append(memif_item *pool, memif_list *l, uint32_t i, int bank)
{
	if (bank) {
		pool[i].bprev = l->tail;
		pool[i].bnext = MEMIF_NIL;
		if (l->tail != MEMIF_NIL)
			pool[l->tail].bnext = i;
	} else {
		pool[i].qprev = l->tail;
		pool[i].qnext = MEMIF_NIL;
		if (l->tail != MEMIF_NIL)
			pool[l->tail].qnext = i;
	}
	if (l->head == MEMIF_NIL)
		l->head = i;
	l->tail = i;
}

/* Puts item i into its bank's list at its place in submit order (an item
 * entering its queue's window late is older than the last ones of other
 * queues). Always inlined: gcc had kept it a call from every submit. */
static inline __attribute__((always_inline)) void bank_insert(memif *m, uint32_t i)
{
	memif_item *it = &m->pool[i];
	memif_list *l = &m->bank[it->bank];
	m->banks_used |= 1ull << it->bank;
	m->rowcnt[it->bank][it->row & (MEMIF_ROW_SLOTS - 1)]++;
	uint32_t after = l->tail;
	while (after != MEMIF_NIL && m->pool[after].seq > it->seq)
		after = m->pool[after].bprev;
	if (after == l->tail) {
		list_append(m->pool, l, i, 1);
		return;
	}
	uint32_t before = after == MEMIF_NIL ? l->head : m->pool[after].bnext;
	it->bprev = after;
	it->bnext = before;
	m->pool[before].bprev = i;
	if (after == MEMIF_NIL)
		l->head = i;
	else
		m->pool[after].bnext = i;
}

/* The link field at byte offset off of pool item i, or end when i is
 * MEMIF_NIL, picked by a mask instead of a branch (the address of the
 * item is worked out as a number, never used when i is MEMIF_NIL). */
static inline uint32_t *link_at(uint32_t *end, memif_item *pool, uint32_t i, size_t off)
{
	uintptr_t a = (uintptr_t)end, b = (uintptr_t)pool + (uintptr_t)i * sizeof *pool + off;
	uintptr_t nil = (uintptr_t)0 - (uintptr_t)(i == MEMIF_NIL); /* all ones: no item */
	return (uint32_t *)((a & nil) | (b & ~nil));
}

/* Takes item i (inside its queue's window) out of its queue and its bank's
 * list; the first item after the window, if any, moves into it. */
static void take(memif *m, uint32_t i)
{
	memif_item *it = &m->pool[i];
	memif_queue *q = &m->q[it->req];
	memif_list *bl = &m->bank[it->bank];
	/* each neighbour's link, or the list's end when there is none, chosen
	 * without a branch (link_at: whether the item is first or last in its
	 * lists is as good as random to the host's branch predictor) */
	*link_at(&q->l.head, m->pool, it->qprev, offsetof(memif_item, qnext)) = it->qnext;
	*link_at(&q->l.tail, m->pool, it->qnext, offsetof(memif_item, qprev)) = it->qprev;
	*link_at(&bl->head, m->pool, it->bprev, offsetof(memif_item, bnext)) = it->bnext;
	*link_at(&bl->tail, m->pool, it->bnext, offsetof(memif_item, bprev)) = it->bprev;
	if (bl->head == MEMIF_NIL)
		m->banks_used &= ~(1ull << it->bank);
	m->rowcnt[it->bank][it->row & (MEMIF_ROW_SLOTS - 1)]--;
	q->n--;
	q->nwin--;
	if (q->wend != MEMIF_NIL) {
		uint32_t w = q->wend;
		q->wend = m->pool[w].qnext;
		q->nwin++;
		bank_insert(m, w);
	}
	it->qnext = m->free_head;
	m->free_head = i;
}

/* SDRAM busy at `now`: come back when issuing makes sense. */
static void wait_bus(memif *m)
{
	if (m->queued)
		arm(m, m->sd->bus_free - m->lead);
}

/* The dispatch loop, once the SDRAM can take a request: issues the pick
 * while one is ready and the SDRAM takes it, then re-arms. Out of line:
 * about half the dispatch events find the SDRAM busy and never get here
 * (dispatch stays small for them). */
__attribute__((noinline)) static void issue(memif *m, uint64_t now)
{
	for (;;) {
		uint64_t next_ready;
		uint32_t i;
		if (m->policy == MEMIF_FRFCFS) {
			i = pick_frfcfs(m, now, &next_ready);
		} else {
			int q = pick(m, now, &next_ready);
			i = q < 0 ? MEMIF_NIL : m->q[q].l.head;
		}
		if (i == MEMIF_NIL) {
			if (next_ready != UINT64_MAX)
				arm(m, next_ready);
			return;
		}
		/* take() only links the item into the free list (qnext): its
		 * other fields stay readable until the next submit */
		const memif_item *it = &m->pool[i];
		int r = it->req;
		take(m, i);
		m->queued--;
		m->last = r;
		m->s.queue_ticks[r] += now - it->ready;
		uint64_t done = sdram_access_in(m->sd, now, it->addr, it->bytes, it->write, NULL,
		                                it->bank, it->row);
		if (!it->write)
			m->s.latency_ticks[r] += done - it->ready;
		if (it->done)
			eng_schedule(m->e, done, it->done, it->ctx, it->arg);
		if (m->sd->bus_free > now + m->lead) {
			wait_bus(m);
			return;
		}
	}
}

static void dispatch(eng *e, void *ctx, uint64_t arg)
{
	(void)arg;
	memif *m = ctx;
	uint64_t now = eng_now(e);
	m->armed &= m->armed_at != now; /* this was the armed one (no branch) */
	if (m->sd->bus_free > now + m->lead)
		wait_bus(m);
	else
		issue(m, now);
}

int memif_submit(memif *m, uint64_t t, int requester, uint64_t addr, uint32_t bytes, int write,
                 eng_handler done, void *ctx, uint64_t arg)
{
	if (m->free_head == MEMIF_NIL && grow(m))
		return -1;
	if (t < eng_now(m->e))
		t = eng_now(m->e);
	uint32_t bank, col;
	uint64_t row;
	sdram_decode(m->sd, addr, &bank, &row, &col);
	uint32_t i = m->free_head;
	memif_item *it = &m->pool[i];
	m->free_head = it->qnext;
	*it = (memif_item){.seq = m->seq++,
	                   .ready = t,
	                   .addr = addr,
	                   .row = row,
	                   .bytes = bytes,
	                   .bank = (uint16_t)bank,
	                   .write = (uint8_t)write,
	                   .req = (uint8_t)requester,
	                   .done = done,
	                   .ctx = ctx,
	                   .arg = arg};
	memif_queue *q = &m->q[requester];
	list_append(m->pool, &q->l, i, 0);
	q->n++;
	if (q->nwin < MEMIF_FRFCFS_WINDOW) {
		q->nwin++;
		bank_insert(m, i);
	} else if (q->wend == MEMIF_NIL) {
		q->wend = i;
	}
	m->queued++;
	if (write)
		m->s.writes[requester]++;
	else
		m->s.reads[requester]++;
	m->s.bytes[requester] += bytes;
	arm(m, t);
	return 0;
}
