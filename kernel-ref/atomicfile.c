/*
 * atomicfile.c: temporary-then-rename output files (see atomicfile.h).
 */
#include "kernel-ref/atomicfile.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- Temporaries that exist now, removed on exit or a fatal signal.
 * The handler reads only this static table: a slot's path is written
 * before its flag is set, and unlink is async-signal-safe. */
static char live_path[AF_LIVE_MAX][PATH_MAX + 32];
static volatile sig_atomic_t live_on[AF_LIVE_MAX];
static pthread_mutex_t live_mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_once_t live_once = PTHREAD_ONCE_INIT;

static const int live_sigs[] = {SIGINT, SIGTERM, SIGHUP};

/* af_made_dir's folder; rmdir is async-signal-safe too */
static char made_dir[PATH_MAX];
static volatile sig_atomic_t made_on;

static void live_remove_all(void)
{
	for (int i = 0; i < AF_LIVE_MAX; i++)
		if (live_on[i])
			unlink(live_path[i]);
	if (made_on)
		rmdir(made_dir);
}

static void on_fatal(int sig)
{
	live_remove_all();
	signal(sig, SIG_DFL);
	raise(sig);
}

static void live_install(void)
{
	atexit(live_remove_all);
	for (size_t i = 0; i < sizeof live_sigs / sizeof *live_sigs; i++) {
		struct sigaction old, sa;
		if (sigaction(live_sigs[i], NULL, &old) != 0 || old.sa_handler != SIG_DFL ||
		    (old.sa_flags & SA_SIGINFO))
			continue; /* the program handles it itself */
		memset(&sa, 0, sizeof sa);
		sa.sa_handler = on_fatal;
		sigemptyset(&sa.sa_mask);
		sigaction(live_sigs[i], &sa, NULL);
	}
}

static void live_add(const char *tmp)
{
	pthread_once(&live_once, live_install);
	pthread_mutex_lock(&live_mu);
	for (int i = 0; i < AF_LIVE_MAX; i++)
		if (!live_on[i]) {
			snprintf(live_path[i], sizeof live_path[i], "%s", tmp);
			live_on[i] = 1;
			break;
		}
	pthread_mutex_unlock(&live_mu);
}

void af_made_dir(const char *dir)
{
	pthread_once(&live_once, live_install);
	made_on = 0;
	snprintf(made_dir, sizeof made_dir, "%s", dir);
	made_on = 1;
}

static void live_del(const char *tmp)
{
	pthread_mutex_lock(&live_mu);
	for (int i = 0; i < AF_LIVE_MAX; i++)
		if (live_on[i] && !strcmp(live_path[i], tmp)) {
			live_on[i] = 0;
			break;
		}
	pthread_mutex_unlock(&live_mu);
}

/* ---- Reservations (af_reserve): temporaries made before their writer
 * runs, keyed by the path and suffix the writer will ask for. */
#define RES_MAX 16
static struct {
	char path[PATH_MAX], suffix[32];
	afile a;
	int on;
} res[RES_MAX];

static int res_take(afile *a, const char *path, const char *suffix)
{
	int found = 0;
	pthread_mutex_lock(&live_mu);
	for (int i = 0; i < RES_MAX && !found; i++)
		if (res[i].on && !strcmp(res[i].path, path) && !strcmp(res[i].suffix, suffix)) {
			*a = res[i].a;
			res[i].on = 0;
			found = 1;
		}
	pthread_mutex_unlock(&live_mu);
	return found;
}

/* A dangling link's target, relative to the link's folder when relative;
 * 0 when it cannot be read or is too long. */
static int link_target(const char *link, char out[PATH_MAX])
{
	char t[PATH_MAX];
	ssize_t n = readlink(link, t, sizeof t - 1);
	if (n <= 0)
		return 0;
	t[n] = 0;
	const char *slash = strrchr(link, '/');
	int dirlen = t[0] == '/' || !slash ? 0 : (int)(slash - link + 1);
	if (snprintf(out, PATH_MAX, "%.*s%s", dirlen, link, t) >= PATH_MAX) {
		errno = ENAMETOOLONG;
		return 0;
	}
	return 1;
}

int af_open(afile *a, const char *path, const char *suffix, int want_file)
{
	memset(a, 0, sizeof *a);
	if (res_take(a, path, suffix)) {
		if (want_file && !(a->f = fopen(a->tmp, "wb"))) {
			int e = errno;
			af_abort(a);
			errno = e;
			return -1;
		}
		return 0;
	}
	if (!path[0]) {
		errno = ENOENT;
		return -1;
	}
	/* The rename replaces whatever path names: a symbolic link is written
	 * through (the temporary goes beside its target, which is renamed
	 * over, and the link stays), and a device, FIFO or directory is
	 * refused (run as root, --report /dev/null once replaced the device
	 * with a plain file) */
	char real[PATH_MAX];
	struct stat st;
	if (lstat(path, &st) == 0) {
		if (S_ISLNK(st.st_mode)) {
			if (realpath(path, real)) {
				if (stat(real, &st) != 0)
					return -1;
			} else if (errno == ENOENT && link_target(path, real)) {
				st.st_mode = S_IFREG; /* dangling: the write creates it */
			} else {
				return -1;
			}
			path = real;
		}
		if (!S_ISREG(st.st_mode)) {
			errno = S_ISDIR(st.st_mode) ? EISDIR : EPERM;
			return -1;
		}
	}
	size_t ns = strlen(suffix);
	if (snprintf(a->path, sizeof a->path, "%s", path) >= (int)sizeof a->path ||
	    snprintf(a->tmp, sizeof a->tmp, "%s.XXXXXX%s", path, suffix) >= (int)sizeof a->tmp ||
	    ns > INT_MAX) {
		errno = ENAMETOOLONG;
		return -1;
	}
	int fd = mkstemps(a->tmp, (int)ns);
	if (fd < 0)
		return -1;
	live_add(a->tmp);
	/* mkstemps makes it 0600; the target should read like any file the
	 * user writes */
	mode_t um = umask(0);
	umask(um);
	if (fchmod(fd, 0666 & ~um) != 0 || (want_file && !(a->f = fdopen(fd, "wb")))) {
		int e = errno;
		close(fd);
		unlink(a->tmp);
		live_del(a->tmp);
		errno = e;
		return -1;
	}
	if (!want_file)
		close(fd);
	return 0;
}

/* Why an earlier write to f failed. stdio keeps only the error flag, not
 * the write's errno (which every call since may have changed), and an
 * error once reported as EIO said "Input/output error" for a file over
 * the size limit (ulimit -f) or a full disk. So one byte is written again
 * where the file ends, where the failed write stopped: the same cause
 * fails it with its own errno (the file is a temporary, removed after the
 * error anyway). EIO when it succeeds. */
static int write_errno(FILE *f)
{
	int fd = fileno(f);
	struct stat st;
	if (fd < 0 || fstat(fd, &st) != 0)
		return EIO;
	errno = 0;
	if (pwrite(fd, "", 1, st.st_size) == 1)
		return EIO;
	return errno ? errno : EIO;
}

/* Closes a->f; -1 with errno set on a write error (its own reason). */
static int af_close(afile *a)
{
	int err = 0;
	if (a->f) {
		fflush(a->f); /* what is buffered fails now, with its errno */
		if (ferror(a->f))
			err = write_errno(a->f);
		errno = 0;
		if (fclose(a->f) != 0 && !err)
			err = errno ? errno : EIO;
		a->f = NULL;
	}
	errno = err;
	return err ? -1 : 0;
}

int af_commit(afile *a)
{
	int err = af_close(a) ? errno : 0;
	if (!err && rename(a->tmp, a->path) != 0)
		err = errno;
	if (err)
		unlink(a->tmp);
	live_del(a->tmp);
	errno = err;
	return err ? -1 : 0;
}

int af_commit_to(afile *a, af_group *g)
{
	if (!g)
		return af_commit(a);
	int err = 0;
	if (af_close(a))
		err = errno;
	else if (g->n == AF_GROUP_MAX)
		err = E2BIG;
	if (err) {
		unlink(a->tmp);
		live_del(a->tmp);
		errno = err;
		return -1;
	}
	g->a[g->n++] = *a;
	return 0;
}

int af_group_commit(af_group *g, diag *d)
{
	int rc = 0;
	for (int i = 0; i < g->n; i++) {
		if (rc) {
			unlink(g->a[i].tmp);
			live_del(g->a[i].tmp);
		} else if (af_commit(&g->a[i])) {
			rc = af_diag(d, g->a[i].path);
		}
	}
	g->n = 0;
	return rc;
}

void af_group_abort(af_group *g)
{
	for (int i = 0; i < g->n; i++)
		af_abort(&g->a[i]);
	g->n = 0;
}

void af_abort(afile *a)
{
	if (a->f)
		fclose(a->f);
	a->f = NULL;
	unlink(a->tmp);
	live_del(a->tmp);
}

int af_reserve(const char *path, const char *suffix, diag *d)
{
	afile a;
	if (strlen(path) >= sizeof res[0].path || strlen(suffix) >= sizeof res[0].suffix) {
		errno = ENAMETOOLONG;
		return af_diag(d, path);
	}
	if (af_open(&a, path, suffix, 0))
		return af_diag(d, path);
	pthread_mutex_lock(&live_mu);
	int i = 0;
	while (i < RES_MAX && res[i].on)
		i++;
	if (i < RES_MAX) {
		snprintf(res[i].path, sizeof res[i].path, "%s", path);
		snprintf(res[i].suffix, sizeof res[i].suffix, "%s", suffix);
		res[i].a = a;
		res[i].on = 1;
	}
	pthread_mutex_unlock(&live_mu);
	if (i == RES_MAX) /* nothing lost: the writer makes its own later */
		af_abort(&a);
	return 0;
}

/* The folder part of path ("." when none), into out. */
static void folder_of(const char *path, char *out, size_t n)
{
	const char *slash = strrchr(path, '/');
	if (!slash)
		snprintf(out, n, ".");
	else if (slash == path)
		snprintf(out, n, "/");
	else
		snprintf(out, n, "%.*s", (int)(slash - path), path);
}

int af_diag(diag *d, const char *path)
{
	int e = errno;
	char dir[PATH_MAX];
	struct stat st;
	folder_of(path, dir, sizeof dir);
	size_t n = strlen(path);
	if (e == EISDIR || (n && path[n - 1] == '/') ||
	    (stat(path, &st) == 0 && S_ISDIR(st.st_mode)))
		return diag_set(d, path, 0, 0, "cannot write: it names a folder, not a file");
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode))
		return diag_set(d, path, 0, 0,
		                "cannot write: it is a device or FIFO, not a regular file");
	if (e == ENOENT && stat(dir, &st) != 0)
		return diag_set(d, path, 0, 0, "cannot write: folder %s does not exist", dir);
	if (e == ENOTDIR)
		return diag_set(d, path, 0, 0, "cannot write: %s is not a folder", dir);
	if (e == ENOENT || e == EACCES || e == EPERM || e == EROFS)
		/* the folder exists: the file system refused the new file
		 * (/proc, a read-only mount, no write permission) */
		return diag_set(d, path, 0, 0,
		                "cannot write: cannot create a file in folder %s (%s)", dir,
		                strerror(e));
	return diag_set(d, path, 0, 0, "cannot write: %s", strerror(e));
}
