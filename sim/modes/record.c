/*
 * record.c: the recording sink (see record.h).
 */
#include "sim/modes/record.h"

#include <stdlib.h>
#include <string.h>

#include "sim/modes/slot.h"

static void put(thr_sink *s, thr_ctx *t, int op, int n, uint64_t a, uint64_t b)
{
	pr_put(((mode_rec *)s)->out, mode_slot(t)->rec, op, n, a, b);
}

/* The checksum of the bytes a read of (type, addr, bytes) returns: those
 * memory holds there as it is made (mem_peek). A read returns them: no
 * write reaches the scene's data (spills, the only writes, are recorded
 * without one), and the recording run's units decode these very bytes.
 * Taken at the request because a timed read's bytes arrive later. */
static int read_sum(mode_rec *r, thr_ctx *t, int type, uint64_t addr, uint32_t bytes, uint32_t *sum)
{
	if (bytes > r->cap) {
		uint32_t cap = bytes > 2 * r->cap ? bytes : 2 * r->cap;
		uint8_t *b = realloc(r->buf, cap);
		if (!b)
			return -1;
		r->buf = b;
		r->cap = cap;
	}
	mem_req q = {addr, bytes, (uint8_t)type, 0, (uint16_t)t->rtp->id, NULL, 0};
	mem_peek(t->env->mem, &q, r->buf);
	*sum = pr_sum(r->buf, bytes);
	return 0;
}

/* Records a request: stack spills by entry index, since their address
 * belongs to the thread slot (thr_spill_addr), other requests as they
 * are, a read with its checksum. */
static void rec_req(thr_sink *s, thr_ctx *t, int write, int type, uint64_t addr, uint32_t bytes)
{
	mode_slot_state *m = mode_slot(t);
	/* a wait between requests (the node read after stack refills, the
	 * shading reads after them): a timed replay must make it too */
	if (m->rwait) {
		put(s, t, PR_WAIT, 0, 0, 0);
		m->rwait = 0;
	}
	m->rread |= !write;
	if (addr >= t->env->spill_base) {
		uint64_t idx = (addr - thr_spill_addr(t, 0)) / THR_SPILL_STRIDE;
		put(s, t, write ? PR_SPILL_W : PR_SPILL_R, 1, idx, 0);
		return;
	}
	if (write) {
		put(s, t, PR_WRITE + type, 2, addr, bytes);
		return;
	}
	mode_rec *r = (mode_rec *)s;
	uint32_t sum;
	if (read_sum(r, t, type, addr, bytes, &sum)) {
		r->out->failed = 1; /* out of memory: the record is not stored */
		return;
	}
	uint64_t z = pr_zigzag(addr - m->raddr[type]);
	m->raddr[type] = addr;
	if (bytes == m->rbytes[type]) {
		put(s, t, PR_READ_SAME + type, 1, z, 0);
	} else {
		m->rbytes[type] = bytes;
		put(s, t, PR_READ + type, 2, z, bytes);
	}
	pr_put_sum(r->out, m->rec, sum);
}

static void rec_read(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes, void *dst)
{
	rec_req(s, t, 0, type, addr, bytes);
	s->inner->op->read(s->inner, t, type, addr, bytes, dst);
}

static void rec_write(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes,
                      const void *src)
{
	rec_req(s, t, 1, type, addr, bytes);
	s->inner->op->write(s->inner, t, type, addr, bytes, src);
}

static int rec_wait(thr_sink *s, thr_ctx *t, void (*cont)(thr_ctx *t))
{
	mode_slot_state *m = mode_slot(t);
	if (m->rread) { /* recorded before the next request (rec_req) */
		m->rwait = 1;
		m->rread = 0;
	}
	return s->inner->op->wait(s->inner, t, cont);
}

static void rec_use(thr_sink *s, thr_ctx *t, int kind, int rays, eng_handler done)
{
	/* an op starts after every read so far: its wait is implied */
	mode_slot(t)->rread = mode_slot(t)->rwait = 0;
	put(s, t, PR_USE + kind, 1, (uint64_t)rays, 0);
	s->inner->op->use(s->inner, t, kind, rays, done);
}

static void rec_count(thr_sink *s, thr_ctx *t, int id, uint64_t n)
{
	if (n == 1)
		put(s, t, PR_COUNT1 + id, 0, 0, 0);
	else if (n)
		put(s, t, PR_COUNT + id, 1, n, 0);
	s->inner->op->count(s->inner, t, id, n);
}

/* A maximum keeps the values that raised it: replaying them all gives the
 * same maximum. */
static void rec_count_max(thr_sink *s, thr_ctx *t, int id, uint64_t v)
{
	if (v > *t->env->c[id])
		put(s, t, PR_MAXSP, 1, v, 0);
	s->inner->op->count_max(s->inner, t, id, v);
}

static void rec_shade(thr_sink *s, thr_ctx *t, const shade_counts *add)
{
	const uint64_t *b = (const uint64_t *)add;
	for (size_t i = 0; i < sizeof(shade_counts) / sizeof(uint64_t); i++)
		if (b[i])
			put(s, t, PR_SHADE, 2, (uint64_t)i, b[i]);
	s->inner->op->shade(s->inner, t, add);
}

static void rec_enter(thr_sink *s, thr_ctx *t, int type, uint64_t rays)
{
	mode_slot_state *m = mode_slot(t);
	memset(m->raddr, 0, sizeof m->raddr);
	memset(m->rbytes, 0, sizeof m->rbytes);
	put(s, t, PR_ENTER, 2, (uint64_t)type, rays);
	s->inner->op->enter(s->inner, t, type, rays);
}

/* The children's streams: each a new packet of the record, its id in the
 * parent's stream. */
static int rec_spawn(thr_sink *s, thr_ctx *t, int n, const packet *kids, const int32_t *ids)
{
	(void)ids;
	pktrec *out = ((mode_rec *)s)->out;
	put(s, t, PR_SPAWN, 1, (uint64_t)n, 0);
	int lost = 0;
	for (int k = 0; k < n; k++) {
		int32_t id = pr_new_kid(out, mode_slot(t)->rec, k);
		pr_put_u(out, mode_slot(t)->rec, (uint64_t)(id < 0 ? 0 : id));
		if (s->inner->op->spawn(s->inner, t, 1, kids ? &kids[k] : NULL, &id)) {
			out->failed = 1; /* a lost child: the record is not stored */
			lost = 1;
		}
	}
	return lost ? -1 : 0;
}

static void rec_release(thr_sink *s, thr_ctx *t, int shaded)
{
	put(s, t, PR_END, 0, 0, 0);
	mode_slot(t)->rec = -1;
	s->inner->op->release(s->inner, t, shaded);
}

const thr_sink_ops mode_rec_ops = {
    .read = rec_read,
    .write = rec_write,
    .wait = rec_wait,
    .use = rec_use,
    .count = rec_count,
    .count_max = rec_count_max,
    .shade = rec_shade,
    .enter = rec_enter,
    .spawn = rec_spawn,
    .release = rec_release,
};

void mode_rec_tile(mode_rec *m, thr_ctx *t, int tile)
{
	mode_slot(t)->rec = pr_new(m->out, tile);
}
