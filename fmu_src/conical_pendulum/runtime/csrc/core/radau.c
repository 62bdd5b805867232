/* Radau IIA of order 5, the implicit solver: scipy's Radau (scipy/integrate/_ivp/radau.py,
 * after Hairer & Wanner's radau5) step for step, on the system's exact Jacobian, up to
 * COSTLY_JACOBIAN_DIM states; past them radau5's own choices for large systems (below).
 *
 * Each step solves the collocation system for the three stages by a simplified Newton
 * iteration, whose matrices (MU_REAL / h - J and MU_COMPLEX / h - J) are factored once and
 * kept while the step size stays (a change below 20 % is not made) and the iteration
 * converges; J itself is evaluated only when an iteration with the kept one fails to converge
 * or converges slowly (after more than two iterations, a rate past RECOMPUTE_RATE). A stage
 * whose right-hand side is not finite fails the iteration, which halves the step, as scipy's
 * does.
 *
 * The Newton matrices are newton.c's, factored on the system's structure. */
#include <complex.h>
#include <math.h>
#include <string.h>

#include "solver_common.h"

/* scipy's constants, printed with 17 significant digits (radau.py): the collocation nodes C,
 * the error estimate's weights E, the real and complex eigenvalues of the inverse of the
 * Radau matrix, its eigenvector transformations T and TI, and the dense output's P. */
static const double C[3] = {0.15505102572168222, 0.6449489742783178, 1.0};
static const double E[3] = {-10.048809399827414, 1.382142733160748, -0.33333333333333331};
static const double MU_REAL = 3.637834252744496;
static const double MU_COMPLEX_RE = 2.6810828736277523, MU_COMPLEX_IM = -3.050430199247411;
static const double T[3][3] = {{0.09443876248897524, -0.1412552950209542, 0.03002919410514742},
                               {0.2502131229653333, 0.20412935229379994, -0.3829421127572619},
                               {1.0, 1.0, 0.0}};
static const double TI[3][3] = {{4.178718591551904, 0.32768282076106237, 0.5233764454994495},
                                {-4.178718591551904, -0.32768282076106237, 0.47662355450055044},
                                {0.5028726349457868, -2.571926949855605, 0.5960392048282249}};
static const double P[3][3] = {{10.048809399827414, -25.62959144707664, 15.580782047249224},
                               {-1.382142733160748, 10.296258113743303, -8.914115380582556},
                               {0.33333333333333331, -2.6666666666666665, 3.3333333333333335}};

#define NEWTON_MAXITER 6
/* Past COSTLY_JACOBIAN_DIM states (solver_common.h) the solver takes radau5's advice for
 * large systems rather than scipy's choices (kept below it, step for step):
 * - the Newton rate past which an accepted step's Jacobian is evaluated anew (after more
 *   than two iterations): 0.1 (Hairer's WORK(3) where Jacobians are costly), not 1e-3. On the
 *   damped light chain of 10, 20 and 50 links (rtol 1e-6 to 1e-12) it takes a half to a
 *   quarter of the Jacobians, for the same error;
 * - the step size kept, and with it the factors, unless it would grow by KEEP_STEP_BELOW:
 *   2 (WORK(5), WORK(6) = 1, 2 "for large full systems"), not 1.2;
 * - no growth in the step after a rejected one (radau5's REJECT, which scipy leaves out):
 *   on long light chains half the steps tried fail their Newton iteration, each failure
 *   costing a Jacobian and two factorizations, and growing again at once fails again.
 * The last two, on the 50-link chain at c = 1e2, rtol 1e-6: 307 -> 263 Jacobians, 1676 ->
 * 1080 factorizations, 329 -> 201 rejected steps, the error 1.95e-6 -> 3.37e-6 rad
 * (benchmarks/radau_levers.py). */
#define RECOMPUTE_RATE(dim) (LARGE(dim) ? 0.1 : 1e-3)
#define KEEP_STEP_BELOW(dim) (LARGE(dim) ? 2.0 : 1.2)
#define MIN_FACTOR 0.2
#define MAX_FACTOR 10.0

/* The shifts of the two Newton matrices for the step size h. */
static double real_shift(double h)
{
    return MU_REAL / h;
}

static double complex complex_shift(double h)
{
    return (MU_COMPLEX_RE + MU_COMPLEX_IM * I) / h;
}

void cp_radau_factor(int n, double h, const cp_matrix_view *mx, cp_newton *nw, cp_stats *stats)
{
    *mx->h = h;
    cp_factor_real(n, real_shift(h), mx);
    cp_factor_complex(n, complex_shift(h), mx);
    stats->nlu += 2;
    nw->lu_valid = 1;
    nw->method = CP_RADAU;
}

/* b = (MU_REAL / h - J)^-1 b and b = (MU_COMPLEX / h - J)^-1 b, through the kept factors, for
 * the h they were made for (scratch: 2 n doubles). */
static void solve_with_real(int n, const cp_matrix_view *mx, double *b, double *scratch)
{
    cp_solve_with_real(n, real_shift(*mx->h), mx, b, scratch);
}

static void solve_with_complex(int n, const cp_matrix_view *mx, double complex *b, double *scratch)
{
    cp_solve_with_complex(n, complex_shift(*mx->h), mx, b, scratch);
}

/* Working memory, carved from the caller's work array (CP_CARVED_ROWS rows). */
typedef struct {
    double *Z0, *Z, *W, *F, *dW, *y_new, *scale, *err, *tmp;
    double complex *fc;
} radau_memory;

static radau_memory carve(int n, double *work)
{
    radau_memory m;
    m.Z0 = work;
    m.Z = m.Z0 + 3 * n;
    m.W = m.Z + 3 * n;
    m.F = m.W + 3 * n;
    m.dW = m.F + 3 * n;
    m.y_new = m.dW + 3 * n;
    m.scale = m.y_new + n;
    m.err = m.scale + n;
    m.tmp = m.err + n;
    m.fc = (double complex *)(m.tmp + n);  /* 2 rows */
    return m;
}

/* scipy's predict_factor; a previous step is none where h_old <= 0 or err_old <= 0. */
static double predict_factor(double h_abs, double h_old, double err, double err_old)
{
    double multiplier = 1.0;
    if (h_old > 0 && err_old > 0 && err != 0) multiplier = h_abs / h_old * pow(err_old / err, 0.25);
    return fmin(1.0, multiplier) * pow(err, -0.25);
}

static double rms3(int n, const double *v, const double *scale)
{
    double s = 0.0;
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < n; i++) {
            double r = v[k * n + i] / scale[i];
            s += r * r;
        }
    return sqrt(s / (3 * n));
}

/* solve_collocation_system: the stages Z (3 rows of n) of the step h from (t, y), from the
 * guess Z0; CP_OK and *converged, *n_iter, *rate, or the right-hand side's status. A stage
 * whose right-hand side cannot be had there (cp_trial_rejects, or a non-finite value) ends
 * the iteration unconverged; *trial_failure keeps that status. */
static int collocation(const cp_system *sys, double t, const double *y, double h, radau_memory *m,
                       double tol, const cp_matrix_view *mx, cp_stats *stats, int *converged,
                       int *n_iter, double *rate, int *trial_failure)
{
    const int n = sys->dim;
    const double m_real = MU_REAL / h;
    const double complex m_complex = (MU_COMPLEX_RE + MU_COMPLEX_IM * I) / h;
    double dW_norm_old = -1.0;
    *converged = 0;
    *rate = -1.0;  /* none yet */
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < n; i++)
            m->W[k * n + i] = TI[k][0] * m->Z0[i] + TI[k][1] * m->Z0[n + i] + TI[k][2] * m->Z0[2 * n + i];
    memcpy(m->Z, m->Z0, 3 * n * sizeof(double));
    for (int k = 0; k < NEWTON_MAXITER; k++) {
        *n_iter = k + 1;
        for (int s = 0; s < 3; s++) {
            for (int i = 0; i < n; i++) m->tmp[i] = y[i] + m->Z[s * n + i];
            int status = cp_eval(sys, t + h * C[s], m->tmp, m->F + s * n, stats);
            if (cp_trial_rejects(status) || (status == CP_OK && !cp_all_finite(n, m->F + s * n))) {
                *trial_failure = status ? status : CP_NONFINITE;
                return CP_OK;
            }
            if (status) return status;
        }
        for (int i = 0; i < n; i++) {
            const double f0 = m->F[i], f1 = m->F[n + i], f2 = m->F[2 * n + i];
            m->err[i] = f0 * TI[0][0] + f1 * TI[0][1] + f2 * TI[0][2] - m_real * m->W[i];
            m->fc[i] = f0 * (TI[1][0] + TI[2][0] * I) + f1 * (TI[1][1] + TI[2][1] * I)
                       + f2 * (TI[1][2] + TI[2][2] * I)
                       - m_complex * (m->W[n + i] + m->W[2 * n + i] * I);
        }
        solve_with_real(n, mx, m->err, m->dW);
        solve_with_complex(n, mx, m->fc, m->dW);
        for (int i = 0; i < n; i++) {
            m->dW[i] = m->err[i];
            m->dW[n + i] = creal(m->fc[i]);
            m->dW[2 * n + i] = cimag(m->fc[i]);
        }
        const double dW_norm = rms3(n, m->dW, m->scale);
        if (dW_norm_old >= 0) *rate = dW_norm / dW_norm_old;
        if (cp_newton_gives_up(*rate, NEWTON_MAXITER - k, dW_norm, tol)) break;
        if (!isfinite(dW_norm)) break;  /* a singular factor: scipy's comparisons fail alike */
        for (int i = 0; i < 3 * n; i++) m->W[i] += m->dW[i];
        for (int s = 0; s < 3; s++)
            for (int i = 0; i < n; i++)
                m->Z[s * n + i] = T[s][0] * m->W[i] + T[s][1] * m->W[n + i] + T[s][2] * m->W[2 * n + i];
        if (cp_newton_converged(*rate, dW_norm, tol)) {
            *converged = 1;
            break;
        }
        dW_norm_old = dW_norm;
    }
    return CP_OK;
}

int cp_radau_step(const cp_system *sys, cp_step *step, double *rows, cp_newton *nw,
                  double *block, double t_end, double rtol, double atol, double max_step,
                  long long max_steps, long long *attempts, double *work, cp_stats *stats)
{
    const int n = sys->dim;
    const size_t size = n * sizeof(double);
    double *x0 = rows + CP_ROW_X0 * n, *x1 = rows + CP_ROW_X1 * n, *f1 = rows + CP_ROW_F1 * n;
    double *Q = rows + CP_ROW_DENSE * n;
    const cp_matrix_view mx = cp_carve_matrices(n, block, nw);
    radau_memory m = carve(n, work);
    const double t = step->t1, *y = x1, *f = f1;
    const double newton_tol = cp_scipy_newton_tol(rtol);
    const double min_step = 10 * fabs(nextafter(t, INFINITY) - t);
    const int has_sol = step->method == CP_RADAU && step->t0 < step->t1;
    double h_abs = step->h, h_old = step->h_old, err_old = step->err_old;
    int status, trial_failure = CP_OK;
    if (step->method != CP_RADAU) h_old = err_old = 0.0;  /* a new start, or from DOP853 */
    if (h_abs > max_step || h_abs < min_step) {
        h_abs = h_abs > max_step ? max_step : min_step;
        h_old = err_old = 0.0;
    }
    if (!nw->jac_valid && (status = cp_new_jacobian(sys, t, y, nw, &mx, m.err, m.y_new, stats)))
        return status;
    int rejected = 0, n_iter = 0, tried_longer = 0;  /* tried_longer: a step was rejected */
    double rate = -1.0, error_norm = 0.0, safety = 0.9, t_new, h;
    for (;;) {
        if (h_abs < min_step) return trial_failure ? trial_failure : CP_STEP_UNDERFLOW;
        if (++*attempts > max_steps) return CP_TOO_MANY_STEPS;
        t_new = t + h_abs;
        if (t_new > t_end) t_new = t_end;
        h = t_new - t;
        h_abs = fabs(h);
        if (has_sol) {  /* the last step's dense output, extrapolated to the new stages */
            const double hs = step->t1 - step->t0;
            for (int s = 0; s < 3; s++) {
                const double x = (t + h * C[s] - step->t0) / hs;
                for (int i = 0; i < n; i++) {
                    const double p1 = x, p2 = p1 * x, p3 = p2 * x;
                    double v = Q[i] * p1 + Q[n + i] * p2 + Q[2 * n + i] * p3;
                    m.Z0[s * n + i] = (v + x0[i]) - y[i];
                }
            }
        } else {
            memset(m.Z0, 0, 3 * size);
        }
        for (int i = 0; i < n; i++) m.scale[i] = atol + fabs(y[i]) * rtol;
        int converged = 0;
        for (;;) {
            if (!nw->lu_valid || nw->method != CP_RADAU) cp_radau_factor(n, h, &mx, nw, stats);
            status = collocation(sys, t, y, h, &m, newton_tol, &mx, stats, &converged, &n_iter,
                                 &rate, &trial_failure);
            if (status) return status;
            if (converged || nw->current_jac) break;
            if ((status = cp_new_jacobian(sys, t, y, nw, &mx, m.err, m.y_new, stats))) return status;
        }
        if (!converged) {
            h_abs *= 0.5;
            nw->lu_valid = 0;
            stats->nreject++;
            tried_longer = 1;
            continue;
        }
        for (int i = 0; i < n; i++) {
            m.y_new[i] = y[i] + m.Z[2 * n + i];
            const double ze = (m.Z[i] * E[0] + m.Z[n + i] * E[1] + m.Z[2 * n + i] * E[2]) / h;
            m.tmp[i] = ze;  /* ZE, kept for a second estimate */
            m.err[i] = f[i] + ze;
        }
        solve_with_real(n, &mx, m.err, m.dW);
        for (int i = 0; i < n; i++)
            m.scale[i] = atol + fmax(fabs(y[i]), fabs(m.y_new[i])) * rtol;
        error_norm = cp_rms(n, m.err, m.scale);
        safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter);
        if (rejected && error_norm > 1) {  /* the estimate filtered once more, at y + error */
            double *at = m.F, *fe = m.F + n;
            for (int i = 0; i < n; i++) at[i] = y[i] + m.err[i];
            status = cp_eval(sys, t, at, fe, stats);
            if (status && !cp_trial_rejects(status)) return status;
            for (int i = 0; i < n; i++) m.err[i] = fe[i] + m.tmp[i];
            solve_with_real(n, &mx, m.err, m.dW);
            error_norm = status ? NAN : cp_rms(n, m.err, m.scale);
        }
        if (error_norm > 1 || isnan(error_norm)) {
            const double grow = predict_factor(h_abs, h_old, error_norm, err_old);
            h_abs *= isnan(error_norm) ? MIN_FACTOR : fmax(MIN_FACTOR, safety * grow);
            nw->lu_valid = 0;
            rejected = tried_longer = 1;
            stats->nreject++;
            continue;
        }
        break;
    }
    const int recompute_jac = n_iter > 2 && rate > RECOMPUTE_RATE(n);
    double grow = fmin(MAX_FACTOR, safety * predict_factor(h_abs, h_old, error_norm, err_old));
    if (LARGE(n) && tried_longer) grow = fmin(grow, 1.0);
    if (!recompute_jac && grow < KEEP_STEP_BELOW(n)) grow = 1.0;
    else nw->lu_valid = 0;
    /* the step is taken: its start, end, x' there and dense output into the rows */
    memcpy(x0, y, size);
    memcpy(x1, m.y_new, size);
    for (int r = 0; r < 3; r++)
        for (int i = 0; i < n; i++)
            Q[r * n + i] = m.Z[i] * P[0][r] + m.Z[n + i] * P[1][r] + m.Z[2 * n + i] * P[2][r];
    step->h_old = step->h;
    step->err_old = error_norm;
    step->h = h_abs * grow;
    step->t0 = t;
    step->t1 = t_new;
    step->method = CP_RADAU;
    step->dense = 1;
    stats->naccept++;
    if ((status = cp_eval(sys, t_new, x1, f1, stats))) {
        step->fsal = 0;
        return status;
    }
    step->fsal = 1;
    if (recompute_jac) return cp_new_jacobian(sys, t_new, x1, nw, &mx, m.err, m.y_new, stats);
    nw->current_jac = 0;
    return CP_OK;
}
