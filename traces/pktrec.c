/*
 * pktrec.c: recording, storing and loading packet records (see
 * pktrec.h). While recording, every packet's stream grows as a chain of
 * fixed-size chunks (packets of a busy chip run interleaved); storing
 * lays the streams end to end.
 *
 * Stored form (little-endian host order; the world cache's CRC and key
 * guard it, pr_load checks its shape):
 *   u32 magic "PKR3", w, h, ntiles, npk, acc bits (32/64), u64 blob bytes
 *   i32 tile_pk[ntiles], padded to 8 bytes
 *   i32 from[npk], padded to 8 bytes; u8 kid[npk], padded to 8 bytes
 *   u64 off[npk + 1]
 *   u8  blob[blob bytes], padded to 8 bytes
 *   u32 or u64 acc[w * h * 3]
 */
#include "traces/pktrec.h"

#include <stdlib.h>
#include <string.h>

#define PR_CHUNK 248

struct pr_chunk {
	uint32_t next, n;
	uint8_t b[PR_CHUNK];
};

/* "PKR3": PKR1 had no PR_WAIT, PKR2 no reads' checksums (its reads would
 * decode wrongly: it is refused, and recorded anew) */
enum { PR_MAGIC = 0x33524b50 };

typedef struct pr_head {
	uint32_t magic, w, h, ntiles, npk, accbits;
	uint64_t nblob;
} pr_head;

int pr_init(pktrec *r, int w, int h, int ntiles)
{
	memset(r, 0, sizeof *r);
	r->w = w;
	r->h = h;
	r->ntiles = ntiles;
	r->tile_pk = malloc((size_t)ntiles * sizeof *r->tile_pk);
	r->capch = 1024;
	r->ch = malloc(r->capch * sizeof *r->ch);
	r->nch = 1; /* chunk 0 means "none" */
	if (!r->tile_pk || !r->ch) {
		pr_free(r);
		return -1;
	}
	for (int i = 0; i < ntiles; i++)
		r->tile_pk[i] = -1;
	return 0;
}

void pr_free(pktrec *r)
{
	if (!r->block) {
		free(r->tile_pk);
		free(r->from);
		free(r->kid);
	}
	free(r->ch);
	free(r->first);
	free(r->last);
	if (r->own)
		free((void *)r->block);
	memset(r, 0, sizeof *r);
}

static uint32_t new_chunk(pktrec *r)
{
	if (r->nch == r->capch) {
		pr_chunk *c = realloc(r->ch, 2 * (size_t)r->capch * sizeof *c);
		if (!c) {
			r->failed = 1;
			return 0;
		}
		r->ch = c;
		r->capch *= 2;
	}
	r->ch[r->nch].next = 0;
	r->ch[r->nch].n = 0;
	return r->nch++;
}

static int32_t new_packet(pktrec *r, int32_t from, int k)
{
	if (r->failed || r->npk >= INT32_MAX)
		return -1;
	if (r->npk == r->cappk) {
		uint32_t cap = r->cappk ? 2 * r->cappk : 4096;
		uint32_t *f = realloc(r->first, cap * sizeof *f);
		if (f)
			r->first = f;
		uint32_t *l = f ? realloc(r->last, cap * sizeof *l) : NULL;
		if (l)
			r->last = l;
		int32_t *fr = l ? realloc(r->from, cap * sizeof *fr) : NULL;
		if (fr)
			r->from = fr;
		uint8_t *kd = fr ? realloc(r->kid, cap) : NULL;
		if (!kd) {
			r->failed = 1;
			return -1;
		}
		r->kid = kd;
		r->cappk = cap;
	}
	uint32_t c = new_chunk(r);
	if (!c)
		return -1;
	r->first[r->npk] = r->last[r->npk] = c;
	r->from[r->npk] = from;
	r->kid[r->npk] = (uint8_t)k;
	return (int32_t)r->npk++;
}

int32_t pr_new(pktrec *r, int tile)
{
	if (tile < 0 || tile >= r->ntiles)
		return -1;
	int32_t id = new_packet(r, -1 - tile, 0);
	if (id >= 0)
		r->tile_pk[tile] = id;
	return id;
}

int32_t pr_new_kid(pktrec *r, int32_t parent, int k)
{
	if (parent < 0 || k < 0 || k > UINT8_MAX) {
		r->failed = 1;
		return -1;
	}
	return new_packet(r, parent, k);
}

static void append(pktrec *r, int32_t id, const uint8_t *b, int n)
{
	if (id < 0 || r->failed)
		return;
	pr_chunk *c = &r->ch[r->last[id]];
	if (c->n + (uint32_t)n > PR_CHUNK) {
		uint32_t k = new_chunk(r);
		if (!k)
			return;
		c = &r->ch[r->last[id]]; /* the array may have moved */
		c->next = k;
		r->last[id] = k;
		c = &r->ch[k];
	}
	memcpy(c->b + c->n, b, (size_t)n);
	c->n += (uint32_t)n;
}

void pr_put(pktrec *r, int32_t id, int op, int n, uint64_t a, uint64_t b)
{
	uint8_t buf[1 + 2 * 10];
	int k = 0;
	buf[k++] = (uint8_t)op;
	if (n > 0)
		k += pr_put_var(buf + k, a);
	if (n > 1)
		k += pr_put_var(buf + k, b);
	append(r, id, buf, k);
}

void pr_put_u(pktrec *r, int32_t id, uint64_t v)
{
	uint8_t buf[10];
	append(r, id, buf, pr_put_var(buf, v));
}

void pr_put_sum(pktrec *r, int32_t id, uint32_t sum)
{
	uint8_t buf[PR_SUM_BYTES];
	for (int k = 0; k < PR_SUM_BYTES; k++)
		buf[k] = (uint8_t)(sum >> 8 * k);
	append(r, id, buf, PR_SUM_BYTES);
}

static size_t pad8(size_t n)
{
	return (n + 7) & ~(size_t)7;
}

int pr_serialize(const pktrec *r, const framebuf *fb, void **out, size_t *n)
{
	*out = NULL;
	*n = 0;
	if (r->failed || !r->first || fb->w != r->w || fb->h != r->h)
		return -1;
	uint64_t nblob = 0;
	for (uint32_t c = 1; c < r->nch; c++)
		nblob += r->ch[c].n;
	size_t npx = (size_t)r->w * (size_t)r->h * 3;
	int bits = 32;
	for (size_t i = 0; i < npx; i++)
		if (fb->acc[i] > UINT32_MAX) {
			bits = 64;
			break;
		}
	size_t o_tiles = sizeof(pr_head), o_from = o_tiles + pad8((size_t)r->ntiles * 4);
	size_t o_kid = o_from + pad8((size_t)r->npk * 4), o_off = o_kid + pad8(r->npk);
	size_t o_blob = o_off + ((size_t)r->npk + 1) * 8, o_acc = o_blob + pad8(nblob);
	size_t total = o_acc + npx * (size_t)(bits / 8);
	uint8_t *b = calloc(1, total);
	if (!b)
		return -1;
	pr_head h = {PR_MAGIC,         (uint32_t)r->w, (uint32_t)r->h, (uint32_t)r->ntiles,
	             (uint32_t)r->npk, (uint32_t)bits, nblob};
	memcpy(b, &h, sizeof h);
	memcpy(b + o_tiles, r->tile_pk, (size_t)r->ntiles * 4);
	memcpy(b + o_from, r->from, (size_t)r->npk * 4);
	memcpy(b + o_kid, r->kid, r->npk);
	uint64_t *off = (uint64_t *)(void *)(b + o_off), pos = 0;
	uint8_t *blob = b + o_blob;
	for (uint32_t p = 0; p < r->npk; p++) {
		off[p] = pos;
		for (uint32_t c = r->first[p]; c; c = r->ch[c].next) {
			memcpy(blob + pos, r->ch[c].b, r->ch[c].n);
			pos += r->ch[c].n;
		}
	}
	off[r->npk] = pos;
	if (bits == 32) {
		uint32_t *a = (uint32_t *)(void *)(b + o_acc);
		for (size_t i = 0; i < npx; i++)
			a[i] = (uint32_t)fb->acc[i];
	} else {
		memcpy(b + o_acc, fb->acc, npx * 8);
	}
	*out = b;
	*n = total;
	return 0;
}

int pr_load(pktrec *r, const void *block, size_t n, int own, int w, int h, int ntiles)
{
	memset(r, 0, sizeof *r);
	r->block = block;
	r->own = own;
	pr_head hd;
	if (!block || n < sizeof hd)
		goto bad;
	memcpy(&hd, block, sizeof hd);
	if (hd.magic != PR_MAGIC || hd.w != (uint32_t)w || hd.h != (uint32_t)h ||
	    hd.ntiles != (uint32_t)ntiles || (hd.accbits != 32 && hd.accbits != 64) ||
	    hd.npk > INT32_MAX)
		goto bad;
	size_t npx = (size_t)w * (size_t)h * 3;
	size_t o_tiles = sizeof hd, o_from = o_tiles + pad8((size_t)ntiles * 4);
	size_t o_kid = o_from + pad8((size_t)hd.npk * 4), o_off = o_kid + pad8(hd.npk);
	size_t o_blob = o_off + ((size_t)hd.npk + 1) * 8;
	if (hd.nblob > n || o_blob > n)
		goto bad;
	size_t o_acc = o_blob + pad8((size_t)hd.nblob);
	if (o_acc + npx * (hd.accbits / 8) != n)
		goto bad;
	/* never written through: a loaded record is read-only (it may be a
	 * read-only mapping, wc_get_mapped) */
	uint8_t *b = (uint8_t *)block;
	r->w = w;
	r->h = h;
	r->ntiles = ntiles;
	r->npk = hd.npk;
	r->tile_pk = (int32_t *)(void *)(b + o_tiles);
	r->from = (int32_t *)(void *)(b + o_from);
	r->kid = b + o_kid;
	r->off = (const uint64_t *)(const void *)(b + o_off);
	r->blob = b + o_blob;
	if (hd.accbits == 32)
		r->acc32 = (const uint32_t *)(const void *)(b + o_acc);
	else
		r->acc64 = (const uint64_t *)(const void *)(b + o_acc);
	/* streams in order and inside the blob; tile ids inside the table */
	if (r->off[0] != 0 || r->off[hd.npk] != hd.nblob)
		goto bad;
	for (uint32_t p = 0; p < hd.npk; p++)
		if (r->off[p] > r->off[p + 1])
			goto bad;
	for (int t = 0; t < ntiles; t++)
		if (r->tile_pk[t] < -1 || r->tile_pk[t] >= (int32_t)hd.npk)
			goto bad;
	/* a child comes after its parent, a primary from a tile in the frame */
	for (uint32_t p = 0; p < hd.npk; p++)
		if (r->from[p] >= (int32_t)p || r->from[p] < -ntiles)
			goto bad;
	return 0;
bad:
	if (own)
		free((void *)block);
	memset(r, 0, sizeof *r);
	return -1;
}

void pr_put_tile(const pktrec *r, framebuf *fb, int tx, int ty, int tw, int th)
{
	int x0 = tx * tw, y0 = ty * th;
	int x1 = x0 + tw < r->w ? x0 + tw : r->w, y1 = y0 + th < r->h ? y0 + th : r->h;
	for (int y = y0; y < y1; y++) {
		size_t i = ((size_t)y * (size_t)r->w + (size_t)x0) * 3, n = (size_t)(x1 - x0) * 3;
		uint64_t *a = fb->acc + i;
		if (r->acc32)
			for (size_t k = 0; k < n; k++)
				a[k] = r->acc32[i + k];
		else
			memcpy(a, r->acc64 + i, n * sizeof *a);
	}
}
