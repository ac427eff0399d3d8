/*
 * infile.h: opening input files (scenes, MTL files, textures, configs,
 * views files, world-cache entries, CSVs appended to) only when they are
 * regular files. fopen on a FIFO waits for a writer, so a FIFO named as a
 * config or scene hung the program; a directory opens and reads as garbage
 * or nothing (Assimp said "vector::reserve" for an MTL path that was a
 * directory); a device may never end. The file is opened without blocking,
 * checked with fstat, and only then handed out as a blocking stream.
 */
#ifndef SAAR_KREF_INFILE_H
#define SAAR_KREF_INFILE_H

#include <stddef.h>
#include <stdio.h>

/* A non-zero status of in_open/in_check that is not an errno value. */
#define IN_NOT_REGULAR (-1)

/* Opens path for reading ("rb") if it is a regular file. 0 and *f, or a
 * status: an errno value (ENOENT, EACCES, ...), EISDIR for a directory, or
 * IN_NOT_REGULAR for a FIFO, device or socket. */
int in_open(const char *path, FILE **f);
/* The same check without keeping the file open (for a path a library
 * opens by name); 0 when path is a regular file. */
int in_check(const char *path);
/* The reason for a status: strerror, or "not a regular file ...". */
const char *in_strerror(int status);
/* Reads all of path (a regular file), inflated when gz is set (gzread also
 * passes a plain file through unchanged), into *out (malloc'd, NUL-
 * terminated; *outlen bytes before the NUL). 0, or the in_open status
 * (ENOENT for a missing file, ...) or EIO for a read, inflate or memory
 * failure, with the reason in err. */
int in_read_all(const char *path, int gz, char **out, size_t *outlen, char *err, size_t errn);

#endif
