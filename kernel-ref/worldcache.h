/*
 * worldcache.h: the world cache (--world-cache DIR). Built worlds (scene
 * figures, kd-tree figures, memory image) and kernel-ref's reference
 * frames kept on disk, so the next run on the same scene skips the import,
 * the kd-tree build and the reference render. worldcache.c says when a
 * file is trusted.
 */
#ifndef SAAR_KREF_WORLDCACHE_H
#define SAAR_KREF_WORLDCACHE_H

#include "kernel-ref/diag.h"
#include "kernel-ref/kdtree.h"
#include "kernel-ref/memimage.h"
#include "kernel-ref/render.h"
#include "kernel-ref/view.h"

#include <stddef.h>
#include <stdint.h>

/* The files a scene was built from, collected while it loads. */
typedef struct wc_files {
	char **path;
	int n, cap;
	int lost; /* a file could not be recorded: the entry is then not stored */
} wc_files;

/* The scene_file_fn for scene_load_files: adds the real path of `path`
 * to the wc_files at ctx, once. */
void wc_files_add(void *ctx, const char *path);
void wc_files_free(wc_files *f);

/* Makes DIR (its last component; with parents, every missing folder
 * on its way, as mkdir -p) if missing and checks it can be written;
 * fills prog (>= 48 bytes) with this program's identity, the CRC-32 and
 * size of its own file. Fails with diag naming DIR. */
int wc_prepare(const char *dir, int parents, char *prog, size_t nprog, diag *d);

/* Where the folder came from (wc_choose). */
enum { WC_FROM_OFF, WC_FROM_FLAG, WC_FROM_ENV, WC_FROM_XDG, WC_FROM_HOME, WC_FROM_NONE };
/* Its name in reports: "off", "--world-cache", "SAARSIM_CACHE_DIR",
 * "XDG_CACHE_HOME", "HOME", "none". */
const char *wc_from_name(int from);

/* The world cache's folder: flag (--world-cache DIR; "off": none), else
 * $SAARSIM_CACHE_DIR (likewise; empty is unset), else
 * $XDG_CACHE_HOME/saarsim (an absolute XDG_CACHE_HOME only, as the XDG
 * base directory spec says), else $HOME/.cache/saarsim. The folder into
 * out (n bytes; "" for none); returns WC_FROM_*: OFF when turned off,
 * NONE when no variable names a folder or the name does not fit. */
int wc_choose(const char *flag, char *out, size_t n);

/* The cap on a folder's entries, bytes: mb >= 0 (--world-cache-max),
 * else $SAARSIM_CACHE_MAX_MB, else WC_DEFAULT_MAX_MB; 0 MB: no cap. -1
 * with diag for a bad variable's value. */
#define WC_DEFAULT_MAX_MB 4096
#define WC_MAX_MB         1073741824 /* the largest cap, MB (1 PiB) */
int wc_cap(long mb, uint64_t *bytes, diag *d);

/* Room for an entry of need bytes under the cap: while the folder's
 * entries (KIND-HASH.bin of the four kinds) and need pass cap, removes
 * the least recently used entry (by modification time: a hit touches
 * its file). -1 when need alone passes the cap (the entry is then not
 * stored); cap 0: nothing to do. */
int wc_make_room(const char *dir, uint64_t need, uint64_t cap);

/* A stored object: fixed-size parts read into caller's memory, then a
 * tail of any length (NULL/0: none). */
typedef struct wc_part {
	void *p;
	size_t n;
} wc_part;

/* DIR/KIND-HASH.bin, the file of key (-1 when the name does not fit). */
int wc_file(char *out, size_t n, const char *dir, const char *kind, const char *key);

/* Reads file: 1 on a hit (the stored key equals key, every recorded file
 * is unchanged, the checks match), the parts filled and the tail malloc'd
 * into *tail / *ntail; 0 on a miss, parts zeroed. */
int wc_get(const char *file, const char *key, const wc_part *parts, int nparts, void **tail,
           size_t *ntail);

/* A file mapped by wc_get_mapped; wc_unmap releases it (a zeroed one is
 * nothing). */
typedef struct wc_map {
	void *base;
	size_t len;
} wc_map;
void wc_unmap(wc_map *m);

/* wc_get without copying the tail: on a hit *tail points into the file,
 * mapped read-only (64-byte aligned), until wc_unmap(m). tail NULL: the
 * object has no tail, and nothing stays mapped. */
int wc_get_mapped(const char *file, const char *key, const wc_part *parts, int nparts,
                  const void **tail, size_t *ntail, wc_map *m);

/* Stores key, the files f (may be NULL), parts and tail atomically (a
 * temporary file, then rename). -1 with diag when it could not. */
int wc_put(const char *file, const char *key, const wc_files *f, const wc_part *parts, int nparts,
           const void *tail, size_t ntail, diag *d);

/* The key of a world: program, scene source (a file by its real path;
 * "spd:..." and NULL, the embedded scene, by name) and kd parameters.
 * malloc'd; NULL when out of memory. */
char *wc_world_key(const char *prog, const char *source, const kd_params *kd);

/* The key of kernel-ref's frame of a memory image (named by the CRC-32
 * of its bytes, image_crc, and its size) seen by view v with options o:
 * everything render_frame depends on (not the host thread count: the
 * frame is the same). NULL (no caching) for reduced precision or out of
 * memory. */
char *wc_frame_key(const char *prog, uint32_t image_crc, uint64_t image_size, const view *v,
                   const render_opts *o);

/* CRC-32 of n bytes (any n). */
uint32_t wc_crc(const void *p, uint64_t n);

#endif
