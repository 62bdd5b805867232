#include "cosim.h"

#include <math.h>
#include <string.h>

#include "dynamics.h"

int cp_cosim_step(const cp_settings *s, const double *p, double *x, double *y, double t,
                  double dt, double *h, double *work, int *fsal, double stats[CP_NSTAT],
                  cp_failure *failure)
{
    return cp_cosim_step_early(s, p, x, y, t, dt, h, work, fsal, stats, failure, NULL);
}

int cp_cosim_step_early(const cp_settings *s, const double *p, double *x, double *y, double t,
                        double dt, double *h, double *work, int *fsal, double stats[CP_NSTAT],
                        cp_failure *failure, double *reached)
{
    cp_model model = {p, 1.0, -1};
    cp_system system = {CP_NSTATE, cp_rhs, &model};
    cp_stats counts = {0, 0, 0};
    double *x_start = work + CP_WORK_SIZE(CP_NSTATE), *y_new = x_start + CP_NSTATE;
    double t_reached = t;
    int status = CP_BAD_STEP;
    if (dt >= 0 && dt < INFINITY) {
        memcpy(x_start, x, CP_NSTATE * sizeof(double));
        status = cp_integrate(s->method, &system, t, x, dt, s->rtol, s->atol, s->max_step,
                              s->max_steps, h, work, fsal, &counts, reached ? &t_reached : NULL);
    }
    stats[CP_STAT_N_RHS] += (double)counts.nfev;
    stats[CP_STAT_N_STEPS] += (double)counts.naccept;
    stats[CP_STAT_N_REJECTED] += (double)counts.nreject;
    /* the outputs where the state now is: at t + dt, or where an early return stopped */
    if ((status == CP_OK || t_reached > t) && CP_NOUTPUT) {
        cp_eval_outputs(x, p, y_new);
        if (cp_all_finite(CP_NOUTPUT, y_new)) {
            memcpy(y, y_new, CP_NOUTPUT * sizeof(double));
        } else {  /* the pivot force where M is singular: cp_rhs says where */
            int found = cp_rhs(&model, x, work);
            if (status == CP_OK) status = found == CP_OK ? CP_NONFINITE : found;
            memcpy(x, x_start, CP_NSTATE * sizeof(double));
            *fsal = 0;
            t_reached = t;
        }
    }
    if (reached) *reached = status == CP_OK ? t + dt : t_reached;
    if (status != CP_OK) {
        cp_failure f = {t, dt, model.bad_dof, model.pivot_ratio, s->rtol, s->atol, s->max_step,
                        s->max_steps, t_reached};
        *failure = f;
    }
    return status;
}
