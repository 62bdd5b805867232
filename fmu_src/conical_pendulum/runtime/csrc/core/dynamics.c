#include "dynamics.h"

#include <math.h>
#include <string.h>

#if !CP_RECURSIVE
/* Factor M in place by LU with partial pivoting: U on and above the diagonal, below it the
 * multipliers of each elimination step, left where the step found them (later row swaps
 * move only the columns still to eliminate), and perm, the row each step swapped in. */
static int lu_factor(cp_real *M, int perm[CP_NDOF], cp_model *model)
{
    const int n = CP_NDOF;
    double largest = 0.0, smallest = INFINITY;
    int weakest = 0;
    for (int k = 0; k < n; k++) {  /* pivots chosen and judged by their real parts */
        int pivot = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(CP_RE(M[i * n + k])) > fabs(CP_RE(M[pivot * n + k]))) pivot = i;
        perm[k] = pivot;
        if (pivot != k)
            for (int j = k; j < n; j++) {
                cp_real tmp = M[k * n + j];
                M[k * n + j] = M[pivot * n + j];
                M[pivot * n + j] = tmp;
            }
        double d = fabs(CP_RE(M[k * n + k]));
        if (d > largest) largest = d;
        if (d < smallest) {
            smallest = d;
            weakest = k;
        }
        if (d == 0.0) break;
        for (int i = k + 1; i < n; i++) {
            cp_real factor = M[i * n + k] / M[k * n + k];
            M[i * n + k] = factor;
            if (factor == 0.0) continue;  /* both parts zero: nothing to eliminate */
            for (int j = k + 1; j < n; j++) M[i * n + j] -= factor * M[k * n + j];
        }
    }
    double ratio = largest > 0 ? smallest / largest : 0.0;
    if (!(ratio >= model->pivot_ratio)) {
        model->pivot_ratio = ratio;
        model->bad_dof = weakest;
    }
    return ratio >= CP_SINGULAR_RATIO ? CP_OK : CP_SINGULAR;
}

/* Solve M u = b in place (b becomes u) with lu_factor's factors of M: the same operations,
 * in the same order, as eliminating b along with M. */
static void lu_solve(const cp_real *LU, const int perm[CP_NDOF], cp_real *b)
{
    const int n = CP_NDOF;
    for (int k = 0; k < n; k++) {
        cp_real tmp = b[k];
        b[k] = b[perm[k]];
        b[perm[k]] = tmp;
        for (int i = k + 1; i < n; i++)
            if (LU[i * n + k] != 0.0) b[i] -= LU[i * n + k] * b[k];
    }
    for (int k = n - 1; k >= 0; k--) {
        cp_real s = b[k];
        for (int j = k + 1; j < n; j++) s -= LU[k * n + j] * b[j];
        b[k] = s / LU[k * n + k];
    }
}
#endif

#if !CP_RECURSIVE
/* x' = (u, M^-1 F), leaving M's LU factors in M and perm. */
static int expanded_rates(cp_model *model, const cp_real *x, cp_real *dx, cp_real *M, int *perm)
{
    cp_real *F = dx + CP_NDOF;
    cp_mass_forcing(x, model->p, M, F);
    memcpy(dx, x + CP_NDOF, CP_NDOF * sizeof(cp_real));
    int status = lu_factor(M, perm, model);
    if (status) return status;
    lu_solve(M, perm, F);
    for (int i = 0; i < CP_NDOF; i++) {
        if (!CP_FINITE(F[i])) {
            model->bad_dof = i;
            return CP_NONFINITE;
        }
    }
    return CP_OK;
}
#endif

#ifdef CP_NELASTIC
/* Elastic rope e's spring and damper at (x, p): its stiffness EA / l, its damping coefficient
 * c = 2 zeta sqrt(EA / l m) (masses from the list at *j, moved past its -1), its stretch
 * and the stretch's rate. */
typedef struct {
    cp_real stiffness, damping, stretch, rate;
} rope_terms;

static rope_terms terms_of(const cp_real *x, const cp_real *p, int e, int *j)
{
    const int k = cp_elastic_rope[e];
    cp_real hanging = 0.0;
    for (; cp_elastic_masses[*j] >= 0; ++*j) hanging += p[cp_elastic_masses[*j]];
    ++*j;
    const cp_real length = x[cp_rope_state[k]], stiffness = p[cp_elastic_stiffness[e]] / length;
    rope_terms r = {stiffness, 2.0 * p[cp_elastic_damping[e]] * sqrt(stiffness * hanging),
                    x[cp_elastic_reach[e]] - length, x[cp_elastic_rate[e]] - p[cp_rope_hoist[k]]};
    return r;
}
#endif

void cp_rope_law(const cp_real *x, cp_real *p)
{
#ifdef CP_NELASTIC
    for (int e = 0, j = 0; e < CP_NELASTIC; e++) {
        const rope_terms r = terms_of(x, p, e, &j);
        const cp_real pull = r.stiffness * r.stretch + r.damping * r.rate;
        /* > 0 exactly where the rope is stretched and pulls: the pull, or while stretching
           the spring's part, <= 0 where it is slack */
        const cp_real margin = CP_RE(r.rate) < 0 ? pull : r.stiffness * r.stretch;
        p[cp_elastic_law[e]] = CP_RE(margin) > 0 ? pull : 0.0;
        p[cp_elastic_law[e] + 1] = CP_RE(r.stretch) > 0 ? r.stretch : 0.0;
        p[cp_elastic_law[e] + 2] = margin;
    }
#else
    (void)x, (void)p;
#endif
}

void cp_rope_tension_rates(const cp_real *x, const cp_real *dx, const cp_real *p, cp_real *rates)
{
#ifdef CP_NELASTIC
    for (int e = 0, j = 0; e < CP_NELASTIC; e++) {
        const int k = cp_elastic_rope[e];
        const rope_terms r = terms_of(x, p, e, &j);
        const cp_real length = x[cp_rope_state[k]], paid = dx[cp_rope_state[k]] / length;
        const cp_real accel = dx[cp_elastic_rate[e]] - p[CP_NPARAM + k];  /* s'' = r'' - l'' */
        /* (EA / l)' = -EA l' / l^2, c' = -c l' / (2 l) */
        rates[e] = CP_RE(p[cp_elastic_law[e] + 2]) > 0
                       ? r.stiffness * (r.rate - paid * r.stretch) + r.damping * (accel - 0.5 * paid * r.rate)
                       : 0.0;
    }
#else
    (void)x, (void)dx, (void)p, (void)rates;
#endif
}

int cp_rhs(void *ctx, const cp_real *x, cp_real *dx)
{
    cp_model *model = ctx;
#ifdef CP_NELASTIC
    const cp_real *given = model->p;
    cp_real p[CP_PSIZE];
    memcpy(p, given, sizeof p);
    cp_rope_law(x, p);
    model->p = p;
#endif
#if CP_RECURSIVE
    int status = cp_chain_rhs(model, x, dx);
#else
    cp_real M[CP_NDOF * CP_NDOF];
    int perm[CP_NDOF];
    int status = expanded_rates(model, x, dx, M, perm);
#endif
#if defined(CP_NWORK) && !CP_RECURSIVE
    /* the energy's books: each added force's power, the rate of its work (the recursive
       formulation's cp_chain_rhs gives them from its own kinematics) */
    if (!status) cp_work_rates(x, model->p, dx, dx + 2 * CP_NDOF);
#endif
#ifdef CP_NROPE
    /* the ropes' lengths grow at their winches' speeds */
    for (int k = 0; k < CP_NROPE; k++) dx[cp_rope_state[k]] = model->p[cp_rope_hoist[k]];
#endif
#ifdef CP_NELASTIC
    model->p = given;
#endif
    return status;
}

#if CP_FORCE_OUTPUT >= 0
/* x' and the chain's apparent mass at the pivot, M_app (3x3, row-major): in the expanded
 * formulation m I - P M^-1 P^T (model.h's cp_momentum: u' answers a_pivot through
 * M^-1 (-P^T), the pivot force through -m a_pivot - P u'), in the recursive one from the
 * articulated inertia at the pivot. */
static int rates_and_apparent_mass(cp_model *model, const cp_real *x, cp_real *dx, cp_real M_app[9])
{
#if CP_RECURSIVE
    return cp_chain_rates_and_apparent_mass(model, x, dx, M_app);
#else
    cp_real M[CP_NDOF * CP_NDOF], P[3 * CP_NDOF], total;
    int perm[CP_NDOF];
    int status = expanded_rates(model, x, dx, M, perm);
    if (status) return status;
    cp_momentum(x, model->p, P, &total);
    for (int c = 0; c < 3; c++) {
        cp_real z[CP_NDOF];  /* M^-1 P^T, column c */
        memcpy(z, P + c * CP_NDOF, sizeof z);
        lu_solve(M, perm, z);
        for (int r = 0; r < 3; r++) {
            cp_real s = 0.0;
            for (int k = 0; k < CP_NDOF; k++) s += P[r * CP_NDOF + k] * z[k];
            M_app[r * 3 + c] = (r == c ? total : 0.0) - s;
        }
    }
    return CP_OK;
#endif
}

/* F_pivot = F_free - M_app a_pivot, exactly affine in the pivot's acceleration (the
 * first inputs, after the parameters in p): F_free is the pivot force at a = 0, so both
 * depend on the state (and F_free on the bobs' applied forces, the inputs after them).
 * out: F_free, then the upper triangle of M_app (of its symmetric mean); NaN where the
 * mass matrix is singular. */
static void free_force_and_apparent_mass(const cp_real *x, const cp_real *p, cp_real *out)
{
    cp_real q[CP_PSIZE], dx[CP_NSTATE], y[CP_NOUTPUT], M[9];
    memcpy(q, p, sizeof q);
    for (int j = 0; j < 3; j++) q[CP_NPARAM - CP_NINPUT + j] = 0.0;
    cp_model model = {q, 1.0, -1};
    if (rates_and_apparent_mass(&model, x, dx, M)) {
        for (int k = 0; k < 9; k++) out[k] = NAN;
        return;
    }
    cp_outputs(x, q, dx, y);
    memcpy(out, y + CP_FORCE_OUTPUT, 3 * sizeof(cp_real));
    int k = 3;
    for (int r = 0; r < 3; r++)
        for (int c = r; c < 3; c++) out[k++] = 0.5 * (M[r * 3 + c] + M[c * 3 + r]);
}
#endif

void cp_eval_outputs(const cp_real *x, const cp_real *given, cp_real *y)
{
#ifdef CP_NELASTIC
    cp_real p[CP_PSIZE];  /* with the elastic ropes' law, which the outputs read */
    memcpy(p, given, sizeof p);
    cp_rope_law(x, p);
#else
    const cp_real *p = given;
#endif
#if CP_OUTPUTS_NEED_RATES
    cp_real dx[CP_NSTATE];
    cp_model model = {p, 1.0, -1};
    if (cp_rhs(&model, x, dx))
        for (int i = 0; i < CP_NSTATE; i++) dx[i] = NAN;
    cp_outputs(x, p, dx, y);
#else
    cp_outputs(x, p, NULL, y);
#endif
#if CP_FORCE_OUTPUT >= 0
    free_force_and_apparent_mass(x, p, y + CP_FORCE_OUTPUT + 3);
#endif
}
