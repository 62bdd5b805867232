/* The backward differentiation formulas of orders 1 to 5, the implicit solver for loose
 * tolerances on large stiff scenes: scipy's BDF (scipy/integrate/_ivp/bdf.py: quasi-constant
 * step size, the numerical differentiation formulas of Shampine and Reichelt's ode15s, after
 * Byrne and Hindmarsh) step for step, on the system's exact Jacobian, which it keeps across
 * steps as CVODE keeps its own: a new one only when the Newton iteration fails with the kept
 * one; the factors of I - c J (c = h / alpha_k) are made again when c changes (newton.c's, on
 * the system's structure: a mechanical system's are half its size).
 *
 * Each step solves one implicit stage (Radau: three), so where Radau's simplified Newton
 * iteration converges slowly (a long light chain, whose stiff modes turn as it moves) BDF's
 * shorter steps take fewer Jacobians and factorizations. Its order is 5 at most and it lets
 * more of each step's error through to the end (some 20 to 400 tolerances where Radau's is
 * 0.5 to 20, tests/test_stiff.py, docs/performance.md): a choice for loose tolerances.
 *
 * The step in flight's rows hold x at t0 and t1 and x' at t1, as every method's do, and the
 * differences D[1..7] (D[0] = x at t1) in the dense output's 7 rows; step->h_old is the step
 * size they are for, step->order the formula's order, step->equal_steps the steps taken since
 * the step size last changed. The dense output is scipy's BdfDenseOutput. */
#include <math.h>
#include <string.h>

#include "solver_common.h"

#define MAX_ORDER 5
#define MIN_FACTOR 0.2
#define MAX_FACTOR 10.0
/* Past COSTLY_JACOBIAN_DIM states, where a Jacobian costs hundreds of right-hand sides and
 * the kept one is often too old for scipy's four iterations, the iteration may take ten
 * before it asks for a new one, to a tolerance of 0.03 of the error test's (scipy's at loose
 * tolerances, Hairer's FNEWT cap; CVODE's is looser still). On the damped light chain of 50
 * links at c = 1e2: rtol 1e-6 196 -> 134 Jacobians, 1e-8 341 -> 165, the error unchanged
 * to the digit that matters (benchmarks/stiff_long_chains.py). Below it, scipy's. */
#define NEWTON_MAXITER(dim) (LARGE(dim) ? 10 : 4)
#define NEWTON_TOL(dim, rtol) (LARGE(dim) ? 0.03 : cp_scipy_newton_tol(rtol))

/* scipy's coefficients, computed as it computes them: kappa (the NDF's), gamma_k = sum 1/j,
 * alpha_k = (1 - kappa_k) gamma_k and the error constants kappa_k gamma_k + 1 / (k + 1). */
static const double KAPPA[MAX_ORDER + 1] = {0, -0.1850, -1.0 / 9, -0.0823, -0.0415, 0};
static double gamma_of(int k)
{
    double g = 0.0;
    for (int j = 1; j <= k; j++) g += 1.0 / j;
    return g;
}

static double alpha_of(int k)
{
    return (1 - KAPPA[k]) * gamma_of(k);
}

static double error_const(int k)
{
    return KAPPA[k] * gamma_of(k) + 1.0 / (k + 1);
}

/* The differences D[0..order] changed in place for a step size factor times the one they are
 * for (scipy's change_D: D <- (R U)^T D); D[0] is unchanged. scratch: order n. */
static void change_differences(int n, double **D, int order, double factor, double *scratch)
{
    double R[MAX_ORDER + 1][MAX_ORDER + 1], U[MAX_ORDER + 1][MAX_ORDER + 1];
    double RU[MAX_ORDER + 1][MAX_ORDER + 1];
    for (int pass = 0; pass < 2; pass++) {  /* compute_R(order, factor), compute_R(order, 1) */
        double (*M)[MAX_ORDER + 1] = pass ? U : R;
        const double f = pass ? 1.0 : factor;
        for (int j = 0; j <= order; j++) M[0][j] = 1.0;
        for (int i = 1; i <= order; i++) {
            M[i][0] = 0.0;
            for (int j = 1; j <= order; j++) M[i][j] = M[i - 1][j] * ((i - 1 - f * j) / i);
        }
    }
    for (int i = 0; i <= order; i++)
        for (int j = 0; j <= order; j++) {
            double s = 0.0;
            for (int k = 0; k <= order; k++) s += R[i][k] * U[k][j];
            RU[i][j] = s;
        }
    for (int j = 1; j <= order; j++)  /* D_new[j] = sum_i RU[i][j] D[i] */
        for (int x = 0; x < n; x++) {
            double s = 0.0;
            for (int i = 0; i <= order; i++) s += RU[i][j] * D[i][x];
            scratch[(j - 1) * n + x] = s;
        }
    for (int j = 1; j <= order; j++) memcpy(D[j], scratch + (j - 1) * n, n * sizeof(double));
}

/* What a step carries of the integration so far: the differences D[0..MAX_ORDER + 2] (D[0]
 * the state), the step size they are for, the order, the steps taken at that size. Worked on
 * in the solver's memory and written into the step in flight when a step is accepted. */
typedef struct {
    double *D[MAX_ORDER + 3];
    double h;
    int order, equal_steps;
} history;

/* The step size changed by factor: the differences for it, and no run of equal steps. */
static void rescale(int n, history *hs, double factor, double *scratch)
{
    change_differences(n, hs->D, hs->order, factor, scratch);
    hs->h *= factor;
    hs->equal_steps = 0;
}

void cp_bdf_factor(int n, double c, const cp_matrix_view *mx, cp_newton *nw, cp_stats *stats)
{
    *mx->h = c;
    cp_factor_real(n, 1.0 / c, mx);  /* (1/c) I - J: I - c J over c */
    stats->nlu++;
    nw->lu_valid = 1;
    nw->method = CP_BDF;
}

/* dy = (I - c J)^-1 b through the factors, for the c they were made for: ((1/c) I - J) dy = b / c. */
static void solve_stage(int n, const cp_matrix_view *mx, double *b, double *scratch)
{
    const double c = *mx->h;
    for (int i = 0; i < n; i++) b[i] /= c;
    cp_solve_with_real(n, 1.0 / c, mx, b, scratch);
}

/* Working memory, carved from the caller's work array (CP_CARVED_ROWS rows): the history's
 * differences, the iteration's vectors, and scratch for the differences' change and the solves. */
typedef struct {
    history hs;
    double *y, *y_predict, *d, *psi, *f, *dy, *scale, *err, *scratch;
} bdf_memory;

static bdf_memory carve(int n, double *work)
{
    bdf_memory m;
    for (int k = 0; k < MAX_ORDER + 3; k++) m.hs.D[k] = work + k * n;
    m.y = work + (MAX_ORDER + 3) * n;
    m.y_predict = m.y + n;
    m.d = m.y_predict + n;
    m.psi = m.d + n;
    m.f = m.psi + n;
    m.dy = m.f + n;
    m.scale = m.dy + n;
    m.err = m.scale + n;
    m.scratch = m.err + n;  /* MAX_ORDER rows, within CP_CARVED_ROWS */
    return m;
}
/* solve_bdf_system: the implicit stage at t_new from m->y (the prediction), for c and psi;
 * *converged, *n_iter, and m->y, m->d (y less the prediction) its result. A right-hand
 * side that cannot be had there ends the iteration unconverged (*trial_failure its status). */
static int newton(const cp_system *sys, double t_new, double c, bdf_memory *m, double tol,
                  const cp_matrix_view *mx, cp_stats *stats, int *converged, int *n_iter,
                  int *trial_failure)
{
    const int n = sys->dim;
    double dy_norm_old = -1.0;
    *converged = 0;
    memset(m->d, 0, n * sizeof(double));
    const int max_iter = NEWTON_MAXITER(n);
    for (int k = 0; k < max_iter; k++) {
        *n_iter = k + 1;
        int status = cp_eval(sys, t_new, m->y, m->f, stats);
        if (cp_trial_rejects(status) || (status == CP_OK && !cp_all_finite(n, m->f))) {
            *trial_failure = status ? status : CP_NONFINITE;
            return CP_OK;
        }
        if (status) return status;
        for (int i = 0; i < n; i++) m->dy[i] = c * m->f[i] - m->psi[i] - m->d[i];
        solve_stage(n, mx, m->dy, m->scratch);
        const double dy_norm = cp_rms(n, m->dy, m->scale);
        const double rate = dy_norm_old >= 0 ? dy_norm / dy_norm_old : -1.0;
        if (cp_newton_gives_up(rate, max_iter - k, dy_norm, tol)) break;
        if (!isfinite(dy_norm)) break;  /* a singular factor: scipy's comparisons fail alike */
        for (int i = 0; i < n; i++) {
            m->y[i] += m->dy[i];
            m->d[i] += m->dy[i];
        }
        if (cp_newton_converged(rate, dy_norm, tol)) {
            *converged = 1;
            break;
        }
        dy_norm_old = dy_norm;
    }
    return CP_OK;
}

int cp_bdf_step(const cp_system *sys, cp_step *step, double *rows, cp_newton *nw,
                double *block, double t_end, double rtol, double atol, double max_step,
                long long max_steps, long long *attempts, double *work, cp_stats *stats)
{
    const int n = sys->dim;
    const size_t size = n * sizeof(double);
    double *x0 = rows + CP_ROW_X0 * n, *x1 = rows + CP_ROW_X1 * n, *f1 = rows + CP_ROW_F1 * n;
    const cp_matrix_view mx = cp_carve_matrices(n, block, nw);
    bdf_memory m = carve(n, work);
    history *hs = &m.hs;
    double **D = hs->D;
    const double t = step->t1;
    const double newton_tol = NEWTON_TOL(n, rtol);
    const double min_step = 10 * fabs(nextafter(t, INFINITY) - t);
    int status, trial_failure = CP_OK;
    memcpy(D[0], x1, size);
    if (step->method == CP_BDF) {  /* the differences the last step left */
        for (int k = 1; k < MAX_ORDER + 3; k++) memcpy(D[k], rows + (CP_ROW_DENSE + k - 1) * n, size);
        hs->h = step->h_old;
        hs->order = step->order;
        hs->equal_steps = step->equal_steps;
        if (step->h != hs->h) rescale(n, hs, step->h / hs->h, m.scratch);  /* cut short by a caller */
    } else {  /* a new start, or from another method: order 1 from x' */
        if (!step->fsal) {
            if ((status = cp_eval(sys, t, x1, f1, stats))) return status;
            step->fsal = 1;
        }
        for (int i = 0; i < n; i++) D[1][i] = f1[i] * step->h;
        for (int k = 2; k < MAX_ORDER + 3; k++) memset(D[k], 0, size);
        hs->h = step->h;
        hs->order = 1;
        hs->equal_steps = 0;
        if (!nw->jac_valid && (status = cp_new_jacobian(sys, t, x1, nw, &mx, m.dy, m.f, stats)))
            return status;
    }
    if (hs->h > max_step) rescale(n, hs, max_step / hs->h, m.scratch);
    else if (hs->h < min_step) rescale(n, hs, min_step / hs->h, m.scratch);
    nw->current_jac = 0;
    const int order = hs->order;
    int n_iter = 0;
    double t_new, error_norm = 0.0, safety = 0.9;
    for (;;) {
        if (hs->h < min_step) return trial_failure ? trial_failure : CP_STEP_UNDERFLOW;
        if (++*attempts > max_steps) return CP_TOO_MANY_STEPS;
        t_new = t + hs->h;
        if (t_new > t_end) {
            t_new = t_end;
            rescale(n, hs, (t_new - t) / hs->h, m.scratch);
            nw->lu_valid = 0;
        }
        hs->h = t_new - t;
        const double alpha = alpha_of(order), c = hs->h / alpha;
        for (int i = 0; i < n; i++) {
            double y = 0.0, psi = 0.0;
            for (int k = 0; k <= order; k++) y += D[k][i];
            for (int k = 1; k <= order; k++) psi += D[k][i] * gamma_of(k);
            m.y_predict[i] = m.y[i] = y;
            m.psi[i] = psi / alpha;
            m.scale[i] = atol + rtol * fabs(y);
        }
        int converged = 0;
        for (;;) {
            if (!nw->jac_valid
                && (status = cp_new_jacobian(sys, t_new, m.y_predict, nw, &mx, m.dy, m.f, stats)))
                return status;
            if (!nw->lu_valid || nw->method != CP_BDF) cp_bdf_factor(n, c, &mx, nw, stats);
            status = newton(sys, t_new, c, &m, newton_tol, &mx, stats, &converged, &n_iter,
                            &trial_failure);
            if (status) return status;
            if (converged || nw->current_jac) break;
            if ((status = cp_new_jacobian(sys, t_new, m.y_predict, nw, &mx, m.dy, m.f, stats)))
                return status;
            memcpy(m.y, m.y_predict, size);
        }
        if (!converged) {
            rescale(n, hs, 0.5, m.scratch);
            nw->lu_valid = 0;
            stats->nreject++;
            continue;
        }
        safety = 0.9 * (2 * NEWTON_MAXITER(n) + 1) / (2 * NEWTON_MAXITER(n) + n_iter);
        for (int i = 0; i < n; i++) {
            m.scale[i] = atol + rtol * fabs(m.y[i]);
            m.err[i] = error_const(order) * m.d[i];
        }
        error_norm = cp_rms(n, m.err, m.scale);
        if (error_norm > 1) {  /* the factors kept: the iteration converged with them */
            rescale(n, hs, fmax(MIN_FACTOR, safety * pow(error_norm, -1.0 / (order + 1))), m.scratch);
            stats->nreject++;
            continue;
        }
        break;
    }
    /* the step is taken: the differences updated, D[0] the new state */
    for (int i = 0; i < n; i++) {
        D[order + 2][i] = m.d[i] - D[order + 1][i];
        D[order + 1][i] = m.d[i];
    }
    for (int k = order; k >= 0; k--)
        for (int i = 0; i < n; i++) D[k][i] += D[k + 1][i];
    hs->equal_steps++;
    if (hs->equal_steps >= order + 1) {  /* the order and step size chosen anew */
        double norms[3] = {INFINITY, error_norm, INFINITY}, factors[3];
        if (order > 1) {
            for (int i = 0; i < n; i++) m.err[i] = error_const(order - 1) * D[order][i];
            norms[0] = cp_rms(n, m.err, m.scale);
        }
        if (order < MAX_ORDER) {
            for (int i = 0; i < n; i++) m.err[i] = error_const(order + 1) * D[order + 2][i];
            norms[2] = cp_rms(n, m.err, m.scale);
        }
        int best = 0;
        for (int k = 0; k < 3; k++) {
            factors[k] = pow(norms[k], -1.0 / (order + k));
            if (factors[k] > factors[best]) best = k;
        }
        hs->order = order + best - 1;
        rescale(n, hs, fmin(MAX_FACTOR, safety * factors[best]), m.scratch);
        nw->lu_valid = 0;
    }
    /* into the step in flight: its start, end, differences, x' at its end */
    memcpy(x0, x1, size);
    memcpy(x1, D[0], size);
    for (int k = 1; k < MAX_ORDER + 3; k++) memcpy(rows + (CP_ROW_DENSE + k - 1) * n, D[k], size);
    step->h = step->h_old = hs->h;
    step->order = hs->order;
    step->equal_steps = hs->equal_steps;
    step->err_old = error_norm;
    step->t0 = t;
    step->t1 = t_new;
    step->method = CP_BDF;
    step->dense = 1;
    stats->naccept++;
    if ((status = cp_eval(sys, t_new, x1, f1, stats))) {
        step->fsal = 0;
        return status;
    }
    step->fsal = 1;
    return CP_OK;
}
