/*
 * modes.c: choosing the sink the units emit into (see modes.h).
 */
#include "sim/modes/modes.h"

#include "sim/modes/functional.h"
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

void mode_sinks_init(mode_sinks *m, thr_env *v)
{
	*m = (mode_sinks){.env = v};
	m->timed.op = &mode_timed_ops;
	m->func.op = &mode_func_ops;
	m->rec.s.op = &mode_rec_ops;
	wire(m);
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
