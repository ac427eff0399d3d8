/*
 * modes.c: choosing the sink the units emit into (see modes.h).
 */
#include "sim/modes/modes.h"

#include "sim/modes/functional.h"
#include "sim/modes/timed.h"

/* thr_env.sink: the recording sink around the base, or the base. */
static void wire(mode_sinks *m)
{
	thr_sink *base = m->func_on ? &m->func : &m->timed;
	m->rec.s.inner = base;
	m->env->sink = m->rec.out ? &m->rec.s : base;
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
