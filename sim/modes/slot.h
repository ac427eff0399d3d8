/*
 * slot.h: what the sinks and replay keep per thread slot (sim/modes/;
 * docs/design-modes.md), outside thr_ctx: the units know nothing of it.
 * One per slot, indexed by thr_ctx.gid, reached through thr_env.modes.
 */
#ifndef SAAR_SIM_MODES_SLOT_H
#define SAAR_SIM_MODES_SLOT_H

#include "traces/pktrec.h"
#include "units/thread.h"

/* A replayed read whose bytes are still to be checked: where they land,
 * and the record's checksum of what the recorded read returned. */
typedef struct mode_rcheck {
	const uint8_t *at;
	uint64_t addr;
	uint32_t bytes, sum;
	int type;
} mode_rcheck;

/* What replay found (replay.c): reads whose bytes' checksum is not the
 * record's. One per chip, shared by its slots; the first one described. */
typedef struct mode_rbad {
	uint64_t n;       /* all frames */
	int32_t pk, tile; /* the first: its packet, and that packet's tile */
	int type;         /* enum mem_req_type */
	uint64_t addr;    /* its address and size */
	uint32_t bytes;
	uint32_t got, want; /* the checksum of what it returned, the record's */
	/* per tile, this frame (the chip's `replayed`): set to 2 when one of
	 * the tile's packets read other bytes (its pixels are not taken from
	 * the record) */
	uint8_t *tiles;
} mode_rbad;

/* A block of a slot's replay buffer (reads in flight keep theirs). */
typedef struct mode_rblk {
	struct mode_rblk *next; /* an older block still holding bytes in flight */
	uint32_t cap, used;
	uint8_t b[];
} mode_rblk;

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
	/* replay: the reads not yet checked (their bytes in rbuf's blocks),
	 * and where findings go */
	mode_rblk *rbuf;
	mode_rcheck *chk;
	uint32_t nchk, capchk;
	mode_rbad *bad;
} mode_slot_state;

static inline mode_slot_state *mode_slot(const thr_ctx *t)
{
	return &((mode_slot_state *)t->env->modes)[t->gid];
}

#endif
