/*
 * base.c: the operations the timed and the functional sink share (see
 * base.h).
 */
#include "sim/modes/base.h"

#include <string.h>

#include "sim/modes/slot.h"
#include "units/rgs.h"

/* The per-type counter (enum thr_type_counter) a thr_counter also
 * counts into, plus one; 0: none. A table, not a switch: every counter
 * update asks (a replayed stream's ops are mostly counts). */
static const uint8_t type_counter1[C_NCOUNTERS] = {
    [C_NODE_STEPS] = TC_NODE_STEPS + 1,       [C_LEAF_VISITS] = TC_LEAF_VISITS + 1,
    [C_LIST_ENTRIES] = TC_LIST_ENTRIES + 1,   [C_TRI_TESTS] = TC_TRI_TESTS + 1,
    [C_RAY_TRI_TESTS] = TC_RAY_TRI_TESTS + 1,
};

void mode_base_count(thr_sink *s, thr_ctx *t, int id, uint64_t n)
{
	(void)s;
	thr_env *v = t->env;
	*v->c[id] += n;
	unsigned tc = type_counter1[id];
	if (tc)
		*v->ct[t->ptype][tc - 1] += n;
}

void mode_base_use(thr_ctx *t, int kind, int rays)
{
	mode_base_use_issue(t, kind, rays, thr_unit_issue(&t->rtp->u[kind], rays));
}

void mode_base_count_max(thr_sink *s, thr_ctx *t, int id, uint64_t v)
{
	(void)s;
	if (v > *t->env->c[id])
		*t->env->c[id] = v;
}

void mode_base_shade(thr_sink *s, thr_ctx *t, const shade_counts *add)
{
	(void)s;
	uint64_t *a = (uint64_t *)&t->env->sh;
	const uint64_t *b = (const uint64_t *)add;
	for (size_t i = 0; i < sizeof(shade_counts) / sizeof(uint64_t); i++)
		a[i] += b[i];
}

void mode_base_enter(thr_sink *s, thr_ctx *t, int type, uint64_t rays)
{
	(void)s;
	thr_env *v = t->env;
	t->age = v->next_age++;
	t->ptype = type;
	++*v->c[C_PKT_PRIMARY + type];
	*v->c[C_RAYS_PRIMARY + type] += rays;
}

int mode_base_spawn(thr_sink *s, thr_ctx *t, int n, const packet *kids, const int32_t *ids)
{
	(void)s;
	thr_env *v = t->env;
	int lost = 0;
	for (int k = 0; k < n; k++) {
		packet *p = kids ? thr_pkt_alloc(v) : NULL;
		/* out of memory: the packet is lost and the image check says so */
		if ((kids && !p) || rgs_spawn(t->rtp, (thr_qitem){p, ids ? ids[k] : -1})) {
			if (p)
				thr_pkt_free(v, p);
			lost = 1;
			continue;
		}
		if (p)
			memcpy(p, &kids[k], sizeof *p);
	}
	return lost ? -1 : 0;
}

int mode_base_wait(thr_sink *s, thr_ctx *t, void (*cont)(thr_ctx *t))
{
	(void)s;
	if (t->pending == 0)
		return 0;
	t->cont = cont;
	thr_set(t, THR_WAIT_MEM);
	return 1;
}

void mode_base_end(thr_ctx *t, int shaded)
{
	if (shaded)
		rgs_spawned(t->rtp);
	mode_slot_state *m = mode_slot(t);
	m->rec = -1;
	if (t->p) /* a replayed packet has none */
		thr_pkt_free(t->env, t->p);
	t->p = NULL;
	m->rp = m->rpe = NULL;
	thr_set(t, THR_IDLE);
}
