/* Directional derivatives of the model by complex-step differentiation (directional.c). */
#ifndef CP_DIRECTIONAL_H
#define CP_DIRECTIONAL_H

/* The derivatives of x' = f(x, p) and of the outputs y(x, p) at (x, p) along the direction
 * (dx_seed, dp_seed), p and dp_seed of the core's size (CP_PSIZE, dynamics.h's cp_model):
 * d_derivatives = (df/dx) dx_seed + (df/dp) dp_seed (CP_NSTATE values) and d_outputs
 * likewise (CP_NOUTPUT values); either may be NULL when not wanted. Exact to
 * rounding: the model's own C evaluated at (x + i h dx_seed, p + i h dp_seed), over h.
 * Returns CP_OK, or the right-hand side's status (status.h) with *pivot_ratio and *bad_dof
 * set as cp_rhs sets them in its cp_model, where the mass matrix is singular there. */
int cp_directional(const double *x, const double *p, const double *dx_seed,
                   const double *dp_seed, double *d_derivatives, double *d_outputs,
                   double *pivot_ratio, int *bad_dof);

/* J = df/dx at (x, p) (CP_NSTATE x CP_NSTATE, row-major), p of the core's size: the implicit
 * solver's. In the expanded formulation a column per state by cp_directional; in the
 * recursive one each column from inverse dynamics and the articulated-body factorization
 * (chain.c's chain_jacobian), the same numbers to rounding at some half the cost.
 * Returns as cp_directional does. */
int cp_jacobian(const double *x, const double *p, double *J, double *pivot_ratio, int *bad_dof);

/* The second derivative in s of the outputs along the curve (x, p) + s v + s^2 w / 2 at
 * s = 0, y''[v, v] + y' w (CP_NOUTPUT values into d2_outputs; p, vp and wp of the core's
 * size, CP_PSIZE): with v = (x', u') and
 * w = (x'', u'') the outputs' second time derivative. Computed in second_directional.c from
 * two evaluations of the model's C in long double complex arithmetic at s = +-h e^(i pi / 4),
 * (Im y(s) + Im y(-s)) / h^2 = y'' + O(h^4): the first-order terms, equal and opposite,
 * cancel, with h = eps_long_double^(1/5) over the curve's rate, so that truncation and
 * rounding both stay below double's rounding (where long double is wider than double, as on
 * x86-64; where it is double, some 1e-13 relative). Returns as cp_directional does. */
int cp_second_directional(const double *x, const double *p, const double *vx, const double *vp,
                          const double *wx, const double *wp, double *d2_outputs,
                          double *pivot_ratio, int *bad_dof);

#endif
