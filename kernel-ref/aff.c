/*
 * aff.c: the AFF reader (aff.h). Our own small strict parser: the format
 * is whitespace-separated tokens, one command letter (or two: am, fm, xs,
 * pp) and its arguments, so a lexer that tracks line and column, a reader
 * per command and an include stack are all it takes. Every value read is
 * checked where it is read, so each refusal names file:line:col; counts
 * are checked against the bytes left in the file before anything is
 * allocated for them, and files, includes and triangles have limits
 * (aff.h), so no input makes the reader allocate without end or loop.
 */
#include "kernel-ref/aff.h"

#include "kernel-ref/image.h"
#include "kernel-ref/infile.h"
#include "kernel-ref/xform.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define AFF_PI 3.14159265358979323846

typedef struct aff_file {
	char path[1024];
	char *buf;
	size_t len;
} aff_file;

typedef struct lexer {
	const char *file, *buf;
	size_t len, pos, ls; /* ls: where the current line starts */
	int line;
} lexer;

typedef struct tok {
	const char *s;
	size_t n;
	int line, col;
} tok;

typedef struct parser {
	aff_scene *a;
	aff_file *files[AFF_FILES_MAX];
	uint32_t nfiles;
	scene_file_fn fn;
	void *ctx;
	int32_t xf, mat; /* current transform and material (-1: none) */
	long detail;     /* `d`: includes with a higher level are skipped */
	int nest;        /* open transform blocks */
	int32_t stack[AFF_NEST_MAX];
	int open_line[AFF_NEST_MAX];
	char entry_dir[1024];
	uint32_t *names, capnames; /* keyframe names: anim index + 1, 0 empty */
	int view_line;             /* where `v` was, 0: none yet */
	tok last;                  /* the last number read (rd_num, rd_uint) */
	diag *d;
} parser;

/* ---- errors, lexer, numbers ---- */

static int perr(const lexer *lx, const tok *t, diag *d, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static int perr(const lexer *lx, const tok *t, diag *d, const char *fmt, ...)
{
	char msg[768];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
	return diag_set(d, lx->file, t->line, t->col, "%s", msg);
}

static int is_ws(unsigned char c)
{
	return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/* The next token into *t: 1, 0 at the end of the file (t at the end), -1
 * with d on a control byte. */
static int lx_next(lexer *lx, tok *t, diag *d)
{
	while (lx->pos < lx->len) {
		unsigned char c = (unsigned char)lx->buf[lx->pos];
		if (c == '\n') {
			lx->line++;
			lx->ls = ++lx->pos;
		} else if (is_ws(c)) {
			lx->pos++;
		} else if (c == '%' || c == '#') {
			while (lx->pos < lx->len && lx->buf[lx->pos] != '\n')
				lx->pos++;
		} else {
			break;
		}
	}
	t->s = lx->buf + lx->pos;
	t->line = lx->line;
	t->col = (int)(lx->pos - lx->ls + 1);
	size_t st = lx->pos;
	while (lx->pos < lx->len) {
		unsigned char c = (unsigned char)lx->buf[lx->pos];
		if (c <= 0x20 || c == 0x7f)
			break;
		lx->pos++;
	}
	t->n = lx->pos - st;
	if (t->n == 0 && lx->pos < lx->len) {
		unsigned char c = (unsigned char)lx->buf[lx->pos];
		return perr(lx, t, d, "not an AFF text file (control byte 0x%02x)", c);
	}
	return t->n > 0;
}

static int tok_is(const tok *t, const char *w)
{
	return t->n == strlen(w) && memcmp(t->s, w, t->n) == 0;
}

/* The next token, which must exist: `what` names what was expected. */
static int need(parser *p, lexer *lx, tok *t, const char *what)
{
	int r = lx_next(lx, t, p->d);
	if (r < 0)
		return -1;
	if (r == 0)
		return perr(lx, t, p->d, "expected %s, found the end of the file", what);
	return 0;
}

static int expect_word(parser *p, lexer *lx, const char *w)
{
	tok t;
	if (need(p, lx, &t, w))
		return -1;
	if (!tok_is(&t, w))
		return perr(lx, &t, p->d, "expected '%s', found '%.*s'", w,
		            (int)(t.n > 40 ? 40 : t.n), t.s);
	return 0;
}

static int rd_num(parser *p, lexer *lx, double *x, const char *what)
{
	tok t;
	if (need(p, lx, &t, what))
		return -1;
	p->last = t;
	char buf[64], *end = buf;
	if (t.n < sizeof buf) {
		memcpy(buf, t.s, t.n);
		buf[t.n] = '\0';
		errno = 0;
		*x = strtod(buf, &end);
	}
	if (t.n >= sizeof buf || end != buf + t.n || t.n == 0)
		return perr(lx, &t, p->d, "expected %s (a number), found '%.*s'", what,
		            (int)(t.n > 40 ? 40 : t.n), t.s);
	if (!isfinite(*x))
		return perr(lx, &t, p->d, "%s is not finite ('%.*s')", what,
		            (int)(t.n > 40 ? 40 : t.n), t.s);
	return 0;
}

static int rd_nums(parser *p, lexer *lx, double *x, int n, const char *what)
{
	for (int i = 0; i < n; i++)
		if (rd_num(p, lx, &x[i], what))
			return -1;
	return 0;
}

/* A decimal integer in [lo, hi] (digits only). */
static int rd_uint(parser *p, lexer *lx, uint32_t lo, uint32_t hi, uint32_t *out, const char *what)
{
	tok t;
	if (need(p, lx, &t, what))
		return -1;
	p->last = t;
	uint64_t v = 0;
	size_t i = 0;
	for (; i < t.n && t.s[i] >= '0' && t.s[i] <= '9' && v <= UINT32_MAX; i++)
		v = v * 10 + (uint64_t)(t.s[i] - '0');
	if (i != t.n || t.n == 0)
		return perr(lx, &t, p->d, "expected %s (a whole number), found '%.*s'", what,
		            (int)(t.n > 40 ? 40 : t.n), t.s);
	if (v < lo || v > hi)
		return perr(lx, &t, p->d, "%s %.*s is out of range [%u, %u]", what, (int)t.n, t.s,
		            lo, hi);
	*out = (uint32_t)v;
	return 0;
}

/* A count of items of k tokens each must fit in what is left of the file
 * (each token takes at least two bytes): checked before allocating. */
static int count_fits(parser *p, lexer *lx, const tok *at, uint32_t n, uint32_t k)
{
	uint64_t left = (uint64_t)(lx->len - lx->pos) / 2 + 1;
	if ((uint64_t)n * k > left)
		return perr(lx, at, p->d,
		            "count %u needs %llu numbers, more than the rest of the file holds", n,
		            (unsigned long long)n * k);
	return 0;
}

/* Grows *arr (elements of `elem` bytes) to hold `want`. */
static int grow(void *arr, uint32_t *cap, uint64_t want, size_t elem)
{
	if (want <= *cap)
		return 0;
	if (want > UINT32_MAX)
		return -1;
	uint64_t nc = *cap ? *cap : 16;
	while (nc < want)
		nc *= 2;
	if (nc > UINT32_MAX)
		nc = UINT32_MAX;
	void *n = realloc(*(void **)arr, (size_t)nc * elem);
	if (!n)
		return -1;
	*(void **)arr = n;
	*cap = (uint32_t)nc;
	return 0;
}

static int oom(parser *p, lexer *lx, const tok *at)
{
	return perr(lx, at, p->d, "out of memory");
}

/* ---- matrices (row-major 3x4) ---- */

static void m_identity(double m[12])
{
	memset(m, 0, 12 * sizeof *m);
	m[0] = m[5] = m[10] = 1.0;
}

/* T * R * S: scale s, then deg degrees about axis ax (unit), then t. */
static void m_trs(const double s[3], const double q[4], const double t[3], double m[12])
{
	double r[9];
	kb_quat_matrix(q, r);
	for (int i = 0; i < 3; i++) {
		for (int j = 0; j < 3; j++)
			m[4 * i + j] = r[3 * i + j] * s[j];
		m[4 * i + 3] = t[i];
	}
}

static void m_mul(const double a[12], const double b[12], double r[12])
{
	for (int i = 0; i < 3; i++) {
		for (int j = 0; j < 4; j++) {
			double x =
			    a[4 * i] * b[j] + a[4 * i + 1] * b[4 + j] + a[4 * i + 2] * b[8 + j];
			r[4 * i + j] = x + (j == 3 ? a[4 * i + 3] : 0.0);
		}
	}
}

static void axis_angle_quat(const double ax[3], double deg, double q[4])
{
	double len = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
	double h = 0.5 * deg * AFF_PI / 180.0, s = len > 0.0 ? sin(h) / len : 0.0;
	q[0] = len > 0.0 ? cos(h) : 1.0;
	q[1] = s * ax[0];
	q[2] = s * ax[1];
	q[3] = s * ax[2];
}

/* ---- view, lights, materials, range ---- */

static int parse_view(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	if (p->view_line)
		return perr(lx, at, p->d, "a second view 'v' (the first is at line %d)",
		            p->view_line);
	p->view_line = at->line;
	if (expect_word(p, lx, "from") || rd_nums(p, lx, a->from, 3, "a 'from' coordinate") ||
	    expect_word(p, lx, "at") || rd_nums(p, lx, a->at, 3, "an 'at' coordinate") ||
	    expect_word(p, lx, "up") || rd_nums(p, lx, a->up, 3, "an 'up' component") ||
	    expect_word(p, lx, "angle"))
		return -1;
	if (rd_num(p, lx, &a->angle, "the field of view in degrees"))
		return -1;
	if (!(a->angle > 0.0 && a->angle < 180.0))
		return perr(lx, &p->last, p->d, "angle %g is not in (0, 180) degrees", a->angle);
	uint32_t w, h;
	if (expect_word(p, lx, "hither") || rd_num(p, lx, &a->hither, "the hither distance") ||
	    expect_word(p, lx, "resolution") || rd_uint(p, lx, 1, 16384, &w, "the image width") ||
	    rd_uint(p, lx, 1, 16384, &h, "the image height"))
		return -1;
	a->res[0] = (int)w;
	a->res[1] = (int)h;
	a->has_view = 1;
	return 0;
}

/* 1 if the next token starts like a number (an optional light colour). */
static int next_is_number(const lexer *lx)
{
	lexer peek = *lx;
	tok t;
	diag d;
	if (lx_next(&peek, &t, &d) != 1)
		return 0;
	char c = t.s[0];
	return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

static int parse_light(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	if (a->nlights == VIEW_MAX_LIGHTS)
		return perr(lx, at, p->d, "more than %d lights", VIEW_MAX_LIGHTS);
	double *l = a->light[a->nlights];
	l[3] = l[4] = l[5] = 1.0;
	if (rd_nums(p, lx, l, 3, "a light position coordinate"))
		return -1;
	if (next_is_number(lx) && rd_nums(p, lx, l + 3, 3, "a light colour component"))
		return -1;
	a->nlights++;
	return 0;
}

static int parse_range(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	uint32_t n;
	if (rd_num(p, lx, &a->t_start, "the animation start time") ||
	    rd_num(p, lx, &a->t_end, "the animation end time") ||
	    rd_uint(p, lx, 1, 10000000, &n, "the number of frames"))
		return -1;
	if (a->t_end < a->t_start)
		return perr(lx, at, p->d, "animation ends (%g) before it starts (%g)", a->t_end,
		            a->t_start);
	a->frames = (int)n;
	a->has_range = 1;
	return 0;
}

/* fm: ambient, diffuse, specular RGB, Phong exponent, transmittance, index
 * of refraction. f (NFF): colour, Kd, Ks, exponent, transmittance, index. */
static int parse_material(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	aff_mat m;
	memset(&m, 0, sizeof m);
	if (tok_is(at, "fm")) {
		if (rd_nums(p, lx, m.amb, 3, "an ambient colour component") ||
		    rd_nums(p, lx, m.diff, 3, "a diffuse colour component") ||
		    rd_nums(p, lx, m.spec, 3, "a specular colour component"))
			return -1;
	} else {
		double c[3], kd, ks;
		if (rd_nums(p, lx, c, 3, "a colour component") ||
		    rd_num(p, lx, &kd, "the diffuse weight Kd") ||
		    rd_num(p, lx, &ks, "the specular weight Ks"))
			return -1;
		for (int i = 0; i < 3; i++) {
			m.diff[i] = c[i] * kd;
			m.spec[i] = ks;
		}
	}
	if (rd_num(p, lx, &m.shine, "the Phong exponent") ||
	    rd_num(p, lx, &m.transmit, "the transmittance") ||
	    rd_num(p, lx, &m.ior, "the index of refraction"))
		return -1;
	if (grow(&a->mat, &a->capmat, (uint64_t)a->nmat + 1, sizeof *a->mat))
		return oom(p, lx, at);
	a->mat[a->nmat] = m;
	p->mat = (int32_t)a->nmat++;
	return 0;
}

/* ---- meshes and polygons ---- */

/* n items of k floats each appended to a pool (*np items held). */
static int rd_pool(parser *p, lexer *lx, const tok *at, float **pool, uint32_t *np, uint32_t *cap,
                   uint32_t n, int k, const char *what)
{
	if (count_fits(p, lx, at, n, (uint32_t)k))
		return -1;
	if ((uint64_t)*np + n > AFF_POOL_MAX)
		return perr(
		    lx, at, p->d,
		    "the scene has more than %u vertices, normals or texture coordinates of "
		    "one kind",
		    AFF_POOL_MAX);
	if (grow(pool, cap, (uint64_t)*np + n, (size_t)k * sizeof(float)))
		return oom(p, lx, at);
	float *dst = *pool + (size_t)*np * (size_t)k;
	for (uint64_t i = 0; i < (uint64_t)n * (uint64_t)k; i++) {
		double x;
		if (rd_num(p, lx, &x, what))
			return -1;
		if (fabs(x) > 1e30)
			return perr(lx, &p->last, p->d, "%s %g is too large for single precision",
			            what, x);
		dst[i] = (float)x;
	}
	*np += n;
	return 0;
}

/* The folder of path (with its '/'), or "" for a bare name. */
static void dir_of(const char *path, char *dir, size_t n)
{
	const char *slash = strrchr(path, '/');
	size_t k = slash ? (size_t)(slash - path) + 1 : 0;
	if (k >= n)
		k = 0;
	memcpy(dir, path, k);
	dir[k] = '\0';
}

/* A texture named by `texturecoords`: the file beside the AFF file that
 * names it, else in TextureFiles/ beside the entry file's folder (BART's
 * layout, ../shared/scenes/bart_robots_aff/README.md). */
static int find_texture(parser *p, lexer *lx, const tok *name, int32_t *idx)
{
	aff_scene *a = p->a;
	char nm[256], dir[1024], cand[2][1024];
	if (name->n >= sizeof nm)
		return perr(lx, name, p->d, "texture name is longer than %zu bytes", sizeof nm - 1);
	memcpy(nm, name->s, name->n);
	nm[name->n] = '\0';
	dir_of(lx->file, dir, sizeof dir);
	int n0 = nm[0] == '/' ? snprintf(cand[0], sizeof cand[0], "%s", nm)
	                      : snprintf(cand[0], sizeof cand[0], "%s%s", dir, nm);
	int n1 = snprintf(cand[1], sizeof cand[1], "%s../TextureFiles/%s", p->entry_dir, nm);
	for (int c = 0; c < 2; c++) {
		if ((c ? n1 : n0) >= (int)sizeof a->tex->path || in_check(cand[c]) != 0)
			continue;
		for (uint32_t i = 0; i < a->ntex; i++) {
			if (!strcmp(a->tex[i].path, cand[c])) {
				*idx = (int32_t)i;
				return 0;
			}
		}
		if (grow(&a->tex, &a->captex, (uint64_t)a->ntex + 1, sizeof *a->tex))
			return oom(p, lx, name);
		memcpy(a->tex[a->ntex].path, cand[c], sizeof a->tex->path); /* length checked */
		snprintf(a->tex[a->ntex].where, sizeof a->tex->where, "%.280s:%d:%d", lx->file,
		         name->line, name->col);
		*idx = (int32_t)a->ntex++;
		return 0;
	}
	return perr(lx, name, p->d, "texture '%s' not found (looked for %s and %s)", nm, cand[0],
	            cand[1]);
}

/* One zero-based index below n. */
static int rd_index(parser *p, lexer *lx, uint32_t n, const char *what, uint32_t *out)
{
	if (rd_uint(p, lx, 0, UINT32_MAX, out, what))
		return -1;
	if (*out >= n)
		return perr(lx, &p->last, p->d,
		            "%s %u is out of range (the mesh has %u; indices start at 0)", what,
		            *out, n);
	return 0;
}

/* `triangles n` and its rows of 3, 6 or 9 indices. */
static int rd_triangles(parser *p, lexer *lx, const tok *at, aff_mesh *m)
{
	aff_scene *a = p->a;
	uint32_t n;
	if (rd_uint(p, lx, 0, AFF_TRIS_MAX, &n, "the number of triangles"))
		return -1;
	int per = 3 + (m->nn ? 3 : 0) + (m->nuv ? 3 : 0);
	if (count_fits(p, lx, &p->last, n, (uint32_t)per))
		return -1;
	if ((uint64_t)a->ntris + n > AFF_TRIS_MAX)
		return perr(lx, &p->last, p->d, "the scene has more than %u triangles",
		            AFF_TRIS_MAX);
	if (grow(&a->idx, &a->capidx, (uint64_t)a->ntris + n, 9 * sizeof *a->idx))
		return oom(p, lx, at);
	m->t0 = a->ntris;
	m->ntris = n;
	for (uint32_t i = 0; i < n; i++) {
		uint32_t *r = a->idx + 9 * (uint64_t)(a->ntris + i);
		for (int k = 0; k < 9; k++)
			r[k] = UINT32_MAX;
		for (int k = 0; k < 3; k++)
			if (rd_index(p, lx, m->nv, "vertex index", &r[k]))
				return -1;
		for (int k = 0; m->nn && k < 3; k++)
			if (rd_index(p, lx, m->nn, "normal index", &r[3 + k]))
				return -1;
		for (int k = 0; m->nuv && k < 3; k++)
			if (rd_index(p, lx, m->nuv, "texture coordinate index", &r[6 + k]))
				return -1;
	}
	a->ntris += n;
	return 0;
}

static int add_mesh(parser *p, lexer *lx, const tok *at, const aff_mesh *m)
{
	aff_scene *a = p->a;
	if (grow(&a->mesh, &a->capmesh, (uint64_t)a->nmesh + 1, sizeof *a->mesh))
		return oom(p, lx, at);
	a->mesh[a->nmesh++] = *m;
	return 0;
}

/* m / vertices n ... / [normals n ...] / [texturecoords n file ...] /
 * triangles n ... */
static int parse_mesh(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	aff_mesh m = {p->xf, p->mat, -1, a->npv, 0, a->npn, 0, a->npuv, 0, a->ntris, 0};
	uint32_t n;
	if (expect_word(p, lx, "vertices") ||
	    rd_uint(p, lx, 1, AFF_TRIS_MAX, &n, "the number of vertices") ||
	    rd_pool(p, lx, &p->last, &a->pv, &a->npv, &a->cappv, n, 3, "a vertex coordinate"))
		return -1;
	m.nv = n;
	for (;;) {
		tok t;
		if (need(p, lx, &t, "normals, texturecoords or triangles"))
			return -1;
		if (tok_is(&t, "triangles"))
			break;
		int nrm = tok_is(&t, "normals");
		if (!nrm && !tok_is(&t, "texturecoords"))
			return perr(lx, &t, p->d,
			            "expected normals, texturecoords or triangles, found '%.*s'",
			            (int)(t.n > 40 ? 40 : t.n), t.s);
		if (nrm ? m.nn != 0 : m.nuv != 0)
			return perr(lx, &t, p->d, "a second '%.*s' in one mesh", (int)t.n, t.s);
		if (rd_uint(p, lx, 1, AFF_TRIS_MAX, &n,
		            nrm ? "the number of normals" : "the number of texture coordinates"))
			return -1;
		if (nrm) {
			if (rd_pool(p, lx, &t, &a->pn, &a->npn, &a->cappn, n, 3,
			            "a normal component"))
				return -1;
			m.nn = n;
			continue;
		}
		tok name;
		if (need(p, lx, &name, "a texture file name") ||
		    find_texture(p, lx, &name, &m.tex) ||
		    rd_pool(p, lx, &t, &a->puv, &a->npuv, &a->cappuv, n, 2, "a texture coordinate"))
			return -1;
		m.nuv = n;
	}
	if (rd_triangles(p, lx, at, &m))
		return -1;
	return add_mesh(p, lx, at, &m);
}

/* p n + n vertices, pp n + n (vertex, normal): a convex polygon, as a
 * fan of n-2 triangles. */
static int parse_poly(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	int pp = tok_is(at, "pp");
	uint32_t n;
	if (rd_uint(p, lx, 3, AFF_TRIS_MAX, &n, "the number of polygon vertices") ||
	    count_fits(p, lx, &p->last, n, pp ? 6 : 3))
		return -1;
	if ((uint64_t)a->ntris + n > AFF_TRIS_MAX)
		return perr(lx, at, p->d, "the scene has more than %u triangles", AFF_TRIS_MAX);
	aff_mesh m = {p->xf,      p->mat,  -1, a->npv,   n,    a->npn,
	              pp ? n : 0, a->npuv, 0,  a->ntris, n - 2};
	if (grow(&a->pv, &a->cappv, (uint64_t)a->npv + n, 3 * sizeof(float)) ||
	    grow(&a->pn, &a->cappn, (uint64_t)a->npn + n, 3 * sizeof(float)) ||
	    grow(&a->idx, &a->capidx, (uint64_t)a->ntris + n, 9 * sizeof *a->idx))
		return oom(p, lx, at);
	for (uint32_t i = 0; i < n; i++) {
		if (rd_pool(p, lx, at, &a->pv, &a->npv, &a->cappv, 1, 3, "a vertex coordinate") ||
		    (pp &&
		     rd_pool(p, lx, at, &a->pn, &a->npn, &a->cappn, 1, 3, "a normal component")))
			return -1;
	}
	for (uint32_t i = 0; i + 2 < n; i++) {
		uint32_t *r = a->idx + 9 * (uint64_t)(a->ntris + i);
		uint32_t c[3] = {0, i + 1, i + 2};
		for (int k = 0; k < 3; k++) {
			r[k] = c[k];
			r[3 + k] = pp ? c[k] : UINT32_MAX;
			r[6 + k] = UINT32_MAX;
		}
	}
	a->ntris += n - 2;
	return add_mesh(p, lx, at, &m);
}

/* ---- transforms ---- */

static int rd_name(parser *p, lexer *lx, tok *t, char *out, const char *what)
{
	if (need(p, lx, t, what))
		return -1;
	if (t->n >= AFF_NAME_MAX)
		return perr(lx, t, p->d, "%s is longer than %d bytes", what, AFF_NAME_MAX - 1);
	memcpy(out, t->s, t->n);
	out[t->n] = '\0';
	return 0;
}

/* xs sx sy sz  ax ay az deg  tx ty tz { ... } or x name { ... }: a new
 * transform below the current one, current until its '}'. */
static int open_xform(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	aff_xform x;
	memset(&x, 0, sizeof x);
	x.parent = p->xf;
	x.anim = -1;
	if (tok_is(at, "x")) {
		tok t;
		x.animated = 1;
		if (rd_name(p, lx, &t, x.name, "a transform name"))
			return -1;
		m_identity(x.m);
	} else {
		double s[3], ax[4], tr[3], q[4];
		if (rd_nums(p, lx, s, 3, "a scale factor") ||
		    rd_nums(p, lx, ax, 4, "a rotation axis component or angle") ||
		    rd_nums(p, lx, tr, 3, "a translation component"))
			return -1;
		if (ax[0] == 0.0 && ax[1] == 0.0 && ax[2] == 0.0 && ax[3] != 0.0)
			return perr(lx, &p->last, p->d, "rotation of %g degrees about a zero axis",
			            ax[3]);
		axis_angle_quat(ax, ax[3], q);
		m_trs(s, q, tr, x.m);
	}
	tok b;
	if (need(p, lx, &b, "'{'"))
		return -1;
	if (!tok_is(&b, "{"))
		return perr(lx, &b, p->d, "expected '{' after the transform, found '%.*s'",
		            (int)(b.n > 40 ? 40 : b.n), b.s);
	if (p->nest == AFF_NEST_MAX)
		return perr(lx, &b, p->d, "transform blocks nested deeper than %d", AFF_NEST_MAX);
	if (grow(&a->xf, &a->capxf, (uint64_t)a->nxf + 1, sizeof *a->xf))
		return oom(p, lx, at);
	a->xf[a->nxf] = x;
	p->stack[p->nest] = p->xf;
	p->open_line[p->nest++] = at->line;
	p->xf = (int32_t)a->nxf++;
	return 0;
}

static int close_xform(parser *p, lexer *lx, const tok *at, int base)
{
	if (p->nest == base)
		return perr(lx, at, p->d, "'}' closes no transform block opened in this file");
	p->xf = p->stack[--p->nest];
	return 0;
}

/* ---- keyframes ---- */

static uint32_t name_hash(const char *s)
{
	uint32_t h = 2166136261u;
	for (; *s; s++)
		h = (h ^ (unsigned char)*s) * 16777619u;
	return h;
}

/* The slot of name in the keyframe-name table (empty or holding it). */
static uint32_t *name_slot(const parser *p, const char *name)
{
	uint32_t m = p->capnames - 1, i = name_hash(name) & m;
	while (p->names[i] && strcmp(p->a->anim[p->names[i] - 1].name, name))
		i = (i + 1) & m;
	return &p->names[i];
}

/* Enters anim index k in the table (kept at most half full). */
static int name_add(parser *p, uint32_t k)
{
	if (2 * ((uint64_t)k + 1) >= p->capnames) {
		uint32_t old = p->capnames, *oldn = p->names;
		p->capnames = old ? 2 * old : 256;
		p->names = calloc(p->capnames, sizeof *p->names);
		if (!p->names) {
			p->names = oldn;
			p->capnames = old;
			return -1;
		}
		for (uint32_t i = 0; i < old; i++)
			if (oldn[i])
				*name_slot(p, p->a->anim[oldn[i] - 1].name) = oldn[i];
		free(oldn);
	}
	*name_slot(p, p->a->anim[k].name) = k + 1;
	return 0;
}

/* transl|rot|scale n and its n rows: time, value (3, or axis and angle),
 * tension, continuity, bias. */
static int rd_track(parser *p, lexer *lx, const tok *kind, aff_track *tr)
{
	int rot = tok_is(kind, "rot");
	int nv = rot ? 4 : 3;
	if (tr->n)
		return perr(lx, kind, p->d, "a second '%.*s' track in one keyframe block",
		            (int)kind->n, kind->s);
	uint32_t n;
	if (rd_uint(p, lx, KB_MIN_KEYS, AFF_TRIS_MAX, &n,
	            "the number of keys (at least 4: the first and last shape the end tangents)") ||
	    count_fits(p, lx, &p->last, n, (uint32_t)(4 + nv)))
		return -1;
	if ((uint64_t)p->a->nkeys + n > AFF_KEYS_MAX)
		return perr(lx, &p->last, p->d, "the scene has more than %u keyframes",
		            AFF_KEYS_MAX);
	p->a->nkeys += n;
	tr->k = calloc(n, sizeof *tr->k);
	if (!tr->k || (rot && !(tr->q = calloc(4 * (size_t)n, sizeof *tr->q))))
		return oom(p, lx, kind);
	tr->n = n;
	for (uint32_t i = 0; i < n; i++) {
		kb_key *k = &tr->k[i];
		if (rd_num(p, lx, &k->t, "a key time") ||
		    rd_nums(p, lx, k->v, nv,
		            rot ? "a rotation axis component or angle" : "a key value"))
			return -1;
		if (rot && k->v[0] == 0.0 && k->v[1] == 0.0 && k->v[2] == 0.0)
			return perr(lx, &p->last, p->d, "rotation key about a zero axis");
		if (rd_num(p, lx, &k->tension, "a key tension") ||
		    rd_num(p, lx, &k->continuity, "a key continuity") ||
		    rd_num(p, lx, &k->bias, "a key bias"))
			return -1;
	}
	if (rot)
		kb_rot_quats(tr->k, n, tr->q);
	return 0;
}

static int parse_keys(parser *p, lexer *lx, const tok *at)
{
	aff_scene *a = p->a;
	if (grow(&a->anim, &a->capanim, (uint64_t)a->nanim + 1, sizeof *a->anim))
		return oom(p, lx, at);
	aff_anim *an = &a->anim[a->nanim];
	memset(an, 0, sizeof *an);
	a->nanim++; /* freed with the scene even when a track fails */
	tok t;
	if (rd_name(p, lx, &t, an->name, "a keyframe block name"))
		return -1;
	if (p->capnames && *name_slot(p, an->name))
		return perr(lx, &t, p->d, "keyframes for '%s' are given twice", an->name);
	if (expect_word(p, lx, "{"))
		return -1;
	for (;;) {
		if (need(p, lx, &t, "transl, rot, scale or '}'"))
			return -1;
		if (tok_is(&t, "}"))
			break;
		int kind = tok_is(&t, "transl")  ? AFF_TRANSL
		           : tok_is(&t, "rot")   ? AFF_ROT
		           : tok_is(&t, "scale") ? AFF_SCALE
		                                 : -1;
		if (kind < 0 && tok_is(&t, "visibility"))
			return perr(lx, &t, p->d, "visibility keys are not supported");
		if (kind < 0)
			return perr(lx, &t, p->d,
			            "expected transl, rot, scale or '}', found '%.*s'",
			            (int)(t.n > 40 ? 40 : t.n), t.s);
		if (rd_track(p, lx, &t, &an->tr[kind]))
			return -1;
	}
	if (name_add(p, a->nanim - 1))
		return oom(p, lx, at);
	if (!strcmp(an->name, "camera"))
		a->cam_anim = (int32_t)(a->nanim - 1);
	return 0;
}

/* ---- files and includes ---- */

static int parse_file(parser *p, const char *path, int depth, const lexer *from, const tok *at);

/* path read once (includes of the same file share it); at/from: the
 * include line that asks for it (NULL for the entry file). */
static int get_file(parser *p, const char *path, const lexer *from, const tok *at, aff_file **out)
{
	for (uint32_t i = 0; i < p->nfiles; i++) {
		if (!strcmp(p->files[i]->path, path)) {
			*out = p->files[i];
			goto count;
		}
	}
	const char *why = NULL;
	char err[256];
	struct stat st;
	int s = in_check(path);
	if (s)
		why = in_strerror(s);
	else if (stat(path, &st) == 0 && st.st_size > (off_t)AFF_FILE_MAX)
		why = "larger than the AFF file limit (64 MB)";
	else if (p->nfiles == AFF_FILES_MAX)
		why = "the scene reads more than 4096 files";
	aff_file *f = why ? NULL : calloc(1, sizeof *f);
	if (!why && !f)
		why = "out of memory";
	if (f && in_read_all(path, 0, &f->buf, &f->len, err, sizeof err)) {
		free(f);
		f = NULL;
		why = err;
	}
	if (!f) {
		if (!from)
			return diag_set(p->d, path, 0, 0, "cannot read AFF file: %s", why);
		return perr(from, at, p->d, "cannot read included file %s: %s", path, why);
	}
	snprintf(f->path, sizeof f->path, "%s", path);
	p->files[p->nfiles++] = f;
	p->a->nfiles = p->nfiles;
	if (p->fn)
		p->fn(p->ctx, path);
	*out = f;
count:
	p->a->bytes += (*out)->len;
	if (p->a->bytes > AFF_TOTAL_MAX) {
		if (!from)
			return diag_set(p->d, path, 0, 0, "AFF file too large");
		return perr(from, at, p->d,
		            "the scene reads more than %u MB over its includes (an include loop?)",
		            AFF_TOTAL_MAX >> 20);
	}
	return 0;
}

/* i level name: the file resolved against the including file's folder
 * (not the working directory), read in place unless level > detail. */
static int parse_include(parser *p, lexer *lx, const tok *at, int depth)
{
	uint32_t level;
	tok name;
	if (rd_uint(p, lx, 0, 1000000, &level, "the include's detail level") ||
	    need(p, lx, &name, "an include file name"))
		return -1;
	if (level > p->detail)
		return 0;
	char dir[1024], path[1024];
	dir_of(lx->file, dir, sizeof dir);
	int n = name.s[0] == '/' ? snprintf(path, sizeof path, "%.*s", (int)name.n, name.s)
	                         : snprintf(path, sizeof path, "%s%.*s", dir, (int)name.n, name.s);
	if (n >= (int)sizeof path || name.n >= sizeof path)
		return perr(lx, &name, p->d, "include path is too long");
	if (depth + 1 > AFF_INCLUDE_DEPTH)
		return perr(lx, at, p->d, "includes nested deeper than %d (an include cycle?)",
		            AFF_INCLUDE_DEPTH);
	if (++p->a->nincludes > AFF_INCLUDES_MAX)
		return perr(lx, at, p->d, "more than %u includes carried out", AFF_INCLUDES_MAX);
	return parse_file(p, path, depth + 1, lx, &name);
}

static int command(parser *p, lexer *lx, const tok *t, int depth, int base)
{
	aff_scene *a = p->a;
	if (tok_is(t, "v"))
		return parse_view(p, lx, t);
	if (tok_is(t, "am"))
		return rd_nums(p, lx, a->ambient, 3, "an ambient colour component");
	if (tok_is(t, "b"))
		return rd_nums(p, lx, a->background, 3, "a background colour component");
	if (tok_is(t, "l"))
		return parse_light(p, lx, t);
	if (tok_is(t, "a"))
		return parse_range(p, lx, t);
	if (tok_is(t, "fm") || tok_is(t, "f"))
		return parse_material(p, lx, t);
	if (tok_is(t, "m"))
		return parse_mesh(p, lx, t);
	if (tok_is(t, "p") || tok_is(t, "pp"))
		return parse_poly(p, lx, t);
	if (tok_is(t, "xs") || tok_is(t, "x"))
		return open_xform(p, lx, t);
	if (tok_is(t, "}"))
		return close_xform(p, lx, t, base);
	if (tok_is(t, "k"))
		return parse_keys(p, lx, t);
	if (tok_is(t, "i"))
		return parse_include(p, lx, t, depth);
	if (tok_is(t, "d")) {
		uint32_t v;
		if (rd_uint(p, lx, 0, 1000000, &v, "the detail level"))
			return -1;
		p->detail = v;
		return 0;
	}
	if (tok_is(t, "s") || tok_is(t, "c") || tok_is(t, "tpa") || tok_is(t, "tpp"))
		return perr(lx, t, p->d,
		            "AFF command '%.*s' is not supported (saarsim reads triangle meshes "
		            "and polygons: m, p, pp)",
		            (int)t->n, t->s);
	return perr(lx, t, p->d, "unknown AFF command '%.*s'", (int)(t->n > 40 ? 40 : t->n), t->s);
}

static int parse_file(parser *p, const char *path, int depth, const lexer *from, const tok *at)
{
	aff_file *f = NULL;
	if (get_file(p, path, from, at, &f))
		return -1;
	lexer lx = {f->path, f->buf, f->len, 0, 0, 1};
	int base = p->nest;
	for (;;) {
		tok t;
		int r = lx_next(&lx, &t, p->d);
		if (r < 0)
			return -1;
		if (r == 0) {
			if (p->nest > base)
				return perr(
				    &lx, &t, p->d,
				    "the transform block opened at line %d is not closed by "
				    "the end of the file",
				    p->open_line[p->nest - 1]);
			return 0;
		}
		if (command(p, &lx, &t, depth, base))
			return -1;
	}
}

int aff_is(const char *path)
{
	size_t n = path ? strlen(path) : 0;
	return n > 4 && !strcmp(path + n - 4, ".aff");
}

void aff_free(aff_scene *a)
{
	for (uint32_t i = 0; i < a->nanim; i++)
		for (int k = 0; k < AFF_NTRACKS; k++) {
			free(a->anim[i].tr[k].k);
			free(a->anim[i].tr[k].q);
		}
	free(a->anim);
	free(a->xf);
	free(a->mesh);
	free(a->pv);
	free(a->pn);
	free(a->puv);
	free(a->idx);
	free(a->mat);
	free(a->tex);
	memset(a, 0, sizeof *a);
	a->cam_anim = -1;
}

/* Each `x` finds its keyframes by name (they may come later in the
 * files); a name no block gives stays the identity, as in BART. */
static void bind_names(parser *p)
{
	aff_scene *a = p->a;
	for (uint32_t i = 0; i < a->nxf; i++) {
		aff_xform *x = &a->xf[i];
		if (x->animated && p->capnames) {
			uint32_t s = *name_slot(p, x->name);
			x->anim = s ? (int32_t)s - 1 : -1;
		}
	}
}

int aff_load(aff_scene *a, const char *path, scene_file_fn fn, void *ctx, diag *d)
{
	memset(a, 0, sizeof *a);
	a->cam_anim = -1;
	a->ambient[0] = a->ambient[1] = a->ambient[2] = 1.0;
	snprintf(a->path, sizeof a->path, "%s", path);
	parser *p = calloc(1, sizeof *p);
	if (!p)
		return diag_set(d, path, 0, 0, "out of memory");
	p->a = a;
	p->fn = fn;
	p->ctx = ctx;
	p->xf = p->mat = -1;
	p->d = d;
	dir_of(path, p->entry_dir, sizeof p->entry_dir);
	int rc = parse_file(p, path, 0, NULL, NULL);
	if (!rc)
		bind_names(p);
	for (uint32_t i = 0; i < p->nfiles; i++) {
		free(p->files[i]->buf);
		free(p->files[i]);
	}
	free(p->names);
	free(p);
	if (rc)
		aff_free(a);
	return rc;
}

/* ---- the scene at a time ---- */

/* The local matrix of keyframes an at time t: T(t) * R(t) * S(t), each
 * factor the identity where the block has no track for it. */
static void anim_local(const aff_anim *an, double t, double m[12])
{
	double s[3] = {1, 1, 1}, q[4] = {1, 0, 0, 0}, tr[3] = {0, 0, 0};
	const aff_track *k = an->tr;
	if (k[AFF_SCALE].n)
		kb_pos_eval(k[AFF_SCALE].k, k[AFF_SCALE].n, t, s);
	if (k[AFF_ROT].n)
		kb_rot_eval(k[AFF_ROT].k, k[AFF_ROT].q, k[AFF_ROT].n, t, q);
	if (k[AFF_TRANSL].n)
		kb_pos_eval(k[AFF_TRANSL].k, k[AFF_TRANSL].n, t, tr);
	m_trs(s, q, tr, m);
}

void aff_matrices(const aff_scene *a, double t, double *m)
{
	for (uint32_t i = 0; i < a->nxf; i++) {
		const aff_xform *x = &a->xf[i];
		double local[12];
		if (x->animated && x->anim >= 0)
			anim_local(&a->anim[x->anim], t, local);
		else
			memcpy(local, x->m, sizeof local);
		/* parents come first: their world matrix is ready */
		if (x->parent >= 0)
			m_mul(m + 12 * (size_t)x->parent, local, m + 12 * (size_t)i);
		else
			memcpy(m + 12 * (size_t)i, local, sizeof local);
	}
}

/* The scene material of (fm, texture) pair: one per distinct pair, found
 * through a hash table over the pairs' values (tab: 2^k slots holding
 * scene material + 1). */
typedef struct matmap {
	uint32_t *slot, cap;
	aff_mat *val;
	int32_t *tex;
} matmap;

static uint32_t mat_hash(const aff_mat *m, int32_t tex)
{
	const unsigned char *b = (const unsigned char *)m;
	uint32_t h = 2166136261u ^ (uint32_t)tex;
	for (size_t i = 0; i < sizeof *m; i++)
		h = (h ^ b[i]) * 16777619u;
	return h;
}

static uint32_t scene_mat(scene *s, matmap *mm, const aff_scene *a, const aff_mesh *me,
                          const int32_t *texmap)
{
	static const aff_mat none = {{0.2, 0.2, 0.2}, {0.8, 0.8, 0.8}, {0, 0, 0}, 10, 0, 0};
	const aff_mat *m = me->mat >= 0 ? &a->mat[me->mat] : &none;
	int32_t tex = me->tex >= 0 && texmap ? texmap[me->tex] : -1;
	uint32_t i = mat_hash(m, tex) & (mm->cap - 1);
	for (; mm->slot[i]; i = (i + 1) & (mm->cap - 1)) {
		uint32_t k = mm->slot[i] - 1;
		if (mm->tex[k] == tex && !memcmp(&mm->val[k], m, sizeof *m))
			return k;
	}
	char name[64];
	snprintf(name, sizeof name, "aff%u", s->nmats);
	material sm = material_default(name);
	sm.ka = v3((float)m->amb[0], (float)m->amb[1], (float)m->amb[2]);
	sm.kd = v3((float)m->diff[0], (float)m->diff[1], (float)m->diff[2]);
	sm.ks = v3((float)m->spec[0], (float)m->spec[1], (float)m->spec[2]);
	sm.ns = (float)m->shine;
	sm.transmit = m->transmit < 0 ? 0.0f : m->transmit > 1 ? 1.0f : (float)m->transmit;
	sm.ni = m->ior > 0 ? (float)m->ior : 1.0f; /* "ior 0" (most BART lines) means none */
	sm.tex_kd = tex;
	uint32_t k = scene_add_material(s, &sm);
	mm->val[k] = *m;
	mm->tex[k] = tex;
	mm->slot[i] = k + 1;
	return k;
}

/* Every texture the meshes name, read once into s->texs. */
static int load_textures(const aff_scene *a, scene *s, int32_t *texmap, diag *d)
{
	if (!a->ntex)
		return 0;
	s->texs = calloc(a->ntex, sizeof *s->texs);
	if (!s->texs)
		return diag_set(d, a->path, 0, 0, "out of memory for textures");
	for (uint32_t i = 0; i < a->ntex; i++) {
		texture *t = &s->texs[i];
		memcpy(t->path, a->tex[i].path, sizeof t->path);
		diag td;
		if (img_read_rgba8(t->path, &t->w, &t->h, &t->rgba, &td))
			return diag_set(d, a->tex[i].where, 0, 0, "texture %s", td.msg);
		s->ntexs = i + 1;
		texmap[i] = (int32_t)i;
	}
	return 0;
}

/* The triangles of mesh me under world matrix m. */
static void add_mesh_tris(const aff_scene *a, const aff_mesh *me, const double m[12], uint32_t mat,
                          scene *s)
{
	double nm[9];
	xf_normal_matrix(m, nm);
	for (uint32_t i = 0; i < me->ntris; i++) {
		const uint32_t *r = a->idx + 9 * (uint64_t)(me->t0 + i);
		vec3 p[3], n[3];
		vec2 uv[3];
		for (int k = 0; k < 3; k++) {
			p[k] = xf_point(m, a->pv + 3 * (uint64_t)(me->v0 + r[k]));
			if (me->nn)
				n[k] = xf_normal(nm, a->pn + 3 * (uint64_t)(me->n0 + r[3 + k]));
			if (me->nuv) {
				const float *q = a->puv + 2 * (uint64_t)(me->uv0 + r[6 + k]);
				uv[k] = (vec2){q[0], q[1]};
			}
		}
		scene_add_triangle(s, p, me->nn ? n : NULL, me->nuv ? uv : NULL, mat);
	}
	if (me->nuv)
		s->has_uv = 1;
}

/* aff_flatten, or with `local` every mesh in its own node's frame. */
static int flatten(const aff_scene *a, double t, int textures, int local, scene *s, diag *d)
{
	scene_init(s, a->path);
	double *m = malloc(12 * ((size_t)a->nxf + 1) * sizeof *m);
	int32_t *texmap = calloc((size_t)a->ntex + 1, sizeof *texmap);
	matmap mm = {NULL, 16, NULL, NULL};
	while (mm.cap < 2 * ((uint64_t)a->nmesh + 1))
		mm.cap *= 2;
	mm.slot = calloc(mm.cap, sizeof *mm.slot);
	mm.val = malloc(((size_t)a->nmesh + 1) * sizeof *mm.val);
	mm.tex = malloc(((size_t)a->nmesh + 1) * sizeof *mm.tex);
	int rc = -1;
	if (!m || !texmap || !mm.slot || !mm.val || !mm.tex) {
		diag_set(d, a->path, 0, 0, "out of memory flattening the scene");
		goto done;
	}
	if (textures && load_textures(a, s, texmap, d))
		goto done;
	aff_matrices(a, t, m);
	double id[12];
	m_identity(id);
	for (uint32_t i = 0; i < a->nmesh; i++) {
		const aff_mesh *me = &a->mesh[i];
		uint32_t mat = scene_mat(s, &mm, a, me, textures ? texmap : NULL);
		add_mesh_tris(a, me, me->xform >= 0 && !local ? m + 12 * (size_t)me->xform : id,
		              mat, s);
	}
	rc = scene_finish(s, a->path, d);
done:
	free(m);
	free(texmap);
	free(mm.slot);
	free(mm.val);
	free(mm.tex);
	if (rc) {
		scene_free(s);
		scene_init(s, a->path);
	}
	return rc;
}

int aff_flatten(const aff_scene *a, double t, int textures, scene *s, diag *d)
{
	return flatten(a, t, textures, 0, s, d);
}

int aff_flatten_local(const aff_scene *a, int textures, scene *s, diag *d)
{
	return flatten(a, 0.0, textures, 1, s, d);
}

int aff_view(const aff_scene *a, double t, view *v, diag *d)
{
	if (!a->has_view && a->cam_anim < 0)
		return 0;
	memset(v, 0, sizeof *v);
	snprintf(v->name, sizeof v->name, "%s", a->cam_anim >= 0 ? "aff-camera" : "aff-v");
	double eye[3] = {0, 0, 0}, dir[3] = {0, 0, -1}, up[3] = {0, 1, 0};
	double fov = a->has_view ? a->angle : 45.0;
	if (a->has_view)
		for (int i = 0; i < 3; i++) {
			eye[i] = a->from[i];
			dir[i] = a->at[i] - a->from[i];
			up[i] = a->up[i];
		}
	if (a->cam_anim >= 0) {
		const aff_track *k = a->anim[a->cam_anim].tr;
		if (k[AFF_TRANSL].n)
			kb_pos_eval(k[AFF_TRANSL].k, k[AFF_TRANSL].n, t, eye);
		if (k[AFF_ROT].n) {
			/* the camera looks down its local -z with +y up */
			double q[4], r[9];
			kb_rot_eval(k[AFF_ROT].k, k[AFF_ROT].q, k[AFF_ROT].n, t, q);
			kb_quat_matrix(q, r);
			for (int i = 0; i < 3; i++) {
				dir[i] = -r[3 * i + 2];
				up[i] = r[3 * i + 1];
			}
		}
	}
	camera *c = &v->cam;
	c->eye = v3((float)eye[0], (float)eye[1], (float)eye[2]);
	c->lookat =
	    v3((float)(eye[0] + dir[0]), (float)(eye[1] + dir[1]), (float)(eye[2] + dir[2]));
	c->up = v3((float)up[0], (float)up[1], (float)up[2]);
	c->fov_deg = (float)fov;
	if (camera_validate(c, a->path, d))
		return -1;
	v->nlights = a->nlights;
	for (int i = 0; i < a->nlights; i++) {
		const double *l = a->light[i];
		v->lights[i].pos = v3((float)l[0], (float)l[1], (float)l[2]);
		v->lights[i].color = v3((float)l[3], (float)l[4], (float)l[5]);
	}
	v->lights_given = a->nlights > 0;
	return 1;
}
