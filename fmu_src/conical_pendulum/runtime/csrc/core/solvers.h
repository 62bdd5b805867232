/* Generic explicit ODE solvers over one communication step: no model knowledge, no Python. */
#ifndef CP_SOLVERS_H
#define CP_SOLVERS_H

#include <math.h>

#include "status.h"

/* x' = f(t, x): the solvers pass every stage's time, so an input that moves within a step
 * (cosim.c's interpolated inputs) is evaluated where the stage is. */
typedef int (*cp_rhs_fn)(void *ctx, double t, const double *x, double *dx);

typedef struct {
    int dim;
    cp_rhs_fn rhs;   /* returns CP_OK, or a status >= 10 that stops the integration */
    void *ctx;
} cp_system;

/* Counts of one call; 64 bits everywhere (long is 32 bits on Windows). */
typedef struct {
    long long nfev, naccept, nreject;
} cp_stats;

enum { CP_RK4 = 0, CP_RK45 = 1, CP_DOP853 = 2 };

static inline int cp_all_finite(int n, const double *v)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* The fewest internal steps of at most max_step that cover dt (0: no limit, one step). */
static inline double cp_fewest_steps(double dt, double max_step)
{
    return max_step > 0 && dt > max_step ? ceil(dt / max_step) : 1.0;
}

/* The shortest step the adaptive pairs take between t0 and t1, as scipy's: ten spacings
 * of the time of larger magnitude. */
static inline double cp_min_step(double t0, double t1)
{
    double t = fmax(fabs(t0), fabs(t1));
    return 10 * (nextafter(t, INFINITY) - t);
}

/* Doubles of scratch memory cp_integrate needs for a system of size dim. */
#define CP_WORK_SIZE(dim) (32 * (dim))

/* CP_OK, or why a step by dt from t cannot be taken with these settings, whatever the
 * state: more than max_steps steps of at most max_step (CP_TOO_MANY_STEPS), or, for an
 * adaptive method (any but CP_RK4), a max_step below what time can resolve there
 * (CP_MAX_STEP_UNRESOLVED). */
static inline int cp_unworkable(int method, double t, double dt, double max_step,
                                long long max_steps)
{
    if (cp_fewest_steps(dt, max_step) > (double)max_steps) return CP_TOO_MANY_STEPS;
    if (method != CP_RK4 && max_step > 0 && max_step < cp_min_step(t, t + dt))
        return CP_MAX_STEP_UNRESOLVED;
    return CP_OK;
}

/* Advance x from t to t + dt. RK4 splits dt evenly into steps of at most max_step.
 * RK45 and DOP853 control the error as scipy's solvers do (RMS norm of the error over
 * atol + rtol * max(|x|, |x_new|), same safety factor and limits); *h carries the
 * proposed step from one call to the next (<= 0: choose one as scipy does). At most
 * max_steps steps are attempted, by every method: a step that max_step would split into
 * more fails at once (CP_TOO_MANY_STEPS), and so does a max_step below what t can resolve
 * (CP_MAX_STEP_UNRESOLVED), before any work. A new x that is not finite fails
 * (CP_NONFINITE). On failure x is left as it was at t, unless reached is not NULL (early
 * return): then x is left at the last point the method reached where x' was computed (RK45
 * and DOP853: the last accepted step; RK4: the last completed substep), or at t if there is
 * none. *reached (when not NULL) is the time of x on return: t + dt on success.
 * *fsal says whether work still holds x' at x from the last call (first same as last);
 * the caller clears it whenever it changes x or the parameters. */
int cp_integrate(int method, const cp_system *sys, double t, double *x, double dt,
                 double rtol, double atol, double max_step, long long max_steps,
                 double *h, double *work, int *fsal, cp_stats *stats, double *reached);

/* DOP853 from times[0] (state in out[0..dim)) through times[ntimes - 1], writing the
 * state at every time into out (row-major, ntimes x dim) from the method's 7th-order
 * dense output, as scipy's solve_ivp(method="DOP853", t_eval=times) does. */
int cp_dop853_grid(const cp_system *sys, const double *times, int ntimes, double *out,
                   double rtol, double atol, double max_step, long long max_steps, double *work,
                   cp_stats *stats);

#endif
