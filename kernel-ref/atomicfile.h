/*
 * atomicfile.h: output files that appear complete or not at all. A writer
 * opens a temporary file beside the target (a unique name, so two runs
 * writing the same path do not share it), writes it, and renames it over
 * the target only when every write succeeded; on failure or abort the
 * temporary is removed. Every file saarsim's programs write goes through
 * here: images, JSON reports, CSV rows, world-cache files, the tables the
 * stress tool splices into docs.
 */
#ifndef SAAR_KREF_ATOMICFILE_H
#define SAAR_KREF_ATOMICFILE_H

#include <limits.h>
#include <stdio.h>

#include "kernel-ref/diag.h"

typedef struct afile {
	FILE *f; /* the temporary, open for writing; NULL when a library writes it by name */
	char path[PATH_MAX], tmp[PATH_MAX + 32];
} afile;

/* Creates the temporary for path, named path.XXXXXX then suffix (an
 * image's ".png", so a library can tell the format; "" for none), readable
 * as any file the user creates (umask). With want_file, a->f is open on
 * it ("wb"); without, it is closed and the caller writes a->tmp by name.
 * A symbolic link is written through to its target; an empty path, or
 * one naming a directory (EISDIR) or a device or FIFO (EPERM), is refused.
 * -1 with errno set (ENAMETOOLONG for a path too long). */
int af_open(afile *a, const char *path, const char *suffix, int want_file);
/* Closes a->f (a write error there fails the commit too) and renames the
 * temporary over path. -1 with errno set; the temporary is removed. */
int af_commit(afile *a);
/* The one line for an af_open or af_commit that failed (errno set):
 * "path: cannot write: reason"; returns diag_set's -1. */
int af_diag(diag *d, const char *path);
/* Closes and removes the temporary. */
void af_abort(afile *a);

/* Outputs checked before the work that fills them. af_reserve creates
 * path's temporary now (af_open's rules, suffix as af_open's), so a
 * missing or unwritable folder is found before a long simulation instead
 * of after it; the next af_open of the same path and suffix takes that
 * temporary instead of making another. A reservation nobody takes is
 * removed at exit. -1 with d set (af_diag's line). */
int af_reserve(const char *path, const char *suffix, diag *d);

/* Every temporary that is open (made by af_open or af_reserve, not yet
 * renamed or removed) is removed when the program exits normally or is
 * ended by SIGINT, SIGTERM or SIGHUP (the signal's default action then
 * runs: the exit status still says the program was interrupted). The
 * handlers are installed by the first af_open, and only for signals whose
 * disposition is still the default. At most AF_LIVE_MAX temporaries are
 * watched at once; more are still written, only not cleaned on a signal. */
#define AF_LIVE_MAX 64

/* A folder the program made for its outputs (saarsim's --heatmap DIR):
 * removed, if it is empty then, after the temporaries at exit and on the
 * signals above, so a failed or interrupted run leaves no folder behind
 * (a run that wrote its files there leaves it, as rmdir fails). One
 * folder; a second call replaces the first. */
void af_made_dir(const char *dir);

/* Outputs that appear together. A program writing several files (an
 * image, a report, a trace, a CSV row) commits each into a group, which
 * only closes its temporary (a write error fails there); once every one is
 * complete af_group_commit renames them all, and on any failure before
 * that af_group_abort removes them: the user's files at the outputs' paths
 * stay as they were unless the run succeeds. (Undoing by deleting outputs
 * already renamed would delete the files they had replaced.) */
#define AF_GROUP_MAX 24
typedef struct af_group {
	int n;
	afile a[AF_GROUP_MAX];
} af_group;

/* With g NULL, af_commit; else closes a->f and keeps the temporary in g.
 * -1 with errno set, the temporary removed (E2BIG: the group is full). */
int af_commit_to(afile *a, af_group *g);
/* Renames every temporary of g over its path, in the order committed;
 * empties g. -1 with d naming the first path that failed (the temporaries
 * after it are removed; those before it are in place). */
int af_group_commit(af_group *g, diag *d);
/* Removes every temporary of g; empties it. */
void af_group_abort(af_group *g);

#endif
