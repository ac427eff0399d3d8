/*
 * import.h: between import.c (the import itself, in the calling process)
 * and importproc.c (the importer process that runs it under limits for
 * scene_load). Other code calls scene.h's functions instead.
 */
#ifndef SAAR_KREF_IMPORT_H
#define SAAR_KREF_IMPORT_H

#include "kernel-ref/scene.h"

/* scene_import_inproc, and on failure *oom set when the cause was a failed
 * allocation (Assimp's std::bad_alloc, ours, a texture's): the importer
 * process reports its memory limit then. */
int import_body(scene *s, const char *path, scene_file_fn fn, void *ctx, int *oom, diag *d);

#endif
