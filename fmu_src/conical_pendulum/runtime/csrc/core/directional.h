/* Directional derivatives of the model by complex-step differentiation (directional.c). */
#ifndef CP_DIRECTIONAL_H
#define CP_DIRECTIONAL_H

/* The derivatives of x' = f(x, p) and of the outputs y(x, p) at (x, p) along the direction
 * (dx_seed, dp_seed): d_derivatives = (df/dx) dx_seed + (df/dp) dp_seed (CP_NSTATE values)
 * and d_outputs likewise (CP_NOUTPUT values); either may be NULL when not wanted. Exact to
 * rounding: the model's own C evaluated at (x + i h dx_seed, p + i h dp_seed), over h.
 * Returns CP_OK, or the right-hand side's status (status.h) with *pivot_ratio and *bad_dof
 * set as cp_rhs sets them in its cp_model, where the mass matrix is singular there. */
int cp_directional(const double *x, const double *p, const double *dx_seed,
                   const double *dp_seed, double *d_derivatives, double *d_outputs,
                   double *pivot_ratio, int *bad_dof);

#endif
