/*
 * objmini.h: a tiny test-only OBJ reader ('v' and triangular 'f' lines,
 * plain or .gz through zlib) so kd-tree and memory-image tests can load the
 * shared scenes without the real importer. Not a general OBJ parser: no
 * materials, normals, texcoords or polygons beyond the first triangle fan.
 */
#ifndef SAAR_TESTS_OBJMINI_H
#define SAAR_TESTS_OBJMINI_H

#include <stdlib.h>
#include <zlib.h>

#include "kernel-ref/scene.h"

/* Loads path into s (scene_init'ed here); 0 on success. */
static inline int objmini_load(scene *s, const char *path)
{
	gzFile f = gzopen(path, "rb");
	if (!f)
		return -1;
	scene_init(s, path);
	vec3 *v = NULL;
	size_t nv = 0, cap = 0;
	char line[512];
	int rc = 0;
	while (gzgets(f, line, sizeof line)) {
		if (line[0] == 'v' && line[1] == ' ') {
			if (nv == cap) {
				cap = cap ? 2 * cap : 4096;
				v = realloc(v, cap * sizeof *v);
			}
			vec3 *p = &v[nv++];
			char *e = line + 2;
			p->x = strtof(e, &e);
			p->y = strtof(e, &e);
			p->z = strtof(e, &e);
		} else if (line[0] == 'f' && line[1] == ' ') {
			long idx[3];
			char *e = line + 2;
			for (int i = 0; i < 3; i++) {
				idx[i] = strtol(e, &e, 10);
				while (*e && *e != ' ' && *e != '\t' && *e != '\n')
					e++; /* skip /vt/vn */
				if (idx[i] < 1 || (size_t)idx[i] > nv)
					rc = -1;
			}
			if (rc)
				break;
			vec3 p[3] = {v[idx[0] - 1], v[idx[1] - 1], v[idx[2] - 1]};
			scene_add_triangle(s, p, NULL, NULL, 0);
		}
	}
	gzclose(f);
	free(v);
	if (rc == 0 && scene_finish(s, path, NULL))
		rc = -1;
	if (rc)
		scene_free(s);
	return rc;
}

#endif
