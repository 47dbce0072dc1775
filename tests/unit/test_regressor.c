/*
 * Unit tests of the regressor (loadid/regressor.h): eq. (6), the zeroing
 * term of eqs. (7)-(9), the 16-parameter offset model [A E6], and the
 * rejection of bad input.
 *
 * The reference is loadid_synth_wrench (tools/synth), which evaluates the
 * paper's eqs. (1)-(2) directly with cross products and the full inertia
 * tensor, independently of the core's regressor. Loads are physically valid
 * bodies built here: inertia about the COM R diag(p) R^T, moved to the
 * origin of S by the parallel-axis theorem computed in this file.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <string.h>

#include "dataset.h"
#include "random_util.h"

_Static_assert(sizeof(loadid_real_t) == sizeof(double), "these tests link the double core");

#define N_RANDOM_STATES 5000
#define REL_TOL 1e-12
#define G_NORM 9.81

/* ---------------------------------------------------------------- helpers */

/* A random state of S within the ranges of the brief: spec = a - g in
 * [-20, 20] m/s^2, w in [-3, 3] rad/s, alpha in [-50, 50] rad/s^2. */
static void random_state(loadid_rng_t *rng, loadid_motion_t *m) {
    memset(m, 0, sizeof *m);
    uniform_vec3(rng, 20.0, m->spec);
    uniform_vec3(rng, 3.0, m->omega);
    uniform_vec3(rng, 50.0, m->alpha);
}

/* A random, physically valid load as phi of eq. (5) about the origin of S:
 * mass 0.1..5 kg, COM components within +-0.15 m, inertia about the COM
 * I_C = R diag(p) R^T. p comes from second moments s_i = m r_i^2 of a real
 * mass distribution (p_1 = s_2 + s_3, ...), so it obeys the triangle
 * inequality strictly. Then I_S = I_C + m (c.c E - c c^T). */
static void random_load_phi(loadid_rng_t *rng, double phi[10]) {
    const double m = uniform_in(rng, 0.1, 5.0);
    double c[3], R[3][3], p[3], Ic[3][3];
    uniform_vec3(rng, 0.15, c);
    random_principal_moments(rng, m, p);
    random_rotation(rng, R);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            Ic[i][j] = 0.0;
            for (int k = 0; k < 3; ++k) Ic[i][j] += R[i][k] * p[k] * R[j][k];
        }
    const double cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    double Is[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Is[i][j] = Ic[i][j] + m * ((i == j ? cc : 0.0) - c[i] * c[j]);
    phi[0] = m;
    for (int i = 0; i < 3; ++i) phi[1 + i] = m * c[i];
    phi[4] = Is[0][0];
    phi[5] = Is[0][1];
    phi[6] = Is[0][2];
    phi[7] = Is[1][1];
    phi[8] = Is[1][2];
    phi[9] = Is[2][2];
}

/* y = A x for a row-major 6 x ncols A, written out by hand. */
static void matvec6(const double *A, int ncols, const double *x, double y[6]) {
    for (int r = 0; r < 6; ++r) {
        double acc = 0.0;
        for (int c = 0; c < ncols; ++c) acc += A[r * ncols + c] * x[c];
        y[r] = acc;
    }
}

static double max_abs(const double *v, int n) {
    double m = 0.0;
    for (int i = 0; i < n; ++i)
        if (fabs(v[i]) > m) m = fabs(v[i]);
    return m;
}

/* max_i |a_i - b_i| / max(max_i |b_i|, 1): the brief's error measure. */
static double rel_err_wrench(const double *a, const double *b, int n) {
    double scale = max_abs(b, n);
    if (scale < 1.0) scale = 1.0;
    double e = 0.0;
    for (int i = 0; i < n; ++i) {
        const double d = fabs(a[i] - b[i]);
        if (!(d <= e)) e = d; /* NaN propagates as a failure */
    }
    return e / scale;
}

static void assert_rel_below(double err, double tol, const char *what, int sample) {
    if (!(err <= tol)) {
        print_error("%s (sample %d): relative error %.3g > %.3g\n", what, sample, err, tol);
        fail();
    }
}

static void regressor_of(const loadid_motion_t *m, double A[60]) {
    assert_int_equal(loadid_regressor(m->spec, m->omega, m->alpha, A), 0);
}

/* Eq. (7) written out from the paper, as a 6x10 matrix (zeros beyond
 * column 3: eq. 8). */
static void paper_zeroing_matrix(const double g[3], double Z[60]) {
    memset(Z, 0, 60 * sizeof *Z);
    const double gx = g[0], gy = g[1], gz = g[2];
    Z[0 * 10 + 0] = gx;
    Z[1 * 10 + 0] = gy;
    Z[2 * 10 + 0] = gz;
    Z[3 * 10 + 2] = gz;
    Z[3 * 10 + 3] = -gy;
    Z[4 * 10 + 1] = -gz;
    Z[4 * 10 + 3] = gx;
    Z[5 * 10 + 1] = gy;
    Z[5 * 10 + 2] = -gx;
}

static void random_gravity(loadid_rng_t *rng, double g[3]) {
    double n2;
    do {
        n2 = 0.0;
        for (int i = 0; i < 3; ++i) {
            g[i] = loadid_rng_normal(rng);
            n2 += g[i] * g[i];
        }
    } while (n2 < 1e-6);
    const double k = G_NORM / sqrt(n2);
    for (int i = 0; i < 3; ++i) g[i] *= k;
}

/* ------------------------------------------------------------ eq. (6) */

/* A phi of eq. (6) against eqs. (1)-(2) evaluated directly, for random
 * states and random physical loads; both through loadid_regressor_apply and
 * through a hand-written product. */
static void test_regressor_matches_newton_euler(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0001ULL);
    double worst_apply = 0.0, worst_hand = 0.0;
    for (int k = 0; k < N_RANDOM_STATES; ++k) {
        loadid_motion_t m;
        double phi[10], A[60], y_apply[6], y_hand[6], w_ref[6];
        random_state(&rng, &m);
        random_load_phi(&rng, phi);
        regressor_of(&m, A);
        assert_int_equal(loadid_regressor_apply(A, LOADID_NPHI, phi, y_apply), 0);
        matvec6(A, 10, phi, y_hand);
        loadid_synth_wrench(phi, &m, w_ref);
        const double e_apply = rel_err_wrench(y_apply, w_ref, 6);
        const double e_hand = rel_err_wrench(y_hand, w_ref, 6);
        assert_rel_below(e_apply, REL_TOL, "loadid_regressor_apply(A, phi) vs eqs. (1)-(2)", k);
        assert_rel_below(e_hand, REL_TOL, "hand-written A phi vs eqs. (1)-(2)", k);
        if (e_apply > worst_apply) worst_apply = e_apply;
        if (e_hand > worst_hand) worst_hand = e_hand;
    }
    print_message(
        "eq. (6) vs eqs. (1)-(2), %d random states: worst relative error "
        "%.3g (apply), %.3g (hand product)\n",
        N_RANDOM_STATES, worst_apply, worst_hand);
}

/* Column j of A is the wrench of the unit "load" e_j (eqs. (1)-(2) are
 * linear in phi), so each entry of eq. (6) is checked on its own. */
static void test_regressor_columns_are_unit_wrenches(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0002ULL);
    double worst = 0.0;
    for (int k = 0; k < 500; ++k) {
        loadid_motion_t m;
        double A[60];
        random_state(&rng, &m);
        regressor_of(&m, A);
        for (int j = 0; j < 10; ++j) {
            double e[10] = {0}, col_ref[6], col[6];
            e[j] = 1.0;
            loadid_synth_wrench(e, &m, col_ref);
            for (int r = 0; r < 6; ++r) col[r] = A[r * 10 + j];
            const double err = rel_err_wrench(col, col_ref, 6);
            if (!(err <= REL_TOL)) {
                print_error("column %d of A (state %d): relative error %.3g\n", j, k, err);
                for (int r = 0; r < 6; ++r)
                    print_error("  row %d: A %.17g, eqs. (1)-(2) %.17g\n", r, col[r], col_ref[r]);
                fail();
            }
            if (err > worst) worst = err;
        }
    }
    print_message("columns of A vs unit-load wrenches: worst relative error %.3g\n", worst);
}

/* A state at rest: with z of S up, a - g = [0 0 +9.81] and the load reads
 * f = [0 0 m 9.81], tau = (m c) x (a - g) (docs/INTERFACE.md sign convention). */
static void test_regressor_static_load_z_up(void **state) {
    (void)state;
    const double spec[3] = {0.0, 0.0, G_NORM}, zero[3] = {0.0, 0.0, 0.0};
    const double phi[10] = {2.0, 2.0 * 0.1, 2.0 * -0.05, 2.0 * 0.02, 1e-2, 0, 0, 1e-2, 0, 1e-2};
    double A[60], y[6];
    assert_int_equal(loadid_regressor(spec, zero, zero, A), 0);
    assert_int_equal(loadid_regressor_apply(A, LOADID_NPHI, phi, y), 0);
    const double tol = 1e-13;
    ASSERT_CLOSE(y[0], 0.0, tol, "f_x at rest");
    ASSERT_CLOSE(y[1], 0.0, tol, "f_y at rest");
    ASSERT_CLOSE(y[2], 2.0 * G_NORM, tol, "f_z at rest = +m g");
    /* (m c) x [0 0 g] = [m cy g, -m cx g, 0] */
    ASSERT_CLOSE(y[3], 2.0 * -0.05 * G_NORM, tol, "tau_x at rest");
    ASSERT_CLOSE(y[4], -2.0 * 0.1 * G_NORM, tol, "tau_y at rest");
    ASSERT_CLOSE(y[5], 0.0, tol, "tau_z at rest");
}

/* ---------------------------------------------------- eqs. (7)-(9) */

/* (A + Z(g_init)) phi is the zeroed wrench: the wrench in the state minus
 * the wrench read still at the zeroing pose (spec = -g_init, w = alpha = 0). */
static void test_zeroing_matches_zeroed_wrench(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0003ULL);
    double worst = 0.0;
    for (int k = 0; k < N_RANDOM_STATES; ++k) {
        double g_init[3], phi[10], A[60], y_model[6], w_state[6], w_still[6], y_ref[6];
        loadid_motion_t m, still;
        random_gravity(&rng, g_init);
        random_state(&rng, &m);
        random_load_phi(&rng, phi);
        memset(&still, 0, sizeof still);
        for (int i = 0; i < 3; ++i) {
            still.spec[i] = -g_init[i];
            still.g[i] = g_init[i];
        }
        loadid_synth_wrench(phi, &m, w_state);
        loadid_synth_wrench(phi, &still, w_still);
        for (int i = 0; i < 6; ++i) y_ref[i] = w_state[i] - w_still[i];

        regressor_of(&m, A);
        assert_int_equal(loadid_regressor_add_zeroing(g_init, A), 0);
        assert_int_equal(loadid_regressor_apply(A, LOADID_NPHI, phi, y_model), 0);
        /* Scale: the size of the two wrenches that were subtracted. */
        double scale = max_abs(w_state, 6);
        if (max_abs(w_still, 6) > scale) scale = max_abs(w_still, 6);
        if (scale < 1.0) scale = 1.0;
        double err = 0.0;
        for (int i = 0; i < 6; ++i) {
            const double d = fabs(y_model[i] - y_ref[i]) / scale;
            if (!(d <= err)) err = d;
        }
        assert_rel_below(err, REL_TOL, "(A + Z(g_init)) phi vs zeroed wrench", k);
        if (err > worst) worst = err;
    }
    print_message(
        "eqs. (7)-(9) vs zeroed eqs. (1)-(2), %d random states: worst relative "
        "error %.3g\n",
        N_RANDOM_STATES, worst);
}

/* loadid_regressor_subtract_zeroing: a load that moved while it was
 * zeroed. Over a window of 50 random motions the zeroed wrench of another
 * motion, w - mean(w) (eqs. 1-2 evaluated directly, tools/synth), is
 * (A - A0) phi with A0 the window's mean regressor; a still window gives
 * loadid_regressor_add_zeroing's A. */
static void test_zeroing_while_moving(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0011ULL);
    for (int trial = 0; trial < 200; ++trial) {
        double phi[10], a0[60] = {0}, w0[6] = {0}, A[60], w[6], y[6];
        random_load_phi(&rng, phi);
        loadid_motion_t m;
        for (int k = 0; k < 50; ++k) {
            random_state(&rng, &m);
            loadid_synth_wrench(phi, &m, w);
            assert_int_equal(loadid_regressor(m.spec, m.omega, m.alpha, A), 0);
            for (int i = 0; i < 60; ++i) a0[i] += A[i] / 50;
            for (int i = 0; i < 6; ++i) w0[i] += w[i] / 50;
        }
        random_state(&rng, &m);
        loadid_synth_wrench(phi, &m, w);
        assert_int_equal(loadid_regressor(m.spec, m.omega, m.alpha, A), 0);
        assert_int_equal(loadid_regressor_subtract_zeroing(a0, A), 0);
        assert_int_equal(loadid_regressor_apply(A, 10, phi, y), 0);
        const double scale = fmax(1.0, fmax(max_abs(w, 6), max_abs(w0, 6)));
        for (int i = 0; i < 6; ++i) ASSERT_CLOSE(y[i], w[i] - w0[i], REL_TOL * scale, "moving");
        /* The model in one call: the same matrix, and [A E6] for 16. */
        double Am[96], A16[96];
        assert_int_equal(loadid_regressor_model_zeroed(m.spec, m.omega, m.alpha, 10, a0, Am), 0);
        assert_memory_equal(Am, A, sizeof A);
        assert_int_equal(loadid_regressor_model_zeroed(m.spec, m.omega, m.alpha, 16, NULL, Am), 0);
        assert_int_equal(loadid_regressor_model(m.spec, m.omega, m.alpha, 16, NULL, A16), 0);
        assert_memory_equal(Am, A16, sizeof A16);
        assert_int_equal(loadid_regressor_model_zeroed(m.spec, m.omega, m.alpha, 10, NULL, Am),
                         -EINVAL);

        /* At rest the window's mean is A(-g_init, 0, 0). */
        double g[3], still[60], zero[3] = {0, 0, 0}, spec[3], B[60];
        random_gravity(&rng, g);
        for (int i = 0; i < 3; ++i) spec[i] = -g[i];
        assert_int_equal(loadid_regressor(spec, zero, zero, still), 0);
        assert_int_equal(loadid_regressor(m.spec, m.omega, m.alpha, A), 0);
        memcpy(B, A, sizeof B);
        assert_int_equal(loadid_regressor_subtract_zeroing(still, A), 0);
        assert_int_equal(loadid_regressor_add_zeroing(g, B), 0);
        for (int i = 0; i < 60; ++i)
            ASSERT_CLOSE(A[i], B[i], REL_TOL * fmax(1.0, fabs(B[i])), "rest");
    }
    double A[60], bad[60] = {0}, untouched[60];
    bad[7] = NAN;
    memset(A, 0x5a, sizeof A);
    memcpy(untouched, A, sizeof A);
    assert_int_equal(loadid_regressor_subtract_zeroing(NULL, A), -EINVAL);
    assert_int_equal(loadid_regressor_subtract_zeroing(bad, NULL), -EINVAL);
    assert_int_equal(loadid_regressor_subtract_zeroing(bad, A), LOADID_E_NONFINITE);
    assert_memory_equal(A, untouched, sizeof A);
}

/* loadid_regressor_model: each of its three models against eqs. (1)-(2)
 * evaluated directly (tools/synth): the plain wrench, the zeroed wrench
 * (eqs. 7-9), and the wrench plus an offset ([A E6]). */
static void test_model_matches_each_wrench(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0009ULL);
    for (int k = 0; k < 500; ++k) {
        double g_init[3], phi[16], A[96], y[6], w[6], w_still[6];
        loadid_motion_t m, still;
        random_gravity(&rng, g_init);
        random_state(&rng, &m);
        random_load_phi(&rng, phi);
        uniform_vec3(&rng, 5.0, phi + 10);
        uniform_vec3(&rng, 0.5, phi + 13);
        memset(&still, 0, sizeof still);
        for (int i = 0; i < 3; ++i) still.spec[i] = -g_init[i], still.g[i] = g_init[i];
        loadid_synth_wrench(phi, &m, w);
        loadid_synth_wrench(phi, &still, w_still);
        double scale = fmax(1.0, fmax(max_abs(w, 6), max_abs(w_still, 6)));

        assert_int_equal(loadid_regressor_model(m.spec, m.omega, m.alpha, 10, NULL, A), 0);
        assert_int_equal(loadid_regressor_apply(A, 10, phi, y), 0);
        for (int i = 0; i < 6; ++i) ASSERT_CLOSE(y[i], w[i], REL_TOL * scale, "plain model");

        assert_int_equal(loadid_regressor_model(m.spec, m.omega, m.alpha, 10, g_init, A), 0);
        assert_int_equal(loadid_regressor_apply(A, 10, phi, y), 0);
        for (int i = 0; i < 6; ++i)
            ASSERT_CLOSE(y[i], w[i] - w_still[i], REL_TOL * scale, "zeroing model");

        assert_int_equal(loadid_regressor_model(m.spec, m.omega, m.alpha, 16, g_init, A), 0);
        assert_int_equal(loadid_regressor_apply(A, 16, phi, y), 0);
        for (int i = 0; i < 6; ++i)
            ASSERT_CLOSE(y[i], w[i] + phi[10 + i], REL_TOL * scale, "offset model");
    }
    double A[96], bad[3] = {0, NAN, 0}, ok[3] = {0, 0, 9.81};
    memset(A, 0x5a, sizeof A);
    assert_int_equal(loadid_regressor_model(ok, ok, ok, 12, NULL, A), -EINVAL);
    assert_int_equal(loadid_regressor_model(ok, ok, ok, 10, NULL, NULL), -EINVAL);
    assert_int_equal(loadid_regressor_model(ok, bad, ok, 16, NULL, A), LOADID_E_NONFINITE);
    assert_int_equal(loadid_regressor_model(ok, ok, ok, 10, bad, A), LOADID_E_NONFINITE);
    double untouched[96];
    memset(untouched, 0x5a, sizeof untouched);
    assert_memory_equal(A, untouched, sizeof A);
}

/* At the zeroing pose itself the zeroed wrench is 0 for every load, so
 * A(-g_init, 0, 0) + Z(g_init) must be exactly the zero matrix. */
static void test_zeroing_cancels_at_zeroing_pose(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0004ULL);
    for (int k = 0; k < 200; ++k) {
        double g[3], spec[3], A[60];
        const double zero[3] = {0.0, 0.0, 0.0};
        random_gravity(&rng, g);
        if (k == 0) { /* the default: z of S up */
            g[0] = 0.0;
            g[1] = 0.0;
            g[2] = -G_NORM;
        }
        for (int i = 0; i < 3; ++i) spec[i] = -g[i];
        assert_int_equal(loadid_regressor(spec, zero, zero, A), 0);
        assert_int_equal(loadid_regressor_add_zeroing(g, A), 0);
        for (int i = 0; i < 60; ++i) {
            if (A[i] != 0.0) {
                print_error("g_init %d: entry (%d, %d) = %.17g, expected 0\n", k, i / 10, i % 10,
                            A[i]);
                fail();
            }
        }
    }
}

/* The entries of Z against eq. (7) of the paper for g_init = [1 2 3]:
 * exactly on a zero matrix, and as A_after - A_before on a real regressor
 * (columns 4..9 unchanged: eq. 8). */
static void test_zeroing_entries_match_paper_eq7(void **state) {
    (void)state;
    const double g[3] = {1.0, 2.0, 3.0};
    double Z_paper[60], Z[60];
    paper_zeroing_matrix(g, Z_paper);

    memset(Z, 0, sizeof Z);
    assert_int_equal(loadid_regressor_add_zeroing(g, Z), 0);
    for (int i = 0; i < 60; ++i) {
        if (Z[i] != Z_paper[i]) {
            print_error("Z(%d, %d) = %g, eq. (7) says %g\n", i / 10, i % 10, Z[i], Z_paper[i]);
            fail();
        }
    }

    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0005ULL);
    for (int k = 0; k < 100; ++k) {
        loadid_motion_t m;
        double before[60], after[60];
        random_state(&rng, &m);
        regressor_of(&m, before);
        memcpy(after, before, sizeof after);
        assert_int_equal(loadid_regressor_add_zeroing(g, after), 0);
        for (int i = 0; i < 60; ++i) {
            const double diff = after[i] - before[i];
            /* (a + z) - a == z up to the rounding of the sum. */
            const double tol = 2.0 * DBL_EPSILON * (fabs(before[i]) + fabs(Z_paper[i]));
            if (!(fabs(diff - Z_paper[i]) <= tol)) {
                print_error("state %d: A_after - A_before at (%d, %d) = %.17g, eq. (7) says %g\n",
                            k, i / 10, i % 10, diff, Z_paper[i]);
                fail();
            }
            if (i % 10 >= 4 && after[i] != before[i]) {
                print_error("state %d: inertia column (%d, %d) changed by zeroing\n", k, i / 10,
                            i % 10);
                fail();
            }
        }
    }
}

/* ------------------------------------------------ offset model [A E6] */

static void test_offset_model(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 0x5EED0006ULL);
    double worst = 0.0;
    for (int k = 0; k < 1000; ++k) {
        loadid_motion_t m;
        double A[60], A16[96], x[16], y_apply[6], y_hand[6], w_ref[6];
        random_state(&rng, &m);
        random_load_phi(&rng, x);
        for (int i = 0; i < 3; ++i) x[10 + i] = uniform_in(&rng, -20.0, 20.0); /* o_f [N] */
        for (int i = 0; i < 3; ++i) x[13 + i] = uniform_in(&rng, -2.0, 2.0);   /* o_tau [Nm] */
        regressor_of(&m, A);
        memset(A16, 0xA5, sizeof A16); /* sentinel: every entry must be written */
        assert_int_equal(loadid_regressor_with_offset(A, A16), 0);
        for (int r = 0; r < 6; ++r) {
            for (int c = 0; c < 10; ++c) {
                if (A16[r * 16 + c] != A[r * 10 + c]) {
                    print_error("[A E6] left block (%d, %d) = %.17g, A = %.17g\n", r, c,
                                A16[r * 16 + c], A[r * 10 + c]);
                    fail();
                }
            }
            for (int c = 0; c < 6; ++c) {
                const double want = r == c ? 1.0 : 0.0;
                if (A16[r * 16 + 10 + c] != want) {
                    print_error("[A E6] right block (%d, %d) = %.17g, E6 has %g\n", r, c,
                                A16[r * 16 + 10 + c], want);
                    fail();
                }
            }
        }
        loadid_synth_wrench(x, &m, w_ref);
        for (int i = 0; i < 6; ++i) w_ref[i] += x[10 + i];
        assert_int_equal(loadid_regressor_apply(A16, LOADID_NPHI_OFFSET, x, y_apply), 0);
        matvec6(A16, 16, x, y_hand);
        const double e_apply = rel_err_wrench(y_apply, w_ref, 6);
        const double e_hand = rel_err_wrench(y_hand, w_ref, 6);
        assert_rel_below(e_apply, REL_TOL, "[A E6][phi; o] (apply) vs wrench + o", k);
        assert_rel_below(e_hand, REL_TOL, "[A E6][phi; o] (hand) vs wrench + o", k);
        if (e_apply > worst) worst = e_apply;
        if (e_hand > worst) worst = e_hand;
    }
    print_message("offset model [A E6][phi; o] vs wrench + o: worst relative error %.3g\n", worst);
}

/* ---------------------------------------------------------- bad input */

static void fill_sentinel(double *v, int n) {
    for (int i = 0; i < n; ++i) v[i] = -12345.678 - i;
}

static void test_regressor_rejects_nonfinite(void **state) {
    (void)state;
    const double bad_values[3] = {NAN, INFINITY, -INFINITY};
    const double good[3][3] = {{1.0, -2.0, 9.0}, {0.1, 0.2, -0.3}, {5.0, -4.0, 3.0}};
    for (int which = 0; which < 3; ++which) { /* spec, omega, alpha */
        for (int comp = 0; comp < 3; ++comp) {
            for (int b = 0; b < 3; ++b) {
                double in[3][3], A[60], A_before[60];
                memcpy(in, good, sizeof in);
                in[which][comp] = bad_values[b];
                fill_sentinel(A, 60);
                memcpy(A_before, A, sizeof A);
                const int rc = loadid_regressor(in[0], in[1], in[2], A);
                if (rc != LOADID_E_NONFINITE) {
                    print_error("input %d component %d = %g: rc %d, expected %d\n", which, comp,
                                bad_values[b], rc, LOADID_E_NONFINITE);
                    fail();
                }
                assert_memory_equal(A, A_before, sizeof A);
            }
        }
    }
    /* And the good input is accepted, so the checks above are not vacuous. */
    double A[60];
    assert_int_equal(loadid_regressor(good[0], good[1], good[2], A), 0);
}

static void test_regressor_rejects_null(void **state) {
    (void)state;
    const double v[3] = {1.0, 2.0, 3.0};
    double A[60], A16[96], y[6];
    double phi[16] = {1.0};
    assert_int_equal(loadid_regressor(NULL, v, v, A), -EINVAL);
    assert_int_equal(loadid_regressor(v, NULL, v, A), -EINVAL);
    assert_int_equal(loadid_regressor(v, v, NULL, A), -EINVAL);
    assert_int_equal(loadid_regressor(v, v, v, NULL), -EINVAL);
    assert_int_equal(loadid_regressor(v, v, v, A), 0);
    assert_int_equal(loadid_regressor_add_zeroing(NULL, A), -EINVAL);
    assert_int_equal(loadid_regressor_add_zeroing(v, NULL), -EINVAL);
    assert_int_equal(loadid_regressor_with_offset(NULL, A16), -EINVAL);
    assert_int_equal(loadid_regressor_with_offset(A, NULL), -EINVAL);
    assert_int_equal(loadid_regressor_apply(NULL, 10, phi, y), -EINVAL);
    assert_int_equal(loadid_regressor_apply(A, 10, NULL, y), -EINVAL);
    assert_int_equal(loadid_regressor_apply(A, 10, phi, NULL), -EINVAL);
}

static void test_zeroing_rejects_nonfinite(void **state) {
    (void)state;
    const double bad_values[3] = {NAN, INFINITY, -INFINITY};
    for (int comp = 0; comp < 3; ++comp) {
        for (int b = 0; b < 3; ++b) {
            double g[3] = {0.0, 0.0, -G_NORM}, A[60], A_before[60];
            g[comp] = bad_values[b];
            fill_sentinel(A, 60);
            memcpy(A_before, A, sizeof A);
            assert_int_equal(loadid_regressor_add_zeroing(g, A), LOADID_E_NONFINITE);
            assert_memory_equal(A, A_before, sizeof A);
        }
    }
}

static void test_apply_rejects_bad_param_count(void **state) {
    (void)state;
    double A[96], phi[16], y[6];
    fill_sentinel(A, 96);
    fill_sentinel(phi, 16);
    const int bad_counts[] = {11, 0, -1, 9, 15, 17, 60};
    for (size_t i = 0; i < sizeof bad_counts / sizeof bad_counts[0]; ++i) {
        if (loadid_regressor_apply(A, bad_counts[i], phi, y) != -EINVAL) {
            print_error("n_params %d accepted\n", bad_counts[i]);
            fail();
        }
    }
    assert_int_equal(loadid_regressor_apply(A, 10, phi, y), 0);
    assert_int_equal(loadid_regressor_apply(A, 16, phi, y), 0);
}

static void test_strerror(void **state) {
    (void)state;
    const int codes[] = {
        0, LOADID_E_NONFINITE, LOADID_E_NOT_EXCITED, LOADID_E_NO_SOLUTION, LOADID_E_FULL, -EINVAL};
    const int n = (int)(sizeof codes / sizeof codes[0]);
    const char *text[sizeof codes / sizeof codes[0]];
    for (int i = 0; i < n; ++i) {
        text[i] = loadid_strerror(codes[i]);
        assert_non_null(text[i]);
        if (text[i][0] == '\0') {
            print_error("loadid_strerror(%d) is empty\n", codes[i]);
            fail();
        }
    }
    /* The header says it names each code: no two of these share a text. */
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            if (strcmp(text[i], text[j]) == 0) {
                print_error("codes %d and %d share the text \"%s\"\n", codes[i], codes[j], text[i]);
                fail();
            }
        }
    /* Never NULL, even for codes it does not know; and no known code falls
     * through to the text of an unknown one. */
    const char *unknown = loadid_strerror(-999999);
    assert_non_null(unknown);
    assert_true(unknown[0] != '\0');
    for (int i = 0; i < n; ++i) {
        if (strcmp(text[i], unknown) == 0) {
            print_error("code %d has the text of an unknown code: \"%s\"\n", codes[i], unknown);
            fail();
        }
    }
    assert_non_null(loadid_strerror(12345));
    /* This test links the double core. */
    assert_int_equal(loadid_scalar_is_float(), 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_regressor_matches_newton_euler),
        cmocka_unit_test(test_regressor_columns_are_unit_wrenches),
        cmocka_unit_test(test_regressor_static_load_z_up),
        cmocka_unit_test(test_zeroing_matches_zeroed_wrench),
        cmocka_unit_test(test_zeroing_cancels_at_zeroing_pose),
        cmocka_unit_test(test_zeroing_entries_match_paper_eq7),
        cmocka_unit_test(test_offset_model),
        cmocka_unit_test(test_model_matches_each_wrench),
        cmocka_unit_test(test_zeroing_while_moving),
        cmocka_unit_test(test_regressor_rejects_nonfinite),
        cmocka_unit_test(test_regressor_rejects_null),
        cmocka_unit_test(test_zeroing_rejects_nonfinite),
        cmocka_unit_test(test_apply_rejects_bad_param_count),
        cmocka_unit_test(test_strerror),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
