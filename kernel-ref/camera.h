/*
 * camera.h: primary-ray generation for 8x8 tiles (the RGS's first job).
 *
 * Pinhole camera from a view: vertical field of view, square pixels, rays
 * through pixel centres. A tile at the frame's right or bottom edge has
 * fewer valid rays; the packet keeps 64 lanes and a valid mask.
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
} cam_frame;

void cam_setup(cam_frame *c, const camera *cam, int width, int height);

/* Zeroes p and fills the primary rays of tile (tx, ty) (tile coordinates,
 * TILE_W x TILE_H pixels each). Returns the number of valid rays. */
int cam_primary_packet(const cam_frame *c, int tx, int ty, packet *p);

#endif
