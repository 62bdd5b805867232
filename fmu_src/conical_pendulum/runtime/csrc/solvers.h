/* Generic explicit ODE solvers over one communication step: no model knowledge, no Python. */
#ifndef CP_SOLVERS_H
#define CP_SOLVERS_H

#include "status.h"

typedef int (*cp_rhs_fn)(void *ctx, const double *x, double *dx);

typedef struct {
    int dim;
    cp_rhs_fn rhs;   /* returns CP_OK, or a status >= 10 that stops the integration */
    void *ctx;
} cp_system;

typedef struct {
    long nfev, naccept, nreject;
} cp_stats;

enum { CP_RK4 = 0, CP_RK45 = 1, CP_DOP853 = 2 };

/* Doubles of scratch memory cp_integrate needs for a system of size dim. */
#define CP_WORK_SIZE(dim) (32 * (dim))

/* Advance x from t to t + dt. RK4 splits dt evenly into steps of at most max_step.
 * RK45 and DOP853 control the error as scipy's solvers do (RMS norm of the error over
 * atol + rtol * max(|x|, |x_new|), same safety factor and limits); *h carries the
 * proposed step from one call to the next (<= 0: choose one as scipy does). At most
 * max_steps steps are attempted. On failure x is left as it was at t.
 * *fsal says whether work still holds x' at x from the last call (first same as last);
 * the caller clears it whenever it changes x or the parameters. */
int cp_integrate(int method, const cp_system *sys, double t, double *x, double dt,
                 double rtol, double atol, double max_step, long max_steps,
                 double *h, double *work, int *fsal, cp_stats *stats);

/* DOP853 from times[0] (state in out[0..dim)) through times[ntimes - 1], writing the
 * state at every time into out (row-major, ntimes x dim) from the method's 7th-order
 * dense output, as scipy's solve_ivp(method="DOP853", t_eval=times) does. */
int cp_dop853_grid(const cp_system *sys, const double *times, int ntimes, double *out,
                   double rtol, double atol, double max_step, long max_steps, double *work,
                   cp_stats *stats);

#endif
