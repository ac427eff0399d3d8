/*
 * memtrace.c: trace writer and reader (format in memtrace.h).
 *
 * The writer encodes records into one block buffer and hands each full
 * block to gzwrite in one call. The reader pulls up to 256 KB of inflated
 * data per gzread call (gzip's CRC is checked once, at the end of the
 * stream) and decodes a whole block at a time into an array of records, so
 * the per-record cost is a few byte loads; mtr_read_block hands that array
 * out as is. Decoding needs no per-byte bounds checks: a block's payload is
 * in the buffer before it is decoded, MTR_SLACK zeroed bytes follow the
 * data, no record is longer than MTR_REC_MAX, and a record ending past the
 * payload is an error. Fixed-size fields are (de)serialized byte by byte in
 * little-endian order, independent of the host.
 */
#include "traces/memtrace.h"
#include "traces/pktrec.h"

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

/* ---- writer ---- */

/* The line for a gzwrite or gzclose that failed, e the errno right after
 * it: the system's reason when zlib's error is one of the system's (a full
 * disk, the file-size limit), else zlib's own. */
static int write_err(mtr_writer *w, int zerr, int e, const char *zmsg, diag *d)
{
	const char *why = zerr == Z_ERRNO && e ? strerror(e) : zmsg && *zmsg ? zmsg : "write error";
	return diag_set(d, w->path, 0, 0, "cannot write: %s", why);
}

/* gzwrite of n bytes; -1 with d set when it wrote less. */
static int gz_put(mtr_writer *w, const void *p, unsigned n, diag *d)
{
	errno = 0;
	if (gzwrite(w->gz, p, n) == (int)n)
		return 0;
	int e = errno, zerr;
	const char *zmsg = gzerror(w->gz, &zerr);
	return write_err(w, zerr, e, zmsg, d);
}

int mtr_open_write(mtr_writer *w, const char *path, diag *d)
{
	return mtr_open_write_as(w, path, path, d);
}

int mtr_open_write_as(mtr_writer *w, const char *path, const char *name, diag *d)
{
	memset(w, 0, sizeof *w);
	snprintf(w->path, sizeof w->path, "%s", name);
	gzFile gz = gzopen(path, MTR_GZ_MODE);
	if (!gz)
		return diag_set(d, name, 0, 0, "cannot write: %s", strerror(errno ? errno : EIO));
	w->gz = gz;
	gzbuffer(gz, 1u << 17);
	unsigned char h[MTR_HEADER_SIZE] = {0};
	memcpy(h, MTR_MAGIC, 8);
	put32(h + 8, MTR_VERSION);
	put32(h + 12, 0);
	put32(h + 16, MTR_FIELDS);
	if (gz_put(w, h, sizeof h, d)) {
		gzclose(gz);
		w->gz = NULL;
		return -1;
	}
	return 0;
}

/* Writes the open block (header + payload) in one gzwrite. */
static int flush_w(mtr_writer *w, diag *d)
{
	if (!w->nrec)
		return 0;
	put32(w->buf, w->nrec);
	put32(w->buf + 4, w->used);
	unsigned len = MTR_BLOCK_HDR + w->used;
	w->nrec = w->used = 0;
	return gz_put(w, w->buf, len, d);
}

int mtr_write(mtr_writer *w, const mtr_rec *r, diag *d)
{
	if (r->type >= 4 || r->write > 1)
		return diag_set(d, w->path, 0, 0, "cannot record type %u, write flag %u", r->type,
		                r->write);
	if (r->bytes > MTR_MAX_BYTES)
		return diag_set(d, w->path, 0, 0,
		                "cannot record a request of %u bytes (a trace holds at most %u)",
		                r->bytes, MTR_MAX_BYTES);
	unsigned char *p0 = w->buf + MTR_BLOCK_HDR + w->used, *p = p0 + 1;
	uint64_t dc = r->cycle - w->cycle;
	unsigned cc = dc < 7 ? (unsigned)dc : 7;
	if (cc == 7)
		p += pr_put_var(p, pr_zigzag(dc));
	p += pr_put_var(p, pr_zigzag(r->addr - w->addr[r->type]));
	unsigned bc = r->bytes == 8 ? 0 : r->bytes == 36 ? 1 : r->bytes == 4 ? 2 : 3;
	if (bc == 3)
		p += pr_put_var(p, r->bytes);
	*p0 = (unsigned char)(r->type | r->write << 2 | cc << 3 | bc << 6);
	w->cycle = r->cycle;
	w->addr[r->type] = r->addr;
	w->used += (uint32_t)(p - p0);
	w->n++;
	if (++w->nrec == MTR_BLOCK_RECS)
		return flush_w(w, d);
	return 0;
}

int mtr_close_write(mtr_writer *w, diag *d)
{
	int rc = flush_w(w, d);
	unsigned char end[MTR_BLOCK_HDR + 8];
	put32(end, 0);
	put32(end + 4, 8);
	put64(end + 8, w->n);
	if (!rc)
		rc = gz_put(w, end, sizeof end, d);
	errno = 0;
	int zc = gzclose(w->gz);
	if (zc != Z_OK && !rc)
		rc = write_err(w, zc, errno, NULL, d);
	w->gz = NULL;
	return rc;
}

/* ---- reader ---- */

/* Makes at least `need` unread bytes available if the stream has them,
 * keeping the unread tail; 0 ok (len - pos may stay short at the end of the
 * data), -1 on a zlib error. */
static int fill_r(mtr_reader *r, uint32_t need, diag *d)
{
	uint32_t left = r->len - r->pos;
	if (left >= need)
		return 0;
	memmove(r->buf, r->buf + r->pos, left);
	r->pos = 0;
	r->len = left;
	while (r->len < need) {
		int got = gzread(r->gz, r->buf + r->len, MTR_RBUF - r->len);
		int err = 0;
		const char *m = gzerror(r->gz, &err);
		/* zlib reports a stream cut short as Z_BUF_ERROR, possibly with
		 * data (got > 0) and possibly only on a later call that returns 0 */
		if (got < 0 || err != Z_OK)
			return diag_set(d, r->path, 0, 0, "%s trace (zlib: %s)",
			                err == Z_BUF_ERROR ? "truncated" : "corrupt",
			                m ? m : "error");
		if (got == 0)
			break;
		r->len += (uint32_t)got;
	}
	/* decoders may read up to MTR_SLACK bytes past the data: keep them
	 * defined (and harmless) */
	memset(r->buf + r->len, 0, MTR_SLACK);
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
	if (fill_r(r, MTR_HEADER_SIZE, d))
		goto bad;
	if (r->len < MTR_HEADER_SIZE || memcmp(r->buf, MTR_MAGIC, 8)) {
		diag_set(d, path, 0, 0, "not a saarsim memory trace (bad magic)");
		goto bad;
	}
	r->version = get32(r->buf + 8);
	if (r->version != 1 && r->version != MTR_VERSION) {
		diag_set(d, path, 0, 0, "unsupported trace version %u (this build reads 1 and %u)",
		         r->version, MTR_VERSION);
		goto bad;
	}
	uint32_t rs = get32(r->buf + 12);
	if (rs != (r->version == 1 ? MTR_V1_RECORD : 0) || get32(r->buf + 16) != MTR_FIELDS) {
		diag_set(d, path, 0, 0, "unsupported record layout (size %u, fields 0x%x)", rs,
		         get32(r->buf + 16));
		goto bad;
	}
	r->pos = MTR_HEADER_SIZE;
	return 0;
bad:
	mtr_close_read(r);
	return -1;
}

static int truncated(mtr_reader *r, diag *d)
{
	return diag_set(d, r->path, 0, 0,
	                "truncated trace: ends after %llu records without its end record",
	                (unsigned long long)r->n);
}

/* After the end block or record: the count must match, nothing may follow,
 * and reading to the end of the stream checks gzip's CRC. */
static int finish(mtr_reader *r, uint64_t count, diag *d)
{
	if (count != r->n)
		return diag_set(d, r->path, 0, 0,
		                "corrupt trace: end record counts %llu records, read %llu",
		                (unsigned long long)count, (unsigned long long)r->n);
	if (r->pos != r->len)
		return diag_set(d, r->path, 0, 0, "corrupt trace: data after the end record");
	if (fill_r(r, 1, d))
		return -1;
	if (r->len != r->pos)
		return diag_set(d, r->path, 0, 0, "corrupt trace: data after the end record");
	r->ended = 1;
	return 0;
}

/* Varint at p (at most 10 bytes; reading past a block's payload is caught
 * by the caller, and the buffer's slack keeps it in bounds). */
#define GETVAR(v, p)                                                                               \
	do {                                                                                       \
		uint64_t v_ = *p++;                                                                \
		if (v_ >= 0x80) {                                                                  \
			v_ &= 0x7F;                                                                \
			for (unsigned s_ = 7;; s_ += 7) {                                          \
				uint64_t b_ = *p++;                                                \
				v_ |= (b_ & 0x7F) << s_;                                           \
				if (b_ < 0x80)                                                     \
					break;                                                     \
				if (s_ == 63)                                                      \
					goto bad;                                                  \
			}                                                                          \
		}                                                                                  \
		v = v_;                                                                            \
	} while (0)

static int decode_v2(mtr_reader *r, diag *d)
{
	if (fill_r(r, MTR_BLOCK_HDR, d))
		return -1;
	if (r->len - r->pos < MTR_BLOCK_HDR)
		return truncated(r, d);
	const unsigned char *h = r->buf + r->pos;
	uint32_t nrec = get32(h), nbytes = get32(h + 4);
	if (nrec > MTR_BLOCK_RECS ||
	    (nrec ? nbytes > nrec * MTR_REC_MAX || nbytes < nrec : nbytes != 8))
		return diag_set(d, r->path, 0, 0,
		                "corrupt trace: bad block header after %llu records (%u records, "
		                "%u bytes)",
		                (unsigned long long)r->n, nrec, nbytes);
	if (fill_r(r, MTR_BLOCK_HDR + nbytes, d))
		return -1;
	if (r->len - r->pos < MTR_BLOCK_HDR + nbytes)
		return truncated(r, d);
	const unsigned char *p = r->buf + r->pos + MTR_BLOCK_HDR, *end = p + nbytes;
	r->pos += MTR_BLOCK_HDR + nbytes;
	if (!nrec) {
		int rc = finish(r, get64(p), d);
		return rc < 0 ? -1 : 0;
	}
	uint64_t cyc = r->cycle;
	mtr_rec *o = r->rec;
	for (uint32_t i = 0; i < nrec; i++, o++) {
		unsigned tag = *p++;
		unsigned t = tag & 3, cc = tag >> 3 & 7, bc = tag >> 6;
		if (cc == 7) {
			uint64_t z;
			GETVAR(z, p);
			cyc += pr_unzigzag(z);
		} else {
			cyc += cc;
		}
		uint64_t za;
		GETVAR(za, p);
		uint64_t a = r->addr[t] + pr_unzigzag(za);
		r->addr[t] = a;
		uint64_t nb = bc == 0 ? 8 : bc == 1 ? 36 : 4;
		if (bc == 3) {
			GETVAR(nb, p);
			if (nb > MTR_MAX_BYTES)
				goto big;
		}
		if (p > end)
			goto bad;
		o->cycle = cyc;
		o->addr = a;
		o->bytes = (uint32_t)nb;
		o->type = (uint8_t)t;
		o->write = (uint8_t)(tag >> 2 & 1);
	}
	if (p != end)
		goto bad;
	r->cycle = cyc;
	r->n += nrec;
	return (int)nrec;
bad:
	return diag_set(d, r->path, 0, 0,
	                "corrupt trace: bad record in the block after record %llu",
	                (unsigned long long)r->n);
big:
	return diag_set(d, r->path, 0, 0, "corrupt trace: record %llu asks for more than %u bytes",
	                (unsigned long long)(r->n + (uint64_t)(o - r->rec)), MTR_MAX_BYTES);
}

static int decode_v1(mtr_reader *r, diag *d)
{
	if (fill_r(r, MTR_BLOCK_RECS * MTR_V1_RECORD, d))
		return -1;
	uint32_t avail = (r->len - r->pos) / MTR_V1_RECORD, k = 0;
	if (!avail)
		return truncated(r, d);
	if (avail > MTR_BLOCK_RECS)
		avail = MTR_BLOCK_RECS;
	for (; k < avail; k++) {
		const unsigned char *p = r->buf + r->pos;
		mtr_rec *o = &r->rec[k];
		r->pos += MTR_V1_RECORD;
		o->cycle = get64(p);
		o->addr = get64(p + 8);
		o->bytes = get32(p + 16);
		o->type = p[20];
		o->write = p[21];
		if (o->type == 0xFF && o->cycle == UINT64_MAX) {
			if (k) { /* deliver the records before it first */
				r->pos -= MTR_V1_RECORD;
				break;
			}
			return finish(r, o->addr, d);
		}
		if (o->type >= 4 || o->write > 1 || p[22] || p[23])
			return diag_set(d, r->path, 0, 0,
			                "corrupt trace: bad record %llu (type %u, write %u)",
			                (unsigned long long)(r->n + k), o->type, o->write);
		if (o->bytes > MTR_MAX_BYTES)
			return diag_set(d, r->path, 0, 0,
			                "corrupt trace: record %llu asks for %u bytes (at most %u)",
			                (unsigned long long)(r->n + k), o->bytes, MTR_MAX_BYTES);
	}
	r->n += k;
	return (int)k;
}

int mtr_read_block(mtr_reader *r, const mtr_rec **recs, diag *d)
{
	if (r->next < r->have) { /* what mtr_read left of the current block */
		*recs = r->rec + r->next;
		int k = (int)(r->have - r->next);
		r->next = r->have;
		return k;
	}
	if (r->ended || !r->gz)
		return 0;
	int k = r->version == 1 ? decode_v1(r, d) : decode_v2(r, d);
	r->next = r->have = 0;
	*recs = r->rec;
	return k;
}

int mtr_read(mtr_reader *r, mtr_rec *out, diag *d)
{
	if (r->next == r->have) {
		if (r->ended || !r->gz)
			return 0;
		int k = r->version == 1 ? decode_v1(r, d) : decode_v2(r, d);
		r->next = 0;
		r->have = k > 0 ? (uint32_t)k : 0;
		if (k <= 0)
			return k;
	}
	*out = r->rec[r->next++];
	return 1;
}

void mtr_close_read(mtr_reader *r)
{
	if (r->gz)
		gzclose(r->gz);
	r->gz = NULL;
}
