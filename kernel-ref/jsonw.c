/*
 * jsonw.c: streaming JSON writer (see jsonw.h). Indents two spaces per
 * level so reports are readable and diff well.
 */
#include "kernel-ref/jsonw.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <string.h>
#include <unistd.h>

void jsonw_init_file(jsonw *w, FILE *f)
{
	memset(w, 0, sizeof *w);
	w->f = f;
	w->first[0] = 1;
}

int jsonw_open(jsonw *w, const char *path, diag *d)
{
	if (strcmp(path, "-") == 0) {
		jsonw_init_file(w, stdout);
		return 0;
	}
	afile a;
	if (af_open(&a, path, "", 1))
		return af_diag(d, path);
	jsonw_init_file(w, a.f);
	w->af = a;
	return 0;
}

int jsonw_close(jsonw *w, diag *d)
{
	int to_file = w->af.path[0] != 0; /* else stdout, which stays open */
	fputc('\n', w->f);
	if (!to_file)
		fflush(w->f);
	w->f = NULL;
	if (w->dup[0]) {
		if (to_file)
			af_abort(&w->af);
		return diag_set(d, to_file ? w->af.path : "-", 0, 0,
		                "key '%s' written twice into one object (a bug: please report it)",
		                w->dup);
	}
	if (to_file && af_commit_to(&w->af, w->group))
		return diag_set(d, w->af.path, 0, 0, "write failed: %s", strerror(errno));
	return 0;
}

static void indent(jsonw *w)
{
	fputc('\n', w->f);
	for (int i = 0; i < w->depth; i++)
		fputs("  ", w->f);
}

/* Called before any value or key: commas and line breaks. */
static void pre(jsonw *w)
{
	if (w->after_key) {
		w->after_key = 0;
		return;
	}
	if (!w->first[w->depth])
		fputc(',', w->f);
	w->first[w->depth] = 0;
	if (w->depth > 0)
		indent(w);
}

static void open_(jsonw *w, char c)
{
	pre(w);
	fputc(c, w->f);
	if (w->depth + 1 < JSONW_MAX_DEPTH)
		w->depth++;
	w->first[w->depth] = 1;
	w->mark[w->depth] = w->nkeys;
}

static void close_(jsonw *w, char c)
{
	int empty = w->first[w->depth];
	w->nkeys = w->mark[w->depth];
	if (w->depth > 0)
		w->depth--;
	if (!empty)
		indent(w);
	fputc(c, w->f);
}

void jsonw_obj_begin(jsonw *w)
{
	open_(w, '{');
}
void jsonw_obj_end(jsonw *w)
{
	close_(w, '}');
}
void jsonw_arr_begin(jsonw *w)
{
	open_(w, '[');
}
void jsonw_arr_end(jsonw *w)
{
	close_(w, ']');
}

/* The length of the well-formed UTF-8 sequence at p (1-4), or 0 (a stray
 * continuation byte, a truncated or overlong sequence, a surrogate, or a
 * code point above U+10FFFF). */
static int utf8_len(const unsigned char *p)
{
	unsigned c = p[0];
	int n = c < 0x80                ? 1
	        : c >= 0xC2 && c < 0xE0 ? 2
	        : c >= 0xE0 && c < 0xF0 ? 3
	        : c >= 0xF0 && c < 0xF5 ? 4
	                                : 0;
	for (int i = 1; i < n; i++)
		if ((p[i] & 0xC0) != 0x80)
			return 0; /* also stops at the terminating NUL */
	if ((c == 0xE0 && p[1] < 0xA0) || (c == 0xED && p[1] >= 0xA0) ||
	    (c == 0xF0 && p[1] < 0x90) || (c == 0xF4 && p[1] >= 0x90))
		return 0;
	return n;
}

/* A JSON string: quotes, backslashes and control characters escaped, and
 * bytes that are not UTF-8 (a file name in Latin-1, say) written as
 * U+FFFD: JSON text must be Unicode, and a parser refuses the whole report
 * over one such byte. */
static void put_str(FILE *f, const char *s)
{
	fputc('"', f);
	for (const unsigned char *p = (const unsigned char *)s; *p;) {
		int n = utf8_len(p);
		if (n == 0) {
			fputs("\\ufffd", f);
			p++;
			continue;
		}
		if (n > 1) {
			fwrite(p, 1, (size_t)n, f);
			p += n;
			continue;
		}
		if (*p == '"' || *p == '\\')
			fprintf(f, "\\%c", *p);
		else if (*p == '\n')
			fputs("\\n", f);
		else if (*p < 0x20)
			fprintf(f, "\\u%04x", *p);
		else
			fputc(*p, f);
		p++;
	}
	fputc('"', f);
}

void jsonw_key(jsonw *w, const char *k)
{
	uint64_t h = 1469598103934665603ull; /* FNV-1a */
	for (const unsigned char *p = (const unsigned char *)k; *p; p++)
		h = (h ^ *p) * 1099511628211ull;
	for (int i = w->mark[w->depth]; i < w->nkeys; i++)
		if (w->keys[i] == h && !w->dup[0])
			snprintf(w->dup, sizeof w->dup, "%s", k);
	if (w->nkeys < JSONW_MAX_KEYS) /* beyond: unchecked, never wrongly refused */
		w->keys[w->nkeys++] = h;
	pre(w);
	put_str(w->f, k);
	fputs(": ", w->f);
	w->after_key = 1;
}

void jsonw_str(jsonw *w, const char *s)
{
	pre(w);
	put_str(w->f, s ? s : "");
}

void jsonw_num(jsonw *w, double v)
{
	pre(w);
	if (!isfinite(v))
		fputs("null", w->f);
	else if (v == floor(v) && fabs(v) < 1e15)
		fprintf(w->f, "%.1f", v);
	else
		fprintf(w->f, w->exact ? "%.17g" : "%.9g", v);
}

void jsonw_int(jsonw *w, int64_t v)
{
	pre(w);
	fprintf(w->f, "%" PRId64, v);
}

void jsonw_uint(jsonw *w, uint64_t v)
{
	pre(w);
	fprintf(w->f, "%" PRIu64, v);
}

void jsonw_bool(jsonw *w, int v)
{
	pre(w);
	fputs(v ? "true" : "false", w->f);
}

void jsonw_null(jsonw *w)
{
	pre(w);
	fputs("null", w->f);
}
