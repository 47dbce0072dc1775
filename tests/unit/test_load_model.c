/*
 * The load model (loadid_load_model): identified groups from the standard
 * deviations, the nearest physically consistent inertia, the fallback.
 * References: a solid box's inertia by formula; the projection checked
 * against many random consistent candidates (none may be nearer) and
 * against the pseudo-inertia's eigenvalues computed here (Jacobi on 4x4).
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "loadid/core.h"
#include "random_util.h"

/* phi of a solid box (sides a, b, c [m], mass m) whose centre is at com. */
static void box_phi(double m, double a, double b, double c, const double com[3],
                    loadid_real_t phi[10]) {
    const loadid_real_t Ic[6] = {m * (b * b + c * c) / 12, 0, 0,
                                 m * (a * a + c * c) / 12, 0, m * (a * a + b * b) / 12};
    const loadid_real_t cc[3] = {com[0], com[1], com[2]};
    assert_int_equal(loadid_phi_from_physical(m, cc, Ic, phi), 0);
}

/* Sigma_C = tr(I_C)/2 E - I_C of phi as a 3x3 (row-major). */
static void second_moment(const loadid_real_t phi[10], double S[9]) {
    loadid_physical_t p;
    assert_int_equal(loadid_phi_to_physical(phi, &p), 0);
    const double *v = NULL;
    double I[9];
    const double in[6] = {p.inertia_com[0], p.inertia_com[1], p.inertia_com[2],
                          p.inertia_com[3], p.inertia_com[4], p.inertia_com[5]};
    v = in;
    I[0] = v[0], I[1] = v[1], I[2] = v[2], I[3] = v[1], I[4] = v[3], I[5] = v[4], I[6] = v[2],
    I[7] = v[4], I[8] = v[5];
    const double tr = I[0] + I[4] + I[8];
    for (int i = 0; i < 9; ++i) S[i] = (i % 4 == 0 ? tr / 2 : 0) - I[i];
}

/* Eigenvalues of a symmetric 3x3 by cyclic Jacobi (the test's own). */
static void eig3(const double A[9], double l[3]) {
    double a[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) a[i][j] = A[i * 3 + j];
    for (int sweep = 0; sweep < 50; ++sweep)
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (fabs(a[p][q]) < 1e-300) continue;
                const double th = 0.5 * atan2(2 * a[p][q], a[q][q] - a[p][p]);
                const double c = cos(th), s = sin(th);
                for (int k = 0; k < 3; ++k) {
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq, a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk, a[q][k] = s * apk + c * aqk;
                }
            }
    for (int i = 0; i < 3; ++i) l[i] = a[i][i];
}

static void small_std(const loadid_real_t phi[10], loadid_real_t std[10]) {
    for (int i = 0; i < 10; ++i) std[i] = 1e-4 * (fabs(phi[i]) + 1e-4);
}

static void test_consistent_load_passes_unchanged(void **state) {
    (void)state;
    const double com[3] = {0.01, -0.02, 0.05};
    loadid_real_t phi[10], std[10];
    box_phi(1.2, 0.08, 0.05, 0.12, com, phi);
    small_std(phi, std);
    loadid_model_config_t cfg;
    loadid_model_config_default(&cfg);
    loadid_load_model_t m;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
    assert_int_equal(m.identified, LOADID_IDENT_MASS | LOADID_IDENT_COM | LOADID_IDENT_INERTIA);
    assert_int_equal(m.projected, 0);
    for (int i = 0; i < 10; ++i)
        assert_true(fabs(m.phi[i] - phi[i]) <= 1e-15 + 1e-12 * fabs(phi[i]));
    assert_int_equal(m.physical.violations, 0);
}

static void test_inconsistent_inertia_is_projected_to_the_nearest(void **state) {
    (void)state;
    loadid_model_config_t cfg;
    loadid_model_config_default(&cfg);
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 42);
    int projected = 0;
    for (int trial = 0; trial < 200; ++trial) {
        /* A box, its inertia about the COM disturbed until it may break
         * the triangle inequality. */
        const double com[3] = {0.05 * loadid_rng_normal(&rng), 0.05 * loadid_rng_normal(&rng),
                               0.05 * loadid_rng_normal(&rng)};
        loadid_real_t phi[10], std[10];
        box_phi(0.5 + fabs(loadid_rng_normal(&rng)), 0.05, 0.1, 0.02, com, phi);
        for (int i = 4; i < 10; ++i) phi[i] += 4e-4 * loadid_rng_normal(&rng);
        small_std(phi, std);
        loadid_load_model_t m;
        assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
        assert_int_equal(m.physical.violations, 0); /* never physically impossible */
        for (int i = 0; i < 4; ++i) assert_true(m.phi[i] == phi[i]); /* mass, COM kept */
        double S[9], Sm[9], l[3];
        second_moment(phi, S);
        second_moment(m.phi, Sm);
        eig3(S, l);
        const int was_bad = l[0] < 0 || l[1] < 0 || l[2] < 0;
        assert_int_equal(m.projected, was_bad);
        projected += was_bad;
        if (!was_bad) continue;
        /* Nearest: no consistent candidate near the answer is nearer to the
         * estimate's Sigma_C (Frobenius). Candidates: the answer moved by
         * random symmetric steps, kept where positive semidefinite. */
        double best = 0;
        for (int i = 0; i < 9; ++i) best += (Sm[i] - S[i]) * (Sm[i] - S[i]);
        for (int c = 0; c < 300; ++c) {
            double C[9], step[6], lc[3];
            for (int i = 0; i < 6; ++i) step[i] = 2e-5 * loadid_rng_normal(&rng);
            const int map[9] = {0, 1, 2, 1, 3, 4, 2, 4, 5};
            for (int i = 0; i < 9; ++i) C[i] = Sm[i] + step[map[i]];
            eig3(C, lc);
            if (lc[0] < 0 || lc[1] < 0 || lc[2] < 0) continue;
            double dist = 0;
            for (int i = 0; i < 9; ++i) dist += (C[i] - S[i]) * (C[i] - S[i]);
            assert_true(dist >= best * (1 - 1e-9) - 1e-24);
        }
    }
    print_message("%d of 200 disturbed boxes were inconsistent and projected\n", projected);
    assert_true(projected > 20);
}

static void test_unidentified_inertia_falls_back_to_a_sphere(void **state) {
    (void)state;
    const double com[3] = {0, 0, 0.1};
    loadid_real_t phi[10], std[10];
    box_phi(2.0, 0.1, 0.1, 0.1, com, phi);
    small_std(phi, std);
    for (int i = 4; i < 10; ++i) std[i] = 0.5; /* kg m^2: the data say nothing */
    loadid_model_config_t cfg;
    loadid_model_config_default(&cfg);
    loadid_load_model_t m;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
    assert_int_equal(m.identified, LOADID_IDENT_MASS | LOADID_IDENT_COM);
    assert_int_equal(m.projected, 1);
    const double r = cbrt(3 * 2.0 / (4 * 3.14159265358979323846 * 2700.0)), I = 0.4 * 2.0 * r * r;
    assert_true(fabs(m.physical.inertia_com[0] - I) < 1e-12);
    assert_true(fabs(m.physical.inertia_com[3] - I) < 1e-12);
    assert_true(fabs(m.physical.inertia_com[5] - I) < 1e-12);
    assert_true(fabs(m.physical.inertia_com[1]) < 1e-15);
    assert_true(fabs(m.physical.com[2] - 0.1) < 1e-12);
    assert_int_equal(m.physical.violations, 0);
}

static void test_groups_and_bad_input(void **state) {
    (void)state;
    const double com[3] = {0.02, 0, 0.04};
    loadid_real_t phi[10], std[10];
    box_phi(1.0, 0.1, 0.06, 0.03, com, phi);
    small_std(phi, std);
    loadid_model_config_t cfg;
    loadid_model_config_default(&cfg);
    loadid_load_model_t m;
    /* COM std 6 mm > 5 mm: neither COM nor inertia. */
    std[1] = 0.006;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
    assert_int_equal(m.identified, LOADID_IDENT_MASS);
    /* Why: c_x's std, sqrt(std(m c_x)^2 + c_x^2 std(m)^2) / m, over 5 mm;
     * the inertia for want of the COM. */
    assert_int_equal(m.why[0], LOADID_WHY_IDENTIFIED);
    assert_int_equal(m.why[1], LOADID_WHY_STD);
    assert_true(fabs(m.over[1] - hypot(0.006, 0.02 * std[0]) / 0.005) < 1e-12);
    assert_int_equal(m.why[2], LOADID_WHY_NEEDS);
    /* mass std 2.4 % <= 2.5 % (2 sigma within 5 %): the mass; 3 %: nothing. */
    small_std(phi, std);
    std[0] = 0.024;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
    assert_true(m.identified & LOADID_IDENT_MASS);
    std[0] = 0.03;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
    assert_int_equal(m.identified, 0);
    assert_int_equal(m.why[0], LOADID_WHY_STD);
    assert_true(fabs(m.over[0] - 0.03 / 0.025) < 1e-12);
    assert_int_equal(m.why[1], LOADID_WHY_NEEDS);
    assert_int_equal(m.why[2], LOADID_WHY_NEEDS);
    /* Inertia: its largest element std against 15 % of the inertia's
     * scale, the mean principal moment about the COM (tr(I_C) / 3 =
     * m (a^2 + b^2 + c^2) / 18 for the box) or the aluminium sphere's if
     * larger: 14 % identified, 16 % not. */
    const double r_sphere = cbrt(3 * 1.0 / (4 * 3.14159265358979323846 * 2700.0));
    const double scale =
        fmax((0.1 * 0.1 + 0.06 * 0.06 + 0.03 * 0.03) / 18, 0.4 * r_sphere * r_sphere);
    for (int k = 0; k < 2; ++k) {
        small_std(phi, std);
        std[4 + 2 * k] = (loadid_real_t)((k ? 0.16 : 0.14) * scale);
        assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
        assert_int_equal(m.identified,
                         LOADID_IDENT_MASS | LOADID_IDENT_COM | (k ? 0 : LOADID_IDENT_INERTIA));
        assert_int_equal(m.why[2], k ? LOADID_WHY_STD : LOADID_WHY_IDENTIFIED);
        if (k) assert_true(fabs(m.over[2] - 0.16 / 0.15) < 1e-9);
    }
    /* NaN std: not identified, never a crash. */
    small_std(phi, std);
    std[7] = NAN;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), 0);
    assert_int_equal(m.identified, LOADID_IDENT_MASS | LOADID_IDENT_COM);
    assert_int_equal(m.why[2], LOADID_WHY_STD);
    assert_true(isnan(m.over[2]));
    /* Too little torque from the inertia (a slow motion): not identified. */
    const loadid_real_t weak[3] = {100, 50, 0.9}, strong[3] = {100, 50, 1.1};
    small_std(phi, std);
    assert_int_equal(loadid_load_model(phi, std, weak, &cfg, &m), 0);
    assert_int_equal(m.identified, LOADID_IDENT_MASS | LOADID_IDENT_COM);
    assert_int_equal(m.why[2], LOADID_WHY_SNR);
    assert_true(fabs(m.over[2] - 1 / 0.9) < 1e-12);
    assert_int_equal(loadid_load_model(phi, std, strong, &cfg, &m), 0);
    assert_int_equal(m.identified, LOADID_IDENT_MASS | LOADID_IDENT_COM | LOADID_IDENT_INERTIA);
    /* An inertia 10 m in gyration radius is no wrist load. */
    small_std(phi, std);
    loadid_real_t huge[10];
    memcpy(huge, phi, sizeof huge);
    huge[4] += 100, huge[7] += 100, huge[9] += 100;
    small_std(huge, std);
    assert_int_equal(loadid_load_model(huge, std, NULL, &cfg, &m), 0);
    assert_int_equal(m.identified, LOADID_IDENT_MASS | LOADID_IDENT_COM);
    /* Its radius sqrt(tr(I_C) / 2m), I_C by the parallel-axis theorem. */
    const double c2 = com[0] * com[0] + com[1] * com[1] + com[2] * com[2];
    const double trace_c = (double)(huge[4] + huge[7] + huge[9]) - 2 * 1.0 * c2;
    assert_int_equal(m.why[2], LOADID_WHY_GYRATION);
    assert_true(fabs(m.over[2] - sqrt(trace_c / 2) / 0.5) < 1e-9);
    /* No positive mass: no load. */
    loadid_real_t neg[10];
    memcpy(neg, phi, sizeof neg);
    neg[0] = -0.2;
    assert_int_equal(loadid_load_model(neg, std, NULL, &cfg, &m), 0);
    assert_int_equal(m.identified, 0);
    for (int g = 0; g < 3; ++g) assert_int_equal(m.why[g], LOADID_WHY_NO_MASS);
    assert_int_equal(m.projected, 1);
    for (int i = 0; i < 10; ++i) assert_true(m.phi[i] == 0);
    /* Bad arguments. */
    phi[3] = NAN;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), LOADID_E_NONFINITE);
    assert_int_equal(loadid_load_model(NULL, std, NULL, &cfg, &m), -EINVAL);
    cfg.com_std = 0;
    phi[3] = 0;
    assert_int_equal(loadid_load_model(phi, std, NULL, &cfg, &m), -EINVAL);
    assert_string_equal(loadid_ident_name(LOADID_IDENT_INERTIA), "inertia");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_consistent_load_passes_unchanged),
        cmocka_unit_test(test_inconsistent_inertia_is_projected_to_the_nearest),
        cmocka_unit_test(test_unidentified_inertia_falls_back_to_a_sphere),
        cmocka_unit_test(test_groups_and_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
