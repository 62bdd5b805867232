/* One co-simulation step of the model, for every FMU of the package (the pythonfmu slave's
 * core and the native glue): the settings as the solvers take them, the integration, the
 * outputs, the statistics and, on failure, what the diagnosis needs. A state or an output
 * that is not finite is never reported as success. */
#ifndef CP_COSIM_H
#define CP_COSIM_H

#include "diagnosis.h"
#include "dynamics.h"
#include "model.h"
#include "solvers.h"

typedef struct {
    int method;           /* CP_RK4, CP_RK45, CP_DOP853, CP_RADAU or CP_AUTO (solvers.h) */
    double rtol, atol, max_step;
    long long max_steps;
    int across_points;    /* all but RK4 step across the communication points (cp_flight) */
} cp_settings;

/* A communication point within this many units in the last place of the point the step in
 * flight left is that point: a master that computes its points as k h, or restores a state
 * saved at t + h, continues the integration rather than restarting it. */
#define CP_SAME_POINT_ULPS 4

/* Whether t is the point (cp_same_point's rule, CP_SAME_POINT_ULPS). */
int cp_same_point(double t, double point);

/* The implicit solver's Jacobian and factors, kept beside the flight in two parts. The record,
 * which an FMU state holds (O(n) doubles): solvers.h's cp_newton (its flags, and the step size
 * of the factors) and where the Jacobian was evaluated, the state and the core's p. The
 * matrices (solvers.h's block, 4n^2 + 4n doubles), which it does not: an instance's own, with
 * the record they were made for; where that is not the record a step starts with (a state
 * restored), they are made again from it, bit for bit as they were (cp_cosim_advance). Any
 * Jacobian serves the Newton iteration (it evaluates a new one where the kept one fails), so a
 * failed step that leaves them changed loses nothing. */
typedef struct {
    cp_newton newton;
    double x[CP_NSTATE];  /* the state J was evaluated at (newton.jac_valid) */
    double p[CP_PSIZE];   /* ... with this core p (dynamics.h) */
} cp_jacobian_record;

typedef struct {
    cp_jacobian_record made_for;  /* the record the block holds the matrices of */
    double block[CP_NEWTON_SIZE(CP_NSTATE)];
} cp_matrices;

/* Doubles of work a step needs: the solvers', then the state at t and the new outputs. */
#define CP_STEP_WORK_SIZE (CP_WORK_SIZE(CP_NSTATE) + CP_NSTATE + CP_NOUTPUT)

/* What the integration sees of the elastic ropes besides the state (the scene's ROPE_EVENTS:
 * each one's largest tension since the last point, its snaps, whether it is taut; codegen's
 * CP_ROPE_EVENT_* say where), and what it keeps of each between steps (cp_flight's ropes). */
#ifdef CP_NELASTIC
#define CP_NWATCHED CP_NELASTIC
#else
#define CP_NWATCHED 0
#define CP_NROPE_EVENT 0
#endif

/* An elastic rope as the watch left it (cosim.c): its tension's rate at the end of the step
 * in flight, and the largest tension inside that step, when and what (0: none found). */
typedef struct {
    double slope, peak_time, peak;
} cp_rope_watch;

/* The integration a co-simulation carries from one communication point to the next: plain
 * data, which an FMU state copies and serializes byte for byte. With across_points, the
 * adaptive solvers take their own steps whatever the points: a point inside the step in flight is
 * answered from the step's dense output, and the next communication step continues from the
 * step's end, never from the interpolated state. Without it, each communication step ends
 * its integration on the point (the step in flight ends there), and the next continues from
 * there with the step size and x' it carried. The integration restarts (from the caller's x,
 * at the point, keeping the proposed step size) when what it assumed no longer holds: the
 * inputs at the point, or their derivatives, are not bit for bit those of the polynomials it
 * integrated with (cp_flight_inputs), the point is another (cp_same_point), or the caller dropped it (live
 * 0: a parameter, state or setting set, an early return). A restart for new inputs ends its
 * first integration on the next point, so that inputs set anew at every point (a coupled
 * co-simulation) cost what ending every integration on the point costs, with no interpolant
 * to pay for. RK4 restarts at every point. */
typedef struct {
    int live;           /* 1: the next step may continue the integration */
    int reserved;       /* 0 (the padding, named so that a state's bytes are all defined) */
    double t_point;     /* the communication point the caller's x and outputs are at */
    cp_step step;       /* the solver's last accepted step (solvers.h) */
    double rows[CP_FLIGHT_ROWS][CP_NSTATE];
    double t_inputs;    /* where the inputs' polynomials start: the integration's start */
    double inputs[CP_NINPUT + 1][3];  /* each input there: u, u', u'' (+1: C has no empty array) */
    cp_rope_watch ropes[CP_NWATCHED + 1];  /* each elastic rope's, at the step in flight */
} cp_flight;

/* Advance the co-simulation from the communication point t (x, y: the state and outputs there)
 * to t + dt, continuing the step in flight when nothing it assumed changed (cp_flight), else
 * restarting at t from x; p holds the parameters and the inputs at t, input_rates (CP_NINPUT
 * rows, not NULL) their first and second time derivatives at t: over the integration every
 * input follows its Taylor polynomial, evaluated at each stage's time. No step ends after
 * t_stop (the experiment's stop time, INFINITY: none), unless the point is beyond it. x and y
 * become the state and outputs at t + dt (the outputs with the inputs there: cp_flight_inputs);
 * stats (right-hand sides, accepted and rejected steps, at model.h's CP_STAT_*) grow by what
 * the step cost, failed or not. Returns CP_OK, or a status with *failure filled for
 * cp_diagnose: then, with reached NULL, x, y and the flight are as they were; with reached
 * not NULL (early return), x and y are at the last point the solver reached where x' was
 * computed (RK45 and DOP853: the last accepted step; RK4: the last completed substep) and the
 * outputs there are finite, or as they were at t, and the flight restarts there. *reached
 * (when not NULL) is the time of x on return: t + dt on success; failure->kept says it too.
 * The elastic ropes' slack and snap events are located inside the step (solvers.h's
 * cp_watch; the adaptive solvers); rope_events (CP_NROPE_EVENT values, or NULL) become what
 * the integration saw of each rope up to where x got: its largest tension since t (at t, at
 * every step's end, and inside the steps where its rate changes sign, by golden section on
 * their dense output), its snaps (slack to taut) counted on, whether it is taut there.
 * work: CP_STEP_WORK_SIZE doubles of scratch. */
int cp_cosim_advance(const cp_settings *settings, const double *p, const double (*input_rates)[2],
                     double *x, double *y, double t, double dt, double t_stop, cp_flight *flight,
                     cp_jacobian_record *jacobian, cp_matrices *matrices, double *work,
                     double stats[CP_NSTAT],
                     double *rope_events, cp_failure *failure, double *reached);

/* The inputs as the flight's integration has them at t: their values into p's input entries
 * (p: CP_NPARAM values, the parameters untouched) and their first and second derivatives into
 * rates (CP_NINPUT rows), as cp_input_at evaluates the polynomials. */
void cp_flight_inputs(const cp_flight *flight, double t, double *p, double (*rates)[2]);

/* cp_cosim_advance of one communication step that ends its integration on the point (the old
 * behaviour, which the Stepper of core.pyx keeps): inputs held as p has them, *h and *fsal the
 * solver's memory between steps (the proposed step size; whether work starts with x' at x),
 * no stop time, no early return. */
int cp_cosim_step(const cp_settings *settings, const double *p, double *x, double *y, double t,
                  double dt, double *h, double *work, int *fsal, cp_jacobian_record *jacobian,
                  cp_matrices *matrices, double stats[CP_NSTAT], cp_failure *failure);

/* Whether the ropes (if any) hold at time t in the state x with outputs y: each length in its
 * range (else CP_ROPE_RANGE), each tension not negative (else CP_ROPE_SLACK: a rope cannot
 * push), with *failure's rope fields filled (cp_rope_hint says what is wrong); CP_OK. A NaN
 * tension (a singular mass matrix) is left to the check of the outputs. Every step's end is
 * checked (cp_cosim_advance), and Model Exchange's derivatives. */
int cp_ropes_hold(const double *x, const double *y, double t, cp_failure *failure);

/* cp_rhs as a solver's system's right-hand side (ctx a cp_model): the inputs held as its p
 * has them, whatever t. */
int cp_held_rhs(void *ctx, double t, const double *x, double *dx);

/* Its exact Jacobian (cp_jac_fn): directional.h's cp_jacobian. */
int cp_held_jac(void *ctx, double t, const double *x, double *J);

/* Its elastic ropes' switches as the watch of an integration of it (model a cp_model; solvers.h's
 * cp_watch: their taut margins as events, nothing else watched), filled into watch; NULL
 * where the scene has no elastic rope. The core's own integrations (core.pyx's
 * integrate_grid) locate the switches as the FMUs' steps do. */
const cp_watch *cp_held_watch(void *model, cp_watch *watch);

/* The inputs of p (CP_NPARAM values, the inputs last) tau after the point where they are p's,
 * each on its Taylor polynomial u + u' tau + u'' tau^2 / 2 (rates[k] = {u', u''}), into p_at,
 * the core's p (dynamics.h: CP_PSIZE values, the parameters copied, each rope's l'' the rate
 * of its v_hoist there, u' + u'' tau). */
void cp_input_at(const double *p, const double (*rates)[2], double tau, double *p_at);

/* cp_input_at's derivative of order 1 or 2 in tau at tau = 0 (CP_PSIZE values, the parameters'
 * entries 0): the direction the inputs move the core's p in, for the output derivatives. */
void cp_input_direction(const double (*rates)[2], int order, double *dp);

#endif
