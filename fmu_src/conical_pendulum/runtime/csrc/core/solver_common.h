/* What the solvers of solvers.c and radau.c share: counted evaluations, the RMS norm, the
 * first step's choice and the implicit step. Internal to the core's solvers. */
#ifndef CP_SOLVER_COMMON_H
#define CP_SOLVER_COMMON_H

#include <complex.h>
#include <float.h>
#include <math.h>

#include "solvers.h"

static inline int cp_eval(const cp_system *sys, double t, const double *x, double *dx,
                          cp_stats *stats)
{
    stats->nfev++;
    return sys->rhs(sys->ctx, t, x, dx);
}

/* sqrt(mean((v / scale)^2)): scipy's norm of a scaled error. */
/* A trial stage's failure that rejects the step rather than ending the integration: a
 * non-finite acceleration or a singular mass matrix there says the step was too long for the
 * scene (a trial stage can fling a light body through a configuration the path never
 * reaches), not that the scene is wrong; where the path itself meets one, the step shrinks
 * to the least step and fails with it. */
static inline int cp_trial_rejects(int status)
{
    return status == CP_NONFINITE || status == CP_SINGULAR;
}

static inline double cp_rms(int n, const double *v, const double *scale)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) {
        double r = v[i] / scale[i];
        s += r * r;
    }
    return sqrt(s / n);
}

/* scipy's tolerance for the simplified Newton iteration of its implicit solvers (Radau, BDF),
 * in the norm of the error test. */
static inline double cp_scipy_newton_tol(double rtol)
{
    return fmax(10 * DBL_EPSILON / rtol, fmin(0.03, sqrt(rtol)));
}

/* scipy's tests of a simplified Newton iteration (Radau's and BDF's), after its increment's
 * norm and its rate of convergence (the norm over the last one's; < 0: none yet): it will not
 * reach tol in the iterations left, or it has reached it. */
static inline int cp_newton_gives_up(double rate, int iterations_left, double norm, double tol)
{
    return rate >= 0 && (rate >= 1 || pow(rate, iterations_left) / (1 - rate) * norm > tol);
}

static inline int cp_newton_converged(double rate, double norm, double tol)
{
    return norm == 0 || (rate >= 0 && rate / (1 - rate) * norm < tol);
}

/* The implicit solvers' view of the matrices block (CP_NEWTON_SIZE, newton.c): J, the real
 * factors, the complex factors (two doubles an entry), the two pivot vectors (whole numbers)
 * and the structure the factors are on; the step size they are for is the cp_newton's. */
typedef struct {
    double *J, *lu_real;
    double complex *lu_complex;
    double *pivots_real, *pivots_complex, *velocity, *slot, *h;
} cp_matrix_view;

cp_matrix_view cp_carve_matrices(int n, double *block, cp_newton *nw);

/* The view of a block whose J was put there from outside (a restored state's), its
 * structure read as a new Jacobian's is. */
cp_matrix_view cp_matrices_of_jacobian(int n, double *block, cp_newton *nw);

/* J at (t, x) into the block, its structure read, its factors forgotten, its spectral radius
 * estimated (v, w: scratch of n): the status of the system's Jacobian. */
int cp_new_jacobian(const cp_system *sys, double t, const double *x, cp_newton *nw,
                    const cp_matrix_view *mx, double *v, double *w, cp_stats *stats);

/* shift I - J factored on J's structure (the real or the complex factors), and
 * b = (shift I - J)^-1 b through them, shift the one they were made with (scratch: n). */
void cp_factor_real(int n, double shift, const cp_matrix_view *mx);
void cp_factor_complex(int n, double complex shift, const cp_matrix_view *mx);
void cp_solve_with_real(int n, double shift, const cp_matrix_view *mx, double *b, double *scratch);
void cp_solve_with_complex(int n, double complex shift, const cp_matrix_view *mx,
                           double complex *b, double *scratch);

/* One accepted step of Radau IIA (radau.c) or of the BDF (bdf.c) from the end of the step in
 * flight, none ending after t_end, their memory carved from work (CP_CARVED_ROWS rows); the
 * rows become the new step's (Radau: x0, x1, x' at x1, the dense output's 3 rows of Q; BDF:
 * x0, x1 and its differences). nw and block: the Jacobian and its factors, kept between
 * steps (cp_newton). */
int cp_radau_step(const cp_system *sys, cp_step *step, double *rows, cp_newton *nw,
                  double *block, double t_end, double rtol, double atol, double max_step,
                  long long max_steps, long long *attempts, double *work, cp_stats *stats);
int cp_bdf_step(const cp_system *sys, cp_step *step, double *rows, cp_newton *nw,
                double *block, double t_end, double rtol, double atol, double max_step,
                long long max_steps, long long *attempts, double *work, cp_stats *stats);

/* Each method's factors of the block's J for its step size h (Radau: its real and complex
 * matrices; BDF: I - h J, h its step over its leading coefficient), nw->lu_valid set. */
void cp_radau_factor(int n, double h, const cp_matrix_view *mx, cp_newton *nw, cp_stats *stats);
void cp_bdf_factor(int n, double h, const cp_matrix_view *mx, cp_newton *nw, cp_stats *stats);

/* Past COSTLY_JACOBIAN_DIM states (5 links) a Jacobian costs dim complex-step right-hand sides
 * (in the recursive formulation some half as many) and a factorization grows as dim^3: the
 * implicit solvers take the advice for large systems there (radau.c, bdf.c). */
#define COSTLY_JACOBIAN_DIM 20
#define LARGE(dim) ((dim) > COSTLY_JACOBIAN_DIM)

/* Rows of dim doubles a solver's step carves from the work array (the rest keeps cp_dense_grid's
 * step in flight). */
#define CP_CARVED_ROWS 22

#endif
