/*
 * traversal.c: the traversal unit (see traversal.h).
 *
 * A step: the stack entries the pop looks at that live in memory (index
 * chip.stack_depth and up) are read back and decoded into the stack; then
 * the pop; then the node is read and the step is done on its bytes; a far
 * child pushed past the on-chip stack is written out. How many entries the
 * pop looks at is known before they are read (pkt_trav_pops, on the
 * copies the functional stack keeps: the read-back requests all go out at
 * once, a prefetch); if the bytes read back change that count (a damaged
 * spill area), the entries it then needs are read in a further round, so
 * the pop only ever sees entries as memory returned them.
 */
#include "units/traversal.h"

#include <stdlib.h>
#include <string.h>

static void cone_built(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	tu_step(ctx);
}

uint64_t tu_enter(thr_ctx *t, int scene_box)
{
	uint64_t enter =
	    pkt_trav_begin_fp(&t->ts, t->p, thr_img(t), t->stack, PKT_STACK_MAX, &t->env->prec);
	t->sp = 0;
	t->steps = 0;
	if (scene_box) { /* not an object's box, whose misses are no scene's */
		thr_count(t, C_BOX_MISS_RAYS, (uint64_t)thr_pop(t->p->valid & ~enter));
		thr_count(t, C_BOX_MISS_PACKETS, (uint64_t)!enter);
	}
	if (!enter)
		t->env->route.finish(t);
	return enter;
}

/* tu_begin and tu_begin_object: the packet enters the tree whose box is
 * the scene's (scene_box 1) or an object's (0). */
static void begin(thr_ctx *t, int scene_box)
{
	thr_env *v = t->env;
	uint64_t enter = tu_enter(t, scene_box);
	if (!enter)
		return;
	if (v->cone_cull) {
		/* seed 004 §4: the rays that entered, enclosed in a cone by the
		 * RGS, which holds them (one op of those rays) */
		cone_build(&t->cone, t->p, enter);
		thr_count(t, C_CONE_PACKETS, 1);
		thr_use(t, UNIT_RGS, thr_pop(enter), cone_built);
		return;
	}
	tu_step(t);
}

void tu_begin(thr_ctx *t)
{
	begin(t, 1);
}

void tu_begin_object(thr_ctx *t)
{
	begin(t, 0);
}

/* A stack entry in memory (THR_STACK_ENTRY_BYTES): node index (4), ray
 * mask (8), entry and exit distances (64 floats each), little-endian as
 * the host is. */
static void spill_pack(const trav_entry *e, uint8_t *b)
{
	memcpy(b, &e->node, 4);
	memcpy(b + 4, &e->mask, 8);
	memcpy(b + 12, e->tn, sizeof e->tn);
	memcpy(b + 12 + sizeof e->tn, e->tf, sizeof e->tf);
}

static void spill_unpack(const uint8_t *b, trav_entry *e)
{
	memcpy(&e->node, b, 4);
	memcpy(&e->mask, b + 4, 8);
	memcpy(e->tn, b + 12, sizeof e->tn);
	memcpy(e->tf, b + 12 + sizeof e->tn, sizeof e->tf);
}
_Static_assert(12 + 2 * sizeof(float) * PKT_RAYS == THR_STACK_ENTRY_BYTES, "spill entry size");

static void done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	thr_ctx *t = ctx;
	if (t->r.op == TRAV_LEAF)
		t->env->route.leaf(t);
	else
		tu_step(t);
}

/* The node arrived: the step on its bytes, a spill of the far child if
 * it went past the on-chip stack, then the unit's op. */
static void node_fetched(thr_ctx *t)
{
	thr_env *v = t->env;
	trav_result *r = &t->r;
	/* node data that loops (damaged memory, a wrong address) would keep
	 * the packet, and the frame, going for ever: end it and fail the
	 * frame instead */
	if (++t->steps > v->max_steps) {
		v->damaged = 1;
		t->sp = 0;
		t->env->route.finish(t);
		return;
	}
	pkt_trav_node(&t->ts, t->p, t->node, r);
	t->sp = r->sp;
	thr_count(t, C_NODE_STEPS, 1);
	thr_count_max(t, C_MAX_SP, (uint64_t)r->sp);
	if (r->pushed && r->sp - 1 >= v->stack_depth) {
		uint8_t b[THR_STACK_ENTRY_BYTES];
		spill_pack(&t->stack[r->sp - 1], b);
		thr_count(t, C_STACK_OVERFLOWS, 1);
		thr_write(t, MEM_KD, thr_spill_addr(t, (uint64_t)(r->sp - 1)),
		          THR_STACK_ENTRY_BYTES, b);
	}
	thr_use(t, UNIT_TRAV, thr_pop(r->mask), done);
}

/* Every entry the pop looks at is as memory returned it: pop, then read
 * the node (its address comes from the popped entry). */
static void pop(thr_ctx *t)
{
	thr_env *v = t->env;
	trav_result *r = &t->r;
	if (!pkt_trav_pop(&t->ts, t->p, r)) {
		t->sp = 0;
		t->env->route.finish(t);
		return;
	}
	uint32_t node = r->node;
	if (v->mutant == THR_MUT_KD_SIBLING && node) /* test hook: the pair's other node */
		node = node & 1 ? node + 1 : node - 1;
	thr_read(t, MEM_KD, mimg_node_addr(thr_img(t), node), MIMG_NODE_BYTES, &t->node);
	thr_wait_mem(t, node_fetched);
}

static void refill(thr_ctx *t);

/* Entries [rlo, rhi) came back: into the stack, then the pop may need
 * more. */
static void refilled(thr_ctx *t)
{
	for (int i = t->rlo; i < t->rhi; i++)
		spill_unpack(t->spill_in + (size_t)i * THR_STACK_ENTRY_BYTES, &t->stack[i]);
	refill(t);
}

/* Reads back the spilled entries the pop will look at that were not read
 * this step (top down, all at once), or pops when there are none. */
static void refill(thr_ctx *t)
{
	thr_env *v = t->env;
	/* nothing spilled (the usual case): no entry to read back */
	if (t->backed <= v->stack_depth) {
		pop(t);
		return;
	}
	int lo = t->ts.sp - pkt_trav_pops(&t->ts, t->p);
	if (lo < v->stack_depth)
		lo = v->stack_depth;
	if (lo >= t->backed) {
		pop(t);
		return;
	}
	if (!t->spill_in &&
	    !(t->spill_in = malloc((size_t)PKT_STACK_MAX * THR_STACK_ENTRY_BYTES))) {
		v->oom = 1; /* the frame fails; the copies stand in */
		t->backed = lo;
		pop(t);
		return;
	}
	t->rlo = lo;
	t->rhi = t->backed;
	for (int i = t->backed - 1; i >= lo; i--) {
		thr_count(t, C_STACK_REFILLS, 1);
		thr_read(t, MEM_KD, thr_spill_addr(t, (uint64_t)i), THR_STACK_ENTRY_BYTES,
		         t->spill_in + (size_t)i * THR_STACK_ENTRY_BYTES);
	}
	t->backed = lo;
	thr_wait_mem(t, refilled);
}

void tu_step(thr_ctx *t)
{
	t->backed = t->ts.sp; /* nothing read back yet */
	refill(t);
}
