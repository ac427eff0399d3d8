/*
 * image_plugin.h: the boundary between image.c (C) and the OpenImageIO
 * plugin, libsaar-oiio.so (image_oiio.cpp, the only C++ in saarsim).
 *
 * OpenImageIO drags hundreds of shared libraries into a process (ldd
 * libsaar-oiio.so lists them); binding their symbols cost every saarsim
 * start a noticeable part of a second, whether it wrote an image or not.
 * So the programs do not link OIIO: image.c opens the plugin with dlopen
 * on the first image read or write, and a run that writes no image (a
 * sweep point, --no-check without --out) never loads it.
 *
 * The plugin knows nothing of diag or temporary files: it writes one file
 * under the name it is given and reads one, and on failure puts one line of
 * text into err. image.c does the rest.
 */
#ifndef SAAR_KREF_IMAGE_PLUGIN_H
#define SAAR_KREF_IMAGE_PLUGIN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Bumped whenever img_plugin changes; image.c refuses another version. */
#define IMG_PLUGIN_ABI   3
#define IMG_PLUGIN_FILE  "libsaar-oiio.so"
#define IMG_PLUGIN_ENTRY "saar_image_plugin"

typedef struct img_plugin {
	int abi;
	/* Writes w x h RGB to path in the format of ext (lower case, no dot):
	 * 8-bit from rgb8, or half floats from rgbf for float formats (exr,
	 * hdr) when rgbf is non-NULL. 0, or -1 with err filled. */
	int (*write_rgb)(const char *path, const char *ext, int w, int h, const uint8_t *rgb8,
	                 const float *rgbf, char *err, size_t errlen);
	/* 0 if OIIO has a writer for path's extension, else -1 with err. */
	int (*can_write)(const char *path, char *err, size_t errlen);
	/* Reads any format as RGBA8 into a malloc'd *rgba. 0, or -1 with err. */
	int (*read_rgba8)(const char *path, int *w, int *h, uint8_t **rgba, char *err,
	                  size_t errlen);
	/* Writes w x h values of one channel ("Y") as 32-bit floats to path
	 * in the format of ext (a float format: exr). 0, or -1 with err. */
	int (*write_y32f)(const char *path, const char *ext, int w, int h, const float *v,
	                  char *err, size_t errlen);
} img_plugin;

/* The one symbol the plugin exports. */
const img_plugin *saar_image_plugin(void);

#ifdef __cplusplus
}
#endif

#endif
