/*
 * image.h: image files through OpenImageIO, which image.c loads as a plugin
 * on first use (image_plugin.h says why; image_oiio.cpp is the plugin).
 *
 * Writes go to a temporary file beside the target and are renamed into
 * place, so a failed or interrupted write never leaves a partial file that
 * looks complete.
 */
#ifndef SAAR_KREF_IMAGE_H
#define SAAR_KREF_IMAGE_H

#include <stdint.h>

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/diag.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Writes an 8-bit RGB image (w*h*3 bytes, row 0 at the top). The format
 * follows the extension (.png, .exr, .ppm, .tif, ...); float formats such as
 * EXR get the float buffer `rgbf` (w*h*3, linear) when it is non-NULL.
 * With a group g the file is renamed into place by af_group_commit. */
int img_write(const char *path, int w, int h, const uint8_t *rgb8, const float *rgbf, af_group *g,
              diag *d);

/* Writes w*h values (row 0 at the top) as one 32-bit float channel "Y"
 * to a float format (.exr): raw data, not a picture. g as img_write. */
int img_write_values(const char *path, int w, int h, const float *v, af_group *g, diag *d);
/* 0 if an image can be written to path's format (the plugin loads and has
 * a writer for the extension), else -1 with d set: lets a program refuse
 * --out before it spends the run. */
int img_can_write(const char *path, diag *d);

/* img_can_write, then the image's temporary made now (af_reserve), so a
 * missing or unwritable folder is refused before the run too; img_write
 * to the same path takes it. A path naming a folder ("out/") is refused
 * as such. */
int img_reserve(const char *path, diag *d);

/* img_reserve without img_can_write: the plugin is not loaded. A program
 * that imports a scene file calls this before the import and
 * img_can_write after it: the plugin's libraries start threads when they
 * load (log4cplus, through OpenVDB), and the importer forks
 * (importproc.c); a child forked beside other threads can hang on a lock
 * one of them held (seen under AddressSanitizer: its allocator's). */
int img_reserve_file(const char *path, diag *d);

/* The image plugin file that reads and writes images (out, n bytes); -1
 * with d set when there is none. A world cache keys texture-decoding
 * results on it, since rebuilding the plugin does not rebuild the program. */
int img_plugin_path(char *out, size_t n, diag *d);

/* Reads any OIIO-readable image as RGBA8 (row 0 at the top). *rgba is
 * malloc'd; the caller frees it. */
int img_read_rgba8(const char *path, int *w, int *h, uint8_t **rgba, diag *d);

#ifdef __cplusplus
}
#endif

#endif
