/* One co-simulation step of the model, for every FMU of the package (the pythonfmu slave's
 * core and the native glue): the settings as the solvers take them, the integration, the
 * outputs, the statistics and, on failure, what the diagnosis needs. A state or an output
 * that is not finite is never reported as success. */
#ifndef CP_COSIM_H
#define CP_COSIM_H

#include "diagnosis.h"
#include "model.h"
#include "solvers.h"

typedef struct {
    int method;           /* CP_RK4, CP_RK45 or CP_DOP853 */
    double rtol, atol, max_step;
    long long max_steps;
} cp_settings;

/* Doubles of work a step needs: the solvers', then the state at t and the new outputs. */
#define CP_STEP_WORK_SIZE (CP_WORK_SIZE(CP_NSTATE) + CP_NSTATE + CP_NOUTPUT)

/* Advance x from t to t + dt and write the outputs there into y; p holds the parameters
 * and inputs. *h and *fsal are the solvers' memory (cp_integrate); stats (right-hand
 * sides, accepted and rejected steps, at model.h's CP_STAT_*) grow by what the step cost,
 * failed or not. Returns
 * CP_OK, or a status with *failure filled for cp_diagnose, x and y as they were. */
int cp_cosim_step(const cp_settings *settings, const double *p, double *x, double *y, double t,
                  double dt, double *h, double *work, int *fsal, double stats[CP_NSTAT],
                  cp_failure *failure);

/* cp_cosim_step with early return when reached is not NULL: on failure x and y are left at
 * the last point the solver reached where x' was computed (cp_integrate) and its outputs are
 * finite, or as they were at t; *reached is that time (t + dt on success), and
 * failure->kept says it too. With input_rates not NULL (CP_NINPUT rows of the first and
 * second time derivatives of the inputs at t: cp_input_at's rates), every input follows its
 * Taylor polynomial over the step, evaluated at each stage's time, and y is computed with the
 * inputs where the state ends; NULL holds them, as p has them. */
int cp_cosim_step_early(const cp_settings *settings, const double *p, double *x, double *y,
                        double t, double dt, double *h, double *work, int *fsal,
                        double stats[CP_NSTAT], cp_failure *failure, double *reached,
                        const double (*input_rates)[2]);

/* cp_rhs as a solver's system's right-hand side (ctx a cp_model): the inputs held as its p
 * has them, whatever t. */
int cp_held_rhs(void *ctx, double t, const double *x, double *dx);

/* The inputs of p (its last CP_NINPUT values) tau after the point where they are p's, each
 * on its Taylor polynomial u + u' tau + u'' tau^2 / 2 (rates[k] = {u', u''}), into p_at (all
 * CP_NPARAM values: the parameters copied). */
void cp_input_at(const double *p, const double (*rates)[2], double tau, double *p_at);

#endif
