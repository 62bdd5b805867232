/* The coupled demo's cart behind the model contract (fmu_model.h): a mass on a spring and
 * damper along X carrying an apparent mass M_x, (m_cart + M_x) a = F - k_cart x - c_cart v,
 * F the force in effect. Co-Simulation: over a step the input F_x is held (F_x_order = 0) or
 * extrapolated linearly through the last two communication points (1), and the step is
 * solved exactly by the matrix exponential of (x, v, F, F'), by scaling and squaring with the
 * Taylor series the pythonfmu cart used, so the numbers are its own to rounding. Model
 * Exchange: x' = v, v' = a with F = F_x (F_x_order does not apply). Its variables, starts
 * and value rules are builder/models/cart.py's (fmu_config.h). */
#include "fmu_model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmu_config.h"
#include "rules.h"

#define N_STATE 2
#define N_HELD CP_VR_OUTPUT   /* the Reals held: parameters, inputs, states (a is computed) */
#define N_EXP 4               /* the step's system: (x, v, F, F') */

struct ModelData {
    double r[N_HELD];       /* the held Reals by value reference (fmu_config.h) */
    int f_x_order;
    int has_last;           /* last_time and last_input are a step's */
    double force;           /* the force in effect now: F_x as set, or extrapolated to now */
    double last_time, last_input;  /* the last step's start and F_x there */
    /* the inputs' first and second time derivatives as the master set them, F_x's then M_x's
     * (0: held); over a step the inputs follow their Taylor polynomials, and step along them */
    double input_rates[2][2];
};

const ModelSizes model_sizes = {sizeof(ModelData), 0, CP_NREAL, CP_VR_DERIVATIVE - CP_NREAL,
                                N_STATE, 0, CP_VR_STATE, CP_VR_DERIVATIVE};

static const char *const tolerance_name = "tolerance (from setupExperiment)";

static double mass(const ModelData *m)
{
    return m->r[CP_VR_M_CART] + m->r[CP_VR_M_X];
}

static double acceleration(const ModelData *m)  /* written as the pythonfmu cart wrote it */
{
    return (m->force - m->r[CP_VR_K_CART] * m->r[CP_VR_X] - m->r[CP_VR_C_CART] * m->r[CP_VR_V])
           / mass(m);
}

/* a, or MODEL_DISCARD where values too large for a double make it infinite. */
static ModelStatus checked_acceleration(const ModelData *m, double *a, double time, char *message,
                                        size_t size)
{
    *a = acceleration(m);
    if (isfinite(*a)) return MODEL_OK;
    snprintf(message, size, "a at t = %.9g s is not finite (F = %g N, x = %g m, v = %g m/s): "
             "values too large for a double", time, m->force, m->r[CP_VR_X], m->r[CP_VR_V]);
    return MODEL_DISCARD;
}

static const char *real_rule_refusal(unsigned vr, double value, char *message, size_t size)
{
    return cp_real_refusal(cp_variable_name(vr), value, &cp_rules[cp_real_rule[vr]],
                           cp_real_what[vr], message, size);
}

static const char *order_refusal(int value, char *message, size_t size)
{
    return cp_integer_refusal(cp_variable_name(CP_VR_F_X_ORDER), value,
                              &cp_rules[CP_F_X_ORDER_RULE], "", message, size);
}

/* ---- start values, experiment, initialization ---- */

void model_reset(ModelData *m)
{
    memset(m, 0, sizeof *m);
    memcpy(m->r, cp_real_start, sizeof m->r);
    m->f_x_order = CP_F_X_ORDER_START;
    m->force = m->r[CP_VR_F_X];
}

/* The cart's step is exact: a tolerance has nothing to tighten, but is refused as the
 * pendulum's atol would be when it is no tolerance at all. */
const char *model_tolerance_refusal(double tolerance, const char *name, char *message,
                                    size_t size)
{
    return cp_real_refusal(name ? name : tolerance_name, tolerance, &cp_rules[CP_TOLERANCE_RULE],
                           CP_TOLERANCE_WHAT, message, size);
}

void model_set_tolerance(ModelData *m, double tolerance)
{
    (void)m, (void)tolerance;
}

void model_set_stop_time(ModelData *m, double stop_time)
{
    (void)m, (void)stop_time;  /* the cart's steps are exact: nothing integrates beyond a point */
}

void model_initialize(ModelData *m)
{
    m->has_last = 0;
    m->force = m->r[CP_VR_F_X];
}

void model_get_event_indicators(ModelData *m, double z[])  /* none: n_event_indicator is 0 */
{
    (void)m, (void)z;
}

void model_event_update(ModelData *m)  /* nothing discrete changes at an event */
{
    (void)m;
}

/* ---- the variable table ---- */

ModelStatus model_get_real(ModelData *m, unsigned vr, double *value, double time, char *message,
                           size_t size)
{
    if (vr < N_HELD) {
        *value = m->r[vr];
        return MODEL_OK;
    }
    if (vr == CP_VR_DERIVATIVE) {  /* der(x) = v */
        *value = m->r[CP_VR_V];
        return MODEL_OK;
    }
    if (vr == CP_VR_A || vr == CP_VR_DERIVATIVE + 1)  /* a, and der(v) = a */
        return checked_acceleration(m, value, time, message, size);
    return MODEL_NO_VARIABLE;
}

ModelStatus model_check_real(const ModelData *m, unsigned vr, double value, int phase,
                             char *message, size_t size)
{
    (void)m;
    if (vr >= CP_NREAL && (vr < CP_VR_DERIVATIVE || vr >= CP_VR_DERIVATIVE + N_STATE))
        return MODEL_NO_VARIABLE;
    if (cp_not_settable(vr, phase, message, size)
        || real_rule_refusal(vr, value, message, size))
        return MODEL_REFUSED;
    return MODEL_OK;
}

void model_set_real(ModelData *m, unsigned vr, double value, int phase)
{
    (void)phase;  /* nothing the cart holds jumps with a value set */
    m->r[vr] = value;
    if (vr == CP_VR_F_X) m->force = value;
}

int model_states_jumped(ModelData *m)
{
    (void)m;
    return 0;
}

ModelStatus model_get_integer(const ModelData *m, unsigned vr, int *value)
{
    if (vr != CP_VR_F_X_ORDER) return MODEL_NO_VARIABLE;
    *value = m->f_x_order;
    return MODEL_OK;
}

ModelStatus model_check_integer(const ModelData *m, unsigned vr, int value, int initialized,
                                char *message, size_t size)
{
    (void)m;
    if (vr != CP_VR_F_X_ORDER) return MODEL_NO_VARIABLE;
    return cp_not_settable(vr, initialized, message, size) || order_refusal(value, message, size)
               ? MODEL_REFUSED
               : MODEL_OK;
}

void model_set_integer(ModelData *m, unsigned vr, int value)
{
    (void)vr;
    m->f_x_order = value;
}

/* ---- Model Exchange ---- */

void model_get_states(const ModelData *m, double x[])
{
    memcpy(x, m->r + CP_VR_STATE, N_STATE * sizeof x[0]);
}

const char *model_set_states(ModelData *m, const double x[], char *message, size_t size)
{
    for (int k = 0; k < N_STATE; k++)
        if (real_rule_refusal(CP_VR_STATE + k, x[k], message, size)) return message;
    memcpy(m->r + CP_VR_STATE, x, N_STATE * sizeof x[0]);
    return NULL;
}

void model_get_nominals(const ModelData *m, double x_nominal[])
{
    (void)m;
    memcpy(x_nominal, cp_state_nominal, N_STATE * sizeof x_nominal[0]);
}

ModelStatus model_get_derivatives(ModelData *m, double dx[], double time, char *message,
                                  size_t size)
{
    dx[0] = m->r[CP_VR_V];
    return checked_acceleration(m, &dx[1], time, message, size);
}

/* ---- directional derivatives ---- */

/* d unknown / d known, exact: a = (F - k_cart x - c_cart v) / (m_cart + M_x) is linear in
 * the state, F_x, k_cart and c_cart, and depends on M_x and m_cart through 1 / (m_cart + M_x).
 * A state as unknown is an output of its own value. */
static double jacobian(const ModelData *m, unsigned unknown, unsigned known)
{
    if (unknown == CP_VR_X || unknown == CP_VR_V) return unknown == known;
    if (unknown == CP_VR_DERIVATIVE) return known == CP_VR_V;  /* der(x) = v */
    switch (known) {  /* a and der(v) */
    case CP_VR_X: return -m->r[CP_VR_K_CART] / mass(m);
    case CP_VR_V: return -m->r[CP_VR_C_CART] / mass(m);
    case CP_VR_F_X: return 1.0 / mass(m);
    case CP_VR_K_CART: return -m->r[CP_VR_X] / mass(m);
    case CP_VR_C_CART: return -m->r[CP_VR_V] / mass(m);
    case CP_VR_M_CART:
    case CP_VR_M_X: return -acceleration(m) / mass(m);
    default: return 0.0;  /* no other known (cp_known_refusal) */
    }
}

/* NULL if every value reference is a known or an unknown as its list says, or the message. */
static const char *role_refusal(const unsigned unknowns[], size_t n_unknown,
                                const unsigned knowns[], size_t n_known, char *message,
                                size_t size)
{
    for (size_t k = 0; k < n_known; k++)
        if (cp_known_refusal(knowns[k], message, size)) return message;
    for (size_t k = 0; k < n_unknown; k++)
        if (cp_unknown_refusal(unknowns[k], message, size)) return message;
    return NULL;
}

ModelStatus model_directional_derivative(ModelData *m, const unsigned unknowns[], size_t n_unknown,
                                         const unsigned knowns[], size_t n_known,
                                         const double seed[], double sensitivity[], double time,
                                         char *message, size_t size)
{
    (void)time;
    if (role_refusal(unknowns, n_unknown, knowns, n_known, message, size)) return MODEL_REFUSED;
    for (size_t i = 0; i < n_unknown; i++) {
        double sum = 0.0;
        for (size_t j = 0; j < n_known; j++) sum += jacobian(m, unknowns[i], knowns[j]) * seed[j];
        sensitivity[i] = sum;
    }
    return MODEL_OK;
}

ModelStatus model_adjoint_derivative(ModelData *m, const unsigned unknowns[], size_t n_unknown,
                                     const unsigned knowns[], size_t n_known, const double seed[],
                                     double sensitivity[], double time, char *message, size_t size)
{
    (void)time;
    if (role_refusal(unknowns, n_unknown, knowns, n_known, message, size)) return MODEL_REFUSED;
    for (size_t i = 0; i < n_unknown; i++)
        if (!isfinite(seed[i])) {
            snprintf(message, size, "seed of %s = %g: must be finite", cp_variable_name(unknowns[i]),
                     seed[i]);
            return MODEL_REFUSED;
        }
    for (size_t j = 0; j < n_known; j++) {
        double sum = 0.0;
        for (size_t i = 0; i < n_unknown; i++) sum += seed[i] * jacobian(m, unknowns[i], knowns[j]);
        sensitivity[j] = sum;
    }
    return MODEL_OK;
}

/* ---- input and output derivatives ---- */

static int input_index(unsigned vr)  /* F_x 0, M_x 1, else -1 */
{
    return vr == CP_VR_F_X ? 0 : vr == CP_VR_M_X ? 1 : -1;
}

static int interpolated(const ModelData *m)
{
    for (int k = 0; k < 2; k++)
        if (m->input_rates[k][0] != 0.0 || m->input_rates[k][1] != 0.0) return 1;
    return 0;
}

ModelStatus model_check_input_derivative(const ModelData *m, unsigned vr, int order, double value,
                                         char *message, size_t size)
{
    (void)m, (void)order, (void)value, (void)message, (void)size;
    return input_index(vr) >= 0 ? MODEL_OK : MODEL_NO_VARIABLE;
}

void model_set_input_derivative(ModelData *m, unsigned vr, int order, double value)
{
    m->input_rates[input_index(vr)][order - 1] = value;
}

/* Exact: (m_cart + M_x) a = F - k x - c v differentiated once and twice in time, with F and
 * M_x moving as the master's derivatives say: P a' = F' - k v - c a - P' a,
 * P a'' = F'' - k a - c a' - P'' a - 2 P' a'. */
ModelStatus model_get_output_derivative(ModelData *m, unsigned vr, int order, double *value,
                                        double time, char *message, size_t size)
{
    if (vr != CP_VR_X && vr != CP_VR_V && vr != CP_VR_A) return MODEL_NO_VARIABLE;
    double a;
    ModelStatus status = checked_acceleration(m, &a, time, message, size);
    if (status != MODEL_OK) return status;
    const double(*rate)[2] = (const double(*)[2])m->input_rates, P = mass(m);
    const double k = m->r[CP_VR_K_CART], c = m->r[CP_VR_C_CART];
    const double a1 = (rate[0][0] - k * m->r[CP_VR_V] - c * a - rate[1][0] * a) / P;
    const double a2 = (rate[0][1] - k * a - c * a1 - rate[1][1] * a - 2 * rate[1][0] * a1) / P;
    const double rates[3][2] = {{m->r[CP_VR_V], a}, {a, a1}, {a1, a2}};
    *value = rates[vr == CP_VR_X ? 0 : vr == CP_VR_V ? 1 : 2][order - 1];
    return MODEL_OK;
}

/* The step with moving inputs, exact to rounding: P(tau) x'' + c x' + k x = F(tau), P and F
 * quadratic in tau, solved by its Taylor series in substeps short enough that the series
 * converges geometrically (every coefficient's ratio below one half), summed until its terms
 * fall below rounding. Each substep re-expands P and F where it starts. end: x, v, F at dt. */
static const char *series_step(const ModelData *m, double t, double dt, double end[3],
                               char *message, size_t size)
{
    const double(*rate)[2] = (const double(*)[2])m->input_rates;
    const double k = m->r[CP_VR_K_CART], c = m->r[CP_VR_C_CART];
    const double F[3] = {m->force, rate[0][0], rate[0][1]};
    const double P[3] = {mass(m), rate[1][0], rate[1][1]};
    /* the mass must stay positive: at both ends and at the vertex of its parabola */
    double lowest = fmin(P[0], P[0] + dt * (P[1] + 0.5 * dt * P[2]));
    if (P[2] > 0 && -P[1] / P[2] > 0 && -P[1] / P[2] < dt) lowest = P[0] - 0.5 * P[1] * P[1] / P[2];
    if (!(lowest > 0)) {
        snprintf(message, size, "do_step at t = %.9g s: m_cart + M_x would reach %g kg within the "
                 "step (M_x and its derivatives as set): the moving mass must stay positive; the "
                 "state is kept", t, lowest);
        return message;
    }
    double bound = 0.0;  /* 1 / the shortest time scale of the equation over the step */
    bound = fmax(bound, sqrt(k / lowest) * 2.0);
    bound = fmax(bound, c / lowest * 2.0);
    bound = fmax(bound, fabs(P[1]) / lowest * 2.0);
    bound = fmax(bound, sqrt(fabs(P[2]) / lowest * 2.0));
    const double n_sub = fmax(1.0, ceil(dt * bound));
    if (!(n_sub <= 1e6)) {
        snprintf(message, size, "do_step at t = %.9g s: the step of %g s with these inputs' "
                 "derivatives needs %g substeps; the state is kept", t, dt, n_sub);
        return message;
    }
    const double h = dt / n_sub;
    double x = m->r[CP_VR_X], v = m->r[CP_VR_V];
    for (long sub = 0; sub < (long)n_sub; sub++) {
        const double tau = sub * h;
        const double P0 = P[0] + tau * (P[1] + 0.5 * tau * P[2]), P1 = P[1] + tau * P[2];
        const double Fh[3] = {F[0] + tau * (F[1] + 0.5 * tau * F[2]), (F[1] + tau * F[2]) * h,
                              0.5 * F[2] * h * h};  /* F_n h^n */
        double b0 = x, b1 = v * h, x_end = b0 + b1, v_end = b1;  /* b_n = a_n h^n */
        for (int n = 0; n < 200; n++) {
            const double b2 = h * h / (P0 * (n + 2) * (n + 1))
                              * ((n < 3 ? Fh[n] : 0.0) - (k + 0.5 * P[2] * n * (n - 1)) * b0
                                 - (c + P1 * n) * (n + 1) * b1 / h);
            x_end += b2;
            v_end += (n + 2) * b2;
            if (n > 2 && fabs(b2) + fabs(b1) <= 1e-18 * (fabs(x_end) + fabs(v_end))) break;
            b0 = b1;
            b1 = b2;
        }
        x = x_end;
        v = v_end / h;
    }
    end[0] = x;
    end[1] = v;
    end[2] = F[0] + dt * (F[1] + 0.5 * dt * F[2]);
    return NULL;
}

/* The inputs dt along their polynomials: their values and rates there. */
static void advance_inputs(ModelData *m, double dt)
{
    const unsigned vr[2] = {CP_VR_F_X, CP_VR_M_X};
    for (int k = 0; k < 2; k++) {
        double *rate = m->input_rates[k];
        m->r[vr[k]] += dt * (rate[0] + 0.5 * dt * rate[1]);
        rate[0] += dt * rate[1];
    }
}

/* ---- co-simulation ---- */

/* c = a b, 4 x 4. */
static void product(double c[N_EXP][N_EXP], double a[N_EXP][N_EXP], double b[N_EXP][N_EXP])
{
    for (int i = 0; i < N_EXP; i++)
        for (int j = 0; j < N_EXP; j++) {
            double sum = 0.0;
            for (int l = 0; l < N_EXP; l++) sum += a[i][l] * b[l][j];
            c[i][j] = sum;
        }
}

/* e = exp(a) by scaling and squaring with a Taylor series (the pythonfmu cart's expm,
 * step for step): the norm scaled to 0.25 or below, 0.25^16 / 16! < 1e-22. */
static void expm(double e[N_EXP][N_EXP], double a[N_EXP][N_EXP])
{
    double norm = 0.0, x[N_EXP][N_EXP], term[N_EXP][N_EXP], next[N_EXP][N_EXP];
    for (int i = 0; i < N_EXP; i++) {
        double row = 0.0;
        for (int j = 0; j < N_EXP; j++) row += fabs(a[i][j]);
        norm = fmax(norm, row);
    }
    int squarings = norm > 0.25 ? (int)fmax(0.0, ceil(log2(norm / 0.25))) : 0;
    for (int i = 0; i < N_EXP; i++)
        for (int j = 0; j < N_EXP; j++) {
            x[i][j] = a[i][j] / ldexp(1.0, squarings);
            term[i][j] = e[i][j] = i == j;
        }
    for (int k = 1; k < 16; k++) {
        product(next, term, x);
        for (int i = 0; i < N_EXP; i++)
            for (int j = 0; j < N_EXP; j++) {
                term[i][j] = next[i][j] / k;
                e[i][j] += term[i][j];
            }
    }
    for (int s = 0; s < squarings; s++) {
        product(next, e, e);
        memcpy(e, next, sizeof next);
    }
}

ModelStatus model_do_step(ModelData *m, double t, double dt, char *message, size_t size)
{
    return model_do_step_early(m, t, dt, 0, NULL, message, size);
}

/* The step is exact and all or nothing: early return never applies. */
ModelStatus model_do_step_early(ModelData *m, double t, double dt, int early_return_allowed,
                                double *last_successful_time, char *message, size_t size)
{
    (void)early_return_allowed;
    if (last_successful_time) *last_successful_time = t;
    if (!(dt >= 0 && isfinite(dt))) {
        char shown[40];
        cp_python_repr(shown, sizeof shown, dt);
        snprintf(message, size, "do_step at t = %.9g s: communication step %s: must be a "
                 "non-negative finite number; the state is kept", t, shown);
        return MODEL_DISCARD;
    }
    const double input = m->r[CP_VR_F_X], k = m->r[CP_VR_K_CART], c = m->r[CP_VR_C_CART];
    const int moving = interpolated(m) && dt > 0;  /* the master's polynomials, not the history */
    double end[3] = {0.0, 0.0, 0.0};
    if (moving) {
        if (series_step(m, t, dt, end, message, size)) return MODEL_DISCARD;
    } else {
        double slope = 0.0;
        if (m->f_x_order == 1 && m->has_last && t > m->last_time)
            slope = (input - m->last_input) / (t - m->last_time);
        /* (x, v, F, F') with x' = v, mass v' = F - k x - c v, F' = slope: exact over the step */
        double system[N_EXP][N_EXP] = {{0.0, 1.0, 0.0, 0.0},
                                       {-k / mass(m), -c / mass(m), 1.0 / mass(m), 0.0},
                                       {0.0, 0.0, 0.0, 1.0},
                                       {0.0, 0.0, 0.0, 0.0}};
        for (int i = 0; i < N_EXP; i++)
            for (int j = 0; j < N_EXP; j++) system[i][j] *= dt;
        double e[N_EXP][N_EXP], start[N_EXP] = {m->r[CP_VR_X], m->r[CP_VR_V], input, slope};
        expm(e, system);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < N_EXP; j++) end[i] += e[i][j] * start[j];
    }
    if (!(isfinite(end[0]) && isfinite(end[1]) && isfinite(end[2]))) {
        snprintf(message, size, "do_step at t = %.9g s: the cart's state is not finite after "
                 "the step (values too large for a double); the state is kept", t);
        return MODEL_DISCARD;
    }
    m->has_last = 1;
    m->last_time = t;
    m->last_input = input;
    m->r[CP_VR_X] = end[0];
    m->r[CP_VR_V] = end[1];
    if (moving) {
        advance_inputs(m, dt);
        m->force = m->r[CP_VR_F_X];
    } else {
        m->force = end[2];
    }
    if (last_successful_time) *last_successful_time = t + dt;
    return MODEL_OK;
}

/* ---- FMU states ---- */

/* Every held Real keeps its variable's rule as model_check_real applies it, F_x_order its
 * own; the flag is 0 or 1, the force in effect and what the extrapolation carries are
 * finite. */
const char *model_invalid(const ModelData *m, char *message, size_t size)
{
    if (m->has_last != 0 && m->has_last != 1) {
        snprintf(message, size, "has_last = %d: must be 0 or 1", m->has_last);
        return message;
    }
    for (unsigned vr = 0; vr < N_HELD; vr++)
        if (real_rule_refusal(vr, m->r[vr], message, size)) return message;
    if (order_refusal(m->f_x_order, message, size)) return message;
    const struct { const char *name; double value; } carried[] = {
        {"force", m->force}, {"last_time", m->last_time}, {"last_input", m->last_input},
        {"derivative 1 of F_x", m->input_rates[0][0]}, {"derivative 2 of F_x", m->input_rates[0][1]},
        {"derivative 1 of M_x", m->input_rates[1][0]}, {"derivative 2 of M_x", m->input_rates[1][1]}};
    for (size_t k = 0; k < sizeof carried / sizeof carried[0]; k++)
        if (cp_real_refusal(carried[k].name, carried[k].value, &cp_rules[CP_FINITE_RULE], "",
                            message, size))
            return message;
    return NULL;
}
