/*
 * With noise in the data matrix (accelerations, angular velocity) as well
 * as in the wrench, LS-type estimators are biased towards zero on the
 * parameters whose columns carry the noise (errors-in-variables, paper
 * section IV.B); RTLS is not (IV.D). A statistical test over a fixed set of
 * 100 seeds: RTLS beats RLS on the inertia elements.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "dataset.h"

#ifdef LOADID_SANITIZED
enum { kSeeds = 20 }; /* -O0 with sanitizers: a subset of the same seeds */
#else
enum { kSeeds = 100 };
#endif

/* Mean over Ixx..Izz of the eq. (37) error, in %. */
static double inertia_error(const loadid_real_t *phi, const double *truth) {
    double s = 0;
    for (int j = 4; j < 10; ++j) s += fabs((phi[j] - truth[j]) / truth[j]) * 100.0;
    return s / 6.0;
}

static void test_rtls_beats_rls_on_inertia_over_seeds(void **state) {
    (void)state;
    const loadid_synth_noise_t noise = {
        .sigma_f = 0.1,
        .sigma_tau = 0.005,
        .sigma_spec = 0.5,
        .sigma_alpha = 5.0,
        .sigma_omega = 0.02,
        .offset = {1.0, -2.0, 0.5, 0.05, 0.02, -0.04},
    };
    int rtls_wins = 0;
    double sum_rls = 0, sum_rtls = 0;
    for (int seed = 1; seed <= kSeeds; ++seed) {
        dataset_spec_t spec = {
            .seed = (uint64_t)seed * 1000003u, .n_samples = 1500, .n_params = 10, .noise = noise};
        dataset_t d;
        assert_int_equal(dataset_make(&spec, &d), 0);
        double e[2];
        const loadid_method_t m[2] = {LOADID_METHOD_RLS, LOADID_METHOD_RTLS};
        for (int i = 0; i < 2; ++i) {
            loadid_est_config_t cfg;
            dataset_config(&spec, m[i], &cfg);
            loadid_real_t phi[10];
            assert_int_equal(dataset_estimate(&d, &cfg, phi, NULL), 0);
            e[i] = inertia_error(phi, d.truth);
        }
        sum_rls += e[0];
        sum_rtls += e[1];
        if (e[1] < e[0]) ++rtls_wins;
        dataset_free(&d);
    }
    print_message("%d seeds: mean inertia error RLS %.1f %%, RTLS %.1f %%; RTLS better in %d\n",
                  kSeeds, sum_rls / kSeeds, sum_rtls / kSeeds, rtls_wins);
    /* Thresholds: RTLS wins in at least 90 % of the seeds and halves the
     * mean error; and its own mean error stays within 2.3x of the 4.4 % it
     * shows (RLS 28 %), so that RTLS getting worse fails even while RLS is
     * worse still. Fixed seeds make the outcome deterministic. */
    assert_true(rtls_wins >= (9 * kSeeds) / 10);
    assert_true(sum_rtls < 0.5 * sum_rls);
    assert_true(sum_rtls / kSeeds < 10.0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rtls_beats_rls_on_inertia_over_seeds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
