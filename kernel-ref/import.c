/*
 * import.c: scene_import_inproc(), scene files through Assimp's C API, in
 * the calling process. scene_load runs it in a child process under limits
 * (importproc.c); fuzzers and tests may call it directly.
 *
 * Owns: the formats accepted and their content checks (import_format,
 * content_check), the zlib-backed aiFileIO (so "x.obj.gz" loads as "x.obj"
 * while the .mtl beside it is still read from disk), the OBJ and PLY
 * pre-scans that give bad numbers, indices and headers a line number, the
 * mapping of Assimp materials and textures onto scene.h, and the guard that
 * turns Assimp crashing on a malformed file into an error. The rules are
 * documented in docs/views.md ("Scene files").
 */
#include "kernel-ref/import.h"
#include "kernel-ref/image.h"
#include "kernel-ref/infile.h"
#include "kernel-ref/scene.h"

#include <assimp/ObjMaterial.h>
#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <setjmp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>
#include <zlib.h>

#define PATH_MAX_LEN 1024

/* Files held in memory: the scene file (its content is checked before
 * Assimp sees it), MTL files (checked as text) and gzipped files. Assimp
 * opens the main file twice (an existence probe, then the read), so it is
 * read and inflated once and served from memory. Entries live until the
 * import returns: a stream may still be reading one (the OBJ) while
 * another (a gzipped MTL) is opened. */
#define CACHE_MAX 16
typedef struct memcache {
	struct {
		char path[PATH_MAX_LEN]; /* real path on disk */
		char *buf;
		size_t len;
	} e[CACHE_MAX];
	int n;
	char err[512];    /* first I/O error, reported instead of Assimp's */
	int bad;          /* err is a content check's: the import fails */
	scene_file_fn fn; /* told of every file opened (scene_load_files) */
	void *fn_ctx;
} memcache;

/* An open aiFile: either a stdio stream or a view of the cache. */
typedef struct ofile {
	FILE *fp;
	const char *buf;
	size_t len, pos;
} ofile;

static int ends_with(const char *s, const char *suffix)
{
	size_t n = strlen(s), k = strlen(suffix);
	return n >= k && strcasecmp(s + n - k, suffix) == 0;
}

/* Maps a name Assimp asks for to the file on disk: "X.gz" is inflated, and
 * so is "X" when only "X.gz" exists (that is how "conference.obj" reaches
 * "conference.obj.gz"). Returns 1 for gzip, 0 for a plain file. */
static int real_path(const char *name, char *out, size_t n)
{
	snprintf(out, n, "%s", name);
	if (ends_with(name, ".gz"))
		return 1;
	if (access(name, F_OK) != 0) {
		snprintf(out, n, "%s.gz", name);
		if (access(out, F_OK) == 0)
			return 1;
		snprintf(out, n, "%s", name);
	}
	return 0;
}

static size_t of_read(struct aiFile *af, char *dst, size_t size, size_t count)
{
	ofile *o = (ofile *)af->UserData;
	if (o->fp)
		return fread(dst, size, count, o->fp);
	if (size == 0)
		return 0;
	size_t items = (o->len - o->pos) / size;
	if (items > count)
		items = count;
	memcpy(dst, o->buf + o->pos, items * size);
	o->pos += items * size;
	return items;
}

static size_t of_write(struct aiFile *af, const char *src, size_t size, size_t count)
{
	return 0; /* import only */
}

static size_t of_tell(struct aiFile *af)
{
	ofile *o = (ofile *)af->UserData;
	return o->fp ? (size_t)ftell(o->fp) : o->pos;
}

static size_t of_size(struct aiFile *af)
{
	ofile *o = (ofile *)af->UserData;
	if (!o->fp)
		return o->len;
	long here = ftell(o->fp);
	fseek(o->fp, 0, SEEK_END);
	long end = ftell(o->fp);
	fseek(o->fp, here, SEEK_SET);
	return end < 0 ? 0 : (size_t)end;
}

static enum aiReturn of_seek(struct aiFile *af, size_t off, enum aiOrigin origin)
{
	ofile *o = (ofile *)af->UserData;
	if (o->fp) {
		int wh = origin == aiOrigin_SET   ? SEEK_SET
		         : origin == aiOrigin_CUR ? SEEK_CUR
		                                  : SEEK_END;
		return fseek(o->fp, (long)off, wh) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
	}
	size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? o->pos : o->len;
	if (off > o->len - base)
		return aiReturn_FAILURE;
	o->pos = base + off;
	return aiReturn_SUCCESS;
}

static void of_flush(struct aiFile *af) {}

/* Set when the import failed for want of memory (Assimp's std::bad_alloc,
 * an allocation of ours): the importer process reports its memory limit
 * then. One import at a time, like the crash guard below. */
static int import_oom;

static int oom_text(const char *m)
{
	return strstr(m, "bad_alloc") || strstr(m, "out of memory");
}

/* Text formats hold no control bytes but tab, LF and CR: the first other
 * byte below 0x20 (or 0x7f) is an error naming its line (counted from
 * first_line) and column. `what` names the kind of file ("an OBJ"). */
static int text_check(const char *buf, size_t len, long first_line, const char *file,
                      const char *what, diag *d)
{
	long line = first_line;
	size_t ls = 0;
	for (size_t i = 0; i < len; i++) {
		unsigned char c = (unsigned char)buf[i];
		if (c >= 0x20 && c != 0x7f)
			continue;
		if (c == '\n') {
			line++;
			ls = i + 1;
		} else if (c != '\t' && c != '\r') {
			size_t col = i - ls + 1;
			return diag_set(d, file, line > INT_MAX ? INT_MAX : (int)line,
			                col > INT_MAX ? INT_MAX : (int)col,
			                "not %s text file (control byte 0x%02x)", what, c);
		}
	}
	return 0;
}

/* The import looked for rp and found neither it nor rp.gz (real_path):
 * both are passed to the cache's watch as absent (scene_file_fn), so the
 * built scene is not reused once one appears. */
static void report_absent(memcache *c, const char *rp)
{
	if (!c->fn)
		return;
	char a[PATH_MAX_LEN + 4];
	snprintf(a, sizeof a, "%c%s", SCENE_FILE_ABSENT, rp);
	c->fn(c->fn_ctx, a);
	if (!ends_with(rp, ".gz")) {
		snprintf(a, sizeof a, "%c%s.gz", SCENE_FILE_ABSENT, rp);
		c->fn(c->fn_ctx, a);
	}
}

static struct aiFile *io_open(struct aiFileIO *io, const char *name, const char *mode)
{
	memcache *c = (memcache *)io->UserData;
	if (strchr(mode, 'w') || strchr(mode, 'a'))
		return NULL;
	char rp[PATH_MAX_LEN];
	int gz = real_path(name, rp, sizeof rp);
	/* an MTL is text too: read whole and checked like the OBJ */
	int mtl = ends_with(rp, ".mtl") || ends_with(rp, ".mtl.gz");
	FILE *fp = NULL;
	int k = 0;
	while (k < c->n && strcmp(rp, c->e[k].path) != 0)
		k++;
	if (k == c->n) {
		if (!gz && !mtl) {
			int st = in_open(rp, &fp);
			if (st) {
				/* Assimp says only "cannot open" (or, for a
				 * directory, "vector::reserve"): keep the reason */
				if (!c->err[0] && st != ENOENT)
					snprintf(c->err, sizeof c->err, "%.250s: %.250s", rp,
					         in_strerror(st));
				if (st == ENOENT)
					report_absent(c, rp);
				return NULL;
			}
		} else {
			char err[256];
			if (c->n == CACHE_MAX) {
				if (!c->err[0]) {
					snprintf(c->err, sizeof c->err,
					         "the scene refers to more than %d files",
					         CACHE_MAX);
					c->bad = 1;
				}
				return NULL;
			}
			int st = in_read_all(rp, gz, &c->e[k].buf, &c->e[k].len, err, sizeof err);
			if (st) {
				if (!c->err[0] && st != ENOENT)
					snprintf(c->err, sizeof c->err, "%.250s: %.250s", rp, err);
				if (st == ENOENT)
					report_absent(c, rp);
				import_oom |= oom_text(err);
				return NULL;
			}
			diag td;
			if (mtl && text_check(c->e[k].buf, c->e[k].len, 1, rp, "an MTL", &td)) {
				free(c->e[k].buf);
				if (!c->err[0]) {
					snprintf(c->err, sizeof c->err, "%.500s", td.msg);
					c->bad = 1;
				}
				return NULL;
			}
			snprintf(c->e[k].path, sizeof c->e[k].path, "%s", rp);
			c->n++;
		}
	}
	if (c->fn)
		c->fn(c->fn_ctx, rp);
	struct aiFile *af = calloc(1, sizeof *af);
	ofile *o = calloc(1, sizeof *o);
	if (!af || !o) {
		free(af);
		free(o);
		if (fp)
			fclose(fp);
		return NULL;
	}
	o->fp = fp;
	if (!fp) {
		o->buf = c->e[k].buf;
		o->len = c->e[k].len;
	}
	af->ReadProc = of_read;
	af->WriteProc = of_write;
	af->TellProc = of_tell;
	af->FileSizeProc = of_size;
	af->SeekProc = of_seek;
	af->FlushProc = of_flush;
	af->UserData = (aiUserData)o;
	return af;
}

static void io_close(struct aiFileIO *io, struct aiFile *af)
{
	if (!af)
		return;
	ofile *o = (ofile *)af->UserData;
	if (o->fp)
		fclose(o->fp);
	free(o);
	free(af);
}

/* OBJ pre-scan: Assimp's fast_atof reads "1.0x" as 1 and "nan" as NaN
 * without complaint, and by the time a NaN reaches scene_finish the line
 * is lost. So the `v` and `vn` lines are checked here, with their line,
 * and so are the `f` lines' indices (obj_face). */
/* The most corners an `f` line may have: Assimp triangulates a polygon
 * in time quadratic in its corners (16384 took 3 s, a fuzzed 600 KB file
 * of one 300,000-corner face ran into the import's CPU limit). */
#define OBJ_FACE_MAX 16384

/* The indices of an `f` line: each v, v/vt, v//vn or v/vt/vn must name an
 * element defined above it (1..count, or -1..-count from the last), as
 * Assimp only says "index out of range" without the line; and at most
 * OBJ_FACE_MAX of them. */
static int obj_face(const char *p, const char *t, const char *eol, const long cnt[3],
                    const char *file, int line, diag *d)
{
	static const char *const what[3] = {"vertex", "texture coordinate", "normal"};
	long corners = 0;
	while (t < eol && *t != '#') {
		while (t < eol && isspace((unsigned char)*t))
			t++;
		if (t >= eol || *t == '#')
			break;
		if (++corners > OBJ_FACE_MAX)
			return diag_set(
			    d, file, line, (int)(t - p) + 1,
			    "face of more than %d corners (its triangulation takes time "
			    "quadratic in them)",
			    OBJ_FACE_MAX);
		for (int k = 0; k < 3 && t < eol && !isspace((unsigned char)*t) && *t != '#'; k++) {
			if (*t == '/') { /* v//vn: no texture coordinate */
				t++;
				continue;
			}
			const char *s = t;
			char *end;
			errno = 0;
			long i = strtol(t, &end, 10);
			if (end == t || errno)
				return diag_set(d, file, line, (int)(s - p) + 1,
				                "malformed face index '%.*s'",
				                (int)(end > t ? end - t : 1), t);
			t = end;
			long n = cnt[k];
			if (i == 0 || i > n || i < -n)
				return diag_set(d, file, line, (int)(s - p) + 1,
				                "face refers to %s %ld of %ld defined above it",
				                what[k], i, n);
			if (t < eol && *t == '/')
				t++;
		}
		while (t < eol && !isspace((unsigned char)*t) && *t != '#')
			t++;
	}
	return 0;
}

static int obj_scan(const char *text, const char *file, diag *d)
{
	int line = 1;
	long cnt[3] = {0, 0, 0}; /* v, vt, vn so far */
	for (const char *p = text; *p; line++) {
		const char *eol = strchr(p, '\n');
		if (!eol)
			eol = p + strlen(p);
		const char *q = p;
		while (q < eol && (*q == ' ' || *q == '\t'))
			q++;
		int sp = q + 1 < eol && (q[1] == ' ' || q[1] == '\t');
		int sp2 = q + 2 < eol && (q[2] == ' ' || q[2] == '\t');
		if (q < eol && q[0] == 'v') {
			if (sp)
				cnt[0]++;
			else if (q[1] == 't' && sp2)
				cnt[1]++;
			else if (q[1] == 'n' && sp2)
				cnt[2]++;
		}
		if (q < eol && q[0] == 'f' && sp) {
			if (obj_face(p, q + 1, eol, cnt, file, line, d))
				return -1;
			p = *eol ? eol + 1 : eol;
			continue;
		}
		int normal = q + 1 < eol && q[0] == 'v' && q[1] == 'n';
		int vertex = q < eol && q[0] == 'v';
		const char *t = q + (normal ? 2 : 1);
		if ((normal || vertex) && t < eol && (*t == ' ' || *t == '\t')) {
			while (t < eol && *t != '#') {
				while (t < eol && isspace((unsigned char)*t))
					t++;
				const char *e = t;
				while (e < eol && !isspace((unsigned char)*e) && *e != '#')
					e++;
				if (e == t)
					break;
				char tok[64];
				size_t n = (size_t)(e - t);
				char *end = tok;
				double x = 0;
				if (n < sizeof tok) {
					memcpy(tok, t, n);
					tok[n] = '\0';
					x = strtod(tok, &end);
				}
				int col = (int)(t - p) + 1;
				if (n >= sizeof tok || end != tok + n)
					return diag_set(d, file, line, col,
					                "malformed number '%.*s'",
					                (int)(n > 40 ? 40 : n), t);
				if (!isfinite(x))
					return diag_set(
					    d, file, line, 0,
					    normal ? "normal has a NaN or infinite component"
					           : "vertex has a NaN or infinite coordinate");
				t = e;
			}
		}
		p = *eol ? eol + 1 : eol;
	}
	return 0;
}

/* PLY pre-scan. Assimp 5.2's PLY reader never returns on a header without
 * a whole end_header line (also when the words appear inside another line,
 * "end_headerX" or "comment end_header"), pads an ASCII file that ends
 * early with made-up faces (a header declaring ten faces over one face line
 * gave ten triangles), and allocates for whatever count a header declares
 * before it reads the data. So the header is parsed here, line by line
 * (PLY 1.0: ply, format, comment, obj_info, element NAME COUNT, property
 * TYPE NAME, property list COUNT_TYPE ITEM_TYPE NAME, end_header), and the
 * data is walked element by element against it, ASCII by its lines and
 * tokens, binary by its sizes and list counts: a file that holds less than
 * its header declares is an error naming the element (and, for ASCII, the
 * line); numbers themselves are left to Assimp. The walk is one pass over
 * bytes already in memory and stops at the first shortfall, however large
 * the declared counts. */
#define PLY_MAX_ELEMS 16
#define PLY_MAX_PROPS 64

typedef struct ply_prop {
	unsigned char list, csize, isize; /* list: count and item sizes; else isize */
	unsigned char kind;               /* of the items: PLY_UINT, PLY_INT or PLY_FLOAT */
	unsigned char vidx;               /* a face's vertex index list (ply_scan checks it) */
} ply_prop;

enum { PLY_UINT, PLY_INT, PLY_FLOAT };

typedef struct ply_elem {
	char name[32];
	unsigned long long count;
	int nprops;
	ply_prop prop[PLY_MAX_PROPS];
} ply_elem;

/* Byte size of a PLY scalar type name, 0 if it is none. */
static int ply_type_size(const char *t, size_t n)
{
	static const struct {
		const char *name;
		int size;
	} types[] = {{"char", 1},  {"int8", 1},    {"uchar", 1},  {"uint8", 1},
	             {"short", 2}, {"int16", 2},   {"ushort", 2}, {"uint16", 2},
	             {"int", 4},   {"int32", 4},   {"uint", 4},   {"uint32", 4},
	             {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
	for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
		if (strlen(types[i].name) == n && !memcmp(types[i].name, t, n))
			return types[i].size;
	return 0;
}

/* PLY text is split on spaces and tabs only. isspace also takes a form
 * feed or vertical tab for a blank, while Assimp 5.2 takes them for line
 * ends (and never returned on a form feed before end_header), so the two
 * readings of such a file would differ: ply_line refuses them. */
static int ply_blank(char c)
{
	return c == ' ' || c == '\t';
}

/* The next token of [*s, e) between spaces and tabs: its start in *t and
 * length (0 at the end of the range); *s moves past it. */
static size_t ply_tok(const char **s, const char *e, const char **t)
{
	const char *p = *s;
	while (p < e && ply_blank(*p))
		p++;
	*t = p;
	while (p < e && !ply_blank(*p))
		p++;
	*s = p;
	return (size_t)(p - *t);
}

/* The text line ln starting at p: its end in *eol (before the '\n', and
 * before a '\r' just ahead of it) and the next line's start in *next. A
 * control byte on it (below 0x20 but a tab, or 0x7f) is an error naming
 * its line and column; `where` says which part of the file it is in. */
static int ply_line(const char *p, const char *end, const char **eol, const char **next,
                    const char *file, int ln, const char *where, diag *d)
{
	const char *nl = memchr(p, '\n', (size_t)(end - p));
	const char *e = nl ? nl : end;
	*next = nl ? nl + 1 : end;
	if (e > p && e[-1] == '\r')
		e--;
	for (const char *q = p; q < e; q++) {
		unsigned char c = (unsigned char)*q;
		if ((c < 0x20 && c != '\t') || c == 0x7f)
			return diag_set(d, file, ln, (int)(q - p) + 1,
			                "control byte 0x%02x in the PLY %s", c, where);
	}
	*eol = e;
	return 0;
}

/* A PLY element or property name starts with a letter or an underscore:
 * Assimp read "element 400000000vertex 3" as 400000000 vertices. */
static int ply_name_ok(const char *t, size_t n)
{
	char c = n ? *t : '\0';
	return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}

static int tok_is(const char *t, size_t n, const char *word)
{
	return strlen(word) == n && !memcmp(t, word, n);
}

/* One header line being read: the cursor s in it, its end, its start and
 * number (for the messages' line and column) and the file's name. */
typedef struct ply_hline {
	const char *s, *eol, *ls, *file;
	int ln;
} ply_hline;

/* The column of the token at t (1-based). */
#define COL ((int)(t - h->ls) + 1)

/* "format ascii|binary_little_endian|binary_big_endian 1.0" into *fmt. */
static int ply_hdr_format(ply_hline *h, const char *t, int *fmt, diag *d)
{
	const char *file = h->file;
	int ln = h->ln;
	/* Assimp and this scan must read the same header: a second format
	 * line (the scan kept the last, Assimp the first: a fuzzed file made
	 * Assimp read ASCII data as binary and ask for gigabytes) is refused */
	if (*fmt >= 0)
		return diag_set(d, file, ln, COL, "a second PLY format line");
	size_t n = ply_tok(&h->s, h->eol, &t);
	*fmt = tok_is(t, n, "ascii")                  ? 0
	       : tok_is(t, n, "binary_little_endian") ? 1
	       : tok_is(t, n, "binary_big_endian")    ? 2
	                                              : -1;
	if (*fmt < 0)
		return diag_set(d, file, ln, COL,
		                "unknown PLY format '%.*s' (ascii, binary_little_endian or "
		                "binary_big_endian)",
		                (int)(n > 40 ? 40 : n), t);
	n = ply_tok(&h->s, h->eol, &t);
	if (!tok_is(t, n, "1.0"))
		return diag_set(d, file, ln, n ? COL : 0,
		                "PLY version '%.*s': saarsim reads version 1.0",
		                (int)(n > 40 ? 40 : n), t);
	if (ply_tok(&h->s, h->eol, &t))
		return diag_set(d, file, ln, COL, "text after the PLY version");
	return 0;
}

/* "element NAME COUNT": a new element el[(*nel)++]. */
static int ply_hdr_element(ply_hline *h, const char *t, ply_elem *el, int *nel, diag *d)
{
	const char *file = h->file;
	int ln = h->ln;
	if (*nel == PLY_MAX_ELEMS)
		return diag_set(d, file, ln, 0, "more than %d PLY elements", PLY_MAX_ELEMS);
	ply_elem *e = &el[(*nel)++];
	memset(e, 0, sizeof *e);
	size_t n = ply_tok(&h->s, h->eol, &t);
	if (!n)
		return diag_set(d, file, ln, 0, "element without a name");
	if (!ply_name_ok(t, n))
		return diag_set(d, file, ln, COL,
		                "element name '%.*s' does not begin with a letter or underscore",
		                (int)(n > 40 ? 40 : n), t);
	/* Assimp matches elements by name: one declared twice (fuzz-ply's
	 * fourth finding, with a property line carrying a second header's
	 * words) made it free what it had not allocated */
	if (n >= sizeof e->name)
		return diag_set(d, file, ln, COL, "element name longer than %d bytes",
		                (int)sizeof e->name - 1);
	for (int k = 0; k + 1 < *nel; k++)
		if (tok_is(t, n, el[k].name))
			return diag_set(d, file, ln, COL, "element '%s' declared a second time",
			                el[k].name);
	snprintf(e->name, sizeof e->name, "%.*s", (int)n, t);
	n = ply_tok(&h->s, h->eol, &t);
	char *cend;
	char num[24];
	if (n == 0 || n >= sizeof num || !isdigit((unsigned char)*t))
		return diag_set(d, file, ln, n ? COL : 0, "element %s: expected a count", e->name);
	memcpy(num, t, n);
	num[n] = '\0';
	errno = 0;
	e->count = strtoull(num, &cend, 10);
	if (*cend || errno)
		return diag_set(d, file, ln, COL, "element %s: bad count '%s'", e->name, num);
	if (ply_tok(&h->s, h->eol, &t))
		return diag_set(d, file, ln, COL, "text after the element count");
	return 0;
}

/* "property [list CTYPE] TYPE NAME": a property of the last element. */
static int ply_hdr_property(ply_hline *h, const char *t, ply_elem *el, int nel, diag *d)
{
	const char *file = h->file;
	int ln = h->ln;
	if (!nel)
		return diag_set(d, file, ln, COL, "property before any element");
	ply_elem *e = &el[nel - 1];
	if (e->nprops == PLY_MAX_PROPS)
		return diag_set(d, file, ln, 0, "element %s has more than %d properties", e->name,
		                PLY_MAX_PROPS);
	ply_prop *pr = &e->prop[e->nprops++];
	size_t n = ply_tok(&h->s, h->eol, &t);
	int list = tok_is(t, n, "list");
	if (list) {
		pr->list = 1;
		n = ply_tok(&h->s, h->eol, &t);
		pr->csize = (unsigned char)ply_type_size(t, n);
		if (!pr->csize)
			goto bad_type;
		n = ply_tok(&h->s, h->eol, &t);
	}
	pr->isize = (unsigned char)ply_type_size(t, n);
	if (!pr->isize)
		goto bad_type;
	pr->kind = *t == 'u' ? PLY_UINT : *t == 'f' || *t == 'd' ? PLY_FLOAT : PLY_INT;
	n = ply_tok(&h->s, h->eol, &t);
	if (!n)
		return diag_set(d, file, ln, 0, "property without a name");
	pr->vidx = list && !strcmp(e->name, "face") &&
	           (tok_is(t, n, "vertex_indices") || tok_is(t, n, "vertex_index"));
	if (!ply_name_ok(t, n))
		return diag_set(d, file, ln, COL,
		                "property name '%.*s' does not begin with a letter or underscore",
		                (int)(n > 40 ? 40 : n), t);
	if (ply_tok(&h->s, h->eol, &t))
		return diag_set(d, file, ln, COL, "text after the property name");
	return 0;
bad_type:
	return diag_set(d, file, ln, n ? COL : 0, "unknown PLY type '%.*s'", (int)(n > 40 ? 40 : n),
	                t);
}

/* The first line: exactly "ply", before anything else is read; p moves
 * past it. */
static int ply_magic(const char **p, const char *end, const char *file, diag *d)
{
	const char *nl = memchr(*p, '\n', (size_t)(end - *p));
	size_t k = nl ? (size_t)(nl - *p) : (size_t)(end - *p);
	if (k && (*p)[k - 1] == '\r')
		k--;
	if (k != 3 || memcmp(*p, "ply", 3) != 0)
		return diag_set(d, file, 1, 0,
		                "not a PLY file (it does not begin with a 'ply' line)");
	*p = nl ? nl + 1 : end;
	return 0;
}

/* The header of the PLY in [buf, buf + len): fills el[0, *nel), *fmt (0
 * ascii, 1 binary little-endian, 2 big-endian) and *data (the first byte
 * after the end_header line) and *line (that line's number). */
static int ply_header(const char *buf, size_t len, const char *file, ply_elem *el, int *nel,
                      int *fmt, size_t *data, int *line, diag *d)
{
	const char *p = buf, *end = buf + len;
	*nel = 0;
	*fmt = -1;
	for (int ln = 1;; ln++) {
		if (p >= end)
			return diag_set(d, file, 0, 0, "PLY header has no end_header line");
		if (ln == 1) {
			if (ply_magic(&p, end, file, d))
				return -1;
			continue;
		}
		const char *eol, *next;
		if (ply_line(p, end, &eol, &next, file, ln, "header", d))
			return -1;
		ply_hline hl = {p, eol, p, file, ln}, *h = &hl;
		const char *t;
		size_t n = ply_tok(&h->s, eol, &t);
		p = next;
		if (n == 0 || tok_is(t, n, "comment") || tok_is(t, n, "obj_info"))
			continue;
		if (tok_is(t, n, "end_header")) {
			if (ply_tok(&h->s, eol, &t))
				return diag_set(d, file, ln, COL, "text after end_header");
			/* a file ending right after the word: Assimp 5.2 never
			 * returns (fuzz-ply's fifth finding) */
			if (eol >= end)
				return diag_set(d, file, ln, 0,
				                "end_header is not followed by a line end");
			if (*fmt < 0)
				return diag_set(d, file, ln, 0, "PLY header has no format line");
			*data = (size_t)(p - buf);
			*line = ln;
			return 0;
		}
		int rc = tok_is(t, n, "format")    ? ply_hdr_format(h, t, fmt, d)
		         : tok_is(t, n, "element") ? ply_hdr_element(h, t, el, nel, d)
		         : tok_is(t, n, "property")
		             ? ply_hdr_property(h, t, el, *nel, d)
		             : diag_set(d, file, ln, COL, "unknown PLY header line '%.*s'",
		                        (int)(n > 40 ? 40 : n), t);
		if (rc)
			return rc;
	}
}
#undef COL

/* An unsigned list count of `size` bytes at p in the file's byte order
 * (a negative signed count reads as huge, which no file holds). */
static unsigned long long ply_count(const unsigned char *p, int size, int big)
{
	unsigned long long v = 0;
	for (int i = 0; i < size; i++)
		v |= (unsigned long long)p[big ? size - 1 - i : i] << (8 * i);
	return v;
}

static int ply_short(const char *file, int line, const ply_elem *e, unsigned long long i, diag *d)
{
	return diag_set(d, file, line, 0,
	                "PLY data ends inside %s %llu of the %llu its header declares", e->name,
	                i + 1, e->count);
}

/* Assimp 5.2's PLY reader uses a face's vertex indices before anything
 * checks them: a fuzzed binary face naming vertex 1793 of 4 made it write
 * outside its buffers (AddressSanitizer's heap metadata was found
 * corrupted). So the scan checks every vertex index against the vertex
 * count; v is the item read from the file. */
static int ply_vidx(long double v, unsigned long long nvert, const char *file, int line,
                    const ply_elem *e, unsigned long long i, diag *d)
{
	if (v >= 0 && v < (long double)nvert && v == (long double)(unsigned long long)v)
		return 0;
	return diag_set(d, file, line, 0, "%s %llu refers to vertex %.0Lf of the %llu declared",
	                e->name, i + 1, v, nvert);
}

/* A binary item of `size` bytes at p, of kind kind, in the file's order. */
static long double ply_item(const unsigned char *p, int size, int kind, int big)
{
	unsigned long long u = ply_count(p, size, big);
	if (kind == PLY_FLOAT) {
		if (size == 4) {
			uint32_t b = (uint32_t)u;
			float f;
			memcpy(&f, &b, 4);
			return f;
		}
		double x;
		memcpy(&x, &u, 8);
		return x;
	}
	if (kind == PLY_INT && size < 8 && (u >> (8 * size - 1)) & 1)
		return (long double)u - (long double)(1ull << (8 * size));
	return (long double)u;
}

static int ply_scan(const char *buf, size_t len, const char *file, diag *d)
{
	ply_elem el[PLY_MAX_ELEMS];
	int nel = 0, fmt = 0, line = 0;
	size_t at = 0;
	if (ply_header(buf, len, file, el, &nel, &fmt, &at, &line, d))
		return -1;
	if (fmt == 0 && text_check(buf + at, len - at, line + 1, file, "an ASCII PLY", d))
		return -1;
	const char *p = buf + at, *end = buf + len;
	unsigned long long nvert = 0;
	for (int k = 0; k < nel; k++)
		if (!strcmp(el[k].name, "vertex"))
			nvert = el[k].count;
	for (int k = 0; k < nel; k++) {
		const ply_elem *e = &el[k];
		if (e->count && !e->nprops)
			return diag_set(d, file, 0, 0, "element %s has no properties", e->name);
		for (unsigned long long i = 0; i < e->count; i++) {
			if (fmt) { /* binary: sizes and list counts */
				for (int j = 0; j < e->nprops; j++) {
					const ply_prop *pr = &e->prop[j];
					unsigned long long items = 1;
					if (pr->list) {
						if ((size_t)(end - p) < pr->csize)
							return ply_short(file, 0, e, i, d);
						items = ply_count((const unsigned char *)p,
						                  pr->csize, fmt == 2);
						p += pr->csize;
					}
					if (items > (unsigned long long)(end - p) / pr->isize)
						return ply_short(file, 0, e, i, d);
					for (unsigned long long m = 0; pr->vidx && m < items; m++)
						if (ply_vidx(ply_item((const unsigned char *)p +
						                          m * pr->isize,
						                      pr->isize, pr->kind,
						                      fmt == 2),
						             nvert, file, 0, e, i, d))
							return -1;
					p += items * pr->isize;
				}
				continue;
			}
			/* ASCII: one element per line (a blank line is one with
			 * no values, as Assimp reads it) */
			line++;
			if (p >= end)
				return ply_short(file, 0, e, i, d);
			const char *eol, *next;
			if (ply_line(p, end, &eol, &next, file, line, "data", d))
				return -1;
			const char *s = p, *t;
			for (int j = 0; j < e->nprops; j++) {
				unsigned long long items = 1;
				if (e->prop[j].list) {
					size_t n = ply_tok(&s, eol, &t);
					char num[24];
					char *cend = num;
					if (n && n < sizeof num) {
						memcpy(num, t, n);
						num[n] = '\0';
						items = strtoull(num, &cend, 10);
					}
					if (!n || n >= sizeof num || *cend ||
					    !isdigit((unsigned char)*t))
						return diag_set(d, file, line,
						                n ? (int)(t - p) + 1 : 0,
						                "%s %llu: expected a list length",
						                e->name, i + 1);
				}
				for (unsigned long long m = 0; m < items; m++) {
					size_t tn = ply_tok(&s, eol, &t);
					if (!tn)
						return diag_set(d, file, line, 0,
						                "%s %llu has fewer values than its "
						                "header declares",
						                e->name, i + 1);
					/* every value a finite number: Assimp's
					 * ASCII reader corrupted its heap on a
					 * fuzzed line of other bytes */
					char num[48];
					char *cend = num;
					long double v = -1;
					if (tn < sizeof num) {
						memcpy(num, t, tn);
						num[tn] = '\0';
						v = strtold(num, &cend);
					}
					if (tn >= sizeof num || *cend || !isfinite(v))
						return diag_set(
						    d, file, line, (int)(t - p) + 1,
						    "%s %llu: '%.*s' is not a finite number",
						    e->name, i + 1, (int)(tn > 40 ? 40 : tn), t);
					if (e->prop[j].vidx &&
					    ply_vidx(v, nvert, file, line, e, i, d))
						return -1;
				}
			}
			if (ply_tok(&s, eol, &t))
				return diag_set(d, file, line, (int)(t - p) + 1,
				                "%s %llu has more values than its header declares",
				                e->name, i + 1);
			p = next;
		}
	}
	return 0;
}

/* The formats saarsim reads (docs/views.md, "Scene files"): Assimp 5.2
 * guesses at many more (3,000 random bytes named .ase were an 8-triangle
 * scene), so only these extensions are handed to it, and only when the
 * content is what the extension says (content_check). */
typedef enum { FMT_OBJ, FMT_PLY, FMT_STL, FMT_3DS, FMT_GLTF, FMT_GLB, FMT_DAE } scene_fmt;

static const struct {
	const char *ext;
	scene_fmt fmt;
} formats[] = {{".obj", FMT_OBJ},   {".ply", FMT_PLY}, {".stl", FMT_STL}, {".3ds", FMT_3DS},
               {".gltf", FMT_GLTF}, {".glb", FMT_GLB}, {".dae", FMT_DAE}};

#define FORMAT_LIST ".obj (with .mtl), .ply, .stl, .3ds, .gltf, .glb and .dae, each also gzipped"

/* The format of virt (the name without ".gz"), or -1. */
static int import_format(const char *virt)
{
	for (size_t i = 0; i < sizeof formats / sizeof formats[0]; i++)
		if (ends_with(virt, formats[i].ext))
			return (int)formats[i].fmt;
	return -1;
}

static uint32_t le32(const char *p)
{
	const unsigned char *u = (const unsigned char *)p;
	return (uint32_t)u[0] | (uint32_t)u[1] << 8 | (uint32_t)u[2] << 16 | (uint32_t)u[3] << 24;
}

/* The first byte of text past a UTF-8 byte order mark and blanks. */
static const char *text_start(const char *buf, size_t len)
{
	const char *p = buf, *end = buf + len;
	if (len >= 3 && !memcmp(p, "\xef\xbb\xbf", 3))
		p += 3;
	while (p < end && (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n'))
		p++;
	return p;
}

/* Is the scene file's content the format its extension names? Then the
 * format's own pre-scan (OBJ, PLY). */
static int content_check(scene_fmt fmt, const char *buf, size_t len, const char *file, diag *d)
{
	const char *p = text_start(buf, len), *end = buf + len;
	switch (fmt) {
	case FMT_OBJ:
		if (text_check(buf, len, 1, file, "an OBJ", d))
			return -1;
		return obj_scan(buf, file, d);
	case FMT_PLY:
		return ply_scan(buf, len, file, d);
	case FMT_STL: {
		/* binary: an 80-byte header, a triangle count, 50 bytes each
		 * (the header may begin with "solid" too) */
		if (len >= 84 && 84 + 50 * (uint64_t)le32(buf + 80) == len)
			return 0;
		if ((size_t)(end - p) < 5 || memcmp(p, "solid", 5) != 0) {
			if (len < 84)
				return diag_set(
				    d, file, 0, 0,
				    "not an STL file (%zu bytes: too short for a binary "
				    "STL, and it does not begin with 'solid')",
				    len);
			return diag_set(d, file, 0, 0,
			                "not an STL file (a binary STL of %u triangles has %llu "
			                "bytes, not %zu, and it does not begin with 'solid')",
			                le32(buf + 80),
			                84 + 50 * (unsigned long long)le32(buf + 80), len);
		}
		return text_check(buf, len, 1, file, "an ASCII STL", d);
	}
	case FMT_3DS: {
		unsigned id = len >= 2 ? (unsigned char)buf[0] | (unsigned char)buf[1] << 8 : 0;
		if (len < 6 || id != 0x4D4D)
			return diag_set(d, file, 0, 0,
			                "not a 3DS file (it does not begin with chunk 0x4D4D)");
		if (le32(buf + 2) != len)
			return diag_set(d, file, 0, 0,
			                "not a 3DS file (its main chunk says %u bytes, the file "
			                "has %zu)",
			                le32(buf + 2), len);
		return 0;
	}
	case FMT_GLB:
		if (len < 4 || memcmp(buf, "glTF", 4) != 0)
			return diag_set(d, file, 0, 0,
			                "not a GLB file (it does not begin with 'glTF')");
		if (len < 12)
			return diag_set(d, file, 0, 0,
			                "not a GLB file (%zu bytes: no whole header)", len);
		if (le32(buf + 8) != len)
			return diag_set(
			    d, file, 0, 0,
			    "not a GLB file (its header says %u bytes, the file has %zu)",
			    le32(buf + 8), len);
		return 0;
	case FMT_GLTF:
		if (text_check(buf, len, 1, file, "a glTF JSON", d))
			return -1;
		if (p == end || *p != '{')
			return diag_set(d, file, 0, 0,
			                "not a glTF JSON file (it does not begin with '{')");
		return 0;
	case FMT_DAE:
		if (text_check(buf, len, 1, file, "a Collada XML", d))
			return -1;
		/* no NUL in it now, and in_read_all ends it with one */
		if (p == end || *p != '<' || !strstr(buf, "<COLLADA"))
			return diag_set(d, file, 0, 0,
			                "not a Collada file (XML with a <COLLADA> element)");
		return 0;
	}
	return 0;
}

/* Assimp 5.2 (Debian 12) crashes on some malformed files instead of
 * failing: its binary PLY reader reads out of bounds on a corrupt face
 * list, and an ai_assert in TriangulateProcess aborts on one that does not
 * add up (found by fuzzing). A scene file is user input, so that must end
 * as an error like any other, not as a crash: while Assimp runs, SIGSEGV,
 * SIGBUS, SIGABRT, SIGFPE and SIGILL jump back here (on their own stack,
 * in case the fault is a stack overflow), and Assimp's assert message is
 * kept off stderr (fd 2 points at /dev/null meanwhile; it reports through
 * aiGetErrorString otherwise; in the importer process, whose stderr the
 * parent captures, fd 2 stays: diag_quiet_off). What Assimp held is
 * lost then, and the caller is about to exit. A signal handler reaches
 * only static storage, hence the jump buffer below, used only during one
 * import (imports are not run from several threads). */
static sigjmp_buf crash_jmp;
static volatile sig_atomic_t crash_sig;

static void on_crash(int sig)
{
	crash_sig = sig;
	siglongjmp(crash_jmp, 1);
}

#define GUARD_NSIG  5
#define GUARD_STACK (256 * 1024)

static const struct aiScene *import_guarded(const char *virt, struct aiFileIO *io,
                                            struct aiPropertyStore *props, int *sig)
{
	static const int sigs[GUARD_NSIG] = {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL};
	struct sigaction sa, old[GUARD_NSIG];
	stack_t alt = {0}, old_alt;
	const struct aiScene *volatile as = NULL;
	alt.ss_sp = malloc(GUARD_STACK);
	alt.ss_size = GUARD_STACK;
	int have_alt = alt.ss_sp && sigaltstack(&alt, &old_alt) == 0;
	memset(&sa, 0, sizeof sa);
	sa.sa_handler = on_crash;
	sa.sa_flags = have_alt ? SA_ONSTACK : 0;
	sigemptyset(&sa.sa_mask);
	int err_fd = diag_quiet_begin();
	crash_sig = 0;
	for (int i = 0; i < GUARD_NSIG; i++)
		sigaction(sigs[i], &sa, &old[i]);
	/* savemask 1: the jump restores the mask the handler's signal was
	 * blocked in */
	if (sigsetjmp(crash_jmp, 1) == 0)
		as = aiImportFileExWithProperties(virt,
		                                  aiProcess_Triangulate | aiProcess_SortByPType |
		                                      aiProcess_PreTransformVertices,
		                                  io, props);
	for (int i = 0; i < GUARD_NSIG; i++)
		sigaction(sigs[i], &old[i], NULL);
	diag_quiet_end(err_fd);
	if (have_alt)
		sigaltstack(&old_alt, NULL);
	free(alt.ss_sp);
	*sig = crash_sig;
	return crash_sig ? NULL : as;
}

/* Assimp's messages sometimes carry "line N"; lift it into file:N. */
static int msg_line(const char *msg)
{
	for (const char *p = msg; *p; p++) {
		if (strncasecmp(p, "line", 4) == 0) {
			const char *q = p + 4;
			while (*q == ' ' || *q == ':' || *q == '#')
				q++;
			if (isdigit((unsigned char)*q))
				return atoi(q);
		}
	}
	return 0;
}

static float mean3(struct aiColor4D c)
{
	return (c.r + c.g + c.b) / 3.0f;
}

static float clamp01(float x)
{
	return x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x;
}

/* Loads (or finds, by resolved path) the texture `type` of material m.
 * Returns 0 with *idx = texture index or -1 when there is none. */
static int load_texture(scene *s, const struct aiMaterial *am, enum aiTextureType type,
                        const char *dir, const char *file, const char *mname, int32_t *idx, diag *d)
{
	struct aiString str;
	*idx = -1;
	if (aiGetMaterialTexture(am, type, 0, &str, NULL, NULL, NULL, NULL, NULL, NULL) !=
	    aiReturn_SUCCESS)
		return 0;
	/* "*N" names a texture embedded in the file (glTF/FBX); image.h only
	 * reads files, so those are skipped (documented). */
	if (str.length == 0 || str.data[0] == '*')
		return 0;
	for (char *c = str.data; *c; c++)
		if (*c == '\\')
			*c = '/'; /* MTL files written on Windows */
	texture t;
	memset(&t, 0, sizeof t);
	int n = (str.data[0] == '/' || !dir[0])
	            ? snprintf(t.path, sizeof t.path, "%s", str.data)
	            : snprintf(t.path, sizeof t.path, "%s/%s", dir, str.data);
	if (n < 0 || (size_t)n >= sizeof t.path)
		return diag_set(d, file, 0, 0, "texture path of material '%s' is too long: %s",
		                mname, str.data);
	for (uint32_t i = 0; i < s->ntexs; i++) {
		if (strcmp(s->texs[i].path, t.path) == 0) {
			*idx = (int32_t)i;
			return 0;
		}
	}
	diag td;
	if (img_read_rgba8(t.path, &t.w, &t.h, &t.rgba, &td) != 0) {
		/* the message after the texture's path */
		import_oom |= oom_text(td.msg + strnlen(t.path, sizeof t.path));
		return diag_set(d, file, 0, 0, "material '%s': texture %s", mname, td.msg);
	}
	texture *nt = realloc(s->texs, (s->ntexs + 1) * sizeof *nt);
	if (!nt) {
		free(t.rgba);
		import_oom = 1;
		return diag_set(d, file, 0, 0, "out of memory loading textures");
	}
	s->texs = nt;
	s->texs[s->ntexs] = t;
	*idx = (int32_t)s->ntexs++;
	return 0;
}

/* Converts one Assimp material; the rules are in docs/views.md. */
static int convert_material(scene *s, const struct aiMaterial *am, const char *dir,
                            const char *file, diag *d)
{
	struct aiString name;
	if (aiGetMaterialString(am, AI_MATKEY_NAME, &name) != aiReturn_SUCCESS)
		snprintf(name.data, sizeof name.data, "material%u", s->nmats);
	material m = material_default(name.data);
	struct aiColor4D c;
	if (aiGetMaterialColor(am, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS)
		m.kd = v3(c.r, c.g, c.b);
	if (aiGetMaterialColor(am, AI_MATKEY_COLOR_AMBIENT, &c) == aiReturn_SUCCESS)
		m.ka = v3(c.r, c.g, c.b);
	if (aiGetMaterialColor(am, AI_MATKEY_COLOR_SPECULAR, &c) == aiReturn_SUCCESS)
		m.ks = v3(c.r, c.g, c.b);
	if (aiGetMaterialColor(am, AI_MATKEY_COLOR_EMISSIVE, &c) == aiReturn_SUCCESS)
		m.ke = v3(c.r, c.g, c.b);
	ai_real f;
	unsigned int one = 1;
	if (aiGetMaterialFloatArray(am, AI_MATKEY_SHININESS, &f, &one) == aiReturn_SUCCESS)
		m.ns = f;
	one = 1;
	if (aiGetMaterialFloatArray(am, AI_MATKEY_REFRACTI, &f, &one) == aiReturn_SUCCESS &&
	    f > 0.0f)
		m.ni = f; /* "Ni 0" (BART) means absent */
	int illum = -1;
	one = 1;
	aiGetMaterialIntegerArray(am, AI_MATKEY_OBJ_ILLUM, &illum, &one);

	/* transmit: 1 - d (Assimp folds "Tr t" into the same opacity as
	 * d = 1 - t). Tf is a transmission filter that Assimp reports as
	 * (1,1,1) when absent, so it counts only where it cannot be that
	 * default: with a transparent illum (4, 6, 7, 9), or strictly between
	 * 0 and 1 (BART's "T" exported as Tf). "Tf 0 0 0" stays opaque. */
	float transmit = 0.0f;
	one = 1;
	if (aiGetMaterialFloatArray(am, AI_MATKEY_OPACITY, &f, &one) == aiReturn_SUCCESS)
		transmit = 1.0f - f;
	if (aiGetMaterialColor(am, AI_MATKEY_COLOR_TRANSPARENT, &c) == aiReturn_SUCCESS) {
		float tf = mean3(c);
		int glass = illum == 4 || illum == 6 || illum == 7 || illum == 9;
		if ((glass || (tf > 0.0f && tf < 1.0f)) && tf > transmit)
			transmit = tf;
	}
	one = 1;
	if (aiGetMaterialFloatArray(am, AI_MATKEY_TRANSPARENCYFACTOR, &f, &one) ==
	        aiReturn_SUCCESS &&
	    f > transmit)
		transmit = f;
	m.transmit = clamp01(transmit);

	/* reflect: explicit reflectivity wins; else OBJ illum 3/5/7 (ray-traced
	 * reflection) mirror with the strength of Ks. */
	one = 1;
	if (aiGetMaterialFloatArray(am, AI_MATKEY_REFLECTIVITY, &f, &one) == aiReturn_SUCCESS &&
	    f > 0.0f)
		m.reflect = clamp01(f);
	else if (illum == 3 || illum == 5 || illum == 7)
		m.reflect = clamp01((m.ks.x + m.ks.y + m.ks.z) / 3.0f);

	if (load_texture(s, am, aiTextureType_DIFFUSE, dir, file, m.name, &m.tex_kd, d) != 0)
		return -1;
	enum aiTextureType bt = aiTextureType_HEIGHT;
	if (load_texture(s, am, bt, dir, file, m.name, &m.tex_bump, d) != 0)
		return -1;
	if (m.tex_bump < 0) {
		bt = aiTextureType_NORMALS;
		if (load_texture(s, am, bt, dir, file, m.name, &m.tex_bump, d) != 0)
			return -1;
	}
	one = 1;
	if (m.tex_bump >= 0 && aiGetMaterialFloatArray(am, AI_MATKEY_OBJ_BUMPMULT(bt, 0), &f,
	                                               &one) == aiReturn_SUCCESS)
		m.bump_scale = f;
	/* Assimp reads "Kd nan 0 0" and "Ns inf" without complaint; a NaN
	 * colour would reach every shaded pixel of the material */
	const struct {
		const char *key;
		int ok;
	} vals[] = {{"Kd", v3_finite(m.kd)},
	            {"Ka", v3_finite(m.ka)},
	            {"Ks", v3_finite(m.ks)},
	            {"Ke", v3_finite(m.ke)},
	            {"Ns", isfinite(m.ns)},
	            {"Ni", isfinite(m.ni)},
	            {"d/Tr/Tf (transparency)", isfinite(m.transmit)},
	            {"reflectivity", isfinite(m.reflect)},
	            {"bump multiplier (-bm)", isfinite(m.bump_scale)}};
	for (size_t i = 0; i < sizeof vals / sizeof vals[0]; i++)
		if (!vals[i].ok)
			return diag_set(d, file, 0, 0,
			                "material '%s': %s has a NaN or infinite value", m.name,
			                vals[i].key);
	scene_add_material(s, &m);
	return 0;
}

static int mesh_tris(const struct aiMesh *me)
{
	int n = 0;
	for (unsigned f = 0; f < me->mNumFaces; f++)
		n += me->mFaces[f].mNumIndices == 3;
	return n;
}

/* Copies the used materials (compacted, Assimp's order) and the triangles. */
static int convert_scene(scene *s, const struct aiScene *as, const char *dir, const char *file,
                         diag *d)
{
	uint32_t *remap = malloc((as->mNumMaterials + 1) * sizeof *remap);
	if (!remap) {
		import_oom = 1;
		return diag_set(d, file, 0, 0, "out of memory");
	}
	for (unsigned i = 0; i < as->mNumMaterials; i++)
		remap[i] = UINT32_MAX;
	for (unsigned i = 0; i < as->mNumMeshes; i++) {
		const struct aiMesh *me = as->mMeshes[i];
		if (me->mMaterialIndex < as->mNumMaterials && mesh_tris(me) > 0)
			remap[me->mMaterialIndex] = 0;
	}
	for (unsigned i = 0; i < as->mNumMaterials; i++) {
		if (remap[i] == UINT32_MAX)
			continue;
		remap[i] = s->nmats;
		if (convert_material(s, as->mMaterials[i], dir, file, d) != 0) {
			free(remap);
			return -1;
		}
	}
	for (unsigned i = 0; i < as->mNumMeshes; i++) {
		const struct aiMesh *me = as->mMeshes[i];
		uint32_t mat =
		    me->mMaterialIndex < as->mNumMaterials ? remap[me->mMaterialIndex] : 0;
		const struct aiVector3D *uvs = me->mTextureCoords[0];
		for (unsigned f = 0; f < me->mNumFaces; f++) {
			const struct aiFace *fa = &me->mFaces[f];
			if (fa->mNumIndices != 3)
				continue; /* points and lines are not ray-traceable */
			vec3 p[3], n[3];
			vec2 uv[3];
			for (int k = 0; k < 3; k++) {
				unsigned vi = fa->mIndices[k];
				/* Assimp passes a corrupt binary PLY's face indices on
				 * unchecked (found by fuzzing) */
				if (vi >= me->mNumVertices) {
					free(remap);
					return diag_set(d, file, 0, 0,
					                "mesh %u face %u refers to vertex %u of %u",
					                i, f, vi, me->mNumVertices);
				}
				p[k] = v3(me->mVertices[vi].x, me->mVertices[vi].y,
				          me->mVertices[vi].z);
				if (me->mNormals) {
					const struct aiVector3D *an = &me->mNormals[vi];
					n[k] = v3(an->x, an->y, an->z);
					if (!v3_finite(n[k])) {
						free(remap);
						return diag_set(d, file, 0, 0,
						                "mesh %u vertex %u has a NaN or "
						                "infinite normal",
						                i, vi);
					}
				}
				if (uvs)
					uv[k] = (vec2){uvs[vi].x, uvs[vi].y};
			}
			scene_add_triangle(s, p, me->mNormals ? n : NULL, uvs ? uv : NULL, mat);
		}
	}
	free(remap);
	return 0;
}

int import_body(scene *s, const char *path, scene_file_fn fn, void *ctx, int *oom, diag *d)
{
	scene_init(s, path);
	import_oom = 0;
	*oom = 0;
	char virt[PATH_MAX_LEN], rp[PATH_MAX_LEN];
	snprintf(virt, sizeof virt, "%s", path);
	/* Assimp picks the importer from the extension, so it is handed the
	 * name without ".gz"; io_open maps it back. */
	if (ends_with(virt, ".gz"))
		virt[strlen(virt) - 3] = '\0';
	int fmt = import_format(virt);
	if (fmt < 0) {
		const char *slash = strrchr(virt, '/'), *dot = strrchr(virt, '.');
		if (!dot || (slash && dot < slash))
			return diag_set(d, path, 0, 0,
			                "unsupported scene format (no extension; saarsim reads %s)",
			                FORMAT_LIST);
		return diag_set(d, path, 0, 0,
		                "unsupported scene format '%.40s' (saarsim reads %s)", dot,
		                FORMAT_LIST);
	}
	int gz = real_path(virt, rp, sizeof rp);
	int st = in_check(rp);
	if (st)
		return diag_set(d, path, 0, 0, "cannot open scene file: %s", in_strerror(st));

	memcache cache;
	memset(&cache, 0, sizeof cache);
	cache.fn = fn;
	cache.fn_ctx = ctx;
	if (fn)
		fn(ctx, rp);
	if (in_read_all(rp, gz, &cache.e[0].buf, &cache.e[0].len, cache.err, sizeof cache.err) !=
	    0) {
		*oom = oom_text(cache.err);
		return diag_set(d, path, 0, 0, "%s", cache.err);
	}
	snprintf(cache.e[0].path, sizeof cache.e[0].path, "%s", rp);
	cache.n = 1;
	if (content_check((scene_fmt)fmt, cache.e[0].buf, cache.e[0].len, path, d) != 0) {
		free(cache.e[0].buf);
		return -1;
	}

	struct aiFileIO io = {io_open, io_close, (aiUserData)&cache};
	struct aiPropertyStore *props = aiCreatePropertyStore();
	aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE,
	                           aiPrimitiveType_POINT | aiPrimitiveType_LINE);
	/* No GenNormals: files without normals get face normals in scene_finish. */
	int sig = 0;
	const struct aiScene *as = import_guarded(virt, &io, props, &sig);
	aiReleasePropertyStore(props);
	int rc;
	if (sig) {
		rc = diag_set(d, path, 0, 0,
		              "cannot import scene: the importer (Assimp) crashed on it (%s); the "
		              "file is malformed",
		              strsignal(sig));
	} else if (cache.bad) {
		/* a file it opened failed its check (an MTL with control bytes):
		 * Assimp passed over it as missing */
		rc = diag_set(d, path, 0, 0, "%s", cache.err);
		if (as)
			aiReleaseImport(as);
	} else if (!as) {
		const char *msg = cache.err[0] ? cache.err : aiGetErrorString();
		import_oom |= oom_text(msg);
		/* A file with vertices but no faces ends as Assimp's "No output
		 * meshes"; say what that means for a ray tracer. */
		if (strstr(msg, "No output meshes") || strstr(msg, "No meshes remaining"))
			rc = diag_set(d, path, 0, 0, "scene has no triangles (assimp: %s)", msg);
		else
			rc = diag_set(d, path, msg_line(msg), 0, "cannot import scene: %s", msg);
	} else {
		char dir[PATH_MAX_LEN];
		snprintf(dir, sizeof dir, "%s", path);
		char *slash = strrchr(dir, '/');
		if (slash)
			slash[slash == dir] = '\0'; /* "/x.obj" keeps "/" */
		else
			dir[0] = '\0';
		rc = convert_scene(s, as, dir, path, d);
		aiReleaseImport(as);
		if (rc == 0)
			rc = scene_finish(s, path, d);
	}
	for (int i = 0; i < cache.n; i++)
		free(cache.e[i].buf);
	if (rc != 0) {
		scene_free(s);
		scene_init(s, path);
		*oom = import_oom;
	}
	return rc;
}

int scene_import_inproc(scene *s, const char *path, scene_file_fn fn, void *ctx, diag *d)
{
	int oom;
	return import_body(s, path, fn, ctx, &oom, d);
}
