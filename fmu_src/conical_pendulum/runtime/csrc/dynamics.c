#include "dynamics.h"

#include <math.h>
#include <string.h>

#if !CP_RECURSIVE
/* Solve M u = F in place (F becomes u) by LU with partial pivoting. */
static int lu_solve(cp_real *M, cp_real *F, cp_model *model)
{
    const int n = CP_NDOF;
    double largest = 0.0, smallest = INFINITY;
    int weakest = 0;
    for (int k = 0; k < n; k++) {  /* pivots chosen and judged by their real parts */
        int pivot = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(CP_RE(M[i * n + k])) > fabs(CP_RE(M[pivot * n + k]))) pivot = i;
        if (pivot != k) {
            for (int j = 0; j < n; j++) {
                cp_real tmp = M[k * n + j];
                M[k * n + j] = M[pivot * n + j];
                M[pivot * n + j] = tmp;
            }
            cp_real tmp = F[k];
            F[k] = F[pivot];
            F[pivot] = tmp;
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
            if (factor == 0.0) continue;  /* both parts zero: nothing to eliminate */
            for (int j = k + 1; j < n; j++) M[i * n + j] -= factor * M[k * n + j];
            F[i] -= factor * F[k];
        }
    }
    double ratio = largest > 0 ? smallest / largest : 0.0;
    if (!(ratio >= model->pivot_ratio)) {
        model->pivot_ratio = ratio;
        model->bad_dof = weakest;
    }
    if (!(ratio >= CP_SINGULAR_RATIO)) return CP_SINGULAR;
    for (int k = n - 1; k >= 0; k--) {
        cp_real s = F[k];
        for (int j = k + 1; j < n; j++) s -= M[k * n + j] * F[j];
        F[k] = s / M[k * n + k];
    }
    return 0;
}
#endif

int cp_rhs(void *ctx, const cp_real *x, cp_real *dx)
{
    cp_model *model = (cp_model *)ctx;
#if CP_RECURSIVE
    return cp_chain_rhs(model, x, dx);
#else
    cp_real M[CP_NDOF * CP_NDOF];
    cp_real *F = dx + CP_NDOF;
    cp_mass_forcing(x, model->p, M, F);
    memcpy(dx, x + CP_NDOF, CP_NDOF * sizeof(cp_real));
    int status = lu_solve(M, F, model);
    if (status) return status;
    for (int i = 0; i < CP_NDOF; i++) {
        if (!CP_FINITE(F[i])) {
            model->bad_dof = i;
            return CP_NONFINITE;
        }
    }
    return 0;
#endif
}

#if CP_NINPUT
/* The pivot force of the state x with the parameters and inputs q (model.h: where it is
 * in the outputs). */
static void pivot_force(const cp_real *x, const cp_real *q, cp_real force[3])
{
    cp_real dx[CP_NSTATE], y[CP_NOUTPUT];
    cp_model model = {q, 1.0, -1};
    if (cp_rhs(&model, x, dx))
        for (int i = 0; i < CP_NSTATE; i++) dx[i] = NAN;
    cp_outputs(x, q, dx, y);
    memcpy(force, y + CP_FORCE_OUTPUT, 3 * sizeof(cp_real));
}

/* F_pivot = F_free - M_app a_pivot: F_pivot is affine in the pivot's acceleration (the
 * inputs, last in p), so F_free is the force at a = 0 and M_app's columns are exactly the
 * force's changes from a = 0 to each unit acceleration. out: F_free, then the upper
 * triangle of M_app. */
static void free_force_and_apparent_mass(const cp_real *x, const cp_real *p, cp_real *out)
{
    cp_real q[CP_NPARAM], force[3][3];
    memcpy(q, p, sizeof q);
    cp_real *a = q + CP_NPARAM - CP_NINPUT, *free_force = out;
    a[0] = a[1] = a[2] = 0.0;
    pivot_force(x, q, free_force);
    for (int j = 0; j < 3; j++) {
        a[j] = 1.0;
        pivot_force(x, q, force[j]);
        a[j] = 0.0;
    }
    int k = 3;
    for (int r = 0; r < 3; r++)  /* the upper triangle of the symmetric mean */
        for (int c = r; c < 3; c++)
            out[k++] = 0.5 * ((free_force[r] - force[c][r]) + (free_force[c] - force[r][c]));
}
#endif

void cp_eval_outputs(const cp_real *x, const cp_real *p, cp_real *y)
{
#if CP_OUTPUTS_NEED_RATES
    cp_real dx[CP_NSTATE];
    cp_model model = {p, 1.0, -1};
    if (cp_rhs(&model, x, dx))
        for (int i = 0; i < CP_NSTATE; i++) dx[i] = NAN;
    cp_outputs(x, p, dx, y);
#else
    cp_outputs(x, p, NULL, y);
#endif
#if CP_NINPUT
    free_force_and_apparent_mass(x, p, y + CP_FORCE_OUTPUT + 3);
#endif
}
