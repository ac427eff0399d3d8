/*
 * camera.h: primary-ray generation for 8x8 tiles (the RGS's first job).
 *
 * Pinhole camera from a view: vertical field of view, square pixels, rays
 * through pixel centres. A tile at the frame's right or bottom edge has
 * fewer valid rays; the packet keeps 64 lanes and a valid mask.
 *
 * Distribution ray tracing (drt.h, seed 000 §3.1, §3.4): with spp samples
 * per pixel a tile has spp primary packets; packet s puts each pixel's
 * sample s (a Sudoku sample, sudoku.h) on the image plane, on a thin lens
 * of diameter `aperture` focused at distance `focus` (theta = 2 pi u,
 * r = aperture sqrt(v) / 2), and at a time t of the shutter, when the
 * camera has moved by t * motion. Each ray weighs 1/spp.
 */
#ifndef SAAR_KREF_CAMERA_H
#define SAAR_KREF_CAMERA_H

#include "kernel-ref/packet.h"
#include "kernel-ref/view.h"

#define TILE_W 8
#define TILE_H 8

typedef struct cam_frame {
	vec3 eye, u, v, w; /* right, up, forward (unit) */
	float sx, sy;      /* image-plane half extents at distance 1 */
	int width, height;
	/* distribution ray tracing (drt.h); cam_setup: one sample, a pinhole */
	int spp;
	float lens_r; /* lens radius: aperture / 2 */
	float inv_f;  /* 1 / focal distance */
	vec3 motion;  /* camera displacement over the shutter */
	float weight; /* 1 / spp */
} cam_frame;

void cam_setup(cam_frame *c, const camera *cam, int width, int height);
/* The same with view v's distribution effects (v->drt). */
void cam_setup_view(cam_frame *c, const view *v, int width, int height);

/* Zeroes p and fills the primary rays of tile (tx, ty) (tile coordinates,
 * TILE_W x TILE_H pixels each). Returns the number of valid rays. */
int cam_primary_packet(const cam_frame *c, int tx, int ty, packet *p);
/* The same for sample s (0 <= s < c->spp) of each pixel: packet.sample
 * is s. cam_primary_packet is sample 0. */
int cam_sample_packet(const cam_frame *c, int tx, int ty, int s, packet *p);

#endif
