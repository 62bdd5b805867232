/* Generic ODE solvers over one communication step, explicit (RK4, RK45, DOP853) and implicit
 * (Radau IIA, radau.c), and the automatic choice between DOP853 and Radau: no model knowledge,
 * no Python. */
#ifndef CP_SOLVERS_H
#define CP_SOLVERS_H

#include <math.h>

#include "status.h"

/* x' = f(t, x): the solvers pass every stage's time, so an input that moves within a step
 * (cosim.c's interpolated inputs) is evaluated where the stage is. */
typedef int (*cp_rhs_fn)(void *ctx, double t, const double *x, double *dx);

/* J = df/dx at (t, x), row-major (J[i * dim + j] = df_i / dx_j); returns as the right-hand
 * side does. The implicit solver's only use of it. */
typedef int (*cp_jac_fn)(void *ctx, double t, const double *x, double *J);

typedef struct cp_step cp_step;

/* What a caller watches along an integration (cp_system's watch; NULL: nothing): plain
 * callbacks on its own ctx.
 * - Events: n_events functions g(t, x) (events writes them into g), each a switch of the
 *   right-hand side where its sign changes (> 0 against <= 0). A step whose ends differ in a
 *   sign is taken again to end on the earliest root, located on the step's dense output by
 *   bisection to the first time the function has its new sign (the step's end within a few
 *   units in the last place of the root): no step straddles a switch, so the error control
 *   and the interpolants see a smooth right-hand side, and the next step starts on the
 *   switch's far side. Two roots inside one step (a sign that changes and changes back) go
 *   unseen, as in every event finder. RK4 steps over them.
 * - wants_dense: whether an accepted step ending at (t1, x1), with x' = f1 there, needs its
 *   dense output for what the caller looks for inside it (may be NULL).
 * - accepted: called once per step taken, in order, the step final (its interpolant in rows
 *   where step->dense). */
typedef struct {
    int n_events;  /* at most the system's dim */
    int (*events)(void *ctx, double t, const double *x, double *g);
    int (*wants_dense)(void *ctx, double t1, const double *x1, const double *f1);
    void (*accepted)(void *ctx, const cp_step *step, const double *rows);
    void *ctx;
} cp_watch;

typedef struct {
    int dim;
    cp_rhs_fn rhs;   /* returns CP_OK, or a status >= 10 that stops the integration; a trial
                        stage's CP_NONFINITE rejects the step instead (the step shrinks) */
    void *ctx;
    cp_jac_fn jac;   /* for CP_RADAU and CP_AUTO */
    const cp_watch *watch;  /* NULL: nothing watched */
} cp_system;

/* Counts of one call; 64 bits everywhere (long is 32 bits on Windows). */
typedef struct {
    long long nfev, naccept, nreject, njev, nlu;
    long long nswitch;  /* CP_AUTO's switches between DOP853 and Radau */
} cp_stats;

/* The methods, in the order of the FMUs' `solver` (runtime/rules.py's SOLVERS). CP_AUTO starts
 * with DOP853 and counts its steps as Hairer's stiffness test does (looks_stiff: CP_STIFF_STEPS
 * accepted steps past a bound, never CP_CALM_RESET in a row below it between), but on the
 * dominant mode's decay -h Re(lambda) (a fast oscillation, which Radau would damp, is no
 * stiffness) past CP_AUTO_BOUND, a quarter of DOP853's stability bound: DOP853's interpolant,
 * which no error test controls, is off by 20 tolerances on a decay at h |lambda| = 2.3
 * already (measured on the damped light chain at c = 1, rtol 1e-6, where the steps' ends are
 * within the tolerance). It switches to Radau there, and back when Radau's steps stay below
 * CP_CALM_BOUND (h rho(J), on CP_CALM_STEPS accepted steps in a row). Back with DOP853, its
 * steps are capped at CP_AUTO_BOUND / rho(J), and a step held at the cap while accuracy asks
 * for more counts as stiff too: DOP853's own error estimate underestimates near its
 * stability bound (the 20-link light chain at c = 1 erred 2.7e-5 at rtol 1e-6 without the
 * cap, 4.6e-7 with it). Until
 * it switches, a DOP853 step past CP_AUTO_BOUND that would answer a point from its
 * interpolant is taken again to end on the point. */
enum { CP_RK4 = 0, CP_RK45 = 1, CP_DOP853 = 2, CP_RADAU = 3, CP_AUTO = 4, CP_BDF = 5 };
#define CP_STIFF_BOUND 6.1  /* Hairer's dop853: its stability region ends near 6 */
#define CP_AUTO_BOUND 1.5   /* a quarter of that */
#define CP_CALM_BOUND 0.75  /* half again: Radau hands back only what DOP853 takes with room */
#define CP_CALM_STEPS 50    /* ... over this many steps in a row: a scene calm for a while */
#define CP_STIFF_STEPS 15
#define CP_CALM_RESET 6

/* h |lambda| past which an explicit method's steps are bounded by stability (CP_RK45 or
 * CP_DOP853: the bound its stiffness test uses). */
double cp_stiffness_bound(int method);

/* The implicit solver's matrices, kept between steps and across communication points: flags
 * here (in an FMU's state), the numbers in a block of CP_NEWTON_SIZE(dim) doubles beside it (J,
 * the real and complex factors, their pivots as whole numbers and the structure they are on,
 * radau.c's; not in an FMU's state: cosim.h). */
typedef struct {
    int jac_valid;    /* the block's J is a Jacobian of the system */
    int current_jac;  /* ... evaluated at the start of the step in flight */
    int lu_valid;     /* the factors are J's, for the step size h of method */
    int method;       /* the method whose factors the block holds: CP_RADAU or CP_BDF (0: none) */
    double rho;       /* J's spectral radius, estimated when J was evaluated */
    double h;         /* the step size the factors are for (lu_valid) */
} cp_newton;
#define CP_NEWTON_SIZE(dim) (4 * (dim) * (dim) + 4 * (dim))

/* The factors of the block's J (dim n) for the step size nw->h made again, as the step that
 * made them made them (bit for bit), and nw->lu_valid set: a block restored from its J. */
void cp_newton_refactor(int n, cp_newton *nw, double *block);

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

/* Doubles of scratch memory the solvers need for a system of size dim: a step's own rows
 * (CP_CARVED_ROWS), cp_dense_grid's step in flight (CP_FLIGHT_ROWS), and with a watch the
 * step before the one taken (CP_FLIGHT_ROWS, to take it again) and two rows of event
 * functions. */
#define CP_WORK_SIZE(dim) (44 * (dim))

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

/* RK4, a fixed-step method: advance x from t to t + dt in even steps of at most max_step
 * (one step when max_step is 0), after checking cp_unworkable. A new x that is not finite
 * fails (CP_NONFINITE). On failure x is left as it was at t, unless reached is not NULL (early
 * return): then x is left at the last completed substep (where x' was computed), or at t if
 * there is none. *reached (when not NULL) is the time of x on return: t + dt on success. */
int cp_rk4(const cp_system *sys, double t, double *x, double dt, double max_step,
           long long max_steps, double *work, cp_stats *stats, double *reached);

/* The last accepted step of RK45 or DOP853, the step in flight: what lets one integration run
 * across the times a caller asks for (cp_cover) and answer each from the step that holds it,
 * by its dense output, while the integration itself continues from the step's end only. Plain
 * data; its vectors are CP_FLIGHT_ROWS rows of dim doubles the caller keeps beside it. */
struct cp_step {
    double t0, t1;  /* the step's start and end (equal: no step yet, the integration starts at t1) */
    double h;       /* the step size proposed after it (<= 0: chosen as scipy does) */
    int fsal;       /* the CP_ROW_F1 row holds x' at t1 */
    int dense;      /* the CP_ROW_DENSE rows hold the step's interpolant (needed inside it only;
                       Radau keeps it always: the next step's Newton starts from it) */
    int method;     /* the method that made the step, whose interpolant the rows hold */
    int next;       /* CP_AUTO: the method of the next step (CP_DOP853 or CP_RADAU) */
    int stiff_steps, calm_steps;  /* the stiffness test's counts (looks_stiff; Radau: calm steps) */
    double h_old, err_old;  /* Radau: the step size proposed before the last step and its
                               error norm (0: none); BDF: the step size its differences are
                               for, and the last step's error norm */
    double stiffness;  /* the last step's h |lambda| (explicit: Hairer's estimate; Radau: h rho(J)) */
    int order, equal_steps;  /* BDF: the formula's order, the steps since the size changed */
};

/* The rows: x at t0 and t1, x' at t1, then the interpolant's coefficients (DOP853's 7 rows of
 * F, RK45's 4 rows of Q, Radau's 3 rows of Q, BDF's differences D[1..7], as scipy's dense
 * outputs hold them). */
enum { CP_ROW_X0, CP_ROW_X1, CP_ROW_F1, CP_ROW_DENSE, CP_FLIGHT_ROWS = CP_ROW_DENSE + 7 };

/* An integration that starts at (t, x), with the step size h proposed (<= 0: to be chosen). */
void cp_step_begin(cp_step *step, double *rows, int dim, double t, const double *x, double h);

/* Steps of method (CP_RK45, CP_DOP853, CP_RADAU or CP_AUTO) from the end of the step in flight until it reaches
 * t_target, none ending after t_limit (>= t_target): the error controlled as scipy's solvers
 * control it (RMS norm of the error over atol + rtol * max(|x|, |x_new|), same safety factor
 * and limits). A last step that ends after t_target comes with its interpolant. Nothing to do
 * when the step in flight already reaches t_target. *attempts counts the steps attempted
 * (accepted or rejected) against max_steps (CP_TOO_MANY_STEPS). On failure the step in flight
 * is the last one accepted; on success it holds t_target (cp_step_state). */
int cp_cover(int method, const cp_system *sys, cp_step *step, double *rows, cp_newton *newton,
             double *matrices, double t_target, double t_limit, double rtol, double atol,
             double max_step, long long max_steps, long long *attempts, double *work,
             cp_stats *stats);

/* The state at t, step->t0 <= t <= step->t1, into x: the step's end at t1, else its dense
 * output (DOP853's 7th-order interpolant, the Dormand-Prince continuous extension of order 4
 * for RK45, Radau's collocation polynomial), which step->dense says the rows hold. */
void cp_step_state(const cp_step *step, const double *rows, int dim, double t, double *x);

/* method (CP_RK45, CP_DOP853, CP_RADAU or CP_AUTO) from times[0] (state in out[0..dim)) through times[ntimes - 1],
 * writing the state at every time into out (row-major, ntimes x dim) from the method's dense
 * output, as scipy's solve_ivp(method=..., t_eval=times) does: one integration, cp_cover to
 * each time. */
int cp_dense_grid(int method, const cp_system *sys, const double *times, int ntimes, double *out,
                  double rtol, double atol, double max_step, long long max_steps, double *work,
                  cp_newton *newton, double *matrices, cp_stats *stats);

#endif
