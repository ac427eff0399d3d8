/*
 * slot.h: what the sinks and replay keep per thread slot (sim/modes/;
 * docs/design-modes.md), outside thr_ctx: the units know nothing of it.
 * One per slot, indexed by thr_ctx.gid, reached through thr_env.modes.
 */
#ifndef SAAR_SIM_MODES_SLOT_H
#define SAAR_SIM_MODES_SLOT_H

#include "traces/pktrec.h"
#include "units/thread.h"

typedef struct mode_slot_state {
	/* the packet's stream in the packet record (recorded or replayed),
	 * -1: none */
	int32_t rec;
	/* the functional sink's: the thread's next step (the done handler of
	 * the unit op it stopped at), and that op (functional.c) */
	eng_handler fnext;
	int fkind, frays;
	/* replay: the record and the rest of the packet's stream (thr_ctx.p
	 * is then NULL) */
	const pktrec *src;
	const uint8_t *rp, *rpe;
	/* recording and replay: the packet's last read address and size per
	 * memory type (reads are stored as differences); recording: a read
	 * since the last wait or op, and a wait after reads not yet recorded
	 * (it goes in before the next request: PR_WAIT) */
	uint64_t raddr[MEM_NTYPES];
	uint32_t rbytes[MEM_NTYPES];
	uint8_t rread, rwait;
} mode_slot_state;

static inline mode_slot_state *mode_slot(const thr_ctx *t)
{
	return &((mode_slot_state *)t->env->modes)[t->gid];
}

#endif
