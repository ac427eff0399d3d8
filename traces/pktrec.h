/*
 * pktrec.h: the packet record. What every packet of one frame did besides
 * its math, recorded once per scene, view and datapath: its memory
 * requests, unit operations, counter updates and the packets it spawned,
 * as one byte stream per packet, with the frame it drew. Replaying a
 * stream (sim/modes/replay.c) does to the memory model, the
 * units' counts and the counters exactly what running the packet does,
 * without tracing a ray, so functional and sampled modes warm the caches
 * far faster on every point of a sweep after the first. None of it
 * depends on the memory system, the units or the thread counts; what
 * does (datapath formats, stack depth, spill addresses) is in the key or
 * recomputed at replay. Kept in the world cache (worldcache.h);
 * docs/fidelity.md, "The packet record".
 *
 * A stream is a sequence of ops: one op byte, then its arguments as
 * LEB128 varints (7 bits per byte, low group first). A read (PR_READ,
 * PR_READ_SAME) ends with PR_SUM_BYTES bytes more, the checksum of the
 * bytes the read returned (pr_sum), which a replay compares with what its
 * own read returns (docs/fidelity.md, "What replay checks").
 */
#ifndef SAAR_TRACES_PKTREC_H
#define SAAR_TRACES_PKTREC_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "kernel-ref/framebuf.h"
#include "units/unit_table.h"

/* The codes after PR_USE's range follow it: one PR_USE code per unit kind
 * of units/unit_table.h, so a kind added there can collide with no other
 * op (the format changes with the table; records are keyed by the program
 * that wrote them, kernel-ref/worldcache.h). */
enum pr_op {
	PR_READ = 0, /* + memory type (0-3): address delta, bytes; checksum */
	PR_READ_SAME =
	    4,        /* + memory type: address delta; checksum; bytes as the type's last read */
	PR_WRITE = 8, /* + memory type: address, bytes */
	PR_USE = 12,  /* + unit kind (< UNIT_NKINDS): rays; ends a functional step */
	PR_SPILL_R = PR_USE + UNIT_NKINDS, /* stack entry index: the read of a spilled entry */
	PR_SPILL_W,                        /* stack entry index: a spill */
	PR_MAXSP,                          /* stack depth reached (trav.max_stack_depth) */
	PR_SHADE,                          /* shade_counts field, amount */
	PR_ENTER,                          /* packet type, rays: the packet enters a thread */
	PR_SPAWN,                          /* n, then n packet ids: children queued */
	PR_END,                            /* the packet is done */
	PR_WAIT,        /* wait for the reads so far before the next request (a use waits anyway) */
	PR_COUNT1 = 32, /* + counter (enum thr_counter, < 32): counter += 1 */
	PR_COUNT = 64,  /* + counter: amount; counter += amount */
	PR_NOPS = 96
};
_Static_assert(PR_WAIT < PR_COUNT1, "too many unit kinds for the packet record's op codes");
/* A read's address is the zigzag-mapped difference to the packet's
 * previous read of the same memory type (0 before its first). */

typedef struct pr_chunk pr_chunk;

typedef struct pktrec {
	int w, h, ntiles;
	int32_t *tile_pk; /* per tile (row-major): its primary packet's id, -1 */
	/* per packet: where it came from: -1 - tile for a primary packet,
	 * else its parent's id, and which of the parent's children it is */
	int32_t *from;
	uint8_t *kid;
	uint32_t npk;
	/* recording: per packet, its chunks' chain */
	pr_chunk *ch;
	uint32_t nch, capch, cappk;
	uint32_t *first, *last;
	int failed; /* out of memory: nothing is stored */
	/* loaded: one block (the stored tail) holding everything below,
	 * freed by pr_free when own */
	const void *block;
	int own;
	const uint64_t *off; /* npk + 1 stream offsets into blob */
	const uint8_t *blob;
	const uint32_t *acc32; /* the frame's accumulators, 32 or 64 bits */
	const uint64_t *acc64;
} pktrec;

/* An empty record for a w x h frame of ntiles tiles. -1 when out of
 * memory. */
int pr_init(pktrec *r, int w, int h, int ntiles);
void pr_free(pktrec *r);
/* A new packet stream: tile's primary packet, or child k of packet parent;
 * -1 when out of memory (r->failed is set and recording stops). */
int32_t pr_new(pktrec *r, int tile);
int32_t pr_new_kid(pktrec *r, int32_t parent, int k);
/* Appends op and its n (0-2) arguments to packet id's stream. */
void pr_put(pktrec *r, int32_t id, int op, int n, uint64_t a, uint64_t b);
/* Appends one bare varint (the ids after PR_SPAWN). */
void pr_put_u(pktrec *r, int32_t id, uint64_t v);

/* The stored form: the streams and fb's accumulators, one malloc'd block.
 * -1 when out of memory or the record failed. */
int pr_serialize(const pktrec *r, const framebuf *fb, void **out, size_t *n);
/* Takes a stored block for a w x h frame of ntiles tiles; -1 when it
 * does not hold one (damaged, other frame). With own, the block is
 * malloc'd and passes to r, also on failure; without, the caller keeps it
 * (and its 8-byte alignment) until pr_free. */
int pr_load(pktrec *r, const void *block, size_t n, int own, int w, int h, int ntiles);

/* Stream of packet id and its end; tile t's primary packet id, -1. */
static inline const uint8_t *pr_stream(const pktrec *r, uint32_t id, const uint8_t **end)
{
	*end = r->blob + r->off[id + 1];
	return r->blob + r->off[id];
}

/* Sets fb's pixels of tile (tx, ty) (tiles of tw x th pixels) to the
 * recorded frame's. */
void pr_put_tile(const pktrec *r, framebuf *fb, int tx, int ty, int tw, int th);

/* A read's checksum: its bytes taken 8 at a time (host order, as the
 * whole record), each word mixed in by a multiply and shift (both
 * bijections, so two reads differing in one word always differ in the
 * 64-bit state), the top PR_SUM_BYTES bytes of the final mix kept. A
 * damaged or wrong read passes unseen with odds 2^-16 per read; a damaged
 * triangle or node is read by many packets. Word by word, not FNV-1a's
 * byte by byte: byte-wise hashing took a quarter of a replay's host time.
 * Stored little-endian, after the read's arguments. */
enum { PR_SUM_BYTES = 2 };

static inline uint32_t pr_sum(const void *b, size_t n)
{
	const uint64_t k = 0xff51afd7ed558ccdull;
	const uint8_t *p = b;
	uint64_t h = 0x9e3779b97f4a7c15ull ^ n, w;
	for (; n >= 8; n -= 8, p += 8) {
		memcpy(&w, p, 8);
		h = (h ^ w) * k;
		h ^= h >> 29;
	}
	if (n) {
		/* the last 1-7 bytes as memcpy(&w, p, n) would place them, in
		 * fixed-size pieces (a call to memcpy cost more than the mix) */
		uint8_t tail[8] = {0};
		size_t o = 0;
		if (n & 4) {
			memcpy(tail, p, 4);
			o = 4;
		}
		if (n & 2) {
			memcpy(tail + o, p + o, 2);
			o += 2;
		}
		if (n & 1)
			tail[o] = p[o];
		memcpy(&w, tail, 8);
		h = (h ^ w) * k;
		h ^= h >> 29;
	}
	h = (h ^ h >> 32) * k;
	return (uint32_t)(h >> (64 - 8 * PR_SUM_BYTES));
}

/* Appends sum (pr_sum) to packet id's stream. */
void pr_put_sum(pktrec *r, int32_t id, uint32_t sum);

/* Reads a checksum; a damaged stream's end reads zeros. */
static inline uint32_t pr_get_sum(const uint8_t **p, const uint8_t *end)
{
	uint32_t v = 0;
	for (int k = 0; k < PR_SUM_BYTES; k++)
		if (*p < end)
			v |= (uint32_t) * (*p)++ << 8 * k;
	return v;
}

/* LEB128 encoding of v into b (10 bytes at most); returns the bytes
 * written. Packet records and memory traces (memtrace.c) share it. */
static inline int pr_put_var(uint8_t *b, uint64_t v)
{
	int n = 0;
	do {
		uint8_t x = v & 0x7f;
		v >>= 7;
		b[n++] = (uint8_t)(x | (v ? 0x80 : 0));
	} while (v);
	return n;
}
/* LEB128 decoding; stops at end (a damaged stream reads zeros). */
static inline uint64_t pr_get(const uint8_t **p, const uint8_t *end)
{
	if (*p < end && **p < 0x80)
		return *(*p)++;
	uint64_t v = 0;
	for (int s = 0; *p < end && s < 64; s += 7) {
		uint8_t b = *(*p)++;
		v |= (uint64_t)(b & 0x7f) << s;
		if (!(b & 0x80))
			break;
	}
	return v;
}

static inline uint64_t pr_zigzag(uint64_t d)
{
	return d << 1 ^ (uint64_t) - (int64_t)(d >> 63);
}

static inline uint64_t pr_unzigzag(uint64_t z)
{
	return z >> 1 ^ (uint64_t) - (int64_t)(z & 1);
}

#endif
