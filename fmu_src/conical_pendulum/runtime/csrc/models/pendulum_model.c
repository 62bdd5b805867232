/* The n-link conical pendulum behind the model contract (fmu_model.h): its instance data,
 * its variable table with the value rules of runtime/rules.py (fmu_config.h), its settings
 * and statistics, x' and the outputs (dynamics.h), their directional derivatives
 * (directional.h) and the co-simulation step every FMU of the package takes (cosim.h).
 * Nothing here knows FMI: an FMI layer calls these functions and says the messages. */
#include "fmu_model.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cosim.h"
#include "diagnosis.h"
#include "directional.h"
#include "dynamics.h"
#include "fmu_config.h"
#include "rules.h"
#include "solvers.h"

/* Everything an instance of the model holds: plain data, copied as a whole in FMU states. */
struct ModelData {
    double r[CP_NREAL];           /* Real variables by value reference (fmu_config.h) */
    int solver, max_steps, across_points;  /* the Integer settings */
    int rtol_set;                 /* rtol was set: the experiment's tolerance does not replace it */
    double tolerance;             /* the experiment's; replaces rtol's start value when > 0 */
    double stop_time;             /* the experiment's (INFINITY: none): no step goes beyond */
    cp_flight flight;             /* the integration carried across communication points */
    cp_jacobian_record jacobian;  /* the implicit solver's Jacobian, as a state keeps it */
    double dx[CP_NSTATE];         /* Model Exchange: x' at x when dx_valid */
    int dx_valid, outputs_valid;
    /* the inputs' first and second time derivatives as the master set them (0: held); the
     * inputs follow their Taylor polynomial over a step, and step along it (+1: C has no
     * empty array) */
    double input_rates[CP_NINPUT + 1][2];
    /* the first and second time derivatives of the states and outputs (from CP_VR_STATE)
     * at the current values: the outputs' to order rates_valid (0, 1 or 2), the states' to 2
     * once it is 1 */
    double rates[CP_NSTATE + CP_NOUTPUT][2];
    int rates_valid;
    int states_jumped;            /* a value set at an event jumped a book (model_states_jumped) */
    int hoist_warned;             /* a winch speed changed in continuous-time mode was warned of */
};

/* What an instance keeps beside its data and out of its FMU states (fmu_model.h's scratch):
 * the implicit solver's matrices, which a step makes again from the data's record where they
 * are not its (cosim.h), and a step's scratch. */
typedef struct {
    cp_matrices matrices;
    double work[CP_STEP_WORK_SIZE];
} Scratch;

#define SCRATCH(m) ((Scratch *)((m) + 1))

const ModelSizes model_sizes = {sizeof(ModelData), sizeof(Scratch), CP_NREAL,
                                CP_VR_DERIVATIVE - CP_NREAL, CP_NSTATE, CP_NWATCHED, CP_VR_STATE,
                                CP_VR_DERIVATIVE};

#define X(m) ((m)->r + CP_VR_STATE)
#define Y(m) ((m)->r + CP_VR_OUTPUT)
#define STATS(m) ((m)->r + CP_VR_STATISTICS)
#define ROPE_EVENTS(m) ((m)->r + CP_VR_ROPE_EVENTS)

static const char *const tolerance_name = "tolerance (from setupExperiment)";

static int is_derivative(unsigned vr)
{
    return vr >= CP_VR_DERIVATIVE && vr < CP_VR_DERIVATIVE + CP_NSTATE;
}

static int is_output(unsigned vr)  /* a calculated output, not a state or a statistic */
{
    return vr >= CP_VR_OUTPUT && vr < CP_VR_STATISTICS;
}

static int is_input(unsigned vr)
{
    return vr >= CP_VR_INPUT && vr < CP_VR_INPUT + CP_NINPUT;
}

static int is_integer(unsigned vr)
{
    return vr == CP_VR_SOLVER || vr == CP_VR_MAX_STEPS || vr == CP_VR_ACROSS_POINTS;
}

/* The Integer setting vr (is_integer) in m. */
static int *integer_setting(ModelData *m, unsigned vr)
{
    return vr == CP_VR_SOLVER ? &m->solver : vr == CP_VR_MAX_STEPS ? &m->max_steps : &m->across_points;
}

/* NULL if an Integer setting may take value, or the message refusing it. */
static const char *integer_refusal(unsigned vr, int value, char *message, size_t size)
{
    const int rule = vr == CP_VR_SOLVER      ? CP_SOLVER_RULE
                     : vr == CP_VR_MAX_STEPS ? CP_MAX_STEPS_RULE
                                             : CP_ACROSS_POINTS_RULE;
    return cp_integer_refusal(cp_variable_name(vr), value, &cp_rules[rule], "", message, size);
}

static const char *real_rule_refusal(unsigned vr, double value, char *message, size_t size)
{
    return cp_real_refusal(cp_variable_name(vr), value, &cp_rules[cp_real_rule[vr]],
                           cp_real_what[vr], message, size);
}

/* What was computed from the values is forgotten. */
static void forget_values(ModelData *m)
{
    m->dx_valid = 0;
    m->outputs_valid = 0;
    m->rates_valid = 0;
}

/* ... and the integration restarts. */
static void invalidate(ModelData *m)
{
    forget_values(m);
    m->flight.live = 0;
}

/* The core's p at the model's values (dynamics.h's cp_model): the parameters and inputs that
 * begin m->r, then each rope's l'', its v_hoist's first derivative as the master set it (0:
 * held; Model Exchange has none), as cp_input_at places it, into buffer; without ropes, m->r
 * itself. */
static const double *core_p(const ModelData *m, double buffer[CP_PSIZE])
{
#ifdef CP_NROPE
    cp_input_at(m->r, (const double(*)[2])m->input_rates, 0.0, buffer);
    return buffer;
#else
    (void)buffer;
    return m->r;
#endif
}

/* Whether the input vr is a rope's winch speed, whose derivative is its l''. */
static int is_hoist(unsigned vr)
{
#ifdef CP_NROPE
    for (int k = 0; k < CP_NROPE; k++)
        if ((int)vr == cp_rope_hoist[k]) return 1;
#else
    (void)vr;
#endif
    return 0;
}

static void update_outputs(ModelData *m)
{
    double p[CP_PSIZE];
    if (!m->outputs_valid && CP_NOUTPUT) cp_eval_outputs(X(m), core_p(m, p), Y(m));
    m->outputs_valid = 1;
}

/* MODEL_DISCARD with its message: x' cannot be had at the model's state (status from cp_rhs
 * or from its complex-step copy, with the weakest generalized speed and pivot ratio it found). */
static ModelStatus no_derivatives(double time, int status, int bad_dof, double pivot_ratio,
                                  char *message, size_t size)
{
    snprintf(message, size, "derivatives at t = %.9g s: %s at generalized speed %d (pivot ratio "
             "%.2g); check parameters and state", time, cp_status_message(status), bad_dof,
             pivot_ratio);
    return MODEL_DISCARD;
}

static ModelStatus derivatives(ModelData *m, double time, char *message, size_t size)
{
    if (m->dx_valid) return MODEL_OK;
    double p[CP_PSIZE];
    cp_model model = {core_p(m, p), 1.0, -1};
    int status = cp_rhs(&model, X(m), m->dx);
    if (status != CP_OK)
        return no_derivatives(time, status, model.bad_dof, model.pivot_ratio, message, size);
#ifdef CP_NROPE
    /* a rope out of its range or slack: no derivatives a host could integrate honestly */
    cp_failure failure;
    update_outputs(m);
    status = cp_ropes_hold(X(m), Y(m), time, &failure);
    if (status != CP_OK) {
        int used = snprintf(message, size, "derivatives at t = %.9g s: %s: ", time,
                            cp_status_message(status));
        if (used >= 0 && (size_t)used < size) cp_rope_hint(message + used, size - used, status, &failure);
        return MODEL_DISCARD;
    }
#endif
    m->dx_valid = 1;
    return MODEL_OK;
}

/* ---- start values, experiment, initialization ---- */

void model_reset(ModelData *m)
{
    memset(m, 0, sizeof *m + sizeof(Scratch));
    memcpy(m->r, cp_real_start, sizeof cp_real_start);
    m->solver = CP_SOLVER_START;
    m->max_steps = CP_MAX_STEPS_START;
    m->across_points = CP_ACROSS_POINTS_START;
    m->stop_time = INFINITY;
}

const char *model_tolerance_refusal(double tolerance, const char *name, char *message,
                                    size_t size)
{
    return cp_real_refusal(name ? name : tolerance_name, tolerance, &cp_rules[cp_real_rule[CP_VR_RTOL]],
                           cp_real_what[CP_VR_RTOL], message, size);
}

void model_set_tolerance(ModelData *m, double tolerance)
{
    m->tolerance = tolerance;
}

void model_set_stop_time(ModelData *m, double stop_time)
{
    m->stop_time = stop_time;
}

/* What the elastic ropes show at the model's state, at an event (initialization, Model
 * Exchange's event mode; Co-Simulation's steps see theirs inside, cosim.h): the tension
 * there as the largest since the last, whether taut, and, with count, a snap where a rope
 * slack at the last event is taut now. A host's root finder may stop exactly on a root (the
 * margin 0 to the last bit, fmpy's CVode at a snap): at an event, a margin of 0 is the
 * switch the host stopped for, so the rope takes its other mode there. */
static void see_ropes(ModelData *m, int count)
{
#ifdef CP_NELASTIC
    update_outputs(m);
    double *seen = ROPE_EVENTS(m);
    for (int e = 0; e < CP_NELASTIC; e++) {
        double *was_taut = &seen[CP_ROPE_EVENT_TAUT * CP_NELASTIC + e];
        const double margin = Y(m)[CP_MARGIN_OUTPUT + e];
        const int taut = margin > 0 || (count && margin == 0 && !*was_taut);
        seen[CP_ROPE_EVENT_SNAPS * CP_NELASTIC + e] += count && !*was_taut && taut;
        *was_taut = taut;
        seen[CP_ROPE_EVENT_T_ROPE_PEAK * CP_NELASTIC + e] = Y(m)[CP_TENSION_OUTPUT + cp_elastic_rope[e]];
    }
#else
    (void)m, (void)count;
#endif
}

void model_initialize(ModelData *m)
{
    if (m->tolerance > 0 && !m->rtol_set) m->r[CP_VR_RTOL] = m->tolerance;
    invalidate(m);
    see_ropes(m, 0);
}

void model_get_event_indicators(ModelData *m, double z[])
{
#ifdef CP_NELASTIC
    update_outputs(m);
    memcpy(z, Y(m) + CP_MARGIN_OUTPUT, CP_NELASTIC * sizeof z[0]);
#else
    (void)m, (void)z;
#endif
}

void model_event_update(ModelData *m)
{
    see_ropes(m, 1);
}

/* ---- the variable table ---- */

ModelStatus model_get_real(ModelData *m, unsigned vr, double *value, double time, char *message,
                           size_t size)
{
    if (vr < CP_NREAL) {
        if (is_output(vr)) update_outputs(m);
        *value = m->r[vr];
        return MODEL_OK;
    }
    if (!is_derivative(vr)) return MODEL_NO_VARIABLE;
    ModelStatus status = derivatives(m, time, message, size);
    if (status == MODEL_OK) *value = m->dx[vr - CP_VR_DERIVATIVE];
    return status;
}

ModelStatus model_check_real(const ModelData *m, unsigned vr, double value, int phase,
                             char *message, size_t size)
{
    if (vr >= CP_NREAL && !is_derivative(vr)) return MODEL_NO_VARIABLE;
    if (cp_not_settable(vr, phase, message, size) || real_rule_refusal(vr, value, message, size))
        return MODEL_REFUSED;
    if (phase == MODEL_CONTINUOUS_TIME && is_hoist(vr) && value != m->r[vr] && !m->hoist_warned) {
        snprintf(message, size, "%s = %g (was %g) set in continuous-time mode: a winch's speed "
                 "that varies between events is integrated with its rope's acceleration l'' "
                 "taken as 0 (Model Exchange gives no input derivatives), leaving out the force "
                 "that accelerates what hangs below; set it only at events (its jump is then "
                 "booked in W_hoist), or use Co-Simulation with its derivatives. Said once",
                 cp_variable_name(vr), value, m->r[vr]);
        return MODEL_WARNING;
    }
    return MODEL_OK;
}

#ifdef CP_ENERGY_JUMPS
/* The state of the book that a change of p[k] jumps (a rope's winch speed: W_hoist; a load's
 * mass: W_load), or -1. */
static int jump_book(unsigned k)
{
#ifdef CP_NROPE
    if (is_hoist(k)) return 2 * CP_NDOF + CP_WORK_HOIST;
#endif
#ifdef CP_NLOAD
    for (int j = 0; j < CP_NLOAD; j++)
        if ((int)k == cp_load_mass[j]) return 2 * CP_NDOF + CP_WORK_LOAD;
#endif
    return -1;
}

/* p[k] becomes value at the state x, which keeps its angles and angle rates: the speeds of
 * what a winch moves jump (its start or stop, along its rope), or a load's mass changes at
 * the velocities it had; the book takes the energy's change E(x, p new) - E(x, p) (the
 * impulse's work, the energy the load took away or brought), so that energy less the books
 * is as it was. */
static void book_jump(ModelData *m, unsigned k, double value)
{
    const int book = jump_book(k);
    if (book < 0) return;
    double buffer[CP_PSIZE], p[CP_PSIZE], before, after;
    memcpy(p, core_p(m, buffer), sizeof p);
    cp_rope_law(X(m), p);
    cp_energy(X(m), p, &before);
    p[k] = value;
    cp_rope_law(X(m), p);
    cp_energy(X(m), p, &after);
    X(m)[book] += after - before;
    m->states_jumped = 1;
}
#endif

void model_set_real(ModelData *m, unsigned vr, double value, int phase)
{
    if (m->r[vr] != value) {
        forget_values(m);
#ifdef CP_ENERGY_JUMPS
        if (phase == MODEL_AT_EVENT && vr < CP_NPARAM) book_jump(m, vr, value);
#endif
        if (phase == MODEL_CONTINUOUS_TIME && is_hoist(vr)) m->hoist_warned = 1;
    }
    /* an input: the step decides (cosim.h), an input of the same bits changing nothing (a
     * book it jumped is in the state the restart takes) */
    if (!is_input(vr)) m->flight.live = 0;
    if (vr == CP_VR_RTOL) m->rtol_set = 1;
    m->r[vr] = value;
}

int model_states_jumped(ModelData *m)
{
    const int jumped = m->states_jumped;
    m->states_jumped = 0;
    return jumped;
}

ModelStatus model_get_integer(const ModelData *m, unsigned vr, int *value)
{
    if (!is_integer(vr)) return MODEL_NO_VARIABLE;
    *value = *integer_setting((ModelData *)m, vr);
    return MODEL_OK;
}

ModelStatus model_check_integer(const ModelData *m, unsigned vr, int value, int initialized,
                                char *message, size_t size)
{
    (void)m;
    if (!is_integer(vr)) return MODEL_NO_VARIABLE;
    if (initialized) {  /* the settings are fixed */
        snprintf(message, size, CP_FIXED_MESSAGE, cp_variable_name(vr));
        return MODEL_REFUSED;
    }
    return integer_refusal(vr, value, message, size) ? MODEL_REFUSED : MODEL_OK;
}

void model_set_integer(ModelData *m, unsigned vr, int value)
{
    *integer_setting(m, vr) = value;
    m->flight.live = 0;
}

/* ---- Model Exchange ---- */

void model_get_states(const ModelData *m, double x[])
{
    memcpy(x, X(m), CP_NSTATE * sizeof x[0]);
}

const char *model_set_states(ModelData *m, const double x[], char *message, size_t size)
{
    for (int k = 0; k < CP_NSTATE; k++)
        if (!isfinite(x[k])) {
            snprintf(message, size, "%s = %g: must be finite", cp_variable_name(CP_VR_STATE + k),
                     x[k]);
            return message;
        }
    memcpy(X(m), x, CP_NSTATE * sizeof x[0]);
    invalidate(m);
    return NULL;
}

void model_get_nominals(const ModelData *m, double x_nominal[])
{
    (void)m;
    memcpy(x_nominal, cp_state_nominal, CP_NSTATE * sizeof x_nominal[0]);
}

ModelStatus model_get_derivatives(ModelData *m, double dx[], double time, char *message,
                                  size_t size)
{
    ModelStatus status = derivatives(m, time, message, size);
    if (status == MODEL_OK) memcpy(dx, m->dx, CP_NSTATE * sizeof dx[0]);
    return status;
}

/* ---- directional derivatives ---- */

/* From directional.c: the model's own C evaluated in complex arithmetic, exact to rounding,
 * along states, inputs and parameters alike. A state as unknown is an output of its own
 * value; the statistics depend on nothing (ModelStructure). */
/* The column of the unknowns along (dx_seed, dp_seed): the derivatives and the outputs where
 * wanted (cp_directional), or MODEL_DISCARD with the diagnosis. */
static ModelStatus column(ModelData *m, const double *dx_seed, const double *dp_seed,
                          double *d_derivatives, double *d_outputs, double time, char *message,
                          size_t size)
{
    if (!d_derivatives && !d_outputs) return MODEL_OK;
    double pivot_ratio, p[CP_PSIZE];
    int bad_dof;
    int status = cp_directional(X(m), core_p(m, p), dx_seed, dp_seed, d_derivatives, d_outputs,
                                &pivot_ratio, &bad_dof);
    return status == CP_OK ? MODEL_OK
                           : no_derivatives(time, status, bad_dof, pivot_ratio, message, size);
}

/* A known's seed into the direction (dx_seed, dp_seed): a parameter or an input is an entry
 * of p (the inputs end it, fmu_config.h), a state one of x; a solver setting (rtol, atol,
 * max_step) moves nothing, the derivatives and outputs at an instant not depending on it. */
static void add_seed(unsigned vr, double seed, double *dx_seed, double *dp_seed)
{
    if (vr < CP_VR_STATE) dp_seed[vr] += seed;
    else if (vr < CP_VR_STATE + CP_NSTATE) dx_seed[vr - CP_VR_STATE] += seed;
}

/* The unknown vr's entry of a column (a state's is its own seed; a statistic's 0). */
static double entry(unsigned vr, const double *dx_seed, const double *d_derivatives,
                    const double *d_outputs)
{
    if (is_derivative(vr)) return d_derivatives[vr - CP_VR_DERIVATIVE];
    if (is_output(vr)) return d_outputs[vr - CP_VR_OUTPUT];
    if (vr < CP_VR_OUTPUT) return dx_seed[vr - CP_VR_STATE];
    return 0.0;  /* a statistic */
}

ModelStatus model_directional_derivative(ModelData *m, const unsigned unknowns[], size_t n_unknown,
                                         const unsigned knowns[], size_t n_known,
                                         const double seed[], double sensitivity[], double time,
                                         char *message, size_t size)
{
    double dx_seed[CP_NSTATE] = {0}, dp_seed[CP_PSIZE] = {0};
    for (size_t k = 0; k < n_known; k++) {
        const unsigned vr = knowns[k];
        if (cp_known_refusal(vr, message, size)) return MODEL_REFUSED;
        add_seed(vr, seed[k], dx_seed, dp_seed);
    }
    int want_derivatives = 0, want_outputs = 0;
    for (size_t k = 0; k < n_unknown; k++) {
        if (cp_unknown_refusal(unknowns[k], message, size)) return MODEL_REFUSED;
        want_derivatives |= is_derivative(unknowns[k]);
        want_outputs |= is_output(unknowns[k]);
    }
    double d_derivatives[CP_NSTATE], d_outputs[CP_NOUTPUT + 1];
    ModelStatus status = column(m, dx_seed, dp_seed, want_derivatives ? d_derivatives : NULL,
                                want_outputs ? d_outputs : NULL, time, message, size);
    if (status != MODEL_OK) return status;
    for (size_t k = 0; k < n_unknown; k++)
        sensitivity[k] = entry(unknowns[k], dx_seed, d_derivatives, d_outputs);
    return MODEL_OK;
}

/* By complex step there is no reverse sweep: each known's column is one complex evaluation
 * (cp_directional along that known), and its sensitivity the seed's product with it. Exact to
 * rounding as the columns are; a Jacobian-transposed product costs n_known evaluations. */
ModelStatus model_adjoint_derivative(ModelData *m, const unsigned unknowns[], size_t n_unknown,
                                     const unsigned knowns[], size_t n_known, const double seed[],
                                     double sensitivity[], double time, char *message, size_t size)
{
    int want_derivatives = 0, want_outputs = 0;
    for (size_t k = 0; k < n_known; k++)
        if (cp_known_refusal(knowns[k], message, size)) return MODEL_REFUSED;
    for (size_t k = 0; k < n_unknown; k++) {
        const unsigned vr = unknowns[k];
        if (cp_unknown_refusal(vr, message, size)) return MODEL_REFUSED;
        if (!isfinite(seed[k])) {
            snprintf(message, size, "seed of %s = %g: must be finite", cp_variable_name(vr),
                     seed[k]);
            return MODEL_REFUSED;
        }
        want_derivatives |= is_derivative(vr) && seed[k] != 0.0;
        want_outputs |= is_output(vr) && seed[k] != 0.0;
    }
    double d_derivatives[CP_NSTATE], d_outputs[CP_NOUTPUT + 1];
    for (size_t j = 0; j < n_known; j++) {
        double dx_seed[CP_NSTATE] = {0}, dp_seed[CP_PSIZE] = {0};
        add_seed(knowns[j], 1.0, dx_seed, dp_seed);
        ModelStatus status = column(m, dx_seed, dp_seed, want_derivatives ? d_derivatives : NULL,
                                    want_outputs ? d_outputs : NULL, time, message, size);
        if (status != MODEL_OK) return status;
        double sum = 0.0;
        for (size_t i = 0; i < n_unknown; i++)
            if (seed[i] != 0.0) sum += seed[i] * entry(unknowns[i], dx_seed, d_derivatives, d_outputs);
        sensitivity[j] = sum;
    }
    return MODEL_OK;
}

/* ---- input and output derivatives ---- */


ModelStatus model_check_input_derivative(const ModelData *m, unsigned vr, int order, double value,
                                         char *message, size_t size)
{
    (void)m, (void)order, (void)value, (void)message, (void)size;
    return is_input(vr) ? MODEL_OK : MODEL_NO_VARIABLE;
}

void model_set_input_derivative(ModelData *m, unsigned vr, int order, double value)
{
    double *rate = &m->input_rates[vr - CP_VR_INPUT][order - 1];
    if (*rate != value) {
        /* x' and the outputs at x depend on the inputs' values, and on a winch speed's rate
           (its rope's l'') */
        if (order == 1 && is_hoist(vr)) forget_values(m);
        m->rates_valid = 0;
    }
    *rate = value;
}

/* The time derivatives of the states and outputs to order (m->rates_valid: the order they are
 * valid to): x' = f, x'' = f' (x', u') and y' = y' (x', u') by one complex step (cp_directional
 * along (x', u')); y'' = y''[(x', u'), (x', u')] + y' (x'', u'') by cp_second_directional, only
 * when asked (two evaluations in long double complex, some 50 times one in double complex). */
static ModelStatus time_rates(ModelData *m, int order, double time, char *message, size_t size)
{
    if (m->rates_valid >= order) return MODEL_OK;
    ModelStatus status = derivatives(m, time, message, size);
    if (status != MODEL_OK) return status;
    double vp[CP_PSIZE], wp[CP_PSIZE], x2[CP_NSTATE], y[CP_NOUTPUT + 1], pivot_ratio, buffer[CP_PSIZE];
    cp_input_direction((const double(*)[2])m->input_rates, 1, vp);
    cp_input_direction((const double(*)[2])m->input_rates, 2, wp);
    const double *p = core_p(m, buffer);
    int bad_dof, found = CP_OK;
    if (m->rates_valid < 1) {
        found = cp_directional(X(m), p, m->dx, vp, x2, y, &pivot_ratio, &bad_dof);
        for (int k = 0; found == CP_OK && k < CP_NSTATE; k++) {
            m->rates[k][0] = m->dx[k];
            m->rates[k][1] = x2[k];
        }
        for (int k = 0; found == CP_OK && k < CP_NOUTPUT; k++) m->rates[CP_NSTATE + k][0] = y[k];
    }
    if (found == CP_OK && order >= 2) {
        for (int k = 0; k < CP_NSTATE; k++) x2[k] = m->rates[k][1];
        found = cp_second_directional(X(m), p, m->dx, vp, x2, wp, y, &pivot_ratio, &bad_dof);
        for (int k = 0; found == CP_OK && k < CP_NOUTPUT; k++) m->rates[CP_NSTATE + k][1] = y[k];
    }
    if (found != CP_OK) return no_derivatives(time, found, bad_dof, pivot_ratio, message, size);
    m->rates_valid = order > m->rates_valid ? order : m->rates_valid;
    return MODEL_OK;
}

ModelStatus model_get_output_derivative(ModelData *m, unsigned vr, int order, double *value,
                                        double time, char *message, size_t size)
{
    if (vr < CP_VR_STATE || vr >= CP_VR_STATISTICS) return MODEL_NO_VARIABLE;
    ModelStatus status = time_rates(m, vr < CP_VR_OUTPUT ? 1 : order, time, message, size);
    if (status == MODEL_OK) *value = m->rates[vr - CP_VR_STATE][order - 1];
    return status;
}

/* ---- co-simulation ---- */

ModelStatus model_do_step(ModelData *m, double t, double dt, char *message, size_t size)
{
    return model_do_step_early(m, t, dt, 0, NULL, message, size);
}

ModelStatus model_do_step_early(ModelData *m, double t, double dt, int early_return_allowed,
                                double *last_successful_time, char *message, size_t size)
{
    const cp_settings settings = {m->solver, m->r[CP_VR_RTOL], m->r[CP_VR_ATOL],
                                  m->r[CP_VR_MAX_STEP], m->max_steps, m->across_points};
    cp_failure failure;
    double reached = t;
    int status = cp_cosim_advance(&settings, m->r, (const double(*)[2])m->input_rates, X(m), Y(m),
                                  t, dt, m->stop_time, &m->flight, &m->jacobian,
                                  &SCRATCH(m)->matrices, SCRATCH(m)->work, STATS(m),
                                  ROPE_EVENTS(m), &failure,
                                  early_return_allowed ? &reached : NULL);
    if (last_successful_time) *last_successful_time = status == CP_OK ? t + dt : reached;
    /* valid where the state moved (cosim.c computed them there); at t, computed again */
    m->outputs_valid = status == CP_OK || reached > t;
    if (status == CP_OK || reached > t) {  /* the inputs along their polynomials, where it got */
        m->dx_valid = m->rates_valid = 0;
        cp_flight_inputs(&m->flight, status == CP_OK ? t + dt : reached, m->r, m->input_rates);
    }
    if (status != CP_OK) {
        cp_diagnose(message, size, status, &failure);
        return MODEL_DISCARD;
    }
    return MODEL_OK;
}

/* ---- FMU states ---- */

/* NULL if the step in flight can be continued (cosim.h): its times finite and in order (the
 * point inside the step, the interpolant there where the point is before the step's end), the
 * proposed step finite and not negative, the vectors it holds finite (the interpolant's as
 * many rows as the solver's has), the inputs' polynomials finite; or the message. */
static const char *flight_invalid(const ModelData *m, char *message, size_t size)
{
    const cp_flight *f = &m->flight;
    const cp_step *step = &f->step;
    const struct { const char *name; double value; } times[] = {
        {"t_point", f->t_point}, {"t0", step->t0}, {"t1", step->t1}, {"t_inputs", f->t_inputs}};
    for (size_t k = 0; k < sizeof times / sizeof times[0]; k++) {
        char name[64];
        snprintf(name, sizeof name, "step in flight: %s", times[k].name);
        if (cp_real_refusal(name, times[k].value, &cp_rules[CP_FINITE_RULE], "", message, size))
            return message;
    }
    if (cp_real_refusal("h", step->h, &cp_rules[CP_STEP_RULE], CP_STEP_WHAT, message, size))
        return message;
    if (!f->live) return NULL;  /* the next step restarts from the state */
    if (!(step->t0 <= f->t_point && f->t_point <= step->t1 && f->t_inputs <= f->t_point)
        || (f->t_point < step->t1 && !step->dense)) {
        snprintf(message, size, "step in flight: t_inputs = %.17g, t0 = %.17g, t_point = %.17g, "
                 "t1 = %.17g (dense output %d): the point must lie in the step, after the "
                 "inputs' start, and inside it only with the step's interpolant",
                 f->t_inputs, step->t0, f->t_point, step->t1, step->dense);
        return message;
    }
    const struct { const char *name; int value, low, high; } counts[] = {
        {"method", step->method, CP_RK45, CP_BDF}, {"next", step->next, CP_DOP853, CP_RADAU},
        {"stiff_steps", step->stiff_steps, 0, INT_MAX}, {"calm_steps", step->calm_steps, 0, INT_MAX},
        {"order", step->order, step->method == CP_BDF, step->method == CP_BDF ? 5 : 0},
        {"equal_steps", step->equal_steps, 0, step->method == CP_BDF ? INT_MAX : 0}};
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++)
        if (counts[k].value < counts[k].low || counts[k].value > counts[k].high) {
            snprintf(message, size, "step in flight: %s = %d: must be from %d to %d",
                     counts[k].name, counts[k].value, counts[k].low, counts[k].high);
            return message;
        }
    if (step->method == CP_AUTO) {
        snprintf(message, size, "step in flight: method = %d: the automatic choice makes no step "
                 "of its own", CP_AUTO);
        return message;
    }
    const struct { const char *name; double value; } sizes[] = {
        {"h_old", step->h_old}, {"err_old", step->err_old}, {"stiffness", step->stiffness}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        char name[64];
        snprintf(name, sizeof name, "step in flight: %s", sizes[k].name);
        if (cp_real_refusal(name, sizes[k].value, &cp_rules[CP_STEP_RULE], "", message, size))
            return message;
    }
    const int dense_rows = step->method == CP_DOP853 || step->method == CP_BDF ? 7
                           : step->method == CP_RK45 ? 4 : 3;
    char name[64];
    for (int row = 0; row < CP_FLIGHT_ROWS; row++) {
        const int used = row < CP_ROW_F1 || (row == CP_ROW_F1 && step->fsal)
                         || (step->dense && row - CP_ROW_DENSE < dense_rows);
        for (int k = 0; used && k < CP_NSTATE; k++) {
            snprintf(name, sizeof name, "step in flight: row %d, entry %d", row, k);
            if (cp_real_refusal(name, f->rows[row][k], &cp_rules[CP_FINITE_RULE], "", message, size))
                return message;
        }
    }
    for (int e = 0; e < CP_NWATCHED; e++) {
        const cp_rope_watch *rope = &f->ropes[e];
        if (!(isfinite(rope->slope) && isfinite(rope->peak_time) && rope->peak >= 0
              && isfinite(rope->peak))) {
            snprintf(message, size, "step in flight: elastic rope %d's watch: slope = %.17g, "
                     "peak_time = %.17g, peak = %.17g: must be finite, the peak >= 0", e,
                     rope->slope, rope->peak_time, rope->peak);
            return message;
        }
    }
    for (int k = 0; k < CP_NINPUT; k++)
        for (int order = 0; order < 3; order++) {
            snprintf(name, sizeof name, "step in flight: input %d, derivative %d", k, order);
            if (cp_real_refusal(name, f->inputs[k][order], &cp_rules[CP_FINITE_RULE], "", message,
                                size))
                return message;
        }
    return NULL;
}

/* NULL if the implicit solver's record can be taken (cosim.h's cp_jacobian_record): the flags
 * 0 or 1, factors only of a Jacobian, the spectral radius a number >= 0; where the Jacobian is
 * valid, the state and the core's p it was evaluated at finite; where the factors are, their
 * step size finite and > 0; or the message. The matrices are made again from it, never taken. */
static const char *jacobian_invalid(const ModelData *m, char *message, size_t size)
{
    const cp_jacobian_record *record = &m->jacobian;
    const cp_newton *nw = &record->newton;
    const struct { const char *name; int value; } flags[] = {
        {"jac_valid", nw->jac_valid}, {"current_jac", nw->current_jac}, {"lu_valid", nw->lu_valid}};
    for (size_t k = 0; k < sizeof flags / sizeof flags[0]; k++)
        if (flags[k].value != 0 && flags[k].value != 1) {
            snprintf(message, size, "Jacobian: %s = %d: must be 0 or 1", flags[k].name, flags[k].value);
            return message;
        }
    const int known = nw->method == 0 || nw->method == CP_RADAU || nw->method == CP_BDF;
    if (!known || (nw->lu_valid && (!nw->jac_valid || nw->method == 0)) || !(nw->rho >= 0)) {
        snprintf(message, size, "Jacobian: method = %d, lu_valid = %d with jac_valid = %d, "
                 "rho = %.17g: the factors' method must be 0 (none), %d (radau) or %d (bdf), "
                 "factors need a Jacobian and a method, rho must be >= 0",
                 nw->method, nw->lu_valid, nw->jac_valid, nw->rho, CP_RADAU, CP_BDF);
        return message;
    }
    if (nw->lu_valid && !(isfinite(nw->h) && nw->h > 0)) {
        snprintf(message, size, "Jacobian: the factors' step size is %.17g: must be > 0", nw->h);
        return message;
    }
    char name[160];
    for (int i = 0; nw->jac_valid && i < CP_NSTATE + CP_PSIZE; i++) {
        if (i < CP_NSTATE)
            snprintf(name, sizeof name, "Jacobian evaluated at %s", cp_variable_name(CP_VR_STATE + i));
        else
            snprintf(name, sizeof name, "Jacobian evaluated at the core's p[%d]", i - CP_NSTATE);
        const double value = i < CP_NSTATE ? record->x[i] : record->p[i - CP_NSTATE];
        if (cp_real_refusal(name, value, &cp_rules[CP_FINITE_RULE], "", message, size)) return message;
    }
    return NULL;
}

/* Every Real keeps its variable's rule as model_check_real applies it (the outputs where
 * they are valid), and the statistics are counts; the Integer settings keep theirs as
 * model_check_integer applies them, the tolerance is 0 (none) or keeps
 * model_tolerance_refusal's, the stop time is a time or none; the flags are 0 or 1, the
 * carried derivatives are finite where they are valid, and so are the inputs' derivatives;
 * the step in flight can be continued (flight_invalid). */
const char *model_invalid(const ModelData *m, char *message, size_t size)
{
    const struct { const char *name; int value; } flags[] = {
        {"rtol_set", m->rtol_set}, {"live", m->flight.live}, {"fsal", m->flight.step.fsal},
        {"dense", m->flight.step.dense}, {"dx_valid", m->dx_valid},
        {"outputs_valid", m->outputs_valid}, {"states_jumped", m->states_jumped},
        {"hoist_warned", m->hoist_warned}};
    for (size_t k = 0; k < sizeof flags / sizeof flags[0]; k++)
        if (flags[k].value != 0 && flags[k].value != 1) {
            snprintf(message, size, "%s = %d: must be 0 or 1", flags[k].name, flags[k].value);
            return message;
        }
    if (m->rates_valid < 0 || m->rates_valid > 2) {
        snprintf(message, size, "rates_valid = %d: must be 0, 1 or 2", m->rates_valid);
        return message;
    }
    for (unsigned vr = 0; vr < CP_NREAL; vr++) {
        if (is_output(vr) && !m->outputs_valid) continue;
        if (real_rule_refusal(vr, m->r[vr], message, size)) return message;
    }
    if (integer_refusal(CP_VR_SOLVER, m->solver, message, size)
        || integer_refusal(CP_VR_MAX_STEPS, m->max_steps, message, size)
        || integer_refusal(CP_VR_ACROSS_POINTS, m->across_points, message, size))
        return message;
    if (m->tolerance != 0.0 && model_tolerance_refusal(m->tolerance, NULL, message, size))
        return message;
    if (m->stop_time != INFINITY
        && cp_real_refusal("stop_time", m->stop_time, &cp_rules[CP_FINITE_RULE], "", message, size))
        return message;
    if (flight_invalid(m, message, size) || jacobian_invalid(m, message, size)) return message;
    char name[160];
    for (int k = 0; k < CP_NSTATE; k++)
        if (m->dx_valid && cp_real_refusal(cp_variable_name(CP_VR_DERIVATIVE + k), m->dx[k],
                                           &cp_rules[CP_FINITE_RULE], "", message, size))
            return message;
    for (int k = 0; k < CP_NINPUT; k++)
        for (int order = 1; order <= 2; order++) {
            snprintf(name, sizeof name, "derivative %d of %s", order,
                     cp_variable_name(CP_VR_INPUT + k));
            if (cp_real_refusal(name, m->input_rates[k][order - 1], &cp_rules[CP_FINITE_RULE], "",
                                message, size))
                return message;
        }
    for (int k = 0; k < CP_NSTATE + CP_NOUTPUT; k++)  /* the states' to 2 once rates_valid */
        for (int order = 1; order <= (k < CP_NSTATE && m->rates_valid ? 2 : m->rates_valid); order++) {
            snprintf(name, sizeof name, "carried derivative %d of %s", order,
                     cp_variable_name(CP_VR_STATE + k));
            if (cp_real_refusal(name, m->rates[k][order - 1], &cp_rules[CP_FINITE_RULE], "",
                                message, size))
                return message;
        }
    return NULL;
}
