/*
 * kbspline.c: Kochanek-Bartels splines for BART keyframes (kbspline.h).
 *
 * The formulas are those of Kochanek and Bartels (SIGGRAPH 1984) in the
 * form the BART paper's animation code uses (tangents per segment from
 * four keys, the spacing factor 2*dt_segment / (dt_left + dt_right), and
 * for rotations squad over quaternion logarithms, Shoemake 1987). All in
 * double precision: a frame's transforms are evaluated once per instance,
 * and the result feeds single-precision geometry.
 */
#include "kernel-ref/kbspline.h"

#include <math.h>

#define KB_PI  3.14159265358979323846
#define KB_EPS 1e-6

void kb_segment(const kb_key *k, uint32_t n, double t, uint32_t *seg, double *u)
{
	uint32_t nseg = n - 3;
	if (!(t > k[1].t)) { /* before (or at) the first inner key */
		*seg = 0;
		*u = 0.0;
		return;
	}
	if (!(t < k[nseg + 1].t)) { /* after (or at) the last inner key */
		*seg = nseg - 1;
		*u = 1.0;
		return;
	}
	/* linear, in key order: with unsorted times a binary search would
	 * pick another segment than BART does */
	uint32_t j = 0;
	while (j + 1 < nseg && !(t < k[j + 2].t))
		j++;
	double range = k[j + 2].t - k[j + 1].t;
	double x = range != 0.0 ? (t - k[j + 1].t) / range : 0.0;
	*seg = j;
	*u = x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x;
}

/* 2 * (t2 - t1) / den, the spacing factor; 0 for coinciding keys. */
static double spacing(double t1, double t2, double den)
{
	return den != 0.0 ? 2.0 * (t2 - t1) / den : 0.0;
}

/* The outgoing weights at key b (w[0] on the segment before it, w[1] on
 * the one after) and the incoming weights at key c (w[2] on the segment
 * after it, w[3] on the one before), for the segment from b to c. */
static void tcb_weights(const kb_key *a, const kb_key *b, const kb_key *c, const kb_key *d,
                        double w[4])
{
	double adj0 = spacing(b->t, c->t, c->t - a->t);
	double adj1 = spacing(b->t, c->t, d->t - b->t);
	double tb = 1.0 - b->tension, tc = 1.0 - c->tension;
	w[0] = 0.5 * adj0 * tb * (1.0 + b->continuity) * (1.0 + b->bias);
	w[1] = 0.5 * adj0 * tb * (1.0 - b->continuity) * (1.0 - b->bias);
	w[2] = 0.5 * adj1 * tc * (1.0 + c->continuity) * (1.0 - c->bias);
	w[3] = 0.5 * adj1 * tc * (1.0 - c->continuity) * (1.0 + c->bias);
}

void kb_pos_eval(const kb_key *k, uint32_t n, double t, double out[3])
{
	uint32_t j;
	double u;
	kb_segment(k, n, t, &j, &u);
	const kb_key *a = &k[j], *b = &k[j + 1], *c = &k[j + 2], *d = &k[j + 3];
	double w[4];
	tcb_weights(a, b, c, d, w);
	for (int x = 0; x < 3; x++) {
		double dp = c->v[x] - b->v[x];
		double tout = w[1] * dp + w[0] * (b->v[x] - a->v[x]);
		double tin = w[2] * (d->v[x] - c->v[x]) + w[3] * dp;
		double c2 = 3.0 * dp - 2.0 * tout - tin;
		double c3 = -2.0 * dp + tout + tin;
		out[x] = b->v[x] + u * (tout + u * (c2 + u * c3));
	}
}

/* ---- quaternions (w, x, y, z) ---- */

static void q_mul(const double a[4], const double b[4], double r[4])
{
	double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
	double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
	double y = a[0] * b[2] + a[2] * b[0] + a[3] * b[1] - a[1] * b[3];
	double z = a[0] * b[3] + a[3] * b[0] + a[1] * b[2] - a[2] * b[1];
	r[0] = w;
	r[1] = x;
	r[2] = y;
	r[3] = z;
}

static double q_dot(const double a[4], const double b[4])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

/* log(conj(a) * b) of unit quaternions: a pure quaternion (w = 0). */
static void q_logdiff(const double a[4], const double b[4], double r[4])
{
	double ca[4] = {a[0], -a[1], -a[2], -a[3]}, p[4];
	q_mul(ca, b, p);
	double w = p[0] < -1.0 ? -1.0 : p[0] > 1.0 ? 1.0 : p[0];
	double ang = acos(w), s = sin(ang);
	double f = fabs(s) >= KB_EPS ? ang / s : 1.0;
	r[0] = 0.0;
	r[1] = f * p[1];
	r[2] = f * p[2];
	r[3] = f * p[3];
}

/* q * exp(v) for pure quaternion v. */
static void q_mulexp(const double q[4], const double v[4], double r[4])
{
	double ang = sqrt(v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
	double s = sin(ang), f = fabs(s) >= KB_EPS ? s / ang : 1.0;
	double e[4] = {cos(ang), f * v[1], f * v[2], f * v[3]};
	q_mul(q, e, r);
}

static void q_slerp(double u, const double p[4], const double q[4], double r[4])
{
	double c = q_dot(p, q);
	c = c < -1.0 ? -1.0 : c > 1.0 ? 1.0 : c;
	double ang = acos(c), s = sin(ang);
	double a = 1.0 - u, b = u;
	if (fabs(s) >= KB_EPS) {
		a = sin((1.0 - u) * ang) / s;
		b = sin(u * ang) / s;
	}
	for (int i = 0; i < 4; i++)
		r[i] = a * p[i] + b * q[i];
}

void kb_rot_quats(const kb_key *k, uint32_t n, double *q)
{
	for (uint32_t i = 0; i < n; i++) {
		const double *v = k[i].v;
		double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
		double half = 0.5 * v[3] * KB_PI / 180.0, s = len > 0.0 ? sin(half) / len : 0.0;
		double *qi = q + 4 * (uint64_t)i;
		qi[0] = cos(half);
		qi[1] = s * v[0];
		qi[2] = s * v[1];
		qi[3] = s * v[2];
		if (i > 0 && q_dot(qi - 4, qi) < 0.0)
			for (int c = 0; c < 4; c++)
				qi[c] = -qi[c];
	}
}

void kb_rot_eval(const kb_key *k, const double *q, uint32_t n, double t, double out[4])
{
	uint32_t j;
	double u;
	kb_segment(k, n, t, &j, &u);
	const double *q0 = q + 4 * (uint64_t)j, *q1 = q0 + 4, *q2 = q0 + 8, *q3 = q0 + 12;
	double w[4];
	tcb_weights(&k[j], &k[j + 1], &k[j + 2], &k[j + 3], w);
	double ld[4], l0[4], l3[4];
	q_logdiff(q1, q2, ld);
	q_logdiff(q0, q1, l0);
	q_logdiff(q2, q3, l3);
	/* tangents at q1 (out) and q2 (in), then squad's inner points a, b */
	double ta[4], tb[4], a[4], b[4];
	for (int i = 0; i < 4; i++) {
		double tout = w[1] * ld[i] + w[0] * l0[i];
		double tin = w[2] * l3[i] + w[3] * ld[i];
		ta[i] = 0.5 * (tout - ld[i]);
		tb[i] = 0.5 * (ld[i] - tin);
	}
	q_mulexp(q1, ta, a);
	q_mulexp(q2, tb, b);
	double s0[4], s1[4];
	q_slerp(u, q1, q2, s0);
	q_slerp(u, a, b, s1);
	q_slerp(2.0 * u * (1.0 - u), s0, s1, out);
	double len = sqrt(q_dot(out, out));
	for (int i = 0; i < 4; i++)
		out[i] = len > 0.0 ? out[i] / len : (i == 0);
}

void kb_quat_matrix(const double q[4], double m[9])
{
	double w = q[0], x = q[1], y = q[2], z = q[3];
	m[0] = 1.0 - 2.0 * (y * y + z * z);
	m[1] = 2.0 * (x * y - w * z);
	m[2] = 2.0 * (x * z + w * y);
	m[3] = 2.0 * (x * y + w * z);
	m[4] = 1.0 - 2.0 * (x * x + z * z);
	m[5] = 2.0 * (y * z - w * x);
	m[6] = 2.0 * (x * z - w * y);
	m[7] = 2.0 * (y * z + w * x);
	m[8] = 1.0 - 2.0 * (x * x + y * y);
}
