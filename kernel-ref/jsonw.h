/*
 * jsonw.h: a streaming JSON writer for reports and stats files.
 *
 * Emits one well-formed document: the writer tracks nesting and commas, so
 * callers only say what comes next. Numbers that are NaN or infinite are
 * written as null (JSON has no such numbers). Output goes to a FILE; the
 * caller does the temporary-file-and-rename dance (see jsonw_open/close).
 */
#ifndef SAAR_KREF_JSONW_H
#define SAAR_KREF_JSONW_H

#include <stdint.h>
#include <stdio.h>

#include "kernel-ref/atomicfile.h"

#include "kernel-ref/diag.h"

#define JSONW_MAX_DEPTH 32
#define JSONW_MAX_KEYS  2048 /* keys of the open objects checked for repeats */

typedef struct jsonw {
	FILE *f;
	int depth;
	int first[JSONW_MAX_DEPTH]; /* no element written yet at this depth */
	int after_key;
	afile af;        /* the file (a temporary until jsonw_close); af.path "" for stdout */
	af_group *group; /* set after jsonw_open: jsonw_close commits into it */
	/* A key twice in one object is legal JSON that parsers read
	 * differently (most keep the last value): the hashes of the open
	 * objects' keys, keys[mark[d]..nkeys) those of the object at depth d,
	 * catch it, and jsonw_close fails naming it. */
	uint64_t keys[JSONW_MAX_KEYS];
	int nkeys, mark[JSONW_MAX_DEPTH];
	/* numbers written so that reading them back gives the same double
	 * (%.17g) instead of the report's 9 significant digits: for text that
	 * keys a cache, where two values must never print alike */
	int exact;
	char dup[64]; /* the first repeated key, "" while none */
} jsonw;

/* Opens a temporary beside path (atomicfile.h); jsonw_close renames it to
 * path (0) or removes it and fills d (-1): also when a key was written
 * twice into one object (a writer bug). A path of "-" writes to stdout. */
int jsonw_open(jsonw *w, const char *path, diag *d);
int jsonw_close(jsonw *w, diag *d);
/* Writes into an already open FILE (no rename). */
void jsonw_init_file(jsonw *w, FILE *f);

void jsonw_obj_begin(jsonw *w);
void jsonw_obj_end(jsonw *w);
void jsonw_arr_begin(jsonw *w);
void jsonw_arr_end(jsonw *w);
void jsonw_key(jsonw *w, const char *k);
void jsonw_str(jsonw *w, const char *s);
void jsonw_num(jsonw *w, double v);
void jsonw_int(jsonw *w, int64_t v);
void jsonw_uint(jsonw *w, uint64_t v);
void jsonw_bool(jsonw *w, int v);
void jsonw_null(jsonw *w);

/* key + value shorthands */
static inline void jsonw_kstr(jsonw *w, const char *k, const char *s)
{
	jsonw_key(w, k);
	jsonw_str(w, s);
}
static inline void jsonw_knum(jsonw *w, const char *k, double v)
{
	jsonw_key(w, k);
	jsonw_num(w, v);
}
static inline void jsonw_kuint(jsonw *w, const char *k, uint64_t v)
{
	jsonw_key(w, k);
	jsonw_uint(w, v);
}
static inline void jsonw_kint(jsonw *w, const char *k, int64_t v)
{
	jsonw_key(w, k);
	jsonw_int(w, v);
}
static inline void jsonw_kbool(jsonw *w, const char *k, int v)
{
	jsonw_key(w, k);
	jsonw_bool(w, v);
}

#endif
