/*
 * replay.c: a thread running a recorded packet stream (see replay.h).
 * Each op calls what the unit code that recorded it called in functional
 * processing (thread.c thr_read / thr_write / thr_use / thr_count, rgs.c
 * rgs_enter_count / rgs_spawn), in the same order, so the caches, SDRAM,
 * VMA and counters end up exactly as after the math.
 */
#include "replay.h"

#include "rgs.h"

/* The children a packet's shading queued, in its stream as their ids. */
static void spawn(thr_ctx *t, uint64_t n, const uint8_t **p, const uint8_t *end)
{
	for (uint64_t k = 0; k < n; k++) {
		uint64_t id = pr_get(p, end);
		/* out of memory: the packet is lost and the image check says so */
		if (id < t->env->rec_in->npk)
			rgs_spawn(t->rtp, (thr_qitem){NULL, (int32_t)id});
	}
	rgs_spawned(t->rtp);
}

static void finish(thr_ctx *t)
{
	t->rp = t->rpe = NULL;
	t->rec = -1;
	thr_set(t, THR_IDLE);
}

/* Runs ops up to and including the next PR_USE or PR_END. */
static void run(thr_ctx *t)
{
	thr_env *v = t->env;
	const uint8_t *p = t->rp, *end = t->rpe;
	uint64_t *sh = (uint64_t *)&v->sh;
	while (p < end) {
		int op = *p++;
		uint64_t a, b;
		if (op < PR_WRITE) { /* a read: type in the low bits */
			int type = op & 3;
			a = t->raddr[type] += pr_unzigzag(pr_get(&p, end));
			if (op < PR_READ_SAME)
				t->rbytes[type] = (uint32_t)pr_get(&p, end);
			thr_read(t, type, a, t->rbytes[type]);
			continue;
		}
		if (op < PR_USE) {
			a = pr_get(&p, end);
			b = pr_get(&p, end);
			thr_write(t, op & 3, a, (uint32_t)b);
			continue;
		}
		if (op < PR_SPILL_R) {
			/* no completion: the stream says what comes next */
			thr_use(t, op - PR_USE, (int)pr_get(&p, end), NULL);
			t->rsteps++;
			t->rp = p;
			return;
		}
		if (op >= PR_COUNT1 && op < PR_NOPS) {
			int id = op & 31;
			a = op < PR_COUNT ? 1 : pr_get(&p, end);
			if (id < C_NCOUNTERS)
				thr_count(t, id, a);
			continue;
		}
		switch (op) {
		case PR_SPILL_R:
		case PR_SPILL_W:
			a = thr_spill_addr(t, pr_get(&p, end) % PKT_STACK_MAX);
			if (op == PR_SPILL_W)
				thr_write(t, MEM_KD, a, THR_STACK_ENTRY_BYTES);
			else
				thr_read(t, MEM_KD, a, THR_STACK_ENTRY_BYTES);
			break;
		case PR_MAXSP:
			thr_count_max(t, C_MAX_SP, pr_get(&p, end));
			break;
		case PR_SHADE:
			a = pr_get(&p, end);
			b = pr_get(&p, end);
			if (a < sizeof(shade_counts) / sizeof(uint64_t))
				sh[a] += b;
			break;
		case PR_ENTER:
			a = pr_get(&p, end) % PKT_NTYPES;
			rgs_enter_count(t, (int)a, pr_get(&p, end));
			break;
		case PR_SPAWN:
			spawn(t, pr_get(&p, end), &p, end);
			break;
		default: /* PR_END, or a damaged stream: the packet is done */
			p = end;
			break;
		}
	}
	finish(t);
}

void thr_replay_begin(thr_ctx *t, int32_t id)
{
	const pktrec *r = t->env->rec_in;
	t->rec = id;
	t->rsteps = 0;
	t->rp = pr_stream(r, (uint32_t)id, &t->rpe);
	run(t);
}

int thr_replay_step(thr_ctx *t)
{
	if (!t->rp)
		return 0;
	run(t);
	return 1;
}

/* ---- rebuilding packets: the math, silently (thr_env.silent) ---- */

static void tile_of(const thr_env *v, int32_t from, int *tx, int *ty)
{
	int tile = -1 - from, tiles_x = (v->rec_in->w + TILE_W - 1) / TILE_W;
	*tx = tile % tiles_x;
	*ty = tile / tiles_x;
}

/* Packet id as it entered its thread, into out: a primary from the
 * camera; a child by running its parent (rebuilt the same way) on the
 * scratch thread s up to its shading, which makes the children. */
static int make(thr_ctx *s, int32_t id, packet *out)
{
	thr_env *v = s->env;
	const pktrec *r = v->rec_in;
	int32_t from = r->from[id];
	if (from < 0) {
		int tx, ty;
		tile_of(v, from, &tx, &ty);
		cam_primary_packet(&v->cam, tx, ty, out);
		return 0;
	}
	packet *pp = thr_pkt_alloc(v);
	if (!pp || make(s, from, pp)) {
		if (pp)
			thr_pkt_free(v, pp);
		return -1;
	}
	s->made = -1;
	s->fnext = NULL;
	rgs_secondary(s, pp); /* enter, then traversal (no RGS op: nothing to count) */
	while (s->made < 0 && thr_step_func(s))
		;
	int k = r->kid[id], ok = s->made > k;
	if (ok)
		*out = s->kids[k];
	thr_pkt_free(v, pp);
	s->p = NULL;
	s->fnext = NULL;
	return ok ? 0 : -1;
}

int thr_replay_rebuild(thr_ctx *t, thr_ctx *s)
{
	thr_env *v = t->env;
	if (!t->rp)
		return 0;
	shade_counts sh = v->sh;
	uint64_t age = t->age;
	uint32_t steps = t->rsteps;
	int32_t id = t->rec, from = v->rec_in->from[id], rc = 0, func = v->func;
	v->silent = v->func = 1;
	t->rp = t->rpe = NULL;
	if (from < 0) {
		int tx, ty;
		tile_of(v, from, &tx, &ty);
		rc = rgs_primary(t, tx, ty);
	} else {
		packet *p = thr_pkt_alloc(v);
		if (!p || make(s, id, p)) {
			if (p)
				thr_pkt_free(v, p);
			rc = -1;
		} else {
			rgs_secondary(t, p);
		}
	}
	/* the steps the stream had made (the first came with the packet) */
	for (uint32_t i = 1; !rc && i < steps; i++)
		thr_step_func(t);
	v->silent = 0;
	v->func = func;
	v->sh = sh;
	t->age = age;
	return rc;
}

int thr_replay_rebuild_queue(thr_rtp *r, thr_ctx *s)
{
	thr_env *v = r->env;
	shade_counts sh = v->sh;
	int rc = 0, func = v->func;
	v->silent = v->func = 1;
	for (int i = 0; i < r->qn && !rc; i++) {
		thr_qitem *it = &r->q[(r->qhead + i) % r->qcap];
		if (it->p)
			continue;
		packet *p = thr_pkt_alloc(v);
		if (!p || make(s, it->rec, p)) {
			if (p)
				thr_pkt_free(v, p);
			rc = -1;
		} else {
			it->p = p;
		}
	}
	v->silent = 0;
	v->func = func;
	v->sh = sh;
	return rc;
}
