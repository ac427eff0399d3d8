/*
 * scene.h: the triangle scene every part of saarsim shares.
 *
 * A scene is a flat triangle soup with per-corner normals and texture
 * coordinates, a material per triangle and decoded textures. Importers
 * (import.c: Assimp, .gz through zlib, run by importproc.c), the embedded
 * default scene (default_scene.c) and procedural generators all fill it
 * through the small builder API below, so everything downstream (kd-tree,
 * memory image, tracer, chip model) sees one representation.
 *
 * Invariants after scene_finish(): ntris > 0; every position is finite;
 * n[] is never NULL (face normals are filled in when the file had none, and
 * a zero-length file normal is replaced by the face normal); every mat[i] <
 * nmats; every texture index in a material is -1 or < ntexs; bounds covers
 * every vertex.
 */
#ifndef SAAR_KREF_SCENE_H
#define SAAR_KREF_SCENE_H

#include <stdint.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/vecmath.h"

typedef struct material {
	char name[64];
	vec3 ka, kd, ks;  /* ambient, diffuse, specular colour (MTL Ka Kd Ks) */
	vec3 ke;          /* emission (MTL Ke), added unshadowed */
	float ns;         /* Phong exponent (MTL Ns) */
	float ni;         /* index of refraction (MTL Ni; 1 when absent or 0) */
	float transmit;   /* fraction refracted: from d (1-d), Tr or Tf */
	float reflect;    /* fraction mirrored: MTL "refl" / illum 3,5,7 (Ks) */
	int32_t tex_kd;   /* index into scene.texs for map_Kd, or -1 */
	int32_t tex_bump; /* index into scene.texs for bump / map_bump, or -1 */
	float bump_scale; /* bump height scale (MTL -bm), 1 by default */
} material;

typedef struct texture {
	char path[256];
	int w, h;
	uint8_t *rgba; /* w*h*4 bytes, row 0 is the top row (v = 1) */
} texture;

typedef struct scene {
	char name[256]; /* file path, or "embedded:..." / "spd:..." */
	uint32_t ntris;
	uint32_t cap;  /* builder capacity (triangles) */
	vec3 *v;       /* 3*ntris corner positions: triangle i is v[3i..3i+2] */
	vec3 *n;       /* 3*ntris corner normals, unit length */
	vec2 *uv;      /* 3*ntris texture coordinates (0,0 when absent) */
	uint32_t *mat; /* ntris material indices */
	int has_uv;    /* any texture coordinates came from the file */
	material *mats;
	uint32_t nmats;
	texture *texs;
	uint32_t ntexs;
	aabb bounds;
	uint32_t ndegenerate; /* zero-area triangles kept as they are */
} scene;

/* Loads a scene file through Assimp: .obj (with .mtl), .ply, .stl, .3ds,
 * .gltf, .glb or .dae, its content checked against the extension first. A
 * path ending in .gz is decompressed with zlib first; files it refers to
 * (an MTL beside the OBJ) are still found next to it. Textures named by
 * the materials are read with OpenImageIO. Fails (diag filled, -1) on an
 * unsupported format, a missing or unreadable file, a malformed scene,
 * NaN/Inf positions or zero triangles.
 *
 * The import runs in a child process under a CPU and an address-space
 * limit (importproc.c; docs/design.md, "Third-party parsers"), so a file
 * that makes Assimp loop, allocate without end or crash is an error too.
 * SAARSIM_IMPORT_CPU_S and SAARSIM_IMPORT_MEM_MB set the limits; a bad
 * value is an error naming the variable. */
int scene_load(scene *s, const char *path, diag *d);

/* scene_load, and calls fn(ctx, path) for the scene file and every other
 * file the import opens through Assimp (an MTL, a glTF buffer): what a
 * cache of the built scene must watch (worldcache.c). A file the import
 * looked for and did not find (an OBJ's missing MTL: the import goes on
 * with default materials) is passed too, its path after the byte
 * SCENE_FILE_ABSENT: the cache must see it appear. Textures are not
 * passed (a missing one fails the import); their paths are in s->texs.
 * fn may see a path more than once; it runs in the calling process, after
 * the import. */
#define SCENE_FILE_ABSENT '\x01'
typedef void (*scene_file_fn)(void *ctx, const char *path);
int scene_load_files(scene *s, const char *path, scene_file_fn fn, void *ctx, diag *d);

/* The same import in the calling process, without the child process and
 * its limits: for fuzzers and tests that exercise the checks and the
 * conversion themselves. Assimp's stderr is silenced while it runs. Not
 * for user input in the programs: a file that makes Assimp hang hangs the
 * caller. */
int scene_import_inproc(scene *s, const char *path, scene_file_fn fn, void *ctx, diag *d);

/* The embedded default scene: a Cornell-like room with a diffuse box, a
 * mirror sphere and a glass sphere (tessellated), needing no files. Its
 * standard view is view_default(). */
void scene_default(scene *s);

/* Builder. scene_init zeroes s; scene_add_material returns its index;
 * scene_add_triangle copies 3 positions, optional 3 normals (NULL: face
 * normal) and optional 3 uvs (NULL: zeros). scene_finish fixes normals,
 * computes bounds and checks the invariants above (-1 with diag on
 * failure, naming `file`). */
void scene_init(scene *s, const char *name);
uint32_t scene_add_material(scene *s, const material *m);
void scene_add_triangle(scene *s, const vec3 p[3], const vec3 *n, const vec2 *uv, uint32_t mat);
int scene_finish(scene *s, const char *file, diag *d);
void scene_free(scene *s);

/* A material with neutral defaults (grey diffuse, no specular, no
 * textures, ni 1). */
material material_default(const char *name);

static inline vec3 scene_face_normal(const scene *s, uint32_t tri)
{
	const vec3 *p = s->v + 3 * (uint64_t)tri;
	return v3_norm(v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0])));
}

#endif
