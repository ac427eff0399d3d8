/*
 * stored.c: what functional and sampled runs keep in the world cache
 * (see stored.h): the packet record and stored warming's checkpoints.
 */
#define _GNU_SOURCE /* asprintf, open_memstream */
#include "sim/modes/stored.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/jsonw.h"
#include "kernel-ref/worldcache.h"
#include "sim/warming.h"

/* The packet record's key (its version 2: reads carry checksums,
 * traces/pktrec.h): kernel-ref's frame key for this view and size
 * (the memory image by its CRC, camera, lights, shading depth) and what
 * else changes a packet's work on the chip: the datapath formats and the
 * stack depth (spills), and with a uniform grid (chip.accel grid) its
 * parameters (a kd record's reads hit the same bytes of the frame's
 * image: only the key keeps it from standing for a grid run). Thread
 * counts, units and memory do not. */
static char *rec_key(const chip *c)
{
	const saar_config *g = &c->cfg;
	render_opts ro;
	render_opts_default(&ro);
	ro.width = g->frame.width;
	ro.height = g->frame.height;
	ro.max_depth = g->shading.max_depth;
	char *fk = wc_frame_key(c->w->cache_prog, c->w->image_crc, c->w->m.size, &c->w->v, &ro),
	     *key;
	if (!fk)
		return NULL;
	/* the kd-tree's key is as before the grid (its records stay valid) */
	char gk[160] = "";
	const grid *gr = c->w->grid;
	if (gr)
		snprintf(gk, sizeof gk, "grid %a %d %d %d %d\n", gr->p.lambda, gr->p.macro,
		         gr->p.packet, gr->p.mailbox, gr->p.cull);
	/* cone culling changes the packets' work (their cone tests, the
	 * triangles culled): a record is its own (3: the key before it named
	 * no cone, so a record of either setting was replayed for the other) */
	int n = asprintf(&key,
	                 "saarsim packet record 3\n%sfp %d %d %d %d %d %d round %d\nstack %d\n"
	                 "cone %d\ncounters %d shade %zu\n%s",
	                 fk, g->chip.fp.trav.exp, g->chip.fp.trav.mant, g->chip.fp.isect.exp,
	                 g->chip.fp.isect.mant, g->chip.fp.shade.exp, g->chip.fp.shade.mant,
	                 g->chip.fp.round, g->chip.stack_depth, g->chip.cone_cull ? 1 : 0,
	                 (int)C_NCOUNTERS, sizeof(shade_counts), gk);
	free(fk);
	return n < 0 ? NULL : key;
}

/* Functional and sampled runs with a world cache: replay the stored
 * record of this frame, else record the first frame (mode_rec_store). */
void mode_rec_open(chip *c)
{
	const world *w = c->w;
	chip_fidelity *F = &c->fid;
	if (!w->cache_dir || F->mode == CFG_FIDELITY_CYCLE ||
	    (F->mode == CFG_FIDELITY_SAMPLED && F->exact))
		return;
	double t0 = chip_now_ms();
	c->rec_key = rec_key(c);
	if (!c->rec_key ||
	    wc_file(c->rec_file, sizeof c->rec_file, w->cache_dir, "packets", c->rec_key)) {
		free(c->rec_key);
		c->rec_key = NULL;
		return;
	}
	const void *tail;
	size_t n;
	int W = c->cfg.frame.width, H = c->cfg.frame.height;
	/* replayed where it lies in the file: no copy */
	if (wc_get_mapped(c->rec_file, c->rec_key, NULL, 0, &tail, &n, &c->rec_map) == 1 &&
	    !pr_load(&c->rec, tail, n, 0, W, H, c->g.ntiles)) {
		c->md.in = &c->rec;
		c->rec_state = REC_REPLAYED;
	} else {
		wc_unmap(&c->rec_map);
		if (!pr_init(&c->rec, W, H, c->g.ntiles)) {
			mode_record(&c->md, &c->rec);
			c->rec_state = REC_UNSTORED;
		}
	}
	c->rec_ms += chip_now_ms() - t0;
}

/* After the recorded frame: stores the record (a failure is a warning),
 * and the frames after it replay it. */
void mode_rec_store(chip *c)
{
	if (!c->md.rec.out)
		return;
	double t0 = chip_now_ms();
	mode_record(&c->md, NULL);
	void *b;
	size_t n;
	int rc = pr_serialize(&c->rec, &c->fb, &b, &n);
	pr_free(&c->rec);
	if (rc)
		return;
	diag d;
	if (world_cache_put(c->w, c->rec_file, c->rec_key, NULL, NULL, 0, b, n, &d))
		fprintf(stderr, "warning: %s\n", d.msg);
	else
		c->rec_state = REC_STORED;
	if (!pr_load(&c->rec, b, n, 1, c->cfg.frame.width, c->cfg.frame.height, c->g.ntiles))
		c->md.in = &c->rec;
	c->rec_ms += chip_now_ms() - t0;
}

/* Replayed tiles take the recorded frame's pixels (a replayed packet
 * draws nothing), unless one of their reads returned other bytes than the
 * recorded one (2: replay.h): those keep none. */
void mode_rec_pixels(chip *c)
{
	for (int i = 0; i < c->g.ntiles; i++)
		if (c->replayed[i]) {
			int bad = c->replayed[i] == 2;
			c->replayed[i] = 0;
			if (!bad)
				pr_put_tile(&c->rec, &c->fb, i % c->g.tiles_x, i / c->g.tiles_x,
				            TILE_W, TILE_H);
		}
}

/* Whether the warming run keeps done records (sim/warming.h): only for a
 * sampling.jump that drains (a skip hands the counts over whole). */
static int warm_done(const chip *c)
{
	return c->cfg.sampling.jump == CFG_JUMP_DRAIN || c->cfg.sampling.jump == CFG_JUMP_MIXED;
}

/* The warming run's key: the packet record's (the frame) and every config
 * key functional processing reads. Left out (at their defaults): the name
 * (a label; a config file without one is named after the file), fidelity,
 * sampling and the keys only timing reads (cfg_key.timing_only), so a
 * sweep over those reuses one warming run. */
static char *warm_key(const chip *c, int gl, int gf)
{
	saar_config k = c->cfg, d;
	cfg_defaults(&d);
	memcpy(k.name, d.name, sizeof k.name);
	k.fidelity = d.fidelity;
	k.sampling = d.sampling;
	size_t nk;
	const cfg_key *keys = cfg_keys(&nk);
	for (size_t i = 0; i < nk; i++)
		if (keys[i].timing_only)
			memcpy((char *)&k + keys[i].off, (const char *)&d + keys[i].off,
			       keys[i].size);
	char *js = NULL, *key = NULL;
	size_t n = 0;
	FILE *f = open_memstream(&js, &n);
	if (!f)
		return NULL;
	jsonw w;
	jsonw_init_file(&w, f);
	w.exact = 1; /* two clocks that print alike to 9 digits had shared a file */
	cfg_write_json(&k, &w);
	/* the done records (sampling.jump drain or mixed) make a file of
	 * their own: a relax needs none, and counting them costs */
	if (fclose(f) || asprintf(&key, "saarsim warming 2\n%sgrid %d %d\ndone %d\nconfig %s\n",
	                          c->rec_key, gl, gf, warm_done(c), js) < 0)
		key = NULL;
	free(js);
	return key;
}

/* chip.on_tile during a warming run: a checkpoint at every g_light
 * tiles handed out (sim/warming.h); the slot taking the tile is idle,
 * every other one between two steps. */
static void warm_mark(chip *c, int tile)
{
	if (tile % c->wcap->g_light)
		return;
	if (wm_is_full(c->wcap->g_light, c->wcap->g_full, tile))
		wm_put_full(c->wcap, c, c->frames_done, tile);
	double dem[RES_N];
	chip_demand(c, dem);
	wm_put_light(c->wcap, c, c->frames_done, tile, dem);
}

/* chip.on_destroy once stored warming is asked for: the reader goes. */
static void warm_close(chip *c)
{
	if (c->warm)
		wm_close(c->warm);
	free(c->warm);
	c->warm = NULL;
}

/* The warming run of chip h (functional, replaying the packet record):
 * chip_run with checkpoints on the grids (sim/warming.h). chip_take_tile takes
 * them (warm_mark, its on_tile observer) and chip_run the last of each frame, so the run steps
 * as functional mode does: stopping it at each checkpoint left slots idle
 * until the next and missed fewer L1 lines. */
static int warm_build(chip *h, int gl, int gf, void **out, size_t *n)
{
	wm_writer w;
	if (wm_writer_init(&w, h, gl, gf, warm_done(h)))
		return -1;
	h->wcap = &w;
	h->on_tile = warm_mark;
	diag d;
	int rc =
	    chip_run(h, &d) || h->rec_state != REC_REPLAYED ? -1 : wm_writer_finish(&w, h, out, n);
	h->wcap = NULL;
	h->on_tile = NULL;
	wm_writer_free(&w);
	return rc;
}

/* A functional chip like c for the record and warming runs. */
static chip *helper_chip(const chip *c, int frames)
{
	saar_config k = c->cfg;
	k.fidelity = CFG_FIDELITY_FUNCTIONAL;
	k.frame.frames = frames;
	diag d;
	return chip_create(&k, c->w, &d);
}

/* Stored warming: the checkpoints of this frame and config from the world
 * cache, else a warming run now (stored for the next run). Needs the
 * packet record; without one this run records it first, with a
 * functional chip of one frame. When impossible, full warming runs. */
void mode_warm_open(chip *c)
{
	if (c->cfg.sampling.warming != CFG_WARMING_STORED || !chip_estimates(&c->cfg))
		return;
	double t0 = chip_now_ms();
	c->warm_state = WARM_UNAVAILABLE;
	if (!(c->warm = calloc(1, sizeof *c->warm))) {
		fprintf(stderr, "warning: sampling.warming stored: out of memory; the functional "
		                "stretches run instead\n");
		return;
	}
	c->on_destroy = warm_close;
	if (c->rec_state == REC_UNSTORED) {
		/* make the record now: a warming run replays it */
		chip *h = helper_chip(c, 1);
		diag d;
		int ok = h && !chip_run(h, &d) && h->rec_state == REC_STORED;
		chip_destroy(h);
		mode_record(&c->md, NULL);
		pr_free(&c->rec);
		free(c->rec_key);
		c->rec_key = NULL;
		c->rec_state = REC_OFF;
		c->rec_ms += chip_now_ms() - t0;
		mode_rec_open(c);
		if (ok && c->rec_state == REC_REPLAYED)
			c->rec_state = REC_STORED;
		t0 = chip_now_ms();
	}
	int gl, gf;
	chip_warm_grid(c, &gl, &gf);
	char *key = c->md.in ? warm_key(c, gl, gf) : NULL;
	if (!key || wc_file(c->warm_file, sizeof c->warm_file, c->w->cache_dir, "warming", key)) {
		free(key);
		fprintf(stderr, "warning: sampling.warming stored needs --world-cache and a packet "
		                "record; the functional stretches run instead\n");
		return;
	}
	const void *tail;
	size_t n;
	if (wc_get_mapped(c->warm_file, key, NULL, 0, &tail, &n, &c->warm_map) == 1 &&
	    !wm_open(c->warm, tail, n, c)) {
		c->warm_state = WARM_LOADED;
	} else {
		wc_unmap(&c->warm_map);
		chip *h = helper_chip(c, c->cfg.frame.frames);
		void *b = NULL;
		if (h && !warm_build(h, gl, gf, &b, &n)) {
			diag d;
			c->warm_state = WARM_UNSTORED;
			if (world_cache_put(c->w, c->warm_file, key, NULL, NULL, 0, b, n, &d))
				fprintf(stderr, "warning: %s\n", d.msg);
			else
				c->warm_state = WARM_BUILT;
			if (wm_open(c->warm, b, n, c)) {
				free(b);
				b = NULL;
				c->warm_state = WARM_UNAVAILABLE;
			} else
				c->warm_own = b;
		} else {
			free(b);
			b = NULL;
		}
		if (!b) /* out of memory, or a cache line index past what is stored */
			fprintf(stderr, "warning: sampling.warming stored: the warming run failed; "
			                "the functional stretches run instead\n");
		chip_destroy(h);
	}
	free(key);
	c->warm_ms += chip_now_ms() - t0;
}
