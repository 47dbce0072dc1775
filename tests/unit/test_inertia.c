/*
 * Unit tests of loadid/inertia.h: phi (eq. 5) <-> mass, COM and inertia
 * about the COM, the physical-consistency flags, the distal-part
 * subtraction and the relative error of eq. (37).
 *
 * Every expected value is computed here independently of the library: the
 * parallel-axis theorem I_S = I_C + m (c.c E - c c^T) by hand, box inertias
 * from the textbook formula (cross-checked against an equivalent set of
 * point masses), eigenvalues by a small Jacobi iteration.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <string.h>

#include "dataset.h"
#include "random_util.h"

_Static_assert(sizeof(loadid_real_t) == sizeof(double), "these tests link the double core");

#define REL_TOL 1e-12
#define N_RANDOM_BODIES 2000

#define ALL_FLAGS                                                                        \
    (LOADID_PHYS_MASS_NOT_POSITIVE | LOADID_PHYS_INERTIA_NOT_PD | LOADID_PHYS_TRIANGLE | \
     LOADID_PHYS_PSEUDO_INERTIA_NOT_PD)

#define ASSERT_FLAGS(got, want, what)                                                     \
    do {                                                                                  \
        const int got_f_ = (got), want_f_ = (want);                                       \
        if (got_f_ != want_f_) {                                                          \
            print_error("%s: violations 0x%x, expected 0x%x\n", (what), (unsigned)got_f_, \
                        (unsigned)want_f_);                                               \
            fail();                                                                       \
        }                                                                                 \
    } while (0)

typedef double mat3_t[3][3];

/* A rigid body as the test knows it: the truth behind a phi. */
typedef struct {
    double mass;         /* [kg] */
    double com[3];       /* [m] in S */
    double principal[3]; /* ascending [kg m^2] */
    mat3_t rot;          /* principal axes in S */
    mat3_t inertia_com;  /* R diag(principal) R^T [kg m^2] */
} body_t;

/* ---------------------------------------------------------------- helpers */

static void sort3(double v[3]) {
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2 - i; ++j)
            if (v[j] > v[j + 1]) {
                const double t = v[j];
                v[j] = v[j + 1];
                v[j + 1] = t;
            }
}

static double max_abs(const double *v, int n) {
    double m = 0.0;
    for (int i = 0; i < n; ++i)
        if (fabs(v[i]) > m) m = fabs(v[i]);
    return m;
}

/* out = R diag(d) R^T */
static void rotate_diag(const mat3_t R, const double d[3], mat3_t out) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            out[i][j] = 0.0;
            for (int k = 0; k < 3; ++k) out[i][j] += R[i][k] * d[k] * R[j][k];
        }
}

/* m (c.c E - c c^T): the parallel-axis (Steiner) term. */
static void steiner(double m, const double c[3], mat3_t out) {
    const double cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[i][j] = m * ((i == j ? cc : 0.0) - c[i] * c[j]);
}

static void sym_to6(const mat3_t I, double v[6]) {
    v[0] = I[0][0];
    v[1] = I[0][1];
    v[2] = I[0][2];
    v[3] = I[1][1];
    v[4] = I[1][2];
    v[5] = I[2][2];
}

/* phi of eq. (5) about the origin of S from mass, COM and inertia about the
 * COM: I_S = I_C + m (c.c E - c c^T), computed here, not by the library. */
static void phi_by_hand(double m, const double c[3], const mat3_t Ic, double phi[10]) {
    mat3_t St, Is;
    steiner(m, c, St);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Is[i][j] = Ic[i][j] + St[i][j];
    phi[0] = m;
    for (int i = 0; i < 3; ++i) phi[1 + i] = m * c[i];
    sym_to6(Is, phi + 4);
}

static void body_phi(const body_t *b, double phi[10]) {
    phi_by_hand(b->mass, b->com, b->inertia_com, phi);
}

/* A body with given principal moments p (any order, any sign: also used
 * for impossible "bodies"), random orientation, mass and COM. */
static void body_with_moments(loadid_rng_t *rng, double mass, const double p[3], body_t *b) {
    b->mass = mass;
    uniform_vec3(rng, 0.15, b->com);
    random_rotation(rng, b->rot);
    rotate_diag(b->rot, p, b->inertia_com);
    memcpy(b->principal, p, sizeof b->principal);
    sort3(b->principal);
}

/* A random, physically valid body: mass 0.1..5 kg, COM within +-0.15 m,
 * principal moments from the second moments s_i = m r_i^2 of a real mass
 * distribution (p_1 = s_2 + s_3, ...: the triangle inequality holds
 * strictly). r_i in [0.02, 0.15] m keeps the parallel-axis term m |c|^2
 * within about 100 times I_C, so the round trip loses at most two digits. */
static void random_body(loadid_rng_t *rng, body_t *b) {
    const double m = uniform_in(rng, 0.1, 5.0);
    double p[3];
    random_principal_moments(rng, m, p);
    body_with_moments(rng, m, p, b);
}

/* Eigenvalues of a symmetric 3x3 matrix, ascending, by cyclic Jacobi
 * rotations (independent of the library's Eigen solver). */
static void jacobi_eigenvalues(const mat3_t M, double ev[3]) {
    mat3_t a;
    memcpy(a, M, sizeof a);
    double norm2 = 0.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) norm2 += a[i][j] * a[i][j];
    for (int sweep = 0; sweep < 60; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        if (off <= 1e-40 * norm2) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0) continue;
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t;
                if (fabs(theta) > 1e150)
                    t = 0.5 / theta;
                else
                    t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; ++k) { /* columns p, q */
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) { /* rows p, q */
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
            }
    }
    for (int i = 0; i < 3; ++i) ev[i] = a[i][i];
    sort3(ev);
}

static void to_physical_ok(const double phi[10], loadid_physical_t *out) {
    memset(out, 0x5A, sizeof *out); /* every field must be written */
    assert_int_equal(loadid_phi_to_physical(phi, out), 0);
}

/* ------------------------------------------------------------ round trip */

/* phi_from_physical then phi_to_physical gives back mass, COM, inertia about
 * the COM and the principal moments chosen, and flags nothing. */
static void test_round_trip_random_bodies(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27001ULL);
    double worst_phi = 0, worst_mass = 0, worst_com = 0, worst_ic = 0, worst_p = 0;
    for (int k = 0; k < N_RANDOM_BODIES; ++k) {
        body_t b;
        random_body(&rng, &b);
        double ic6[6], phi_lib[10], phi_hand[10];
        sym_to6(b.inertia_com, ic6);
        assert_int_equal(loadid_phi_from_physical(b.mass, b.com, ic6, phi_lib), 0);
        body_phi(&b, phi_hand);
        /* from_physical agrees with the hand-made parallel axis */
        const double phi_scale[10] = {b.mass,
                                      b.mass * 0.15,
                                      b.mass * 0.15,
                                      b.mass * 0.15,
                                      max_abs(phi_hand + 4, 6),
                                      max_abs(phi_hand + 4, 6),
                                      max_abs(phi_hand + 4, 6),
                                      max_abs(phi_hand + 4, 6),
                                      max_abs(phi_hand + 4, 6),
                                      max_abs(phi_hand + 4, 6)};
        for (int i = 0; i < 10; ++i) {
            const double e = fabs(phi_lib[i] - phi_hand[i]) / phi_scale[i];
            if (e > worst_phi) worst_phi = e;
            ASSERT_CLOSE(phi_lib[i], phi_hand[i], REL_TOL * phi_scale[i], "phi_from_physical");
        }

        loadid_physical_t ph;
        to_physical_ok(phi_lib, &ph);
        ASSERT_FLAGS(ph.violations, 0, "valid random body");
        ASSERT_CLOSE(ph.mass, b.mass, REL_TOL * b.mass, "mass");
        const double com_scale = max_abs(b.com, 3);
        for (int i = 0; i < 3; ++i) {
            ASSERT_CLOSE(ph.com[i], b.com[i], REL_TOL * com_scale, "com");
            if (fabs(ph.com[i] - b.com[i]) / com_scale > worst_com)
                worst_com = fabs(ph.com[i] - b.com[i]) / com_scale;
        }
        if (fabs(ph.mass - b.mass) / b.mass > worst_mass)
            worst_mass = fabs(ph.mass - b.mass) / b.mass;
        /* Inertia and eigenvalues: relative to the largest principal moment
         * (the norm of the tensor; Weyl's bound for the eigenvalues). */
        const double iscale = b.principal[2];
        for (int i = 0; i < 6; ++i) {
            ASSERT_CLOSE(ph.inertia_com[i], ic6[i], REL_TOL * iscale, "inertia_com");
            if (fabs(ph.inertia_com[i] - ic6[i]) / iscale > worst_ic)
                worst_ic = fabs(ph.inertia_com[i] - ic6[i]) / iscale;
        }
        for (int i = 0; i < 3; ++i) {
            ASSERT_CLOSE(ph.principal[i], b.principal[i], REL_TOL * iscale, "principal moment");
            if (fabs(ph.principal[i] - b.principal[i]) / iscale > worst_p)
                worst_p = fabs(ph.principal[i] - b.principal[i]) / iscale;
        }
    }
    print_message(
        "round trip, %d bodies: worst relative error phi %.3g, mass %.3g, com %.3g, "
        "inertia_com %.3g, principal %.3g\n",
        N_RANDOM_BODIES, worst_phi, worst_mass, worst_com, worst_ic, worst_p);
}

/* ------------------------------------------------------------ solid box */

/* A solid box of mass m and sides a, b, c about its centre, in its own
 * axes: diag(m(b^2+c^2)/12, m(a^2+c^2)/12, m(a^2+b^2)/12). */
static void box_moments(double m, const double sides[3], double d[3]) {
    const double a2 = sides[0] * sides[0], b2 = sides[1] * sides[1], c2 = sides[2] * sides[2];
    d[0] = m * (b2 + c2) / 12.0;
    d[1] = m * (a2 + c2) / 12.0;
    d[2] = m * (a2 + b2) / 12.0;
}

/* The same box as 8 point masses m/8 at c0 + R (+-a, +-b, +-c) / (2 sqrt 3):
 * equal first and second moments, so equal phi. I_S = sum m_k (r.r E - r r^T). */
static void box_phi_point_masses(double m, const double sides[3], const double c0[3],
                                 const mat3_t R, double phi[10]) {
    mat3_t Is = {{0}};
    double h[3] = {0, 0, 0};
    const double k = 1.0 / (2.0 * sqrt(3.0));
    for (int corner = 0; corner < 8; ++corner) {
        const double local[3] = {((corner & 1) ? 1 : -1) * sides[0] * k,
                                 ((corner & 2) ? 1 : -1) * sides[1] * k,
                                 ((corner & 4) ? 1 : -1) * sides[2] * k};
        double r[3];
        for (int i = 0; i < 3; ++i)
            r[i] = c0[i] + R[i][0] * local[0] + R[i][1] * local[1] + R[i][2] * local[2];
        mat3_t St;
        steiner(m / 8.0, r, St);
        for (int i = 0; i < 3; ++i) {
            h[i] += m / 8.0 * r[i];
            for (int j = 0; j < 3; ++j) Is[i][j] += St[i][j];
        }
    }
    phi[0] = m;
    for (int i = 0; i < 3; ++i) phi[1 + i] = h[i];
    sym_to6(Is, phi + 4);
}

static void check_box(double m, const double sides[3], const double c0[3], const mat3_t R) {
    double d[3], phi[10], phi_pm[10], expected[3];
    mat3_t Ic;
    box_moments(m, sides, d);
    rotate_diag(R, d, Ic);
    phi_by_hand(m, c0, Ic, phi);

    /* The test's own two routes to phi agree (guards the test itself). */
    box_phi_point_masses(m, sides, c0, R, phi_pm);
    const double iscale = max_abs(phi + 4, 6);
    for (int i = 0; i < 10; ++i)
        ASSERT_CLOSE(phi_pm[i], phi[i],
                     1e-13 * (i == 0  ? m
                              : i < 4 ? m * 0.15
                                      : iscale),
                     "box: point masses vs formula");

    memcpy(expected, d, sizeof expected);
    sort3(expected);
    double ev[3];
    jacobi_eigenvalues(Ic, ev); /* guards the Jacobi helper */
    for (int i = 0; i < 3; ++i)
        ASSERT_CLOSE(ev[i], expected[i], REL_TOL * expected[2], "box: Jacobi eigenvalue");

    loadid_physical_t ph;
    to_physical_ok(phi, &ph);
    ASSERT_FLAGS(ph.violations, 0, "solid box");
    ASSERT_CLOSE(ph.mass, m, REL_TOL * m, "box mass");
    for (int i = 0; i < 3; ++i) ASSERT_CLOSE(ph.com[i], c0[i], REL_TOL * 0.15, "box com");
    for (int i = 0; i < 3; ++i)
        ASSERT_CLOSE(ph.principal[i], expected[i], REL_TOL * expected[2], "box principal moment");
}

static void test_solid_box(void **state) {
    (void)state;
    /* One by the numbers: 2 kg, 0.1 x 0.2 x 0.3 m, axes of S. Principal
     * moments 2 (0.04 + 0.09) / 12, 2 (0.01 + 0.09) / 12, 2 (0.01 + 0.04) / 12. */
    {
        const double sides[3] = {0.1, 0.2, 0.3}, c0[3] = {0.05, -0.02, 0.1};
        const mat3_t eye = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        check_box(2.0, sides, c0, eye);
        double d[3], phi[10];
        mat3_t Ic;
        box_moments(2.0, sides, d);
        rotate_diag(eye, d, Ic);
        phi_by_hand(2.0, c0, Ic, phi);
        loadid_physical_t ph;
        to_physical_ok(phi, &ph);
        ASSERT_CLOSE(ph.principal[0], 0.1 / 12.0, 1e-15, "box 0.1x0.2x0.3: I_min");
        ASSERT_CLOSE(ph.principal[1], 0.2 / 12.0, 1e-15, "box 0.1x0.2x0.3: I_mid");
        ASSERT_CLOSE(ph.principal[2], 0.26 / 12.0, 1e-15, "box 0.1x0.2x0.3: I_max");
    }
    /* Random boxes, rotated and moved; including cubes (triple eigenvalue). */
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27002ULL);
    for (int k = 0; k < 500; ++k) {
        const double m = uniform_in(&rng, 0.1, 5.0);
        double sides[3], c0[3];
        mat3_t R;
        for (int i = 0; i < 3; ++i) sides[i] = uniform_in(&rng, 0.02, 0.3);
        if (k % 10 == 0) sides[1] = sides[2] = sides[0];
        uniform_vec3(&rng, 0.15, c0);
        random_rotation(&rng, R);
        check_box(m, sides, c0, R);
    }
}

/* ------------------------------------------------------ violation flags */

static void physical_of_moments(loadid_rng_t *rng, double mass, const double p[3],
                                loadid_physical_t *ph, body_t *b) {
    double phi[10];
    body_with_moments(rng, mass, p, b);
    body_phi(b, phi);
    to_physical_ok(phi, ph);
}

/* m <= 0: no body. The pseudo-inertia J has J(4,4) = m <= 0, so it cannot be
 * positive definite either; the COM is reported as 0. */
static void test_violation_mass_not_positive(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27003ULL);
    body_t b;
    random_body(&rng, &b);
    double phi[10];
    body_phi(&b, phi);
    const double masses[] = {0.0, -1e-9, -1.0};
    for (size_t i = 0; i < sizeof masses / sizeof masses[0]; ++i) {
        double bad[10];
        memcpy(bad, phi, sizeof bad);
        bad[0] = masses[i];
        if (masses[i] == 0.0) bad[1] = bad[2] = bad[3] = 0.0;
        loadid_physical_t ph;
        to_physical_ok(bad, &ph);
        if (!(ph.violations & LOADID_PHYS_MASS_NOT_POSITIVE) ||
            !(ph.violations & LOADID_PHYS_PSEUDO_INERTIA_NOT_PD)) {
            print_error("mass %g: violations 0x%x lack MASS_NOT_POSITIVE and/or PSEUDO\n",
                        masses[i], (unsigned)ph.violations);
            fail();
        }
        assert_true((ph.violations & ~ALL_FLAGS) == 0);
        ASSERT_CLOSE(ph.mass, masses[i], 0.0, "reported mass");
        for (int j = 0; j < 3; ++j) ASSERT_CLOSE(ph.com[j], 0.0, 0.0, "com when mass <= 0");
    }
}

/* Principal moments (1, 1, 3) 1e-3 kg m^2: positive definite, but
 * I1 + I2 < I3. For m > 0 the pseudo-inertia J is congruent to
 * diag(Sigma_C, m), Sigma_C = 0.5 tr(I_C) E - I_C with eigenvalues
 * (I_j + I_k - I_i) / 2, here (1.5, 1.5, -0.5) 1e-3: J is indefinite. */
static void test_violation_triangle(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27004ULL);
    const double p[3] = {1e-3, 1e-3, 3e-3};
    for (int k = 0; k < 50; ++k) {
        loadid_physical_t ph;
        body_t b;
        physical_of_moments(&rng, uniform_in(&rng, 0.1, 5.0), p, &ph, &b);
        ASSERT_FLAGS(ph.violations, LOADID_PHYS_TRIANGLE | LOADID_PHYS_PSEUDO_INERTIA_NOT_PD,
                     "principal (1, 1, 3) 1e-3");
        for (int i = 0; i < 3; ++i)
            ASSERT_CLOSE(ph.principal[i], b.principal[i], REL_TOL * 3e-3, "principal (1, 1, 3)");
    }
}

/* A negative principal moment: not positive definite; and it implies
 * I1 + I2 < I2 <= I3, so the triangle and pseudo-inertia flags too. */
static void test_violation_negative_moment(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27005ULL);
    const double p[3] = {2e-3, -0.5e-3, 3e-3};
    for (int k = 0; k < 50; ++k) {
        loadid_physical_t ph;
        body_t b;
        physical_of_moments(&rng, uniform_in(&rng, 0.1, 5.0), p, &ph, &b);
        ASSERT_FLAGS(
            ph.violations,
            LOADID_PHYS_INERTIA_NOT_PD | LOADID_PHYS_TRIANGLE | LOADID_PHYS_PSEUDO_INERTIA_NOT_PD,
            "principal (-0.5, 2, 3) 1e-3");
        ASSERT_CLOSE(ph.principal[0], -0.5e-3, REL_TOL * 3e-3, "negative principal moment");
    }
}

/* Borderline: a thin rod (1e-12, 1, 1) 1e-3 kg m^2, i.e. 1e-15 kg m^2 about
 * its axis, 1e-12 of the others. That is below the header's relative
 * tolerance (1e-9 in double), so the library treats it as the line-mass
 * limit: inertia not positive definite, pseudo-inertia not positive definite
 * (Sigma_C has eigenvalue I1/2 ~ 0), while the triangle I1 + I2 >= I3 holds.
 * A rod 1e8 times thicker, (1e-4, 1, 1) 1e-3, is a valid body. */
static void test_thin_rod_borderline(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27006ULL);
    const double rod[3] = {1e-15, 1e-3, 1e-3};
    const double thicker[3] = {1e-7, 1e-3, 1e-3};
    /* Axis-aligned at the origin (no rounding from rotation), then rotated
     * and moved. */
    {
        const double phi[10] = {1.0, 0, 0, 0, rod[0], 0, 0, rod[1], 0, rod[2]};
        loadid_physical_t ph;
        to_physical_ok(phi, &ph);
        ASSERT_FLAGS(ph.violations, LOADID_PHYS_INERTIA_NOT_PD | LOADID_PHYS_PSEUDO_INERTIA_NOT_PD,
                     "thin rod (1e-12, 1, 1) 1e-3 at the origin");
        ASSERT_CLOSE(ph.principal[0], 1e-15, 1e-20, "thin rod: axial moment");
    }
    for (int k = 0; k < 50; ++k) {
        loadid_physical_t ph;
        body_t b;
        physical_of_moments(&rng, 1.0, rod, &ph, &b);
        ASSERT_FLAGS(ph.violations, LOADID_PHYS_INERTIA_NOT_PD | LOADID_PHYS_PSEUDO_INERTIA_NOT_PD,
                     "thin rod (1e-12, 1, 1) 1e-3, rotated and moved");
        physical_of_moments(&rng, 1.0, thicker, &ph, &b);
        ASSERT_FLAGS(ph.violations, 0, "rod (1e-4, 1, 1) 1e-3, rotated and moved");
        ASSERT_CLOSE(ph.principal[0], 1e-7, 1e-6 * 1e-7, "rod: axial moment");
    }
}

/* The flags against the principal moments the body was built with, for
 * random tensors that may be valid or not (margins of at least 1e-3 of the
 * largest moment, away from the tolerance band): for m > 0,
 *   INERTIA_NOT_PD  <=> I1 <= 0,   TRIANGLE <=> I1 + I2 < I3,
 *   PSEUDO_NOT_PD   <=> not (I1 + I2 > I3)  (Sigma_C = diag((Ij+Ik-Ii)/2)). */
static void test_flags_match_principal_moments(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27007ULL);
    int n_checked = 0, n_valid = 0, n_triangle = 0, n_not_pd = 0;
    for (int k = 0; k < 4000; ++k) {
        const double m = uniform_in(&rng, 0.1, 5.0);
        double p[3];
        for (int i = 0; i < 3; ++i) p[i] = uniform_in(&rng, -0.3, 1.0);
        double top = max_abs(p, 3);
        if (top < 1e-6) continue;
        const double scale = m * 0.02 * uniform_in(&rng, 0.2, 1.0) / top;
        for (int i = 0; i < 3; ++i) p[i] *= scale;
        double s[3];
        memcpy(s, p, sizeof s);
        sort3(s);
        const double margin = s[0] + s[1] - s[2];
        const double tol = 1e-3 * fabs(s[2]);
        if (fabs(margin) < tol || fabs(s[0]) < tol) continue;
        int want = 0;
        if (s[0] <= 0) want |= LOADID_PHYS_INERTIA_NOT_PD;
        if (margin < 0) want |= LOADID_PHYS_TRIANGLE | LOADID_PHYS_PSEUDO_INERTIA_NOT_PD;
        loadid_physical_t ph;
        body_t b;
        physical_of_moments(&rng, m, p, &ph, &b);
        if (ph.violations != want) {
            print_error(
                "sample %d: m %g, principal %.6g %.6g %.6g: violations 0x%x, expected "
                "0x%x\n",
                k, m, s[0], s[1], s[2], (unsigned)ph.violations, (unsigned)want);
            fail();
        }
        ++n_checked;
        n_valid += want == 0;
        n_triangle += (want & LOADID_PHYS_TRIANGLE) != 0;
        n_not_pd += (want & LOADID_PHYS_INERTIA_NOT_PD) != 0;
    }
    print_message("flags vs principal moments: %d tensors (%d valid, %d triangle, %d not PD)\n",
                  n_checked, n_valid, n_triangle, n_not_pd);
    /* The sample must cover every case. */
    assert_true(n_valid > 100 && n_triangle > 100 && n_not_pd > 100);
}

/* ------------------------------------------------- the paper's load o1 */

/* Section V.A, o1: m = 1 kg, m c = (-43.5, 28.5, 22.5) kg mm, I_S as given.
 * Its inertia about the COM is computed here by hand and its eigenvalues by
 * Jacobi; the library's report and flags must agree with them. Whether o1
 * is physically consistent is printed; the flags are asserted against the
 * independent triangle check (not against a wish). */
static void test_paper_load_o1(void **state) {
    (void)state;
    const double *phi = loadid_synth_phi_o1;
    const double m = phi[0];
    const double c[3] = {phi[1] / m, phi[2] / m, phi[3] / m};
    const mat3_t Is = {
        {phi[4], phi[5], phi[6]}, {phi[5], phi[7], phi[8]}, {phi[6], phi[8], phi[9]}};
    mat3_t St, Ic;
    steiner(m, c, St);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Ic[i][j] = Is[i][j] - St[i][j];
    double p[3], ic6[6];
    jacobi_eigenvalues(Ic, p);
    sym_to6(Ic, ic6);

    loadid_physical_t ph;
    to_physical_ok(phi, &ph);
    print_message("o1: mass %.6g kg, com [%.6g %.6g %.6g] m\n", ph.mass, ph.com[0], ph.com[1],
                  ph.com[2]);
    print_message("o1: inertia_com [xx xy xz yy yz zz] = [%.6g %.6g %.6g %.6g %.6g %.6g] kg m^2\n",
                  ph.inertia_com[0], ph.inertia_com[1], ph.inertia_com[2], ph.inertia_com[3],
                  ph.inertia_com[4], ph.inertia_com[5]);
    print_message(
        "o1: principal moments [%.6g %.6g %.6g] kg m^2, I1 + I2 - I3 = %.4g kg m^2 "
        "(%.3g %% of I3), violations 0x%x\n",
        ph.principal[0], ph.principal[1], ph.principal[2],
        ph.principal[0] + ph.principal[1] - ph.principal[2],
        100.0 * (ph.principal[0] + ph.principal[1] - ph.principal[2]) / ph.principal[2],
        (unsigned)ph.violations);

    ASSERT_CLOSE(ph.mass, 1.0, 0.0, "o1 mass");
    for (int i = 0; i < 3; ++i) ASSERT_CLOSE(ph.com[i], c[i], 1e-15, "o1 com");
    for (int i = 0; i < 6; ++i) ASSERT_CLOSE(ph.inertia_com[i], ic6[i], 1e-17, "o1 inertia_com");
    for (int i = 0; i < 3; ++i) ASSERT_CLOSE(ph.principal[i], p[i], 1e-17, "o1 principal");

    const double margin = p[0] + p[1] - p[2];
    int want = 0;
    if (p[0] <= 1e-9 * p[2]) want |= LOADID_PHYS_INERTIA_NOT_PD;
    if (margin < -1e-9 * p[2]) want |= LOADID_PHYS_TRIANGLE;
    if (!(margin > 1e-9 * p[2])) want |= LOADID_PHYS_PSEUDO_INERTIA_NOT_PD;
    if (want != 0)
        print_message(
            "o1 is NOT physically consistent as published: its principal moments "
            "about the COM break I1 + I2 >= I3 by %.4g kg m^2\n",
            -margin);
    ASSERT_FLAGS(ph.violations, want, "o1 flags vs the independent triangle check");
}

/* --------------------------------------------- distal part compensation */

/* Rigidly joined bodies add in phi (eq. 5 is linear in the mass
 * distribution): the load is the total minus the distal part, and the
 * composite's COM is the mass-weighted mean of the two. */
static void test_distal_subtraction(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x1E27008ULL);
    double worst_sub = 0.0, worst_com = 0.0, worst_ic = 0.0;
    for (int k = 0; k < 1000; ++k) {
        body_t b1, b2;
        random_body(&rng, &b1);
        random_body(&rng, &b2);
        double phi1[10], phi2[10], total[10], out[10];
        body_phi(&b1, phi1);
        body_phi(&b2, phi2);
        for (int i = 0; i < 10; ++i) total[i] = phi1[i] + phi2[i];

        memset(out, 0x5A, sizeof out);
        assert_int_equal(loadid_phi_subtract(total, phi2, out), 0);
        for (int i = 0; i < 10; ++i) {
            ASSERT_CLOSE(out[i], total[i] - phi2[i], 0.0, "subtract: measured - distal");
            const double scale = fabs(phi1[i]) + fabs(phi2[i]);
            ASSERT_CLOSE(out[i], phi1[i], REL_TOL * scale, "subtract: total - B2 == B1");
            if (scale > 0 && fabs(out[i] - phi1[i]) / scale > worst_sub)
                worst_sub = fabs(out[i] - phi1[i]) / scale;
        }
        /* out may alias measured */
        double alias[10];
        memcpy(alias, total, sizeof alias);
        assert_int_equal(loadid_phi_subtract(alias, phi2, alias), 0);
        assert_memory_equal(alias, out, sizeof out);

        /* The composite, independently: COM = (m1 c1 + m2 c2) / (m1 + m2),
         * I_C = sum_b (I_Cb + m_b ((c_b - c).(c_b - c) E - ...)). */
        const double M = b1.mass + b2.mass;
        double c[3], d1[3], d2[3];
        for (int i = 0; i < 3; ++i) c[i] = (b1.mass * b1.com[i] + b2.mass * b2.com[i]) / M;
        for (int i = 0; i < 3; ++i) {
            d1[i] = b1.com[i] - c[i];
            d2[i] = b2.com[i] - c[i];
        }
        mat3_t S1, S2, Ic;
        steiner(b1.mass, d1, S1);
        steiner(b2.mass, d2, S2);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                Ic[i][j] = b1.inertia_com[i][j] + S1[i][j] + b2.inertia_com[i][j] + S2[i][j];
        double ic6[6], p[3];
        sym_to6(Ic, ic6);
        jacobi_eigenvalues(Ic, p);

        loadid_physical_t ph;
        to_physical_ok(total, &ph);
        ASSERT_FLAGS(ph.violations, 0, "composite of two bodies");
        ASSERT_CLOSE(ph.mass, M, REL_TOL * M, "composite mass");
        for (int i = 0; i < 3; ++i) {
            ASSERT_CLOSE(ph.com[i], c[i], REL_TOL * 0.15, "composite COM");
            if (fabs(ph.com[i] - c[i]) / 0.15 > worst_com)
                worst_com = fabs(ph.com[i] - c[i]) / 0.15;
        }
        for (int i = 0; i < 6; ++i) {
            ASSERT_CLOSE(ph.inertia_com[i], ic6[i], REL_TOL * p[2], "composite inertia_com");
            if (fabs(ph.inertia_com[i] - ic6[i]) / p[2] > worst_ic)
                worst_ic = fabs(ph.inertia_com[i] - ic6[i]) / p[2];
        }
        for (int i = 0; i < 3; ++i)
            ASSERT_CLOSE(ph.principal[i], p[i], REL_TOL * p[2], "composite principal");
    }
    print_message(
        "distal: worst relative error subtract %.3g, composite COM %.3g, composite "
        "inertia_com %.3g\n",
        worst_sub, worst_com, worst_ic);
}

/* ----------------------------------------------------------- eq. (37) */

static void test_relative_error_eq37(void **state) {
    (void)state;
    /* e = |(est - truth) / truth| 100 %, by hand:
     *   1.1 vs 1     -> 10 %     2 vs 2.5 -> 20 %    -3 vs -2 -> 50 %
     *   -43.5e-3 vs -43.5e-3 -> 0 %      0 vs 0 -> 0      5 vs 0 -> +Inf
     *   -1e-3 vs 0 -> +Inf (a negative estimate of a zero truth too)
     *   1 vs -1 -> 200 % */
    const double est[8] = {1.1, 2.0, -3.0, -43.5e-3, 0.0, 5.0, -1e-3, 1.0};
    const double truth[8] = {1.0, 2.5, -2.0, -43.5e-3, 0.0, 0.0, 0.0, -1.0};
    const double want[8] = {10.0, 20.0, 50.0, 0.0, 0.0, INFINITY, INFINITY, 200.0};
    double out[8];
    memset(out, 0, sizeof out);
    assert_int_equal(loadid_relative_error(est, truth, 8, out), 0);
    for (int i = 0; i < 8; ++i) {
        if (isinf(want[i])) {
            if (!(isinf(out[i]) && out[i] > 0)) {
                print_error("element %d: got %g, expected +Inf\n", i, out[i]);
                fail();
            }
        } else {
            ASSERT_CLOSE(out[i], want[i], 1e-12 * (want[i] > 1 ? want[i] : 1.0), "eq. (37)");
        }
    }
    /* n = 0 is an empty, valid call; out untouched. */
    double untouched[1] = {-7.0};
    assert_int_equal(loadid_relative_error(est, truth, 0, untouched), 0);
    ASSERT_CLOSE(untouched[0], -7.0, 0.0, "n = 0 leaves out alone");
    /* Errors */
    assert_int_equal(loadid_relative_error(est, truth, -1, out), -EINVAL);
    assert_int_equal(loadid_relative_error(NULL, truth, 8, out), -EINVAL);
    assert_int_equal(loadid_relative_error(est, NULL, 8, out), -EINVAL);
    assert_int_equal(loadid_relative_error(est, truth, 8, NULL), -EINVAL);
}

/* ---------------------------------------------------------- bad input */

static void test_inertia_bad_input(void **state) {
    (void)state;
    const double bad_values[3] = {NAN, INFINITY, -INFINITY};
    for (int i = 0; i < 10; ++i) {
        for (int b = 0; b < 3; ++b) {
            double phi[10];
            memcpy(phi, loadid_synth_phi_o1, sizeof phi);
            phi[i] = bad_values[b];
            loadid_physical_t ph;
            const int rc = loadid_phi_to_physical(phi, &ph);
            if (rc != LOADID_E_NONFINITE) {
                print_error("phi[%d] = %g: rc %d, expected LOADID_E_NONFINITE\n", i, bad_values[b],
                            rc);
                fail();
            }
        }
    }
    loadid_physical_t ph;
    double phi[10], out[10];
    const double com[3] = {0, 0, 0}, ic[6] = {1e-3, 0, 0, 1e-3, 0, 1e-3};
    assert_int_equal(loadid_phi_to_physical(NULL, &ph), -EINVAL);
    assert_int_equal(loadid_phi_to_physical(loadid_synth_phi_o1, NULL), -EINVAL);
    assert_int_equal(loadid_phi_from_physical(1.0, NULL, ic, phi), -EINVAL);
    assert_int_equal(loadid_phi_from_physical(1.0, com, NULL, phi), -EINVAL);
    assert_int_equal(loadid_phi_from_physical(1.0, com, ic, NULL), -EINVAL);
    assert_int_equal(loadid_phi_from_physical(1.0, com, ic, phi), 0);
    assert_int_equal(loadid_phi_subtract(NULL, phi, out), -EINVAL);
    assert_int_equal(loadid_phi_subtract(phi, NULL, out), -EINVAL);
    assert_int_equal(loadid_phi_subtract(phi, phi, NULL), -EINVAL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_random_bodies),
        cmocka_unit_test(test_solid_box),
        cmocka_unit_test(test_violation_mass_not_positive),
        cmocka_unit_test(test_violation_triangle),
        cmocka_unit_test(test_violation_negative_moment),
        cmocka_unit_test(test_thin_rod_borderline),
        cmocka_unit_test(test_flags_match_principal_moments),
        cmocka_unit_test(test_paper_load_o1),
        cmocka_unit_test(test_distal_subtraction),
        cmocka_unit_test(test_relative_error_eq37),
        cmocka_unit_test(test_inertia_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
