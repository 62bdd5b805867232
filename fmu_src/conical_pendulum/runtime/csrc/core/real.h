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
#if CP_COMPLEX_STEP == 1
/* sin and cos of a complex step's value a + i b. Below |b| = 2^-28 (a complex step's are some
 * 1e-20) cosh b is 1 and sinh b is b to the last bit, so csin's sin a cosh b + i cos a sinh b
 * is sin a + i b cos a, and ccos's is cos a - i b sin a: what glibc's csin and ccos give, bit
 * for bit, at a third of their cost (they took a third of a Jacobian's time: benchmarks/
 * stiff_long_chains.py). Beyond it, csin and ccos themselves. */
#define CP_SMALL_STEP 0x1p-28
static inline cp_real cp_step_parts(double re, double im)  /* C99 has no CMPLX */
{
    cp_real z = re;
    ((double *)&z)[1] = im;  /* a complex is an array of its two parts (C99 6.2.5) */
    return z;
}
static inline cp_real cp_step_sin(cp_real z)
{
    const double a = creal(z), b = cimag(z);
    return fabs(b) < CP_SMALL_STEP ? cp_step_parts(sin(a), b * cos(a)) : csin(z);
}
static inline cp_real cp_step_cos(cp_real z)
{
    const double a = creal(z), b = cimag(z);
    return fabs(b) < CP_SMALL_STEP ? cp_step_parts(cos(a), -b * sin(a)) : ccos(z);
}
#undef sin
#undef cos
#define sin(z) cp_step_sin(z)
#define cos(z) cp_step_cos(z)
#endif
#else
typedef double cp_real;
#define CP_RE(z) (z)
#define CP_FINITE(z) isfinite(z)
#endif

#endif
