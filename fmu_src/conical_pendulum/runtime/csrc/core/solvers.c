#include "solvers.h"

#include <math.h>
#include <string.h>

#include "tableaus.h"

#define SAFETY 0.9
#define MIN_FACTOR 0.2
#define MAX_FACTOR 10.0

typedef struct {
    int stages, order;          /* order of the error estimator */
    const double *c, *a, *b;    /* a: stages x a_stride, row s uses entries 0..s-1 */
    int a_stride;
    const double *e, *e3;       /* e (or e5 with e3 for DOP853): stages + 1 weights */
} tableau;

static const tableau RK45_TABLEAU = {6, 4, RK45_C, &RK45_A[0][0], RK45_B, 5, RK45_E, 0};
static const tableau DOP853_TABLEAU = {DOP853_STAGES, 7, DOP853_C, &DOP853_A[0][0], DOP853_B,
                                       DOP853_STAGES, DOP853_E5, DOP853_E3};

static int eval(const cp_system *sys, double t, const double *x, double *dx, cp_stats *stats)
{
    stats->nfev++;
    return sys->rhs(sys->ctx, t, x, dx);
}

static double rms(int n, const double *v, const double *scale)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) {
        double r = v[i] / scale[i];
        s += r * r;
    }
    return sqrt(s / n);
}

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
    for (int i = 0; i < n; i++) tmp[i] = y[i] + h0 * f[i];
    if ((status = eval(sys, t + h0, tmp, f1, stats))) return status;
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

#define CARVED_ROWS 21  /* the rows carve() takes: K's 16 and five vectors */

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

/* One accepted step from (t, m->y) towards t_end, rejecting as often as needed, as
 * scipy's RungeKutta._step_impl does. On return *t_new and m->y_new hold the new point
 * and K[stages] holds x' there; m->y and K[0] are left for dense output. */
static int one_step(const tableau *tb, const cp_system *sys, double t, double t_end,
                    rk_memory *m, double rtol, double atol, double max_step, long long max_steps,
                    long long *attempts, double *h_abs_io, double *t_new_out, double *h_out,
                    cp_stats *stats)
{
    int n = sys->dim, status;
    double *K = m->K, exponent = -1.0 / (tb->order + 1), h_abs = *h_abs_io;
    double min_step = 10 * fabs(nextafter(t, INFINITY) - t);
    if (h_abs > max_step) h_abs = max_step;
    else if (h_abs < min_step) h_abs = min_step;
    int rejected = 0;
    for (;;) {
        if (h_abs < min_step) return CP_STEP_UNDERFLOW;
        if (++*attempts > max_steps) return CP_TOO_MANY_STEPS;
        double t_new = t + h_abs;
        if (t_new > t_end) t_new = t_end;
        double h = t_new - t;
        h_abs = fabs(h);
        for (int s = 1; s < tb->stages; s++) {
            const double *a = tb->a + s * tb->a_stride;
            for (int i = 0; i < n; i++) {
                double dy = 0.0;
                for (int j = 0; j < s; j++) dy += K[j * n + i] * a[j];
                m->tmp[i] = m->y[i] + dy * h;
            }
            if ((status = eval(sys, t + tb->c[s] * h, m->tmp, K + s * n, stats))) return status;
        }
        for (int i = 0; i < n; i++) {
            double dy = 0.0;
            for (int j = 0; j < tb->stages; j++) dy += K[j * n + i] * tb->b[j];
            m->y_new[i] = m->y[i] + h * dy;
        }
        if ((status = eval(sys, t_new, m->y_new, K + tb->stages * n, stats))) return status;
        for (int i = 0; i < n; i++)
            m->scale[i] = atol + fmax(fabs(m->y[i]), fabs(m->y_new[i])) * rtol;
        double norm = error_norm(tb, n, K, h, m->scale, m->err);
        if (norm < 1) {
            double factor = norm == 0 ? MAX_FACTOR : fmin(MAX_FACTOR, SAFETY * pow(norm, exponent));
            if (rejected && factor > 1) factor = 1;
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
    memcpy(rows + CP_ROW_X1 * dim, x, dim * sizeof(double));
}

int cp_cover(int method, const cp_system *sys, cp_step *step, double *rows, double t_target,
             double t_limit, double rtol, double atol, double max_step, long long max_steps,
             long long *attempts, double *work, cp_stats *stats)
{
    const tableau *tb = method == CP_RK45 ? &RK45_TABLEAU : &DOP853_TABLEAU;
    int n = sys->dim, status;
    size_t size = n * sizeof(double);
    rk_memory m = carve(n, work);
    double *x0 = rows + CP_ROW_X0 * n, *x1 = rows + CP_ROW_X1 * n, *f1 = rows + CP_ROW_F1 * n;
    double *dense = rows + CP_ROW_DENSE * n;
    if (!(max_step > 0)) max_step = INFINITY;
    if (step->t1 >= t_target) return CP_OK;
    if (!step->fsal) {
        if ((status = eval(sys, step->t1, x1, f1, stats))) return status;
        step->fsal = 1;
    }
    if (!(step->h > 0) || !isfinite(step->h)) {
        status = initial_step(sys, step->t1, x1, f1, t_limit - step->t1, rtol, atol, max_step,
                              tb->order, m.tmp, m.err, m.scale, stats, &step->h);
        if (status) return status;
    }
    while (step->t1 < t_target) {
        double h_abs = step->h, t_new, h;
        memcpy(m.y, x1, size);
        memcpy(m.K, f1, size);
        status = one_step(tb, sys, step->t1, t_limit, &m, rtol, atol, max_step, max_steps,
                          attempts, &h_abs, &t_new, &h, stats);
        if (status) return status;
        if (!cp_all_finite(n, m.y_new)) return CP_NONFINITE;
        int crosses = t_new > t_target;  /* the target is answered from this step's interpolant */
        if (crosses) {
            if (method == CP_RK45) rk45_interpolant(n, &m, dense);
            else if ((status = dop853_interpolant(sys, step->t1, h, &m, dense, stats))) return status;
        }
        memcpy(x0, m.y, size);
        memcpy(x1, m.y_new, size);
        memcpy(f1, m.K + tb->stages * n, size);
        step->t0 = step->t1;
        step->t1 = t_new;
        step->h = h_abs;
        step->dense = crosses;
    }
    return CP_OK;
}

void cp_step_state(int method, const cp_step *step, const double *rows, int dim, double t,
                   double *x)
{
    const double *x0 = rows + CP_ROW_X0 * dim, *dense = rows + CP_ROW_DENSE * dim;
    if (t == step->t1) {
        memcpy(x, rows + CP_ROW_X1 * dim, dim * sizeof(double));
        return;
    }
    double h = step->t1 - step->t0, s = (t - step->t0) / h;
    for (int i = 0; i < dim; i++) {
        double y = 0.0;
        if (method == CP_RK45) {  /* RkDenseOutput._call_impl: x0 + h Q (s, s^2, s^3, s^4) */
            double power = s;
            for (int r = 0; r < 4; r++, power *= s) y += dense[r * dim + i] * power;
            x[i] = h * y + x0[i];
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
                  cp_stats *stats)
{
    int n = sys->dim, status;
    double *rows = work + CARVED_ROWS * n;  /* the step in flight after the solver's memory */
    cp_step step;
    long long attempts = 0;
    if (ntimes < 2) return CP_OK;
    cp_step_begin(&step, rows, n, times[0], out, 0.0);
    for (int k = 1; k < ntimes; k++) {
        status = cp_cover(method, sys, &step, rows, times[k], times[ntimes - 1], rtol, atol,
                          max_step, max_steps, &attempts, work, stats);
        if (status) return status;
        cp_step_state(method, &step, rows, n, times[k], out + k * n);
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
