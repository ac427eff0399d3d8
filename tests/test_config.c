/*
 * test_config.c: the YAML config (sim/config.h): defaults, the standard
 * config, every error with its exact location, --set, cross-key checks, the
 * JSON dump and the generated listings.
 */
#include <string.h>
#include <unistd.h>

#include "kernel-ref/jsonw.h"
#include "kernel-ref/yload.h"
#include "sim/config.h"
#include "sim/memconfig.h"
#include "tests/testutil.h"

/* Loads text from a fresh temporary file; returns cfg_load's result and
 * leaves the file path in path. */
static int load_text(saar_config *c, const char *text, diag *d, char *path, size_t n)
{
	char dir[64];
	tu_tmpdir(dir, sizeof dir);
	tu_write(path, n, dir, "cfg.yaml", text);
	return cfg_load(c, path, d);
}

/* Asserts that text fails to load with exactly "<file>:<where>: <msg>". */
static void expect_error(const char *text, const char *where_msg)
{
	saar_config c;
	diag d = {{0}};
	char path[128], want[1200];
	cr_assert_eq(load_text(&c, text, &d, path, sizeof path), -1, "accepted: %s", text);
	snprintf(want, sizeof want, "%s:%s", path, where_msg);
	cr_assert_str_eq(d.msg, want);
}

Test(config, defaults_resolve_and_validate)
{
	saar_config c;
	diag d = {{0}};
	cfg_defaults(&c);
	cr_assert_float_eq(c.chip.clock_mhz, 533.0, 1e-9);
	cr_assert_eq(c.chip.rtps, 4);
	cr_assert_eq(c.chip.threads_per_rtp, 16);
	cr_assert_eq(c.chip.packet_w * c.chip.packet_h, 64);
	cr_assert(c.chip.masked_packets);
	/* thread_sched is calibrated (docs/CALIBRATION.md): the assumption
	 * it replaced stays in the -assumed config */
	saar_config a;
	cr_assert_eq(cfg_load(&a, "configs/saarcor-std-assumed.yaml", &d), 0, "%s", d.msg);
	cr_assert_eq(a.chip.thread_sched, CFG_SCHED_ROUND_ROBIN);
	cr_assert_eq(c.chip.tile_order, CFG_TILES_SCANLINE);
	cr_assert_eq(c.chip.unit[UNIT_TRAV].width, 4 * c.chip.unit[UNIT_ISECT].width,
	             "designed for 4:1 (seed 002 §4.7)");
	cr_assert_eq(c.frame.width, 1024);
	cr_assert_eq(c.frame.height, 768);
	cr_assert_float_eq(c.kdtree.cost_isect, 1.5, 1e-9);
	cr_assert_float_eq(c.kdtree.empty_bonus, 0.2, 1e-9);
	cr_assert_eq(c.kdtree.leaf_size, 2);
	cr_assert_eq(c.memory.model, CFG_MEM_HIERARCHY);
	cr_assert_eq(c.memory.latency, 20);
	cr_assert_eq(c.fidelity, CFG_FIDELITY_CYCLE);
	cr_assert_str_eq(c.name, "saarcor-std");
	cr_assert_eq(cfg_validate(&c, &d), 0, "%s", d.msg);
}

Test(config, schema_table_is_sound)
{
	size_t n;
	const cfg_key *k = cfg_keys(&n);
	cr_assert_gt(n, 30);
	for (size_t i = 0; i < n; i++) {
		cr_assert(k[i].desc && *k[i].desc && k[i].source && *k[i].source, "%s", k[i].path);
		cr_assert_eq(cfg_find(k[i].path), &k[i], "duplicate path %s", k[i].path);
		if (k[i].type == CFG_INT || k[i].type == CFG_FLOAT)
			cr_assert(k[i].min <= k[i].def && k[i].def <= k[i].max, "%s", k[i].path);
		/* the JSON writer needs each section's keys contiguous */
		const char *dot = strrchr(k[i].path, '.');
		size_t sl = dot ? (size_t)(dot - k[i].path) : 0;
		for (size_t j = i + 2; sl && j < n; j++) {
			if (!strncmp(k[j].path, k[i].path, sl) && k[j].path[sl] == '.')
				cr_assert(!strncmp(k[j - 1].path, k[i].path, sl),
				          "section of %s split before %s", k[i].path, k[j].path);
		}
	}
	cr_assert_null(cfg_find("chip"));
	cr_assert_null(cfg_find("chip.trav"));
}

Test(config, standard_config_equals_defaults)
{
	saar_config c, def;
	diag d = {{0}};
	int rc = cfg_load(&c, "configs/saarcor-std.yaml", &d);
	cr_assert_eq(rc, 0, "%s", d.msg);
	cr_assert_eq(cfg_validate(&c, &d), 0, "%s", d.msg);
	/* The defaults are the standard chip; both start from one memset, so
	 * the padding matches too. */
	cfg_defaults(&def);
	cr_assert(!memcmp(&c, &def, sizeof c), "configs/saarcor-std.yaml differs from defaults");
}

/* Calibration (docs/calibration.md) may only move assumed values: a key
 * is never both published and calibrated, and a calibrated one cites the
 * calibration. Catches: a published value (clock, cache sizes, ...) taken
 * into the fit, or a fitted value passed off without its provenance. */
Test(config, calibrated_keys_are_not_published_and_cite_the_fit)
{
	size_t n;
	const cfg_key *k = cfg_keys(&n);
	for (size_t i = 0; i < n; i++) {
		cr_assert(!(k[i].published && k[i].calibrated), "%s: published and calibrated",
		          k[i].path);
		if (k[i].calibrated)
			cr_assert(strstr(k[i].source, "docs/CALIBRATION.md"), "%s: %s", k[i].path,
			          k[i].source);
		cr_assert_str_eq(cfg_provenance(&k[i]), k[i].published    ? "published"
		                                        : k[i].calibrated ? "calibrated"
		                                                          : "assumed");
	}
}

/* The -assumed configs keep the uncalibrated assumptions: each differs
 * from its calibrated config (std = the defaults) in the calibrated keys
 * and the name only, and in every calibrated key. Catches: a calibrated
 * value the schema still calls assumed, a key marked calibrated whose
 * value the calibration did not change, and an -assumed config that
 * drifted from what the calibration started from. */
Test(config, assumed_configs_differ_in_the_calibrated_keys_only)
{
	const char *pairs[2][2] = {
	    {"configs/saarcor-std-assumed.yaml", "configs/saarcor-std.yaml"},
	    {"configs/saarcor-vma-assumed.yaml", "configs/saarcor-vma.yaml"}};
	size_t n;
	const cfg_key *k = cfg_keys(&n);
	for (int p = 0; p < 2; p++) {
		saar_config a, c;
		diag d = {{0}};
		cr_assert_eq(cfg_load(&a, pairs[p][0], &d), 0, "%s", d.msg);
		cr_assert_eq(cfg_load(&c, pairs[p][1], &d), 0, "%s", d.msg);
		for (size_t i = 0; i < n; i++) {
			if (!strcmp(k[i].path, "name"))
				continue;
			int differs = memcmp((const char *)&a + k[i].off,
			                     (const char *)&c + k[i].off, k[i].size) != 0;
			cr_assert_eq(differs, k[i].calibrated, "%s vs %s: %s %s", pairs[p][0],
			             pairs[p][1], k[i].path,
			             differs ? "differs but is not calibrated"
			                     : "is calibrated but the same");
		}
	}
}

Test(config, nested_and_dotted_keys)
{
	saar_config c;
	diag d = {{0}};
	char path[128];
	int rc = load_text(&c,
	                   "chip:\n"
	                   "  trav: {width: 8, latency: 3}\n"
	                   "  masked_packets: no\n"
	                   "  thread_sched: oldest_first\n"
	                   "chip.isect.count: 2\n"
	                   "kdtree:\n"
	                   "  cost_isect: 2.25   # comment\n"
	                   "name: \"my chip\"\n",
	                   &d, path, sizeof path);
	cr_assert_eq(rc, 0, "%s", d.msg);
	cr_assert_eq(c.chip.unit[UNIT_TRAV].width, 8);
	cr_assert_eq(c.chip.unit[UNIT_TRAV].latency, 3);
	cr_assert_eq(c.chip.unit[UNIT_TRAV].count, 1, "untouched keys keep defaults");
	cr_assert_not(c.chip.masked_packets);
	cr_assert_eq(c.chip.thread_sched, CFG_SCHED_OLDEST_FIRST);
	cr_assert_str_eq(cfg_enum_name(&c, "chip.thread_sched"), "oldest_first");
	cr_assert_eq(c.chip.unit[UNIT_ISECT].count, 2);
	cr_assert_float_eq(c.kdtree.cost_isect, 2.25, 1e-12);
	cr_assert_str_eq(c.name, "my chip");
}

Test(config, empty_file_is_defaults)
{
	saar_config c, def;
	diag d = {{0}};
	char path[128];
	cr_assert_eq(load_text(&c, "# nothing but a comment\n", &d, path, sizeof path), 0);
	cfg_defaults(&def);
	/* named after its file, as any config without `name` */
	cr_assert_str_eq(c.name, "cfg");
	snprintf(def.name, sizeof def.name, "cfg");
	cr_assert(!memcmp(&c, &def, sizeof c));
}

Test(config, missing_file)
{
	saar_config c;
	diag d = {{0}};
	cr_assert_eq(cfg_load(&c, "/nonexistent/x.yaml", &d), -1);
	cr_assert_str_eq(d.msg, "/nonexistent/x.yaml: cannot open: No such file or directory");
}

Test(config, unknown_keys_with_suggestions)
{
	expect_error("chip:\n  rtps: 4\n  rtp: 4\n",
	             "3:3: unknown key 'chip.rtp' (did you mean 'chip.rtps'?)");
	expect_error("chip:\n  tarv:\n    width: 3\n",
	             "2:3: unknown key 'chip.tarv' (did you mean 'chip.trav'?)");
	expect_error("chip:\n  trav: {widht: 3}\n",
	             "2:10: unknown key 'chip.trav.widht' (did you mean 'chip.trav.width'?)");
	expect_error("rtps: 4\n", "1:1: unknown key 'rtps' (did you mean 'chip.rtps'?)");
	expect_error("bogus: 4\n", "1:1: unknown key 'bogus'");
}

Test(config, wrong_types)
{
	expect_error("chip:\n  rtps: four\n", "2:9: chip.rtps: expected an integer, got 'four'");
	expect_error("chip:\n  rtps: 4.5\n", "2:9: chip.rtps: expected an integer, got '4.5'");
	expect_error("chip:\n  rtps:\n", "2:8: chip.rtps: expected an integer, got nothing");
	expect_error("chip.clock_mhz: fast\n",
	             "1:17: chip.clock_mhz: expected a number, got 'fast'");
	expect_error("chip.clock_mhz: .nan\n",
	             "1:17: chip.clock_mhz: expected a number, got '.nan'");
	expect_error("chip.masked_packets: maybe\n",
	             "1:22: chip.masked_packets: expected true or false, got 'maybe'");
	expect_error(
	    "chip:\n  thread_sched: lifo\n",
	    "2:17: chip.thread_sched: expected one of round_robin, oldest_first; got 'lifo'");
	expect_error("chip.tile_order: Morton\n",
	             "1:18: chip.tile_order: expected one of scanline, morton; got 'Morton'");
}

Test(config, out_of_range)
{
	expect_error("chip:\n  rtps: 0\n", "2:9: chip.rtps: must be in [1, 1024], got 0");
	expect_error("chip:\n  packet_w: 65\n", "2:13: chip.packet_w: must be in [8, 8], got 65");
	expect_error("kdtree.empty_bonus: 1\n",
	             "1:21: kdtree.empty_bonus: must be in [0, 0.99], got 1");
	expect_error("chip.clock_mhz: 0.5\n",
	             "1:17: chip.clock_mhz: must be in [1, 10000], got 0.5");
	expect_error("chip.rtps: 99999999999999999999\n",
	             "1:12: chip.rtps: expected an integer, got '99999999999999999999'");
}

Test(config, structure_errors)
{
	expect_error("chip:\n  rtps:\n    a: 1\n",
	             "3:5: chip.rtps: expected a single value, got a mapping");
	expect_error("chip:\n  rtps: [1]\n",
	             "2:9: chip.rtps: expected a single value, got a sequence");
	expect_error("chip: 4\n",
	             "1:7: 'chip' is a section: expected a mapping of its keys, got a value");
	expect_error("- a\n", "1:1: expected a mapping of keys at the top level, got a sequence");
	expect_error("chip:\n  rtps: 4\n---\nchip:\n  rtps: 4\n",
	             "4:1: only one YAML document is allowed");
}

Test(config, duplicate_keys)
{
	expect_error("chip:\n  rtps: 4\n  rtps: 5\n",
	             "3:3: duplicate key 'rtps' (first at line 2)");
	expect_error("chip: {rtps: 4}\nchip: {rtps: 5}\n",
	             "2:1: duplicate key 'chip' (first at line 1)");
	expect_error("chip:\n  rtps: 4\nchip.rtps: 5\n",
	             "3:1: duplicate key 'chip.rtps' (first at line 2)");
}

Test(config, bad_yaml)
{
	expect_error("chip:\n  rtps: 4\n bad\n",
	             "3:2: YAML syntax error: did not find expected key (while parsing a block "
	             "mapping)");
	expect_error("chip: {rtps: 4\n",
	             "2:1: YAML syntax error: did not find expected ',' or '}' (while parsing a "
	             "flow mapping)");
	expect_error("chip:\n\trtps: 4\n", "2:1: YAML syntax error: found character that cannot "
	                                   "start any token (while scanning for the next token)");
}

/* The config is checked as it streams (kernel-ref/yload.h): the first
 * unknown key stops the load whatever follows it. A 45 MB config whose
 * valid keys were followed by a 5-million-item list under `stuff` took
 * 808 MB before it was refused; here the list is followed by a syntax
 * error, which the old loader (the whole document first, then the keys)
 * reported instead. */
Test(config, first_unknown_key_stops_the_load)
{
	char *text = tu_repeat("name: x\nchip:\n  rtps: 2\nstuff: [", "1, ", 300000, "1]\n]]]\n");
	expect_error(text, "4:1: unknown key 'stuff'");
	free(text);
}

/* The limits of a config (docs/config.md "Limits"), each refused at the
 * event that breaks it; the old loader read all of it (and took minutes
 * over 200,000 `[`). The largest input within each limit loads as far as
 * its other checks. */
Test(config, size_depth_and_node_limits)
{
	/* size: CFG_FILE_MAX bytes of comment load; one byte more does not */
	char *text = tu_repeat("#", " ", CFG_FILE_MAX - 2, "\n");
	saar_config c;
	diag d = {{0}};
	char path[128], want[512];
	cr_assert_eq(load_text(&c, text, &d, path, sizeof path), 0, "%s", d.msg);
	free(text);
	text = tu_repeat("#", " ", CFG_FILE_MAX - 1, "\n");
	cr_assert_eq(load_text(&c, text, &d, path, sizeof path), -1);
	snprintf(want, sizeof want, "%s: larger than the size limit for a config (%u bytes)", path,
	         CFG_FILE_MAX);
	cr_assert_str_eq(d.msg, want);
	free(text);

	/* depth: YL_DEPTH_MAX nested sequences parse (the root is no mapping),
	 * one more is refused where it opens */
	char *close = tu_repeat("", "]", YL_DEPTH_MAX, "\n");
	text = tu_repeat("", "[", YL_DEPTH_MAX, close);
	expect_error(text, "1:1: expected a mapping of keys at the top level, got a sequence");
	free(text);
	free(close);
	text = tu_repeat("", "[", 200000, "");
	expect_error(text,
	             "1:33: YAML nested deeper than 32 levels (the depth limit for a config)");
	free(text);

	/* nodes: the root and CFG_NODES_MAX - 1 items parse, one more does not */
	text = tu_repeat("[0", ",1", CFG_NODES_MAX - 2, "]\n");
	expect_error(text, "1:1: expected a mapping of keys at the top level, got a sequence");
	free(text);
	text = tu_repeat("[0", ",1", CFG_NODES_MAX - 1, "]\n");
	snprintf(want, sizeof want, "1:%d: more than %d YAML nodes (the node limit for a config)",
	         2 + 2 * (CFG_NODES_MAX - 1), CFG_NODES_MAX);
	expect_error(text, want);
	free(text);
}

/* Anchors and aliases are refused (kernel-ref/yload.h says why): the
 * billion laughs, nine levels of ten aliases each, at its first anchor. */
Test(config, anchors_and_aliases_are_refused)
{
	char text[2048] = "lol0: &a0 [lol]\n";
	for (int i = 1; i < 10; i++) {
		snprintf(text + strlen(text), sizeof text - strlen(text), "lol%d: &a%d [", i, i);
		for (int j = 0; j < 10; j++)
			snprintf(text + strlen(text), sizeof text - strlen(text), "%s*a%d",
			         j ? ", " : "", i - 1);
		snprintf(text + strlen(text), sizeof text - strlen(text), "]\n");
	}
	expect_error(text, "1:7: YAML anchors and aliases are not allowed in a config (&a0)");
	expect_error("chip:\n  rtps: &r 2\n", "2:9: YAML anchors and aliases are not allowed in a "
	                                      "config (&r)");
	expect_error("name: *x\n",
	             "1:7: YAML anchors and aliases are not allowed in a config (*x)");
}

Test(config, set_overrides)
{
	saar_config c;
	diag d = {{0}};
	cfg_defaults(&c);
	cr_assert_eq(cfg_set(&c, "chip.trav.width=8", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, " chip.rtps = 2 ", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "chip.masked_packets=false", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "chip.tile_order=morton", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "kdtree.cost_trav=0.5", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "name=a=b", &d), 0, "%s", d.msg);
	cr_assert_eq(c.chip.unit[UNIT_TRAV].width, 8);
	cr_assert_eq(c.chip.rtps, 2);
	cr_assert_not(c.chip.masked_packets);
	cr_assert_eq(c.chip.tile_order, CFG_TILES_MORTON);
	cr_assert_float_eq(c.kdtree.cost_trav, 0.5, 1e-12);
	cr_assert_str_eq(c.name, "a=b", "only the first '=' splits");
}

static void expect_set_error(const char *arg, const char *msg)
{
	saar_config c;
	diag d = {{0}};
	cfg_defaults(&c);
	cr_assert_eq(cfg_set(&c, arg, &d), -1, "accepted %s", arg);
	cr_assert_str_eq(d.msg, msg);
}

Test(config, set_errors)
{
	expect_set_error("chip.rtps", "--set: expected key=value, got 'chip.rtps'");
	expect_set_error("chip.rtp=4", "--set: unknown key 'chip.rtp' (did you mean 'chip.rtps'?)");
	expect_set_error("chip.rtps=abc", "--set: chip.rtps: expected an integer, got 'abc'");
	expect_set_error("chip.rtps=", "--set: chip.rtps: expected an integer, got nothing");
	expect_set_error("chip.trav.latency=0",
	                 "--set: chip.trav.latency: must be in [1, 10000], got 0");
	expect_set_error("chip.trav=4", "--set: 'chip.trav' is a section; set one of its keys "
	                                "(chip.trav.*)");
	expect_set_error("fidelity=fast",
	                 "--set: fidelity: expected one of cycle, sampled, functional; got 'fast'");
}

Test(config, validate_cross_keys)
{
	saar_config c;
	diag d = {{0}};
	cfg_defaults(&c);
	/* a packet is one 8 x 8 tile (kernel-ref's): other sizes are out of range */
	cr_assert_eq(cfg_set(&c, "chip.packet_w=4", &d), -1);
	cr_assert_str_eq(d.msg, "--set: chip.packet_w: must be in [8, 8], got 4");
	/* a stack below the tree depth spills to memory: a design-space parameter */
	cfg_set(&c, "chip.stack_depth=4", &d);
	cr_assert_eq(cfg_validate(&c, &d), 0, "%s", d.msg);
	cfg_set(&c, "kdtree.max_depth=40", &d);
	cr_assert_eq(cfg_validate(&c, &d), 0, "%s", d.msg);
}

/* sampling.overlap: -1 (fitted) or a share from 0 on; a value between
 * is bad input, not a silent fit. Catches the check left out. */
Test(config, overlap_between_fitted_and_none_is_refused)
{
	saar_config c;
	diag d = {{0}};
	cfg_defaults(&c);
	cr_assert_eq(c.sampling.overlap, -1.0, "the default: fitted");
	cr_assert_eq(cfg_validate(&c, &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "sampling.overlap=0", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_validate(&c, &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "sampling.overlap=-0.5", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_validate(&c, &d), -1);
	cr_assert_str_eq(d.msg,
	                 "config: sampling.overlap -0.5: -1 (fitted) or a share from 0 to 4");
}

/* Runs a writer into a temporary file and returns its text (malloc'd). */
static char *capture(void (*fn)(FILE *, const saar_config *), const saar_config *c)
{
	FILE *f = tmpfile();
	cr_assert(f);
	fn(f, c);
	long n = ftell(f);
	rewind(f);
	char *s = calloc(1, (size_t)n + 1);
	cr_assert_eq(fread(s, 1, (size_t)n, f), (size_t)n);
	fclose(f);
	return s;
}

static void json_fn(FILE *f, const saar_config *c)
{
	jsonw w;
	jsonw_init_file(&w, f);
	cfg_write_json(c, &w);
}
static void list_fn(FILE *f, const saar_config *c)
{
	cfg_list(f);
}
static void md_fn(FILE *f, const saar_config *c)
{
	cfg_write_markdown(f);
}

Test(config, json_dump_has_every_key_nested)
{
	saar_config c;
	diag d = {{0}};
	cfg_defaults(&c);
	cfg_set(&c, "chip.thread_sched=oldest_first", &d);
	char *s = capture(json_fn, &c);
	size_t n;
	const cfg_key *k = cfg_keys(&n);
	for (size_t i = 0; i < n; i++) {
		const char *dot = strrchr(k[i].path, '.');
		char leaf[80];
		snprintf(leaf, sizeof leaf, "\"%s\": ", dot ? dot + 1 : k[i].path);
		cr_assert(strstr(s, leaf), "%s missing in %s", k[i].path, s);
	}
	/* nesting follows the dotted paths; enums are names, bools literals */
	const char *chip = strstr(s, "\"chip\": {"), *trav = strstr(s, "\"trav\": {"),
	           *frame = strstr(s, "\"frame\": {");
	cr_assert(chip && trav && frame && chip < trav && trav < frame, "%s", s);
	cr_assert(strstr(s, "\"thread_sched\": \"oldest_first\""), "%s", s);
	cr_assert(strstr(s, "\"masked_packets\": true"), "%s", s);
	cr_assert(strstr(s, "\"cost_isect\": 1.5"), "%s", s);
	cr_assert(strstr(s, "\"rtps\": 4"), "%s", s);
	int depth = 0, maxd = 0;
	for (const char *p = s; *p; p++) {
		depth += (*p == '{') - (*p == '}');
		cr_assert_geq(depth, 0);
		maxd = depth > maxd ? depth : maxd;
	}
	cr_assert_eq(depth, 0, "%s", s);
	cr_assert_eq(maxd, 4,
	             "top, memory, memory.l1, memory.l1.kd: nesting follows the dotted keys");
	free(s);
}

Test(config, list_and_markdown_name_every_key)
{
	char *l = capture(list_fn, NULL), *m = capture(md_fn, NULL);
	size_t n;
	const cfg_key *k = cfg_keys(&n);
	for (size_t i = 0; i < n; i++) {
		char want[96];
		snprintf(want, sizeof want, "| `%s` |", k[i].path);
		cr_assert(strstr(m, want), "%s missing in markdown", k[i].path);
		cr_assert(strstr(l, k[i].path), "%s missing in list", k[i].path);
	}
	cr_assert(strstr(l, "round_robin, oldest_first"));
	cr_assert(strstr(m, "## Errors"));
	free(l);
	free(m);
}

/* Every bad-input error is one line: a library message that quotes a
 * file's bytes (newline, tab, escape) comes out with them as '?'. */
Test(config, diag_message_is_one_line)
{
	diag d = {{0}};
	cr_assert_eq(diag_set(&d, "f.ply", 3, 0, "bad \"%s\"", "k\n0\t1\x1b"), -1);
	cr_assert_str_eq(d.msg, "f.ply:3: bad \"k?0?1?\"");
}

/* Writes {"a": {FLAG: true, "vma": {"vma": 3}}, "b": (the same)} to p and
 * returns jsonw_close's result: FLAG "vma" repeats a key in one object. */
static int write_doc(const char *p, const char *flag, diag *d)
{
	jsonw w;
	cr_assert_eq(jsonw_open(&w, p, d), 0);
	jsonw_obj_begin(&w);
	for (int i = 0; i < 2; i++) {
		jsonw_key(&w, i ? "b" : "a");
		jsonw_obj_begin(&w);
		jsonw_kbool(&w, flag, 1);
		jsonw_key(&w, "vma");
		jsonw_obj_begin(&w);
		jsonw_kuint(&w, "vma", 3);
		jsonw_obj_end(&w);
		jsonw_obj_end(&w);
	}
	jsonw_obj_end(&w);
	return jsonw_close(&w, d);
}

/* A key twice in one object is a writer bug the report must not hide
 * (parsers keep one of the values): jsonw_close fails naming it and leaves
 * no file. The same key in sibling or nested objects is fine. */
Test(config, json_writer_refuses_a_repeated_key)
{
	char dir[256], p[512];
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/r.json", dir);
	diag d = {{0}};
	cr_assert_eq(write_doc(p, "vma", &d), -1);
	cr_assert(strstr(d.msg, "r.json: key 'vma' written twice"), "%s", d.msg);
	cr_assert_not(tu_exists(dir, "r.json"));
	cr_assert_eq(tu_temps(dir, "r.json"), 0);

	cr_assert_eq(write_doc(p, "vma_enabled", &d), 0, "%s", d.msg);
	cr_assert(tu_exists(dir, "r.json"));
	unlink(p);
	rmdir(dir);
}

/* JSON text must be Unicode: a byte that is not UTF-8 (a Latin-1 file
 * name in the report's scene path) made the whole report unreadable to a
 * JSON parser. Such bytes become U+FFFD; well-formed UTF-8 passes as is;
 * quotes, backslashes and control characters are escaped. */
Test(config, json_strings_are_always_utf8)
{
	char dir[256], p[512];
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/u.json", dir);
	diag d = {{0}};
	jsonw w;
	cr_assert_eq(jsonw_open(&w, p, &d), 0, "%s", d.msg);
	jsonw_obj_begin(&w);
	jsonw_kstr(&w, "latin1", "sc\xe9ne");                /* lone lead byte */
	jsonw_kstr(&w, "utf8", "sc\xc3\xa9ne \xe2\x82\xac"); /* e-acute, euro */
	jsonw_kstr(&w, "bad", "\x80\xc0\xaf\xed\xa0\x80\xf4\x90\x80\x80\xe2\x82");
	jsonw_kstr(&w, "esc", "a\"b\\c\n\x01");
	jsonw_obj_end(&w);
	cr_assert_eq(jsonw_close(&w, &d), 0, "%s", d.msg);
	char *t = tu_slurp(dir, "u.json");
	cr_assert(strstr(t, "\"latin1\": \"sc\\ufffdne\""), "%s", t);
	cr_assert(strstr(t, "\"utf8\": \"sc\xc3\xa9ne \xe2\x82\xac\""), "%s", t);
	/* a stray continuation, an overlong 2-byte form, a surrogate, a code
	 * point above U+10FFFF, a cut 3-byte form: one U+FFFD per byte */
	cr_assert(strstr(t, "\"bad\": \"\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd"
	                    "\\ufffd\\ufffd\\ufffd\\ufffd\""),
	          "%s", t);
	cr_assert(strstr(t, "\"esc\": \"a\\\"b\\\\c\\n\\u0001\""), "%s", t);
	/* none of the bad bytes is left raw */
	for (const unsigned char *q = (const unsigned char *)t; *q; q++)
		cr_assert(*q != 0xe9 && *q != 0x80 && *q != 0xc0 && *q != 0xed && *q != 0xf4,
		          "raw byte 0x%02x at %td", *q, (const char *)q - t);
	unlink(p);
	rmdir(dir);
}

/* The shipped configs say what the fidelity key can be: they said
 * "fidelity: cycle # the only mode so far" long after sampled and
 * functional existed. Each config's fidelity line names all three modes
 * the loader accepts. */
Test(config, shipped_configs_name_every_fidelity_mode)
{
	const char *files[] = {"configs/saarcor-std.yaml", "configs/saarcor-vma.yaml",
	                       "configs/fpga-2004.yaml"};
	for (int i = 0; i < 3; i++) {
		FILE *f = fopen(files[i], "r");
		cr_assert(f, "cannot read %s", files[i]);
		char line[512];
		int found = 0;
		while (fgets(line, sizeof line, f))
			if (!strncmp(line, "fidelity:", 9)) {
				found = 1;
				cr_assert(strstr(line, "cycle") && strstr(line, "sampled") &&
				              strstr(line, "functional") &&
				              !strstr(line, "only mode"),
				          "%s: %s", files[i], line);
			}
		fclose(f);
		cr_assert(found, "%s has no fidelity line", files[i]);
		for (int m = 0; m < 3; m++) {
			static const char *const modes[] = {"cycle", "sampled", "functional"};
			saar_config c;
			diag d;
			char kv[64];
			cr_assert_eq(cfg_load(&c, files[i], &d), 0, "%s", d.msg);
			snprintf(kv, sizeof kv, "fidelity=%s", modes[m]);
			cr_assert_eq(cfg_set(&c, kv, &d), 0, "%s: %s", kv, d.msg);
		}
	}
}

/* The checks after loading (the memory's builder's, cross-key) name
 * where the value at fault came from, as the loader's own errors do: the
 * file's line and column of the value, or the flag that set it; a check
 * of several keys of a section names the one set last. Catches the
 * loader keeping no line for a key (the message said "config: ..." and
 * named neither the file nor the line). */
Test(config, checks_after_loading_name_the_file_or_the_flag)
{
	saar_config c;
	cfg_origin o;
	diag d = {{0}};
	char dir[64], path[128], want[1200];
	tu_tmpdir(dir, sizeof dir);
	tu_write(path, sizeof path, dir, "banks.yaml", "name: b\nmemory:\n  sdram: {banks: 3}\n");
	cr_assert_eq(cfg_load_at(&c, path, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, &o, &d), -1);
	snprintf(want, sizeof want,
	         "%s:3:18: memory.sdram.banks must be a power of two <= 64, got 3", path);
	cr_assert_str_eq(d.msg, want);
	/* a flag set after the file takes the blame for its own key */
	cr_assert_eq(cfg_set_at(&c, "--set", "memory.sdram.banks=4", &o, &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set_at(&c, "--set", "memory.sdram.row_bytes=100", &o, &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, &o, &d), -1);
	cr_assert_str_eq(d.msg, "--set: memory.sdram.row_bytes must be a power of two >= the bus "
	                        "width, got 100");
	/* the cache's ways from the file, its policy from a flag: the flag,
	 * set last, is named */
	tu_write(path, sizeof path, dir, "ways.yaml", "memory.l1.kd.ways: 3\n");
	cr_assert_eq(cfg_load_at(&c, path, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set_at(&c, "--set", "memory.l1.kd.replacement=plru", &o, &d), 0);
	cr_assert_eq(memcfg_validate(&c, &o, &d), -1);
	cr_assert(!strncmp(d.msg, "--set: memory.l1.kd: replacement plru cannot manage 3 ways", 58),
	          "%s", d.msg);
	/* a replacement name no policy has, from the file */
	tu_write(path, sizeof path, dir, "repl.yaml", "memory:\n  vma:\n    replacement: bogus\n");
	cr_assert_eq(cfg_load_at(&c, path, &o, &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, &o, &d), -1);
	snprintf(want, sizeof want, "%s:3:18: memory.vma.replacement: unknown replacement policy",
	         path);
	cr_assert(!strncmp(d.msg, want, strlen(want)), "%s", d.msg);
	/* without origins: "config" */
	cr_assert_eq(memcfg_validate(&c, NULL, &d), -1);
	cr_assert(!strncmp(d.msg, "config: memory.vma.replacement: ", 32), "%s", d.msg);
}

/* memcfg_validate of the default config with memory.levels set to v
 * (cfg_set takes it: the stack is checked after loading), d its error. */
static int levels_check(const char *v, diag *d)
{
	saar_config c;
	char kv[64];
	cfg_defaults(&c);
	snprintf(kv, sizeof kv, "memory.levels=%s", v);
	cr_assert_eq(cfg_set(&c, kv, d), 0, "%s", d->msg);
	return memcfg_validate(&c, NULL, d);
}

/* memory.levels: fixed is a model alone (one latency for every access);
 * a stack that names it beside anything is bad input, as the stacks the
 * hierarchy cannot build are, and is refused by the checks before any
 * run. Catches a stack that merely holds "fixed" taken for the fixed
 * model (fixed,garbage ran the fixed model without a word, while
 * saarsim-replay refused it). */
Test(config, fixed_level_stands_alone)
{
	const char *bad[] = {"fixed,garbage", "fixed,fixed", "fixed,l1,sdram", "l1,fixed"};
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		diag d = {{0}};
		cr_assert_eq(levels_check(bad[i], &d), -1, "%s accepted", bad[i]);
		cr_assert(!strncmp(d.msg, "config: memory.levels '", 23), "%s", d.msg);
	}
	const char *good[] = {"fixed", " fixed ", "l1,sdram", "l1,vma,sdram"};
	for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
		diag d = {{0}};
		cr_assert_eq(levels_check(good[i], &d), 0, "%s: %s", good[i], d.msg);
	}
}

/* The VMA's own keys are checked when the stack has no VMA, as the host
 * bus's are: a tag cache geometry the VMA could not build is refused when
 * it is set, not in the later run that turns the VMA on. The on-board
 * size is not held against an unused VMA (a small board without it is a
 * fine config). Catches the check running only with memory.vma.enabled
 * (plru over 3 tag-cache ways passed). */
Test(config, unused_vma_keys_are_checked)
{
	saar_config c;
	diag d = {{0}};
	cfg_defaults(&c);
	cr_assert(!c.memory.vma.enabled, "the default config has no VMA");
	cr_assert_eq(cfg_set(&c, "memory.vma.tag_cache_ways=3", &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, NULL, &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "memory.vma.tag_cache_replacement=plru", &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, NULL, &d), -1, "plru over 3 tag-cache ways accepted");
	cr_assert(
	    !strncmp(d.msg, "config: memory.vma.tag_cache: replacement plru cannot manage 3", 62),
	    "%s", d.msg);
	/* the same with the VMA on */
	cr_assert_eq(cfg_set(&c, "memory.vma.enabled=true", &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, NULL, &d), -1);
	/* the on-board cache's own policy, VMA off */
	cfg_defaults(&c);
	cr_assert_eq(cfg_set(&c, "memory.vma.ways=3", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "memory.vma.replacement=plru", &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, NULL, &d), -1, "plru over 3 VMA ways accepted");
	cr_assert(!strncmp(d.msg, "config: memory.vma: replacement plru cannot manage 3", 51), "%s",
	          d.msg);
	/* a board too small for one VMA set is fine while the VMA is off */
	cfg_defaults(&c);
	cr_assert_eq(cfg_set(&c, "memory.sdram.mb=1", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "memory.vma.line=65536", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "memory.vma.ways=32", &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, NULL, &d), 0, "%s", d.msg);
	cr_assert_eq(cfg_set(&c, "memory.vma.enabled=true", &d), 0, "%s", d.msg);
	cr_assert_eq(memcfg_validate(&c, NULL, &d), -1, "1 MB of 2 MB sets accepted with the VMA");
}
