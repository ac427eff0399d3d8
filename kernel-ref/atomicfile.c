/*
 * atomicfile.c: temporary-then-rename output files (see atomicfile.h).
 */
#include "atomicfile.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int af_open(afile *a, const char *path, const char *suffix, int want_file)
{
	memset(a, 0, sizeof *a);
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

int af_commit(afile *a)
{
	int err = 0;
	if (a->f) {
		if (ferror(a->f))
			err = EIO;
		if (fclose(a->f) != 0 && !err)
			err = errno ? errno : EIO;
		a->f = NULL;
	}
	if (!err && rename(a->tmp, a->path) != 0)
		err = errno;
	if (err) {
		unlink(a->tmp);
		errno = err;
		return -1;
	}
	return 0;
}

void af_abort(afile *a)
{
	if (a->f)
		fclose(a->f);
	a->f = NULL;
	unlink(a->tmp);
}
