/* The model's real type: double, or double complex for complex-step differentiation.
 *
 * Everything the model computes from the state, the parameters and the inputs is a
 * cp_real. The core, the solvers and the FMI glue compile it as double. directional.c
 * compiles the same model sources a second time with CP_COMPLEX_STEP defined: cp_real is
 * then double complex and <tgmath.h> sends sin, cos, ... to csin, ccos, ..., so that
 * f(x + i h v) = f(x) + i h f'(x) v + O(h^2): the imaginary part over h is the directional
 * derivative, with no truncation or cancellation error worth the name. second_directional.c
 * compiles them a third time with CP_COMPLEX_STEP 2: cp_real is long double complex.
 *
 * What is not analytic must look at the real part only: pivot choices, singularity and
 * finiteness checks, branches. CP_RE(z) is that real part (z itself in the real build),
 * so a real-build value is computed exactly as before. Never apply fabs, fmin, fmax or a
 * comparison to a cp_real: under <tgmath.h> fabs of a complex is cabs, which is wrong. */
#ifndef CP_REAL_H
#define CP_REAL_H

#include <math.h>

#ifdef CP_COMPLEX_STEP
#include <complex.h>
#include <tgmath.h>
#undef I  /* the model's names (a link's spatial inertia I) stay its own: use _Complex_I */
#if CP_COMPLEX_STEP == 2
/* second_directional.c: long double complex, so that its second derivatives, which a
 * complex step cannot give free of cancellation, are exact to double rounding */
typedef long double complex cp_real;
#else
typedef double complex cp_real;
#endif
#define CP_RE(z) creal(z)
/* Both parts finite: an overflowing derivative is as bad as an overflowing value. */
#define CP_FINITE(z) (isfinite(creal(z)) && isfinite(cimag(z)))
#else
typedef double cp_real;
#define CP_RE(z) (z)
#define CP_FINITE(z) isfinite(z)
#endif

#endif
