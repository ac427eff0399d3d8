/*
 * fuzz.h: shared by the libFuzzer harnesses (make fuzz, docs/TESTING.md).
 *
 * saarsim's readers take paths (they check the file is regular, name it in
 * their one-line errors and, for scenes, pick the importer by extension),
 * so each input is written to a file of this process's own in /dev/shm
 * (memory, not disk) and read back through the real entry point. What a
 * harness checks besides the sanitizers: every refusal fills its diag with
 * one line (no newline inside), as the programs print it.
 */
#ifndef SAAR_FUZZ_H
#define SAAR_FUZZ_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "kernel-ref/diag.h"

/* The input's bytes in a file named fuzz-PID + suffix; its path. */
static inline const char *fz_file(const uint8_t *data, size_t n, const char *suffix)
{
	static char path[256];
	snprintf(path, sizeof path, "/dev/shm/saar-fuzz-%d%s", (int)getpid(), suffix);
	FILE *f = fopen(path, "wb");
	if (!f || fwrite(data, 1, n, f) != n || fclose(f) != 0)
		abort();
	return path;
}

/* A refusal is one line: a message, no newline in it. */
static inline void fz_one_line(int rc, const diag *d)
{
	if (rc == 0)
		return;
	if (!d->msg[0] || strchr(d->msg, '\n'))
		abort();
}

#endif
