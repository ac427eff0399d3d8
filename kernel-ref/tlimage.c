/*
 * tlimage.c: the chip's memory image of a two-level scene (tlimage.h).
 */
#include "kernel-ref/tlimage.h"

#include <stdlib.h>
#include <string.h>

static void put_box(uint8_t *b, aabb x)
{
	const float f[6] = {x.lo.x, x.lo.y, x.lo.z, x.hi.x, x.hi.y, x.hi.z};
	memcpy(b, f, sizeof f);
}

static aabb get_box(const uint8_t *b)
{
	float f[6];
	memcpy(f, b, sizeof f);
	return (aabb){v3(f[0], f[1], f[2]), v3(f[3], f[4], f[5])};
}

static void put32(uint8_t *b, uint64_t v)
{
	uint32_t x = (uint32_t)v;
	memcpy(b, &x, 4);
}

static uint32_t get32(const uint8_t *b)
{
	uint32_t x;
	memcpy(&x, b, 4);
	return x;
}

void tli_node_decode(const uint8_t *b, tli_node *n)
{
	n->box = get_box(b);
	n->first = get32(b + 24);
	n->count = get32(b + 28);
}

void tli_inst_decode(const uint8_t *b, tli_inst *in)
{
	memcpy(in->inv, b, sizeof in->inv);
	in->box = get_box(b + 96);
	memset(&in->regs, 0, sizeof in->regs);
	in->regs.bounds = get_box(b + 120);
	in->regs.base[MIMG_NODES] = get32(b + 144);
	in->regs.base[MIMG_LISTS] = get32(b + 148);
	in->regs.base[MIMG_TRIS] = get32(b + 152);
	in->map = get32(b + 156);
}

/* Object ob's image at offset base: its bytes, the list entries (triangle
 * addresses in its own image) moved by base. */
static void place_object(uint8_t *dst, const tl_object *ob, uint64_t base)
{
	const mimg *m = &ob->m;
	memcpy(dst + base, m->bytes, m->size);
	uint8_t *l = dst + base + m->base[MIMG_LISTS];
	for (uint32_t k = 0; k < m->nlist; k++)
		put32(l + 4 * (uint64_t)k, get32(l + 4 * (uint64_t)k) + base);
}

uint64_t tli_write_top(tl_image *im, const tl_scene *t)
{
	uint8_t *b = im->bytes + im->top_base;
	for (uint32_t k = 0; k < t->nnode; k++, b += TLI_NODE_BYTES) {
		const tl_node *n = &t->node[k];
		put_box(b, n->box);
		put32(b + 24, n->count ? n->first : n->left);
		put32(b + 28, n->count);
	}
	b = im->bytes + im->inst_base;
	for (uint32_t k = 0; k < t->ninst; k++, b += TLI_INST_BYTES) {
		const tl_inst *in = &t->inst[t->order[k]];
		const tl_object *ob = &t->obj[in->obj];
		uint64_t o = im->obj_base[in->obj];
		memcpy(b, in->inv, 96);
		put_box(b + 96, in->box);
		put_box(b + 120, ob->m.bounds);
		put32(b + 144, o + ob->m.base[MIMG_NODES]);
		put32(b + 148, o + ob->m.base[MIMG_LISTS]);
		put32(b + 152, o + ob->m.base[MIMG_TRIS]);
		put32(b + 156, im->map_base + 4 * (uint64_t)in->first);
		memcpy(b + TLI_INST_WALK_BYTES, t->xf + (size_t)k * SHADE_XF_BYTES, SHADE_XF_BYTES);
	}
	return im->top_bytes;
}

/* The image's layout: the parts' bases and its size (obj_base NULL: the
 * objects' bases are not kept). */
static void layout(tl_image *im, const tl_scene *t, const mimg *world)
{
	uint64_t at = mimg_align_up(world->size, TLI_ALIGN);
	uint64_t ntri = 0;
	for (uint32_t o = 0; o < t->nobj; o++) {
		if (im->obj_base)
			im->obj_base[o] = at;
		at = mimg_align_up(at + t->obj[o].m.size, TLI_ALIGN);
		if (t->obj[o].m.nnodes > im->max_nodes)
			im->max_nodes = t->obj[o].m.nnodes;
	}
	for (uint32_t k = 0; k < t->ninst; k++)
		ntri += t->obj[t->inst[k].obj].ntris;
	im->map_base = at;
	im->top_base = mimg_align_up(at + 4 * ntri, TLI_ALIGN);
	im->inst_base = im->top_base + (uint64_t)t->nnode * TLI_NODE_BYTES;
	im->top_bytes = im->inst_base + (uint64_t)t->ninst * TLI_INST_BYTES - im->top_base;
	im->size = im->top_base + im->top_bytes;
	im->shade = (shade_tl){im->inst_base + TLI_INST_WALK_BYTES, TLI_INST_BYTES, NULL, 0};
}

uint64_t tli_size(const tl_scene *t, const mimg *world)
{
	tl_image im;
	memset(&im, 0, sizeof im);
	layout(&im, t, world);
	return im.size;
}

int tli_build(tl_image *im, const tl_scene *t, const mimg *world, diag *d)
{
	memset(im, 0, sizeof *im);
	im->obj_base = calloc((size_t)t->nobj + 1, sizeof *im->obj_base);
	if (!im->obj_base)
		return diag_set(d, "two-level image", 0, 0, "out of memory");
	layout(im, t, world);
	/* the image's addresses are 32-bit (list entries, records) */
	if (im->size > UINT32_MAX || !(im->bytes = calloc(1, im->size))) {
		tli_free(im);
		return diag_set(d, "two-level image", 0, 0, "out of memory (or over 4 GB)");
	}
	memcpy(im->bytes, world->bytes, world->size);
	for (uint32_t o = 0; o < t->nobj; o++)
		place_object(im->bytes, &t->obj[o], im->obj_base[o]);
	/* the map: instance k's object triangle j is the flattened scene's
	 * gtri[first + j] (twolevel.c world_addr) */
	for (uint32_t k = 0; k < t->ninst; k++) {
		const tl_inst *in = &t->inst[k];
		for (uint32_t j = 0; j < t->obj[in->obj].ntris; j++)
			put32(im->bytes + im->map_base + 4 * ((uint64_t)in->first + j),
			      mimg_tri_addr(world, t->gtri[in->first + j]));
	}
	tli_write_top(im, t);
	return 0;
}

void tli_free(tl_image *im)
{
	free(im->bytes);
	free(im->obj_base);
	memset(im, 0, sizeof *im);
}
