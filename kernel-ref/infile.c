/*
 * infile.c: input files that must be regular files (infile.h says why),
 * and reading one whole (scenes, CSVs appended to).
 */
#include "kernel-ref/infile.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

/* An O_NONBLOCK descriptor of path checked to be a regular file, or -1
 * with *status set. O_NONBLOCK makes opening a FIFO return at once. */
static int open_regular(const char *path, int *status)
{
	int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0) {
		*status = errno ? errno : ENOENT;
		return -1;
	}
	struct stat st;
	if (fstat(fd, &st) != 0)
		*status = errno ? errno : EIO;
	else if (!S_ISREG(st.st_mode))
		*status = S_ISDIR(st.st_mode) ? EISDIR : IN_NOT_REGULAR;
	else
		*status = 0;
	if (*status) {
		close(fd);
		return -1;
	}
	return fd;
}

int in_open(const char *path, FILE **f)
{
	int status;
	int fd = open_regular(path, &status);
	*f = NULL;
	if (fd < 0)
		return status;
	int fl = fcntl(fd, F_GETFL);
	if (fl < 0 || fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) < 0 || !(*f = fdopen(fd, "rb"))) {
		status = errno ? errno : EIO;
		close(fd);
		return status;
	}
	return 0;
}

int in_check(const char *path)
{
	int status;
	int fd = open_regular(path, &status);
	if (fd >= 0)
		close(fd);
	return status;
}

const char *in_strerror(int status)
{
	return status == IN_NOT_REGULAR ? "not a regular file (a FIFO, device or socket)"
	                                : strerror(status);
}

/* One loop for plain and gzip files: the buffer doubles as it fills, one
 * byte kept for the terminating NUL. */
int in_read_all(const char *path, int gz, char **out, size_t *outlen, char *err, size_t errn)
{
	FILE *f = NULL;
	int st = gz ? in_check(path) : in_open(path, &f);
	gzFile g = gz && !st ? gzopen(path, "rb") : NULL;
	if (!st && !g && !f)
		st = errno ? errno : ENOENT;
	if (st) {
		snprintf(err, errn, "cannot open: %s", in_strerror(st));
		return st;
	}
	size_t cap = 1 << 16, len = 0;
	char *buf = malloc(cap + 1);
	st = EIO; /* what a failure below returns */
	if (!buf) {
		snprintf(err, errn, "out of memory reading the file");
		goto fail;
	}
	for (;;) {
		if (len == cap) {
			cap *= 2;
			char *nb = realloc(buf, cap + 1);
			if (!nb) {
				snprintf(err, errn, "out of memory reading the file");
				goto fail;
			}
			buf = nb;
		}
		size_t want = cap - len;
		long got;
		if (g) {
			int r =
			    gzread(g, buf + len, want > (1u << 30) ? (1u << 30) : (unsigned)want);
			if (r < 0) {
				int zerr;
				const char *m = gzerror(g, &zerr);
				snprintf(err, errn, "gzip data is corrupt: %s", m);
				goto fail;
			}
			got = r;
		} else {
			got = (long)fread(buf + len, 1, want, f);
			if (got == 0 && ferror(f)) {
				snprintf(err, errn, "read error: %s", strerror(errno));
				goto fail;
			}
		}
		if (got == 0)
			break;
		len += (size_t)got;
	}
	if (g) {
		/* A truncated or corrupt stream ends reads early without -1. */
		int zerr;
		const char *m = gzerror(g, &zerr);
		if (zerr != Z_OK) {
			snprintf(err, errn, "gzip data is corrupt or truncated: %s", m);
			goto fail;
		}
		gzclose(g);
	} else {
		fclose(f);
	}
	buf[len] = '\0';
	*out = buf;
	*outlen = len;
	return 0;
fail:
	free(buf);
	if (g)
		gzclose(g);
	else
		fclose(f);
	return st;
}
