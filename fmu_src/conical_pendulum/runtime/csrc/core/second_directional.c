/* Second directional derivatives of the model's outputs (directional.h), the model's own C
 * compiled a third time with cp_real = long double complex (real.h), its external names
 * renamed (model_copy.h) as directional.c's are for its copy.
 *
 * A complex step gives first derivatives free of cancellation, not second ones: no single
 * complex point has an imaginary part of order h^2 without one of order h. Two points do:
 * g(s) + g(-s) at s = h e^(i pi / 4) keeps the even Taylor terms, whose imaginary parts are
 * g'' h^2 (s^2 = i h^2), 0 (s^4 = -h^4) and -g^(6) h^6 / 360: the error is O(h^4) of
 * truncation and eps |g'| / h of rounding (the first-order terms cancel). In long double
 * (eps 1.1e-19 on x86-64) with h = eps^(1/5) both are below a double's rounding. */
#define CP_COMPLEX_STEP 2
#define CP_COPY_SUFFIX _cs2
#include "model_copy.h"

#include <float.h>

#include "directional.h"

int cp_second_directional(const double *x, const double *p, const double *vx, const double *vp,
                          const double *wx, const double *wp, double *d2_outputs,
                          double *pivot_ratio, int *bad_dof)
{
    *pivot_ratio = 1.0;
    *bad_dof = -1;
#if CP_NOUTPUT
    double rate = 0.0;  /* the curve's rate: 1 / its time scale */
    for (int k = 0; k < CP_NSTATE; k++) rate = fmax(rate, fmax(fabs(vx[k]), sqrt(fabs(wx[k]))));
    for (int k = 0; k < CP_PSIZE; k++) rate = fmax(rate, fmax(fabs(vp[k]), sqrt(fabs(wp[k]))));
    if (!(rate > 0)) {  /* a point, not a curve: the outputs do not move */
        for (int k = 0; k < CP_NOUTPUT; k++) d2_outputs[k] = 0.0;
        return CP_OK;
    }
    const long double h = powl(LDBL_EPSILON, 0.2L) / rate;
    const cp_real s1 = h * (cp_real)(0.7071067811865475244L + 0.7071067811865475244L * _Complex_I);
    const cp_real half_s2 = 0.5L * h * h * _Complex_I;  /* s^2 / 2, the same for -s */
    long double sum[CP_NOUTPUT] = {0};
    for (int sign = -1; sign <= 1; sign += 2) {
        const cp_real s = sign * s1;
        cp_real xc[CP_NSTATE], pc[CP_PSIZE], y[CP_NOUTPUT];
        for (int k = 0; k < CP_NSTATE; k++) xc[k] = x[k] + s * vx[k] + half_s2 * wx[k];
        for (int k = 0; k < CP_PSIZE; k++) pc[k] = p[k] + s * vp[k] + half_s2 * wp[k];
        cp_eval_outputs_cs2(xc, pc, y);
        for (int k = 0; k < CP_NOUTPUT; k++)
            if (!CP_FINITE(y[k])) {  /* the rates cannot be had there: cp_rhs says why */
                cp_model model = {pc, 1.0, -1};
                cp_real dx[CP_NSTATE];
                int status = cp_rhs_cs2(&model, xc, dx);
                *pivot_ratio = model.pivot_ratio;
                *bad_dof = model.bad_dof;
                return status != CP_OK ? status : CP_NONFINITE;
            }
        for (int k = 0; k < CP_NOUTPUT; k++) sum[k] += cimag(y[k]);
    }
    for (int k = 0; k < CP_NOUTPUT; k++) d2_outputs[k] = (double)(sum[k] / (h * h));
#else
    (void)x, (void)p, (void)vx, (void)vp, (void)wx, (void)wp, (void)d2_outputs;
#endif
    return CP_OK;
}
