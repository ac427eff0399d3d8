/*
 * diag.c: formatting of one-line input errors (see diag.h).
 */
#include "kernel-ref/diag.h"

#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <unistd.h>

int diag_set(diag *d, const char *file, int line, int col, const char *fmt, ...)
{
	if (!d)
		return -1;
	size_t n = sizeof d->msg;
	int k;
	if (line > 0 && col > 0)
		k = snprintf(d->msg, n, "%s:%d:%d: ", file, line, col);
	else if (line > 0)
		k = snprintf(d->msg, n, "%s:%d: ", file, line);
	else
		k = snprintf(d->msg, n, "%s: ", file ? file : "(input)");
	if (k < 0 || (size_t)k >= n)
		return -1;
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(d->msg + k, n - (size_t)k, fmt, ap);
	va_end(ap);
	/* one line whatever the arguments carry: libraries' messages quote the
	 * bad bytes of a file, newlines and all (Assimp's parse errors) */
	for (char *c = d->msg; *c; c++)
		if ((unsigned char)*c < 0x20 || *c == 0x7f)
			*c = '?';
	return -1;
}

static int quiet_off;

void diag_quiet_off(void)
{
	quiet_off = 1;
}

int diag_quiet_begin(void)
{
	if (quiet_off)
		return -1;
	fflush(stderr);
	int null = open("/dev/null", O_WRONLY | O_CLOEXEC);
	if (null < 0)
		return -1;
	int saved = fcntl(2, F_DUPFD_CLOEXEC, 3);
	if (saved >= 0 && dup2(null, 2) < 0) {
		close(saved);
		saved = -1;
	}
	close(null);
	return saved;
}

void diag_quiet_end(int saved)
{
	if (saved < 0)
		return;
	fflush(stderr);
	dup2(saved, 2);
	close(saved);
}
