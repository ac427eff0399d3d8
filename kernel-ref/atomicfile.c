/*
 * atomicfile.c: temporary-then-rename output files (see atomicfile.h).
 */
#include "atomicfile.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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
	/* mkstemps makes it 0600; the target should read like any file the
	 * user writes */
	mode_t um = umask(0);
	umask(um);
	if (fchmod(fd, 0666 & ~um) != 0 || (want_file && !(a->f = fdopen(fd, "wb")))) {
		int e = errno;
		close(fd);
		unlink(a->tmp);
		errno = e;
		return -1;
	}
	if (!want_file)
		close(fd);
	return 0;
}

/* Closes a->f; -1 with errno set on a write error. */
static int af_close(afile *a)
{
	int err = 0;
	if (a->f) {
		if (ferror(a->f))
			err = EIO;
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
	if (err) {
		unlink(a->tmp);
		errno = err;
		return -1;
	}
	return 0;
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
}

int af_diag(diag *d, const char *path)
{
	return diag_set(d, path, 0, 0, "cannot write: %s", strerror(errno));
}
