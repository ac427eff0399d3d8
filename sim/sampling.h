/*
 * sampling.h: the estimator of fidelity `sampled` (docs/fidelity.md "The
 * estimator", "Demand models"). sim/chip.c simulates detailed regions
 * between functional stretches and records, for every stretch of tiles,
 * its resource demands (smp_piece) and, for every measured unit, its
 * cycles; this file turns them into the cycles of the frame's middle with
 * a variance. No time and no chip state here: numbers in, numbers out.
 */
#ifndef SAAR_SIM_SAMPLING_H
#define SAAR_SIM_SAMPLING_H

#include "mem/memport.h"
#include "sim/config.h"
#include "units/unit_table.h"

/* The demand of a stretch of tiles in core cycles: its busiest compute
 * resource (unit issue cycles per instance, L1 requests per port), SDRAM
 * data-bus time and host-bus time, and the linear model's regressors
 * (SMP_LIN: every unit kind's issue cycles, SDRAM, host bus; the chip
 * names them, chip_lin_name); hard: memory bound (sampling.hard_share),
 * its stratum. */
enum { SMP_LIN = UNIT_NKINDS + 2 };
/* compute resources: the unit kinds, the L1 ports (enum chip_res) */
enum { SMP_COMP = UNIT_NKINDS + MEM_NTYPES };
typedef struct smp_piece {
	double comp, sdram, hbus;
	double res[SMP_COMP]; /* each compute resource (comp is the largest) */
	double lin[SMP_LIN];
	int hard;
} smp_piece;

/* How a piece's demand follows from its resources: max(comp, k x sdram,
 * hbus) + g x min(comp, k x sdram), sum(beta x lin), or the p-norm of
 * res, sdram and hbus. */
typedef struct smp_model {
	int linear;
	double k;
	double beta[SMP_LIN];
	double g; /* the overlap term's share (max model) */
	double p; /* > 0: the p-norm model, ||(res, sdram, hbus)||_p (may be INFINITY) */
} smp_model;

/* The estimate of a frame's middle: cycles, their variance and degrees of
 * freedom (fitted parameters taken off), and the demand model used. */
typedef struct smp_est {
	double est, var, df;
	smp_model model;
} smp_est;

/* A piece's demand under model m; its plain busiest resource (k = 1). */
double smp_demand(const smp_piece *p, const smp_model *m);
double smp_busiest(const smp_piece *p);
/* The SDRAM factor fitted to n units' demands and cycles with no overlap
 * term (smp_fit_max with g = 0). */
double smp_fit_sdram_factor(const smp_piece *u, const double *cyc, int n);
/* The max model's k and g fitted to n units' demands and cycles: kfix > 0
 * fixes k, gfix >= 0 fixes g, the others are fitted (sampling.c). */
void smp_fit_max(const smp_piece *u, const double *cyc, int n, double kfix, double gfix, double *k,
                 double *g);
/* The p-norm model fitted to n units' demands and cycles (sampling.c). */
smp_model smp_fit_p(const smp_piece *u, const double *cyc, int n);
/* The linear model's non-negative least-squares fit (beta); returns the
 * number of regressors kept, 0 when none fits. */
int smp_fit_linear(const smp_piece *u, const double *cyc, int n, double beta[SMP_LIN]);
/* 97.5% quantile of Student's t with df degrees of freedom. */
double smp_t975(int df);
/* The stratified ratio estimate of the middle's cycles from n measured
 * units u (cycles cyc, strata u[j].hard) and the middle's npc pieces pc
 * (the units' own among them), with the demand model picked by
 * sampling.demand_model (enum cfg_demand_model), sampling.sdram_factor
 * (0 = fitted) and sampling.overlap (negative = fitted). Its variance
 * holds the fitted parameters' uncertainty too (the linear model's
 * coefficients; the max model's k and g; the p-norm model's p,
 * docs/fidelity.md). */
void smp_estimate(const smp_piece *u, const double *cyc, int n, const smp_piece *pc, int npc,
                  double sdram_factor, double overlap, int demand_model, smp_est *r);

#endif
