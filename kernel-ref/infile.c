/*
 * infile.c: input files that must be regular files (infile.h says why).
 */
#include "infile.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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
