/*
 * modes.c: choosing the sink the units emit into (see modes.h).
 */
#include "sim/modes/modes.h"

#include <stdlib.h>

#include "sim/modes/functional.h"
#include "sim/modes/replay.h"
#include "sim/modes/timed.h"

/* thr_env.sink: the observer around the recording sink around the base,
 * each when set. */
static void wire(mode_sinks *m)
{
	thr_sink *s = m->func_on ? &m->func : &m->timed;
	m->rec.s.inner = s;
	if (m->rec.out)
		s = &m->rec.s;
	if (m->obs) {
		m->obs->inner = s;
		s = m->obs;
	}
	m->env->sink = s;
}

int mode_sinks_init(mode_sinks *m, thr_env *v, int nslots, uint8_t *tiles)
{
	*m = (mode_sinks){.env = v, .nslots = nslots};
	m->slot = calloc((size_t)(nslots > 0 ? nslots : 1), sizeof *m->slot);
	if (!m->slot)
		return -1;
	m->bad.tiles = tiles;
	for (int i = 0; i < nslots; i++) {
		m->slot[i].rec = -1;
		m->slot[i].bad = &m->bad;
	}
	v->modes = m->slot;
	m->timed.op = &mode_timed_ops;
	m->func.op = &mode_func_ops;
	m->rec.s.op = &mode_rec_ops;
	wire(m);
	return 0;
}

void mode_sinks_free(mode_sinks *m)
{
	for (int i = 0; m->slot && i < m->nslots; i++)
		mode_replay_free(&m->slot[i]);
	free(m->slot);
	m->slot = NULL;
	free(m->rec.buf);
	m->rec.buf = NULL;
}

void mode_set_func(mode_sinks *m, int on)
{
	m->func_on = on;
	wire(m);
}

void mode_record(mode_sinks *m, pktrec *out)
{
	m->rec.out = out;
	wire(m);
}

void mode_observe(mode_sinks *m, thr_sink *obs)
{
	m->obs = obs;
	wire(m);
}
