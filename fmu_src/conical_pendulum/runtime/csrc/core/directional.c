/* Directional derivatives of the model by complex-step differentiation.
 *
 * This file compiles the model's own C (model.c, dynamics.c, chain.c) a second time with
 * cp_real = double complex (real.h), its external names renamed so that one binary
 * carries both the real model and this copy. For an analytic f, f(x + i h v) =
 * f(x) + i h f'(x) v - h^2 f''(x)[v, v] / 2 - i h^3 f'''(x)[v, v, v] / 6 + ..., so
 * Im f(x + i h v) / h = f'(x) v + O(h^2): with h = 1e-20 and the direction scaled to
 * unit size, the truncation error is some 1e-40 relative, and nothing is subtracted, so
 * the result is f'(x) v to the rounding of the evaluation itself. What is not analytic
 * (pivot choice and checks) acts on real parts, which are f(x)'s to 1e-40 relative.
 */
#define CP_COMPLEX_STEP 1
#define CP_COPY_SUFFIX _cs
#include "model_copy.h"

#include "directional.h"

#define CP_COMPLEX_STEP_SIZE 1e-20

/* re + i im, for finite parts (C99 has no CMPLX). */
static cp_real complex_of(double re, double im)
{
    return re + im * _Complex_I;
}

int cp_directional(const double *x, const double *p, const double *dx_seed,
                   const double *dp_seed, double *d_derivatives, double *d_outputs,
                   double *pivot_ratio, int *bad_dof)
{
    double scale = 0.0;  /* the seed's largest component: the step is h along seed / scale */
    for (int k = 0; k < CP_NSTATE; k++) scale = fmax(scale, fabs(dx_seed[k]));
    for (int k = 0; k < CP_PSIZE; k++) scale = fmax(scale, fabs(dp_seed[k]));
    const double h = CP_COMPLEX_STEP_SIZE, step = scale > 0 ? h / scale : 0.0;
    cp_real xc[CP_NSTATE], pc[CP_PSIZE], dx[CP_NSTATE];
    for (int k = 0; k < CP_NSTATE; k++) xc[k] = complex_of(x[k], step * dx_seed[k]);
    for (int k = 0; k < CP_PSIZE; k++) pc[k] = complex_of(p[k], step * dp_seed[k]);
    const double back = scale / h;  /* Im(.) / step */
    cp_model model = {pc, 1.0, -1};
    *pivot_ratio = 1.0;
    *bad_dof = -1;
    if (d_derivatives || (d_outputs && CP_OUTPUTS_NEED_RATES)) {
        int status = cp_rhs_cs(&model, xc, dx);
        *pivot_ratio = model.pivot_ratio;
        *bad_dof = model.bad_dof;
        if (status != CP_OK) return status;
        if (d_derivatives)
            for (int k = 0; k < CP_NSTATE; k++) d_derivatives[k] = cimag(dx[k]) * back;
    }
#if CP_NOUTPUT
    if (d_outputs) {
        cp_real y[CP_NOUTPUT];
        cp_eval_outputs_cs(xc, pc, y);
        for (int k = 0; k < CP_NOUTPUT; k++) d_outputs[k] = cimag(y[k]) * back;
    }
#else
    (void)d_outputs;
#endif
    return CP_OK;
}

int cp_jacobian(const double *x, const double *p, double *J, double *pivot_ratio, int *bad_dof)
{
#if CP_RECURSIVE
    cp_model model = {NULL, 1.0, -1};
    const int status = chain_jacobian(x, p, CP_COMPLEX_STEP_SIZE, J, &model);
    *pivot_ratio = model.pivot_ratio;
    *bad_dof = model.bad_dof;
    return status;
#else
    static const double no_dp[CP_PSIZE + 1];
    double seed[CP_NSTATE] = {0}, column[CP_NSTATE];
    for (int j = 0; j < CP_NSTATE; j++) {
        seed[j] = 1.0;
        int status = cp_directional(x, p, seed, no_dp, column, NULL, pivot_ratio, bad_dof);
        seed[j] = 0.0;
        if (status) return status;
        for (int i = 0; i < CP_NSTATE; i++) J[i * CP_NSTATE + j] = column[i];
    }
    return CP_OK;
#endif
}
