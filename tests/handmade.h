/*
 * handmade.h: worlds built by hand for tests: a few quads, a kd-tree whose
 * nodes the test writes itself (no SAH build, so the tree is exactly what
 * the test needs: which triangles lie in which leaf, which child is near),
 * its memory image, a camera and lights. A world made here is freed with
 * world_free like a loaded one.
 */
#ifndef SAAR_TESTS_HANDMADE_H
#define SAAR_TESTS_HANDMADE_H

#include <stdlib.h>
#include <string.h>

#include "kernel-ref/world.h"
#include "tests/testutil.h"

/* An empty world with one grey material (material_default). */
static inline void hm_begin(world *w)
{
	memset(w, 0, sizeof *w);
	scene_init(&w->s, "handmade");
	material m = material_default("grey");
	scene_add_material(&w->s, &m);
}

static inline void hm_tri(world *w, vec3 a, vec3 b, vec3 c)
{
	vec3 t[3] = {a, b, c};
	scene_add_triangle(&w->s, t, NULL, NULL, 0);
}

/* The quad a b c d as two triangles, (a b c) then (a c d). */
static inline void hm_quad(world *w, vec3 a, vec3 b, vec3 c, vec3 d)
{
	hm_tri(w, a, b, c);
	hm_tri(w, a, c, d);
}

/* Finishes the scene and gives it the tree nodes[0..nn) (nodes[0] is the
 * root, leaves index list[0..nl)), whose root box is the scene's box, then
 * builds the memory image and sets the view. */
static inline void hm_finish(world *w, const kd_node *nodes, uint32_t nn, const uint32_t *list,
                             uint32_t nl, camera cam, const light *lights, int nlights)
{
	diag d;
	cr_assert_eq(scene_finish(&w->s, "handmade", &d), 0, "%s", d.msg);
	kdtree *t = &w->kd;
	t->nodes = malloc(nn * sizeof *nodes);
	t->list = malloc((nl ? nl : 1) * sizeof *list);
	cr_assert(t->nodes && t->list, "out of memory");
	memcpy(t->nodes, nodes, nn * sizeof *nodes);
	if (nl)
		memcpy(t->list, list, nl * sizeof *list);
	t->nnodes = nn;
	t->nlist = nl;
	t->bounds = w->s.bounds;
	for (uint32_t i = 0; i < nn; i++)
		t->nleaves += kd_is_leaf(nodes[i]);
	cr_assert_eq(mimg_build(&w->m, &w->s, t, &d), 0, "%s", d.msg);
	snprintf(w->v.name, sizeof w->v.name, "handmade");
	w->v.cam = cam;
	w->v.lights_given = 1;
	w->v.nlights = nlights;
	for (int i = 0; i < nlights; i++)
		w->v.lights[i] = lights[i];
	snprintf(w->scene_label, sizeof w->scene_label, "handmade");
}

/* 64-byte aligned memory for packets, traversal states and stacks. */
static inline void *hm_alloc(size_t n)
{
	void *p = aligned_alloc(64, (n + 63) & ~(size_t)63);
	cr_assert(p, "out of memory");
	memset(p, 0, n);
	return p;
}

#endif
