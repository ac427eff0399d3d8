/*
 * importproc.c: scene_load and scene_load_files, the scene import on a
 * leash (docs/design.md, "Third-party parsers").
 *
 * Assimp, and OpenImageIO for the textures, run in a forked child process
 * under a CPU limit (RLIMIT_CPU) and an address-space limit (RLIMIT_AS: the
 * child's size at the fork plus a budget), so a file that makes them loop,
 * allocate without end or crash costs one error line instead of the run.
 * The child runs import_body (import.c), writes the scene (or its one-line
 * error) into a pipe and _exits; the parent reads it with every size
 * checked against what the child announced and against the bytes that
 * actually arrive, under a wall-clock deadline, and turns every other end
 * of the child into one line. The child's stdout and stderr go to a second
 * pipe: a sanitizer's report found there is passed on, Assimp's chatter is
 * dropped.
 *
 * Why a pipe and not a temporary file: nothing to create, clean up or find
 * room for (a killed child leaves nothing behind), and the parent can wait
 * on the result and the stderr pipe together with poll(), which is also
 * where the deadline is kept.
 */
#define _GNU_SOURCE /* pipe2, F_SETPIPE_SZ */
#include "kernel-ref/import.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* Default limits. The largest shared scene (Stanford dragon res2, 202,520
 * triangles, 7.2 MB of OBJ in 2.2 MB of gzip) imports in 0.2 s of CPU
 * (0.7 s under ASan) and peaks at 70 MB above the process's size. */
#define IMP_CPU_DEFAULT_S  120
#define IMP_CPU_MAX_S      86400
#define IMP_MEM_DEFAULT_MB 4096
#define IMP_MEM_PER_BYTE   64 /* and at least this many times the file's size */
#define IMP_MEM_MAX_MB     (1ull << 24)
/* Wall clock: twice the CPU limit and this much more. */
#define IMP_WALL_EXTRA_S 5

#define IMP_ERR_KEEP   (256 * 1024) /* of the child's stderr */
#define IMP_MAX_PATHS  65536
#define IMP_MAX_PATH   4096
#define IMP_MAX_PIXELS (1ull << 28) /* the image plugin's limit */

static const char IMP_MAGIC[8] = {'S', 'A', 'A', 'R', 'I', 'M', 'P', '1'};
static const char IMP_END[8] = {'S', 'A', 'A', 'R', 'E', 'N', 'D', '1'};

enum { ST_OK = 0, ST_FAIL = 1, ST_FAIL_OOM = 2 };

typedef struct imp_limits {
	unsigned long long cpu_s, mem_mb;
} imp_limits;

/* ---- limits ---- */

/* An environment variable holding a whole number in [lo, hi]: 0 with *out
 * set (or left when the variable is unset or empty), or -1 with d. */
static int env_num(const char *name, unsigned long long lo, unsigned long long hi, const char *unit,
                   unsigned long long *out, diag *d)
{
	const char *v = getenv(name);
	if (!v || !*v)
		return 0;
	char *end;
	errno = 0;
	unsigned long long x = strtoull(v, &end, 10);
	if (!isdigit((unsigned char)v[0]) || *end || errno || x < lo || x > hi)
		return diag_set(d, name, 0, 0,
		                "'%.40s' is not a whole number of %s from %llu to %llu", v, unit,
		                lo, hi);
	*out = x;
	return 0;
}

/* The size of the file an import of path reads first (path, or path.gz
 * when only that exists, as import.c maps it), 0 if there is none. */
static unsigned long long scene_file_size(const char *path)
{
	struct stat st;
	if (stat(path, &st) == 0)
		return (unsigned long long)st.st_size;
	char gz[IMP_MAX_PATH];
	int n = snprintf(gz, sizeof gz, "%s.gz", path);
	if (n > 0 && (size_t)n < sizeof gz && stat(gz, &st) == 0)
		return (unsigned long long)st.st_size;
	return 0;
}

static int limits_get(imp_limits *lim, const char *path, diag *d)
{
	lim->cpu_s = IMP_CPU_DEFAULT_S;
	unsigned long long mb = (scene_file_size(path) * IMP_MEM_PER_BYTE + (1 << 20) - 1) >> 20;
	lim->mem_mb = mb > IMP_MEM_DEFAULT_MB ? (mb < IMP_MEM_MAX_MB ? mb : IMP_MEM_MAX_MB)
	                                      : IMP_MEM_DEFAULT_MB;
	if (env_num("SAARSIM_IMPORT_CPU_S", 1, IMP_CPU_MAX_S, "seconds", &lim->cpu_s, d))
		return -1;
	return env_num("SAARSIM_IMPORT_MEM_MB", 1, IMP_MEM_MAX_MB, "megabytes", &lim->mem_mb, d);
}

/* ---- the child ---- */

typedef struct wr {
	int fd, failed;
	size_t n;
	unsigned char b[1 << 16];
} wr;

static void wr_raw(wr *w, const void *p, size_t n)
{
	const char *c = p;
	while (n && !w->failed) {
		ssize_t k = write(w->fd, c, n);
		if (k < 0 && errno == EINTR)
			continue;
		if (k <= 0) {
			w->failed = 1;
			return;
		}
		c += k;
		n -= (size_t)k;
	}
}

static void wr_flush(wr *w)
{
	wr_raw(w, w->b, w->n);
	w->n = 0;
}

static void wr_put(wr *w, const void *p, size_t n)
{
	if (w->n + n > sizeof w->b) {
		wr_flush(w);
		if (n >= sizeof w->b) {
			wr_raw(w, p, n);
			return;
		}
	}
	memcpy(w->b + w->n, p, n);
	w->n += n;
}

static void wr_u32(wr *w, uint32_t v)
{
	wr_put(w, &v, sizeof v);
}

static void wr_str(wr *w, const char *s)
{
	size_t n = strlen(s);
	wr_u32(w, (uint32_t)n);
	wr_put(w, s, n);
}

typedef struct pathlist {
	char **p;
	uint32_t n, cap;
	int lost; /* a name could not be kept */
} pathlist;

/* Adds path to the list the parent gets. A name that cannot be kept (the
 * list full, too long, out of memory) is not dropped in silence: the list
 * ends with an empty name (child_main), which the parent's watch cannot
 * resolve (wc_files_add: the world is then not stored), instead of a file
 * left unwatched. */
static void pl_add(void *ctx, const char *path)
{
	pathlist *pl = ctx;
	if (pl->n + 1 >= IMP_MAX_PATHS || strlen(path) >= IMP_MAX_PATH) {
		pl->lost = 1; /* the last slot is the empty name's */
		return;
	}
	if (pl->n == pl->cap) {
		uint32_t cap = pl->cap ? 2 * pl->cap : 16;
		char **np = realloc(pl->p, cap * sizeof *np);
		if (!np) {
			pl->lost = 1;
			return;
		}
		pl->p = np;
		pl->cap = cap;
	}
	char *c = strdup(path);
	if (c)
		pl->p[pl->n++] = c;
	else
		pl->lost = 1;
}

static void pl_free(pathlist *pl)
{
	for (uint32_t i = 0; i < pl->n; i++)
		free(pl->p[i]);
	free(pl->p);
	memset(pl, 0, sizeof *pl);
}

static void wr_scene(wr *w, const scene *s);

/* Test-only faults (docs/design.md): SAAR_IMPORT_FAULT makes the child
 * misbehave the ways a third-party parser can (spin, hog, crash, hang,
 * exit), or send a result that lies about its size (lie), to test the
 * leash and the parent's reading. Read here only, in the child. */
static void *volatile hog_last;

static int fault(wr *w, const char *path, int *oom, diag *d)
{
	const char *f = getenv("SAAR_IMPORT_FAULT");
	if (!f || !*f)
		return 0;
	if (!strcmp(f, "lie")) {
		/* a triangle count worth 17 GB of arrays, and 1 KB of them */
		static char some[1024];
		uint32_t hdr[5] = {UINT32_MAX / 3, 1, 0, 0, 0};
		aabb b = {{0, 0, 0}, {0, 0, 0}};
		wr_put(w, IMP_MAGIC, sizeof IMP_MAGIC);
		wr_u32(w, ST_OK);
		wr_put(w, hdr, sizeof hdr);
		wr_put(w, &b, sizeof b);
		wr_str(w, path);
		wr_put(w, some, sizeof some);
		wr_flush(w);
		_exit(0);
	}
	if (!strcmp(f, "spin"))
		for (volatile unsigned long i = 0;; i++)
			;
	if (!strcmp(f, "hog")) {
		/* 16 MB blocks are mmap'd, by glibc and by ASan alike, so
		 * each counts against RLIMIT_AS */
		for (void **p; (p = malloc(16u << 20));) {
			*p = hog_last;
			hog_last = p;
		}
		*oom = 1;
		return diag_set(d, path, 0, 0, "out of memory (SAAR_IMPORT_FAULT=hog)");
	}
	if (!strcmp(f, "crash")) {
		signal(SIGSEGV, SIG_DFL); /* past a sanitizer's handler */
		raise(SIGSEGV);
		_exit(5);
	}
	if (!strcmp(f, "hang"))
		for (;;)
			pause();
	if (!strcmp(f, "exit"))
		_exit(1);
	return diag_set(d, "SAAR_IMPORT_FAULT", 0, 0,
	                "unknown fault '%.40s' (spin, hog, crash, hang, exit or lie)", f);
}

/* The child's limits: CPU seconds, and its address space now plus the
 * budget (so that a sanitizer's shadow reservation, terabytes of address
 * space, does not count against it). */
static int child_limits(const imp_limits *lim, const char *path, diag *d)
{
	struct rlimit r = {0, 0};
	setrlimit(RLIMIT_CORE, &r); /* a crash on a bad file leaves no core */
	/* soft: SIGXCPU; hard, a second later: SIGKILL (never above a hard
	 * limit the process already has) */
	rlim_t hard = getrlimit(RLIMIT_CPU, &r) == 0 ? r.rlim_max : RLIM_INFINITY;
	r.rlim_cur = hard != RLIM_INFINITY && hard < lim->cpu_s ? hard : lim->cpu_s;
	r.rlim_max = hard != RLIM_INFINITY && hard < lim->cpu_s + 1 ? hard : lim->cpu_s + 1;
	if (setrlimit(RLIMIT_CPU, &r) != 0)
		return diag_set(d, path, 0, 0, "cannot set the importer's CPU limit: %s",
		                strerror(errno));
	unsigned long long pages = 0;
	FILE *f = fopen("/proc/self/statm", "r");
	int ok = f && fscanf(f, "%llu", &pages) == 1;
	if (f)
		fclose(f);
	long psz = sysconf(_SC_PAGESIZE);
	if (!ok || psz <= 0)
		return diag_set(
		    d, path, 0, 0,
		    "cannot set the importer's memory limit: /proc/self/statm unreadable");
	unsigned long long now = pages * (unsigned long long)psz, budget = lim->mem_mb << 20;
	unsigned long long as = now + budget < now ? RLIM_INFINITY : now + budget;
	if (getrlimit(RLIMIT_AS, &r) != 0)
		return diag_set(d, path, 0, 0, "cannot set the importer's memory limit: %s",
		                strerror(errno));
	if (r.rlim_max == RLIM_INFINITY || as < r.rlim_max)
		r.rlim_cur = as;
	else
		r.rlim_cur = r.rlim_max;
	if (setrlimit(RLIMIT_AS, &r) != 0)
		return diag_set(d, path, 0, 0, "cannot set the importer's memory limit: %s",
		                strerror(errno));
	return 0;
}

static void wr_scene(wr *w, const scene *s)
{
	uint32_t hdr[5] = {s->ntris, s->nmats, s->ntexs, (uint32_t)s->has_uv, s->ndegenerate};
	wr_put(w, hdr, sizeof hdr);
	wr_put(w, &s->bounds, sizeof s->bounds);
	wr_str(w, s->name);
	size_t k = 3 * (size_t)s->ntris;
	wr_put(w, s->v, k * sizeof *s->v);
	wr_put(w, s->n, k * sizeof *s->n);
	wr_put(w, s->uv, k * sizeof *s->uv);
	wr_put(w, s->mat, s->ntris * sizeof *s->mat);
	wr_put(w, s->mats, s->nmats * sizeof *s->mats);
	for (uint32_t i = 0; i < s->ntexs; i++) {
		const texture *t = &s->texs[i];
		wr_str(w, t->path);
		int32_t wh[2] = {t->w, t->h};
		wr_put(w, wh, sizeof wh);
		wr_put(w, t->rgba, (size_t)t->w * (size_t)t->h * 4);
	}
}

/* The child: the import and nothing else, then _exit (no atexit handlers,
 * no stdio buffers it inherited flushed twice). */
static _Noreturn void child_main(const char *path, int want_files, const imp_limits *lim,
                                 pid_t parent, int res_fd, int err_fd)
{
	/* stdout and stderr into the parent's capture (the result pipe is
	 * moved out of the way first should it be fd 1 or 2) */
	if (res_fd <= 2 && (res_fd = fcntl(res_fd, F_DUPFD_CLOEXEC, 3)) < 0)
		_exit(4);
	if ((err_fd != 1 && dup2(err_fd, 1) < 0) || (err_fd != 2 && dup2(err_fd, 2) < 0))
		_exit(4);
	if (err_fd > 2)
		close(err_fd);
	/* the import ends with the parent: a killed run leaves no child
	 * spinning on a file */
	prctl(PR_SET_PDEATHSIG, SIGKILL);
	if (getppid() != parent)
		_exit(4);
	/* the CPU limit's SIGXCPU must end it whatever the parent had */
	sigset_t none;
	sigemptyset(&none);
	sigprocmask(SIG_SETMASK, &none, NULL);
	signal(SIGXCPU, SIG_DFL);
	signal(SIGPIPE, SIG_DFL);
	diag_quiet_off(); /* fd 2 is the capture now */

	static wr w;
	w.fd = res_fd;
	pathlist pl = {0};
	scene s;
	scene_init(&s, path);
	diag d;
	int oom = 0;
	int rc = child_limits(lim, path, &d);
	if (!rc)
		rc = fault(&w, path, &oom, &d);
	if (!rc)
		rc = import_body(&s, path, want_files ? pl_add : NULL, &pl, &oom, &d);
	wr_put(&w, IMP_MAGIC, sizeof IMP_MAGIC);
	wr_u32(&w, rc == 0 ? ST_OK : oom ? ST_FAIL_OOM : ST_FAIL);
	if (rc == 0)
		wr_scene(&w, &s);
	else
		wr_str(&w, d.msg);
	wr_u32(&w, pl.n + (uint32_t)pl.lost);
	for (uint32_t i = 0; i < pl.n; i++)
		wr_str(&w, pl.p[i]);
	if (pl.lost)
		wr_str(&w, "");
	wr_put(&w, IMP_END, sizeof IMP_END);
	wr_flush(&w);
	_exit(w.failed ? 3 : 0);
}

/* ---- the parent ---- */

typedef struct rd {
	int fd, efd;     /* the result and stderr pipes, -1 once they end */
	double deadline; /* CLOCK_MONOTONIC seconds */
	int timed_out;   /* the deadline passed */
	int nomem;       /* the parent ran out of memory receiving */
	size_t got;      /* result bytes read */
	const char *bad; /* what was malformed */
	char *err;       /* the child's stderr: its first IMP_ERR_KEEP bytes */
	size_t nerr;
	size_t pos, len;
	unsigned char b[1 << 16];
} rd;

static double mono(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Reads what the child wrote to stderr; the part past IMP_ERR_KEEP is
 * read and dropped. */
static void rd_stderr(rd *r)
{
	char tmp[4096];
	ssize_t k = read(r->efd, tmp, sizeof tmp);
	if (k < 0 && (errno == EINTR || errno == EAGAIN))
		return;
	if (k <= 0) {
		close(r->efd);
		r->efd = -1;
		return;
	}
	size_t room = IMP_ERR_KEEP - r->nerr, n = (size_t)k < room ? (size_t)k : room;
	if (r->err && n) {
		memcpy(r->err + r->nerr, tmp, n);
		r->nerr += n;
		r->err[r->nerr] = '\0';
	}
}

/* Waits until the result pipe has bytes or ends (1), reading stderr
 * meanwhile; 0 when the result pipe ended before, or the deadline passed
 * (timed_out). With fd < 0 it waits for stderr alone to end. */
static int rd_wait(rd *r)
{
	for (;;) {
		if (r->fd < 0 && r->efd < 0)
			return 0;
		struct pollfd pf[2];
		int n = 0, ri = -1, ei = -1;
		if (r->fd >= 0) {
			pf[n] = (struct pollfd){r->fd, POLLIN, 0};
			ri = n++;
		}
		if (r->efd >= 0) {
			pf[n] = (struct pollfd){r->efd, POLLIN, 0};
			ei = n++;
		}
		double left = r->deadline - mono();
		if (left <= 0) {
			r->timed_out = 1;
			return 0;
		}
		int k = poll(pf, (nfds_t)n, left > 3600 ? 3600000 : (int)(left * 1000) + 1);
		if (k < 0 && errno != EINTR)
			return 0;
		if (k <= 0)
			continue;
		if (ei >= 0 && pf[ei].revents)
			rd_stderr(r);
		if (ri >= 0 && pf[ri].revents)
			return 1;
	}
}

/* Some bytes (1..n) into dst, from the buffer or the pipe (large reads
 * straight into dst); -1 when the pipe ended or the deadline passed. */
static long rd_some(rd *r, void *dst, size_t n)
{
	while (r->pos == r->len) {
		if (r->fd < 0 || !rd_wait(r))
			return -1;
		int direct = n >= sizeof r->b;
		size_t cap = direct ? (n < (1u << 30) ? n : (1u << 30)) : sizeof r->b;
		ssize_t k = read(r->fd, direct ? dst : (void *)r->b, cap);
		if (k < 0 && (errno == EINTR || errno == EAGAIN))
			continue;
		if (k <= 0) {
			close(r->fd);
			r->fd = -1;
			return -1;
		}
		r->got += (size_t)k;
		if (direct)
			return (long)k;
		r->pos = 0;
		r->len = (size_t)k;
	}
	size_t k = r->len - r->pos < n ? r->len - r->pos : n;
	memcpy(dst, r->b + r->pos, k);
	r->pos += k;
	return (long)k;
}

static int rd_get(rd *r, void *dst, size_t n)
{
	for (char *c = dst; n;) {
		long k = rd_some(r, c, n);
		if (k < 0)
			return -1;
		c += k;
		n -= (size_t)k;
	}
	return 0;
}

static int rd_u32(rd *r, uint32_t *v)
{
	return rd_get(r, v, sizeof *v);
}

static int rd_fail(rd *r, const char *what)
{
	if (!r->bad)
		r->bad = what;
	return -1;
}

/* A string of fewer than cap bytes, without NULs, into dst. */
static int rd_str(rd *r, char *dst, size_t cap, const char *what)
{
	uint32_t n;
	if (rd_u32(r, &n))
		return -1;
	if (n >= cap)
		return rd_fail(r, what);
	if (rd_get(r, dst, n))
		return -1;
	dst[n] = '\0';
	return strlen(dst) == n ? 0 : rd_fail(r, what);
}

/* count elements of size sz into a new array. The array grows as the
 * bytes arrive, so an announced count the child does not send never
 * becomes an allocation. */
static int rd_array(rd *r, void **out, size_t sz, uint64_t count)
{
	*out = NULL;
	if (count == 0)
		return 0;
	if (count > SIZE_MAX / 2 / sz)
		return rd_fail(r, "an array's size overflows");
	size_t total = (size_t)count * sz, have = 0, cap = 0;
	unsigned char *p = NULL;
	while (have < total) {
		if (have == cap) {
			size_t ncap = cap ? 2 * cap : (size_t)1 << 20;
			if (ncap > total)
				ncap = total;
			unsigned char *np = realloc(p, ncap);
			if (!np) {
				free(p);
				r->nomem = 1;
				return -1;
			}
			p = np;
			cap = ncap;
		}
		long k = rd_some(r, p + have, cap - have);
		if (k < 0) {
			free(p);
			return -1;
		}
		have += (size_t)k;
	}
	*out = p;
	return 0;
}

/* Does the scene the child sent hold together (every index in range,
 * every string ended)? NULL, or what does not. */
static const char *scene_bad(const scene *s)
{
	for (uint32_t t = 0; t < s->ntris; t++)
		if (s->mat[t] >= s->nmats)
			return "a material index out of range";
	for (uint32_t i = 0; i < s->nmats; i++) {
		const material *m = &s->mats[i];
		if (!memchr(m->name, '\0', sizeof m->name))
			return "an unterminated material name";
		if (m->tex_kd < -1 || m->tex_kd >= (int32_t)s->ntexs || m->tex_bump < -1 ||
		    m->tex_bump >= (int32_t)s->ntexs)
			return "a texture index out of range";
	}
	return NULL;
}

static int rd_scene(rd *r, scene *s)
{
	uint32_t hdr[5];
	if (rd_get(r, hdr, sizeof hdr) || rd_get(r, &s->bounds, sizeof s->bounds))
		return -1;
	uint32_t ntris = hdr[0], nmats = hdr[1], ntexs = hdr[2];
	if (ntris == 0 || ntris > UINT32_MAX / 3 || nmats == 0 || nmats > ntris + 1ull ||
	    ntexs > 2ull * nmats || hdr[3] > 1)
		return rd_fail(r, "counts out of range");
	if (rd_str(r, s->name, sizeof s->name, "a scene name too long"))
		return -1;
	s->has_uv = (int)hdr[3];
	s->ndegenerate = hdr[4];
	uint64_t k = 3 * (uint64_t)ntris;
	void *p;
	/* each array is the scene's as soon as it is in: scene_free frees
	 * what arrived if a later one does not */
	if (rd_array(r, &p, sizeof *s->v, k))
		return -1;
	s->v = p;
	if (rd_array(r, &p, sizeof *s->n, k))
		return -1;
	s->n = p;
	if (rd_array(r, &p, sizeof *s->uv, k))
		return -1;
	s->uv = p;
	if (rd_array(r, &p, sizeof *s->mat, ntris))
		return -1;
	s->mat = p;
	s->ntris = s->cap = ntris;
	if (rd_array(r, &p, sizeof *s->mats, nmats))
		return -1;
	s->mats = p;
	s->nmats = nmats;
	if (ntexs) {
		s->texs = calloc(ntexs, sizeof *s->texs);
		if (!s->texs) {
			r->nomem = 1;
			return -1;
		}
	}
	for (uint32_t i = 0; i < ntexs; i++) {
		texture *t = &s->texs[i];
		int32_t wh[2];
		if (rd_str(r, t->path, sizeof t->path, "a texture path too long") ||
		    rd_get(r, wh, sizeof wh))
			return -1;
		if (wh[0] < 1 || wh[1] < 1 || (uint64_t)wh[0] * (uint64_t)wh[1] > IMP_MAX_PIXELS)
			return rd_fail(r, "a texture size out of range");
		t->w = wh[0];
		t->h = wh[1];
		s->ntexs = i + 1;
		if (rd_array(r, &p, 4, (uint64_t)wh[0] * (uint64_t)wh[1]))
			return -1;
		t->rgba = p;
	}
	const char *why = scene_bad(s);
	return why ? rd_fail(r, why) : 0;
}

/* The child's whole message: its status, the scene or its error (cd), the
 * files it opened (pl). 0 when all of it arrived and holds together. */
static int rd_result(rd *r, scene *s, uint32_t *status, diag *cd, pathlist *pl)
{
	char magic[sizeof IMP_MAGIC];
	if (rd_get(r, magic, sizeof magic))
		return -1;
	if (memcmp(magic, IMP_MAGIC, sizeof magic))
		return rd_fail(r, "no header");
	if (rd_u32(r, status))
		return -1;
	if (*status == ST_OK) {
		if (rd_scene(r, s))
			return -1;
	} else if (*status == ST_FAIL || *status == ST_FAIL_OOM) {
		if (rd_str(r, cd->msg, sizeof cd->msg, "an error message too long"))
			return -1;
	} else {
		return rd_fail(r, "an unknown status");
	}
	uint32_t n;
	if (rd_u32(r, &n))
		return -1;
	if (n > IMP_MAX_PATHS)
		return rd_fail(r, "too many file names");
	if (n && !(pl->p = calloc(n, sizeof *pl->p))) {
		r->nomem = 1;
		return -1;
	}
	char path[IMP_MAX_PATH];
	for (uint32_t i = 0; i < n; i++) {
		if (rd_str(r, path, sizeof path, "a file name too long"))
			return -1;
		if (!(pl->p[i] = strdup(path))) {
			r->nomem = 1;
			return -1;
		}
		pl->n = i + 1;
	}
	if (rd_get(r, magic, sizeof magic))
		return -1;
	if (memcmp(magic, IMP_END, sizeof magic))
		return rd_fail(r, "no end marker");
	/* nothing may follow */
	return rd_some(r, magic, 1) < 0 && !r->timed_out ? 0 : rd_fail(r, "bytes after the end");
}

/* Waits for the child to end, until the deadline; then kills it. */
static void reap(pid_t pid, double deadline, int *status, struct rusage *ru, int *killed)
{
	for (long ns = 1000000;;) {
		pid_t k = wait4(pid, status, WNOHANG, ru);
		if (k == pid)
			return;
		if (k < 0 && errno != EINTR) {
			*status = -1; /* reaped by someone else (a SIGCHLD handler) */
			return;
		}
		if (k == 0 && mono() >= deadline) {
			kill(pid, SIGKILL);
			*killed = 1;
			while (wait4(pid, status, 0, ru) < 0 && errno == EINTR)
				;
			return;
		}
		struct timespec t = {0, ns};
		nanosleep(&t, NULL);
		if (ns < 20000000)
			ns *= 2;
	}
}

static int mem_text(const char *e)
{
	static const char *const marks[] = {"bad_alloc",
	                                    "out of memory",
	                                    "failed to allocate",
	                                    "allocation-size-too-big",
	                                    "requested allocation size",
	                                    "Cannot allocate memory"};
	for (size_t i = 0; e && i < sizeof marks / sizeof marks[0]; i++)
		if (strstr(e, marks[i]))
			return 1;
	return 0;
}

static int sanitizer_text(const char *e)
{
	static const char *const marks[] = {
	    "AddressSanitizer", "LeakSanitizer",   "UndefinedBehaviorSanitizer",
	    "runtime error:",   "ThreadSanitizer", "MemorySanitizer"};
	for (size_t i = 0; e && i < sizeof marks / sizeof marks[0]; i++)
		if (strstr(e, marks[i]))
			return 1;
	return 0;
}

static void mem_line(diag *d, const char *path, const imp_limits *lim)
{
	diag_set(d, path, 0, 0,
	         "cannot import scene: the importer (Assimp) exceeded its %llu MB memory limit; "
	         "SAARSIM_IMPORT_MEM_MB raises it",
	         lim->mem_mb);
}

/* The one line for a child that ended without a whole result and exit
 * status 0 (st: its wait status, -1 unknown; killed: at the deadline),
 * after the sanitizer's report it left, if any. */
static void abnormal_line(diag *d, const char *path, const imp_limits *lim, const rd *r, int st,
                          int killed, const struct rusage *ru)
{
	if (r->nerr && sanitizer_text(r->err)) {
		fflush(stderr);
		fputs(r->err, stderr);
		if (r->err[r->nerr - 1] != '\n')
			fputc('\n', stderr);
		fflush(stderr);
	}
	double cpu = (double)ru->ru_utime.tv_sec + 1e-6 * (double)ru->ru_utime.tv_usec +
	             (double)ru->ru_stime.tv_sec + 1e-6 * (double)ru->ru_stime.tv_usec;
	int sig = st != -1 && WIFSIGNALED(st) ? WTERMSIG(st) : 0;
	if (killed)
		diag_set(d, path, 0, 0,
		         "cannot import scene: the importer (Assimp) was stopped after %llu s of "
		         "wall-clock time (twice its CPU limit and %d s); SAARSIM_IMPORT_CPU_S "
		         "raises it",
		         2 * lim->cpu_s + IMP_WALL_EXTRA_S, IMP_WALL_EXTRA_S);
	else if (sig == SIGXCPU || (sig == SIGKILL && cpu >= (double)lim->cpu_s))
		diag_set(d, path, 0, 0,
		         "cannot import scene: the importer (Assimp) used its %llu s CPU limit on "
		         "it; SAARSIM_IMPORT_CPU_S raises it",
		         lim->cpu_s);
	else if (mem_text(r->err))
		mem_line(d, path, lim);
	else if (r->bad)
		diag_set(d, path, 0, 0,
		         "cannot import scene: the importer process sent a malformed result (%s)",
		         r->bad);
	else if (sig)
		diag_set(d, path, 0, 0,
		         "cannot import scene: the importer (Assimp) crashed on it (%s); the file "
		         "is malformed",
		         strsignal(sig));
	else if (st == -1)
		diag_set(d, path, 0, 0,
		         "cannot import scene: the importer process ended without a result (its "
		         "status was taken by a SIGCHLD handler)");
	else
		diag_set(d, path, 0, 0,
		         "cannot import scene: the importer process ended %s (exit status %d)",
		         r->got ? "before its result was complete" : "without a result",
		         WEXITSTATUS(st));
}

/* SIGCHLD ignored (or SA_NOCLDWAIT) makes children reap themselves and
 * their status unknowable: the default disposition is put back while the
 * child runs (1, old in *old). A handler the program installed stays. */
static int sigchld_default(struct sigaction *old)
{
	if (sigaction(SIGCHLD, NULL, old) != 0)
		return 0;
	if (old->sa_handler != SIG_IGN && !(old->sa_flags & SA_NOCLDWAIT))
		return 0;
	struct sigaction sa;
	memset(&sa, 0, sizeof sa);
	sa.sa_handler = SIG_DFL;
	sigemptyset(&sa.sa_mask);
	return sigaction(SIGCHLD, &sa, NULL) == 0;
}

/* The threads of this process (/proc/self/task), or 0 if unknown. */
static unsigned threads_now(void)
{
	DIR *t = opendir("/proc/self/task");
	if (!t)
		return 0;
	unsigned n = 0;
	for (struct dirent *e; (e = readdir(t));)
		n += e->d_name[0] != '.';
	closedir(t);
	return n;
}

int scene_load_files(scene *s, const char *path, scene_file_fn fn, void *ctx, diag *d)
{
	scene_init(s, path);
	/* Test-only (docs/design.md): SAAR_IMPORT_ONE_THREAD refuses to fork
	 * beside other threads. A child forked then can hang on a lock one of
	 * them held (seen under AddressSanitizer, with the image plugin's
	 * libraries' threads: image.h, img_reserve_file); the programs keep
	 * the plugin unloaded until the scene is imported, and the test that
	 * sets this proves it. */
	const char *one = getenv("SAAR_IMPORT_ONE_THREAD");
	unsigned nth = one && *one ? threads_now() : 0;
	if (nth > 1)
		return diag_set(d, path, 0, 0,
		                "the importer would fork beside %u other threads "
		                "(SAAR_IMPORT_ONE_THREAD)",
		                nth - 1);
	imp_limits lim;
	if (limits_get(&lim, path, d))
		return -1;
	int res[2], err[2];
	if (pipe2(res, O_CLOEXEC) != 0)
		return diag_set(d, path, 0, 0, "cannot start the importer process: %s",
		                strerror(errno));
	if (pipe2(err, O_CLOEXEC) != 0) {
		int e = errno;
		close(res[0]);
		close(res[1]);
		return diag_set(d, path, 0, 0, "cannot start the importer process: %s",
		                strerror(e));
	}
	fcntl(res[0], F_SETPIPE_SZ, 1 << 20); /* fewer switches on a big scene */
	struct sigaction old_chld;
	int chld = sigchld_default(&old_chld);
	pid_t parent = getpid();
	pid_t pid = fork();
	if (pid == 0) {
		close(res[0]);
		close(err[0]);
		child_main(path, fn != NULL, &lim, parent, res[1], err[1]);
	}
	int fork_errno = errno;
	close(res[1]);
	close(err[1]);
	if (pid < 0) {
		close(res[0]);
		close(err[0]);
		if (chld)
			sigaction(SIGCHLD, &old_chld, NULL);
		return diag_set(d, path, 0, 0, "cannot start the importer process: %s",
		                strerror(fork_errno));
	}

	rd *r = calloc(1, sizeof *r);
	char *errbuf = malloc(IMP_ERR_KEEP + 1);
	if (!r) { /* no memory to take the result in: stop the child */
		kill(pid, SIGKILL);
		close(res[0]);
		close(err[0]);
	}
	pathlist pl = {0};
	diag cd = {{0}};
	uint32_t status = ST_FAIL;
	int got = 0;
	if (r) {
		r->fd = res[0];
		r->efd = err[0];
		r->deadline = mono() + 2.0 * (double)lim.cpu_s + IMP_WALL_EXTRA_S;
		r->err = errbuf;
		if (errbuf)
			errbuf[0] = '\0';
		got = rd_result(r, s, &status, &cd, &pl) == 0;
		/* a result that does not hold together, or no memory to take
		 * it: the child is of no more use */
		if (!got && (r->bad || r->nomem) && !r->timed_out)
			kill(pid, SIGKILL);
		/* the rest of stderr, until the child closes it by ending */
		if (r->fd >= 0) {
			close(r->fd);
			r->fd = -1;
		}
		while (!r->timed_out && rd_wait(r))
			;
	}
	int st = 0, killed = 0;
	struct rusage ru;
	memset(&ru, 0, sizeof ru);
	reap(pid, r && !r->timed_out ? r->deadline : 0, &st, &ru, &killed);
	if (chld)
		sigaction(SIGCHLD, &old_chld, NULL);
	if (r && r->efd >= 0)
		close(r->efd);
	/* a whole result and exit status 0 (or no status: a program's own
	 * SIGCHLD handler reaped the child, after it had sent everything) */
	int clean = st == -1 || (WIFEXITED(st) && WEXITSTATUS(st) == 0);
	int rc = -1;
	if (got && clean && status == ST_OK)
		rc = 0;
	else if (!r || (r->nomem && !r->timed_out))
		diag_set(d, path, 0, 0,
		         "cannot import scene: out of memory receiving it from the importer "
		         "process");
	else if (got && clean && (status == ST_FAIL_OOM || mem_text(r->err)))
		mem_line(d, path, &lim);
	else if (got && clean)
		*d = cd;
	else
		abnormal_line(d, path, &lim, r, st, killed, &ru);
	/* the files the import opened: also when it failed on one of them */
	if (got && fn)
		for (uint32_t i = 0; i < pl.n; i++)
			fn(ctx, pl.p[i]);
	pl_free(&pl);
	free(errbuf);
	free(r);
	if (rc != 0) {
		scene_free(s);
		scene_init(s, path);
	}
	return rc;
}

int scene_load(scene *s, const char *path, diag *d)
{
	return scene_load_files(s, path, NULL, NULL, d);
}
