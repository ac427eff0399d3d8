/*
 * report.h: what a run says about itself: a text summary (stdout) and a
 * JSON report (--report) and a CSV row (--csv), all from the chip's stats registry and results.
 * Every field is documented in docs/report.md. Host-time fields all live
 * under "host", so two runs of the same input give reports that are
 * identical once "host" is removed.
 */
#ifndef SAAR_SIM_REPORT_H
#define SAAR_SIM_REPORT_H

#include <stdio.h>

#include "kernel-ref/world.h"
#include "sim/chip.h"
#include "sim/figures.h"

typedef struct report_info {
	const chip *c;
	const world *w;
	const chip_check *check; /* NULL: --no-check */
	double load_ms;          /* scene load, kd-tree, memory image */
	double wall_ms;          /* whole run so far */
	af_group *group;         /* the files are renamed by af_group_commit; NULL: each at once */
	double mem_estimate_mb;  /* hostmem.h's estimate before the run (0: none made) */
	const struct rc_list *invariants; /* the violated ones (reportcheck.h); NULL: not checked */
} report_info;

void report_text(FILE *f, const report_info *ri);
/* Writes the JSON report atomically (tmp + rename). */
int report_json(const char *path, const report_info *ri, diag *d);
/* Appends one CSV row (for sweeps) to path, with the header line first when
 * the file is new or empty. Atomic: the old contents and the row go to a
 * temporary beside path (atomicfile.h), renamed over it. */
int report_csv(const char *path, const report_info *ri, diag *d);
/* Serialises appends to CSVs in path's folder among saarsim processes:
 * hold it from before report_csv reads the old rows until the new file is
 * renamed into place (concurrent runs of a sweep into one CSV lost rows:
 * each renamed its copy over the others'). An exclusive flock on the
 * folder (the CSV itself is replaced by the rename, so it cannot carry
 * the lock). Returns the descriptor to pass to report_csv_unlock, or -1
 * when the folder cannot be opened (the append goes on unlocked). */
int report_csv_lock(const char *path);
void report_csv_unlock(int fd);
/* Before a run: fails when path exists, is not empty and does not start
 * with our header line (a CSV of other columns), as report_csv would. */
int report_csv_check(const char *path, diag *d);
/* Writes the census (chip_census_on) as CSV, atomically: one row per chunk
 * of fid.unit_tiles tiles in hand-out order (the last of a frame runs to
 * its end), with its core cycles (empty in functional mode, which has no
 * time) and the core cycles each resource's work needs (docs/report.md). */
int report_census(const char *path, const report_info *ri, diag *d);

#endif
