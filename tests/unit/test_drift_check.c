/*
 * The zeroed model's drift check (host/src/pipeline/drift_check.h):
 *  - its rates and pull equal weighted least squares solved apart, by the
 *    core's LS_BATCH (an SVD) on [A  tau E6] and on A;
 *  - on white noise without drift its p-values (the delete-a-block
 *    jackknife's Wald test) are about uniform, and a drift of 0.05 N/s
 *    in 0.1 N of noise is found every time;
 *  - RIV's pull equals what the core's RIV estimates with the fitted drift
 *    taken out of the wrench, less what it estimates without;
 *  - extra_var is the pull's jackknife where a slow misfit makes it the
 *    larger, against LS_BATCH fits without each block;
 *  - a sample with a NaN does not reach the sums;
 *  - blocks merge in pairs over a long window, a short one is not tested;
 *  - the F tail against the closed forms of F(2, d2) and F(d1, 2).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "drift_check.h"
#include "loadid/core.h"
#include "random_util.h"

#define TWO_PI 6.283185307179586
#define SIGMA_F 0.1
#define SIGMA_T 0.005

static loadid_drift_check_t check; /* large: off the stack */

static const double kPhi[10] = {1.0, -0.045, 0.03, 0.015, 0.003, 0.0, 0.0, 0.0035, 0.0, 0.0032};
static const double kRate[6] = {0.05, -0.04, 0.03, 0.002, -0.002, 0.001};

/* One sample of a smooth random motion at t seconds (eq. 6) and its
 * wrench with drift * t and white noise. */
static void sample(loadid_rng_t *rng, const double w[3][3], double t, const double drift[6],
                   loadid_real_t A[60], loadid_real_t y[6]) {
    loadid_real_t spec[3], omega[3], alpha[3];
    for (int i = 0; i < 3; ++i) {
        const double f = 0.5 + 0.3 * i;
        spec[i] = (loadid_real_t)(3 * sin(w[0][i] + TWO_PI * f * t) + (i == 2 ? 9.81 : 0));
        omega[i] = (loadid_real_t)(1.5 * sin(w[1][i] + TWO_PI * f * t));
        alpha[i] = (loadid_real_t)(6 * cos(w[2][i] + TWO_PI * f * t));
    }
    assert_int_equal(loadid_regressor(spec, omega, alpha, A), 0);
    for (int r = 0; r < 6; ++r) {
        double v = drift[r] * t + (r < 3 ? SIGMA_F : SIGMA_T) * loadid_rng_normal(rng);
        for (int j = 0; j < 10; ++j) v += (double)A[r * 10 + j] * kPhi[j];
        y[r] = (loadid_real_t)v;
    }
}

static void phases(loadid_rng_t *rng, double w[3][3]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) w[i][j] = uniform_in(rng, 0, TWO_PI);
}

/* The zeroing's time: a window's sample k is at k ms, tau_k after it. */
#define T0_US (-200000)

static double tau_of(int k) {
    return (double)(k * 1000 - T0_US) * 1e-6;
}

/* A new window: the motion's phases drawn, the check reset at T0_US. */
static void begin(loadid_rng_t *rng, double w[3][3]) {
    phases(rng, w);
    loadid_drift_check_reset(&check, T0_US, SIGMA_F, SIGMA_T);
}

/* One sample to least squares on [A  tau E6] (ls16) and on A (ls10). */
static void feed_ls(loadid_est_t *ls16, loadid_est_t *ls10, const loadid_real_t A[60],
                    const loadid_real_t y[6], double tau) {
    loadid_real_t A16[6 * 16] = {0};
    for (int r = 0; r < 6; ++r) {
        for (int j = 0; j < 10; ++j) A16[r * 16 + j] = A[r * 10 + j];
        A16[r * 16 + 10 + r] = (loadid_real_t)tau;
    }
    assert_int_equal(loadid_est_update(ls16, A16, NULL, y), 0);
    assert_int_equal(loadid_est_update(ls10, A, NULL, y), 0);
}

/* Samples at 1 kHz for seconds (sample() drifts from the zeroing too). */
static void run(loadid_rng_t *rng, double seconds, const double drift[6], loadid_est_t *ls16,
                loadid_est_t *ls10) {
    double w[3][3];
    begin(rng, w);
    const int n = (int)llround(seconds * 1000);
    for (int k = 0; k < n; ++k) {
        loadid_real_t A[60], y[6];
        sample(rng, w, tau_of(k), drift, A, y);
        loadid_drift_check_add(&check, k * 1000, A, y);
        if (ls16) feed_ls(ls16, ls10, A, y, tau_of(k));
    }
}

static loadid_est_t *batch_ls(int n_params, int capacity) {
    loadid_est_config_t cfg;
    assert_int_equal(loadid_est_config_default(LOADID_METHOD_LS_BATCH, n_params, &cfg), 0);
    for (int r = 0; r < 6; ++r) cfg.row_sigma[r] = (loadid_real_t)(r < 3 ? SIGMA_F : SIGMA_T);
    cfg.batch_capacity = capacity;
    cfg.max_noise_ratio = 1;
    loadid_est_t *e = NULL;
    assert_int_equal(loadid_est_create(&cfg, &e), 0);
    return e;
}

static void test_fit_equals_batch_least_squares(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 3);
    loadid_est_t *ls16 = batch_ls(16, 3000), *ls10 = batch_ls(10, 3000);
    run(&rng, 3.0, kRate, ls16, ls10);
    loadid_drift_result_t r;
    loadid_drift_check_result(&check, &r);
    assert_true(r.tested);
    assert_int_equal(r.blocks, 30);
    loadid_real_t theta[16], phi10[10];
    assert_int_equal(loadid_est_estimate(ls16, theta, NULL), 0);
    assert_int_equal(loadid_est_estimate(ls10, phi10, NULL), 0);
    double worst_rate = 0, worst_pull = 0;
    for (int i = 0; i < 6; ++i)
        worst_rate = fmax(worst_rate, fabs(r.rate[i] - (double)theta[10 + i]) / fabs(kRate[i]));
    for (int i = 0; i < 10; ++i)
        worst_pull = fmax(worst_pull, fabs(r.pull[i] - (double)(phi10[i] - theta[i])) /
                                          (fabs((double)theta[i]) + 1e-3));
    print_message(
        "rates %.4f %.4f %.4f %.5f %.5f %.5f; against LS_BATCH: rates %.1e, pull %.1e; "
        "mass pull %.4f kg, p %.2g\n",
        r.rate[0], r.rate[1], r.rate[2], r.rate[3], r.rate[4], r.rate[5], worst_rate, worst_pull,
        r.pull[0], r.p_value);
    /* Normal equations against an SVD, conditioned as the regressor is:
     * seen 1e-12 and below. */
    assert_true(worst_rate < 1e-8);
    assert_true(worst_pull < 1e-8);
    /* The drift moved the zeroed model's fit (the pull is not trivially 0),
     * and it is plain in the test. */
    assert_true(fabs(r.pull[0]) > 1e-4);
    assert_true(r.p_value < 1e-6);
    for (int i = 0; i < 10; ++i) assert_true(r.extra_var[i] >= 0);
    loadid_est_destroy(ls16);
    loadid_est_destroy(ls10);
}

/* On white noise the jackknife's Wald test is about right: P(p < 0.05) over
 * 400 windows of 1.5 s (15 blocks). The drift of the real-data-like
 * case (0.05 N/s in 0.1 N of noise) is found in all of 50 windows. */
static void test_p_values_without_and_with_drift(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 11);
    const double none[6] = {0};
    int below5 = 0, below1 = 0;
    const int trials = 400;
    for (int k = 0; k < trials; ++k) {
        run(&rng, 1.5, none, NULL, NULL);
        loadid_drift_result_t r;
        loadid_drift_check_result(&check, &r);
        assert_true(r.tested);
        below5 += r.p_value < 0.05;
        below1 += r.p_value < 0.01;
    }
    double worst = 0;
    for (int k = 0; k < 50; ++k) {
        run(&rng, 1.5, kRate, NULL, NULL);
        loadid_drift_result_t r;
        loadid_drift_check_result(&check, &r);
        worst = fmax(worst, r.p_value);
    }
    print_message("no drift: p < 0.05 in %d of %d, p < 0.01 in %d; drift: largest p %.2g\n", below5,
                  trials, below1, worst);
    /* Binomial(400, 0.05): 20 +- 4.4; 3 sigma each way. */
    assert_in_range(below5, 7, 33);
    assert_true(below1 <= 12);
    assert_true(worst < 1e-4);
}

static void test_blocks_merge_and_short_windows_are_not_tested(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 7);
    loadid_drift_result_t r;
    /* 10 s of 100 ms blocks: 32 merge into 16 of 200 ms, which reach 32 at
     * 6.4 s and merge into 16 of 400 ms; 3.6 s more make 9. */
    run(&rng, 10.0, kRate, NULL, NULL);
    loadid_drift_check_result(&check, &r);
    assert_int_equal(r.blocks, 25);
    assert_true(r.tested && r.p_value < 1e-6);
    /* 0.96 s: nine blocks and a half (the half counts), under the ten a
     * test needs. */
    run(&rng, 0.96, kRate, NULL, NULL);
    loadid_drift_check_result(&check, &r);
    assert_int_equal(r.blocks, 10);
    assert_true(r.tested);
    run(&rng, 0.9, kRate, NULL, NULL);
    loadid_drift_check_result(&check, &r);
    assert_int_equal(r.blocks, 9);
    assert_false(r.tested);
    assert_true(r.p_value == 1);
}

/* RIV's pull: two RIV estimators on the same data, one fed y, one fed y
 * less the fitted drift; instruments C are A off by up to 10 % (as the
 * setpoint's motion is the encoders' but for the servo's lag). */
static void test_iv_pull_equals_riv_on_the_detrended_wrench(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 17);
    double w[3][3];
    begin(&rng, w);
    const int n = 1500;
    static loadid_real_t As[1500][60], Cs[1500][60], ys[1500][6];
    const loadid_real_t spec_lag = (loadid_real_t)0.1;
    for (int k = 0; k < n; ++k) {
        const double t = tau_of(k);
        sample(&rng, w, t, kRate, As[k], ys[k]);
        for (int i = 0; i < 60; ++i)
            Cs[k][i] = As[k][i] * (1 + spec_lag * (loadid_real_t)sin(0.7 * i + t));
        loadid_drift_check_add(&check, k * 1000, As[k], ys[k]);
        loadid_drift_check_add_instruments(&check, k * 1000, As[k], Cs[k]);
    }
    loadid_drift_result_t r;
    loadid_drift_check_result(&check, &r);
    double pull[10];
    assert_int_equal(loadid_drift_check_iv_pull(&check, &r, pull), 0);
    loadid_est_t *riv[2];
    for (int e = 0; e < 2; ++e) {
        loadid_est_config_t cfg;
        assert_int_equal(loadid_est_config_default(LOADID_METHOD_RIV, 10, &cfg), 0);
        for (int row = 0; row < 6; ++row)
            cfg.row_sigma[row] = (loadid_real_t)(row < 3 ? SIGMA_F : SIGMA_T);
        cfg.max_noise_ratio = 1;
        assert_int_equal(loadid_est_create(&cfg, &riv[e]), 0);
    }
    for (int k = 0; k < n; ++k) {
        const double tau = tau_of(k);
        loadid_real_t y2[6];
        for (int row = 0; row < 6; ++row) y2[row] = (loadid_real_t)(ys[k][row] - r.rate[row] * tau);
        assert_int_equal(loadid_est_update(riv[0], As[k], Cs[k], ys[k]), 0);
        assert_int_equal(loadid_est_update(riv[1], As[k], Cs[k], y2), 0);
    }
    loadid_real_t phi[2][10];
    for (int e = 0; e < 2; ++e) assert_int_equal(loadid_est_estimate(riv[e], phi[e], NULL), 0);
    double worst = 0, worst_ls = 0;
    for (int i = 0; i < 10; ++i) {
        const double want = (double)(phi[0][i] - phi[1][i]);
        worst = fmax(worst, fabs(pull[i] - want) / (fabs(want) + 1e-4));
        worst_ls = fmax(worst_ls, fabs(r.pull[i] - want) / (fabs(want) + 1e-4));
    }
    print_message("IV pull against RIV on the detrended wrench: %.1e (the LS pull's: %.1e)\n",
                  worst, worst_ls);
    /* The IV sums take every 4th sample (drift_check.c): the sums' ends
     * leave 3.2e-3 here (every sample: 6e-13, RIV's ridge cancelling).
     * The least-squares pull is 3.6e-2 off. */
    assert_true(worst < 1e-2);
    assert_true(worst_ls > 3 * worst);
    for (int e = 0; e < 2; ++e) loadid_est_destroy(riv[e]);
    /* Without instruments there is no IV pull. */
    loadid_drift_check_reset(&check, T0_US, SIGMA_F, SIGMA_T);
    assert_int_equal(loadid_drift_check_iv_pull(&check, &r, pull), -1);
}

/* extra_var, what fitting the rates adds to phi's variance, is the larger
 * of the white cost and the pull's delete-a-block jackknife, computed here
 * with the core's LS_BATCH (an SVD) on [A  tau E6] and on A over the
 * samples outside each 100 ms block: with a slow misfit in the wrench
 * (0.3 Hz, twice the noise, which white s^2 counts as fast) the
 * jackknife. */
static void test_extra_var_is_the_pulls_jackknife(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 23);
    double w[3][3];
    begin(&rng, w);
    enum { n = 1500, blocks = 15 };
    static loadid_real_t As[n][60], ys[n][6];
    double ph[6];
    for (int r = 0; r < 6; ++r) ph[r] = uniform_in(&rng, 0, TWO_PI);
    for (int k = 0; k < n; ++k) {
        const double t = tau_of(k);
        sample(&rng, w, t, kRate, As[k], ys[k]);
        for (int r = 0; r < 6; ++r)
            ys[k][r] +=
                (loadid_real_t)(2 * (r < 3 ? SIGMA_F : SIGMA_T) * sin(ph[r] + TWO_PI * 0.3 * t));
        loadid_drift_check_add(&check, k * 1000, As[k], ys[k]);
    }
    loadid_drift_result_t r;
    loadid_drift_check_result(&check, &r);
    assert_true(r.tested);
    assert_int_equal(r.blocks, blocks);
    double pulls[blocks][10], mean[10] = {0};
    for (int b = 0; b < blocks; ++b) {
        loadid_est_t *ls16 = batch_ls(16, n), *ls10 = batch_ls(10, n);
        for (int k = 0; k < n; ++k)
            if (k / 100 != b) feed_ls(ls16, ls10, As[k], ys[k], tau_of(k));
        loadid_real_t theta[16], phi10[10];
        assert_int_equal(loadid_est_estimate(ls16, theta, NULL), 0);
        assert_int_equal(loadid_est_estimate(ls10, phi10, NULL), 0);
        for (int i = 0; i < 10; ++i) {
            pulls[b][i] = (double)(phi10[i] - theta[i]);
            mean[i] += pulls[b][i] / blocks;
        }
        loadid_est_destroy(ls16);
        loadid_est_destroy(ls10);
    }
    double worst = 0;
    for (int i = 0; i < 10; ++i) {
        double jack = 0;
        for (int b = 0; b < blocks; ++b) jack += (pulls[b][i] - mean[i]) * (pulls[b][i] - mean[i]);
        jack *= (blocks - 1.0) / blocks;
        assert_true(jack > 0);
        worst = fmax(worst, fabs(r.extra_var[i] - jack) / jack);
    }
    /* Seen 1.6e-11; the white cost alone is 0.99 of the jackknife off. */
    print_message("extra_var against the pull's jackknife by LS_BATCH: worst relative %.1e\n",
                  worst);
    assert_true(worst < 1e-6);
}

/* A NaN in the wrench or the regressor leaves the sums as they were. */
static void test_nan_samples_are_left_out(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 13);
    run(&rng, 1.5, kRate, NULL, NULL);
    loadid_drift_check_t before = check;
    loadid_real_t A[60] = {0}, y[6] = {0};
    y[2] = (loadid_real_t)NAN;
    loadid_drift_check_add(&check, 1500000, A, y);
    y[2] = 0;
    A[17] = (loadid_real_t)INFINITY;
    loadid_drift_check_add(&check, 1501000, A, y);
    assert_memory_equal(&before, &check, sizeof check);
    loadid_drift_result_t r;
    loadid_drift_check_result(&check, &r);
    assert_true(r.tested && isfinite(r.p_value) && isfinite(r.pull[0]));
}

/* P(F(2, d2) > f) = (1 + 2 f / d2)^(-d2 / 2); P(F(d1, 2) > f) =
 * 1 - (d1 f / (2 + d1 f))^(d1 / 2). */
static void test_f_tail_closed_forms(void **state) {
    (void)state;
    double worst = 0;
    const double f[] = {0.01, 0.3, 1, 2.5, 7, 40, 300};
    const double d[] = {1, 3, 6, 9, 24, 100};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; ++i)
        for (size_t j = 0; j < sizeof d / sizeof d[0]; ++j) {
            const double a = pow(1 + 2 * f[i] / d[j], -d[j] / 2);
            const double b = 1 - pow(d[j] * f[i] / (2 + d[j] * f[i]), d[j] / 2);
            worst = fmax(worst, fabs(loadid_f_upper_tail(f[i], 2, d[j]) - a) / a);
            worst = fmax(worst, fabs(loadid_f_upper_tail(f[i], d[j], 2) - b) / b);
        }
    print_message("F tail against closed forms: worst relative error %.1e\n", worst);
    assert_true(worst < 1e-10);
    assert_true(loadid_f_upper_tail(0, 6, 9) == 1);
    assert_true(loadid_f_upper_tail(INFINITY, 6, 9) == 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fit_equals_batch_least_squares),
        cmocka_unit_test(test_p_values_without_and_with_drift),
        cmocka_unit_test(test_blocks_merge_and_short_windows_are_not_tested),
        cmocka_unit_test(test_iv_pull_equals_riv_on_the_detrended_wrench),
        cmocka_unit_test(test_extra_var_is_the_pulls_jackknife),
        cmocka_unit_test(test_nan_samples_are_left_out),
        cmocka_unit_test(test_f_tail_closed_forms),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
