/*
 * diag.h: how kernel-ref and the simulator report bad input.
 *
 * Library code never prints and never exits: a function that can fail on
 * user input fills a diag with one line ("FILE:LINE:COL: message", or
 * "FILE: message" where the format has no lines) and returns non-zero.
 * Only the command-line front ends print it and exit with DIAG_EXIT (2).
 */
#ifndef SAAR_KREF_DIAG_H
#define SAAR_KREF_DIAG_H

#include <stddef.h>

#define DIAG_EXIT 2

typedef struct diag {
	char msg[1024];
} diag;

/* Formats "file: message" (line <= 0) or "file:line:col: message" (col <= 0
 * prints "file:line: message"); control characters the arguments bring
 * (a library's message quoting a file's bytes) become '?', so it stays one
 * line. Always returns -1 so callers can write
 * `return diag_set(...)`. d may be NULL. */
int diag_set(diag *d, const char *file, int line, int col, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

/* Silences file descriptor 2 until diag_quiet_end: around a library that
 * prints a damaged file's error on stderr itself besides returning it
 * (Assimp's importers, libpng's default handler), which would make a
 * second line beside the diag. Returns what diag_quiet_end takes (-1: not
 * silenced). Not for while other threads print. */
int diag_quiet_begin(void);
void diag_quiet_end(int saved);

/* For a process whose fd 2 is captured by its parent (the importer
 * process, importproc.c): from now on diag_quiet_begin leaves fd 2 alone,
 * so a library's lines land in the capture (the parent drops them) and a
 * sanitizer's report there is not lost. */
void diag_quiet_off(void);

#endif
