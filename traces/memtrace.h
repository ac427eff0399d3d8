/*
 * memtrace.h: zlib-compressed binary memory traces (writer and reader).
 *
 * One trace is a gzip stream of a 32-byte header and then, for version 2 (the
 * one written), blocks of variable-length records and an end block. All
 * fixed-size integers are little-endian.
 *
 *   header   0  char[8]  magic "SAARMTRC"
 *            8  u32      version (2; version 1 files are still read)
 *           12  u32      record size in bytes: 0 = variable (v1: 24)
 *           16  u32      fields: MTR_FIELDS (cycle, type, addr, bytes, write)
 *           20  u32      0
 *           24  u64      0
 *   block    0  u32      records in the block, 1..MTR_BLOCK_RECS (0: end block)
 *            4  u32      payload bytes that follow, at most records x
 *                        MTR_REC_MAX (end block: 8)
 *            8  ...      the records, back to back
 *   end      a block with 0 records and an 8-byte payload: u64 record count.
 *
 * A v2 record is one tag byte and up to three LEB128 varints (7 bits per
 * byte, low group first, high bit = more follows; at most 10 bytes):
 *
 *   tag      bits 0-1 type (MEM_SHADE..MEM_TRI), bit 2 write flag,
 *            bits 3-5 cycle code: 0-6 = cycle delta, 7 = a varint follows,
 *            bits 6-7 bytes code: 0 = 8, 1 = 36, 2 = 4, 3 = a varint follows
 *   [cycle]  zigzag(cycle - previous record's cycle), if cycle code 7
 *   address  zigzag(addr - previous address of the same type)
 *   [bytes]  bytes (<= MTR_MAX_BYTES), if bytes code 3
 *
 * Deltas are 64-bit wrapping differences, zigzag-mapped (0,-1,1,-2.. to
 * 0,1,2,3..), so any sequence round-trips; the previous cycle and the four
 * previous addresses start at 0 and carry across blocks. A Conference frame
 * averages about 4.2 bytes a record before compression (v1: 24).
 *
 * Version 1 (still read): after the header, 24-byte records (u64 cycle, u64
 * address, u32 bytes, u8 type, u8 write, u16 0) and an end record with
 * cycle = UINT64_MAX, type = 0xFF and the record count as its address.
 *
 * The end block (record) is how a truncated trace is told from a complete
 * one (gzip also checks its CRC at the end); a bad block header, a record
 * running past its block, a bad v1 type or flag, a bad header, a count
 * mismatch, data after the end or a zlib error is reported through diag as
 * "FILE: message"; the reader never crashes on bad input.
 */
#ifndef SAAR_TRACES_MEMTRACE_H
#define SAAR_TRACES_MEMTRACE_H

#include <stdint.h>

#include "kernel-ref/diag.h"

#define MTR_MAGIC       "SAARMTRC"
#define MTR_VERSION     2u
#define MTR_HEADER_SIZE 32u
#define MTR_V1_RECORD   24u
#define MTR_FIELDS      0x1Fu /* bit per field: cycle type addr bytes write */
/* The writer's gzip level: 0, stored blocks (gzip framing and CRC, no
 * deflate). The varint records are the compression: deflate only takes
 * another ~22% off them (address deltas are close to random) and inflating
 * that costs about as much as the whole rest of a replay; any gzip level is
 * read (`zcat t.gz | gzip -9` makes a smaller, slower trace). */
#define MTR_GZ_MODE       "wb0"
#define MTR_BLOCK_RECS    4096u
#define MTR_BLOCK_HDR     8u
#define MTR_REC_MAX       26u /* tag + 10-byte cycle + 10-byte address + 5-byte bytes */
#define MTR_BLOCK_PAYLOAD (MTR_BLOCK_RECS * MTR_REC_MAX)
#define MTR_WBUF          (MTR_BLOCK_HDR + MTR_BLOCK_PAYLOAD)
#define MTR_RBUF          (1u << 18) /* >= 2 blocks; gzread fills it in one call */
#define MTR_SLACK         32u        /* zeroed bytes past the data: a decoder may overrun */
/* The largest request a record may ask for, written or read: 16 MiB, a
 * leaf's list of four million triangles (the chip's largest requests are
 * list reads; a real leaf holds a handful). Replaying walks a request line
 * by line, so without a cap one 10-byte record could ask for 4 GiB and
 * keep a replay busy for minutes. */
#define MTR_MAX_BYTES (1u << 24)

typedef struct mtr_rec {
	uint64_t cycle, addr;
	uint32_t bytes;
	uint8_t type, write;
} mtr_rec;

typedef struct mtr_writer {
	void *gz;
	uint64_t n;
	uint64_t cycle, addr[4]; /* delta bases */
	uint32_t used, nrec;     /* payload bytes and records of the open block */
	char path[1024];
	unsigned char buf[MTR_WBUF];
} mtr_writer;

typedef struct mtr_reader {
	void *gz;
	uint64_t n;          /* records decoded so far */
	uint32_t version;    /* 1 or 2 */
	uint32_t pos, len;   /* unread bytes are buf[pos, len) */
	uint32_t next, have; /* mtr_read's position in rec[0, have) */
	int ended;
	uint64_t cycle, addr[4]; /* v2 delta bases */
	char path[1024];
	mtr_rec rec[MTR_BLOCK_RECS]; /* the current block, decoded */
	unsigned char buf[MTR_RBUF + MTR_SLACK];
} mtr_reader;

int mtr_open_write(mtr_writer *w, const char *path, diag *d);
/* The same, messages naming the file `name` (the user's path, when path is
 * the temporary it is written under): "name: cannot write: reason". */
int mtr_open_write_as(mtr_writer *w, const char *path, const char *name, diag *d);
/* Appends one record; -1 on an I/O error, a type >= 4, a write flag > 1 or
 * bytes > MTR_MAX_BYTES. */
int mtr_write(mtr_writer *w, const mtr_rec *r, diag *d);
/* Writes the end block and closes; -1 on an I/O error. */
int mtr_close_write(mtr_writer *w, diag *d);

int mtr_open_read(mtr_reader *r, const char *path, diag *d);
/* 1: *out holds the next record; 0: clean end; -1: error (d filled). */
int mtr_read(mtr_reader *r, mtr_rec *out, diag *d);
/* The next block of records at once (the fast path): > 0 records in *recs,
 * valid until the next call; 0: clean end; -1: error (d filled). After some
 * mtr_read calls it first returns the rest of the current block. */
int mtr_read_block(mtr_reader *r, const mtr_rec **recs, diag *d);
void mtr_close_read(mtr_reader *r);

#endif
