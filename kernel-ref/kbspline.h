/*
 * kbspline.h: Kochanek-Bartels (TCB) keyframe splines as BART uses them
 * for its animated transforms and camera (Lext, Assarsson, Moller, "BART:
 * A Benchmark for Animated Ray Tracing", 2001, section "Animation";
 * Kochanek and Bartels, "Interpolating Splines with Local Tension,
 * Continuity, and Bias Control", SIGGRAPH 1984).
 *
 * A track is n >= 4 keys in file order. The first and the last key only
 * shape the end tangents: the curve runs from key 1 to key n-2 through
 * n-3 segments (segment j joins key j+1 and key j+2), and holds its end
 * values outside that range. Positions and scales are cubic Hermite
 * segments; rotations are unit quaternions joined by squad. Both use the
 * TCB tangent weights with BART's correction for unequal key spacing.
 */
#ifndef SAAR_KREF_KBSPLINE_H
#define SAAR_KREF_KBSPLINE_H

#include <stdint.h>

/* Fewest keys a track may have (two inner keys and the two tangent keys). */
#define KB_MIN_KEYS 4

typedef struct kb_key {
	double t;          /* key time */
	double v[4];       /* position/scale x y z; rotation: axis x y z, angle (degrees) */
	double tension;    /* T: 1 tightens the curve at the key, -1 slackens it */
	double continuity; /* C: 0 keeps the tangent continuous across the key */
	double bias;       /* B: leans the tangent towards the previous (+) or next (-) key */
} kb_key;

/* The segment that time t falls in and the parameter u in [0, 1] on it:
 * the FIRST segment, in key order, whose end time exceeds t (BART's rule;
 * it also decides where t falls when key times are not sorted, as in the
 * Robots' gun_rot1), clamped to the first segment's start and the last
 * segment's end. n >= KB_MIN_KEYS. */
void kb_segment(const kb_key *k, uint32_t n, double t, uint32_t *seg, double *u);

/* Position (or scale) track at time t into out[3]. */
void kb_pos_eval(const kb_key *k, uint32_t n, double t, double out[3]);

/* The key quaternions of a rotation track (w, x, y, z each), in key order:
 * key i's rotation of v[3] degrees about its axis (normalised; a zero
 * axis is an error the reader refuses), each negated where needed so that
 * it makes an acute angle with the previous one. q holds 4n doubles. */
void kb_rot_quats(const kb_key *k, uint32_t n, double *q);

/* Rotation track at time t as a unit quaternion (w, x, y, z) into out[4];
 * q from kb_rot_quats. */
void kb_rot_eval(const kb_key *k, const double *q, uint32_t n, double t, double out[4]);

/* The 3x3 rotation matrix (row-major) of unit quaternion q. */
void kb_quat_matrix(const double q[4], double m[9]);

#endif
