/*
 * cone.c: enclosing cones of packets and triangle culling (see cone.h;
 * seed 004 §4).
 */
#include "kernel-ref/cone.h"

#include <math.h>

static double dot3(const double *a, const double *b)
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The axis: the mean unit direction; 0 when the directions cancel. */
static int cone_axis(pkt_cone *c, const packet *p, uint64_t mask)
{
	double s[3] = {0, 0, 0};
	for (uint64_t m = mask; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		double d[3] = {p->dx[i], p->dy[i], p->dz[i]};
		double l = sqrt(dot3(d, d));
		if (!(l > 0))
			return 0;
		for (int k = 0; k < 3; k++)
			s[k] += d[k] / l;
	}
	double l = sqrt(dot3(s, s));
	if (!(l > 1e-9))
		return 0;
	for (int k = 0; k < 3; k++)
		c->x[k] = s[k] / l;
	return 1;
}

void cone_build(pkt_cone *c, const packet *p, uint64_t mask)
{
	c->all = 1;
	c->phi = 0;
	if (!mask || !cone_axis(c, p, mask))
		return;
	double cen[3] = {0, 0, 0}, phi = 0;
	int n = 0;
	for (uint64_t m = mask; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		double d[3] = {p->dx[i], p->dy[i], p->dz[i]};
		double cs = dot3(d, c->x) / sqrt(dot3(d, d));
		double a = acos(cs > 1 ? 1 : cs < -1 ? -1 : cs);
		phi = a > phi ? a : phi;
		cen[0] += p->ox[i];
		cen[1] += p->oy[i];
		cen[2] += p->oz[i];
		n++;
	}
	if (phi > CONE_MAX_PHI)
		return;
	double rad = 0;
	for (int k = 0; k < 3; k++)
		cen[k] /= n;
	for (uint64_t m = mask; m; m &= m - 1) {
		int i = __builtin_ctzll(m);
		double o[3] = {p->ox[i] - cen[0], p->oy[i] - cen[1], p->oz[i] - cen[2]};
		double r = sqrt(dot3(o, o));
		rad = r > rad ? r : rad;
	}
	/* a floor on the angle keeps the apex at a finite distance */
	phi = phi < 1e-6 ? 1e-6 : phi;
	double back = rad > 0 ? rad * (1 + 1e-9) / sin(phi) : 0;
	for (int k = 0; k < 3; k++)
		c->a[k] = cen[k] - back * c->x[k];
	c->phi = phi;
	c->all = 0;
}

int cone_culls_tri(const pkt_cone *c, const mimg_tri *t)
{
	if (c->all)
		return 0;
	double v[3];
	for (int k = 0; k < 3; k++)
		v[k] = ((double)t->v[0][k] + t->v[1][k] + t->v[2][k]) / 3;
	double r = 0;
	for (int j = 0; j < 3; j++) {
		double e[3] = {t->v[j][0] - v[0], t->v[j][1] - v[1], t->v[j][2] - v[2]};
		double l = sqrt(dot3(e, e));
		r = l > r ? l : r;
	}
	double w[3] = {v[0] - c->a[0], v[1] - c->a[1], v[2] - c->a[2]};
	double d = sqrt(dot3(w, w));
	r = r * (1 + 1e-6) + 1e-6 * d; /* float vertices and rays: a little more */
	if (!(d > r))
		return 0;
	double cs = dot3(w, c->x) / d;
	double theta = acos(cs > 1 ? 1 : cs < -1 ? -1 : cs);
	return theta - asin(r / d) > c->phi + CONE_MARGIN;
}
