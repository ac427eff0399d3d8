/*
 * aff.h: BART's Animation File Format (.aff), read by our own small strict
 * reader, and the scene it describes flattened at a time.
 *
 * AFF (Lext, Assarsson, Moller, "BART: A Benchmark for Animated Ray
 * Tracing", IEEE CG&A 21(2), 2001) extends Eric Haines' NFF with triangle
 * meshes, materials, static and keyframed transforms and includes. What is
 * read and how (docs/design.md, "AFF scenes and animation time"; the
 * syntax as ../shared/scenes/bart_robots_aff/README.md describes it):
 *
 *   v (from/at/up/angle/hither/resolution)  static camera
 *   am r g b, b r g b, l x y z [r g b]      ambient, background, point lights
 *   a start end frames                      animation range
 *   fm (12 numbers), f (8 numbers)          material (running state)
 *   m ... , p n ..., pp n ...               meshes and polygons
 *   xs S / A deg / T { ... }                static transform T*R*S
 *   x name { ... }                          transform keyed by `k name`
 *   k name { transl n ... rot n ... scale n ... }   keyframes (kbspline.h)
 *   i level file, d level                   include (relative to the
 *                                           including file's folder), detail
 *   % or # to the end of the line           comment
 *
 * Anything else (spheres, cones, visibility keys) is an error naming
 * file:line:col. The reader keeps the transform tree and the meshes in
 * their own frames; aff_flatten places them at a time t into one triangle
 * soup (scene.h), aff_view gives the camera at t.
 */
#ifndef SAAR_KREF_AFF_H
#define SAAR_KREF_AFF_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/kbspline.h"
#include "kernel-ref/scene.h"
#include "kernel-ref/view.h"

/* Limits (docs/views.md, "AFF scenes"): a file that would exceed one is an
 * error naming where it happened. */
#define AFF_INCLUDE_DEPTH 16           /* include nesting */
#define AFF_FILE_MAX      (64u << 20)  /* bytes of one file */
#define AFF_TOTAL_MAX     (256u << 20) /* bytes read over all includes */
#define AFF_TRIS_MAX      (1u << 22)   /* triangles after expanding includes */
#define AFF_POOL_MAX      (3u << 22)   /* vertices, normals, texture coordinates (each) */
#define AFF_KEYS_MAX      (1u << 20)   /* keyframes, all tracks */
#define AFF_NEST_MAX      256          /* open transform blocks */
#define AFF_NAME_MAX      64           /* transform and keyframe names */
#define AFF_FILES_MAX     4096         /* distinct files */
#define AFF_INCLUDES_MAX  (1u << 20)   /* include lines carried out */

enum { AFF_TRANSL, AFF_ROT, AFF_SCALE, AFF_NTRACKS };

typedef struct aff_track {
	uint32_t n; /* 0: absent */
	kb_key *k;
	double *q; /* rotation tracks: kb_rot_quats */
} aff_track;

typedef struct aff_anim {
	char name[AFF_NAME_MAX];
	aff_track tr[AFF_NTRACKS];
} aff_anim;

/* A transform node: static (m) or animated (anim: index, -1 for a name
 * no `k` block gives, which is the identity as in BART). */
typedef struct aff_xform {
	int32_t parent; /* -1: the root */
	int animated;
	int32_t anim;
	char name[AFF_NAME_MAX];
	double m[12]; /* static: row-major 3x4 T*R*S */
} aff_xform;

typedef struct aff_mat {
	double amb[3], diff[3], spec[3], shine, transmit, ior;
} aff_mat;

typedef struct aff_tex {
	char path[256];  /* resolved file (as long as scene.h's texture paths) */
	char where[320]; /* "file:line:col" of the first texturecoords naming it */
} aff_tex;

/* A mesh (or polygon) in the frame of transform `xform` (-1: world).
 * Triangle i's corners are idx[9i..9i+8]: 3 vertex, 3 normal, 3 texture
 * coordinate indices into this mesh's ranges of the pools (UINT32_MAX:
 * absent). */
typedef struct aff_mesh {
	int32_t xform;
	int32_t mat;                       /* -1: the default material */
	int32_t tex;                       /* -1: none */
	uint32_t v0, nv, n0, nn, uv0, nuv; /* ranges in the pools */
	uint32_t t0, ntris;                /* range in idx (triangles) */
} aff_mesh;

typedef struct aff_scene {
	char path[1024]; /* entry file */
	aff_xform *xf;
	uint32_t nxf, capxf;
	aff_mesh *mesh;
	uint32_t nmesh, capmesh;
	float *pv, *pn, *puv; /* vertex, normal (3 each), uv (2) pools */
	uint32_t npv, npn, npuv, cappv, cappn, cappuv;
	uint32_t *idx;
	uint32_t ntris, capidx; /* idx holds 9 * capidx */
	aff_mat *mat;
	uint32_t nmat, capmat;
	aff_tex *tex;
	uint32_t ntex, captex;
	aff_anim *anim;
	uint32_t nanim, capanim;
	int32_t cam_anim; /* the `k camera` block, or -1 */
	/* view and lights */
	int has_view;
	double from[3], at[3], up[3], angle, hither;
	int res[2];
	int nlights;
	double light[VIEW_MAX_LIGHTS][6];
	double ambient[3], background[3];
	/* `a start end frames` */
	int has_range;
	double t_start, t_end;
	int frames;
	uint32_t nfiles;    /* distinct files read */
	uint32_t nincludes; /* include lines carried out */
	uint32_t nkeys;     /* keyframes read */
	uint64_t bytes;     /* bytes read, includes counted each time */
} aff_scene;

/* 1 if path names an AFF file (ends in .aff). */
int aff_is(const char *path);

/* Reads the entry file and its includes. -1 with "file:line:col: reason"
 * in d on bad input. fn (may be NULL) is told of every file read. */
int aff_load(aff_scene *a, const char *path, scene_file_fn fn, void *ctx, diag *d);
void aff_free(aff_scene *a);

/* The world matrix (row-major 3x4) of every transform at time t into m
 * (12 * a->nxf doubles): parent * local, local = T*R*S. */
void aff_matrices(const aff_scene *a, double t, double *m);

/* The scene at time t as one triangle soup: every mesh placed by its
 * transforms, normals by their inverse transpose, one material per used
 * (fm, texture) pair, textures read when `textures` is set. */
int aff_flatten(const aff_scene *a, double t, int textures, scene *s, diag *d);

/* The same soup, triangles in the same order, with every mesh in its own
 * transform node's frame (no transform applied): the two-level scenes'
 * shading image (twolevel.h), the same at every time. */
int aff_flatten_local(const aff_scene *a, int textures, scene *s, diag *d);

/* The camera at time t: the `k camera` block's translation as the eye and
 * its rotation R as the orientation (view direction -R[:,2], up R[:,1]),
 * over the static `v` (which gives the field of view, and eye and
 * orientation where the block has none); the file's lights. Returns 1
 * with *v filled, 0 when the file has neither `v` nor `k camera`, -1
 * with d on a degenerate camera. */
int aff_view(const aff_scene *a, double t, view *v, diag *d);

#endif
