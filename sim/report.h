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

#include "chip.h"
#include "world.h"

typedef struct report_info {
	const chip *c;
	const world *w;
	const chip_check *check; /* NULL: --no-check */
	double load_ms;          /* scene load, kd-tree, memory image */
	double wall_ms;          /* whole run so far */
} report_info;

void report_text(FILE *f, const report_info *ri);
/* Writes the JSON report atomically (tmp + rename). */
int report_json(const char *path, const report_info *ri, diag *d);
/* Appends one CSV row (for sweeps) to path, with the header line first when
 * the file is new or empty. Atomic: the old contents and the row go to
 * path.tmp, which is renamed over path. */
int report_csv(const char *path, const report_info *ri, diag *d);

#endif
