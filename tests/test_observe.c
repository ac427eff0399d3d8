/*
 * test_observe.c: seeing inside a run (docs/observe.md). The timeline
 * (--timeline) is valid trace-event JSON whose spans agree with the same
 * run's report (scripts/timeline-check.py: per RTP and unit the ops and
 * issue cycles, per RTP the thread-state time, the L1 fills, the SDRAM
 * segments and busy time, the host-bus transfers); a window holds exactly
 * the full timeline's part; the cap is kept and said; the checker itself
 * catches a dropped op, an overlap and a wrong total; the observers change
 * nothing in the report; bad flags give one line and no file. The heat
 * maps (--heatmap) add up to the report's totals (scripts/heatmap-check.py:
 * kd steps, triangle tests, L1 misses, busy and memory-waiting thread
 * cycles), each EXR to its heatmap.json total; a folder the run made is
 * gone when the run fails.
 */
#include <sys/stat.h>

#include "sim/observe.h"
#include "tests/testutil.h"

static char dir[256];

static void setup(void)
{
	tu_tmpdir(dir, sizeof dir);
}

TestSuite(observe, .init = setup);

static const char *root(void)
{
	const char *r = getenv("SAAR_ROOT");
	return r && *r ? r : ".";
}

static int saarsim(const char *args)
{
	return tu_prog(dir, "saarsim", args);
}

/* scripts/timeline-check.py on dir's files (args: "t.json r.json" ...);
 * its output in dir/check. */
static int check(const char *args)
{
	char cmd[2048], a[1024];
	/* every file name in args is in dir */
	a[0] = 0;
	for (const char *p = args; *p;) {
		size_t n = strcspn(p, " ");
		if (!strncmp(p, "--", 2))
			snprintf(a + strlen(a), sizeof a - strlen(a), "%.*s ", (int)n, p);
		else
			snprintf(a + strlen(a), sizeof a - strlen(a), "%s/%.*s ", dir, (int)n, p);
		p += n;
		p += strspn(p, " ");
	}
	snprintf(cmd, sizeof cmd, "python3 %s/scripts/timeline-check.py %s >%s/check 2>&1", root(),
	         a, dir);
	return tu_run(cmd);
}

#define RUN2 "--size 64x48 --set chip.rtps=2 --no-check"

Test(observe, timeline_agrees_with_the_report)
{
	char args[1024];
	snprintf(args, sizeof args, RUN2 " --report %s/r.json --timeline %s/t.json", dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(tu_temps(dir, "t.json"), 0);
	cr_assert_eq(check("t.json r.json"), 0, "%s", tu_slurp(dir, "check"));
	/* a run that loads is more than parseable: it has ops of every kind
	 * and the memory tracks */
	char *t = tu_slurp(dir, "t.json");
	for (const char *s = "\"name\":\"trav\"\0\"name\":\"isect\"\0\"name\":\"list\"\0"
	                     "\"name\":\"rgs\"\0\"name\":\"waiting_memory\"\0\"name\":\"kd miss\"\0"
	                     "\"name\":\"read\"\0";
	     *s; s += strlen(s) + 1)
		cr_assert(strstr(t, s), "no %s in the timeline", s);
}

/* Several instances of a unit (each op on the instance it issued on:
 * no overlap on a track) and the VMA's host bus. */
Test(observe, timeline_instances_and_host_bus)
{
	char args[1024];
	snprintf(
	    args, sizeof args,
	    "--config %s/configs/saarcor-vma.yaml --size 64x48 --no-check --set "
	    "chip.trav.count=3 --set chip.isect.count=2 --report %s/r.json --timeline %s/t.json",
	    root(), dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(check("t.json r.json"), 0, "%s", tu_slurp(dir, "check"));
	char *t = tu_slurp(dir, "t.json");
	cr_assert(strstr(t, "\"name\":\"dma\""), "no host-bus transfer");
	cr_assert(strstr(t, "\"kind\":\"trav\",\"instance\":2"), "trav instance 2 never used");
}

/* The "done when": a Conference run's timeline is valid trace
 * events agreeing with its report, and its heat maps' totals are the
 * report's. (heat_check is defined with the heat-map tests below.) */
static int heat_check(const char *report);

Test(observe, conference_timeline_and_heatmap, .timeout = 120)
{
	char views[512], args[2048];
	SCENE_OR_SKIP(views, "views.yaml");
	snprintf(args, sizeof args,
	         "--views %s --view conference --size 64x48 --no-check --report %s/r.json "
	         "--timeline %s/t.json --heatmap %s/hm",
	         views, dir, dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(check("t.json r.json"), 0, "%s", tu_slurp(dir, "check"));
	cr_assert_eq(heat_check("r.json"), 0, "%s", tu_slurp(dir, "check"));
}

Test(observe, window_is_the_full_timelines_part)
{
	char args[1024];
	snprintf(args, sizeof args, RUN2 " --timeline %s/t.json", dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	snprintf(args, sizeof args, RUN2 " --timeline-window 20000:50000 --timeline %s/w.json",
	         dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(check("w.json --full t.json"), 0, "%s", tu_slurp(dir, "check"));
	/* open ends */
	snprintf(args, sizeof args,
	         RUN2 " --timeline-window 150000: --timeline %s/w.json --report %s/r.json", dir,
	         dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(check("w.json --full t.json"), 0, "%s", tu_slurp(dir, "check"));
	/* a window against the run's own report is refused, and for that
	 * reason (a crash on the wrong file would also exit non-zero) */
	cr_assert_neq(check("w.json r.json"), 0);
	cr_assert(strstr(tu_slurp(dir, "check"), "whole run"), "%s", tu_slurp(dir, "check"));
}

Test(observe, cap_is_kept_and_said)
{
	char args[1024];
	snprintf(args, sizeof args, RUN2 " --timeline-max-events 100 --timeline %s/t.json", dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(check("t.json"), 0, "%s", tu_slurp(dir, "check"));
	cr_assert(strstr(tu_slurp(dir, "check"), "ok: 100 spans"), "%s", tu_slurp(dir, "check"));
	char *t = tu_slurp(dir, "t.json");
	cr_assert(strstr(t, "\"max_events\":100,") && strstr(t, "\"capped\":true"), "%s",
	          strstr(t, "otherData"));
	char *e = tu_slurp(dir, "err");
	cr_assert(strstr(e, "saarsim: --timeline: capped at 100 events"), "%s", e);
}

/* The observers only look: the report is the same with and without
 * them, host times aside. */
Test(observe, report_unchanged_by_the_timeline)
{
	char args[1024];
	snprintf(args, sizeof args, RUN2 " --report %s/a.json", dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	snprintf(args, sizeof args, RUN2 " --report %s/b.json --timeline %s/t.json", dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	char cmd[2048];
	snprintf(cmd, sizeof cmd,
	         "python3 -c \"import json,sys; a,b=(json.load(open(p)) for p in sys.argv[1:]); "
	         "[x.pop(k,None) for x in (a,b) for k in ('host','program')]; "
	         "sys.exit(a!=b)\" %s/a.json %s/b.json",
	         dir, dir);
	cr_assert_eq(tu_run(cmd), 0, "the report changed with --timeline");
}

/* The checker catches the mistakes it is there for. Each edit of a good
 * timeline (python, on the parsed JSON) must fail the check naming it. */
static void planted(const char *edit, const char *named)
{
	char cmd[4096];
	snprintf(cmd, sizeof cmd,
	         "python3 -c \"import json; d=json.load(open('%s/t.json')); "
	         "x=[e for e in d['traceEvents'] if e['ph']=='X']; %s; "
	         "json.dump(d, open('%s/m.json','w'))\"",
	         dir, edit, dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", cmd);
	cr_assert_eq(check("m.json r.json"), 1, "not caught: %s", edit);
	cr_assert(strstr(tu_slurp(dir, "check"), named), "%s: %s", edit, tu_slurp(dir, "check"));
}

Test(observe, checker_catches_planted_mistakes)
{
	char args[1024];
	snprintf(args, sizeof args, RUN2 " --report %s/r.json --timeline %s/t.json", dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	/* a dropped unit op (the count in otherData kept right) */
	planted("o=[e for e in x if e['name']=='trav'][5]; d['traceEvents'].remove(o); "
	        "d['otherData']['events']-=1",
	        "trav.ops");
	/* an op with one issue cycle too many */
	planted("o=[e for e in x if e['name']=='isect'][3]; o['args']['issue_cycles']+=1", "isect");
	/* two ops of one unit overlapping */
	planted("o=[e for e in x if e['name']=='trav' and e['pid']==0 and e['tid']==1001]; "
	        "o[1]['ts']=o[0]['ts']",
	        "overlaps");
	/* a thread-state span lost (the longest: the sums allow the 3
	 * decimals' rounding, half a thousandth of a cycle per span) */
	planted("o=max((e for e in x if e['name']=='waiting_memory'), key=lambda e: e['dur']); "
	        "d['traceEvents'].remove(o); "
	        "d['otherData']['events']-=1",
	        "waiting_memory_ps");
	/* an L1 miss lost */
	planted("o=[e for e in x if e['name']=='kd miss'][0]; d['traceEvents'].remove(o); "
	        "d['otherData']['events']-=1",
	        "l1.kd");
	/* the event count disagreeing with the events */
	planted("d['otherData']['events']+=1", "otherData.events");
	/* an event outside the window */
	planted("d['otherData']['window']=[10, 1000]", "outside the window");
}

Test(observe, bad_flags_one_line_no_file)
{
	struct {
		const char *args, *named;
	} bad[] = {
	    {"--fidelity functional --timeline %s/t.json", "--timeline"},
	    {"--fidelity sampled --timeline %s/t.json", "--timeline"},
	    {"--timeline %s/t.json --timeline-window 5:3", "--timeline-window"},
	    {"--timeline %s/t.json --timeline-window 5", "--timeline-window"},
	    {"--timeline %s/t.json --timeline-window a:9", "--timeline-window"},
	    {"--timeline %s/t.json --timeline-window -1:9", "--timeline-window"},
	    {"--timeline %s/t.json --timeline-max-events 0", "--timeline-max-events"},
	    {"--timeline-window 0:9 --csv %s/t.json", "--timeline-window"},
	    {"--timeline %s/no/such/dir/t.json", "--timeline: "},
	};
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		char a[512], args[1024];
		snprintf(a, sizeof a, bad[i].args, dir);
		snprintf(args, sizeof args, "--size 16x16 --report %s/r.json %s", dir, a);
		cr_assert_eq(saarsim(args), 2, "%s", args);
		tu_one_line(dir, "saarsim", bad[i].named);
		cr_assert(!tu_exists(dir, "t.json") && !tu_exists(dir, "r.json"), "%s left a file",
		          args);
		cr_assert_eq(tu_temps(dir, "t.json") + tu_temps(dir, "r.json"), 0, "%s", args);
	}
}

/* ---- heat maps ---- */

/* scripts/heatmap-check.py on dir/hm (and a report): each map's EXR adds
 * up to heatmap.json's total, and the totals are the report's. */
static int heat_check(const char *report)
{
	char cmd[2048];
	snprintf(cmd, sizeof cmd, "python3 %s/scripts/heatmap-check.py %s/hm %s%s%s >%s/check 2>&1",
	         root(), dir, report ? dir : "", report ? "/" : "", report ? report : "", dir);
	return tu_run(cmd);
}

Test(observe, heatmap_totals_equal_the_report)
{
	char args[1024];
	/* 100x60: partial tiles at the right and bottom edges */
	snprintf(args, sizeof args,
	         "--size 100x60 --set chip.rtps=2 --report %s/r.json --heatmap %s/hm", dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(heat_check("r.json"), 0, "%s", tu_slurp(dir, "check"));
	char *j = tu_slurp(dir, "hm/heatmap.json");
	cr_assert(strstr(j, "\"tiles_x\":13,\"tiles_y\":8,") &&
	              strstr(j, "\"l1_misses_unattributed\":0,"),
	          "%s", j);
	char d2[300];
	snprintf(d2, sizeof d2, "%s/hm", dir);
	for (int i = 0; obs_heat_files[i]; i++)
		cr_assert(tu_exists(d2, obs_heat_files[i]) && !tu_temps(d2, obs_heat_files[i]),
		          "%s", obs_heat_files[i]);
}

/* With the VMA, two frames (the maps add both up, as the report does),
 * a timeline beside them (one set of observers serves both). */
Test(observe, heatmap_vma_two_frames_with_timeline)
{
	char args[1024];
	snprintf(args, sizeof args,
	         "--config %s/configs/saarcor-vma.yaml --size 64x48 --frames 2 --no-check --report "
	         "%s/r.json --heatmap %s/hm --timeline %s/t.json",
	         root(), dir, dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	cr_assert_eq(heat_check("r.json"), 0, "%s", tu_slurp(dir, "check"));
	cr_assert_eq(check("t.json r.json"), 0, "%s", tu_slurp(dir, "check"));
}

/* The checker catches a map that lost a tile's worth, and a total that
 * disagrees with the report. */
Test(observe, heatmap_checker_catches_planted_mistakes)
{
	char args[1024], cmd[2048];
	snprintf(args, sizeof args, RUN2 " --report %s/r.json --heatmap %s/hm", dir, dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	/* an EXR whose values no longer add up (a thousandth less) */
	snprintf(cmd, sizeof cmd,
	         "cd %s/hm && oiiotool kd_steps.exr --mulc 0.999 -d float -o k.exr && mv "
	         "k.exr kd_steps.exr",
	         dir);
	cr_assert_eq(tu_run(cmd), 0);
	cr_assert_eq(heat_check(NULL), 1, "not caught: a changed EXR");
	cr_assert(strstr(tu_slurp(dir, "check"), "kd_steps.exr: values add up"), "%s",
	          tu_slurp(dir, "check"));
	/* a total off by one against the report */
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	snprintf(cmd, sizeof cmd,
	         "python3 -c \"import json; p='%s/r.json'; r=json.load(open(p)); "
	         "r['traversal']['triangle_tests']+=1; json.dump(r, open(p,'w'))\"",
	         dir);
	cr_assert_eq(tu_run(cmd), 0);
	cr_assert_eq(heat_check("r.json"), 1, "not caught: a total off by one");
	cr_assert(strstr(tu_slurp(dir, "check"), "tri_tests"), "%s", tu_slurp(dir, "check"));
}

Test(observe, heatmap_bad_input_one_line_no_folder_left)
{
	char args[1024];
	/* not a cycle run */
	snprintf(args, sizeof args, "--size 16x16 --fidelity functional --heatmap %s/hm", dir);
	cr_assert_eq(saarsim(args), 2);
	tu_one_line(dir, "saarsim", "--heatmap");
	cr_assert(!tu_exists(dir, "hm"));
	/* a file where the folder should be */
	snprintf(args, sizeof args, "--size 16x16 --heatmap %s/out", dir);
	cr_assert_eq(saarsim(args), 2);
	tu_one_line(dir, "saarsim", "--heatmap");
	/* a parent that does not exist */
	snprintf(args, sizeof args, "--size 16x16 --heatmap %s/no/such/hm", dir);
	cr_assert_eq(saarsim(args), 2);
	tu_one_line(dir, "saarsim", "--heatmap");
	/* a run that fails after the folder was made: nothing left, the
	 * folder neither */
	snprintf(args, sizeof args, "--size 16x16 --scene %s/none.obj --heatmap %s/hm", dir, dir);
	cr_assert_eq(saarsim(args), 2);
	cr_assert(!tu_exists(dir, "hm"), "the folder it made is left");
	/* a folder that was there stays, with nothing added */
	char made[300];
	snprintf(made, sizeof made, "%s/keep", dir);
	cr_assert_eq(mkdir(made, 0777), 0);
	snprintf(args, sizeof args, "--size 16x16 --scene %s/none.obj --heatmap %s/keep", dir, dir);
	cr_assert_eq(saarsim(args), 2);
	cr_assert(tu_exists(dir, "keep"));
	char any[600];
	cr_assert_eq(tu_find_files(made, "", any, sizeof any), 2, "files left in the folder");
}

/* ---- progress ---- */

/* Runs cmd (a shell command) on a pseudo-terminal (python3's pty: the
 * program's stdout and stderr are the terminal) with env before it;
 * what the terminal showed goes to dir/tty. Returns the exit status. */
static int on_tty(const char *env, const char *cmd)
{
	static const char py[] = "import os, pty, sys\n"
	                         "pid, fd = pty.fork()\n"
	                         "if pid == 0:\n"
	                         "    os.execv('/bin/sh', ['sh', '-c', sys.argv[1]])\n"
	                         "out = b''\n"
	                         "while True:\n"
	                         "    try:\n"
	                         "        b = os.read(fd, 65536)\n"
	                         "    except OSError:\n"
	                         "        break\n"
	                         "    if not b:\n"
	                         "        break\n"
	                         "    out += b\n"
	                         "_, st = os.waitpid(pid, 0)\n"
	                         "open(sys.argv[2], 'wb').write(out)\n"
	                         "sys.exit(os.WEXITSTATUS(st))\n";
	char path[512], full[4096];
	tu_write(path, sizeof path, dir, "ontty.py",
	         py); /* not pty.py: it would shadow the module */
	snprintf(full, sizeof full, "%s python3 %s '%s' %s/tty", env, path, cmd, dir);
	return tu_run(full);
}

#define PROG_RUN "--size 256x256 --no-check"

Test(observe, progress_line_on_a_terminal_only)
{
	char cmd[2048];
	/* on a terminal: the line, with its fields, rewritten in place and
	 * cleared before the summary */
	snprintf(cmd, sizeof cmd, "%s/saarsim " PROG_RUN, tu_bin_dir());
	cr_assert_eq(on_tty("SAARSIM_PROGRESS_AFTER_MS=0", cmd), 0);
	char *t = tu_slurp(dir, "tty");
	cr_assert(strstr(t, "\r\033[Ksaarsim: frame 1/1, 64/1024 tiles, "), "%s", t);
	cr_assert(strstr(t, " cycles/s, ") && strstr(t, " s left"), "%s", t);
	cr_assert(strstr(t, "left\r\033[Ksaarsim: embedded:cornell"), "not cleared: %s", t);
	/* --quiet: none */
	snprintf(cmd, sizeof cmd, "%s/saarsim " PROG_RUN " --quiet", tu_bin_dir());
	cr_assert_eq(on_tty("SAARSIM_PROGRESS_AFTER_MS=0", cmd), 0);
	cr_assert(!strstr(tu_slurp(dir, "tty"), "tiles"), "%s", tu_slurp(dir, "tty"));
	/* a run shorter than the default 2 s: none */
	snprintf(cmd, sizeof cmd, "%s/saarsim --size 64x64 --no-check", tu_bin_dir());
	cr_assert_eq(on_tty("", cmd), 0);
	cr_assert(!strstr(tu_slurp(dir, "tty"), "tiles"), "%s", tu_slurp(dir, "tty"));
	/* stderr a file, or a pipe (stdout still the terminal): none */
	snprintf(cmd, sizeof cmd, "%s/saarsim " PROG_RUN " 2>%s/e1", tu_bin_dir(), dir);
	cr_assert_eq(on_tty("SAARSIM_PROGRESS_AFTER_MS=0", cmd), 0);
	cr_assert(!strstr(tu_slurp(dir, "e1"), "tiles"), "%s", tu_slurp(dir, "e1"));
	cr_assert(!strstr(tu_slurp(dir, "tty"), "tiles"));
	snprintf(cmd, sizeof cmd, "%s/saarsim " PROG_RUN " 2>&1 | cat >%s/e2", tu_bin_dir(), dir);
	cr_assert_eq(on_tty("SAARSIM_PROGRESS_AFTER_MS=0", cmd), 0);
	char *e2 = tu_slurp(dir, "e2");
	cr_assert(strstr(e2, "saarsim: embedded:cornell") && !strstr(e2, "tiles"), "%s", e2);
}

Test(observe, sweep_progress_on_a_terminal_only, .timeout = 120)
{
	char cmd[2048];
	snprintf(cmd, sizeof cmd,
	         "SAARSIM=%s/saarsim sh %s/scripts/sweep --out %s/sw --scene spd:tetra:2 --size "
	         "32x32 --set chip.threads_per_rtp=2,16 -j 2",
	         tu_bin_dir(), root(), dir);
	cr_assert_eq(on_tty("", cmd), 0, "%s", tu_slurp(dir, "tty"));
	char *t = tu_slurp(dir, "tty");
	cr_assert(strstr(t, "\r\033[Ksweep: 0 of 2 points done") ||
	              strstr(t, "\r\033[Ksweep: 1 of 2 points done"),
	          "%s", t);
	/* stderr a file: none; --quiet: none */
	char cmd2[4800];
	snprintf(cmd2, sizeof cmd2, "%s --out %s/sw2 2>%s/e1", cmd, dir, dir);
	cr_assert_eq(on_tty("", cmd2), 0);
	cr_assert(!strstr(tu_slurp(dir, "e1"), "points done"), "%s", tu_slurp(dir, "e1"));
	snprintf(cmd2, sizeof cmd2, "%s --out %s/sw3 --quiet", cmd, dir);
	cr_assert_eq(on_tty("", cmd2), 0);
	cr_assert(!strstr(tu_slurp(dir, "tty"), "points done"), "%s", tu_slurp(dir, "tty"));
}

/* ---- the timeline's picture ---- */

Test(observe, timeline_plot_writes_a_png, .timeout = 120)
{
	char args[1024], cmd[2048];
	snprintf(args, sizeof args, RUN2 " --timeline-window 20000:22000 --timeline %s/t.json",
	         dir);
	cr_assert_eq(saarsim(args), 0, "%s", tu_slurp(dir, "err"));
	snprintf(cmd, sizeof cmd,
	         "python3 %s/scripts/timeline-plot %s/t.json %s/t.png --threads 4 2>%s/perr",
	         root(), dir, dir, dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", tu_slurp(dir, "perr"));
	char *png = tu_slurp(dir, "t.png");
	cr_assert(!memcmp(png, "\x89PNG\r\n", 6), "not a PNG");
	cr_assert_eq(tu_temps(dir, "t.png"), 0);
	/* one data row per span drawn: the panels hold the window's ops */
	char *gp = tu_slurp(dir, "t.plot/plot.gp");
	cr_assert(strstr(gp, "'trav 0' 1") && strstr(gp, "'thread 3'") && !strstr(gp, "'thread 4'"),
	          "%s", gp);
	/* bad input: one line, exit 2, no picture */
	snprintf(cmd, sizeof cmd,
	         "python3 %s/scripts/timeline-plot %s/t.json %s/u.png --window 9:3 2>%s/perr",
	         root(), dir, dir, dir);
	cr_assert_eq(tu_run(cmd), 2);
	cr_assert(strstr(tu_slurp(dir, "perr"), "timeline-plot: --window"), "%s",
	          tu_slurp(dir, "perr"));
	snprintf(cmd, sizeof cmd, "python3 %s/scripts/timeline-plot %s/out %s/u.png 2>%s/perr",
	         root(), dir, dir, dir);
	cr_assert_eq(tu_run(cmd), 2);
	cr_assert(!tu_exists(dir, "u.png"));
}
