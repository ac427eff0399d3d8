/*
 * test_saarsim_cli.c: saarsim end to end: a good run writes the frame and a
 * report whose check says identical; two runs give the same report except
 * host times; bad input (config key with file:line:col, --set, --size,
 * unknown option) gives one line on stderr, exit status 2, no output file.
 */
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

static char dir[256];

static void setup(void)
{
	tu_tmpdir(dir, sizeof dir);
}

static int saarsim(const char *args)
{
	char cmd[4096];
	snprintf(cmd, sizeof cmd, "%s/saarsim %s >%s/out 2>%s/err", tu_bin_dir(), args, dir, dir);
	return tu_run(cmd);
}

static int exists(const char *name)
{
	char p[512];
	snprintf(p, sizeof p, "%s/%s", dir, name);
	struct stat sb;
	return stat(p, &sb) == 0;
}

static char *slurp(const char *name)
{
	char p[512];
	snprintf(p, sizeof p, "%s/%s", dir, name);
	FILE *f = fopen(p, "r");
	cr_assert(f, "cannot read %s", p);
	static char bufs[2][1 << 16];
	static int which;
	char *buf = bufs[which ^= 1];
	size_t n = fread(buf, 1, sizeof bufs[0] - 1, f);
	buf[n] = 0;
	fclose(f);
	return buf;
}

static void one_line_naming(const char *what)
{
	char *buf = slurp("err");
	cr_assert(*buf, "nothing on stderr");
	char *nl = strchr(buf, '\n');
	cr_assert(nl && nl[1] == 0, "stderr is not one line: %s", buf);
	cr_assert(!strncmp(buf, "saarsim: ", 9), "stderr does not start with 'saarsim: ': %s", buf);
	cr_assert(strstr(buf, what), "stderr does not name '%s': %s", what, buf);
}

TestSuite(saarsim_cli, .init = setup);

Test(saarsim_cli, good_run_writes_frame_and_identical_reports)
{
	char args[1024];
	snprintf(args, sizeof args,
	         "--size 64x48 --set chip.rtps=2 --out %s/f.png --report %s/a.json", dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", slurp("err"));
	cr_assert(exists("f.png") && exists("a.json"));
	cr_assert_not(exists("f.png.tmp") || exists("a.json.tmp"));
	char *out = slurp("out");
	cr_assert(strstr(out, "identical"), "summary: %s", out);
	snprintf(args, sizeof args, "--size 64x48 --set chip.rtps=2 --report %s/b.json", dir);
	cr_assert_eq(saarsim(args), 0);
	char *a = slurp("a.json"), *b = slurp("b.json");
	const char *keys[] = {"\"config\"",
	                      "\"cycles_per_frame\"",
	                      "\"fps\"",
	                      "\"utilisation\"",
	                      "\"waiting_memory\"",
	                      "\"kd_node_steps\"",
	                      "\"trav_isect_ratio\"",
	                      "\"stack_overflows\"",
	                      "\"box_miss_packets\"",
	                      "\"identical_8bit\": true",
	                      "\"sim_cycles_per_s\"",
	                      "\"rtps\": 2"};
	for (size_t k = 0; k < sizeof keys / sizeof *keys; k++)
		cr_assert(strstr(a, keys[k]), "report lacks %s", keys[k]);
	/* host times come last, under "host" */
	char *ha = strstr(a, "\"host\""), *hb = strstr(b, "\"host\"");
	cr_assert(ha && hb);
	*ha = *hb = 0;
	cr_assert_str_eq(a, b, "reports differ outside \"host\"");
}

Test(saarsim_cli, bad_config_key_names_file_line_col)
{
	char p[512], args[2048];
	tu_write(p, sizeof p, dir, "cfg.yaml", "chip:\n  tarv:\n    width: 4\n");
	snprintf(args, sizeof args, "--config %s --out %s/f.png --report %s/r.json", p, dir, dir);
	cr_assert_eq(saarsim(args), 2);
	one_line_naming("cfg.yaml:2:3: unknown key 'chip.tarv'");
	cr_assert_not(exists("f.png") || exists("r.json"));
}

Test(saarsim_cli, bad_config_value_out_of_range)
{
	char p[512], args[2048];
	tu_write(p, sizeof p, dir, "cfg.yaml", "chip:\n  rtps: 0\n");
	snprintf(args, sizeof args, "--config %s --report %s/r.json", p, dir);
	cr_assert_eq(saarsim(args), 2);
	one_line_naming("cfg.yaml:2:9: chip.rtps: must be in");
	cr_assert_not(exists("r.json"));
}

Test(saarsim_cli, bad_set)
{
	char args[1024];
	snprintf(args, sizeof args, "--set chip.rtp=2 --out %s/f.png", dir);
	cr_assert_eq(saarsim(args), 2);
	one_line_naming("--set: unknown key 'chip.rtp'");
	cr_assert_not(exists("f.png"));
	snprintf(args, sizeof args, "--set chip.masked_packets=maybe --out %s/f.png", dir);
	cr_assert_eq(saarsim(args), 2);
	one_line_naming("chip.masked_packets");
	cr_assert_not(exists("f.png"));
}

Test(saarsim_cli, bad_size)
{
	char args[1024];
	const char *sizes[] = {"64", "0x10", "10x", "axb", "20000x10"};
	for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++) {
		snprintf(args, sizeof args, "--size %s --out %s/f.png --report %s/r.json", sizes[k],
		         dir, dir);
		cr_assert_eq(saarsim(args), 2, "--size %s", sizes[k]);
		one_line_naming("--size");
		cr_assert_not(exists("f.png") || exists("r.json"));
	}
}

Test(saarsim_cli, unknown_option_and_missing_scene)
{
	char args[1024];
	snprintf(args, sizeof args, "--frobnicate 3 --out %s/f.png", dir);
	cr_assert_eq(saarsim(args), 2);
	one_line_naming("--frobnicate");
	snprintf(args, sizeof args, "--scene %s/nope.obj --out %s/f.png", dir, dir);
	cr_assert_eq(saarsim(args), 2);
	one_line_naming("nope.obj");
	cr_assert_not(exists("f.png"));
}

Test(saarsim_cli, config_doc_matches_docs)
{
	char cmd[1024];
	snprintf(cmd, sizeof cmd, "%s/saarsim --config-doc | cmp -s - docs/config.md",
	         tu_bin_dir());
	cr_assert_eq(tu_run(cmd), 0, "docs/config.md is not `saarsim --config-doc`");
}
