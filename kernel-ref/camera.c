/*
 * camera.c: primary rays for tiles (see camera.h).
 */
#include "kernel-ref/camera.h"

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
}

void pkt_clear(packet *p, int type, int depth)
{
	memset(p, 0, sizeof *p);
	p->type = (uint8_t)type;
	p->depth = (uint8_t)depth;
}

int cam_primary_packet(const cam_frame *c, int tx, int ty, packet *p)
{
	pkt_clear(p, PKT_PRIMARY, 0);
	int nvalid = 0;
	for (int j = 0; j < TILE_H; j++)
		for (int i = 0; i < TILE_W; i++) {
			int lane = j * TILE_W + i;
			int x = tx * TILE_W + i, y = ty * TILE_H + j;
			p->tmax[lane] = INFINITY;
			if (x >= c->width || y >= c->height)
				continue;
			float px = (2.0f * ((float)x + 0.5f) / (float)c->width - 1.0f) * c->sx;
			float py = (1.0f - 2.0f * ((float)y + 0.5f) / (float)c->height) * c->sy;
			vec3 d =
			    v3_norm(v3_add(c->w, v3_add(v3_scale(c->u, px), v3_scale(c->v, py))));
			p->ox[lane] = c->eye.x;
			p->oy[lane] = c->eye.y;
			p->oz[lane] = c->eye.z;
			p->dx[lane] = d.x;
			p->dy[lane] = d.y;
			p->dz[lane] = d.z;
			p->pixel[lane] = (uint32_t)(y * c->width + x);
			p->wr[lane] = p->wg[lane] = p->wb[lane] = 1.0f;
			p->valid |= 1ull << lane;
			nvalid++;
		}
	p->n = PKT_RAYS;
	return nvalid;
}
