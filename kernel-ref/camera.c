/*
 * camera.c: primary rays for tiles (see camera.h).
 */
#include "kernel-ref/camera.h"
#include "kernel-ref/simd.h"

#include "kernel-ref/sudoku.h"

#include <stddef.h>
#include <string.h>

void cam_setup(cam_frame *c, const camera *cam, int width, int height)
{
	c->eye = cam->eye;
	c->w = v3_norm(v3_sub(cam->lookat, cam->eye));
	c->u = v3_norm(v3_cross(c->w, cam->up));
	c->v = v3_cross(c->u, c->w);
	c->sy = tanf(cam->fov_deg * (float)M_PI / 360.0f);
	c->sx = c->sy * (float)width / (float)height;
	c->width = width;
	c->height = height;
	c->spp = 1;
	c->lens_r = 0.0f;
	c->inv_f = 1.0f;
	c->motion = v3(0, 0, 0);
	c->weight = 1.0f;
}

void cam_setup_view(cam_frame *c, const view *v, int width, int height)
{
	cam_setup(c, &v->cam, width, height);
	const drt_params *p = &v->drt;
	c->spp = drt_spp(p);
	c->lens_r = 0.5f * p->aperture;
	float f = p->focus > 0.0f ? p->focus : v3_len(v3_sub(v->cam.lookat, v->cam.eye));
	c->inv_f = 1.0f / f;
	c->motion = p->motion;
	c->weight = 1.0f / (float)c->spp;
}

/* Sample s of pixel (x, y): origin and direction through the thin lens
 * at the shutter time of the sample. The pinhole ray d points at the
 * focal plane's point eye + f d (d has unit length along w); from the
 * lens point eye + l the direction is f d - l, i.e. d - l / f. A zero
 * lens offset or motion adds nothing (drt_add), so a pinhole is exact. */
static void sample_ray(const cam_frame *c, int x, int y, int s, vec3 *o, vec3 *dir)
{
	float u, v;
	sudoku_sample((uint32_t)x, (uint32_t)y, s, SUDOKU_DIM_IMAGE, c->spp, &u, &v);
	float px = (2.0f * ((float)x + u) / (float)c->width - 1.0f) * c->sx;
	float py = (1.0f - 2.0f * ((float)y + v) / (float)c->height) * c->sy;
	vec3 d = v3_add(c->w, v3_add(v3_scale(c->u, px), v3_scale(c->v, py)));
	vec3 e = c->eye;
	if (c->spp > 1 || c->lens_r != 0.0f || c->motion.x != 0.0f || c->motion.y != 0.0f ||
	    c->motion.z != 0.0f) {
		float t, tv, lu, lv;
		sudoku_sample((uint32_t)x, (uint32_t)y, s, SUDOKU_DIM_TIME, c->spp, &t, &tv);
		e = drt_add3(e, v3_scale(c->motion, t));
		sudoku_sample((uint32_t)x, (uint32_t)y, s, SUDOKU_DIM_LENS, c->spp, &lu, &lv);
		float th = 2.0f * (float)M_PI * lu, r = c->lens_r * sqrtf(lv);
		vec3 l = v3_add(v3_scale(c->u, r * cosf(th)), v3_scale(c->v, r * sinf(th)));
		e = drt_add3(e, l);
		d = drt_add3(d, v3_scale(l, -c->inv_f));
	}
	*o = e;
	*dir = v3_norm(d);
}

void pkt_clear(packet *p, int type, int depth)
{
	memset(p, 0, sizeof *p);
	p->type = (uint8_t)type;
	p->depth = (uint8_t)depth;
}

int cam_primary_packet(const cam_frame *c, int tx, int ty, packet *p)
{
	return cam_sample_packet(c, tx, ty, 0, p);
}

/* A pinhole camera's packet (one sample per pixel, no lens, no motion):
 * sample_ray's arithmetic for the pixel centres, the same operations in
 * the same order lane by lane (so the same floats), as loops over the
 * packet's arrays, the directions in SIMD_W-lane vectors (a square
 * root and a division are correctly rounded in a lane as alone;
 * tests/test_trace.c checks the floats). The tile lies wholly inside the
 * frame. */
static void pinhole_packet(const cam_frame *c, int tx, int ty, packet *p)
{
#if SIMD_W == 16 && TILE_W == 8 && TILE_H == 8 && defined(__GNUC__) && __GNUC__ >= 12
	/* A lane group is two tile rows: a pixel's x depends on its column,
	 * its y on its row, so the tile's eight of each, in one 8-lane vector
	 * each, are all there is to compute (the scalar loop's 128 divisions
	 * and its stores read back as vectors, which the store buffer cannot
	 * forward, cost more than the directions) */
	typedef float f8 __attribute__((vector_size(32)));
	const f8 i8 = {0, 1, 2, 3, 4, 5, 6, 7};
	f8 x8 = (float)(tx * TILE_W) + i8, y8 = (float)(ty * TILE_H) + i8;
	f8 cx = (2.0f * (x8 + 0.5f) / (float)c->width - 1.0f) * c->sx;
	f8 ry = (1.0f - 2.0f * (y8 + 0.5f) / (float)c->height) * c->sy;
	const fv xs =
	    __builtin_shufflevector(cx, cx, 0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3, 4, 5, 6, 7);
	const fv ys[4] = {
	    __builtin_shufflevector(ry, ry, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1),
	    __builtin_shufflevector(ry, ry, 2, 2, 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3),
	    __builtin_shufflevector(ry, ry, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 5, 5, 5, 5, 5),
	    __builtin_shufflevector(ry, ry, 6, 6, 6, 6, 6, 6, 6, 6, 7, 7, 7, 7, 7, 7, 7, 7)};
#else
	float px[PKT_RAYS], py[PKT_RAYS];
	for (int l = 0; l < PKT_RAYS; l++) {
		float x = (float)(tx * TILE_W + l % TILE_W), y = (float)(ty * TILE_H + l / TILE_W);
		px[l] = (2.0f * (x + 0.5f) / (float)c->width - 1.0f) * c->sx;
		py[l] = (1.0f - 2.0f * (y + 0.5f) / (float)c->height) * c->sy;
	}
#endif
	/* the directions SIMD_W lanes at a time: the same operations, each
	 * correctly rounded in a lane as alone */
	for (int o = 0; o < PKT_RAYS; o += SIMD_W) {
#if SIMD_W == 16 && TILE_W == 8 && TILE_H == 8 && defined(__GNUC__) && __GNUC__ >= 12
		fv x = xs, y = ys[o / SIMD_W];
#else
		fv x = fv_load(px + o), y = fv_load(py + o);
#endif
		fv dx = fv_set1(c->w.x) + (fv_set1(c->u.x) * x + fv_set1(c->v.x) * y);
		fv dy = fv_set1(c->w.y) + (fv_set1(c->u.y) * x + fv_set1(c->v.y) * y);
		fv dz = fv_set1(c->w.z) + (fv_set1(c->u.z) * x + fv_set1(c->v.z) * y);
		fv len = fv_sqrt(dx * dx + dy * dy + dz * dz), inv = fv_set1(1.0f) / len;
		iv pos = len > fv_set1(0.0f);
		fv_store(p->dx + o, fv_sel(pos, dx * inv, dx));
		fv_store(p->dy + o, fv_sel(pos, dy * inv, dy));
		fv_store(p->dz + o, fv_sel(pos, dz * inv, dz));
	}
	for (int l = 0; l < PKT_RAYS; l++) {
		p->ox[l] = c->eye.x;
		p->oy[l] = c->eye.y;
		p->oz[l] = c->eye.z;
		p->tmax[l] = INFINITY;
		p->wr[l] = p->wg[l] = p->wb[l] = c->weight;
		p->pixel[l] =
		    (uint32_t)((ty * TILE_H + l / TILE_W) * c->width + tx * TILE_W + l % TILE_W);
	}
	p->valid = ~0ull;
}

int cam_sample_packet(const cam_frame *c, int tx, int ty, int s, packet *p)
{
	if (c->spp == 1 && c->lens_r == 0.0f && c->motion.x == 0.0f && c->motion.y == 0.0f &&
	    c->motion.z == 0.0f && (tx + 1) * TILE_W <= c->width &&
	    (ty + 1) * TILE_H <= c->height) {
		/* pkt_clear's bytes, but the arrays before t, which
		 * pinhole_packet writes in every lane, are not zeroed first */
		_Static_assert(offsetof(packet, t) == 11 * PKT_RAYS * sizeof(float),
		               "cam_sample_packet: pinhole_packet writes ox .. wb, nothing else");
		memset(&p->t, 0, sizeof *p - offsetof(packet, t));
		p->type = PKT_PRIMARY;
		p->depth = 0;
		p->sample = (uint16_t)s;
		p->n = PKT_RAYS;
		pinhole_packet(c, tx, ty, p);
		return PKT_RAYS;
	}
	pkt_clear(p, PKT_PRIMARY, 0);
	p->sample = (uint16_t)s;
	p->n = PKT_RAYS;
	int nvalid = 0;
	for (int j = 0; j < TILE_H; j++)
		for (int i = 0; i < TILE_W; i++) {
			int lane = j * TILE_W + i;
			int x = tx * TILE_W + i, y = ty * TILE_H + j;
			p->tmax[lane] = INFINITY;
			if (x >= c->width || y >= c->height)
				continue;
			vec3 o, d;
			sample_ray(c, x, y, s, &o, &d);
			p->ox[lane] = o.x;
			p->oy[lane] = o.y;
			p->oz[lane] = o.z;
			p->dx[lane] = d.x;
			p->dy[lane] = d.y;
			p->dz[lane] = d.z;
			p->pixel[lane] = (uint32_t)(y * c->width + x);
			p->wr[lane] = p->wg[lane] = p->wb[lane] = c->weight;
			p->valid |= 1ull << lane;
			nvalid++;
		}
	p->n = PKT_RAYS;
	return nvalid;
}
