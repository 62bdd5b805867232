#include "cosim.h"

#include <math.h>
#include <string.h>

#include "dynamics.h"

int cp_cosim_step(const cp_settings *s, const double *p, double *x, double *y, double t,
                  double dt, double *h, double *work, int *fsal, double stats[CP_NSTAT],
                  cp_failure *failure)
{
    return cp_cosim_step_early(s, p, x, y, t, dt, h, work, fsal, stats, failure, NULL, NULL);
}

void cp_input_at(const double *p, const double (*rates)[2], double tau, double *p_at)
{
    memcpy(p_at, p, CP_NPARAM * sizeof(double));
    for (int k = 0; k < CP_NINPUT; k++) {
        const int i = CP_NPARAM - CP_NINPUT + k;  /* the inputs end p (model.h) */
        p_at[i] = p[i] + tau * (rates[k][0] + 0.5 * tau * rates[k][1]);
    }
}

/* The model's right-hand side with interpolated inputs: the inputs at the stage's time. */
typedef struct {
    cp_model model;               /* model.p is p_at */
    const double *p;              /* the parameters and the inputs at t0 */
    const double (*rates)[2];
    double t0;
    double p_at[CP_NPARAM];
} interpolated;

int cp_held_rhs(void *ctx, double t, const double *x, double *dx)
{
    (void)t;
    return cp_rhs(ctx, x, dx);
}

static int interpolated_rhs(void *ctx, double t, const double *x, double *dx)
{
    interpolated *in = ctx;
    cp_input_at(in->p, in->rates, t - in->t0, in->p_at);
    return cp_rhs(&in->model, x, dx);
}

int cp_cosim_step_early(const cp_settings *s, const double *p, double *x, double *y, double t,
                        double dt, double *h, double *work, int *fsal, double stats[CP_NSTAT],
                        cp_failure *failure, double *reached, const double (*input_rates)[2])
{
    interpolated in = {{p, 1.0, -1}, p, input_rates, t, {0}};
    cp_model *const model_at = &in.model;  /* its p: the inputs where the state is */
    if (input_rates && CP_NINPUT) in.model.p = in.p_at;
    else input_rates = NULL;
    cp_system system = {CP_NSTATE, input_rates ? interpolated_rhs : cp_held_rhs,
                        input_rates ? (void *)&in : (void *)model_at};
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
        if (input_rates) cp_input_at(p, input_rates, status == CP_OK ? dt : t_reached - t, in.p_at);
        cp_eval_outputs(x, model_at->p, y_new);
        if (cp_all_finite(CP_NOUTPUT, y_new)) {
            memcpy(y, y_new, CP_NOUTPUT * sizeof(double));
        } else {  /* the pivot force where M is singular: cp_rhs says where */
            int found = cp_rhs(model_at, x, work);
            if (status == CP_OK) status = found == CP_OK ? CP_NONFINITE : found;
            memcpy(x, x_start, CP_NSTATE * sizeof(double));
            *fsal = 0;
            t_reached = t;
        }
    }
    if (reached) *reached = status == CP_OK ? t + dt : t_reached;
    if (status != CP_OK) {
        cp_failure f = {t, dt, model_at->bad_dof, model_at->pivot_ratio, s->rtol, s->atol, s->max_step,
                        s->max_steps, t_reached};
        *failure = f;
    }
    return status;
}
