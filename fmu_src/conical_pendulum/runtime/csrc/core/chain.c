/* The recursive formulation (chain.h): articulated-body algorithm for x', recursive
 * Newton-Euler for M and F, and the scene's outputs, each in loops over the links.
 *
 * Spatial vectors are [angular; linear] in inertial components, each link's about its
 * joint (the top of the link); accelerations are classical (of the reference point), so
 * a rigid body's force is f = I a + b, with b the velocity terms. Gravity enters as an
 * upward acceleration of the pivot, so the force through joint 0 is the support's force.
 *
 * An elastic rope's bob slides along the rope (its reach r, a generalized coordinate): a
 * prismatic joint along -e_y between the massless rope and its bob (with all below it), at the
 * same reference point, so that the articulated-body algorithm condenses it first (its
 * generalized force -T, the rope's law from p) and the rope's two angles after it.
 *
 * Every value computed from x and p is a cp_real (real.h): double, or double complex in
 * directional.c's complex-step copy; what is not analytic (the pivot check) looks at real
 * parts only.
 */
#include "model.h"

#if CP_RECURSIVE

#include <math.h>
#include <string.h>

#include "chain.h"
#include "dynamics.h"

typedef struct {
    cp_real R[9];      /* the link's axes in inertial components (columns), row-major */
    cp_real E[6];      /* the joint's angular velocity per angle rate, inertial (3x2) */
    cp_real w[3];      /* angular velocity */
    cp_real pos[3];    /* joint position, relative to the pivot */
    cp_real vel[3];    /* joint velocity, relative to the pivot */
    cp_real d[3];      /* from the parent's joint to this one */
    cp_real r[3];      /* from this joint to the next (along the link) */
    cp_real s[3];      /* a rope's: its lower end's velocity along it, -v_hoist e_y (else 0) */
    cp_real as[3];     /* and that end's acceleration relative to the link's frame, 2 w x s -
                          l'' e_y: its Coriolis and the winch's acceleration (else 0) */
    cp_real zeta[6];   /* acceleration at zero rates' rates, less the parent's carried over */
    cp_real I[36];     /* spatial inertia of link and bob about the joint */
    cp_real b[6];      /* velocity-dependent force of link and bob about the joint */
    cp_real IA[36], pA[6], U[12], Dinv[4], uu[2];
    cp_real Up[6], Dp, up;  /* an elastic rope's slide: IA S, S^T IA S and -T - S^T pA */
#ifdef CP_DRAG
    cp_real drag[3];   /* the air's drag on the bob (bob_drag) */
#endif
} Link;

static void cross(const cp_real *a, const cp_real *b, cp_real *out)
{
    cp_real c0 = a[1] * b[2] - a[2] * b[1], c1 = a[2] * b[0] - a[0] * b[2];
    cp_real c2 = a[0] * b[1] - a[1] * b[0];
    out[0] = c0, out[1] = c1, out[2] = c2;
}

/* out = A (3x3) B (3xk), row-major. */
static void mul3(const cp_real *A, const cp_real *B, int k, cp_real *out)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < k; j++)
            out[i * k + j] = A[i * 3] * B[j] + A[i * 3 + 1] * B[k + j] + A[i * 3 + 2] * B[2 * k + j];
}

static void mul32(const cp_real E[6], const cp_real u[2], cp_real out[3])
{
    for (int i = 0; i < 3; i++) out[i] = E[2 * i] * u[0] + E[2 * i + 1] * u[1];
}

/* Adds a body (mass, centre c relative to the joint, central inertia Ic in inertial
 * components) moving with angular velocity w to the link's spatial inertia and bias. */
static void add_body(Link *k, cp_real mass, const cp_real c[3], const cp_real Ic[9])
{
    const cp_real cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    const cp_real cx[9] = {0, -c[2], c[1], c[2], 0, -c[0], -c[1], c[0], 0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            cp_real rot = (Ic ? Ic[i * 3 + j] : 0.0) + mass * ((i == j) * cc - c[i] * c[j]);
            k->I[i * 6 + j] += rot;
            k->I[i * 6 + 3 + j] += mass * cx[i * 3 + j];
            k->I[(3 + i) * 6 + j] -= mass * cx[i * 3 + j];
            k->I[(3 + i) * 6 + 3 + j] += mass * (i == j);
        }
    cp_real wc[3], wwc[3], force[3], moment[3];
    cross(k->w, c, wc);
    cross(k->w, wc, wwc);
    for (int i = 0; i < 3; i++) force[i] = mass * wwc[i];
    cross(c, force, moment);
    if (Ic) {
        cp_real Iw[3], wIw[3];
        for (int i = 0; i < 3; i++) Iw[i] = Ic[i * 3] * k->w[0] + Ic[i * 3 + 1] * k->w[1] + Ic[i * 3 + 2] * k->w[2];
        cross(k->w, Iw, wIw);
        for (int i = 0; i < 3; i++) moment[i] += wIw[i];
    }
    for (int i = 0; i < 3; i++) k->b[i] += moment[i], k->b[3 + i] += force[i];
}

/* The link's central inertia in inertial components: R diag(Ixx, Iyy, Izz) R^T. */
static void central_inertia(const Link *k, const cp_real *p, const cp_link_params *lp, cp_real Ic[9])
{
    const cp_real diag[3] = {p[lp->Ixx], p[lp->Iyy], p[lp->Izz]};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            Ic[i * 3 + j] = k->R[i * 3] * diag[0] * k->R[j * 3] + k->R[i * 3 + 1] * diag[1] * k->R[j * 3 + 1]
                            + k->R[i * 3 + 2] * diag[2] * k->R[j * 3 + 2];
}

#if defined(CP_BOB_FORCES) || defined(CP_DRAG) || defined(CP_NROPE)
/* A force F (inertial components) at the link's bob: -[r x F; F] to its bias force. */
static void apply_at_bob(Link *k, const cp_real F[3])
{
    cp_real t[3];
    cross(k->r, F, t);
    for (int j = 0; j < 3; j++) k->b[j] -= t[j], k->b[3 + j] -= F[j];
}
#endif

#ifdef CP_DRAG
/* The air's drag on link i's bob, -1/2 rho C_d A |v_air| v_air, v_air the bob's velocity
 * relative to the pivot, plus the pivot's (with coupling), less the wind (builder.core.equations's
 * _drag): into k->drag, and applied at the bob. */
static void bob_drag(Link *k, const cp_real *p, int i)
{
    cp_real wr[3], v[3];
    cross(k->w, k->r, wr);
    for (int j = 0; j < 3; j++) {
        v[j] = k->vel[j] + wr[j] + k->s[j] - p[CP_WIND_INDEX + j];
#if CP_PIVOT_VELOCITY_INDEX >= 0
        v[j] += p[CP_PIVOT_VELOCITY_INDEX + j];
#endif
    }
    const cp_real speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    const cp_real scale = -0.5 * p[CP_RHO_INDEX] * p[cp_bob_drag[i]] * p[cp_bob_area[i]] * speed;
    for (int j = 0; j < 3; j++) k->drag[j] = scale * v[j];
    apply_at_bob(k, k->drag);
}
#endif

/* Positions, velocities, joint axes, bias accelerations, and each link's inertia, of the
 * links from start on (those before it as links has them). */
static void kinematics_from(const cp_real *x, const cp_real *p, Link *links, int start)
{
    const int n = CP_NLINK;
    static const cp_real identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = start; i < n; i++) {
        Link *k = &links[i];
        const Link *parent = i ? &links[i - 1] : NULL;
        const cp_real *Rp = parent ? parent->R : identity;
        const cp_real zero[3] = {0, 0, 0};
        const cp_real *wp = parent ? parent->w : zero;
        const cp_real u[2] = {x[CP_NDOF + i], x[CP_NDOF + n + i]};
        cp_real C[9], J[6], Ja[6], Jb[6], rate[6], wrel[3], dE[3], t[3];
        cp_joint(x[i], x[n + i], C, J, Ja, Jb);
        mul3(Rp, C, 3, k->R);
        mul3(Rp, J, 2, k->E);
        mul32(k->E, u, wrel);
        for (int j = 0; j < 3; j++) k->w[j] = wp[j] + wrel[j];
        for (int j = 0; j < 6; j++) rate[j] = Ja[j] * u[0] + Jb[j] * u[1];
        mul32(rate, u, t);
        mul3(Rp, t, 1, dE);
        cross(wp, wrel, t);
        for (int j = 0; j < 3; j++) k->zeta[j] = t[j] + dE[j];
        if (parent) {
            memcpy(k->d, parent->r, sizeof k->d);
            cp_real wd[3];
            cross(wp, k->d, wd);
            cross(wp, wd, t);
            for (int j = 0; j < 3; j++) {  /* the joint on a rope's sliding end: its as more */
                k->pos[j] = parent->pos[j] + k->d[j];
                k->vel[j] = parent->vel[j] + wd[j] + parent->s[j];
                k->zeta[3 + j] = t[j] + parent->as[j];
            }
        } else {
            memset(k->d, 0, sizeof k->d);
            memset(k->pos, 0, sizeof k->pos);
            memset(k->vel, 0, sizeof k->vel);
            memset(k->zeta + 3, 0, 3 * sizeof(cp_real));
        }
        const cp_link_params *lp = &cp_links[i];
#ifdef CP_NROPE
        const int rope = cp_link_rope[i];
        cp_real l = rope >= 0 ? x[cp_rope_state[rope]] : p[lp->l];
        cp_real v = rope >= 0 ? p[cp_rope_hoist[rope]] : 0.0;
        cp_real a = rope >= 0 ? p[CP_NPARAM + rope] : 0.0;  /* l'' (cp_model's p) */
#ifdef CP_NELASTIC
        const int elastic = cp_link_elastic[i];
        if (elastic >= 0) {  /* its bob at its reach, sliding at v_r; v_r' is a rate */
            l = x[cp_elastic_reach[elastic]];
            v = x[cp_elastic_rate[elastic]];
            a = 0.0;
        }
#endif
#else
        const cp_real l = p[lp->l], v = 0.0, a = 0.0;
#endif
        cp_real ws[3];
        for (int j = 0; j < 3; j++) k->r[j] = -l * k->R[j * 3 + 1], k->s[j] = -v * k->R[j * 3 + 1];
        cross(k->w, k->s, ws);
        for (int j = 0; j < 3; j++) k->as[j] = 2 * ws[j] - a * k->R[j * 3 + 1];
        memset(k->I, 0, sizeof k->I);
        memset(k->b, 0, sizeof k->b);
        if (lp->M >= 0) {
            cp_real Ic[9], half[3] = {k->r[0] / 2, k->r[1] / 2, k->r[2] / 2};
            central_inertia(k, p, lp, Ic);
            add_body(k, p[lp->M], half, Ic);
        }
        if (lp->m >= 0) add_body(k, p[lp->m], k->r, NULL);
#ifdef CP_NROPE
        if (rope >= 0 && lp->m >= 0) {  /* the bob on a rope's sliding end: m as more */
            cp_real sliding[3];
            for (int j = 0; j < 3; j++) sliding[j] = -p[lp->m] * k->as[j];
            apply_at_bob(k, sliding);
        }
#endif
#ifdef CP_BOB_FORCES
        if (cp_bob_force[i] >= 0) apply_at_bob(k, p + cp_bob_force[i]);
#endif
#ifdef CP_DRAG
        if (cp_bob_drag[i] >= 0) bob_drag(k, p, i);
#endif
    }
}

static void kinematics(const cp_real *x, const cp_real *p, Link *links)
{
    kinematics_from(x, p, links, 0);
}

/* The pivot's acceleration seen by the chain: its input (if any) plus g upwards. */
static void base_acceleration(const cp_real *p, int with_gravity, cp_real a[6])
{
    memset(a, 0, 6 * sizeof(cp_real));
#if CP_PIVOT_INDEX >= 0
    for (int j = 0; j < 3; j++) a[3 + j] = p[CP_PIVOT_INDEX + j];
#endif
    if (with_gravity) a[4] += p[CP_G_INDEX];
}

/* The child's acceleration carried to its joint: [a_ang; a_lin - d x a_ang] + zeta. */
static void carry(const Link *k, const cp_real parent[6], cp_real out[6])
{
    cp_real t[3];
    cross(k->d, parent, t);
    for (int j = 0; j < 3; j++) {
        out[j] = parent[j] + k->zeta[j];
        out[3 + j] = parent[3 + j] - t[j] + k->zeta[3 + j];
    }
}

#ifdef CP_NELASTIC
/* An elastic rope's slide, S = [0; -e_y], with its generalized force: U = IA S, D = S^T U and
 * u = force - S^T pA kept, IA and pA condensed in place (IA - U U^T / D, pA + U u / D: its
 * velocity terms are the bob's and the children's already, Link.as). */
static void slide(Link *k, cp_real force)
{
    const cp_real ey[3] = {k->R[1], k->R[4], k->R[7]};
    for (int r = 0; r < 6; r++)
        k->Up[r] = -(k->IA[r * 6 + 3] * ey[0] + k->IA[r * 6 + 4] * ey[1] + k->IA[r * 6 + 5] * ey[2]);
    k->Dp = -(ey[0] * k->Up[3] + ey[1] * k->Up[4] + ey[2] * k->Up[5]);
    k->up = force + ey[0] * k->pA[3] + ey[1] * k->pA[4] + ey[2] * k->pA[5];
    for (int r = 0; r < 6; r++) {
        for (int c = 0; c < 6; c++) k->IA[r * 6 + c] -= k->Up[r] * k->Up[c] / k->Dp;
        k->pA[r] += k->Up[r] * k->up / k->Dp;
    }
}

/* The slide's acceleration r'' once the rope's frame accelerates by a, which it then adds to a
 * (the bob's and the children's frame). */
static cp_real slide_acceleration(const Link *k, cp_real a[6])
{
    cp_real rdd = k->up;
    for (int j = 0; j < 6; j++) rdd -= k->Up[j] * a[j];
    rdd /= k->Dp;
    for (int j = 0; j < 3; j++) a[3 + j] -= k->R[j * 3 + 1] * rdd;
    return rdd;
}
#endif

/* The articulated-body algorithm's pass from the tip to the pivot: every link's articulated
 * inertia IA and bias pA, and its joint's U, Dinv and uu. CP_SINGULAR where a joint's 2x2
 * articulated inertia is. */
static int articulate(cp_model *model, const cp_real *x, Link *links)
{
    const int n = CP_NLINK;
    const cp_real *p = model->p;
    kinematics(x, p, links);
    for (int i = 0; i < n; i++) {
        memcpy(links[i].IA, links[i].I, sizeof links[i].I);
        memcpy(links[i].pA, links[i].b, sizeof links[i].b);
    }
    for (int i = n - 1; i >= 0; i--) {
        Link *k = &links[i];
#ifdef CP_NELASTIC
        if (cp_link_elastic[i] >= 0) slide(k, -p[cp_elastic_law[cp_link_elastic[i]]]);
#endif
        cp_real D[4] = {0, 0, 0, 0};
        for (int r = 0; r < 6; r++)
            for (int c = 0; c < 2; c++)
                k->U[r * 2 + c] = k->IA[r * 6] * k->E[c] + k->IA[r * 6 + 1] * k->E[2 + c]
                                  + k->IA[r * 6 + 2] * k->E[4 + c];
        for (int r = 0; r < 2; r++) {
            k->uu[r] = 0;
            for (int j = 0; j < 3; j++) {
                D[r * 2] += k->E[j * 2 + r] * k->U[j * 2];
                D[r * 2 + 1] += k->E[j * 2 + r] * k->U[j * 2 + 1];
                k->uu[r] -= k->E[j * 2 + r] * k->pA[j];
            }
        }
#ifdef CP_DAMPING_INDEX
        /* the joint's damping torque -c w_rel: generalized forces -c (omega, delta), as the
           joint's axes are orthonormal (builder.core.equations.joint_damping) */
        for (int r = 0; r < 2; r++) k->uu[r] -= p[CP_DAMPING_INDEX + i] * x[CP_NDOF + r * n + i];
#endif
        /* LDL^T pivots of this joint's 2x2 articulated inertia: a cheap condition estimate,
           of the real parts (real.h) */
        const double d1 = CP_RE(D[0]),
                     d2 = d1 > 0 ? CP_RE(D[3]) - CP_RE(D[1]) * CP_RE(D[2]) / d1 : 0.0;
        const double ratio = d1 > 0 && d2 > 0 ? fmin(d1, d2) / fmax(d1, d2) : 0.0;
        if (!(ratio >= model->pivot_ratio)) {
            model->pivot_ratio = ratio;
            model->bad_dof = d2 < d1 ? n + i : i;
        }
        if (!(ratio >= CP_SINGULAR_RATIO)) return CP_SINGULAR;
        const cp_real det = D[0] * D[3] - D[1] * D[2];
        k->Dinv[0] = D[3] / det, k->Dinv[1] = -D[1] / det;
        k->Dinv[2] = -D[2] / det, k->Dinv[3] = D[0] / det;
        if (!i) break;
        /* Ia = IA - U Dinv U^T, pa = pA + Ia zeta + U Dinv uu, then carried to the parent */
        cp_real UD[12], Ia[36], pa[6], T[36];
        for (int r = 0; r < 6; r++)
            for (int c = 0; c < 2; c++)
                UD[r * 2 + c] = k->U[r * 2] * k->Dinv[c] + k->U[r * 2 + 1] * k->Dinv[2 + c];
        /* Ia is symmetric, and only its upper triangle is computed: rounding that made it
           not so would grow by (link length / radius of gyration about the link's axis)^2
           per link (40 seed links lost definiteness before). */
        for (int r = 0; r < 6; r++)
            for (int c = r; c < 6; c++)
                Ia[r * 6 + c] = Ia[c * 6 + r] = k->IA[r * 6 + c] - UD[r * 2] * k->U[c * 2]
                                                - UD[r * 2 + 1] * k->U[c * 2 + 1];
        for (int r = 0; r < 6; r++) {
            pa[r] = k->pA[r] + UD[r * 2] * k->uu[0] + UD[r * 2 + 1] * k->uu[1];
            for (int c = 0; c < 6; c++) pa[r] += Ia[r * 6 + c] * k->zeta[c];
        }
        /* X^T Ia X with X = [[1, 0], [-d^, 1]], X^T = [[1, d^], [0, 1]]: first T = Ia X,
           whose angular columns are Ia's plus d x (its linear columns), row by row */
        const cp_real *d = k->d;
        for (int r = 0; r < 6; r++) {
            const cp_real *row = Ia + r * 6;
            cp_real t[3];
            cross(d, row + 3, t);
            for (int j = 0; j < 3; j++) T[r * 6 + j] = row[j] + t[j], T[r * 6 + 3 + j] = row[3 + j];
        }
        Link *up = &links[i - 1];
        for (int c = 0; c < 6; c++) {
            cp_real lin[3] = {T[18 + c], T[24 + c], T[30 + c]}, t[3];
            cross(d, lin, t);
            for (int j = 0; j < 3; j++) {
                up->IA[j * 6 + c] += T[j * 6 + c] + t[j];
                up->IA[(3 + j) * 6 + c] += lin[j];
            }
        }
        cp_real t[3];
        cross(d, pa + 3, t);
        for (int j = 0; j < 3; j++) up->pA[j] += pa[j] + t[j], up->pA[3 + j] += pa[3 + j];
    }
    return CP_OK;
}

/* The pass from the pivot to the tip: x' from articulate's quantities. */
static int accelerate(cp_model *model, const cp_real *x, const Link *links, cp_real *dx)
{
    const int n = CP_NLINK;
    const cp_real *p = model->p;
    cp_real a[6];
    base_acceleration(p, 1, a);
    memcpy(dx, x + CP_NDOF, CP_NDOF * sizeof(cp_real));
    for (int i = 0; i < n; i++) {
        const Link *k = &links[i];
        cp_real ai[6], rhs[2];
        carry(k, a, ai);
        for (int r = 0; r < 2; r++) {
            rhs[r] = k->uu[r];
            for (int j = 0; j < 6; j++) rhs[r] -= k->U[j * 2 + r] * ai[j];
        }
        const cp_real ud[2] = {k->Dinv[0] * rhs[0] + k->Dinv[1] * rhs[1],
                              k->Dinv[2] * rhs[0] + k->Dinv[3] * rhs[1]};
        cp_real Eu[3];
        mul32(k->E, ud, Eu);
        for (int j = 0; j < 3; j++) ai[j] += Eu[j];
        dx[CP_NDOF + i] = ud[0], dx[CP_NDOF + n + i] = ud[1];
        if (!CP_FINITE(ud[0]) || !CP_FINITE(ud[1])) {
            model->bad_dof = CP_FINITE(ud[0]) ? n + i : i;
            return CP_NONFINITE;
        }
#ifdef CP_NELASTIC
        const int e = cp_link_elastic[i];
        if (e >= 0) {
            const cp_real rdd = dx[cp_elastic_rate[e]] = slide_acceleration(k, ai);
            if (!CP_FINITE(rdd)) {
                model->bad_dof = 2 * n + e;
                return CP_NONFINITE;
            }
        }
#endif
        memcpy(a, ai, sizeof a);
    }
    return CP_OK;
}

#if defined(CP_NROPE) || CP_PIVOT_INDEX >= 0
/* Newton's law for what hangs from each joint: hang[i] = sum over the bodies of links i and
 * below of m (a - g) less the forces applied to them (the bobs' and the drag), a their full
 * accelerations with the rates' rates from dx; the force through joint i is -hang[i] (through
 * the pivot, -hang[0]: the support force F_pivot). */
static void hanging(const cp_real *p, const Link *links, const cp_real *dx, cp_real hang[][3])
{
    const int n = CP_NLINK;
    cp_real a[6];
    base_acceleration(p, 0, a);
    for (int i = 0; i < n; i++) {
        const Link *k = &links[i];
        const cp_link_params *lp = &cp_links[i];
        cp_real ai[6], Eu[3];
        const cp_real u2[2] = {dx[CP_NDOF + i], dx[CP_NDOF + n + i]};
        carry(k, a, ai);
        mul32(k->E, u2, Eu);
        for (int j = 0; j < 3; j++) ai[j] += Eu[j];
#ifdef CP_NELASTIC
        if (cp_link_elastic[i] >= 0)  /* the bob's slide */
            for (int j = 0; j < 3; j++) ai[3 + j] -= k->R[j * 3 + 1] * dx[cp_elastic_rate[cp_link_elastic[i]]];
#endif
        memcpy(a, ai, sizeof a);
        cp_real *h = hang[i];
        h[0] = h[1] = h[2] = 0;
        for (int body = 0; body < 2; body++) {
            const int index = body ? lp->m : lp->M;
            if (index < 0) continue;
            const cp_real share = body ? 1.0 : 0.5;  /* bob at the end, link's centre halfway */
            cp_real c[3] = {k->r[0] * share, k->r[1] * share, k->r[2] * share}, t[3], wc[3], wwc[3];
            cross(ai, c, t);
            cross(k->w, c, wc);
            cross(k->w, wc, wwc);
            for (int j = 0; j < 3; j++) h[j] += p[index] * (ai[3 + j] + t[j] + wwc[j]);
#ifdef CP_NROPE
            if (body)  /* a rope's bob: its sliding end's acceleration */
                for (int j = 0; j < 3; j++) h[j] += p[index] * k->as[j];
#endif
            h[1] += p[index] * p[CP_G_INDEX];
        }
#ifdef CP_BOB_FORCES
        if (cp_bob_force[i] >= 0)
            for (int j = 0; j < 3; j++) h[j] -= p[cp_bob_force[i] + j];
#endif
#ifdef CP_DRAG
        if (cp_bob_drag[i] >= 0)
            for (int j = 0; j < 3; j++) h[j] -= k->drag[j];
#endif
    }
    for (int i = n - 2; i >= 0; i--)
        for (int j = 0; j < 3; j++) hang[i][j] += hang[i + 1][j];
}
#endif

#ifdef CP_NROPE
/* Each rope's tension (Scene.ropes' order): what hangs from its joint along the rope, e_y; an
 * elastic rope's, its law's (p). */
static void tensions(const cp_real *p, const Link *links, const cp_real hang[][3], cp_real *T)
{
    (void)p;
    for (int k = 0; k < CP_NROPE; k++) {
        const Link *rope = &links[cp_rope_link[k]];
        const cp_real *h = hang[cp_rope_link[k]];
        T[k] = rope->R[1] * h[0] + rope->R[4] * h[1] + rope->R[7] * h[2];
    }
#ifdef CP_NELASTIC
    for (int e = 0; e < CP_NELASTIC; e++) T[cp_elastic_rope[e]] = p[cp_elastic_law[e]];
#endif
}

/* Rope k's winch's power: -T v_hoist; an elastic rope's -(T + EA s+^2 / (2 l^2)) v_hoist,
 * with the strain energy the rope paid out carries (builder.core.equations). */
static cp_real hoist_power(int k, const cp_real *x, const cp_real *p, const cp_real *T)
{
    cp_real carried = 0.0;
#ifdef CP_NELASTIC
    for (int e = 0; e < CP_NELASTIC; e++)
        if (cp_elastic_rope[e] == k) {
            const cp_real strain = p[cp_elastic_law[e] + 1] / x[cp_rope_state[k]];
            carried = p[cp_elastic_stiffness[e]] * strain * strain / 2;
        }
#else
    (void)x;
#endif
    return -(T[k] + carried) * p[cp_rope_hoist[k]];
}
#endif

#ifdef CP_NELASTIC
/* Elastic rope e's strain energy EA s+^2 / (2 l) and its damping's power (EA s+ / l - T)
 * (v_r - v_hoist), from its law in p. */
static cp_real strain_energy(int e, const cp_real *x, const cp_real *p)
{
    const cp_real taut = p[cp_elastic_law[e] + 1];
    return p[cp_elastic_stiffness[e]] * taut * taut / (2 * x[cp_rope_state[cp_elastic_rope[e]]]);
}

static cp_real rope_damping_power(int e, const cp_real *x, const cp_real *p)
{
    const int k = cp_elastic_rope[e];
    const cp_real elastic = p[cp_elastic_stiffness[e]] * p[cp_elastic_law[e] + 1] / x[cp_rope_state[k]];
    return (elastic - p[cp_elastic_law[e]]) * (x[cp_elastic_rate[e]] - p[cp_rope_hoist[k]]);
}
#endif

#ifdef CP_NWORK
/* The energy's books: each force's power, in Scene.work_names' order (CP_WORK_*: -1 for
 * those the scene has not), with velocities relative to the pivot as the energy's; the
 * winches' from the ropes' tensions, which need the rates' rates dx; the loads' none. */
static void work_rates(const cp_real *x, const cp_real *p, const Link *links, const cp_real *dx,
                       cp_real *dW)
{
    const int n = CP_NLINK;
    (void)x, (void)p, (void)links, (void)n, (void)dx;
#if CP_WORK_HOIST >= 0
    cp_real hang[CP_NLINK][3], T[CP_NROPE], hoist = 0;
    hanging(p, links, dx, hang);
    tensions(p, links, (const cp_real(*)[3])hang, T);
    for (int k = 0; k < CP_NROPE; k++) hoist += hoist_power(k, x, p, T);
    dW[CP_WORK_HOIST] = hoist;
#endif
#ifdef CP_WORK_ROPE  /* defined only where kept: the elastic ropes' damping */
    cp_real damped = 0;
    for (int e = 0; e < CP_NELASTIC; e++) damped += rope_damping_power(e, x, p);
    dW[CP_WORK_ROPE] = damped;
#endif
#ifdef CP_WORK_LOAD  /* defined only where kept: it jumps at a load's change, and stays between */
    dW[CP_WORK_LOAD] = 0;
#endif
#if CP_WORK_DAMPING >= 0
    cp_real damping = 0;  /* -c (omega^2 + delta^2) per joint (articulate) */
    for (int i = 0; i < n; i++)
        damping -= p[CP_DAMPING_INDEX + i]
                   * (x[CP_NDOF + i] * x[CP_NDOF + i] + x[CP_NDOF + n + i] * x[CP_NDOF + n + i]);
    dW[CP_WORK_DAMPING] = damping;
#endif
#if CP_WORK_DRAG >= 0 || CP_WORK_EXTERNAL >= 0 || CP_WORK_PIVOT >= 0
    /* each force times the velocity, relative to the pivot, of the point it acts at */
    cp_real momentum[3] = {0, 0, 0}, drag = 0, external = 0;
    for (int i = 0; i < n; i++) {
        const Link *k = &links[i];
        cp_real wr[3], bob[3];
        cross(k->w, k->r, wr);
        for (int j = 0; j < 3; j++) bob[j] = k->vel[j] + wr[j] + k->s[j];
#if CP_WORK_PIVOT >= 0
        const cp_link_params *lp = &cp_links[i];
        for (int j = 0; j < 3; j++) {
            if (lp->M >= 0) momentum[j] += p[lp->M] * (k->vel[j] + wr[j] / 2);
            if (lp->m >= 0) momentum[j] += p[lp->m] * bob[j];
        }
#endif
#ifdef CP_DRAG
        if (cp_bob_drag[i] >= 0)
            for (int j = 0; j < 3; j++) drag += k->drag[j] * bob[j];
#endif
#ifdef CP_BOB_FORCES
        if (cp_bob_force[i] >= 0)
            for (int j = 0; j < 3; j++) external += p[cp_bob_force[i] + j] * bob[j];
#endif
    }
    (void)momentum, (void)drag, (void)external;
#if CP_WORK_DRAG >= 0
    dW[CP_WORK_DRAG] = drag;
#endif
#if CP_WORK_EXTERNAL >= 0
    dW[CP_WORK_EXTERNAL] = external;
#endif
#if CP_WORK_PIVOT >= 0  /* the inertial force -m a_pivot on every mass */
    dW[CP_WORK_PIVOT] = -(p[CP_PIVOT_INDEX] * momentum[0] + p[CP_PIVOT_INDEX + 1] * momentum[1]
                          + p[CP_PIVOT_INDEX + 2] * momentum[2]);
#endif
#endif
}
#endif

int cp_chain_rhs(cp_model *model, const cp_real *x, cp_real *dx)
{
    Link links[CP_NLINK];
    int status = articulate(model, x, links);
    if (!status) status = accelerate(model, x, links, dx);
#ifdef CP_NWORK
    if (!status) work_rates(x, model->p, links, dx, dx + 2 * CP_NDOF);
#endif
    return status;
}

#if CP_PIVOT_INDEX >= 0
int cp_chain_rates_and_apparent_mass(cp_model *model, const cp_real *x, cp_real *dx, cp_real M[9])
{
    Link links[CP_NLINK];
    int status = articulate(model, x, links);
    if (status) return status;
    /* IA - U Dinv U^T of link 0, about the pivot: what the support's translation meets */
    const Link *k = &links[0];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            const cp_real *ur = k->U + (3 + r) * 2, *uc = k->U + (3 + c) * 2;
            M[r * 3 + c] = k->IA[(3 + r) * 6 + 3 + c]
                           - ur[0] * (k->Dinv[0] * uc[0] + k->Dinv[1] * uc[1])
                           - ur[1] * (k->Dinv[2] * uc[0] + k->Dinv[3] * uc[1]);
        }
    return accelerate(model, x, links, dx);
}
#endif

/* Generalized forces tau that give the rates' rates ud (recursive Newton-Euler), with each
 * link's acceleration and its own force f = I a + b (without its children's) into acc and
 * force: from the link start on; those before it as acc and force have them. */
static void inverse_dynamics_from(const Link *links, const cp_real *p, const cp_real *ud, int start,
                                  cp_real (*acc)[6], cp_real (*force)[6], cp_real *tau)
{
    const int n = CP_NLINK;
    cp_real a[6], f[6];
    if (start) memcpy(a, acc[start - 1], sizeof a);
    else base_acceleration(p, 1, a);
    for (int i = start; i < n; i++) {
        const Link *k = &links[i];
        cp_real ai[6], Eu[3];
        const cp_real u2[2] = {ud[i], ud[n + i]};
        carry(k, a, ai);
        mul32(k->E, u2, Eu);
        for (int j = 0; j < 3; j++) ai[j] += Eu[j];
#ifdef CP_NELASTIC
        if (cp_link_elastic[i] >= 0)  /* the bob's slide */
            for (int j = 0; j < 3; j++) ai[3 + j] -= k->R[j * 3 + 1] * ud[2 * n + cp_link_elastic[i]];
#endif
        for (int r = 0; r < 6; r++) {
            force[i][r] = k->b[r];
            for (int c = 0; c < 6; c++) force[i][r] += k->I[r * 6 + c] * ai[c];
        }
        memcpy(acc[i], ai, sizeof a);
        memcpy(a, ai, sizeof a);
    }
    for (int i = n - 1; i >= 0; i--) {  /* f: what joint i carries, its link's and below */
        const Link *k = &links[i];
        if (i == n - 1) memcpy(f, force[i], sizeof f);
        else {
            cp_real t[3];  /* the child's carried to this joint, plus this link's own */
            cross(links[i + 1].d, f + 3, t);
            for (int j = 0; j < 3; j++) f[j] = force[i][j] + (f[j] + t[j]), f[3 + j] += force[i][3 + j];
        }
        tau[i] = tau[n + i] = 0;
        for (int j = 0; j < 3; j++) tau[i] += k->E[j * 2] * f[j], tau[n + i] += k->E[j * 2 + 1] * f[j];
#ifdef CP_NELASTIC
        if (cp_link_elastic[i] >= 0) {  /* the force along the slide, S^T f */
            cp_real *t = &tau[2 * n + cp_link_elastic[i]];
            *t = 0;
            for (int j = 0; j < 3; j++) *t -= k->R[j * 3 + 1] * f[3 + j];
        }
#endif
    }
}

static void inverse_dynamics(const Link *links, const cp_real *p, const cp_real *ud, cp_real *tau)
{
    cp_real acc[CP_NLINK][6], force[CP_NLINK][6];
    inverse_dynamics_from(links, p, ud, 0, acc, force, tau);
}

#if CP_COMPLEX_STEP == 1
/* The Jacobian J = df/dx of the recursive formulation, for directional.c's cp_jacobian (this
 * complex-step copy only). M u' = F is r(x, u') = 0 with r the generalized forces inverse
 * dynamics needs for u' (its recursive Newton-Euler, every option's force among them) plus the
 * joints' damping and the elastic ropes' pull: a column is u'_j = -M^-1 dr/dx_j at u' fixed,
 * dr/dx_j by a complex step through kinematics and inverse dynamics from the link x_j moves
 * on (the links before it as they were), M^-1 by the articulated-body factorization the
 * right-hand side made, with neither velocity terms nor gravity. Some n^2 / 2 links' worth
 * of a complex-step right-hand side's work instead of n^2 twice over (a column of it per
 * state): tests/test_jacobian.py holds it to the columns of cp_directional. */

/* What a solve with M needs of a link's articulated-body factorization, real. */
typedef struct {
    double E[6], U[12], Dinv[4], d[3];
#ifdef CP_NELASTIC
    double ey[3], Up[6], Dp;  /* its slide's, where its bob hangs from an elastic rope */
#endif
} Factored;

static void factored_of(const Link *links, Factored *out)
{
    for (int i = 0; i < CP_NLINK; i++) {
        const Link *k = &links[i];
        Factored *f = &out[i];
        for (int j = 0; j < 6; j++) f->E[j] = creal(k->E[j]);
        for (int j = 0; j < 12; j++) f->U[j] = creal(k->U[j]);
        for (int j = 0; j < 4; j++) f->Dinv[j] = creal(k->Dinv[j]);
        for (int j = 0; j < 3; j++) f->d[j] = creal(k->d[j]);
#ifdef CP_NELASTIC
        for (int j = 0; j < 3; j++) f->ey[j] = creal(k->R[j * 3 + 1]);
        for (int j = 0; j < 6; j++) f->Up[j] = creal(k->Up[j]);
        f->Dp = creal(k->Dp);
#endif
    }
}

static void real_cross(const double *a, const double *b, double *out)
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* ud = M^-1 tau (CP_NDOF values each): articulate's and accelerate's passes on the factored
 * links, their forces tau alone. */
static void solve_mass(const Factored *links, const double *tau, double *ud)
{
    const int n = CP_NLINK;
    double pA[6] = {0, 0, 0, 0, 0, 0}, uu[CP_NLINK][2], a[6] = {0, 0, 0, 0, 0, 0};
#ifdef CP_NELASTIC
    double up[CP_NLINK];
#endif
    for (int i = n - 1; i >= 0; i--) {  /* pA: what the links below carry to joint i */
        const Factored *k = &links[i];
#ifdef CP_NELASTIC
        const int e = cp_link_elastic[i];
        if (e >= 0) {
            up[i] = tau[2 * n + e] + k->ey[0] * pA[3] + k->ey[1] * pA[4] + k->ey[2] * pA[5];
            for (int r = 0; r < 6; r++) pA[r] += k->Up[r] * up[i] / k->Dp;
        }
#endif
        for (int r = 0; r < 2; r++)
            uu[i][r] = tau[r * n + i] - (k->E[r] * pA[0] + k->E[2 + r] * pA[1] + k->E[4 + r] * pA[2]);
        if (!i) break;
        double pa[6], t[3];
        for (int r = 0; r < 6; r++) {
            const double UD0 = k->U[r * 2] * k->Dinv[0] + k->U[r * 2 + 1] * k->Dinv[2];
            const double UD1 = k->U[r * 2] * k->Dinv[1] + k->U[r * 2 + 1] * k->Dinv[3];
            pa[r] = pA[r] + UD0 * uu[i][0] + UD1 * uu[i][1];
        }
        real_cross(k->d, pa + 3, t);
        for (int j = 0; j < 3; j++) pA[j] = pa[j] + t[j], pA[3 + j] = pa[3 + j];
    }
    for (int i = 0; i < n; i++) {
        const Factored *k = &links[i];
        double t[3], rhs[2];
        real_cross(k->d, a, t);
        for (int j = 0; j < 3; j++) a[3 + j] -= t[j];
        for (int r = 0; r < 2; r++) {
            rhs[r] = uu[i][r];
            for (int j = 0; j < 6; j++) rhs[r] -= k->U[j * 2 + r] * a[j];
        }
        const double u0 = k->Dinv[0] * rhs[0] + k->Dinv[1] * rhs[1];
        const double u1 = k->Dinv[2] * rhs[0] + k->Dinv[3] * rhs[1];
        for (int j = 0; j < 3; j++) a[j] += k->E[j * 2] * u0 + k->E[j * 2 + 1] * u1;
        ud[i] = u0, ud[n + i] = u1;
#ifdef CP_NELASTIC
        const int e = cp_link_elastic[i];
        if (e >= 0) {
            double rdd = up[i];
            for (int j = 0; j < 6; j++) rdd -= k->Up[j] * a[j];
            rdd /= k->Dp;
            for (int j = 0; j < 3; j++) a[3 + j] -= k->ey[j] * rdd;
            ud[2 * n + e] = rdd;
        }
#endif
    }
}

/* The first link a state moves: its joint's angles and rates, its slide's reach and rate, its
 * rope's length; -1 for a state nothing depends on (a book). */
static int first_link_moved(int state)
{
    const int n = CP_NLINK;
    int k = state < 2 * CP_NDOF ? state % CP_NDOF : -1;
    if (k >= 0 && k < 2 * n) return k % n;
#ifdef CP_NELASTIC
    if (k >= 2 * n) return cp_rope_link[cp_elastic_rope[k - 2 * n]];
#endif
#ifdef CP_NROPE
    for (int r = 0; r < CP_NROPE; r++)
        if (cp_rope_state[r] == state) return cp_rope_link[r];
#endif
    return -1;
}

/* J (CP_NSTATE^2, row-major) at (x, p), p the core's (CP_PSIZE), step the complex step's size;
 * CP_OK, or the right-hand side's status there, its model's pivot ratio and bad dof in
 * *model_out. */
static int chain_jacobian(const double *x, const double *p, double step, double *J,
                          cp_model *model_out)
{
    const int n = CP_NLINK, N = CP_NSTATE;
    cp_real xc[CP_NSTATE], pc[CP_PSIZE], rates[CP_NSTATE], ud[CP_NDOF], tau[CP_NDOF];
    cp_real acc[CP_NLINK][6], force[CP_NLINK][6];
    for (int k = 0; k < N; k++) xc[k] = x[k], rates[k] = 0.0;
    for (int k = 0; k < CP_PSIZE; k++) pc[k] = p[k];
    cp_rope_law(xc, pc);
    cp_model model = {pc, 1.0, -1};
    Link links[CP_NLINK];
    Factored factored[CP_NLINK];
    int status = articulate(&model, xc, links);
    if (!status) status = accelerate(&model, xc, links, rates);
    model_out->pivot_ratio = model.pivot_ratio;
    model_out->bad_dof = model.bad_dof;
    if (status) return status;
    factored_of(links, factored);
    memcpy(ud, rates + CP_NDOF, sizeof ud);
    inverse_dynamics_from(links, pc, ud, 0, acc, force, tau);  /* every link's, at x */
    memset(J, 0, (size_t)N * N * sizeof(double));
    for (int k = 0; k < CP_NDOF; k++) J[k * N + CP_NDOF + k] = 1.0;  /* q' = u */
    for (int first = n - 1; first >= 0; first--)  /* the links from first on made anew */
        for (int j = 0; j < N; j++) {
            if (first_link_moved(j) != first) continue;
            double dr[CP_NDOF], column[CP_NDOF];
            xc[j] = x[j] + step * _Complex_I;
            cp_rope_law(xc, pc);
            kinematics_from(xc, pc, links, first);
            inverse_dynamics_from(links, pc, ud, first, acc, force, tau);
            for (int k = 0; k < CP_NDOF; k++) {
                cp_real r = tau[k];
#ifdef CP_DAMPING_INDEX
                if (k < 2 * n) r += pc[CP_DAMPING_INDEX + k % n] * xc[CP_NDOF + k];
#endif
#ifdef CP_NELASTIC
                if (k >= 2 * n) r += pc[cp_elastic_law[k - 2 * n]];
#endif
                dr[k] = -cimag(r) / step;
            }
            solve_mass(factored, dr, column);
            for (int k = 0; k < CP_NDOF; k++) {
                J[(CP_NDOF + k) * N + j] = column[k];
                if (!isfinite(column[k])) {
                    model_out->bad_dof = k;
                    return CP_NONFINITE;
                }
            }
#ifdef CP_NWORK
            cp_real dx[CP_NSTATE], dW[CP_NWORK];  /* the books' rates along the column */
            for (int k = 0; k < N; k++) dx[k] = rates[k];
            for (int k = 0; k < CP_NDOF; k++)
                dx[k] = xc[CP_NDOF + k], dx[CP_NDOF + k] = ud[k] + step * column[k] * _Complex_I;
            work_rates(xc, pc, links, dx, dW);
            for (int w = 0; w < CP_NWORK; w++) J[(2 * CP_NDOF + w) * N + j] = cimag(dW[w]) / step;
#endif
            xc[j] = x[j];
        }
    return CP_OK;
}
#endif

void cp_mass_forcing(const cp_real *x, const cp_real *p, cp_real *M, cp_real *F)
{
    Link links[CP_NLINK];
    cp_real ud[CP_NDOF] = {0}, tau[CP_NDOF];
    kinematics(x, p, links);
    inverse_dynamics(links, p, ud, F);
    for (int k = 0; k < CP_NDOF; k++) F[k] = -F[k];
    for (int c = 0; c < CP_NDOF; c++) {
        ud[c] = 1.0;
        inverse_dynamics(links, p, ud, tau);
        ud[c] = 0.0;
        for (int r = 0; r < CP_NDOF; r++) M[r * CP_NDOF + c] = tau[r] + F[r];
    }
#ifdef CP_DAMPING_INDEX
    /* the joints' damping, -c (omega, delta) (articulate) */
    for (int k = 0; k < 2 * CP_NLINK; k++) F[k] -= p[CP_DAMPING_INDEX + k % CP_NLINK] * x[CP_NDOF + k];
#endif
#ifdef CP_NELASTIC
    /* each elastic rope's pull on its bob: -T on its slide */
    for (int e = 0; e < CP_NELASTIC; e++) F[2 * CP_NLINK + e] -= p[cp_elastic_law[e]];
#endif
}

#if CP_OUTPUT_POSES
/* Orientation quaternion (w, x, y, z) of a link: its parent's times qx(beta) qz(alpha). */
static void quaternion(const cp_real parent[4], cp_real a, cp_real b, cp_real q[4])
{
    const cp_real ca = cos(a / 2), sa = sin(a / 2), cb = cos(b / 2), sb = sin(b / 2);
    const cp_real rel[4] = {cb * ca, sb * ca, -sb * sa, cb * sa};
    const cp_real w1 = parent[0], x1 = parent[1], y1 = parent[2], z1 = parent[3];
    const cp_real w2 = rel[0], x2 = rel[1], y2 = rel[2], z2 = rel[3];
    q[0] = w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2;
    q[1] = w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2;
    q[2] = w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2;
    q[3] = w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2;
}
#endif

#if CP_OUTPUT_ENERGY || defined(CP_ENERGY_JUMPS)
/* The chain's energy from its links' kinematics: kinetic, relative to the pivot, and potential
 * (zero at Y = 0). */
static cp_real energy_of(const cp_real *x, const Link *links, const cp_real *p)
{
    const cp_real g = p[CP_G_INDEX];
    cp_real energy = 0;
    (void)x;
#ifdef CP_NELASTIC
    for (int e = 0; e < CP_NELASTIC; e++) energy += strain_energy(e, x, p);
#endif
    for (int i = 0; i < CP_NLINK; i++) {
        const Link *k = &links[i];
        const cp_link_params *lp = &cp_links[i];
        cp_real wr[3];
        cross(k->w, k->r, wr);
        if (lp->M >= 0) {
            cp_real Ic[9], v[3], Iw[3], mass = p[lp->M];
            central_inertia(k, p, lp, Ic);
            for (int j = 0; j < 3; j++) v[j] = k->vel[j] + wr[j] / 2;
            mul3(Ic, k->w, 1, Iw);
            energy += 0.5 * mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                      + 0.5 * (k->w[0] * Iw[0] + k->w[1] * Iw[1] + k->w[2] * Iw[2])
                      + mass * g * (k->pos[1] + k->r[1] / 2);
        }
        if (lp->m >= 0) {
            cp_real v[3], mass = p[lp->m];
            for (int j = 0; j < 3; j++) v[j] = k->vel[j] + wr[j] + k->s[j];
            energy += 0.5 * mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                      + mass * g * (k->pos[1] + k->r[1]);
        }
    }
    return energy;
}
#endif

#ifdef CP_ENERGY_JUMPS
void cp_energy(const cp_real *x, const cp_real *p, cp_real *E)
{
    Link links[CP_NLINK];
    kinematics(x, p, links);
    *E = energy_of(x, links, p);
}
#endif

void cp_outputs(const cp_real *x, const cp_real *p, const cp_real *dx, cp_real *y)
{
    const int n = CP_NLINK;
    Link links[CP_NLINK];
    kinematics(x, p, links);
    cp_real *out = y;
    (void)n, (void)out, (void)dx;
#if CP_OUTPUT_BOBS
    for (int i = 0; i < n; i++)
        if (cp_links[i].m >= 0)
            for (int j = 0; j < 3; j++) *out++ = links[i].pos[j] + links[i].r[j];
#endif
#if CP_OUTPUT_POSES
    cp_real q[4] = {1, 0, 0, 0};
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < 3; j++) *out++ = links[i].pos[j] + links[i].r[j] / 2;
        quaternion(q, x[i], x[n + i], q);
        for (int j = 0; j < 4; j++) *out++ = q[j];
    }
#endif
#if CP_OUTPUT_ENERGY
    *out++ = energy_of(x, links, p);
#endif
#if defined(CP_NROPE) || CP_PIVOT_INDEX >= 0
    cp_real hang[CP_NLINK][3];
    hanging(p, links, dx, hang);
#endif
#if CP_PIVOT_INDEX >= 0
    for (int j = 0; j < 3; j++) *out++ = -hang[0][j];  /* the support holds all that hangs */
#endif
#ifdef CP_NROPE
    out += 9 * (CP_PIVOT_INDEX >= 0);  /* F_free and M_app: dynamics.c's */
    /* each rope's tension, then its winch's power, then each elastic rope's stretch and taut
       margin */
    cp_real T[CP_NROPE];
    tensions(p, links, (const cp_real(*)[3])hang, T);
    for (int k = 0; k < CP_NROPE; k++) *out++ = T[k];
    for (int k = 0; k < CP_NROPE; k++) *out++ = hoist_power(k, x, p, T);
#endif
#ifdef CP_NELASTIC
    for (int e = 0; e < CP_NELASTIC; e++) *out++ = x[cp_elastic_reach[e]] - x[cp_rope_state[cp_elastic_rope[e]]];
    for (int e = 0; e < CP_NELASTIC; e++) *out++ = p[cp_elastic_law[e] + 2];
#endif
}

#endif
