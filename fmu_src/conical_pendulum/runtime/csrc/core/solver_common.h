/* What the solvers of solvers.c and radau.c share: counted evaluations, the RMS norm, the
 * first step's choice and the implicit step. Internal to the core's solvers. */
#ifndef CP_SOLVER_COMMON_H
#define CP_SOLVER_COMMON_H

#include <math.h>

#include "solvers.h"

static inline int cp_eval(const cp_system *sys, double t, const double *x, double *dx,
                          cp_stats *stats)
{
    stats->nfev++;
    return sys->rhs(sys->ctx, t, x, dx);
}

/* sqrt(mean((v / scale)^2)): scipy's norm of a scaled error. */
/* A trial stage's failure that rejects the step rather than ending the integration: a
 * non-finite acceleration or a singular mass matrix there says the step was too long for the
 * scene (a trial stage can fling a light body through a configuration the path never
 * reaches), not that the scene is wrong; where the path itself meets one, the step shrinks
 * to the least step and fails with it. */
static inline int cp_trial_rejects(int status)
{
    return status == CP_NONFINITE || status == CP_SINGULAR;
}

static inline double cp_rms(int n, const double *v, const double *scale)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) {
        double r = v[i] / scale[i];
        s += r * r;
    }
    return sqrt(s / n);
}

/* One accepted step of Radau IIA (radau.c) from the end of the step in flight, none ending
 * after t_end, its stages' and error's memory carved from work (CP_CARVED_ROWS rows); the
 * rows become the new step's (x0, x1, x' at x1, the dense output's 3 rows of Q). nw and
 * block: the Jacobian and its factors, kept between steps (cp_newton). */
int cp_radau_step(const cp_system *sys, cp_step *step, double *rows, cp_newton *nw,
                  double *block, double t_end, double rtol, double atol, double max_step,
                  long long max_steps, long long *attempts, double *work, cp_stats *stats);

/* Rows of dim doubles a solver's step carves from the work array (the rest keeps cp_dense_grid's
 * step in flight). */
#define CP_CARVED_ROWS 22

#endif
