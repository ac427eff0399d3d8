/*
 * memtrace.h: zlib-compressed binary memory traces (writer and reader).
 *
 * One trace is a gzip stream of: a 32-byte header, fixed-size records, and
 * an end record. All integers little-endian.
 *
 *   header   0  char[8]  magic "SAARMTRC"
 *            8  u32      version (1)
 *           12  u32      record size in bytes (24)
 *           16  u32      fields: MTR_FIELDS (cycle, type, addr, bytes, write)
 *           20  u32      0
 *           24  u64      0
 *   record   0  u64      cycle (core cycles of the issuing chip)
 *            8  u64      address
 *           16  u32      bytes
 *           20  u8       requester type (MEM_SHADE..MEM_TRI)
 *           21  u8       write flag (0/1)
 *           22  u16      0
 *   end      a record with cycle = UINT64_MAX, type = 0xFF, and the record
 *            count in the address field.
 *
 * The end record is how a truncated trace is told from a complete one (gzip
 * also checks its CRC at the end); a record with a bad type or flag, a bad
 * header, a count mismatch or a zlib error is reported through diag as
 * "FILE: message"; the reader never crashes on bad input.
 */
#ifndef SAAR_TRACES_MEMTRACE_H
#define SAAR_TRACES_MEMTRACE_H

#include <stdint.h>

#include "diag.h"

#define MTR_MAGIC       "SAARMTRC"
#define MTR_VERSION     1u
#define MTR_HEADER_SIZE 32u
#define MTR_RECORD_SIZE 24u
#define MTR_FIELDS      0x1Fu /* bit per field: cycle type addr bytes write */
#define MTR_BUF         (1u << 16)

typedef struct mtr_rec {
	uint64_t cycle, addr;
	uint32_t bytes;
	uint8_t type, write;
} mtr_rec;

typedef struct mtr_writer {
	void *gz;
	uint64_t n;
	uint32_t used;
	char path[1024];
	unsigned char buf[MTR_BUF];
} mtr_writer;

typedef struct mtr_reader {
	void *gz;
	uint64_t n;
	uint32_t pos, len;
	int ended;
	char path[1024];
	unsigned char buf[MTR_BUF];
} mtr_reader;

int mtr_open_write(mtr_writer *w, const char *path, diag *d);
int mtr_write(mtr_writer *w, const mtr_rec *r, diag *d);
/* Writes the end record and closes; -1 on an I/O error. */
int mtr_close_write(mtr_writer *w, diag *d);

int mtr_open_read(mtr_reader *r, const char *path, diag *d);
/* 1: *out holds the next record; 0: clean end; -1: error (d filled). */
int mtr_read(mtr_reader *r, mtr_rec *out, diag *d);
void mtr_close_read(mtr_reader *r);

#endif
