/*
 * test_units_table.c: every per-kind list derives from units/unit_table.h.
 * For every entry of the table: --list-config has chip.<name>.count/width/
 * latency with the table's default, range and provenance, and they set
 * the config's unit[kind]; the report JSON has units.<name> with its
 * utilisation; the bound's resources and the sampled linear model's
 * regressors name it; the packet record's unit-op codes cover it without
 * touching another op's. And the pipeline's order is data set at wiring
 * time: a route the chip set can be replaced.
 *
 * Each test is written to catch "a table-derived list forgot a kind" (or
 * took another kind's slot) in one of the derivations.
 */
#include <math.h>
#include <stdlib.h>

#include "kernel-ref/view.h"
#include "sim/report.h"
#include "tests/chiptest.h"
#include "traces/pktrec.h"
#include "units/list.h"
#include "units/unit_table.h"

TestSuite(units_table);

/* Catches: an entry left out of the designated initializers (all zero,
 * name NULL), two kinds with one name, a default outside its range. */
Test(units_table, every_kind_is_described)
{
	for (int k = 0; k < UNIT_NKINDS; k++) {
		const unit_desc *u = &unit_table[k];
		cr_assert(u->name && *u->name && u->what && *u->what, "kind %d has no name", k);
		cr_assert_str_eq(unit_name(k), u->name);
		cr_assert_eq(unit_find(u->name), k, "%s: another kind has its name", u->name);
		const unit_param_desc *p[3] = {&u->count, &u->width, &u->latency};
		for (int i = 0; i < 3; i++) {
			cr_assert(p[i]->source && *p[i]->source, "%s: parameter %d unsourced",
			          u->name, i);
			cr_assert(p[i]->min <= p[i]->def && p[i]->def <= p[i]->max,
			          "%s: parameter %d default outside its range", u->name, i);
		}
		cr_assert(u->mem >= -1 && u->mem < MEM_NTYPES, "%s: memory type %d", u->name,
		          u->mem);
	}
	cr_assert_str_eq(unit_name(UNIT_NKINDS), "?");
	cr_assert_eq(unit_find("nope"), -1);
}

/* Catches: the config builder looping over fewer kinds than the table, or
 * a key's offset landing on another kind's (or field's) slot. */
Test(units_table, config_keys_follow_the_table)
{
	static const char *const leaf[3] = {"count", "width", "latency"};
	saar_config c;
	cfg_defaults(&c);
	for (int k = 0; k < UNIT_NKINDS; k++) {
		const unit_desc *u = &unit_table[k];
		const unit_param_desc *p[3] = {&u->count, &u->width, &u->latency};
		int *field[3] = {&c.chip.unit[k].count, &c.chip.unit[k].width,
		                 &c.chip.unit[k].latency};
		for (int i = 0; i < 3; i++) {
			char path[64], set[96];
			snprintf(path, sizeof path, "chip.%s.%s", u->name, leaf[i]);
			const cfg_key *key = cfg_find(path);
			cr_assert(key, "no key %s", path);
			cr_assert_eq(key->def, p[i]->def, "%s default", path);
			cr_assert_eq(key->min, p[i]->min, "%s min", path);
			cr_assert_eq(key->max, p[i]->max, "%s max", path);
			cr_assert_eq(key->published, p[i]->published != 0, "%s provenance", path);
			cr_assert_eq(key->calibrated, p[i]->calibrated != 0, "%s calibrated", path);
			cr_assert_eq(key->timing_only, p[i]->timing != 0, "%s timing", path);
			cr_assert_str_eq(key->source, p[i]->source);
			cr_assert(strstr(key->desc, u->what), "%s: %s", path, key->desc);
			cr_assert_eq(*field[i], p[i]->def, "%s: default not in unit[%d]", path, k);
			/* a value only this key could have put there */
			int v = p[i]->def == p[i]->max ? p[i]->min : p[i]->def + 1;
			snprintf(set, sizeof set, "%s=%d", path, v);
			diag d;
			cr_assert_eq(cfg_set(&c, set, &d), 0, "%s", d.msg);
			cr_assert_eq(*field[i], v, "%s does not set unit[%d].%s", path, k, leaf[i]);
		}
	}
}

/* Catches: --list-config (the program's, not only the library's table)
 * missing a kind's keys. */
Test(units_table, list_config_has_every_kind)
{
	char dir[256];
	tu_tmpdir(dir, sizeof dir);
	cr_assert_eq(tu_prog(dir, "saarsim", "--list-config"), 0);
	char *out = tu_slurp(dir, "out");
	for (int k = 0; k < UNIT_NKINDS; k++)
		for (int i = 0; i < 3; i++) {
			static const char *const leaf[3] = {"count ", "width ", "latency "};
			char line[64];
			snprintf(line, sizeof line, "\nchip.%s.%s", unit_table[k].name, leaf[i]);
			cr_assert(strstr(out, line), "--list-config lacks %s", line + 1);
		}
}

/* Catches: chip_res or SMP_LIN sized or named without a kind: every unit
 * kind is a resource of the bound and a regressor of the linear model,
 * under its own name; no resource is left unnamed. */
Test(units_table, resources_and_regressors_cover_every_kind)
{
	for (int k = 0; k < UNIT_NKINDS; k++) {
		cr_assert_str_eq(chip_res_name(RES_UNIT + k), unit_table[k].name);
		cr_assert_str_eq(chip_lin_name(k), unit_table[k].name);
	}
	for (int r = 0; r < RES_N; r++) {
		cr_assert(chip_res_name(r) && strcmp(chip_res_name(r), "?"), "resource %d unnamed",
		          r);
		for (int q = 0; q < r; q++)
			cr_assert(strcmp(chip_res_name(r), chip_res_name(q)),
			          "resources %d, %d: %s", q, r, chip_res_name(r));
	}
	cr_assert_eq(SMP_LIN, UNIT_NKINDS + 2);
	cr_assert_str_eq(chip_lin_name(UNIT_NKINDS), "sdram");
	cr_assert_str_eq(chip_lin_name(UNIT_NKINDS + 1), "hostbus");
}

/* Catches: two ops of the packet record sharing a code: a kind's PR_USE
 * code on the next op (the fifth kind used to be PR_SPILL_R), the typed-in
 * bases of the per-memory-type ranges (READ, READ_SAME, WRITE, USE) too
 * close for MEM_NTYPES types, or an op reaching the counter codes. Every
 * code below PR_COUNT1 is marked once; a second mark is the collision. */
Test(units_table, packet_record_op_range_covers_every_kind)
{
	int owner[PR_COUNT1];
	for (int i = 0; i < PR_COUNT1; i++)
		owner[i] = -1;
	int n = 0;
#define MARK(code)                                                                                 \
	do {                                                                                       \
		int c_ = (code);                                                                   \
		cr_assert(c_ >= 0 && c_ < PR_COUNT1, "op code %d outside 0..%d", c_,               \
		          PR_COUNT1 - 1);                                                          \
		cr_assert_eq(owner[c_], -1, "op code %d used by ops %d and %d", c_, owner[c_], n); \
		owner[c_] = n++;                                                                   \
	} while (0)
	for (int t = 0; t < MEM_NTYPES; t++) {
		MARK(PR_READ + t);
		MARK(PR_READ_SAME + t);
		MARK(PR_WRITE + t);
	}
	for (int k = 0; k < UNIT_NKINDS; k++)
		MARK(PR_USE + k);
	int later[] = {PR_SPILL_R, PR_SPILL_W, PR_MAXSP, PR_SHADE,
	               PR_ENTER,   PR_SPAWN,   PR_END,   PR_WAIT};
	for (size_t i = 0; i < sizeof later / sizeof *later; i++)
		MARK(later[i]);
#undef MARK
}

/* The run the two tests below look at: the embedded room, small. */
static chip *small_run(world *w, saar_config *c)
{
	tu_load_world(w, NULL, NULL, NULL);
	cfg_defaults(c);
	c->frame.width = 48;
	c->frame.height = 32;
	c->chip.rtps = 2;
	diag d;
	chip *ch = chip_create(c, w, &d);
	cr_assert(ch, "%s", d.msg);
	return ch;
}

/* Catches: the report's units object, or the chip's counters behind it,
 * missing a kind: units.<name> with a utilisation above 0 (every kind
 * but the transformation unit works on every frame of the room). */
Test(units_table, report_has_every_kind_with_utilisation)
{
	world w;
	saar_config c;
	chip *ch = small_run(&w, &c);
	diag d;
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	tu_assert_report_ok(ch); /* a test that writes a report checks it */
	char dir[256], path[300];
	tu_tmpdir(dir, sizeof dir);
	snprintf(path, sizeof path, "%s/r.json", dir);
	report_info ri = {.c = ch, .w = &w};
	cr_assert_eq(report_json(path, &ri, &d), 0, "%s", d.msg);
	char *s = tu_squeeze_json(tu_slurp(dir, "r.json"));
	const char *units = strstr(s, "\"units\":{\"");
	cr_assert(units, "no units object");
	for (int k = 0; k < UNIT_NKINDS; k++) {
		char key[64];
		snprintf(key, sizeof key, "\"%s\":{\"units\":", unit_table[k].name);
		const char *u = strstr(units, key);
		cr_assert(u, "report lacks units.%s", unit_table[k].name);
		const char *ut = strstr(u, "\"utilisation\":"), *end = strchr(u + strlen(key), '}');
		cr_assert(ut && ut < end, "units.%s has no utilisation", unit_table[k].name);
		/* the report's number is this kind's own (not another kind's, not 0) */
		double v = strtod(ut + strlen("\"utilisation\":"), NULL),
		       want = fig_util(ch, k, -1);
		/* the transformation unit works on two-level scenes only
		 * (tests/test_chip_twolevel.c counts its ops there) */
		if (k != UNIT_XFORM)
			cr_assert_gt(want, 0, "%s idle", unit_table[k].name);
		/* within the report's 9 significant digits (jsonw's %.9g: a
		 * relative rounding of up to 5e-9; 1e-9 failed on a sixth kind) */
		cr_assert(fabs(v - want) <= 1e-8 * want,
		          "units.%s.utilisation %.17g, the chip's %.17g", unit_table[k].name, v,
		          want);
	}

	chip_destroy(ch);
	world_free(&w);
}

/* The pipeline's order is data: what follows traversal at a leaf is the
 * route the wiring set, and a route put in its place is what runs.
 * Catches: a unit calling its successor directly again (the replacement
 * would see no leaf). */
static int leaves;
static void counting_leaf(thr_ctx *t)
{
	leaves++;
	list_leaf(t);
}

Test(units_table, routing_is_set_at_wiring)
{
	world w;
	saar_config c;
	chip *ch = small_run(&w, &c);
	const unit_route *r = &ch->env.route;
	cr_assert(r->enter && r->leaf && r->triangles && r->traverse && r->finish,
	          "a route is unset");
	cr_assert(r->leaf == list_leaf);
	ch->env.route.leaf = counting_leaf;
	leaves = 0;
	diag d;
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	cr_assert_gt(leaves, 0);
	cr_assert_eq((uint64_t)leaves, stats_get(&ch->st, "trav.leaf_visits"),
	             "every leaf went through the route");
	tu_assert_identical(ch, "rerouted through a counting leaf");
	chip_destroy(ch);
	world_free(&w);
}
