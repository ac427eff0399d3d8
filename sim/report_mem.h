/*
 * report_mem.h: the memory hierarchy's part of the report (moved out of
 * mem/, which writes no report code): hier_stats as JSON.
 */
#ifndef SAAR_SIM_REPORT_MEM_H
#define SAAR_SIM_REPORT_MEM_H

#include "kernel-ref/jsonw.h"
#include "mem/hier.h"

/* Writes the stats as one JSON object (a value: the caller writes the key). */
void hier_write_json(const hier_stats *s, jsonw *w);

#endif
