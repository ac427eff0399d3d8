/*
 * sampling.c: the sampled mode's estimator (see sampling.h): the demand
 * models and their fits, the stratified ratio estimate of a frame's middle
 * and its variance. Statistics on what the chip measured; sim/chip.c runs
 * the regions and collects the pieces.
 */
#include "sim/sampling.h"

#include <math.h>
#include <string.h>

/* A piece's demand with SDRAM time scaled by k: the cycles its busiest
 * resource needs when the SDRAM delivers 1/k of its data-bus peak (row
 * misses, refresh, turnarounds). k = 1 is the plain busiest resource. */
static double demand_k(const smp_piece *p, double k)
{
	double x = p->comp > p->hbus ? p->comp : p->hbus;
	return k * p->sdram > x ? k * p->sdram : x;
}

/* demand_k plus the overlap term: g times the smaller of the compute and
 * the scaled SDRAM time. Where the two are alike, neither hides the
 * other: a chunk whose packets wait for memory as long as they compute
 * runs well above its busiest resource, one that is all memory or all
 * compute near it (docs/fidelity.md "The estimator"). */
static double demand_kg(const smp_piece *p, double k, double g)
{
	double s = k * p->sdram, lo = s < p->comp ? s : p->comp;
	return demand_k(p, k) + g * lo;
}

/* The p-norm of a piece's resources (every compute resource, SDRAM and
 * host-bus time): where one resource far exceeds the others it is that
 * one, where several are alike, more (two equal ones 2^(1/p) times one).
 * Packets that keep several units busy in turn do not overlap them
 * perfectly: a chunk whose shading and intersection demands are alike runs
 * well above the busiest of them (docs/fidelity.md "Demand models"). */
static double demand_p(const smp_piece *p, double e)
{
	double m = demand_k(p, 1); /* the busiest resource */
	if (m <= 0 || isinf(e))
		return m > 0 ? m : 0;
	double s = 0;
	for (int i = 0; i < SMP_COMP; i++)
		if (p->res[i] > 0)
			s += pow(p->res[i] / m, e);
	if (p->sdram > 0)
		s += pow(p->sdram / m, e);
	if (p->hbus > 0)
		s += pow(p->hbus / m, e);
	return m * pow(s, 1 / e);
}

double smp_demand(const smp_piece *p, const smp_model *m)
{
	if (!m->linear)
		return m->p > 0 ? demand_p(p, m->p) : demand_kg(p, m->k, m->g);
	double x = 0;
	for (int i = 0; i < SMP_LIN; i++)
		x += m->beta[i] * p->lin[i];
	return x;
}

double smp_busiest(const smp_piece *p)
{
	return demand_k(p, 1);
}

double smp_t975(int df)
{
	static const double t[31] = {0,     12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365,
	                             2.306, 2.262,  2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
	                             2.120, 2.110,  2.101, 2.093, 2.086, 2.080, 2.074, 2.069,
	                             2.064, 2.060,  2.056, 2.052, 2.048, 2.045, 2.042};
	if (df < 1)
		return INFINITY;
	if (df <= 30)
		return t[df];
	/* Cornish-Fisher: within 1e-3 of the table beyond 30 */
	double z = 1.959964, z3 = z * z * z;
	return z + (z3 + z) / (4.0 * df) + (5 * z3 * z * z + 16 * z3 + 3 * z) / (96.0 * df * df);
}

/* One stratum's ratio estimate over units [lo, hi) of stratum h (or of
 * both, h < 0), their demand under model m: R; ss, the residuals' sum of
 * squares; and g, such that the variance of R x X for the stratum's demand
 * X is g x s^2 for a residual variance s^2 (finite-population corrected
 * over its chunks). */
typedef struct strat {
	int n;
	double R, ss, g;
} strat;

static strat stratum(const smp_piece *u, const double *cyc, const smp_model *m, int lo, int hi,
                     int h, double X, int chunks)
{
	strat s = {0, 0, 0, 0};
	double sc = 0, sx = 0;
	for (int j = lo; j < hi; j++)
		if (h < 0 || u[j].hard == h) {
			sc += cyc[j];
			sx += smp_demand(&u[j], m);
			s.n++;
		}
	if (!s.n || sx <= 0)
		return s;
	s.R = sc / sx;
	double xbar = sx / s.n;
	for (int j = lo; j < hi; j++)
		if (h < 0 || u[j].hard == h) {
			double e = cyc[j] - s.R * smp_demand(&u[j], m);
			s.ss += e * e;
		}
	double fpc = chunks > s.n ? 1.0 - (double)s.n / chunks : 0;
	s.g = X * X * fpc / s.n / (xbar * xbar);
	return s;
}

/* Residual sum of squares of one ratio fitted to n units' cycles against
 * their demand under model m. */
static double ratio_ss(const smp_piece *u, const double *cyc, int n, const smp_model *m)
{
	double sc = 0, sx = 0, ss = 0;
	for (int j = 0; j < n; j++) {
		sc += cyc[j];
		sx += smp_demand(&u[j], m);
	}
	double R = sx > 0 ? sc / sx : 0;
	for (int j = 0; j < n; j++) {
		double d = cyc[j] - R * smp_demand(&u[j], m);
		ss += d * d;
	}
	return ss;
}

/* The max model's (k, g) grid, shared by the fit and its uncertainty
 * (param_var): k in [1, 4], g in [0, 1], steps of 0.02; a given k
 * (kfix > 0) or g (gfix >= 0) is the only point on its axis. grid_steps
 * gives the last step on each axis, grid_model the model at (ks, gs). */
static void grid_steps(double kfix, double gfix, int *nk, int *ng)
{
	*nk = kfix > 0 ? 0 : 150;
	*ng = gfix >= 0 ? 0 : 50;
}

static smp_model grid_model(double kfix, double gfix, int ks, int gs)
{
	smp_model m = {0, kfix > 0 ? kfix : 1.0 + 0.02 * ks, {0}, gfix >= 0 ? gfix : 0.02 * gs, 0};
	return m;
}

/* The max model's k and g for n units (demand, cycles). Where a unit's
 * SDRAM time nears its compute time, its cycles follow k x SDRAM time, k
 * about 1.5 for the standard SDRAM's row misses; with k = 1 those units
 * sat 1.4-1.6x above the rest and dominated the spread. Where its compute
 * and SDRAM times are alike, neither hides the other (demand_kg's g).
 * k in [1, 4] and g in [0, 1] (steps of 0.02) are the values under which
 * one ratio fits all units best (least squares of cycles - R x demand, R
 * their ratio); the smallest such g, then k, so 1 and 0 when no unit tells
 * them apart. Fitting to the strata's own ratios instead would favour a k
 * that shrinks the memory-bound stratum's estimate (and so its variance).
 * docs/fidelity.md. */
void smp_fit_max(const smp_piece *u, const double *cyc, int n, double kfix, double gfix, double *k,
                 double *g)
{
	int nk, ng;
	grid_steps(kfix, gfix, &nk, &ng);
	double sbest = INFINITY;
	*k = kfix > 0 ? kfix : 1;
	*g = gfix >= 0 ? gfix : 0;
	for (int gs = 0; gs <= ng; gs++)
		for (int ks = 0; ks <= nk; ks++) {
			smp_model m = grid_model(kfix, gfix, ks, gs);
			double ss = ratio_ss(u, cyc, n, &m);
			if ((gs == 0 && ks == 0) || ss < sbest * (1 - 1e-6)) {
				sbest = ss;
				*k = m.k;
				*g = m.g;
			}
		}
}

/* The p-norm model's grid: p = 1 to 4 in steps of 0.1, then 5, 6, 8, 12,
 * 16; step SMP_PSTEPS is p = infinity (INFINITY), the plain busiest
 * resource (the max model's demand with k = 1, g = 0). */
#define SMP_PSTEPS 36
static smp_model p_model(int i)
{
	static const double hi[5] = {5, 6, 8, 12, 16};
	smp_model m = {0, 1, {0}, 0, 0};
	m.p = i < 31 ? 1 + 0.1 * i : i < SMP_PSTEPS ? hi[i - 31] : INFINITY;
	return m;
}

/* The p fitted to n units: the one under which one ratio fits them best,
 * the largest such (infinity, the busiest resource, when no unit tells
 * the values apart). */
smp_model smp_fit_p(const smp_piece *u, const double *cyc, int n)
{
	smp_model best = p_model(SMP_PSTEPS);
	double sbest = ratio_ss(u, cyc, n, &best);
	for (int i = SMP_PSTEPS - 1; i >= 0; i--) {
		smp_model m = p_model(i);
		double ss = ratio_ss(u, cyc, n, &m);
		if (ss < sbest * (1 - 1e-6)) {
			sbest = ss;
			best = m;
		}
	}
	return best;
}

double smp_fit_sdram_factor(const smp_piece *u, const double *cyc, int n)
{
	double k, g;
	smp_fit_max(u, cyc, n, 0, 0, &k, &g);
	return k;
}

/* Solves the m x m system A z = y in place (Gaussian elimination with
 * partial pivoting); -1 when it is singular. */
static int solve(double *A, double *y, int m)
{
	for (int c = 0; c < m; c++) {
		int piv = c;
		for (int r = c + 1; r < m; r++)
			if (fabs(A[r * m + c]) > fabs(A[piv * m + c]))
				piv = r;
		if (fabs(A[piv * m + c]) < 1e-12 * (fabs(A[c * m + c]) + 1e-300) ||
		    A[piv * m + c] == 0)
			return -1;
		for (int k = 0; k < m; k++) {
			double t = A[c * m + k];
			A[c * m + k] = A[piv * m + k];
			A[piv * m + k] = t;
		}
		double t = y[c];
		y[c] = y[piv];
		y[piv] = t;
		for (int r = c + 1; r < m; r++) {
			double f = A[r * m + c] / A[c * m + c];
			for (int k = c; k < m; k++)
				A[r * m + k] -= f * A[c * m + k];
			y[r] -= f * y[c];
		}
	}
	for (int c = m - 1; c >= 0; c--) {
		for (int k = c + 1; k < m; k++)
			y[c] -= A[c * m + k] * y[k];
		y[c] /= A[c * m + c];
	}
	return 0;
}

/* The linear model: cycles = sum(beta_i x lin_i) over the unit kinds'
 * issue cycles, SDRAM and host-bus time, beta >= 0, least squares over the
 * n units. With few threads a packet's operations and memory waits follow
 * one another, so its cycles add up its resources' times rather than
 * follow the busiest. Regressors that are zero in every unit are left
 * out; a fit with a negative coefficient drops that regressor and fits
 * again (an active set; six regressors at most). */
int smp_fit_linear(const smp_piece *u, const double *cyc, int n, double beta[SMP_LIN])
{
	int on[SMP_LIN], m;
	for (int i = 0; i < SMP_LIN; i++) {
		double ss = 0;
		for (int j = 0; j < n; j++)
			ss += u[j].lin[i] * u[j].lin[i];
		on[i] = ss > 0;
		beta[i] = 0;
	}
	for (;;) {
		int idx[SMP_LIN];
		m = 0;
		for (int i = 0; i < SMP_LIN; i++)
			if (on[i])
				idx[m++] = i;
		if (m == 0 || n < m)
			return 0;
		double A[SMP_LIN * SMP_LIN] = {0}, y[SMP_LIN] = {0};
		for (int j = 0; j < n; j++)
			for (int a = 0; a < m; a++) {
				y[a] += u[j].lin[idx[a]] * cyc[j];
				for (int b = 0; b < m; b++)
					A[a * m + b] += u[j].lin[idx[a]] * u[j].lin[idx[b]];
			}
		int worst = -1;
		if (solve(A, y, m) == 0) {
			for (int a = 0; a < m; a++)
				if (y[a] < 0 && (worst < 0 || y[a] < y[worst]))
					worst = a;
		} else {
			worst = m - 1; /* collinear: drop the last regressor */
		}
		if (worst < 0) {
			for (int a = 0; a < m; a++)
				beta[idx[a]] = y[a];
			return m;
		}
		on[idx[worst]] = 0;
	}
}

/* The linear model's kept regressors (beta > 0) into idx and the n units'
 * normal matrix D'D over them into A (p x p); returns p. */
static int lin_normal(const smp_piece *u, int n, const smp_model *m, int idx[SMP_LIN],
                      double A[SMP_LIN * SMP_LIN])
{
	int p = 0;
	for (int i = 0; i < SMP_LIN; i++)
		if (m->beta[i] > 0)
			idx[p++] = i;
	for (int i = 0; i < p * p; i++)
		A[i] = 0;
	for (int j = 0; j < n; j++)
		for (int a = 0; a < p; a++)
			for (int b = 0; b < p; b++)
				A[a * p + b] += u[j].lin[idx[a]] * u[j].lin[idx[b]];
	return p;
}

/* The linear model's leave-one-out error over n units: PRESS = sum of
 * (e_j / (1 - h_j))^2, e_j the fit's residual and h_j the unit's leverage
 * (its share in fitting its own value), over the regressors kept; *ss gets
 * the plain sum of e_j^2 (whenever the model has fewer parameters than
 * units). INFINITY when a unit alone sets a coefficient (h_j = 1): on
 * small frames a regressor nonzero in one or two units (the
 * host bus, lists) made the fit look perfect and the interval a fraction
 * of the error. */
static double lin_press(const smp_piece *u, const double *cyc, int n, const smp_model *m,
                        double *ss)
{
	int idx[SMP_LIN];
	double A[SMP_LIN * SMP_LIN], inv[SMP_LIN * SMP_LIN];
	int p = lin_normal(u, n, m, idx, A);
	*ss = INFINITY;
	if (p == 0 || n <= p)
		return INFINITY;
	*ss = 0;
	for (int j = 0; j < n; j++) {
		double e = cyc[j] - smp_demand(&u[j], m);
		*ss += e * e;
	}
	for (int k = 0; k < p; k++) { /* (D'D)^-1, column by column */
		double A2[SMP_LIN * SMP_LIN], z[SMP_LIN] = {0};
		memcpy(A2, A, sizeof A2);
		z[k] = 1;
		if (solve(A2, z, p))
			return INFINITY;
		for (int a = 0; a < p; a++)
			inv[a * p + k] = z[a];
	}
	double press = 0;
	for (int j = 0; j < n; j++) {
		double h = 0, e = cyc[j] - smp_demand(&u[j], m);
		for (int a = 0; a < p; a++)
			for (int b = 0; b < p; b++)
				h += u[j].lin[idx[a]] * inv[a * p + b] * u[j].lin[idx[b]];
		if (h > 1 - 1e-9)
			return INFINITY;
		press += e * e / ((1 - h) * (1 - h));
	}
	return press;
}

/* The linear model's parameter uncertainty carried to the estimate: the
 * variance of sum(beta x X) over the middle's npc pieces, X their regressor
 * totals, s^2 X' (D'D)^-1 X with D the n units' regressors (those kept in
 * the fit) and s^2 = ss / (n - p) the fit's residual variance (ss: its
 * residual sum of squares, from lin_press). The ratio on the fitted
 * demand sees only the error along the fitted direction; the frame's mix
 * of resources differs from the units' and the coefficients' errors
 * reach it through the other directions too. */
static double lin_param_var(const smp_piece *u, int n, const smp_piece *pc, int npc,
                            const smp_model *m, double ss)
{
	int idx[SMP_LIN];
	double A[SMP_LIN * SMP_LIN], X[SMP_LIN] = {0};
	int p = lin_normal(u, n, m, idx, A);
	if (p == 0 || n <= p)
		return 0;
	for (int i = 0; i < npc; i++)
		for (int a = 0; a < p; a++)
			X[a] += pc[i].lin[idx[a]];
	double z[SMP_LIN];
	memcpy(z, X, sizeof z);
	if (solve(A, z, p)) /* z = (D'D)^-1 X */
		return INFINITY;
	double q = 0;
	for (int a = 0; a < p; a++)
		q += X[a] * z[a];
	return ss / (n - p) * q;
}

/* The frame's middle under demand model m: the stratified ratio estimate
 * (r->est), its variance (r->var) and degrees of freedom (r->df, before
 * the model's fitted parameters are taken off). */
static void ratio_est(const smp_piece *u, const double *cyc, int n, const smp_piece *pc, int npc,
                      const smp_model *m, smp_est *r)
{
	double X[2] = {0, 0};
	int nc[2] = {0, 0};
	for (int i = 0; i < npc; i++) {
		X[pc[i].hard] += smp_demand(&pc[i], m);
		nc[pc[i].hard]++;
	}
	/* two strata when each has at least two units, else one. The
	 * residual variance is pooled over the strata: once the demand model
	 * fits, both hold cycles near one ratio, and a memory-bound stratum of
	 * two or three units would otherwise leave the interval one or two
	 * degrees of freedom */
	strat e = stratum(u, cyc, m, 0, n, 0, X[0], nc[0]);
	strat h = stratum(u, cyc, m, 0, n, 1, X[1], nc[1]);
	if (e.n >= 2 && h.n >= 2) {
		r->est = e.R * X[0] + h.R * X[1];
		r->df = e.n + h.n - 2;
		r->var = (e.g + h.g) * (e.ss + h.ss) / r->df;
	} else {
		strat a = stratum(u, cyc, m, 0, n, -1, X[0] + X[1], nc[0] + nc[1]);
		r->est = a.R * (X[0] + X[1]);
		r->df = a.n - 1;
		r->var = a.n > 1 ? a.g * a.ss / r->df : INFINITY;
	}
}

/* A fitted model's parameters are themselves uncertain: where the units'
 * SDRAM and compute times never come close (the max model's k and g), or
 * no two resources are alike (the p-norm model's p), other values fit
 * them almost as well and, applied to chunks where they do, give another
 * frame. The values of the model's grid (pnorm: p_model's, else the max
 * model's k and g) whose residual sum of squares stays within the 95%
 * joint region of the fit (ss <= ss_best (1 + p F(p, d) / d), p the
 * parameters fitted, d the residual degrees of freedom) are taken as
 * possible; the largest distance of their estimates from r->est, divided
 * by the interval's t quantile, is returned as a variance, so the
 * interval's half-width is at least that distance. */
static double param_var(const smp_piece *u, const double *cyc, int n, const smp_piece *pc, int npc,
                        int pnorm, double kfix, double gfix, int p, const smp_est *r)
{
	int d = n - 1 - p;
	if (d < 1 || r->df < 1)
		return 0;
	double F = p == 1 ? smp_t975(d) * smp_t975(d) : 0.5 * d * (pow(0.05, -2.0 / d) - 1);
	double lim = ratio_ss(u, cyc, n, &r->model) * (1 + p * F / d), dev = 0;
	int nk, ng;
	grid_steps(kfix, gfix, &nk, &ng);
	int count = pnorm ? SMP_PSTEPS + 1 : (nk + 1) * (ng + 1);
	for (int i = 0; i < count; i++) {
		smp_model m =
		    pnorm ? p_model(i) : grid_model(kfix, gfix, i % (nk + 1), i / (nk + 1));
		if (ratio_ss(u, cyc, n, &m) > lim)
			continue;
		smp_est e;
		ratio_est(u, cyc, n, pc, npc, &m, &e);
		double x = fabs(e.est - r->est);
		dev = x > dev ? x : dev;
	}
	double t = smp_t975((int)r->df);
	return dev > 0 && isfinite(t) ? dev * dev / (t * t) : 0;
}

void smp_estimate(const smp_piece *u, const double *cyc, int n, const smp_piece *pc, int npc,
                  double sdram_factor, double overlap, int demand_model, smp_est *r)
{
	/* the demand model: max, with the SDRAM factor and the overlap share
	 * fitted or given; pnorm, p fitted; or linear, fitted when there are
	 * 30 units or more. auto takes linear when its leave-one-out error
	 * (PRESS / n) is below the max model's residual variance per degree
	 * of freedom, else the one of max and pnorm with the smaller residual
	 * variance per degree of freedom. Linear is weighed against max
	 * alone: the p-norm model's in-sample variance beside linear's
	 * out-of-sample error took pnorm where linear had fitted better (8
	 * threads per RTP, docs/fidelity.md). extra: parameters fitted beyond
	 * the ratio, each a degree of freedom; infl: how much larger the
	 * linear model's leave-one-out error is than its residuals say, by
	 * which its variance is widened */
	smp_model mm = {0, sdram_factor, {0}, overlap, 0}, ml = {1, 1, {0}, 0, 0}, mp = mm;
	int fitk = mm.k <= 0, fitg = mm.g < 0, auto_ = demand_model == CFG_DEMAND_AUTO;
	if ((fitk || fitg) && demand_model != CFG_DEMAND_PNORM)
		smp_fit_max(u, cyc, n, sdram_factor, overlap, &mm.k, &mm.g);
	int extra = (fitk && mm.k > 1) + (fitg && mm.g > 0);
	double smax = n - 1 - extra > 0 ? ratio_ss(u, cyc, n, &mm) / (n - 1 - extra) : INFINITY;
	const smp_model *use = &mm;
	int plin = (auto_ || demand_model == CFG_DEMAND_LINEAR) && n >= 30
	               ? smp_fit_linear(u, cyc, n, ml.beta)
	               : 0;
	double infl = 1, lss = 0;
	if (plin) {
		double ss, press = lin_press(u, cyc, n, &ml, &ss);
		lss = ss;
		if (!auto_ || press / n < smax) {
			use = &ml;
			extra = plin - 1;
			infl = ss > 0 ? press / n / (ss / (n - plin)) : 1;
			infl = infl > 1 ? infl : 1;
		}
	}
	if ((auto_ && use == &mm) || demand_model == CFG_DEMAND_PNORM) {
		mp = smp_fit_p(u, cyc, n);
		/* p is a fitted parameter even where the fit keeps infinity (no
		 * unit's resources alike): the middle's may be */
		double sp = n > 2 ? ratio_ss(u, cyc, n, &mp) / (n - 2) : INFINITY;
		if (!auto_ || sp < smax) {
			use = &mp;
			extra = 1;
		}
	}
	r->model = *use;
	ratio_est(u, cyc, n, pc, npc, use, r);
	r->df -= extra; /* the model's fitted parameters */
	if (use->linear)
		r->var = (r->var + lin_param_var(u, n, pc, npc, use, lss)) * infl;
	else if (use == &mp)
		r->var += param_var(u, cyc, n, pc, npc, 1, 1, 0, 1, r);
	else if (fitk || fitg)
		r->var += param_var(u, cyc, n, pc, npc, 0, sdram_factor, overlap, fitk + fitg, r);
}
