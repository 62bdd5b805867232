#include "cosim.h"

#include <math.h>
#include <string.h>

#include "directional.h"
#include "dynamics.h"

#define INPUT0 (CP_NPARAM - CP_NINPUT)  /* the inputs end p (model.h) */

void cp_input_at(const double *p, const double (*rates)[2], double tau, double *p_at)
{
    memcpy(p_at, p, CP_NPARAM * sizeof(double));
    for (int k = 0; k < CP_NINPUT; k++) {
        const int i = INPUT0 + k;
        p_at[i] = p[i] + tau * (rates[k][0] + 0.5 * tau * rates[k][1]);
    }
#ifdef CP_NROPE
    for (int k = 0; k < CP_NROPE; k++) {  /* l'' = v_hoist' */
        const int i = cp_rope_hoist[k] - INPUT0;
        p_at[CP_NPARAM + k] = rates[i][0] + tau * rates[i][1];
    }
#endif
    /* the elastic ropes' law: the core's to fill from the state (cp_rope_law) */
    for (int k = CP_NPARAM + CP_NHOIST_ACC; k < CP_PSIZE; k++) p_at[k] = 0.0;
}

void cp_input_direction(const double (*rates)[2], int order, double *dp)
{
    memset(dp, 0, CP_PSIZE * sizeof(double));
    for (int k = 0; k < CP_NINPUT; k++) dp[INPUT0 + k] = rates[k][order - 1];
#ifdef CP_NROPE
    for (int k = 0; k < CP_NROPE && order == 1; k++)  /* (u' + u'' tau)' = u'' */
        dp[CP_NPARAM + k] = rates[cp_rope_hoist[k] - INPUT0][1];
#endif
}

/* The model's right-hand side with interpolated inputs: the inputs at the stage's time. */
typedef struct {
    cp_model model;               /* model.p is p_at (moving), else the held inputs' p */
    const double *p;              /* the parameters and the inputs at t0 */
    const double (*rates)[2];
    double t0;
    double p_at[CP_PSIZE];
    int moving;                   /* the inputs move (else held: model.p) */
    cp_jacobian_record *record;   /* where recorded_jac notes its Jacobians */
} interpolated;

int cp_held_rhs(void *ctx, double t, const double *x, double *dx)
{
    (void)t;
    return cp_rhs(ctx, x, dx);
}

/* The model with the inputs at t (ctx an interpolated). */
static cp_model *model_at(void *ctx, double t)
{
    interpolated *in = ctx;
    cp_input_at(in->p, in->rates, t - in->t0, in->p_at);
    return &in->model;
}

static int interpolated_rhs(void *ctx, double t, const double *x, double *dx)
{
    return cp_rhs(model_at(ctx, t), x, dx);
}

/* J = df/dx of the model at (x, its p), exact (directional.h's cp_jacobian); a singular mass
 * matrix is reported as cp_rhs reports it. */
static int model_jacobian(cp_model *model, const double *x, double *J)
{
    return cp_jacobian(x, model->p, J, &model->pivot_ratio, &model->bad_dof);
}

int cp_held_jac(void *ctx, double t, const double *x, double *J)
{
    (void)t;
    return model_jacobian(ctx, x, J);
}

/* The Jacobian of cp_cosim_advance's model (ctx its interpolated, or that one's model, its
 * first member), noted in its record with the state and the core's p it was evaluated at. */
static int recorded_jac(void *ctx, double t, const double *x, double *J)
{
    interpolated *in = ctx;
    cp_model *model = in->moving ? model_at(in, t) : &in->model;
    memcpy(in->record->x, x, sizeof in->record->x);
    memcpy(in->record->p, model->p, sizeof in->record->p);
    return model_jacobian(model, x, J);
}

/* The matrices made again for the record where they were made for another (cosim.h): J at
 * the recorded point, and its factors for the recorded step size; a Jacobian that cannot be
 * had there (a record from elsewhere) is forgotten, and the solver evaluates one where it
 * needs it. Not counted: the step that made them counted them. */
static void remake(cp_jacobian_record *record, cp_matrices *matrices)
{
    cp_newton *nw = &record->newton;
    if (nw->jac_valid) {
        cp_model model = {record->p, 1.0, -1};
        if (model_jacobian(&model, record->x, matrices->block) != CP_OK
            || !cp_all_finite(CP_NSTATE * CP_NSTATE, matrices->block))
            nw->jac_valid = nw->current_jac = nw->lu_valid = 0;
        else if (nw->lu_valid)
            cp_newton_refactor(CP_NSTATE, nw, matrices->block);
    }
    matrices->made_for = *record;
}

#ifdef CP_NELASTIC
/* The watch on the elastic ropes over one communication step (t_from, t_to] (solvers.h's
 * cp_watch): the model's p at any time, the flight whose steps it sees, and what it has seen
 * so far (rope_events' layout: CP_ROPE_EVENT_* rows of CP_NELASTIC). */
typedef struct {
    interpolated *in;
    int moving;
    cp_flight *flight;
    double t_from, t_to;
    double seen[CP_NROPE_EVENT];
} watcher;

#define SEEN(w, what, e) ((w)->seen[CP_ROPE_EVENT_##what * CP_NELASTIC + (e)])

/* The core's p at t, with the ropes' law at x. */
static void law_at(watcher *w, double t, const double *x, double *p)
{
    memcpy(p, w->moving ? model_at(w->in, t)->p : w->in->model.p, CP_PSIZE * sizeof(double));
    cp_rope_law(x, p);
}

/* Each rope's taut margin (cp_rope_law) from p, the law filled. */
static void taut_margins(const double *p, double *g)
{
    for (int e = 0; e < CP_NELASTIC; e++) g[e] = p[cp_elastic_law[e] + 2];
}

/* The events: the taut margins at (t, x). */
static int margins(void *ctx, double t, const double *x, double *g)
{
    double p[CP_PSIZE];
    law_at(ctx, t, x, p);
    taut_margins(p, g);
    return CP_OK;
}

/* ... of a held model (ctx a cp_model). */
static int held_margins(void *ctx, double t, const double *x, double *g)
{
    double p[CP_PSIZE];
    (void)t;
    memcpy(p, ((cp_model *)ctx)->p, sizeof p);
    cp_rope_law(x, p);
    taut_margins(p, g);
    return CP_OK;
}

/* Each rope's tension rate at (t, x), x' = f there. */
static void slopes(watcher *w, double t, const double *x, const double *f, double *rates)
{
    double p[CP_PSIZE];
    law_at(w, t, x, p);
    cp_rope_tension_rates(x, f, p, rates);
}

/* Whether a tension rising (or not known: 0) at a step's start and falling at its end peaks
 * inside it. */
static int may_peak(double start, double end)
{
    return start >= 0 && end < 0;
}

static int wants_dense(void *ctx, double t1, const double *x1, const double *f1)
{
    watcher *w = ctx;
    double rates[CP_NELASTIC];
    slopes(w, t1, x1, f1, rates);
    for (int e = 0; e < CP_NELASTIC; e++)
        if (may_peak(w->flight->ropes[e].slope, rates[e])) return 1;
    return 0;
}

/* Rope e's tension at t inside the step (its dense output). */
static double tension_at(watcher *w, const cp_step *step, const double *rows, double t, int e)
{
    double x[CP_NSTATE], p[CP_PSIZE];
    cp_step_state(step, rows, CP_NSTATE, t, x);
    law_at(w, t, x, p);
    return p[cp_elastic_law[e]];
}

/* Rope e's largest tension inside the step, by golden section on its dense output down to a
 * billionth of the step (the peak's value then exact to rounding: flat there). */
static void golden_peak(watcher *w, const cp_step *step, const double *rows, int e,
                        cp_rope_watch *rope)
{
    const double ratio = 0.5 * (sqrt(5.0) - 1.0), small = 1e-9 * (step->t1 - step->t0);
    double a = step->t0, b = step->t1, c = b - ratio * (b - a), d = a + ratio * (b - a);
    double fc = tension_at(w, step, rows, c, e), fd = tension_at(w, step, rows, d, e);
    while (b - a > small) {
        if (fc > fd) {
            b = d, d = c, fd = fc;
            c = b - ratio * (b - a);
            fc = tension_at(w, step, rows, c, e);
        } else {
            a = c, c = d, fc = fd;
            d = a + ratio * (b - a);
            fd = tension_at(w, step, rows, d, e);
        }
    }
    rope->peak_time = fc > fd ? c : d;
    rope->peak = fmax(fc, fd);
}

/* What a step shows inside (t_from, t_to]: the tension at its end and its peak inside it,
 * where they fall there, and a snap at its end (its start slack, its end taut). */
static void see(watcher *w, const cp_step *step, const double *rows)
{
    if (!(step->t1 > step->t0)) return;
    double g0[CP_NELASTIC], p[CP_PSIZE];
    margins(w, step->t0, rows + CP_ROW_X0 * CP_NSTATE, g0);
    law_at(w, step->t1, rows + CP_ROW_X1 * CP_NSTATE, p);
    const int end_inside = step->t1 > w->t_from && step->t1 <= w->t_to;
    for (int e = 0; e < CP_NELASTIC; e++) {
        const cp_rope_watch *rope = &w->flight->ropes[e];
        if (end_inside) {
            SEEN(w, T_ROPE_PEAK, e) = fmax(SEEN(w, T_ROPE_PEAK, e), p[cp_elastic_law[e]]);
            SEEN(w, SNAPS, e) += g0[e] <= 0 && p[cp_elastic_law[e] + 2] > 0;
        }
        if (rope->peak > 0 && rope->peak_time > w->t_from && rope->peak_time <= w->t_to)
            SEEN(w, T_ROPE_PEAK, e) = fmax(SEEN(w, T_ROPE_PEAK, e), rope->peak);
    }
}

static void accepted(void *ctx, const cp_step *step, const double *rows)
{
    watcher *w = ctx;
    double rates[CP_NELASTIC];
    slopes(w, step->t1, rows + CP_ROW_X1 * CP_NSTATE, rows + CP_ROW_F1 * CP_NSTATE, rates);
    for (int e = 0; e < CP_NELASTIC; e++) {
        cp_rope_watch *rope = &w->flight->ropes[e];
        const int peaks = step->dense && may_peak(rope->slope, rates[e]);
        rope->peak = 0.0;
        rope->peak_time = step->t0;
        if (peaks) golden_peak(w, step, rows, e, rope);
        rope->slope = rates[e];
    }
    see(w, step, rows);
}
#endif

const cp_watch *cp_held_watch(void *model, cp_watch *watch)
{
#ifdef CP_NELASTIC
    *watch = (cp_watch){CP_NELASTIC, held_margins, NULL, NULL, model};
    return watch;
#else
    (void)model, (void)watch;
    return NULL;
#endif
}

/* The polynomials' start: p with the inputs where the flight's integration started, and
 * their rates there; p0 the core's p there (cp_input_at). Whether any input moves. */
static int polynomials(const cp_flight *f, const double *p, double *p0, double (*rates)[2])
{
    int moving = 0;
    double start[CP_NPARAM];
    memcpy(start, p, sizeof start);
    for (int k = 0; k < CP_NINPUT; k++) {
        start[INPUT0 + k] = f->inputs[k][0];
        rates[k][0] = f->inputs[k][1];
        rates[k][1] = f->inputs[k][2];
        moving |= rates[k][0] != 0.0 || rates[k][1] != 0.0;
    }
    cp_input_at(start, (const double(*)[2])rates, 0.0, p0);
    return moving;
}

/* The core's p at t on the flight's polynomials (p: the parameters). */
static void core_p_at(const cp_flight *f, double t, const double *p, double *p_at)
{
    double p0[CP_PSIZE], rates0[CP_NINPUT + 1][2];
    polynomials(f, p, p0, rates0);
    cp_input_at(p0, (const double(*)[2])rates0, t - f->t_inputs, p_at);
}

void cp_flight_inputs(const cp_flight *f, double t, double *p, double (*rates)[2])
{
    double p0[CP_PSIZE], p_at[CP_PSIZE], rates0[CP_NINPUT + 1][2];
    const double tau = t - f->t_inputs;
    polynomials(f, p, p0, rates0);
    cp_input_at(p0, (const double(*)[2])rates0, tau, p_at);
    for (int k = 0; k < CP_NINPUT; k++) {
        p[INPUT0 + k] = p_at[INPUT0 + k];
        rates[k][0] = rates0[k][0] + tau * rates0[k][1];
        rates[k][1] = rates0[k][1];
    }
}

int cp_same_point(double t, double point)
{
    const double larger = fmax(fabs(t), fabs(point));
    return fabs(t - point) <= CP_SAME_POINT_ULPS * (nextafter(larger, INFINITY) - larger);
}

/* Whether the step in flight may go on from t: live, at the point it left (cp_same_point;
 * else RESTART), with the inputs and their rates bit for bit those its polynomials give there
 * (else NEW_INPUTS). */
enum { CONTINUE, RESTART, NEW_INPUTS };

static int continues(const cp_flight *f, const cp_settings *s, const double *p,
                     const double (*rates)[2], double t)
{
    if (!f->live || s->method == CP_RK4 || !cp_same_point(t, f->t_point)) return RESTART;
    double p_at[CP_NPARAM], rates_at[CP_NINPUT + 1][2];
    memcpy(p_at, p, CP_NPARAM * sizeof(double));
    cp_flight_inputs(f, f->t_point, p_at, rates_at);
    return memcmp(p_at + INPUT0, p + INPUT0, CP_NINPUT * sizeof(double)) == 0
                   && memcmp(rates_at, rates, CP_NINPUT * sizeof rates_at[0]) == 0
               ? CONTINUE
               : NEW_INPUTS;
}

/* A new integration from (t, x), the inputs' polynomials starting there, the proposed step
 * size kept, and, where the flight was live (new inputs), the automatic choice's method and
 * its counts: new inputs do not make a scene more or less stiff. The Jacobian is kept, no
 * longer current. */
static void restart(cp_flight *f, cp_newton *newton, const double *p, const double (*rates)[2],
                    double t, const double *x)
{
    const cp_step was = f->step;
    cp_step_begin(&f->step, &f->rows[0][0], CP_NSTATE, t, x, was.h);
    if (f->live) {
        f->step.next = was.next;
        f->step.stiff_steps = was.stiff_steps;
        f->step.calm_steps = was.calm_steps;
    }
    newton->current_jac = 0;
    for (int e = 0; e < CP_NWATCHED; e++) f->ropes[e] = (cp_rope_watch){0.0, t, 0.0};
    f->live = 1;
    f->reserved = 0;
    f->t_point = f->t_inputs = t;
    for (int k = 0; k < CP_NINPUT; k++) {
        f->inputs[k][0] = p[INPUT0 + k];
        f->inputs[k][1] = rates[k][0];
        f->inputs[k][2] = rates[k][1];
    }
}

int cp_ropes_hold(const double *x, const double *y, double t, cp_failure *failure)
{
#ifdef CP_NROPE
    for (int k = 0; k < CP_NROPE; k++) {
        const double length = x[cp_rope_state[k]], tension = y[CP_TENSION_OUTPUT + k];
        const int range = !(length >= cp_rope_min[k] && length <= cp_rope_max[k]);
        if (range || tension < 0.0) {
            failure->rope = cp_rope_link[k];
            failure->at = t;
            failure->value = range ? length : tension;
            failure->low = cp_rope_min[k];
            failure->high = cp_rope_max[k];
            return range ? CP_ROPE_RANGE : CP_ROPE_SLACK;
        }
    }
#else
    (void)x, (void)y, (void)t, (void)failure;
#endif
    return CP_OK;
}

/* The integration of trial from the point t to t + dt: x_new at the time *t_reached it got to
 * (t + dt on success; on failure with early return, the last accepted step or substep). With
 * on_point (or without across_points) it ends on t + dt. */
static int integrate(const cp_settings *s, cp_flight *trial, cp_newton *newton, double *matrices,
                     const cp_system *system, const double *x, double t, double dt,
                     double t_stop, int on_point, double *work, cp_stats *counts, double *x_new,
                     double *t_reached, int early)
{
    int status = cp_unworkable(s->method, t, dt, s->max_step, s->max_steps);
    *t_reached = t;
    if (status) return status;
    if (s->method == CP_RK4) {
        memcpy(x_new, x, CP_NSTATE * sizeof(double));
        status = cp_rk4(system, t, x_new, dt, s->max_step, s->max_steps, work, counts,
                        early ? t_reached : NULL);
        if (status == CP_OK) *t_reached = t + dt;
        return status;
    }
    const double t_target = t + dt;
    const double t_limit = s->across_points && !on_point ? fmax(t_stop, t_target) : t_target;
    long long attempts = 0;
    status = cp_cover(s->method, system, &trial->step, &trial->rows[0][0], newton, matrices,
                      t_target, t_limit, s->rtol, s->atol, s->max_step, s->max_steps, &attempts,
                      work, counts);
    if (status == CP_OK) {
        cp_step_state(&trial->step, &trial->rows[0][0], CP_NSTATE, t_target, x_new);
        *t_reached = t_target;
        return cp_all_finite(CP_NSTATE, x_new) ? CP_OK : CP_NONFINITE;
    }
    if (early && trial->step.t1 > t) {  /* the last accepted step, where x' was computed */
        memcpy(x_new, trial->rows[CP_ROW_X1], CP_NSTATE * sizeof(double));
        *t_reached = trial->step.t1;
    }
    return status;
}

int cp_cosim_advance(const cp_settings *s, const double *p, const double (*input_rates)[2],
                     double *x, double *y, double t, double dt, double t_stop, cp_flight *flight,
                     cp_jacobian_record *jacobian, cp_matrices *matrices, double *work,
                     double stats[CP_NSTAT], double *rope_events, cp_failure *failure,
                     double *reached)
{
    if (memcmp(&matrices->made_for, jacobian, sizeof *jacobian)) remake(jacobian, matrices);
    cp_flight trial = *flight;  /* taken only where the step gets somewhere */
    const int why = continues(&trial, s, p, input_rates, t);
    if (why != CONTINUE) restart(&trial, &jacobian->newton, p, input_rates, t, x);
    double p0[CP_PSIZE], rates0[CP_NINPUT + 1][2];
    const int moving = polynomials(&trial, p, p0, rates0);
    interpolated in = {{p0, 1.0, -1}, p0, (const double(*)[2])rates0, trial.t_inputs, {0},
                       moving, jacobian};
    if (moving) in.model.p = in.p_at;
    cp_system system = {CP_NSTATE, moving ? interpolated_rhs : cp_held_rhs,
                        moving ? (void *)&in : (void *)&in.model, recorded_jac, NULL};
#ifdef CP_NELASTIC
    watcher w = {&in, moving, &trial, t, t + dt, {0}};
    const cp_watch watch = {CP_NELASTIC, margins, wants_dense, accepted, &w};
    double start[CP_PSIZE];
    law_at(&w, t, x, start);
    for (int e = 0; e < CP_NELASTIC; e++) {
        SEEN(&w, T_ROPE_PEAK, e) = start[cp_elastic_law[e]];
        SEEN(&w, SNAPS, e) = rope_events ? rope_events[CP_ROPE_EVENT_SNAPS * CP_NELASTIC + e] : 0;
    }
    see(&w, &trial.step, &trial.rows[0][0]);  /* the step in flight's part after t */
    system.watch = &watch;
#endif
    cp_stats counts = {0, 0, 0, 0, 0, 0};
    double *x_new = work + CP_WORK_SIZE(CP_NSTATE), *y_new = x_new + CP_NSTATE;
    double t_reached = t, p_at[CP_PSIZE];
    cp_failure rope_failure = {0};
    int status = CP_BAD_STEP;
    if (dt >= 0 && dt < INFINITY)
        status = integrate(s, &trial, &jacobian->newton, matrices->block, &system, x, t, dt,
                           t_stop, why == NEW_INPUTS, work, &counts, x_new, &t_reached,
                           reached != NULL);
    matrices->made_for = *jacobian;
    stats[CP_STAT_N_RHS] += (double)counts.nfev;
    stats[CP_STAT_N_STEPS] += (double)counts.naccept;
    stats[CP_STAT_N_REJECTED] += (double)counts.nreject;
    stats[CP_STAT_N_JACOBIANS] += (double)counts.njev;
    stats[CP_STAT_N_FACTORIZATIONS] += (double)counts.nlu;
    if (t_reached > t || status == CP_OK) {  /* the outputs where the state got to */
        core_p_at(&trial, t_reached, p, p_at);
        cp_model model_at = {p_at, 1.0, -1};
        if (CP_NOUTPUT) cp_eval_outputs(x_new, p_at, y_new);
        int rope_status = cp_ropes_hold(x_new, y_new, t_reached, &rope_failure);
        if (rope_status) {  /* the ropes cannot be where the step got to: the state stays at t */
            status = rope_status;
            t_reached = t;
        } else if (cp_all_finite(CP_NOUTPUT, y_new)) {
            memcpy(x, x_new, CP_NSTATE * sizeof(double));
            memcpy(y, y_new, CP_NOUTPUT * sizeof(double));
#ifdef CP_NELASTIC
            for (int e = 0; e < CP_NELASTIC; e++) {  /* where the state got to */
                const double tension = y_new[CP_TENSION_OUTPUT + cp_elastic_rope[e]];
                const int taut = y_new[CP_MARGIN_OUTPUT + e] > 0;
                SEEN(&w, T_ROPE_PEAK, e) = fmax(SEEN(&w, T_ROPE_PEAK, e), tension);
                /* RK4 steps over the events: a snap between its points */
                SEEN(&w, SNAPS, e) += s->method == CP_RK4 && start[cp_elastic_law[e] + 2] <= 0 && taut;
                SEEN(&w, TAUT, e) = taut;
            }
            if (rope_events) memcpy(rope_events, w.seen, sizeof w.seen);
#else
            (void)rope_events;
#endif
            trial.t_point = t_reached;
            /* an early return restarts where it stopped; RK4 at every point */
            trial.live &= status == CP_OK && s->method != CP_RK4;
            *flight = trial;
        } else {  /* the pivot force where M is singular: cp_rhs says where */
            int found = cp_rhs(&model_at, x_new, work);
            if (status == CP_OK) status = found == CP_OK ? CP_NONFINITE : found;
            in.model.bad_dof = model_at.bad_dof;
            in.model.pivot_ratio = model_at.pivot_ratio;
            t_reached = t;
        }
    }
    if (reached) *reached = t_reached;
    if (status != CP_OK) {
        cp_failure f = rope_failure;
        f.t = t, f.dt = dt, f.bad_dof = in.model.bad_dof, f.pivot_ratio = in.model.pivot_ratio;
        f.rtol = s->rtol, f.atol = s->atol, f.max_step = s->max_step, f.max_steps = s->max_steps;
        f.kept = t_reached;
        f.method = trial.step.method;  /* the stiffness of the last step (CP_STIFF) */
        f.stiffness = trial.step.t1 > trial.step.t0
                          ? trial.step.stiffness / (trial.step.t1 - trial.step.t0)
                          : 0.0;
        *failure = f;
    }
    return status;
}

int cp_cosim_step(const cp_settings *s, const double *p, double *x, double *y, double t,
                  double dt, double *h, double *work, int *fsal, cp_jacobian_record *jacobian,
                  cp_matrices *matrices, double stats[CP_NSTAT], cp_failure *failure)
{
    static const double held[CP_NINPUT + 1][2];
    cp_settings on_points = *s;
    cp_flight flight;
    memset(&flight, 0, sizeof flight);
    on_points.across_points = 0;
    restart(&flight, &jacobian->newton, p, held, t, x);
    flight.step.h = *h;
    if (*fsal) {  /* work starts with x' at x */
        memcpy(flight.rows[CP_ROW_F1], work, CP_NSTATE * sizeof(double));
        flight.step.fsal = 1;
    }
    int status = cp_cosim_advance(&on_points, p, held, x, y, t, dt, INFINITY, &flight, jacobian,
                                  matrices, work, stats, NULL, failure, NULL);
    *h = flight.step.h;
    *fsal = s->method != CP_RK4 && flight.step.fsal;
    if (*fsal) memcpy(work, flight.rows[CP_ROW_F1], CP_NSTATE * sizeof(double));
    return status;
}
