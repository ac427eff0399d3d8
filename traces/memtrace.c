/*
 * memtrace.c: trace writer and reader (format in memtrace.h).
 *
 * Both sides batch records through a 64 KB buffer so gzwrite/gzread run a
 * few times per thousand records; fields are (de)serialized byte by byte in
 * little-endian order, independent of the host.
 */
#include "memtrace.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <zlib.h>

static void put32(unsigned char *p, uint32_t v)
{
	for (int i = 0; i < 4; i++)
		p[i] = (unsigned char)(v >> (8 * i));
}
static void put64(unsigned char *p, uint64_t v)
{
	for (int i = 0; i < 8; i++)
		p[i] = (unsigned char)(v >> (8 * i));
}
static uint32_t get32(const unsigned char *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint64_t get64(const unsigned char *p)
{
	return (uint64_t)get32(p) | (uint64_t)get32(p + 4) << 32;
}

static void enc(unsigned char *p, const mtr_rec *r)
{
	put64(p, r->cycle);
	put64(p + 8, r->addr);
	put32(p + 16, r->bytes);
	p[20] = r->type;
	p[21] = r->write;
	p[22] = p[23] = 0;
}

/* ---- writer ---- */

int mtr_open_write(mtr_writer *w, const char *path, diag *d)
{
	memset(w, 0, sizeof *w);
	snprintf(w->path, sizeof w->path, "%s", path);
	gzFile gz = gzopen(path, "wb6");
	if (!gz)
		return diag_set(d, path, 0, 0, "cannot write: %s", strerror(errno ? errno : EIO));
	w->gz = gz;
	unsigned char h[MTR_HEADER_SIZE] = {0};
	memcpy(h, MTR_MAGIC, 8);
	put32(h + 8, MTR_VERSION);
	put32(h + 12, MTR_RECORD_SIZE);
	put32(h + 16, MTR_FIELDS);
	memcpy(w->buf, h, sizeof h);
	w->used = sizeof h;
	return 0;
}

static int flush_w(mtr_writer *w, diag *d)
{
	if (w->used && gzwrite(w->gz, w->buf, w->used) != (int)w->used)
		return diag_set(d, w->path, 0, 0, "write error");
	w->used = 0;
	return 0;
}

int mtr_write(mtr_writer *w, const mtr_rec *r, diag *d)
{
	if (w->used + MTR_RECORD_SIZE > MTR_BUF && flush_w(w, d))
		return -1;
	enc(w->buf + w->used, r);
	w->used += MTR_RECORD_SIZE;
	w->n++;
	return 0;
}

int mtr_close_write(mtr_writer *w, diag *d)
{
	mtr_rec end = {UINT64_MAX, w->n, 0, 0xFF, 0};
	int rc = 0;
	if (w->used + MTR_RECORD_SIZE > MTR_BUF)
		rc = flush_w(w, d);
	enc(w->buf + w->used, &end);
	w->used += MTR_RECORD_SIZE;
	if (!rc)
		rc = flush_w(w, d);
	if (gzclose(w->gz) != Z_OK && !rc)
		rc = diag_set(d, w->path, 0, 0, "write error on close");
	w->gz = NULL;
	return rc;
}

/* ---- reader ---- */

/* Refills the buffer keeping the unread tail; 0 ok (len may stay short at
 * end of data), -1 on a zlib error. */
static int fill_r(mtr_reader *r, diag *d)
{
	uint32_t left = r->len - r->pos;
	memmove(r->buf, r->buf + r->pos, left);
	r->pos = 0;
	r->len = left;
	int got = gzread(r->gz, r->buf + left, MTR_BUF - left);
	int err = 0;
	const char *m = gzerror(r->gz, &err);
	/* zlib reports a stream cut short as Z_BUF_ERROR, possibly with data
	 * (got > 0) and possibly only on a later call that returns 0 */
	if (got < 0 || err != Z_OK) {
		return diag_set(d, r->path, 0, 0, "%s trace (zlib: %s)",
		                err == Z_BUF_ERROR ? "truncated" : "corrupt", m ? m : "error");
	}
	r->len += (uint32_t)got;
	return 0;
}

int mtr_open_read(mtr_reader *r, const char *path, diag *d)
{
	memset(r, 0, sizeof *r);
	snprintf(r->path, sizeof r->path, "%s", path);
	gzFile gz = gzopen(path, "rb");
	if (!gz)
		return diag_set(d, path, 0, 0, "cannot open: %s", strerror(errno ? errno : ENOENT));
	gzbuffer(gz, 1u << 17);
	r->gz = gz;
	if (fill_r(r, d))
		goto bad;
	if (r->len < MTR_HEADER_SIZE || memcmp(r->buf, MTR_MAGIC, 8)) {
		diag_set(d, path, 0, 0, "not a saarsim memory trace (bad magic)");
		goto bad;
	}
	if (get32(r->buf + 8) != MTR_VERSION) {
		diag_set(d, path, 0, 0, "unsupported trace version %u (this build reads %u)",
		         get32(r->buf + 8), MTR_VERSION);
		goto bad;
	}
	if (get32(r->buf + 12) != MTR_RECORD_SIZE || get32(r->buf + 16) != MTR_FIELDS) {
		diag_set(d, path, 0, 0, "unsupported record layout (size %u, fields 0x%x)",
		         get32(r->buf + 12), get32(r->buf + 16));
		goto bad;
	}
	r->pos = MTR_HEADER_SIZE;
	return 0;
bad:
	mtr_close_read(r);
	return -1;
}

int mtr_read(mtr_reader *r, mtr_rec *out, diag *d)
{
	if (r->ended)
		return 0;
	if (r->len - r->pos < MTR_RECORD_SIZE) {
		if (fill_r(r, d))
			return -1;
		if (r->len - r->pos < MTR_RECORD_SIZE)
			return diag_set(
			    d, r->path, 0, 0,
			    "truncated trace: ends after %llu records without its end record",
			    (unsigned long long)r->n);
	}
	const unsigned char *p = r->buf + r->pos;
	r->pos += MTR_RECORD_SIZE;
	out->cycle = get64(p);
	out->addr = get64(p + 8);
	out->bytes = get32(p + 16);
	out->type = p[20];
	out->write = p[21];
	if (out->type == 0xFF && out->cycle == UINT64_MAX) {
		if (out->addr != r->n)
			return diag_set(d, r->path, 0, 0,
			                "corrupt trace: end record counts %llu records, read %llu",
			                (unsigned long long)out->addr, (unsigned long long)r->n);
		/* nothing may follow, and reading to the end checks gzip's CRC */
		if (r->pos != r->len || fill_r(r, d))
			return r->pos != r->len
			           ? diag_set(d, r->path, 0, 0,
			                      "corrupt trace: data after the end record")
			           : -1;
		if (r->len)
			return diag_set(d, r->path, 0, 0,
			                "corrupt trace: data after the end record");
		r->ended = 1;
		return 0;
	}
	if (out->type >= 4 || out->write > 1 || p[22] || p[23])
		return diag_set(d, r->path, 0, 0,
		                "corrupt trace: bad record %llu (type %u, write %u)",
		                (unsigned long long)r->n, out->type, out->write);
	r->n++;
	return 1;
}

void mtr_close_read(mtr_reader *r)
{
	if (r->gz)
		gzclose(r->gz);
	r->gz = NULL;
}
