/*
 * warming.c: stored warming's checkpoints: writing them from a functional
 * chip, and restoring a chip from them (see warming.h).
 *
 * Layout of the stored block (8-byte aligned sections; all of it this
 * build's own, validated against the chip that reads it):
 *
 *   head       wm_head
 *   light      frames x nlight records: demand (WM_NDEM doubles), the
 *              on-board-cache hit ticks, the counters (ncnt uint64)
 *   done       frames x nlight records as light's, of the work of the
 *              tiles before each checkpoint's (wm_attr), the demand
 *              computed from their counters
 *   offsets    frames x nfull uint64: each full checkpoint's offset
 *   oldest     frames x nlight int32 (padded to 8 bytes): at each light
 *              checkpoint, the hand-out index of the oldest tile with a
 *              packet in flight (the checkpoint's own when none is)
 *   full       per full checkpoint: wm_fhead, the slots (mode_replay_state, turn
 *              order), per RTP its queue length then the queued packet
 *              ids, the L1s and tag cache whole (hier_ckpt_save: each
 *              cache in its own checkpoint form, lines then its policy's
 *              state), the on-board cache's changed sets (their count,
 *              indices, then each set's cache_ckpt_save form)
 */
#include "sim/warming.h"

#include <stdlib.h>
#include <string.h>

#include "kernel-ref/bitset.h"
#include "sim/chip.h"
#include "sim/modes/replay.h"
#include "units/rgs.h"

_Static_assert(WM_NDEM == RES_N, "warming.h WM_NDEM is chip.h RES_N");

#define WM_MAGIC "saarwm06"

typedef struct wm_head {
	char magic[8];
	int32_t frames, ntiles, g_light, g_full, nlight, nfull, nslots, nrtp;
	int32_t l2_sets, l2_ways;
	uint64_t whole_bytes; /* hier_ckpt_bytes: the caches stored whole */
	uint64_t ncnt, light_at, done_at, offs_at, oldest_at, full_at, full_bytes;
} wm_head;

typedef struct wm_fhead {
	int32_t frame, tile;
	uint64_t next_age;
} wm_fhead;

static size_t pad8(size_t n)
{
	return (n + 7) & ~(size_t)7;
}

/* Every counter functional processing moves, in one order for writer and
 * reader: the stats registry, the memory port, shade_counts, the
 * hierarchy's. out NULL: only counts them. */
static size_t chip_counter_ptrs(chip *c, uint64_t **out, size_t cap)
{
	size_t n = 0;
#define PUT(p)                                                                                     \
	do {                                                                                       \
		if (out && n < cap)                                                                \
			out[n] = (p);                                                              \
		n++;                                                                               \
	} while (0)
	for (size_t i = 0; i < c->st.n; i++)
		PUT(c->st.e[i].value);
	uint64_t *mn = (uint64_t *)&c->mem.n, *sh = (uint64_t *)&c->env.sh;
	for (size_t i = 0; i < sizeof c->mem.n / sizeof(uint64_t); i++)
		PUT(mn + i);
	for (size_t i = 0; i < sizeof c->env.sh / sizeof(uint64_t); i++)
		PUT(sh + i);
#undef PUT
	if (hier_is(&c->mem))
		n += hier_counter_ptrs(&c->mem, out ? out + (n < cap ? n : cap) : NULL,
		                       n < cap ? cap - n : 0);
	return n;
}

static uint64_t **counters_of(chip *c, size_t *n)
{
	*n = chip_counter_ptrs(c, NULL, 0);
	uint64_t **p = malloc((*n ? *n : 1) * sizeof *p);
	if (p)
		chip_counter_ptrs(c, p, *n);
	return p;
}

/* Whether counter p is a maximum, not a sum (a gap's count is then the
 * later value, not a sum of deltas). */
static int is_max_counter(const chip *c, const uint64_t *p)
{
	return p == c->env.c[C_MAX_SP] || p == c->env.c[C_MAX_QUEUE];
}

/* The on-board cache's hit ticks so far (0 without one). */
static uint64_t l2hit_now(chip *c)
{
	return hier_is(&c->mem) ? hier_l2hit_ticks(&c->mem) : 0;
}

/* The on-board cache (NULL: none), stored by set. */
static cache *onboard(chip *c)
{
	return hier_onboard(&c->mem);
}

static int nlight_of(int ntiles, int g)
{
	return ntiles / g + 1 + (ntiles % g != 0);
}

/* Index of the light checkpoint at tile (a multiple of g, or ntiles). */
static int light_index(int ntiles, int g, int tile)
{
	return tile == ntiles ? nlight_of(ntiles, g) - 1 : tile / g;
}

int wm_full_tile(int g_light, int g_full, int k)
{
	if (k <= 0)
		return 0;
	/* a multiplicative hash of k (Knuth's), scaled to the places by its
	 * high bits (its low bits repeat with short periods) */
	uint32_t h = (uint32_t)k * 2654435761u;
	uint64_t j = ((uint64_t)h * (uint64_t)(g_full / g_light)) >> 32;
	return k * g_full + (int)j * g_light;
}

int wm_is_full(int g_light, int g_full, int tile)
{
	return tile == wm_full_tile(g_light, g_full, tile / g_full);
}

/* ---- writing ---- */

/* Four counters at once (GCC's vector extension: AVX2 where the build
 * targets it, else pairs of SSE2 operations); wraparound sums, as uint64_t. */
typedef uint64_t u64x4 __attribute__((vector_size(32)));

/* w->runs from w->cnt: the counters come in 17 runs of adjacent ones on
 * the standard chip (376 counters), so wm_attr's pass over them at every
 * functional step reads arrays instead of chasing a pointer each. */
static int make_runs(wm_writer *w)
{
	size_t n = 0;
	for (size_t i = 0; i < w->ncnt; i++)
		n += i == 0 || w->cnt[i] != w->cnt[i - 1] + 1;
	w->runs = malloc((n ? n : 1) * sizeof *w->runs);
	if (!w->runs)
		return -1;
	w->nruns = 0;
	for (size_t i = 0; i < w->ncnt; i++) {
		if (i == 0 || w->cnt[i] != w->cnt[i - 1] + 1)
			w->runs[w->nruns++] = (struct wm_run){w->cnt[i], (uint32_t)i, 0};
		w->runs[w->nruns - 1].n++;
	}
	return 0;
}

int wm_writer_init(wm_writer *w, chip *c, int g_light, int g_full, int done)
{
	memset(w, 0, sizeof *w);
	w->frames = c->cfg.frame.frames;
	w->ntiles = c->g.ntiles;
	w->g_light = g_light;
	w->g_full = g_full;
	w->nlight = nlight_of(w->ntiles, g_light);
	w->nfull = (w->ntiles + g_full - 1) / g_full;
	w->cnt = counters_of(c, &w->ncnt);
	w->lsize = sizeof(double) * WM_NDEM + sizeof(uint64_t) * (1 + w->ncnt);
	w->light = calloc((size_t)w->frames * (size_t)w->nlight, w->lsize);
	w->foff = malloc((size_t)w->frames * (size_t)w->nfull * sizeof *w->foff);
	w->oldest = calloc((size_t)w->frames * (size_t)w->nlight, sizeof *w->oldest);
	w->pos = malloc((size_t)(w->ntiles ? w->ntiles : 1) * sizeof *w->pos);
	for (int k = 0; w->pos && k < w->ntiles; k++)
		w->pos[c->g.order[k]] = k;
	if (w->foff) /* a checkpoint jittered past the frame's end is never written */
		memset(w->foff, 0xff, (size_t)w->frames * (size_t)w->nfull * sizeof *w->foff);
	if (done) {
		size_t nd = (size_t)w->frames * (size_t)w->nlight * (1 + w->ncnt);
		w->done = calloc(nd ? nd : 1, sizeof *w->done);
		w->snap = calloc(1 + w->ncnt, sizeof *w->snap);
		w->handout = malloc((size_t)w->ntiles * sizeof *w->handout);
		if (!w->done || !w->snap || !w->handout || !w->cnt || make_runs(w))
			w->failed = 1;
	}
	cache *l2 = onboard(c);
	if (l2 && cache_track(l2))
		w->failed = 1;
	if (!w->cnt || !w->light || !w->foff || !w->oldest || !w->pos || w->failed) {
		wm_writer_free(w);
		return -1;
	}
	return 0;
}

void wm_writer_free(wm_writer *w)
{
	free(w->cnt);
	free(w->light);
	free(w->foff);
	free(w->full);
	free(w->done);
	free(w->snap);
	free(w->handout);
	free(w->runs);
	free(w->tile_of);
	free(w->oldest);
	free(w->pos);
	memset(w, 0, sizeof *w);
}

/* The on-board-cache hit ticks and the counters now into v (1 + ncnt). */
static void read_counts(wm_writer *w, chip *c, uint64_t *v)
{
	v[0] = l2hit_now(c);
	for (size_t i = 0; i < w->ncnt; i++)
		v[1 + i] = *w->cnt[i];
}

/* The tile of the primary packet stream rec descends from (parents come
 * first), through the record's parents; -1 when the chain is damaged. */
static int32_t primary_tile(const int32_t *from, uint32_t npk, int32_t rec)
{
	int32_t p = rec;
	for (int depth = 0; from[p] >= 0; depth++) {
		if (depth > 4096 || (uint32_t)from[p] >= npk)
			return -1;
		p = from[p];
	}
	return -1 - from[p];
}

/* Each packet stream's primary tile, once the packet record is open (it
 * is as the run starts): worked out once, not by a walk up the stream's
 * parents at every step (wm_attr) or checkpoint (oldest_in_flight). */
static void know_tiles(wm_writer *w, chip *c)
{
	if (w->from || !c->md.in)
		return;
	w->from = c->md.in->from;
	w->npk = c->md.in->npk;
	w->tile_of = malloc((w->npk ? w->npk : 1) * sizeof *w->tile_of);
	if (!w->tile_of)
		w->failed = 1;
	for (uint32_t i = 0; w->tile_of && i < w->npk; i++)
		w->tile_of[i] = primary_tile(w->from, w->npk, (int32_t)i);
}

void wm_attr_take(wm_writer *w, chip *c, int32_t rec, int at)
{
	know_tiles(w, c);
	if (w->failed || !w->handout || rec < 0 || (uint32_t)rec >= w->npk || w->from[rec] >= 0)
		return;
	int tile = -1 - w->from[rec];
	if (tile < w->ntiles)
		w->handout[tile] = at;
}

void wm_attr(wm_writer *w, chip *c, int32_t rec)
{
	int frame = c->frames_done;
	if (w->failed || !w->done || rec < 0 || (uint32_t)rec >= w->npk || frame >= w->frames)
		return;
	int32_t tile = w->tile_of[rec];
	if (tile < 0 || tile >= w->ntiles)
		return;
	uint64_t *d = w->done + ((size_t)frame * (size_t)w->nlight +
	                         (size_t)(w->handout[tile] / w->g_light)) *
	                            (1 + w->ncnt);
	uint64_t l2 = l2hit_now(c);
	d[0] += l2 - w->snap[0];
	w->snap[0] = l2;
	uint64_t *dd = d + 1, *sn = w->snap + 1;
	for (size_t r = 0; r < w->nruns; r++) {
		const uint64_t *v = w->runs[r].src;
		uint32_t at = w->runs[r].at, n = w->runs[r].n, j = 0;
		for (; j + 4 <= n; j += 4) { /* four at a time (the same sums) */
			u64x4 x, s0, a;
			memcpy(&x, v + j, sizeof x);
			memcpy(&s0, sn + at + j, sizeof s0);
			memcpy(&a, dd + at + j, sizeof a);
			a += x - s0;
			memcpy(dd + at + j, &a, sizeof a);
			memcpy(sn + at + j, &x, sizeof x);
		}
		for (; j < n; j++) {
			uint64_t x = v[j];
			dd[at + j] += x - sn[at + j];
			sn[at + j] = x;
		}
	}
}

/* The hand-out index of packet stream rec's tile; 0 (the frame's first,
 * so nothing counts as done) when the record cannot tell. */
static int handout_of(const wm_writer *w, int32_t rec)
{
	if (rec < 0 || (uint32_t)rec >= w->npk || !w->tile_of || w->tile_of[rec] < 0 ||
	    w->tile_of[rec] >= w->ntiles)
		return 0;
	return w->pos[w->tile_of[rec]];
}

/* The hand-out index of the oldest tile with a packet in flight at the
 * light checkpoint at tile (in a slot or an RTP's queue); tile when none
 * is: every tile before it is done. */
static int oldest_in_flight(wm_writer *w, chip *c, int tile)
{
	know_tiles(w, c);
	int o = tile, ns = c->nrtp * c->tpr;
	for (int i = 0; i < ns; i++) {
		thr_ctx *t = c->turn[i];
		if (t->p || mode_slot(t)->rp) {
			int h = handout_of(w, mode_slot(t)->rec);
			o = h < o ? h : o;
		}
	}
	for (int r = 0; r < c->nrtp; r++)
		for (int i = 0, n = rgs_queue_len(&c->rtp[r]); i < n; i++) {
			int h = handout_of(w, rgs_queue_at(&c->rtp[r], i).rec);
			o = h < o ? h : o;
		}
	return o;
}

void wm_put_light(wm_writer *w, chip *c, int frame, int tile, const double *dem)
{
	if (w->failed || frame >= w->frames)
		return;
	w->oldest[(size_t)frame * (size_t)w->nlight +
	          (size_t)light_index(w->ntiles, w->g_light, tile)] = oldest_in_flight(w, c, tile);
	uint8_t *p = w->light + ((size_t)frame * (size_t)w->nlight +
	                         (size_t)light_index(w->ntiles, w->g_light, tile)) *
	                            w->lsize;
	memcpy(p, dem, sizeof(double) * WM_NDEM);
	uint64_t *u = (uint64_t *)(void *)(p + sizeof(double) * WM_NDEM);
	read_counts(w, c, u);
	/* the frame's first tile: what was counted before it stays out of
	 * its tiles' work (the done records start from this one) */
	if (tile == 0 && w->snap)
		memcpy(w->snap, u, (1 + w->ncnt) * sizeof *u);
}

/* The done records of every frame (see the layout above) into out: the
 * counts of the frame's first light checkpoint plus the work of the tiles
 * before each, and the demand chip_demand makes of those counters (the
 * chip's counters are set to them for it, then put back). Maxima keep
 * the light record's value. */
static void put_done(wm_writer *w, chip *c, uint8_t *out)
{
	size_t nv = 1 + w->ncnt;
	uint64_t *keep = malloc(nv * sizeof *keep), *sum = malloc(nv * sizeof *sum);
	if (!keep || !sum) {
		w->failed = 1;
		free(keep);
		free(sum);
		return;
	}
	read_counts(w, c, keep);
	for (int f = 0; f < w->frames; f++) {
		size_t base = (size_t)f * (size_t)w->nlight;
		memcpy(sum, w->light + base * w->lsize + sizeof(double) * WM_NDEM,
		       nv * sizeof *sum);
		for (int k = 0; k < w->nlight; k++) {
			const uint8_t *lp = w->light + (base + (size_t)k) * w->lsize;
			uint8_t *p = out + (base + (size_t)k) * w->lsize;
			uint64_t *u = (uint64_t *)(void *)(p + sizeof(double) * WM_NDEM);
			const uint64_t *lu =
			    (const uint64_t *)(const void *)(lp + sizeof(double) * WM_NDEM);
			for (size_t i = 0; i < nv; i++)
				u[i] = i > 0 && is_max_counter(c, w->cnt[i - 1]) ? lu[i] : sum[i];
			for (size_t i = 0; i < w->ncnt; i++)
				*w->cnt[i] = u[1 + i];
			double dem[WM_NDEM];
			chip_demand(c, dem);
			memcpy(p, dem, sizeof dem);
			const uint64_t *t = w->done + (base + (size_t)k) * nv;
			for (size_t i = 0; i < nv; i++)
				sum[i] += t[i];
		}
	}
	for (size_t i = 0; i < w->ncnt; i++)
		*w->cnt[i] = keep[1 + i];
	free(keep);
	free(sum);
}

/* Room for n more bytes of full checkpoints (8-byte aligned). */
static uint8_t *full_room(wm_writer *w, size_t n)
{
	n = pad8(n);
	if (w->nfullb + n > w->capfull) {
		size_t cap = w->capfull ? w->capfull : 1 << 20;
		while (cap < w->nfullb + n)
			cap *= 2;
		uint8_t *b = realloc(w->full, cap);
		if (!b) {
			w->failed = 1;
			return NULL;
		}
		w->full = b;
		w->capfull = cap;
	}
	uint8_t *p = w->full + w->nfullb;
	memset(p, 0, n);
	w->nfullb += n;
	return p;
}

/* Appends set `set` of the on-board cache in its checkpoint form. */
static void put_set(wm_writer *w, const cache *l2, uint32_t set)
{
	uint8_t *p = full_room(w, cache_ckpt_bytes(l2, 1));
	if (p && cache_ckpt_save(l2, set, 1, p))
		w->failed = 1;
}

void wm_put_full(wm_writer *w, chip *c, int frame, int tile)
{
	if (w->failed || frame >= w->frames)
		return;
	w->foff[(size_t)frame * (size_t)w->nfull + (size_t)(tile / w->g_full)] = w->nfullb;
	int ns = c->nrtp * c->tpr;
	wm_fhead fh = {frame, tile, c->env.next_age};
	uint8_t *p = full_room(w, sizeof fh);
	if (!p)
		return;
	memcpy(p, &fh, sizeof fh);
	for (int i = 0; i < ns; i++) {
		mode_replay_state s;
		if (mode_replay_save(c->turn[i], &s)) {
			w->failed = 1;
			return;
		}
		if (!(p = full_room(w, sizeof s)))
			return;
		memcpy(p, &s, sizeof s);
	}
	for (int r = 0; r < c->nrtp; r++) {
		int32_t n = rgs_queue_len(&c->rtp[r]);
		if (!(p = full_room(w, 4 + 4 * (size_t)n)))
			return;
		memcpy(p, &n, 4);
		if (mode_queue_save(&c->rtp[r], p + 4)) {
			w->failed = 1;
			return;
		}
	}
	if (!hier_is(&c->mem))
		return;
	/* the caches stored whole save themselves */
	size_t wb = hier_ckpt_bytes(&c->mem);
	if (!(p = full_room(w, wb)))
		return;
	if (hier_ckpt_save(&c->mem, p)) {
		w->failed = 1;
		return;
	}
	cache *l2 = onboard(c);
	if (!l2)
		return;
	/* the on-board cache's sets changed since the last full checkpoint */
	uint32_t nd = (uint32_t)bits_count(l2->dirty, (int)l2->nsets);
	size_t at = w->nfullb;
	if (!full_room(w, 4 + 4 * (size_t)nd))
		return;
	memcpy(w->full + at, &nd, 4);
	uint32_t j = 0;
	for (int s = bits_next(l2->dirty, (int)l2->nsets, 0); s < (int)l2->nsets;
	     s = bits_next(l2->dirty, (int)l2->nsets, s + 1)) {
		uint32_t set = (uint32_t)s;
		memcpy(w->full + at + 4 + 4 * (size_t)j++, &set, 4);
	}
	for (int s = bits_next(l2->dirty, (int)l2->nsets, 0); s < (int)l2->nsets;
	     s = bits_next(l2->dirty, (int)l2->nsets, s + 1))
		put_set(w, l2, (uint32_t)s);
	cache_dirty_clear(l2);
}

static void geometry(chip *c, wm_head *h);

int wm_writer_finish(wm_writer *w, chip *c, void **out, size_t *n)
{
	if (w->failed || (w->done && !w->from))
		return -1;
	wm_head h;
	memset(&h, 0, sizeof h);
	memcpy(h.magic, WM_MAGIC, 8);
	h.frames = w->frames;
	h.ntiles = w->ntiles;
	h.g_light = w->g_light;
	h.g_full = w->g_full;
	h.nlight = w->nlight;
	h.nfull = w->nfull;
	h.ncnt = w->ncnt;
	size_t nl = (size_t)w->frames * (size_t)w->nlight * w->lsize,
	       no = (size_t)w->frames * (size_t)w->nfull * sizeof(uint64_t),
	       nold = pad8((size_t)w->frames * (size_t)w->nlight * sizeof(int32_t));
	h.light_at = pad8(sizeof h);
	h.done_at = h.light_at + nl;
	h.offs_at = h.done_at + (w->done ? nl : 0);
	h.oldest_at = h.offs_at + no;
	h.full_at = h.oldest_at + nold;
	h.full_bytes = w->nfullb;
	geometry(c, &h); /* wm_open checks it against the reader's */
	*n = (size_t)h.full_at + w->nfullb;
	uint8_t *b = malloc(*n);
	if (!b)
		return -1;
	memcpy(b, &h, sizeof h);
	memcpy(b + h.light_at, w->light, nl);
	if (w->done)
		put_done(w, c, b + h.done_at);
	if (w->failed) {
		free(b);
		return -1;
	}
	memcpy(b + h.offs_at, w->foff, no);
	memset(b + h.oldest_at, 0, nold);
	memcpy(b + h.oldest_at, w->oldest, (size_t)w->frames * (size_t)w->nlight * sizeof(int32_t));
	memcpy(b + h.full_at, w->full, w->nfullb);
	*out = b;
	return 0;
}

/* The chip's geometry as the head stores it. */
static void geometry(chip *c, wm_head *h)
{
	h->nslots = c->nrtp * c->tpr;
	h->nrtp = c->nrtp;
	cache *l2 = onboard(c);
	h->whole_bytes = hier_ckpt_bytes(&c->mem);
	h->l2_sets = l2 ? (int32_t)l2->nsets : 0;
	h->l2_ways = l2 ? (int32_t)l2->p.ways : 0;
}

/* ---- reading ---- */

void wm_close(wm *r)
{
	free(r->cnt);
	free(r->is_max);
	free(r->prev);
	free(r->sk);
	free(r->mark);
	free(r->l2img);
	free(r->l2pend);
	memset(r, 0, sizeof *r);
}

/* The counters a skip (wm_skip) takes back: every one of
 * chip_counter_ptrs but the maxima, the reads' waits and MSHR stalls
 * (timing's own, which functional processing never moves) and the
 * caches' skip_hits and skip_merges (hier_kept_ptrs), and the timed
 * models' traffic (hier_traffic_ptrs), whose functional counters are
 * among the first. A cache's counts go back together (its merges and
 * refusals with its misses and fills), or its relations would break; its
 * timed hits and merges, whose shares the estimated hit rates and the
 * gaps' SDRAM demand take, stay in skip_hits and skip_merges
 * (hier_keep_shares). */
static int skip_counters(wm *r, chip *c)
{
	int hi = hier_is(&c->mem);
	size_t nt = hi ? hier_traffic_ptrs(&c->mem, NULL, 0) : 0,
	       nw = hi ? hier_kept_ptrs(&c->mem, NULL, 0) : 0;
	uint64_t **wp = malloc((nw + 1) * sizeof *wp);
	r->sk = malloc((r->ncnt + nt + 1) * sizeof *r->sk);
	r->mark = calloc(r->ncnt + nt + 1, sizeof *r->mark);
	if (!wp || !r->sk || !r->mark) {
		free(wp);
		return -1;
	}
	if (nw)
		hier_kept_ptrs(&c->mem, wp, nw);
	r->nsk = 0;
	for (size_t i = 0; i < r->ncnt; i++) {
		int keep = r->is_max[i];
		for (size_t k = 0; k < nw && !keep; k++)
			keep = wp[k] == r->cnt[i];
		/* the threads' time by state is timing's own too: rolled back,
		 * the shares were those of the last region's ends alone (24%
		 * idle on Conference, 1% in cycle mode) */
		for (int q = 0; q < c->nrtp && !keep; q++)
			for (int s = 0; s < THR_NSTATES && !keep; s++)
				keep = c->rtp[q].occ[s] == r->cnt[i];
		if (!keep)
			r->sk[r->nsk++] = r->cnt[i];
	}
	free(wp);
	if (nt)
		r->nsk += hier_traffic_ptrs(&c->mem, r->sk + r->nsk, nt);
	return 0;
}

int wm_open(wm *r, const void *b, size_t n, chip *c)
{
	memset(r, 0, sizeof *r);
	wm_head h, g;
	if (n < sizeof h)
		return -1;
	memcpy(&h, b, sizeof h);
	g = h;
	geometry(c, &g);
	size_t ncnt = chip_counter_ptrs(c, NULL, 0);
	if (memcmp(h.magic, WM_MAGIC, 8) || memcmp(&h, &g, sizeof h) || h.ncnt != ncnt ||
	    h.frames != c->cfg.frame.frames || h.ntiles != c->g.ntiles || h.g_light < 1 ||
	    h.g_full < h.g_light || h.g_full % h.g_light ||
	    h.nlight != nlight_of(h.ntiles, h.g_light) ||
	    h.nfull != (h.ntiles + h.g_full - 1) / h.g_full)
		return -1;
	r->b = b;
	r->n = n;
	r->frames = h.frames;
	r->ntiles = h.ntiles;
	r->g_light = h.g_light;
	r->g_full = h.g_full;
	r->nlight = h.nlight;
	r->nfull = h.nfull;
	r->ncnt = ncnt;
	r->lsize = sizeof(double) * WM_NDEM + sizeof(uint64_t) * (1 + ncnt);
	size_t nl = (size_t)h.frames * (size_t)h.nlight * r->lsize,
	       no = (size_t)h.frames * (size_t)h.nfull * sizeof(uint64_t),
	       nold = pad8((size_t)h.frames * (size_t)h.nlight * sizeof(int32_t));
	r->has_done = h.offs_at != h.done_at;
	if (h.light_at != pad8(sizeof h) || h.done_at != h.light_at + nl ||
	    (h.offs_at != h.done_at && h.offs_at != h.done_at + nl) ||
	    h.oldest_at != h.offs_at + no || h.full_at != h.oldest_at + nold ||
	    h.full_at + h.full_bytes != n)
		return -1;
	r->oldest_at = h.oldest_at;
	r->cnt = counters_of(c, &ncnt);
	r->is_max = calloc(ncnt ? ncnt : 1, 1);
	r->prev = calloc(ncnt ? ncnt : 1, sizeof *r->prev);
	if (!r->cnt || !r->is_max || !r->prev)
		goto fail;
	for (size_t i = 0; i < ncnt; i++)
		r->is_max[i] = (uint8_t)is_max_counter(c, r->cnt[i]);
	if (skip_counters(r, c))
		goto fail;
	cache *l2 = onboard(c);
	if (l2) {
		r->l2set = cache_ckpt_bytes(l2, 1);
		r->l2img = malloc(l2->nsets * r->l2set);
		r->l2pend = calloc((size_t)bits_words((int)l2->nsets), sizeof *r->l2pend);
		if (!r->l2img || !r->l2pend || cache_track(l2))
			goto fail;
		for (uint32_t s = 0; s < l2->nsets; s++) /* empty at the start */
			cache_ckpt_empty(l2, 1, r->l2img + s * r->l2set);
	}
	return 0;
fail:
	wm_close(r);
	return -1;
}

/* The light (done 0) or done (1) record at tile of frame. */
static const uint8_t *light_at(const wm *r, int frame, int tile, int done)
{
	const wm_head *h = (const wm_head *)(const void *)r->b;
	return r->b + (done ? h->done_at : h->light_at) +
	       ((size_t)frame * (size_t)r->nlight +
	        (size_t)light_index(r->ntiles, r->g_light, tile)) *
	           r->lsize;
}

const double *wm_demand(const wm *r, int frame, int tile, uint64_t *l2hit)
{
	const uint8_t *p = light_at(r, frame, tile, 0);
	memcpy(l2hit, p + sizeof(double) * WM_NDEM, sizeof *l2hit);
	return (const double *)(const void *)p;
}

const double *wm_demand_done(const wm *r, int frame, int tile, uint64_t *l2hit)
{
	const uint8_t *p = light_at(r, frame, tile, 1);
	memcpy(l2hit, p + sizeof(double) * WM_NDEM, sizeof *l2hit);
	return (const double *)(const void *)p;
}

int wm_full_below(const wm *r, int tile)
{
	int k = tile / r->g_full, t = wm_full_tile(r->g_light, r->g_full, k);
	return t <= tile ? t : wm_full_tile(r->g_light, r->g_full, k - 1);
}

int wm_full_above(const wm *r, int tile)
{
	int k = tile / r->g_full, t = wm_full_tile(r->g_light, r->g_full, k);
	if (t < tile)
		t = wm_full_tile(r->g_light, r->g_full, k + 1);
	return t < r->ntiles ? t : r->ntiles;
}

int wm_done_by(const wm *r, int frame, int at, int x)
{
	if (!r->has_done)
		return 0;
	const uint8_t *a = light_at(r, frame, at, 1) + sizeof(double) * WM_NDEM,
	              *b = light_at(r, frame, x, 0) + sizeof(double) * WM_NDEM;
	for (size_t i = 0; i <= r->ncnt; i++) {
		uint64_t u, v;
		memcpy(&u, a + 8 * i, 8);
		memcpy(&v, b + 8 * i, 8);
		if (u > v && (i == 0 || !r->is_max[i - 1]))
			return 0;
	}
	return 1;
}

int wm_oldest(const wm *r, int frame, int tile)
{
	int32_t o;
	memcpy(&o,
	       r->b + r->oldest_at +
	           ((size_t)frame * (size_t)r->nlight +
	            (size_t)light_index(r->ntiles, r->g_light, tile)) *
	               sizeof o,
	       sizeof o);
	return o;
}

void wm_mark(wm *r, struct chip *c)
{
	for (size_t i = 0; i < r->nsk; i++)
		r->mark[i] = *r->sk[i];
	hier_stats s;
	r->mark_merge = hier_get_stats(&c->mem, &s) ? 0 : s.func_sdram_merge_ticks;
	if (hier_is(&c->mem))
		hier_mark_shares(&c->mem);
}

void wm_skip(wm *r, struct chip *c, int frame, int tile)
{
	/* the on-board cache's timed shares first: the counts go back next */
	hier_stats s;
	if (hier_is(&c->mem))
		hier_keep_shares(&c->mem);
	for (size_t i = 0; i < r->nsk; i++)
		*r->sk[i] = r->mark[i];
	if (!hier_get_stats(&c->mem, &s))
		hier_add_merge_ticks(&c->mem, r->mark_merge - s.func_sdram_merge_ticks);
	wm_region_end(r, frame, tile, 0);
}

void wm_region_end(wm *r, int frame, int tile, int done)
{
	const uint8_t *p = light_at(r, frame, tile, done) + sizeof(double) * WM_NDEM;
	memcpy(&r->prev_l2hit, p, 8);
	memcpy(r->prev, p + 8, r->ncnt * sizeof *r->prev);
}

/* A reader over the full checkpoints' bytes that fails once past them. */
typedef struct rd {
	const uint8_t *p, *end;
	int bad;
} rd;

static const uint8_t *take(rd *d, size_t n)
{
	n = pad8(n);
	if (d->bad || (size_t)(d->end - d->p) < n) {
		d->bad = 1;
		return NULL;
	}
	const uint8_t *q = d->p;
	d->p += n;
	return q;
}

/* Skips (or, for the last, stops before) the parts of full checkpoint gi
 * ahead of its caches; returns the reader at its slots. */
static rd full_reader(const wm *r, int gi)
{
	const wm_head *h = (const wm_head *)(const void *)r->b;
	rd d = {NULL, r->b + h->full_at + h->full_bytes, 1};
	uint64_t off;
	memcpy(&off, r->b + h->offs_at + (size_t)gi * 8, 8);
	if (off < h->full_bytes) {
		d.p = r->b + h->full_at + off;
		d.bad = 0;
	}
	return d;
}

/* Reads past the slots and queues of a full checkpoint. */
static void skip_threads(rd *d, int nslots, int nrtp)
{
	take(d, sizeof(wm_fhead));
	take(d, sizeof(mode_replay_state) * (size_t)nslots);
	for (int q = 0; q < nrtp && !d->bad; q++) {
		int32_t qn;
		const uint8_t *p = d->p;
		if ((size_t)(d->end - p) < 4) {
			d->bad = 1;
			return;
		}
		memcpy(&qn, p, 4);
		if (qn < 0 || !take(d, 4 + 4 * (size_t)qn))
			d->bad = 1;
	}
}

/* The on-board cache's changes in full checkpoint gi, into the warm
 * image (their sets become pending for the chip). */
static void roll_l2(wm *r, chip *c, int gi, const cache *l2)
{
	const wm_head *h = (const wm_head *)(const void *)r->b;
	rd d = full_reader(r, gi);
	skip_threads(&d, h->nslots, h->nrtp);
	take(&d, h->whole_bytes);
	/* the count and the set indices are one block */
	uint32_t nd = 0;
	if (!d.bad && d.end - d.p >= 4)
		memcpy(&nd, d.p, 4);
	const uint8_t *p = take(&d, 4 + 4 * (size_t)nd), *sets = p ? p + 4 : NULL;
	for (uint32_t j = 0; j < nd && !d.bad; j++) {
		uint32_t s;
		memcpy(&s, sets + 4 * (size_t)j, 4);
		const uint8_t *img = take(&d, r->l2set);
		if (!img || s >= l2->nsets)
			break;
		memcpy(r->l2img + s * r->l2set, img, r->l2set);
		bits_set(r->l2pend, (int)s);
	}
	(void)c;
}

int wm_restore(wm *r, chip *c, int frame, int tile, double merge_share)
{
	const wm_head *h = (const wm_head *)(const void *)r->b;
	if (frame >= r->frames || tile >= r->ntiles || !wm_is_full(r->g_light, r->g_full, tile))
		return -1;
	int gi = frame * r->nfull + tile / r->g_full;
	cache *l2 = onboard(c);
	if (gi < r->next_full - 1)
		return -1;
	for (; r->next_full <= gi; r->next_full++)
		if (l2)
			roll_l2(r, c, r->next_full, l2);
	rd d = full_reader(r, gi);
	const uint8_t *p = take(&d, sizeof(wm_fhead));
	wm_fhead fh;
	if (!p)
		return -1;
	memcpy(&fh, p, sizeof fh);
	if (fh.frame != frame || fh.tile != tile)
		return -1;
	/* the slots, in turn order */
	for (int i = 0; i < h->nslots; i++) {
		mode_replay_state s;
		if (!(p = take(&d, sizeof s)))
			return -1;
		memcpy(&s, p, sizeof s);
		if (mode_replay_restore(c->md.in, c->turn[i], &s))
			return -1;
	}
	for (int q = 0; q < h->nrtp; q++) {
		int32_t qn;
		if ((size_t)(d.end - d.p) < 4)
			return -1;
		memcpy(&qn, d.p, 4);
		if (qn < 0 || !(p = take(&d, 4 + 4 * (size_t)qn)))
			return -1;
		if (mode_queue_restore(c->md.in, &c->rtp[q], p + 4, qn))
			return -1;
	}
	/* the caches stored whole restore themselves */
	if (h->whole_bytes) {
		const uint8_t *wp = take(&d, h->whole_bytes);
		if (!wp || hier_ckpt_load(&c->mem, wp))
			return -1;
	}
	/* the on-board cache: the sets the checkpoints since the last restore
	 * or the region since it changed */
	if (l2) {
		if (cache_busy(l2))
			return -1;
		int ns = (int)l2->nsets;
		for (int w = 0; w < bits_words(ns); w++)
			r->l2pend[w] |= l2->dirty[w];
		for (int s = bits_next(r->l2pend, ns, 0); s < ns;
		     s = bits_next(r->l2pend, ns, s + 1))
			cache_ckpt_load(l2, (uint32_t)s, 1, r->l2img + (size_t)s * r->l2set);
	}
	/* the loaded lines' bytes (every packet replays here, so nothing
	 * decodes them; the lines stay true to their addresses all the same) */
	if (hier_is(&c->mem))
		hier_reload(&c->mem, l2 ? r->l2pend : NULL);
	if (l2) {
		memset(r->l2pend, 0, (size_t)bits_words((int)l2->nsets) * sizeof *r->l2pend);
		cache_dirty_clear(l2);
	}
	chip_resume_at(c, tile, fh.next_age);
	/* the counters: what the warming run counted since the last region's
	 * end; maxima take the larger */
	const uint8_t *lp = light_at(r, frame, tile, 0) + sizeof(double) * WM_NDEM;
	uint64_t l2hit;
	memcpy(&l2hit, lp, 8);
	for (size_t i = 0; i < r->ncnt; i++) {
		uint64_t v;
		memcpy(&v, lp + 8 + 8 * i, 8);
		if (r->is_max[i])
			*r->cnt[i] = v > *r->cnt[i] ? v : *r->cnt[i];
		else
			*r->cnt[i] += v - r->prev[i];
	}
	if (hier_is(&c->mem) && l2hit > r->prev_l2hit)
		hier_add_merge_ticks(&c->mem, merge_share * (double)(l2hit - r->prev_l2hit));
	return 0;
}
