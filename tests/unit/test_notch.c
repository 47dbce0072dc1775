/*
 * The notch on the estimators' rows (host/src/pipeline/notch.h):
 *  - its response against the analog prototype's through the bilinear map,
 *    |1 - x^2| / sqrt((1 - x^2)^2 + (x / q)^2), x = tan(w / 2) / tan(w0 / 2):
 *    by the coefficients (loadid_biquad_gain) and by what the filter does
 *    to a sinusoid (a least-squares fit of its output's amplitude);
 *  - a constant passes unchanged from the first sample (primed state);
 *  - its gain on white noise against the variance of filtered noise;
 *  - A phi = y still holds after the bank filters A's columns and y;
 *  - the bank's bounds: stages, channels, a restart.
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "loadid/core.h"
#include "notch.h"
#include "random_util.h"

#define TWO_PI 6.283185307179586
#define DT 1e-3

static loadid_notch_bank_t bank; /* large: off the stack */

static double prototype_gain(double hz, double f0, double q) {
    const double x = tan(0.5 * TWO_PI * hz * DT) / tan(0.5 * TWO_PI * f0 * DT), d = 1 - x * x;
    return fabs(d) / sqrt(d * d + (x / q) * (x / q));
}

/* The amplitude of one channel's output for a unit sinusoid at hz, from a
 * least-squares fit of cos and sin over samples 3000 .. 5999 (the
 * transient of a 10 Hz notch at q 2 has decayed by e^-50 by then). */
static double measured_gain(double hz) {
    loadid_notch_bank_restart(&bank);
    double cc = 0, ss = 0, cs = 0, yc = 0, ys = 0;
    for (int k = 0; k < 6000; ++k) {
        const double w = TWO_PI * hz * k * DT;
        loadid_real_t v = (loadid_real_t)sin(w + 0.3);
        loadid_notch_bank_apply(&bank, 5, 1, &v);
        if (k < 3000) continue;
        const double c = cos(w), s = sin(w);
        cc += c * c, ss += s * s, cs += c * s, yc += v * c, ys += v * s;
    }
    const double det = cc * ss - cs * cs, a = (yc * ss - ys * cs) / det,
                 b = (ys * cc - yc * cs) / det;
    return sqrt(a * a + b * b);
}

static void test_response_is_the_prototype_s(void **state) {
    (void)state;
    const double f0s[3] = {10.0, 28.0, 150.0}, q = 2.0;
    const double probes[7] = {0.5, 2.0, 5.0, 20.0, 27.0, 60.0, 300.0};
    for (int i = 0; i < 3; ++i) {
        loadid_biquad_t bq;
        assert_int_equal(loadid_notch_design(f0s[i], DT, q, &bq), 0);
        ASSERT_CLOSE(bq.a[0], 1.0, 0.0, "a0");
        ASSERT_CLOSE(loadid_biquad_gain(&bq, f0s[i], DT), 0.0, 1e-9, "gain at f0");
        loadid_notch_bank_clear(&bank);
        assert_int_equal(loadid_notch_bank_add(&bank, &bq), 0);
        for (int j = 0; j < 7; ++j) {
            const double want = prototype_gain(probes[j], f0s[i], q);
            ASSERT_CLOSE(loadid_biquad_gain(&bq, probes[j], DT), want, 1e-12, "coefficients");
            ASSERT_CLOSE(measured_gain(probes[j]), want, 1e-6, "filtered sinusoid");
        }
        ASSERT_CLOSE(measured_gain(f0s[i]), 0.0, 1e-6, "the tone itself");
    }
    /* At the motion's few hertz a 28 Hz notch changes the rows by under 1 %. */
    assert_true(prototype_gain(5.0, 28.0, 2.0) > 0.99);
    loadid_biquad_t bq;
    assert_int_equal(loadid_notch_design(0.0, DT, 2, &bq), -EINVAL);
    assert_int_equal(loadid_notch_design(500.0, DT, 2, &bq), -EINVAL);
    assert_int_equal(loadid_notch_design(NAN, DT, 2, &bq), -EINVAL);
    assert_int_equal(loadid_notch_design(28.0, 0.0, 2, &bq), -EINVAL);
    assert_int_equal(loadid_notch_design(28.0, DT, 0.0, &bq), -EINVAL);
}

static void test_a_constant_passes_from_the_first_sample(void **state) {
    (void)state;
    loadid_biquad_t b1, b2;
    assert_int_equal(loadid_notch_design(28.0, DT, 2.0, &b1), 0);
    assert_int_equal(loadid_notch_design(61.0, DT, 2.0, &b2), 0);
    loadid_notch_bank_clear(&bank);
    loadid_notch_bank_add(&bank, &b1);
    loadid_notch_bank_add(&bank, &b2);
    for (int k = 0; k < 100; ++k) {
        loadid_real_t v[3] = {-9.81, 0.25, 1e3};
        loadid_notch_bank_apply(&bank, 0, 3, v);
        ASSERT_CLOSE(v[0], -9.81, 1e-12, "constant");
        ASSERT_CLOSE(v[1], 0.25, 1e-12, "constant");
        ASSERT_CLOSE(v[2], 1e3, 1e-9, "constant");
    }
}

/* The variance white noise keeps through two stages, over 400 000
 * samples (the estimate's own error about 0.3 %). */
static void test_gain_on_white_noise(void **state) {
    (void)state;
    loadid_biquad_t b1, b2;
    assert_int_equal(loadid_notch_design(28.0, DT, 2.0, &b1), 0);
    assert_int_equal(loadid_notch_design(90.0, DT, 3.0, &b2), 0);
    loadid_notch_bank_clear(&bank);
    ASSERT_CLOSE(loadid_notch_bank_noise_gain(&bank), 1.0, 0.0, "no stages");
    loadid_notch_bank_add(&bank, &b1);
    loadid_notch_bank_add(&bank, &b2);
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 7);
    double in2 = 0, out2 = 0;
    for (int k = 0; k < 400000; ++k) {
        const double x = loadid_rng_normal(&rng);
        loadid_real_t v = (loadid_real_t)x;
        loadid_notch_bank_apply(&bank, 0, 1, &v);
        in2 += x * x, out2 += (double)v * (double)v;
    }
    const double gain = loadid_notch_bank_noise_gain(&bank);
    print_message("noise gain %.4f, measured %.4f\n", gain, out2 / in2);
    ASSERT_CLOSE(out2 / in2, gain, 0.01, "white noise's variance");
    /* the two notches take about (pi / 2) (f0 / q) / 500 Hz each */
    assert_true(gain > 0.85 && gain < 0.97);
}

/* Rows of a smooth motion with a 28 Hz tone in their columns, and
 * y = A phi: after the bank, the filtered A times phi is the filtered y. */
static void test_the_model_still_holds(void **state) {
    (void)state;
    loadid_biquad_t bq;
    assert_int_equal(loadid_notch_design(28.0, DT, 2.0, &bq), 0);
    loadid_notch_bank_clear(&bank);
    loadid_notch_bank_add(&bank, &bq);
    static const double phi[10] = {1.0, -0.045, 0.03, 0.015, 0.003, 0.0, 0.0, 0.0035, 0.0, 0.0032};
    double worst = 0;
    for (int k = 0; k < 3000; ++k) {
        const double t = k * DT;
        loadid_real_t A[60], y[6];
        for (int i = 0; i < 60; ++i)
            A[i] =
                (loadid_real_t)(sin(0.7 * t * (1 + i % 7) + i) + 0.2 * sin(TWO_PI * 28.0 * t + i));
        for (int r = 0; r < 6; ++r) {
            double v = 0;
            for (int j = 0; j < 10; ++j) v += A[10 * r + j] * phi[j];
            y[r] = (loadid_real_t)v;
        }
        loadid_notch_bank_apply(&bank, LOADID_NOTCH_A, 60, A);
        loadid_notch_bank_apply(&bank, LOADID_NOTCH_Y, 6, y);
        for (int r = 0; r < 6; ++r) {
            double v = 0;
            for (int j = 0; j < 10; ++j) v += A[10 * r + j] * phi[j];
            worst = fmax(worst, fabs(v - y[r]));
        }
    }
    ASSERT_CLOSE(worst, 0.0, 1e-12, "A phi = y after the notch");
}

static void test_bank_bounds(void **state) {
    (void)state;
    loadid_biquad_t bq;
    assert_int_equal(loadid_notch_design(28.0, DT, 2.0, &bq), 0);
    loadid_notch_bank_clear(&bank);
    /* no stages: unchanged */
    loadid_real_t v = 1.5;
    loadid_notch_bank_apply(&bank, 0, 1, &v);
    ASSERT_CLOSE(v, 1.5, 0.0, "no stages");
    assert_int_equal(loadid_notch_bank_add(&bank, &bq), 0);
    assert_int_equal(loadid_notch_bank_add(&bank, &bq), 0);
    assert_int_equal(loadid_notch_bank_add(&bank, &bq), -ENOSPC);
    /* channels outside the bank pass unchanged */
    loadid_real_t x[4] = {1, 2, 3, 4};
    loadid_notch_bank_apply(&bank, LOADID_NOTCH_CHANNELS - 2, 4, x);
    ASSERT_CLOSE(x[2], 3.0, 0.0, "outside");
    ASSERT_CLOSE(x[3], 4.0, 0.0, "outside");
    /* a restart primes again: a step then looks like a constant */
    loadid_notch_bank_restart(&bank);
    v = 2.0;
    loadid_notch_bank_apply(&bank, 0, 1, &v);
    ASSERT_CLOSE(v, 2.0, 1e-12, "restart");
    v = 7.0;
    loadid_notch_bank_apply(&bank, 0, 1, &v);
    assert_true(fabs(v - 7.0) > 1e-3); /* primed: a step is filtered */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_response_is_the_prototype_s),
        cmocka_unit_test(test_a_constant_passes_from_the_first_sample),
        cmocka_unit_test(test_gain_on_white_noise),
        cmocka_unit_test(test_the_model_still_holds),
        cmocka_unit_test(test_bank_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
