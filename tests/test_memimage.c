/*
 * test_memimage.c: mimg_build layout (memimage.h, docs/memory-map.md).
 *
 * Every region is 128-byte aligned, in order and non-overlapping, gaps are
 * zero, the header describes the image, and every record holds exactly
 * what the scene and the kd-tree say; list entries are byte addresses of
 * triangle records. Oversized images and inconsistent input fail with a
 * diag instead of allocating or crashing.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/memimage.h"
#include "tests/objmini.h"
#include "tests/testutil.h"

static uint32_t rd32(const mimg *m, uint64_t at)
{
	uint32_t x;
	memcpy(&x, m->bytes + at, sizeof x);
	return x;
}

static uint64_t rd64(const mimg *m, uint64_t at)
{
	uint64_t x;
	memcpy(&x, m->bytes + at, sizeof x);
	return x;
}

static void check_image(const mimg *m, const scene *s, const kdtree *t)
{
	/* Header: magic, version, regions, counts (docs/memory-map.md). */
	cr_assert_eq(memcmp(m->bytes, "SAARMIMG", 8), 0);
	cr_assert_eq(rd32(m, 8), 1);
	cr_assert_eq(rd32(m, 12), MIMG_NREGIONS);
	for (int r = 0; r < MIMG_NREGIONS; r++) {
		cr_assert_eq(rd64(m, 16 + 8 * r), m->base[r]);
		cr_assert_eq(rd64(m, 80 + 8 * r), m->len[r]);
	}
	cr_assert_eq(rd32(m, 144), t->nnodes);
	cr_assert_eq(rd32(m, 148), t->nlist);
	cr_assert_eq(rd32(m, 152), s->ntris);
	cr_assert_eq(rd32(m, 156), s->nmats);
	cr_assert_eq(rd32(m, 160), s->ntexs);
	float b[6];
	memcpy(b, m->bytes + 164, sizeof b);
	cr_assert(b[0] == t->bounds.lo.x && b[1] == t->bounds.lo.y && b[2] == t->bounds.lo.z);
	cr_assert(b[3] == t->bounds.hi.x && b[4] == t->bounds.hi.y && b[5] == t->bounds.hi.z);

	/* Regions: aligned, ordered, non-overlapping, zero gaps. */
	uint64_t want[MIMG_NREGIONS] = {
	    192,
	    8ull * t->nnodes,
	    4ull * t->nlist,
	    36ull * s->ntris,
	    64ull * s->ntris,
	    64ull * s->nmats,
	    16ull * s->ntexs,
	    0,
	};
	for (uint32_t i = 0; i < s->ntexs; i++)
		want[MIMG_TEXELS] += 4ull * (uint64_t)s->texs[i].w * (uint64_t)s->texs[i].h;
	cr_assert_eq(m->base[0], 0);
	uint64_t end = 0;
	for (int r = 0; r < MIMG_NREGIONS; r++) {
		cr_assert_eq(m->base[r] % MIMG_ALIGN, 0, "%s unaligned", mimg_region_name(r));
		/* a triangle record fills one 36-byte triangle-cache line */
		if (r == MIMG_TRIS)
			cr_assert_eq(m->base[r] % MIMG_TRI_BYTES, 0, "tris not on a 36-byte line");
		cr_assert_eq(m->len[r], want[r], "%s length", mimg_region_name(r));
		cr_assert_geq(m->base[r], end, "%s overlaps", mimg_region_name(r));
		for (uint64_t g = end; g < m->base[r]; g++)
			cr_assert_eq(m->bytes[g], 0, "gap byte %llu not zero",
			             (unsigned long long)g);
		end = m->base[r] + m->len[r];
	}
	cr_assert_leq(end, m->size);
	cr_assert_leq(m->size, 1ull << 32);
	cr_assert_eq(m->nnodes, t->nnodes);
	cr_assert_eq(m->nlist, t->nlist);
	cr_assert_eq(m->ntris, s->ntris);

	/* Nodes are the tree's nodes, byte for byte. */
	cr_assert_eq(memcmp(m->bytes + m->base[MIMG_NODES], t->nodes, 8ull * t->nnodes), 0);
	cr_assert_eq(mimg_nodes(m)[0].b, t->nodes[0].b);
	/* List entries: byte addresses of triangle records. */
	for (uint32_t k = 0; k < t->nlist; k++) {
		uint32_t a = mimg_lists(m)[k];
		cr_assert_eq(a, rd32(m, mimg_list_addr(m, k)));
		cr_assert(a >= m->base[MIMG_TRIS] && a < m->base[MIMG_TRIS] + m->len[MIMG_TRIS]);
		cr_assert_eq((a - m->base[MIMG_TRIS]) % MIMG_TRI_BYTES, 0);
		cr_assert_eq(mimg_tri_index(m, a), t->list[k]);
		cr_assert_eq(a, mimg_tri_addr(m, t->list[k]));
	}
	/* Triangle and shading records. */
	for (uint32_t i = 0; i < s->ntris; i++) {
		const mimg_tri *tr = mimg_tri_at(m, (uint32_t)mimg_tri_addr(m, i));
		const mimg_shade *sh = mimg_shade_at(m, i);
		for (int c = 0; c < 3; c++) {
			vec3 v = s->v[3 * i + c], n = s->n[3 * i + c];
			vec2 uv = s->uv[3 * i + c];
			cr_assert(tr->v[c][0] == v.x && tr->v[c][1] == v.y && tr->v[c][2] == v.z);
			cr_assert(sh->n[c][0] == n.x && sh->n[c][1] == n.y && sh->n[c][2] == n.z);
			cr_assert(sh->uv[c][0] == uv.u && sh->uv[c][1] == uv.v);
		}
		cr_assert_eq(sh->mat, s->mat[i]);
	}
	/* Materials and textures. */
	for (uint32_t i = 0; i < s->nmats; i++) {
		const mimg_mat *mm = mimg_mat_at(m, i);
		const material *x = &s->mats[i];
		cr_assert(mm->kd[0] == x->kd.x && mm->kd[1] == x->kd.y && mm->kd[2] == x->kd.z);
		cr_assert(mm->ks[0] == x->ks.x && mm->ks[2] == x->ks.z);
		cr_assert(mm->ka[1] == x->ka.y);
		cr_assert(mm->ns == x->ns && mm->ni == x->ni);
		cr_assert(mm->transmit == x->transmit && mm->reflect == x->reflect);
		cr_assert_eq(mm->tex_kd, x->tex_kd);
		cr_assert_eq(mm->tex_bump, x->tex_bump);
		cr_assert(mm->bump_scale == x->bump_scale);
	}
	for (uint32_t i = 0; i < s->ntexs; i++) {
		const mimg_texhdr *th = mimg_texhdr_at(m, i);
		const texture *x = &s->texs[i];
		cr_assert_eq(th->w, (uint32_t)x->w);
		cr_assert_eq(th->h, (uint32_t)x->h);
		uint64_t n = 4ull * (uint64_t)x->w * (uint64_t)x->h;
		cr_assert_geq(th->texel_addr, m->base[MIMG_TEXELS]);
		cr_assert_leq(th->texel_addr + n, m->base[MIMG_TEXELS] + m->len[MIMG_TEXELS]);
		cr_assert_eq(memcmp(m->bytes + th->texel_addr, x->rgba, n), 0);
	}
}

/* Random triangles with normals, uvs, two materials and two textures. */
static void make_scene(scene *s)
{
	scene_init(s, "mimg");
	material a = material_default("plain"), b = material_default("textured");
	b.kd = v3(0.1f, 0.2f, 0.3f);
	b.ks = v3(0.4f, 0.5f, 0.6f);
	b.ns = 20;
	b.ni = 1.5f;
	b.transmit = 0.25f;
	b.reflect = 0.5f;
	b.tex_kd = 0;
	b.tex_bump = 1;
	b.bump_scale = 2;
	scene_add_material(s, &a);
	scene_add_material(s, &b);
	s->ntexs = 2;
	s->texs = calloc(2, sizeof *s->texs);
	int dims[2][2] = {{3, 2}, {5, 1}};
	for (int i = 0; i < 2; i++) {
		texture *x = &s->texs[i];
		x->w = dims[i][0];
		x->h = dims[i][1];
		x->rgba = malloc(4 * (size_t)x->w * (size_t)x->h);
		for (int k = 0; k < 4 * x->w * x->h; k++)
			x->rgba[k] = (uint8_t)(17 * k + 3 * i + 1);
	}
	uint64_t st = 11;
	for (int i = 0; i < 300; i++) {
		vec3 p[3], n[3];
		vec2 uv[3];
		for (int c = 0; c < 3; c++) {
			st = st * 6364136223846793005ull + 1442695040888963407ull;
			float r1 = (float)(st >> 40) / 16777216.0f;
			st = st * 6364136223846793005ull + 1442695040888963407ull;
			float r2 = (float)(st >> 40) / 16777216.0f;
			p[c] = v3(r1 + 0.05f * c, r2, (float)(i % 7) * 0.1f + 0.03f * c);
			n[c] = v3(r2, 1, r1);
			uv[c] = (vec2){r1, r2};
		}
		scene_add_triangle(s, p, n, uv, (uint32_t)(i % 2));
	}
	diag d;
	cr_assert_eq(scene_finish(s, "mimg", &d), 0, "%s", d.msg);
}

Test(memimage, layout_and_records)
{
	scene s;
	make_scene(&s);
	kdtree t;
	mimg m;
	diag d;
	cr_assert_eq(kd_build(&t, &s, NULL, &d), 0, "%s", d.msg);
	cr_assert_eq(mimg_build(&m, &s, &t, &d), 0, "%s", d.msg);
	check_image(&m, &s, &t);
	mimg_free(&m);
	cr_assert_null(m.bytes);
	kd_free(&t);
	scene_free(&s);
}

Test(memimage, region_names)
{
	const char *want[] = {"header", "nodes", "lists",  "tris",
	                      "shade",  "mats",  "texhdr", "texels"};
	for (int r = 0; r < MIMG_NREGIONS; r++)
		cr_assert_str_eq(mimg_region_name(r), want[r]);
	cr_assert_str_eq(mimg_region_name(-1), "?");
	cr_assert_str_eq(mimg_region_name(MIMG_NREGIONS), "?");
}

Test(memimage, over_4gib_fails_without_allocating)
{
	scene s;
	make_scene(&s);
	/* A fake tree whose list alone needs 4 GiB; the data is never read. */
	kd_node root = kd_make_leaf(0, 0);
	kdtree t;
	memset(&t, 0, sizeof t);
	t.nodes = &root;
	t.nnodes = 1;
	t.nlist = 1u << 30;
	mimg m;
	diag d = {{0}};
	cr_assert_eq(mimg_build(&m, &s, &t, &d), -1);
	cr_assert_not_null(strstr(d.msg, "4 GiB"), "%s", d.msg);
	cr_assert_null(m.bytes);
	scene_free(&s);
}

Test(memimage, bad_list_entry_fails)
{
	scene s;
	make_scene(&s);
	uint32_t list[1] = {s.ntris};
	kd_node root = kd_make_leaf(0, 1);
	kdtree t;
	memset(&t, 0, sizeof t);
	t.nodes = &root;
	t.nnodes = 1;
	t.list = list;
	t.nlist = 1;
	mimg m;
	diag d = {{0}};
	cr_assert_eq(mimg_build(&m, &s, &t, &d), -1);
	cr_assert_neq(d.msg[0], 0);
	cr_assert_null(m.bytes);
	scene_free(&s);
}

Test(memimage, dragon_res4)
{
	char path[1024];
	SCENE_OR_SKIP(path, "stanford_dragon/dragon_vrip_res4.obj");
	scene s;
	cr_assert_eq(objmini_load(&s, path), 0, "cannot read %s", path);
	kdtree t;
	mimg m;
	diag d;
	cr_assert_eq(kd_build(&t, &s, NULL, &d), 0, "%s", d.msg);
	cr_assert_eq(mimg_build(&m, &s, &t, &d), 0, "%s", d.msg);
	check_image(&m, &s, &t);
	mimg_free(&m);
	kd_free(&t);
	scene_free(&s);
}
