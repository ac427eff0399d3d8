/*
 * diag.c: formatting of one-line input errors (see diag.h).
 */
#include "diag.h"

#include <stdarg.h>
#include <stdio.h>

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
