#include "solvers.h"

#include <math.h>
#include <string.h>

#include "solver_common.h"
#include "tableaus.h"

#define SAFETY 0.9
#define MIN_FACTOR 0.2
#define MAX_FACTOR 10.0

typedef struct {
    int stages, order;          /* order of the error estimator */
    const double *c, *a, *b;    /* a: stages x a_stride, row s uses entries 0..s-1 */
    int a_stride;
    const double *e, *e3;       /* e (or e5 with e3 for DOP853): stages + 1 weights */
    double stiff_bound;         /* h |lambda| past which the steps are bounded by stability */
} tableau;

/* The stiffness bounds are Hairer's (dopri5 3.25, dop853 6.1): where each method's stability
 * region ends along the estimate h |lambda| his codes test. */
static const tableau RK45_TABLEAU = {6, 4, RK45_C, &RK45_A[0][0], RK45_B, 5, RK45_E, 0, 3.25};
static const tableau DOP853_TABLEAU = {DOP853_STAGES, 7, DOP853_C, &DOP853_A[0][0], DOP853_B,
                                       DOP853_STAGES, DOP853_E5, DOP853_E3, CP_STIFF_BOUND};

double cp_stiffness_bound(int method)
{
    return method == CP_RK45 ? RK45_TABLEAU.stiff_bound : DOP853_TABLEAU.stiff_bound;
}

#define eval cp_eval
#define rms cp_rms


/* cp_rk4 has checked that ceil(dt / max_step) <= max_steps. On failure, good holds the
 * last point where x' was computed (x itself when none was) and *done the substeps that led
 * there. */
static int rk4(const cp_system *sys, double t, double *x, double dt, double max_step, double *work,
               cp_stats *stats, long long *done)
{
    int n = sys->dim, status;
    long long steps = (long long)cp_fewest_steps(dt, max_step);
    double h = dt / steps;
    double *y = work, *k1 = y + n, *k2 = k1 + n, *k3 = k2 + n, *k4 = k3 + n, *tmp = k4 + n;
    double *good = tmp + n;
    memcpy(y, x, n * sizeof(double));
    memcpy(good, x, n * sizeof(double));
    *done = 0;
    for (long long s = 0; s < steps; s++) {
        const double ts = t + s * h;
        if ((status = eval(sys, ts, y, k1, stats))) return status;
        memcpy(good, y, n * sizeof(double));  /* x' is defined at y */
        *done = s;
        for (int i = 0; i < n; i++) tmp[i] = y[i] + 0.5 * h * k1[i];
        if ((status = eval(sys, ts + 0.5 * h, tmp, k2, stats))) return status;
        for (int i = 0; i < n; i++) tmp[i] = y[i] + 0.5 * h * k2[i];
        if ((status = eval(sys, ts + 0.5 * h, tmp, k3, stats))) return status;
        for (int i = 0; i < n; i++) tmp[i] = y[i] + h * k3[i];
        if ((status = eval(sys, ts + h, tmp, k4, stats))) return status;
        for (int i = 0; i < n; i++) y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        stats->naccept++;
    }
    if (!cp_all_finite(n, y)) return CP_NONFINITE;  /* the last update is evaluated by no one */
    memcpy(x, y, n * sizeof(double));
    return CP_OK;
}

/* scipy.integrate._ivp.common.select_initial_step */
static int initial_step(const cp_system *sys, double t, const double *y, const double *f, double interval,
                        double rtol, double atol, double max_step, int order, double *tmp,
                        double *f1, double *scale, cp_stats *stats, double *h)
{
    int n = sys->dim, status;
    for (int i = 0; i < n; i++) scale[i] = atol + fabs(y[i]) * rtol;
    double d0 = rms(n, y, scale), d1 = rms(n, f, scale);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > interval) h0 = interval;
    for (;;) {  /* the Euler step's guess shrunk until the scene can be evaluated there */
        for (int i = 0; i < n; i++) tmp[i] = y[i] + h0 * f[i];
        status = eval(sys, t + h0, tmp, f1, stats);
        if (!(cp_trial_rejects(status) || (status == CP_OK && !cp_all_finite(n, f1)))) break;
        if ((h0 *= 0.01) < cp_min_step(t, t + interval)) return status ? status : CP_NONFINITE;
    }
    if (status) return status;
    for (int i = 0; i < n; i++) tmp[i] = f1[i] - f[i];
    double d2 = rms(n, tmp, scale) / h0;
    double h1 = (d1 <= 1e-15 && d2 <= 1e-15) ? fmax(1e-6, h0 * 1e-3)
                                             : pow(0.01 / fmax(d1, d2), 1.0 / (order + 1));
    *h = fmin(fmin(100 * h0, h1), fmin(interval, max_step));
    return CP_OK;
}

static double error_norm(const tableau *tb, int n, const double *K, double h, const double *scale,
                         double *err)
{
    int rows = tb->stages + 1;
    if (!tb->e3) {
        for (int i = 0; i < n; i++) {
            double s = 0.0;
            for (int j = 0; j < rows; j++) s += K[j * n + i] * tb->e[j];
            err[i] = s * h;
        }
        return rms(n, err, scale);
    }
    double e5 = 0.0, e3 = 0.0;   /* DOP853: the 5th- and 3rd-order estimates combined */
    for (int i = 0; i < n; i++) {
        double s5 = 0.0, s3 = 0.0;
        for (int j = 0; j < rows; j++) {
            s5 += K[j * n + i] * tb->e[j];
            s3 += K[j * n + i] * tb->e3[j];
        }
        s5 /= scale[i];
        s3 /= scale[i];
        e5 += s5 * s5;
        e3 += s3 * s3;
    }
    if (e5 == 0.0 && e3 == 0.0) return 0.0;
    return fabs(h) * e5 / sqrt((e5 + 0.01 * e3) * n);
}

/* Working memory of the adaptive pairs, carved from the caller's work array. */
typedef struct {
    double *K, *y, *y_new, *tmp, *scale, *err;
} rk_memory;

/* carve() takes K's 16 rows and five vectors: within CP_CARVED_ROWS */

static rk_memory carve(int n, double *work)
{
    rk_memory m;
    m.K = work;                 /* 16 rows: stages, x' at the new point, dense-output stages */
    m.y = m.K + 16 * n;
    m.y_new = m.y + n;
    m.tmp = m.y_new + n;
    m.scale = m.tmp + n;
    m.err = m.scale + n;
    return m;
}

/* Hairer's estimate of the dominant mode an explicit step meets, from its last stage and its
 * new point (both at the step's end): size h |lambda| (his stiffness test's) and decay
 * -h Re(lambda), the Rayleigh quotient of the same differences, near 0 for a fast oscillation
 * and near size for a fast decay. */
typedef struct {
    double size, decay;
} estimate;

/* One accepted step from (t, m->y) towards t_end, rejecting as often as needed, as
 * scipy's RungeKutta._step_impl does; a trial stage that is not finite (trial_rejects) is a
 * rejection too, shrinking the step as a NaN error norm does, and the integration fails only
 * where no step down to the shortest one avoids it (then with that stage's status). On
 * return *t_new and m->y_new hold the new point and K[stages] holds x' there; m->y and K[0]
 * are left for dense output; *stiffness is the accepted step's estimate. */
static int one_step(const tableau *tb, const cp_system *sys, double t, double t_end,
                    rk_memory *m, double rtol, double atol, double max_step, long long max_steps,
                    long long *attempts, double *h_abs_io, double *t_new_out, double *h_out,
                    estimate *stiffness, cp_stats *stats)
{
    int n = sys->dim, status, last_failure = CP_OK;  /* the last trial stage's, if it rejected */
    double *K = m->K, exponent = -1.0 / (tb->order + 1), h_abs = *h_abs_io;
    double min_step = 10 * fabs(nextafter(t, INFINITY) - t);
    if (h_abs > max_step) h_abs = max_step;
    else if (h_abs < min_step) h_abs = min_step;
    int rejected = 0;
    for (;;) {
        if (h_abs < min_step) return last_failure ? last_failure : CP_STEP_UNDERFLOW;
        if (++*attempts > max_steps) return CP_TOO_MANY_STEPS;
        double t_new = t + h_abs;
        if (t_new > t_end) t_new = t_end;
        double h = t_new - t;
        h_abs = fabs(h);
        double norm = NAN;
        int trial_failure = CP_OK;
        for (int s = 1; s < tb->stages && !trial_failure; s++) {
            const double *a = tb->a + s * tb->a_stride;
            for (int i = 0; i < n; i++) {
                double dy = 0.0;
                for (int j = 0; j < s; j++) dy += K[j * n + i] * a[j];
                m->tmp[i] = m->y[i] + dy * h;
            }
            status = eval(sys, t + tb->c[s] * h, m->tmp, K + s * n, stats);
            if (cp_trial_rejects(status)) trial_failure = status;
            else if (status) return status;
        }
        if (!trial_failure) {
            for (int i = 0; i < n; i++) {
                double dy = 0.0;
                for (int j = 0; j < tb->stages; j++) dy += K[j * n + i] * tb->b[j];
                m->y_new[i] = m->y[i] + h * dy;
            }
            status = eval(sys, t_new, m->y_new, K + tb->stages * n, stats);
            if (cp_trial_rejects(status)) trial_failure = status;
            else if (status) return status;
        }
        if (!trial_failure) {
            for (int i = 0; i < n; i++)
                m->scale[i] = atol + fmax(fabs(m->y[i]), fabs(m->y_new[i])) * rtol;
            norm = error_norm(tb, n, K, h, m->scale, m->err);
        }
        if (norm < 1) {
            double factor = norm == 0 ? MAX_FACTOR : fmin(MAX_FACTOR, SAFETY * pow(norm, exponent));
            if (rejected && factor > 1) factor = 1;
            double num = 0.0, dot = 0.0, den = 0.0;  /* last stage and new point, at t_new */
            const double *k_last = K + (tb->stages - 1) * n, *k_new = K + tb->stages * n;
            for (int i = 0; i < n; i++) {
                const double dk = k_new[i] - k_last[i], dy = m->y_new[i] - m->tmp[i];
                num += dk * dk;
                dot += dk * dy;
                den += dy * dy;
            }
            stiffness->size = den > 0 ? h_abs * sqrt(num / den) : 0.0;
            stiffness->decay = den > 0 ? -h_abs * dot / den : 0.0;
            *h_abs_io = h_abs * factor;
            *t_new_out = t_new;
            *h_out = h;
            stats->naccept++;
            return CP_OK;
        }
        /* a NaN norm (non-finite stage) counts as a failed step */
        h_abs *= isnan(norm) ? MIN_FACTOR : fmax(MIN_FACTOR, SAFETY * pow(norm, exponent));
        rejected = 1;
        stats->nreject++;
        last_failure = trial_failure;
    }
}

/* scipy's DOP853._dense_output_impl: three more stages, then the interpolant F (7 rows). */
static int dop853_interpolant(const cp_system *sys, double t, double h, rk_memory *m, double *F,
                              cp_stats *stats)
{
    int n = sys->dim, status, stages = DOP853_STAGES;
    double *K = m->K;
    for (int e = 0; e < 3; e++) {
        int s = stages + 1 + e;
        for (int i = 0; i < n; i++) {
            double dy = 0.0;
            for (int j = 0; j < s; j++) dy += K[j * n + i] * DOP853_A_EXTRA[e][j];
            m->tmp[i] = m->y[i] + dy * h;
        }
        if ((status = eval(sys, t + DOP853_C_EXTRA[e] * h, m->tmp, K + s * n, stats))) return status;
    }
    const double *f_old = K, *f_new = K + stages * n;
    for (int i = 0; i < n; i++) {
        double delta = m->y_new[i] - m->y[i];
        F[i] = delta;
        F[n + i] = h * f_old[i] - delta;
        F[2 * n + i] = 2 * delta - h * (f_new[i] + f_old[i]);
        for (int r = 0; r < 4; r++) {
            double s = 0.0;
            for (int j = 0; j < 16; j++) s += DOP853_D[r][j] * K[j * n + i];
            F[(3 + r) * n + i] = h * s;
        }
    }
    return CP_OK;
}

/* scipy's RK45._dense_output_impl: Q = K^T P (4 rows), no more stages. */
static void rk45_interpolant(int n, const rk_memory *m, double *Q)
{
    for (int r = 0; r < 4; r++)
        for (int i = 0; i < n; i++) {
            double s = 0.0;
            for (int j = 0; j < 7; j++) s += m->K[j * n + i] * RK45_P[j][r];
            Q[r * n + i] = s;
        }
}

void cp_step_begin(cp_step *step, double *rows, int dim, double t, const double *x, double h)
{
    step->t0 = step->t1 = t;
    step->h = h;
    step->fsal = step->dense = 0;
    step->method = step->next = CP_DOP853;
    step->stiff_steps = step->calm_steps = 0;
    step->h_old = step->err_old = step->stiffness = 0.0;
    step->order = step->equal_steps = 0;
    memcpy(rows + CP_ROW_X1 * dim, x, dim * sizeof(double));
}

void cp_newton_refactor(int n, cp_newton *nw, double *block)
{
    const cp_matrix_view mx = cp_matrices_of_jacobian(n, block, nw);
    cp_stats uncounted = {0, 0, 0, 0, 0, 0};  /* no step's work: the step counted it */
    (nw->method == CP_BDF ? cp_bdf_factor : cp_radau_factor)(n, nw->h, &mx, nw, &uncounted);
}

/* The order of a method's error estimator, which its first step's choice assumes. */
static int estimator_order(int method)
{
    return method == CP_RK45 ? 4 : method == CP_RADAU ? 3 : method == CP_BDF ? 1 : 7;
}

/* The watch's rows after the solver's and cp_dense_grid's: the step before the one taken,
 * then the event functions at the step's start and end. */
#define SAVED_ROWS (CP_CARVED_ROWS + CP_FLIGHT_ROWS)
#define EVENT_ROWS (SAVED_ROWS + CP_FLIGHT_ROWS)

/* Whether g's sign says its switch is on (cp_watch). */
static int on(double g)
{
    return g > 0;
}

/* The watch's event functions at (t0, x0) and (t1, x1) into the event rows of work; whether
 * any sign differs. */
static int events_differ(const cp_system *sys, double t0, const double *x0, double t1,
                         const double *x1, double *work)
{
    const cp_watch *w = sys->watch;
    if (!w || !w->n_events) return 0;
    double *g0 = work + EVENT_ROWS * sys->dim, *g1 = g0 + sys->dim;
    w->events(w->ctx, t0, x0, g0);
    w->events(w->ctx, t1, x1, g1);
    for (int k = 0; k < w->n_events; k++)
        if (on(g0[k]) != on(g1[k])) return 1;
    return 0;
}

/* Whether an accepted step from (t0, x0) to (t1, x1), x' = f1 there, needs its dense output
 * for the watch: an event inside it, or what the watch looks for. */
static int watched_inside(const cp_system *sys, double t0, const double *x0, double t1,
                          const double *x1, const double *f1, double *work)
{
    const cp_watch *w = sys->watch;
    if (!w) return 0;
    return events_differ(sys, t0, x0, t1, x1, work)
           || (w->wants_dense && w->wants_dense(w->ctx, t1, x1, f1));
}

/* The earliest time inside the step in flight (dense) at which an event function has the
 * sign it has at the step's end, its sign at the start differing: bisection on the dense
 * output down to adjacent doubles, so the root lies within an ulp before it. step->t1 when
 * no sign differs. The event rows hold the functions at the step's ends (events_differ). */
static double earliest_switch(const cp_system *sys, const cp_step *step, const double *rows,
                              double *work)
{
    const cp_watch *w = sys->watch;
    const int n = sys->dim;
    double *g0 = work + EVENT_ROWS * n, *g1 = g0 + n;
    double *x = work, *g = work + n;  /* carved rows the taken step no longer needs */
    double found = step->t1;
    for (int k = 0; k < w->n_events; k++) {
        if (on(g0[k]) == on(g1[k])) continue;
        const int from = on(g0[k]);
        double before = step->t0, after = found;  /* a root of g_k before found, if any */
        cp_step_state(step, rows, n, after, x);
        w->events(w->ctx, after, x, g);
        if (on(g[k]) == from) continue;  /* k switches after an earlier one */
        for (;;) {
            const double mid = before + 0.5 * (after - before);
            if (mid <= before || mid >= after) break;
            cp_step_state(step, rows, n, mid, x);
            w->events(w->ctx, mid, x, g);
            if (on(g[k]) == from) before = mid;
            else after = mid;
        }
        found = after;
    }
    return found;
}

/* explicit_step's answer for a step that would answer t_target from an interpolant it cannot
 * trust: not taken, to be taken again ending on t_target. */
#define RETAKE_ON_POINT (-1)

/* One accepted step of RK45 or DOP853 from the end of the step in flight, with its interpolant
 * when it crosses t_target; *stiffness as one_step's. A step that crosses t_target with a
 * decay past trust_bound is not taken (RETAKE_ON_POINT, counted as a rejection): DOP853's
 * interpolant on a fast decay is off by up to a hundred tolerances where the step's end is
 * not (measured on the damped light chain: 7e-5 inside its steps, 3e-6 at their ends, at
 * rtol 1e-6). */
static int explicit_step(int method, const cp_system *sys, cp_step *step, double *rows,
                         double t_target, double t_limit, double trust_bound, double rtol,
                         double atol, double max_step, long long max_steps, long long *attempts,
                         double *work, estimate *stiffness, cp_stats *stats)
{
    const tableau *tb = method == CP_RK45 ? &RK45_TABLEAU : &DOP853_TABLEAU;
    int n = sys->dim, status;
    size_t size = n * sizeof(double);
    rk_memory m = carve(n, work);
    double *x0 = rows + CP_ROW_X0 * n, *x1 = rows + CP_ROW_X1 * n, *f1 = rows + CP_ROW_F1 * n;
    double h_abs = step->h, t_new, h;
    memcpy(m.y, x1, size);
    memcpy(m.K, f1, size);
    status = one_step(tb, sys, step->t1, t_limit, &m, rtol, atol, max_step, max_steps, attempts,
                      &h_abs, &t_new, &h, stiffness, stats);
    if (status) return status;
    if (!cp_all_finite(n, m.y_new)) return CP_NONFINITE;
    int crosses = t_new > t_target;  /* the target is answered from this step's interpolant */
    if (crosses && stiffness->decay > trust_bound) {
        stats->naccept--;
        stats->nreject++;
        return RETAKE_ON_POINT;
    }
    const int dense = crosses || watched_inside(sys, step->t1, m.y, t_new, m.y_new,
                                                m.K + tb->stages * n, work);
    if (dense) {
        double *dense = rows + CP_ROW_DENSE * n;
        if (method == CP_RK45) rk45_interpolant(n, &m, dense);
        else if ((status = dop853_interpolant(sys, step->t1, h, &m, dense, stats))) return status;
    }
    memcpy(x0, m.y, size);
    memcpy(x1, m.y_new, size);
    memcpy(f1, m.K + tb->stages * n, size);
    step->t0 = step->t1;
    step->t1 = t_new;
    step->h = h_abs;
    step->dense = dense;
    step->method = method;
    return CP_OK;
}

/* Hairer's count of an explicit pair's accepted steps past its stiffness bound: 15 of them
 * with never 6 in a row inside it between make the scene stiff. */
static int looks_stiff(cp_step *step, int past)
{
    if (past) {
        step->stiff_steps++;
        step->calm_steps = 0;
    } else if (++step->calm_steps >= CP_CALM_RESET) {
        step->stiff_steps = 0;
    }
    return step->stiff_steps >= CP_STIFF_STEPS;
}

/* The largest step DOP853 takes under CP_AUTO back from Radau: inside its trusted bound on
 * the Jacobian's modes. */
static double explicit_cap(int method, const cp_newton *newton, double max_step)
{
    return method == CP_AUTO && newton->jac_valid && newton->rho > 0
               ? fmin(max_step, CP_AUTO_BOUND / newton->rho)
               : max_step;
}

/* One accepted step of use (the method in use under method) from the end of the step in
 * flight, none ending after t_limit; *stiffness the explicit pair's estimate. */
static int take(int method, int use, const cp_system *sys, cp_step *step, double *rows,
                cp_newton *newton, double *matrices, double t_target, double t_limit,
                double rtol, double atol, double max_step, long long max_steps,
                long long *attempts, double *work, estimate *stiffness, cp_stats *stats)
{
    int n = sys->dim, status;
    if (use == CP_RADAU || use == CP_BDF) {
        status = (use == CP_RADAU ? cp_radau_step : cp_bdf_step)(
            sys, step, rows, newton, matrices, t_limit, rtol, atol, max_step, max_steps,
            attempts, work, stats);
        if (status) return status;
        return cp_all_finite(n, rows + CP_ROW_X1 * n) ? CP_OK : CP_NONFINITE;
    }
    const double trust = method == CP_AUTO ? CP_AUTO_BOUND : INFINITY;
    const double cap = explicit_cap(method, newton, max_step);
    status = explicit_step(use, sys, step, rows, t_target, t_limit, trust, rtol, atol, cap,
                           max_steps, attempts, work, stiffness, stats);
    if (status == RETAKE_ON_POINT) {  /* the stiffness test counts the step not taken */
        estimate shortened;
        status = explicit_step(use, sys, step, rows, t_target, fmin(t_target, t_limit), INFINITY,
                               rtol, atol, cap, max_steps, attempts, work, &shortened, stats);
    }
    if (status == CP_TOO_MANY_STEPS && step->stiff_steps >= CP_STIFF_STEPS)
        return CP_STIFF;  /* the steps were bounded by stability, not accuracy */
    return status;
}

int cp_cover(int method, const cp_system *sys, cp_step *step, double *rows, cp_newton *newton,
             double *matrices, double t_target, double t_limit, double rtol, double atol,
             double max_step, long long max_steps, long long *attempts, double *work,
             cp_stats *stats)
{
    int n = sys->dim, status;
    double *x1 = rows + CP_ROW_X1 * n, *f1 = rows + CP_ROW_F1 * n;
    if (!(max_step > 0)) max_step = INFINITY;
    if (step->t1 >= t_target) return CP_OK;
    if (!step->fsal) {
        if ((status = eval(sys, step->t1, x1, f1, stats))) return status;
        step->fsal = 1;
    }
    if (!(step->h > 0) || !isfinite(step->h)) {
        rk_memory m = carve(n, work);
        int first = method == CP_AUTO ? step->next : method;
        status = initial_step(sys, step->t1, x1, f1, t_limit - step->t1, rtol, atol, max_step,
                              estimator_order(first), m.tmp, m.err, m.scale, stats, &step->h);
        if (status) return status;
    }
    const cp_watch *watch = sys->watch;
    double *saved = work + SAVED_ROWS * n;  /* the step before the one taken, with a watch */
    while (step->t1 < t_target) {
        const int use = method == CP_AUTO ? step->next : method;
        const cp_step before = *step;
        if (watch) memcpy(saved, rows, CP_FLIGHT_ROWS * n * sizeof(double));
        estimate stiffness = {0.0, 0.0};
        status = take(method, use, sys, step, rows, newton, matrices, t_target, t_limit, rtol,
                      atol, max_step, max_steps, attempts, work, &stiffness, stats);
        if (status) return status;
        if (watch && watch->n_events
            && events_differ(sys, step->t0, rows + CP_ROW_X0 * n, step->t1, rows + CP_ROW_X1 * n, work)) {
            const double t_switch = earliest_switch(sys, step, rows, work);
            if (t_switch < step->t1) {  /* taken again, to end on the switch */
                *step = before;
                memcpy(rows, saved, CP_FLIGHT_ROWS * n * sizeof(double));
                step->h = t_switch - step->t1;
                stats->naccept--;
                stats->nreject++;
                status = take(method, use, sys, step, rows, newton, matrices, t_target, t_switch,
                              rtol, atol, max_step, max_steps, attempts, work, &stiffness, stats);
                if (status) return status;
            }
        }
        if (use == CP_RADAU) {
            step->stiffness = (step->t1 - step->t0) * newton->rho;
            step->calm_steps = step->stiffness < CP_CALM_BOUND ? step->calm_steps + 1 : 0;
            if (method == CP_AUTO && step->calm_steps >= CP_CALM_STEPS) {
                step->next = CP_DOP853;  /* the scene calmed: back to the explicit pair */
                step->calm_steps = step->stiff_steps = 0;
                stats->nswitch++;
            }
        } else {
            step->stiffness = stiffness.size;
            const tableau *tb = use == CP_RK45 ? &RK45_TABLEAU : &DOP853_TABLEAU;
            /* auto: a fast decay, or a step held at the cap while accuracy asks for more */
            const double cap = explicit_cap(method, newton, max_step);
            const int held = step->t1 - step->t0 >= cap && step->h > cap;
            const int past = method == CP_AUTO ? stiffness.decay > CP_AUTO_BOUND || held
                                               : stiffness.size > tb->stiff_bound;
            if (looks_stiff(step, past) && method == CP_AUTO) {
                step->next = CP_RADAU;  /* stiff: the implicit solver from here */
                step->calm_steps = step->stiff_steps = 0;
                newton->current_jac = 0;
                stats->nswitch++;
            }
        }
        if (watch && watch->accepted) watch->accepted(watch->ctx, step, rows);
    }
    return CP_OK;
}

void cp_step_state(const cp_step *step, const double *rows, int dim, double t, double *x)
{
    const double *x0 = rows + CP_ROW_X0 * dim, *dense = rows + CP_ROW_DENSE * dim;
    if (t == step->t1) {
        memcpy(x, rows + CP_ROW_X1 * dim, dim * sizeof(double));
        return;
    }
    if (step->method == CP_BDF) {  /* BdfDenseOutput._call_impl: D[0] + sum D[j] prod x_m */
        const double h = step->h_old;
        double p[7], prod = 1.0;
        for (int m = 0; m < step->order; m++) p[m] = prod *= (t - (step->t1 - h * m)) / (h * (1 + m));
        for (int i = 0; i < dim; i++) {
            double y = 0.0;
            for (int j = 1; j <= step->order; j++) y += dense[(j - 1) * dim + i] * p[j - 1];
            x[i] = y + rows[CP_ROW_X1 * dim + i];
        }
        return;
    }
    double h = step->t1 - step->t0, s = (t - step->t0) / h;
    for (int i = 0; i < dim; i++) {
        double y = 0.0;
        if (step->method == CP_RK45) {  /* RkDenseOutput._call_impl: x0 + h Q (s, s^2, s^3, s^4) */
            double power = s;
            for (int r = 0; r < 4; r++, power *= s) y += dense[r * dim + i] * power;
            x[i] = h * y + x0[i];
        } else if (step->method == CP_RADAU) {  /* RadauDenseOutput._call_impl: x0 + Q (s, s^2, s^3) */
            const double p1 = s, p2 = p1 * s, p3 = p2 * s;
            y = dense[i] * p1 + dense[dim + i] * p2 + dense[2 * dim + i] * p3;
            x[i] = y + x0[i];
        } else {  /* Dop853DenseOutput._call_impl */
            for (int k = 6, odd = 0; k >= 0; k--, odd ^= 1) {
                y += dense[k * dim + i];
                y *= odd ? 1 - s : s;
            }
            x[i] = y + x0[i];
        }
    }
}

int cp_dense_grid(int method, const cp_system *sys, const double *times, int ntimes, double *out,
                  double rtol, double atol, double max_step, long long max_steps, double *work,
                  cp_newton *newton, double *matrices, cp_stats *stats)
{
    int n = sys->dim, status;
    double *rows = work + CP_CARVED_ROWS * n;  /* the step in flight after the solver's memory */
    cp_step step;
    long long attempts = 0;
    if (ntimes < 2) return CP_OK;
    cp_step_begin(&step, rows, n, times[0], out, 0.0);
    for (int k = 1; k < ntimes; k++) {
        status = cp_cover(method, sys, &step, rows, newton, matrices, times[k], times[ntimes - 1],
                          rtol, atol, max_step, max_steps, &attempts, work, stats);
        if (status) return status;
        cp_step_state(&step, rows, n, times[k], out + k * n);
    }
    return CP_OK;
}

int cp_rk4(const cp_system *sys, double t, double *x, double dt, double max_step,
           long long max_steps, double *work, cp_stats *stats, double *reached)
{
    int status;
    long long done;
    if (reached) *reached = t;
    if (dt <= 0) return CP_OK;
    if ((status = cp_unworkable(CP_RK4, t, dt, max_step, max_steps))) return status;
    status = rk4(sys, t, x, dt, max_step, work, stats, &done);
    if (status == CP_OK) {
        if (reached) *reached = t + dt;
    } else if (reached && done > 0) {  /* the last substep where x' was computed */
        memcpy(x, work + 6 * sys->dim, sys->dim * sizeof(double));
        *reached = t + done * (dt / (long long)cp_fewest_steps(dt, max_step));
    }
    return status;
}
