/*
 * memimage.c: mimg_build, the flat memory image of memimage.h.
 *
 * Owns the byte layout of docs/memory-map.md. Invariants of a built image:
 * one calloc'd array of m->size bytes; regions in enum order (header,
 * nodes, lists, tris, shade, mats, texhdr, texels), each starting on a
 * MIMG_ALIGN (128-byte) boundary, so no two regions share a cache line
 * (the triangles on a MIMG_TRI_ALIGN one, so each record fills one 36-byte
 * triangle-cache line);
 * every address (list entries, texel_addr) fits in 32 bits, as the chip's
 * address registers are 32 bits wide. Gaps between regions are zero.
 *
 * The header region holds mimg_header below (little-endian, 192 bytes):
 * magic, version, base and length of every region, the record counts and
 * the scene box, so an image dumped to a file describes itself.
 */
#include "kernel-ref/memimage.h"

#include <stdlib.h>
#include <string.h>

#define MIMG_VERSION 1u
#define MIMG_4GIB    (UINT64_C(1) << 32)

typedef struct mimg_header {
	char magic[8];     /* "SAARMIMG", no terminator */
	uint32_t version;  /* MIMG_VERSION */
	uint32_t nregions; /* MIMG_NREGIONS */
	uint64_t base[MIMG_NREGIONS];
	uint64_t len[MIMG_NREGIONS];
	uint32_t nnodes, nlist, ntris, nmats, ntexs;
	float bounds[6]; /* lo xyz, hi xyz */
	uint32_t reserved;
} mimg_header;

_Static_assert(sizeof(mimg_header) == 192, "header layout of docs/memory-map.md");
_Static_assert(sizeof(kd_node) == MIMG_NODE_BYTES, "node record");
_Static_assert(sizeof(mimg_tri) == MIMG_TRI_BYTES, "triangle record");
_Static_assert(MIMG_TRI_ALIGN % MIMG_TRI_BYTES == 0 && MIMG_TRI_ALIGN % MIMG_ALIGN == 0,
               "triangle region alignment");
_Static_assert(sizeof(mimg_shade) == MIMG_SHADE_BYTES, "shading record");
_Static_assert(sizeof(mimg_mat) == MIMG_MAT_BYTES, "material record");
_Static_assert(sizeof(mimg_texhdr) == MIMG_TEXHDR_BYTES, "texture header record");

const char *mimg_region_name(int region)
{
	static const char *const names[MIMG_NREGIONS] = {"header", "nodes", "lists",  "tris",
	                                                 "shade",  "mats",  "texhdr", "texels"};
	return region >= 0 && region < MIMG_NREGIONS ? names[region] : "?";
}

/* The regions' bases and lengths into m from the scene's and the tree's
 * sizes; the image's size into *size. Checks only sizes, so an oversized
 * scene fails without allocating. */
static int layout(mimg *m, const scene *s, const kdtree *t, const char *file, uint64_t *size,
                  diag *d)
{
	uint64_t texel_bytes = 0;
	for (uint32_t i = 0; i < s->ntexs; i++) {
		const texture *x = &s->texs[i];
		if (x->w < 0 || x->h < 0 || (uint64_t)x->w * (uint64_t)x->h >= MIMG_4GIB ||
		    (x->w > 0 && x->h > 0 && !x->rgba))
			return diag_set(d, file, 0, 0, "texture %u (%s) has no valid %dx%d texels",
			                i, x->path, x->w, x->h);
		texel_bytes += 4 * (uint64_t)x->w * (uint64_t)x->h;
	}
	uint64_t len[MIMG_NREGIONS] = {
	    [MIMG_HEADER] = sizeof(mimg_header),
	    [MIMG_NODES] = (uint64_t)MIMG_NODE_BYTES * t->nnodes,
	    [MIMG_LISTS] = (uint64_t)MIMG_LIST_BYTES * t->nlist,
	    [MIMG_TRIS] = (uint64_t)MIMG_TRI_BYTES * s->ntris,
	    [MIMG_SHADE] = (uint64_t)MIMG_SHADE_BYTES * s->ntris,
	    [MIMG_MATS] = (uint64_t)MIMG_MAT_BYTES * s->nmats,
	    [MIMG_TEXHDR] = (uint64_t)MIMG_TEXHDR_BYTES * s->ntexs,
	    [MIMG_TEXELS] = texel_bytes,
	};
	uint64_t at = 0;
	for (int r = 0; r < MIMG_NREGIONS; r++) {
		if (r == MIMG_TRIS)
			at = (at + MIMG_TRI_ALIGN - 1) / MIMG_TRI_ALIGN * MIMG_TRI_ALIGN;
		m->base[r] = at;
		m->len[r] = len[r];
		at = mimg_align_up(at + len[r], MIMG_ALIGN);
	}
	if (at > MIMG_4GIB)
		return diag_set(d, file, 0, 0,
		                "memory image would need %llu bytes; chip addresses are 32 bits (4 "
		                "GiB)",
		                (unsigned long long)at);
	*size = at;
	return 0;
}

/* Every texture a material names and every triangle a list entry names
 * exists. */
static int check_refs(const scene *s, const kdtree *t, const char *file, diag *d)
{
	for (uint32_t i = 0; i < s->nmats; i++) {
		const material *x = &s->mats[i];
		if (x->tex_kd < -1 || x->tex_kd >= (int32_t)s->ntexs || x->tex_bump < -1 ||
		    x->tex_bump >= (int32_t)s->ntexs)
			return diag_set(d, file, 0, 0, "material %u (%s) names a missing texture",
			                i, x->name);
	}
	for (uint32_t k = 0; k < t->nlist; k++)
		if (t->list[k] >= s->ntris)
			return diag_set(d, file, 0, 0,
			                "kd-tree list entry %u names triangle %u of %u", k,
			                t->list[k], s->ntris);
	return 0;
}

static void write_header(mimg *m, const kdtree *t)
{
	mimg_header h;
	memset(&h, 0, sizeof h);
	memcpy(h.magic, "SAARMIMG", 8);
	h.version = MIMG_VERSION;
	h.nregions = MIMG_NREGIONS;
	memcpy(h.base, m->base, sizeof h.base);
	memcpy(h.len, m->len, sizeof h.len);
	h.nnodes = m->nnodes;
	h.nlist = m->nlist;
	h.ntris = m->ntris;
	h.nmats = m->nmats;
	h.ntexs = m->ntexs;
	float b[6] = {t->bounds.lo.x, t->bounds.lo.y, t->bounds.lo.z,
	              t->bounds.hi.x, t->bounds.hi.y, t->bounds.hi.z};
	memcpy(h.bounds, b, sizeof b);
	memcpy(m->bytes, &h, sizeof h);
}

/* The kd-tree's nodes and lists (as triangle addresses), the triangle and
 * shading records. */
static void write_geometry(mimg *m, const scene *s, const kdtree *t)
{
	memcpy(m->bytes + m->base[MIMG_NODES], t->nodes, m->len[MIMG_NODES]);
	uint8_t *p = m->bytes + m->base[MIMG_LISTS];
	for (uint32_t k = 0; k < t->nlist; k++, p += MIMG_LIST_BYTES) {
		uint32_t addr = (uint32_t)mimg_tri_addr(m, t->list[k]);
		memcpy(p, &addr, sizeof addr);
	}
	for (uint32_t i = 0; i < s->ntris; i++) {
		const vec3 *v = s->v + 3 * (size_t)i, *n = s->n + 3 * (size_t)i;
		const vec2 *uv = s->uv + 3 * (size_t)i;
		mimg_tri tr;
		mimg_shade sh;
		for (int c = 0; c < 3; c++) {
			tr.v[c][0] = v[c].x;
			tr.v[c][1] = v[c].y;
			tr.v[c][2] = v[c].z;
			sh.n[c][0] = n[c].x;
			sh.n[c][1] = n[c].y;
			sh.n[c][2] = n[c].z;
			sh.uv[c][0] = uv[c].u;
			sh.uv[c][1] = uv[c].v;
		}
		sh.mat = s->mat[i];
		memcpy(m->bytes + mimg_tri_addr(m, i), &tr, sizeof tr);
		memcpy(m->bytes + mimg_shade_addr(m, i), &sh, sizeof sh);
	}
}

/* The material records, the texture headers and the texels. */
static void write_materials(mimg *m, const scene *s)
{
	for (uint32_t i = 0; i < s->nmats; i++) {
		const material *x = &s->mats[i];
		mimg_mat mm = {
		    .kd = {x->kd.x, x->kd.y, x->kd.z},
		    .ks = {x->ks.x, x->ks.y, x->ks.z},
		    .ka = {x->ka.x, x->ka.y, x->ka.z},
		    .ns = x->ns,
		    .ni = x->ni,
		    .transmit = x->transmit,
		    .reflect = x->reflect,
		    /* checked in check_refs: -1 or < ntexs <= INT16_MAX */
		    .tex_kd = (int16_t)x->tex_kd,
		    .tex_bump = (int16_t)x->tex_bump,
		    .bump_scale = x->bump_scale,
		    .pad = 0,
		};
		memcpy(m->bytes + mimg_mat_addr(m, i), &mm, sizeof mm);
	}
	uint64_t texel = m->base[MIMG_TEXELS];
	for (uint32_t i = 0; i < s->ntexs; i++) {
		const texture *x = &s->texs[i];
		uint64_t bytes = 4 * (uint64_t)x->w * (uint64_t)x->h;
		mimg_texhdr th = {(uint32_t)x->w, (uint32_t)x->h, (uint32_t)texel, 0};
		memcpy(m->bytes + m->base[MIMG_TEXHDR] + (uint64_t)MIMG_TEXHDR_BYTES * i, &th,
		       sizeof th);
		if (bytes)
			memcpy(m->bytes + texel, x->rgba, (size_t)bytes);
		texel += bytes;
	}
}

int mimg_build(mimg *m, const scene *s, const kdtree *t, diag *d)
{
	memset(m, 0, sizeof *m);
	const char *file = s->name[0] ? s->name : "(scene)";
	if (!t || !t->nodes || t->nnodes == 0)
		return diag_set(d, file, 0, 0, "memory image needs a built kd-tree");
	if (s->ntexs > INT16_MAX)
		return diag_set(d, file, 0, 0, "%u textures; the material record holds at most %d",
		                s->ntexs, INT16_MAX);
	uint64_t at = 0;
	if (layout(m, s, t, file, &at, d) || check_refs(s, t, file, d))
		return -1;
	m->bytes = calloc(1, (size_t)at);
	if (!m->bytes)
		return diag_set(d, file, 0, 0, "out of memory for a %llu-byte memory image",
		                (unsigned long long)at);
	m->size = at;
	m->nnodes = t->nnodes;
	m->nlist = t->nlist;
	m->ntris = s->ntris;
	m->nmats = s->nmats;
	m->ntexs = s->ntexs;
	m->bounds = t->bounds;
	write_header(m, t);
	write_geometry(m, s, t);
	write_materials(m, s);
	return 0;
}

void mimg_free(mimg *m)
{
	free(m->bytes);
	memset(m, 0, sizeof *m);
}
