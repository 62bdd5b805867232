#include "dynamics.h"

#include <math.h>
#include <string.h>

#if !CP_RECURSIVE
/* Solve M u = F in place (F becomes u) by LU with partial pivoting. */
static int lu_solve(double *M, double *F, cp_model *model)
{
    const int n = CP_NDOF;
    double largest = 0.0, smallest = INFINITY;
    int weakest = 0;
    for (int k = 0; k < n; k++) {
        int pivot = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(M[i * n + k]) > fabs(M[pivot * n + k])) pivot = i;
        if (pivot != k) {
            for (int j = 0; j < n; j++) {
                double tmp = M[k * n + j];
                M[k * n + j] = M[pivot * n + j];
                M[pivot * n + j] = tmp;
            }
            double tmp = F[k];
            F[k] = F[pivot];
            F[pivot] = tmp;
        }
        double d = fabs(M[k * n + k]);
        if (d > largest) largest = d;
        if (d < smallest) {
            smallest = d;
            weakest = k;
        }
        if (d == 0.0) break;
        for (int i = k + 1; i < n; i++) {
            double factor = M[i * n + k] / M[k * n + k];
            if (factor == 0.0) continue;
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
        double s = F[k];
        for (int j = k + 1; j < n; j++) s -= M[k * n + j] * F[j];
        F[k] = s / M[k * n + k];
    }
    return 0;
}
#endif

int cp_rhs(void *ctx, const double *x, double *dx)
{
    cp_model *model = (cp_model *)ctx;
#if CP_RECURSIVE
    return cp_chain_rhs(model, x, dx);
#else
    double M[CP_NDOF * CP_NDOF];
    double *F = dx + CP_NDOF;
    cp_mass_forcing(x, model->p, M, F);
    memcpy(dx, x + CP_NDOF, CP_NDOF * sizeof(double));
    int status = lu_solve(M, F, model);
    if (status) return status;
    for (int i = 0; i < CP_NDOF; i++) {
        if (!isfinite(F[i])) {
            model->bad_dof = i;
            return CP_NONFINITE;
        }
    }
    return 0;
#endif
}

void cp_eval_outputs(const double *x, const double *p, double *y)
{
#if CP_OUTPUTS_NEED_RATES
    double dx[CP_NSTATE];
    cp_model model = {p, 1.0, -1};
    if (cp_rhs(&model, x, dx))
        for (int i = 0; i < CP_NSTATE; i++) dx[i] = NAN;
    cp_outputs(x, p, dx, y);
#else
    cp_outputs(x, p, NULL, y);
#endif
}
