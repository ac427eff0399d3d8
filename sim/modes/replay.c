/*
 * replay.c: a thread running a recorded packet stream (see replay.h). The
 * decoder turns each stored op back into the sink operation the unit code
 * emitted when it was recorded (units/sink.h: thr_read, thr_write,
 * thr_use, thr_count, ...), in the same order and, timed, at the same
 * ticks, so the caches, SDRAM, VMA, units and counters end up exactly as
 * after the math. It is no second pipeline: what an op costs is the
 * sink's.
 */
#include "sim/modes/replay.h"

#include <stdlib.h>
#include <string.h>

#include "sim/modes/functional.h"
#include "sim/modes/slot.h"

/* The children a packet's shading queued, in its stream as their ids. */
static void spawn(thr_ctx *t, uint64_t n, const uint8_t **p, const uint8_t *end)
{
	for (uint64_t k = 0; k < n; k++) {
		uint64_t id = pr_get(p, end);
		/* out of memory: the packet is lost and the image check says so */
		if (id < mode_slot(t)->src->npk) {
			int32_t i = (int32_t)id;
			thr_spawn(t, 1, NULL, &i);
		}
	}
}

static void run(thr_ctx *t);
static inline void check_reads(thr_ctx *t, mode_slot_state *m);

/* wait_reads' work when reads are outstanding: the sink's wait. */
static __attribute__((noinline)) int park(thr_ctx *t, mode_slot_state *m, const uint8_t *p)
{
	if (!thr_park_mem(t, run))
		return 0;
	m->rp = p;
	return 1;
}

/* The reads so far are still on their way (timed): the stream goes on
 * from p when they are in, as thr_wait_mem's continuation does. With none
 * outstanding (functional, always) the sink's wait would answer 0 (units/
 * sink.h), so it is not asked. */
static inline int wait_reads(thr_ctx *t, mode_slot_state *m, const uint8_t *p)
{
	if (t->pending && park(t, m, p))
		return 1;
	check_reads(t, m);
	return 0;
}

static void op_done(eng *e, void *ctx, uint64_t arg);

/* Room for a read of n bytes in slot m's buffer; NULL when out of memory.
 * A block with reads in flight is never moved: a larger one replaces it
 * and it is freed once they are in (checked). */
static uint8_t *room(mode_slot_state *m, uint32_t n)
{
	mode_rblk *b = m->rbuf;
	if (b && b->cap - b->used >= n) {
		b->used += n;
		return b->b + b->used - n;
	}
	/* small at first: every slot that replays has one (a million slots
	 * are a legal config); a node is 8 bytes, a triangle 36 */
	uint32_t cap = b && 2 * b->cap > n ? 2 * b->cap : n > 64 ? n : 64;
	mode_rblk *nb = malloc(sizeof *nb + cap);
	if (!nb)
		return NULL;
	nb->cap = cap;
	nb->used = n;
	nb->next = NULL;
	if (b && b->used)
		nb->next = b; /* still receiving */
	else
		free(b);
	m->rbuf = nb;
	return nb->b;
}

/* The first read whose bytes are not the recorded ones, described; the
 * packet's tile takes no pixels from the record. */
static void found(thr_ctx *t, const mode_rcheck *k, uint32_t got)
{
	mode_slot_state *m = mode_slot(t);
	mode_rbad *bad = m->bad;
	int32_t p = m->rec;
	while (p >= 0 && m->src->from[p] >= 0) /* up to the tile's primary */
		p = m->src->from[p];
	int32_t tile = p >= 0 ? -1 - m->src->from[p] : -1;
	if (!bad->n++)
		*bad = (mode_rbad){1,        m->rec, tile,   k->type,   k->addr,
		                   k->bytes, got,    k->sum, bad->tiles};
	if (bad->tiles && tile >= 0)
		bad->tiles[tile] = 2;
}

/* check_reads' work, when there is a read to check: every read's bytes
 * against the record's checksum, then the buffer emptied. */
static __attribute__((noinline)) void check_now(thr_ctx *t, mode_slot_state *m)
{
	for (uint32_t i = 0; i < m->nchk; i++) {
		const mode_rcheck *k = &m->chk[i];
		uint32_t got = pr_sum(k->at, k->bytes);
		if (got != k->sum)
			found(t, k, got);
	}
	m->nchk = 0;
	mode_rblk *b = m->rbuf;
	if (b) {
		for (mode_rblk *o = b->next, *n; o; o = n) {
			n = o->next;
			free(o);
		}
		b->next = NULL;
		b->used = 0;
	}
}

/* The reads so far are in (no read of the thread is outstanding): their
 * bytes' checksums against the record's. Most calls find none to check
 * (at a stream's resumption, before a unit op): an unchecked read is
 * what puts bytes in the buffer, so with none the buffer is empty too. */
static inline void check_reads(thr_ctx *t, mode_slot_state *m)
{
	if (!t->pending && m->nchk)
		check_now(t, m);
}

/* A replayed read: its bytes into the slot's buffer, checked against the
 * recorded checksum once they are in. A read in at once (functional:
 * nothing outstanding after it) with no earlier one awaiting its check is
 * checked here and its bytes given back, so a functional stream's reads
 * never pile up in m->chk. */
static void read_checked(thr_ctx *t, mode_slot_state *m, int type, uint64_t a, uint32_t bytes,
                         uint32_t sum)
{
	if (t->env->mutant == THR_MUT_REPLAY_NEXT_TRI && type == MEM_TRI)
		a += MIMG_TRI_BYTES; /* test hook */
	if (m->nchk == m->capchk) {
		uint32_t cap = m->capchk ? 2 * m->capchk : 4;
		mode_rcheck *c = realloc(m->chk, cap * sizeof *c);
		if (!c) {
			t->env->oom = 1; /* the frame fails */
			thr_read(t, type, a, bytes, NULL);
			return;
		}
		m->chk = c;
		m->capchk = cap;
	}
	uint8_t *dst = room(m, bytes);
	if (!dst) {
		t->env->oom = 1;
		thr_read(t, type, a, bytes, NULL);
		return;
	}
	thr_read(t, type, a, bytes, dst);
	mode_rcheck k = {dst, a, bytes, sum, type};
	if (!t->pending && !m->nchk) {
		uint32_t got = pr_sum(dst, bytes);
		m->rbuf->used -= bytes; /* room's, the block's last */
		if (got != sum)
			found(t, &k, got);
		return;
	}
	m->chk[m->nchk++] = k;
	check_reads(t, m);
}

/* A read or write op (below PR_USE). */
static void access(thr_ctx *t, mode_slot_state *m, int op, const uint8_t **p, const uint8_t *end)
{
	if (op >= PR_WRITE) {
		uint64_t a = pr_get(p, end), b = pr_get(p, end);
		thr_write(t, op & 3, a, (uint32_t)b, NULL);
		return;
	}
	int type = op & 3;
	uint64_t a = m->raddr[type] += pr_unzigzag(pr_get(p, end));
	if (op < PR_READ_SAME)
		m->rbytes[type] = (uint32_t)pr_get(p, end);
	read_checked(t, m, type, a, m->rbytes[type], pr_get_sum(p, end));
}

/* A shading count or a packet entering: the ops between PR_SPILL_R and
 * PR_SPAWN that neither wait nor end. */
static void other(thr_ctx *t, int op, const uint8_t **p, const uint8_t *end)
{
	uint64_t a, b;
	switch (op) {
	case PR_SPILL_R:
	case PR_SPILL_W:
		a = thr_spill_addr(t, pr_get(p, end) % PKT_STACK_MAX);
		if (op == PR_SPILL_W)
			thr_write(t, MEM_KD, a, THR_STACK_ENTRY_BYTES, NULL);
		else
			thr_read(t, MEM_KD, a, THR_STACK_ENTRY_BYTES, NULL);
		break;
	case PR_MAXSP:
		thr_count_max(t, C_MAX_SP, pr_get(p, end));
		break;
	case PR_SHADE:
		a = pr_get(p, end);
		b = pr_get(p, end);
		if (a < sizeof(shade_counts) / sizeof(uint64_t)) {
			shade_counts add;
			memset(&add, 0, sizeof add);
			((uint64_t *)&add)[a] = b;
			thr_shade_count(t, &add);
		}
		break;
	case PR_ENTER:
		a = pr_get(p, end) % PKT_NTYPES;
		memset(mode_slot(t)->raddr, 0, sizeof mode_slot(t)->raddr);
		memset(mode_slot(t)->rbytes, 0, sizeof mode_slot(t)->rbytes);
		thr_enter(t, (int)a, pr_get(p, end));
		break;
	}
}

/* Runs ops up to and including the next PR_USE (its unit op requested,
 * timed, or counted with op_done as the next step, functional), up to a
 * wait for reads in flight, or up to the end. */
static void run(thr_ctx *t)
{
	mode_slot_state *m = mode_slot(t);
	const uint8_t *p = m->rp, *end = m->rpe;
	int spawned = 0;
	check_reads(t, m); /* the reads waited for are in */
	while (p < end) {
		const uint8_t *at = p;
		int op = *p++;
		if (op < PR_USE) {
			access(t, m, op, &p, end);
		} else if (op < PR_SPILL_R) {
			/* the op starts once its reads are in (thr_wait_mem
			 * before every thr_use) */
			if (wait_reads(t, m, at))
				return;
			thr_use(t, op - PR_USE, (int)pr_get(&p, end), op_done);
			m->rp = p;
			return;
		} else if (op >= PR_COUNT1 && op < PR_NOPS) {
			int id = op & 31;
			uint64_t a = op < PR_COUNT ? 1 : pr_get(&p, end);
			if (id < C_NCOUNTERS)
				thr_count(t, id, a);
		} else if (op == PR_WAIT) {
			if (wait_reads(t, m, p))
				return;
		} else if (op == PR_SPAWN) {
			spawn(t, pr_get(&p, end), &p, end);
			spawned = 1;
		} else if (op < PR_END) {
			other(t, op, &p, end);
		} else { /* PR_END, or a damaged stream: the packet is done */
			p = end;
		}
	}
	check_reads(t, m);
	/* as shade_done and shadow_done: the slot is free, and after a
	 * shading op the RTP's idle slots get the children it queued */
	if (spawned)
		thr_release_shaded(t);
	else
		thr_release(t);
}

/* A unit op is done (timed), or functional processing takes the step
 * after it (mode_func_step). */
static void op_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	run(ctx);
}

void mode_replay_begin(const pktrec *r, thr_ctx *t, int32_t id)
{
	mode_slot_state *m = mode_slot(t);
	m->rec = id;
	m->src = r;
	m->rp = pr_stream(r, (uint32_t)id, &m->rpe);
	run(t);
}

void mode_replay_free(mode_slot_state *m)
{
	for (mode_rblk *b = m->rbuf, *n; b; b = n) {
		n = b->next;
		free(b);
	}
	m->rbuf = NULL;
	free(m->chk);
	m->chk = NULL;
	m->nchk = m->capchk = 0;
}

int mode_replay_save(const thr_ctx *t, mode_replay_state *s)
{
	const mode_slot_state *m = mode_slot(t);
	memset(s, 0, sizeof *s);
	s->rec = -1;
	if (t->p || (m->rp && !m->fnext) || m->nchk)
		return -1;
	if (!m->rp)
		return 0;
	const uint8_t *end, *st = pr_stream(m->src, (uint32_t)m->rec, &end);
	s->rec = m->rec;
	s->kind = (int16_t)m->fkind;
	s->rays = (int16_t)m->frays;
	s->off = (uint64_t)(m->rp - st);
	s->age = t->age;
	s->ptype = t->ptype;
	memcpy(s->raddr, m->raddr, sizeof s->raddr);
	memcpy(s->rbytes, m->rbytes, sizeof s->rbytes);
	return 0;
}

int mode_replay_restore(const pktrec *r, thr_ctx *t, const mode_replay_state *s)
{
	mode_slot_state *m = mode_slot(t);
	if (t->p) { /* its math: stored warming replays every packet */
		thr_pkt_free(t->env, t->p);
		t->p = NULL;
	}
	t->pending = 0;
	t->cont = NULL;
	mode_replay_free(m); /* no read is outstanding */
	m->rec = -1;
	m->rp = m->rpe = NULL;
	m->fnext = NULL;
	const uint8_t *end = NULL, *st = NULL;
	int ok = s->rec < 0;
	if (!ok && r && (uint32_t)s->rec < r->npk && s->kind >= 0 && s->kind < UNIT_NKINDS &&
	    s->ptype >= 0 && s->ptype < PKT_NTYPES) {
		st = pr_stream(r, (uint32_t)s->rec, &end);
		ok = s->off <= (uint64_t)(end - st);
	}
	if (s->rec < 0 || !ok) {
		if (t->state != THR_IDLE)
			thr_set(t, THR_IDLE);
		return ok ? 0 : -1;
	}
	m->rec = s->rec;
	m->src = r;
	m->rp = st + s->off;
	m->rpe = end;
	m->fnext = op_done;
	m->fkind = s->kind;
	m->frays = s->rays;
	t->age = s->age;
	t->ptype = s->ptype;
	memcpy(m->raddr, s->raddr, sizeof m->raddr);
	memcpy(m->rbytes, s->rbytes, sizeof m->rbytes);
	if (t->state == THR_IDLE)
		thr_set(t, THR_RUN);
	return 0;
}

int mode_queue_save(const thr_rtp *r, void *out)
{
	int n = rgs_queue_len(r);
	for (int i = 0; i < n; i++) {
		thr_qitem it = rgs_queue_at(r, i);
		if (it.p)
			return -1;
		memcpy((uint8_t *)out + 4 * (size_t)i, &it.rec, 4);
	}
	return 0;
}

int mode_queue_restore(const pktrec *rec, thr_rtp *r, const void *ids, int n)
{
	int32_t id;
	for (int i = 0; i < n; i++) {
		memcpy(&id, (const uint8_t *)ids + 4 * (size_t)i, 4);
		if (!rec || (uint32_t)id >= rec->npk)
			return -1;
	}
	rgs_queue_clear(r);
	for (int i = 0; i < n; i++) {
		memcpy(&id, (const uint8_t *)ids + 4 * (size_t)i, 4);
		if (rgs_queue_put(r, (thr_qitem){NULL, id}))
			return -1;
	}
	return 0;
}
