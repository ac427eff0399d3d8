/*
 * test_modes.c: the simulation modes as sinks (units/sink.h,
 * sim/modes/; docs/design-modes.md). A test-only observer sink, put
 * outside the mode's sinks with mode_observe (as docs/extending.md
 * shows), tallies every operation the units (or a replayed stream) emit;
 * the tallies and the chip's counters tell whether a sink dropped,
 * doubled or changed an operation.
 */
#include <string.h>

#include "sim/modes/modes.h"
#include "tests/chiptest.h"

/* What went through the observer. Waits and maxima are left out: the
 * math waits after every batch of reads and raises a maximum at every
 * step, a replayed stream only where it must (traces/pktrec.h). */
typedef struct tally {
	thr_sink s;
	uint64_t reads[MEM_NTYPES], read_bytes[MEM_NTYPES], writes[MEM_NTYPES];
	uint64_t uses[UNIT_NKINDS], use_rays[UNIT_NKINDS];
	uint64_t counts[C_NCOUNTERS];
	uint64_t shade[sizeof(shade_counts) / sizeof(uint64_t)];
	uint64_t enters[PKT_NTYPES], enter_rays, kids, releases, shaded;
} tally;

static void t_read(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes, void *dst)
{
	tally *y = (tally *)s;
	y->reads[type]++;
	y->read_bytes[type] += bytes;
	s->inner->op->read(s->inner, t, type, addr, bytes, dst);
}

static void t_write(thr_sink *s, thr_ctx *t, int type, uint64_t addr, uint32_t bytes,
                    const void *src)
{
	((tally *)s)->writes[type]++;
	s->inner->op->write(s->inner, t, type, addr, bytes, src);
}

static int t_wait(thr_sink *s, thr_ctx *t, void (*cont)(thr_ctx *t))
{
	return s->inner->op->wait(s->inner, t, cont);
}

static void t_use(thr_sink *s, thr_ctx *t, int kind, int rays, eng_handler done)
{
	tally *y = (tally *)s;
	y->uses[kind]++;
	y->use_rays[kind] += (uint64_t)rays;
	s->inner->op->use(s->inner, t, kind, rays, done);
}

static void t_count(thr_sink *s, thr_ctx *t, int id, uint64_t n)
{
	((tally *)s)->counts[id] += n;
	s->inner->op->count(s->inner, t, id, n);
}

static void t_count_max(thr_sink *s, thr_ctx *t, int id, uint64_t v)
{
	s->inner->op->count_max(s->inner, t, id, v);
}

static void t_shade(thr_sink *s, thr_ctx *t, const shade_counts *add)
{
	const uint64_t *a = (const uint64_t *)add;
	for (size_t i = 0; i < sizeof(shade_counts) / sizeof(uint64_t); i++)
		((tally *)s)->shade[i] += a[i];
	s->inner->op->shade(s->inner, t, add);
}

static void t_enter(thr_sink *s, thr_ctx *t, int type, uint64_t rays)
{
	((tally *)s)->enters[type]++;
	((tally *)s)->enter_rays += rays;
	s->inner->op->enter(s->inner, t, type, rays);
}

static int t_spawn(thr_sink *s, thr_ctx *t, int n, const packet *kids, const int32_t *ids)
{
	((tally *)s)->kids += (uint64_t)n;
	return s->inner->op->spawn(s->inner, t, n, kids, ids);
}

static void t_release(thr_sink *s, thr_ctx *t, int shaded)
{
	((tally *)s)->releases++;
	((tally *)s)->shaded += (uint64_t)shaded;
	s->inner->op->release(s->inner, t, shaded);
}

static const thr_sink_ops tally_ops = {t_read,      t_write, t_wait,  t_use,   t_count,
                                       t_count_max, t_shade, t_enter, t_spawn, t_release};

/* Runs config c on w with a tally outside the mode's sinks. */
static chip *run_tallied(const world *w, const saar_config *c, tally *y)
{
	memset(y, 0, sizeof *y);
	y->s.op = &tally_ops;
	diag d;
	chip *ch = chip_create(c, w, &d);
	cr_assert(ch, "%s", d.msg);
	mode_observe(&ch->md, &y->s);
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	tu_assert_report_ok(ch);
	return ch;
}

static void same_tally(const tally *a, const tally *b, const char *what)
{
	const uint64_t *x = (const uint64_t *)&a->reads, *y = (const uint64_t *)&b->reads;
	size_t n = (sizeof(tally) - offsetof(tally, reads)) / sizeof(uint64_t);
	for (size_t i = 0; i < n; i++)
		cr_assert_eq(x[i], y[i], "%s: tally word %zu: %llu vs %llu", what, i,
		             (unsigned long long)x[i], (unsigned long long)y[i]);
	cr_assert_gt(a->releases, 0, "%s: nothing ran", what);
	cr_assert_gt(a->writes[MEM_KD], 0, "%s: no stack spill", what);
}

/* The tally against the chip's own counts: every read and write the
 * sinks got reached the memory port, every unit op its unit. */
static void tally_reached(const chip *ch, const tally *y, const char *what)
{
	for (int t = 0; t < MEM_NTYPES; t++) {
		cr_assert_eq(ch->mem.n.reads[t], y->reads[t], "%s: %s reads at the port", what,
		             mem_type_name(t));
		cr_assert_eq(ch->mem.n.read_bytes[t], y->read_bytes[t], "%s", what);
		cr_assert_eq(ch->mem.n.writes[t], y->writes[t], "%s", what);
	}
	for (int k = 0; k < UNIT_NKINDS; k++) {
		uint64_t ops = 0, rays = 0;
		for (int r = 0; r < ch->nrtp; r++) {
			ops += *ch->rtp[r].u[k].ops_n;
			rays += *ch->rtp[r].u[k].rays;
		}
		cr_assert_eq(ops, y->uses[k], "%s: %s ops", what, chip_unit_name(k));
		cr_assert_eq(rays, y->use_rays[k], "%s: %s rays", what, chip_unit_name(k));
	}
	uint64_t rays = 0;
	for (int p = 0; p < PKT_NTYPES; p++) {
		cr_assert_eq(*ch->env.c[C_PKT_PRIMARY + p], y->enters[p], "%s: packets", what);
		rays += *ch->env.c[C_RAYS_PRIMARY + p];
	}
	cr_assert_eq(rays, y->enter_rays, "%s: rays", what);
	/* the counters the units bump through thr_count (the queue's are the
	 * base sinks' own, the maximum is raised, not added) */
	for (int i = C_BOX_MISS_PACKETS; i < C_NCOUNTERS; i++)
		if (i != C_MAX_SP && i != C_SPAWNED && i != C_QUEUED && i != C_MAX_QUEUE)
			cr_assert_eq(*ch->env.c[i], y->counts[i], "%s: counter %d", what, i);
	cr_assert_eq(memcmp(&ch->env.sh, y->shade, sizeof y->shade), 0, "%s: shade counts", what);
	cr_assert_eq(*ch->env.c[C_SPAWNED], y->kids, "%s: children queued", what);
}

static void room(world *w, const char *cache_dir, saar_config *c)
{
	tu_load_world_cached(w, NULL, NULL, NULL, cache_dir);
	cfg_defaults(c);
	c->frame.width = c->frame.height = 128;
	c->chip.threads_per_rtp = 4;
	c->chip.stack_depth = 2; /* stack spills: writes, and reads of spilled entries */
}

/* Mistake caught: a sink that drops, doubles or changes an operation (the
 * functional sink not counting a unit op's rays, a timed write not sent
 * to memory, a base sink not queueing a child): the timed and the
 * functional sink must do the same work for the same frame, only its time
 * differs, and what each was given must reach the memory port, the units
 * and the counters. */
Test(modes, timed_and_functional_sinks_do_the_same_work)
{
	world w;
	saar_config c;
	room(&w, NULL, &c);
	tally a, b;
	c.fidelity = CFG_FIDELITY_CYCLE;
	chip *x = run_tallied(&w, &c, &a);
	c.fidelity = CFG_FIDELITY_FUNCTIONAL;
	chip *y = run_tallied(&w, &c, &b);
	same_tally(&a, &b, "cycle vs functional");
	tally_reached(x, &a, "cycle");
	tally_reached(y, &b, "functional");
	tu_assert_identical(x, "cycle");
	tu_assert_identical(y, "functional");
	chip_destroy(x);
	chip_destroy(y);
	world_free(&w);
}

/* Mistake caught: replay that decodes a stream into other operations than
 * the recording sink took in (a child not spawned, a shading count into
 * the wrong field, a read of the wrong size), or a recording sink that
 * does not pass an operation on: the run replaying the record must emit
 * what the recording run emitted, operation for operation. Functional,
 * and sampled (the detailed regions replay into the timed sink). */
Test(modes, replay_emits_what_was_recorded)
{
	char dir[64];
	tu_tmpdir(dir, sizeof dir);
	world w;
	saar_config c;
	room(&w, dir, &c);
	const int fid[2] = {CFG_FIDELITY_FUNCTIONAL, CFG_FIDELITY_SAMPLED};
	for (int i = 0; i < 2; i++) {
		c.fidelity = fid[i];
		c.sampling.rate = 0.1;
		c.sampling.warming = CFG_WARMING_FULL; /* the stretches replay too (auto: stored) */
		if (fid[i] == CFG_FIDELITY_SAMPLED)
			c.frame.width = c.frame.height = 256;
		tally a, b;
		chip *rec = run_tallied(&w, &c, &a);
		cr_assert(rec->rec_state == REC_STORED, "no record stored: %s",
		          chip_rec_name(rec->rec_state));
		chip *rep = run_tallied(&w, &c, &b);
		cr_assert_eq(rep->rec_state, REC_REPLAYED, "%s", chip_rec_name(rep->rec_state));
		same_tally(&a, &b,
		           i ? "sampled: recording vs replay" : "functional: recording vs replay");
		tally_reached(rec, &a, "recording");
		tally_reached(rep, &b, "replay");
		chip_destroy(rec);
		chip_destroy(rep);
	}
	world_free(&w);
}
