/* The implicit solvers' Newton matrices (Radau's and BDF's): the system's Jacobian, its
 * structure, its spectral radius, and shift I - J factored and solved on that structure.
 *
 * The Newton matrices shift I - J are factored on the system's structure (radau5's treatment
 * of second-order systems): where J says x_i' = x_v (a position i, its row of J a single 1 at
 * its velocity v), the equation shift a_i - b_v = r_i gives a_i = (r_i + b_v) / shift, and the
 * rest of the system, without the positions, is solved alone: a mechanical system's matrices
 * are half as large, a factorization an eighth of the work, a solve a quarter. The answer is
 * the full system's to rounding; a system without positions is factored whole. */
#include <complex.h>
#include <math.h>

#include "solver_common.h"

cp_matrix_view cp_carve_matrices(int n, double *block, cp_newton *nw)
{
    cp_matrix_view mx;
    mx.J = block;
    mx.lu_real = block + n * n;
    mx.lu_complex = (double complex *)(block + 2 * n * n);
    mx.pivots_real = block + 4 * n * n;
    mx.pivots_complex = mx.pivots_real + n;
    mx.velocity = mx.pivots_complex + n;
    mx.slot = mx.velocity + n;
    mx.h = &nw->h;
    return mx;
}

/* The structure of the Newton systems, read off the Jacobian J (dim n) of x' = f(x): state i
 * is a position when x_i' = x_v (its row of J a single 1 at v != i) and v is no position
 * (decided in turn); velocity[i] = v for a position, -1 for the others, which slot numbers
 * 0, 1, ... in order (-1 for a position). Read once per Jacobian: half the states of a
 * mechanical system are positions, whose rows the factors and the power iteration skip. */
static void newton_structure(int n, const double *J, double *velocity, double *slot)
{
    for (int i = 0; i < n; i++) {  /* rows that are a single 1 off the diagonal */
        int one = -1, others = 0;
        for (int j = 0; j < n && others == 0; j++) {
            const double entry = J[i * n + j];
            if (entry == 1.0 && one < 0 && j != i) one = j;
            else if (entry != 0.0) others = 1;
        }
        velocity[i] = others ? -1 : one;
    }
    for (int i = 0; i < n; i++) {  /* a position's velocity must stay in the rest: in turn, */
        const int v = (int)velocity[i];  /* those before i decided, those after i candidates */
        if (v >= 0 && velocity[v] >= 0) velocity[i] = -1;
    }
    int r = 0;
    for (int i = 0; i < n; i++) slot[i] = velocity[i] >= 0 ? -1 : r++;
}

/* shift I - J on the structure (velocity, slot; r the rest's size) into a, r x r, factored
 * in place by partial pivoting (LAPACK's getrf without blocking); and the solve of
 * (shift I - J) x = b in place, through the factors (scratch: r of type): for real and for
 * complex matrices alike (type, its magnitude for the pivot's choice, and its row
 * elimination). The pivots past r are their own rows. A zero pivot is left as it is: the
 * solve gives inf, and the Newton iteration fails on it. */
#define LU_FUNCTIONS(factor_name, solve_name, type, magnitude, eliminate)                   \
    static void factor_name(int n, int r, type shift, const double *J, const double *velocity, \
                            const double *slot, type *a, double *pivots)                     \
    {                                                                                        \
        const type inverse = 1.0 / shift;  /* one division, not one an entry */               \
        for (int i = 0; i < n; i++) {                                                        \
            const int row = (int)slot[i];                                                    \
            if (row < 0) continue;                                                           \
            for (int j = 0; j < n; j++)                                                      \
                if (slot[j] >= 0) a[row * r + (int)slot[j]] = -J[i * n + j];                 \
            a[row * r + row] += shift;                                                       \
            for (int j = 0; j < n; j++)  /* a position's column, through a_j = b_v / shift */ \
                if (velocity[j] >= 0 && J[i * n + j] != 0.0)                                 \
                    a[row * r + (int)slot[(int)velocity[j]]] -= J[i * n + j] * inverse;      \
        }                                                                                    \
        for (int k = r; k < n; k++) pivots[k] = k;                                           \
        for (int k = 0; k < r; k++) {                                                        \
            int p = k;                                                                       \
            for (int i = k + 1; i < r; i++)                                                  \
                if (magnitude(a[i * r + k]) > magnitude(a[p * r + k])) p = i;                \
            pivots[k] = p;                                                                   \
            for (int j = 0; p != k && j < r; j++) {                                          \
                type s = a[k * r + j];                                                       \
                a[k * r + j] = a[p * r + j];                                                 \
                a[p * r + j] = s;                                                            \
            }                                                                                \
            if (a[k * r + k] == 0.0) continue;                                               \
            for (int i = k + 1; i < r; i++) {                                                \
                type l = a[i * r + k] /= a[k * r + k];                                       \
                eliminate(r - k - 1, l, a + i * r + k + 1, a + k * r + k + 1);               \
            }                                                                                \
        }                                                                                    \
    }                                                                                        \
    static void solve_name(int n, int r, type shift, const double *J, const double *velocity, \
                           const double *slot, const type *a, const double *pivots, type *b,  \
                           type *c)                                                          \
    {                                                                                        \
        for (int i = 0; i < n; i++) {  /* the rest's right-hand side, the positions' r_j in */ \
            if (slot[i] < 0) continue;                                                       \
            type s = 0.0;  /* the positions' part, divided by shift once */                  \
            for (int j = 0; r < n && j < n; j++)                                             \
                if (velocity[j] >= 0 && J[i * n + j] != 0.0) s += J[i * n + j] * b[j];       \
            c[(int)slot[i]] = b[i] + s / shift;                                              \
        }                                                                                    \
        for (int k = 0; k < r; k++) {                                                        \
            int p = (int)pivots[k];                                                          \
            type s = c[k];                                                                   \
            c[k] = c[p];                                                                     \
            c[p] = s;                                                                        \
        }                                                                                    \
        for (int i = 1; i < r; i++)                                                          \
            for (int j = 0; j < i; j++) c[i] -= a[i * r + j] * c[j];                         \
        for (int i = r - 1; i >= 0; i--) {                                                   \
            for (int j = i + 1; j < r; j++) c[i] -= a[i * r + j] * c[j];                     \
            c[i] /= a[i * r + i];                                                            \
        }                                                                                    \
        for (int i = 0; i < n; i++)                                                          \
            if (slot[i] >= 0) b[i] = c[(int)slot[i]];                                        \
        for (int i = 0; i < n; i++)                                                          \
            if (velocity[i] >= 0) b[i] = (b[i] + b[(int)velocity[i]]) / shift;               \
    }

/* row -= l pivot_row over count entries: the factorization's inner loop, where its time goes.
 * The rows never overlap (restrict), and the complex one multiplies as C does for finite
 * numbers, part by part (C's operator adds a test for NaN parts that keeps the loop from
 * being compiled tight): the same numbers, bit for bit, in some half the time. */
static void eliminate_real(int count, double l, double *restrict row, const double *restrict pivot_row)
{
    for (int j = 0; j < count; j++) row[j] -= l * pivot_row[j];
}

static void eliminate_complex(int count, double complex l, double complex *row_z,
                              const double complex *pivot_z)
{
    const double lr = creal(l), li = cimag(l);
    double *restrict row = (double *)row_z;  /* a complex is its two parts (C99 6.2.5) */
    const double *restrict pivot_row = (const double *)pivot_z;
    for (int j = 0; j < count; j++) {
        const double br = pivot_row[2 * j], bi = pivot_row[2 * j + 1];
        row[2 * j] -= lr * br - li * bi;
        row[2 * j + 1] -= lr * bi + li * br;
    }
}

LU_FUNCTIONS(lu_real, solve_real, double, fabs, eliminate_real)
LU_FUNCTIONS(lu_complex, solve_complex, double complex, cabs, eliminate_complex)

/* The size of the Newton systems the factors are on: the states that are no position. */
static int rest_size(int n, const cp_matrix_view *mx)
{
    int r = 0;
    for (int i = 0; i < n; i++) r += mx->slot[i] >= 0;
    return r;
}

void cp_factor_real(int n, double shift, const cp_matrix_view *mx)
{
    lu_real(n, rest_size(n, mx), shift, mx->J, mx->velocity, mx->slot, mx->lu_real, mx->pivots_real);
}

void cp_factor_complex(int n, double complex shift, const cp_matrix_view *mx)
{
    lu_complex(n, rest_size(n, mx), shift, mx->J, mx->velocity, mx->slot, mx->lu_complex,
               mx->pivots_complex);
}

void cp_solve_with_real(int n, double shift, const cp_matrix_view *mx, double *b, double *scratch)
{
    solve_real(n, rest_size(n, mx), shift, mx->J, mx->velocity, mx->slot, mx->lu_real,
               mx->pivots_real, b, scratch);
}

void cp_solve_with_complex(int n, double complex shift, const cp_matrix_view *mx,
                           double complex *b, double *scratch)
{
    solve_complex(n, rest_size(n, mx), shift, mx->J, mx->velocity, mx->slot, mx->lu_complex,
                  mx->pivots_complex, b, (double complex *)scratch);
}

/* The largest |eigenvalue| of J, estimated by twenty power iterations from a fixed start
 * (growth over the last ten): the automatic choice's measure of how stiff the scene is. */
static double spectral_radius(int n, const cp_matrix_view *mx, double *v, double *w)
{
    const double *J = mx->J;
    double log_growth = 0.0;
    for (int i = 0; i < n; i++) v[i] = 1.0 + 0.01 * i;
    for (int k = 0; k < 20; k++) {
        double norm = 0.0;
        for (int i = 0; i < n; i++) {
            double s = 0.0;
            if (mx->velocity[i] >= 0) s = v[(int)mx->velocity[i]];  /* J's row a single 1 */
            else
                for (int j = 0; j < n; j++) s += J[i * n + j] * v[j];
            w[i] = s;
            norm += s * s;
        }
        norm = sqrt(norm);
        if (!(norm > 0.0) || !isfinite(norm)) return norm > 0.0 ? INFINITY : 0.0;
        if (k >= 10) log_growth += log(norm);
        for (int i = 0; i < n; i++) v[i] = w[i] / norm;
    }
    return exp(log_growth / 10);
}

/* J at (t, x), its factors forgotten, its spectral radius estimated (v, w: scratch). */
int cp_new_jacobian(const cp_system *sys, double t, const double *x, cp_newton *nw,
                    const cp_matrix_view *mx, double *v, double *w, cp_stats *stats)
{
    stats->njev++;
    int status = sys->jac(sys->ctx, t, x, mx->J);
    nw->jac_valid = status == CP_OK;
    nw->current_jac = nw->jac_valid;
    nw->lu_valid = 0;
    if (status != CP_OK) return status;
    newton_structure(sys->dim, mx->J, mx->velocity, mx->slot);
    nw->rho = spectral_radius(sys->dim, mx, v, w);
    return status;
}

cp_matrix_view cp_matrices_of_jacobian(int n, double *block, cp_newton *nw)
{
    const cp_matrix_view mx = cp_carve_matrices(n, block, nw);
    newton_structure(n, mx.J, mx.velocity, mx.slot);
    return mx;
}
