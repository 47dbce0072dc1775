/*
 * phi_std by band of frequency (host/src/pipeline/spectrum_rows.h and
 * loadid_est_uncertainty_spectral):
 *  - the bands are the DFT of the weighted rows at the samples' own times,
 *    computed here directly sample by sample (the block sums' error within
 *    its bound), and RIV's C^T W C per row group the plain sums;
 *  - with a misfit at tens of Hz (doublets, as a gear's backlash gives at
 *    each reversal) 20 times the noise's power, the white sandwich
 *    overstates the error of least squares and IV (RMS error / std far
 *    below 1) and the bands' sandwich is calibrated over 150 draws; with
 *    white noise alone it stays calibrated;
 *  - with the sensor's own accelerometer as a - g and alpha, the
 *    regressor's noise reaches a sample's rows together: the bands with
 *    the rows apart (and IV's own leverage) keep RIV calibrated, one level
 *    per row group is narrow, and RIV's white sandwich keeps a level per
 *    row group (one for all rows was 2.3 times wide on m); with the joint filter's columns (exact) the
 *    rows apart are not used;
 *  - spectra that do not fit the estimator (samples, bins, RIV without
 *    the instruments' bands, a NaN) are refused, and so are rows that
 *    lost a sample or are too few.
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "loadid/core.h"
#include "random_util.h"
#include "spectrum_rows.h"

#define TWO_PI 6.283185307179586
#define SIGMA_F 0.1
#define SIGMA_T 0.005
#define SAMPLES 1500
#define DRAWS 150

static const double kPhi[10] = {1.0, -0.045, 0.03, 0.015, 0.003, 0.0, 0.0, 0.0035, 0.0, 0.0032};
/* A 2 kg load 11 cm off the flange (I about the COM diag(0.01, 0.012,
 * 0.008)), whose c couples a - g's noise into the torque rows. */
static const double kHeavy[10] = {2.0,    0.06,   -0.04,  0.2,   0.0308,
                                  0.0012, -0.006, 0.0338, 0.004, 0.0106};
/* The phi and the regressor's noise (a - g, omega, alpha) of the draws. */
static const double *phi_true = kPhi;
static double noise_spec = 0.02, noise_omega = 0.002, noise_alpha = 0.05;
static loadid_spectrum_t bands; /* large: off the stack */

/* A smooth random motion at t seconds (phases w): a - g, omega, alpha. */
static void motion(const double w[3][3], double t, loadid_real_t spec[3], loadid_real_t omega[3],
                   loadid_real_t alpha[3]) {
    for (int i = 0; i < 3; ++i) {
        const double f = 0.5 + 0.3 * i;
        spec[i] = (loadid_real_t)(3 * sin(w[0][i] + TWO_PI * f * t) + (i == 2 ? 9.81 : 0));
        omega[i] = (loadid_real_t)(1.5 * sin(w[1][i] + TWO_PI * f * t));
        alpha[i] = (loadid_real_t)(6 * cos(w[2][i] + TWO_PI * f * t));
    }
}

/* A doublet of width 5 ms centred at c, unit peak: what a reversal through
 * a gear's play adds to alpha's error. */
static double doublet(double t, double c) {
    const double u = (t - c) / 0.005;
    return u * exp(0.5 - u * u) * 1.1658; /* peak 1 at u = 1/sqrt(2) */
}

typedef struct {
    double w[3][3];
    double at[15], amp[15][6]; /* the misfit's doublets */
    int n_doublets;
} draw_t;

/* The draw's phases and, with misfit, a doublet about every 100 ms whose
 * peaks make the misfit's power about 20 times the noise's. */
static void new_draw(loadid_rng_t *rng, int misfit, draw_t *d) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) d->w[i][j] = uniform_in(rng, 0, TWO_PI);
    d->n_doublets = misfit ? 15 : 0;
    for (int k = 0; k < d->n_doublets; ++k) {
        d->at[k] = (k + uniform_in(rng, 0.1, 0.9)) * 0.1;
        for (int r = 0; r < 6; ++r)
            d->amp[k][r] =
                (r < 3 ? SIGMA_F : SIGMA_T) * 10 * (loadid_rng_uniform(rng) < 0.5 ? -1 : 1);
    }
}

/* Sample k (1 kHz with 0.2 ms of jitter): its time, the regressor C of
 * the true motion (RIV's instruments), A of the measured one (white noise
 * on a - g, omega, alpha) and the wrench. */
static void sample(loadid_rng_t *rng, const draw_t *d, int k, int64_t *t_us, loadid_real_t A[60],
                   loadid_real_t C[60], loadid_real_t y[6]) {
    *t_us = (int64_t)k * 1000 + (int64_t)llround(uniform_in(rng, -200, 200));
    const double t = (double)*t_us * 1e-6;
    loadid_real_t spec[3], omega[3], alpha[3];
    motion(d->w, t, spec, omega, alpha);
    assert_int_equal(loadid_regressor(spec, omega, alpha, C), 0);
    for (int r = 0; r < 6; ++r) {
        double v = (r < 3 ? SIGMA_F : SIGMA_T) * loadid_rng_normal(rng);
        for (int j = 0; j < 10; ++j) v += (double)C[r * 10 + j] * phi_true[j];
        for (int m = 0; m < d->n_doublets; ++m) v += d->amp[m][r] * doublet(t, d->at[m]);
        y[r] = (loadid_real_t)v;
    }
    for (int i = 0; i < 3; ++i) {
        spec[i] += (loadid_real_t)(noise_spec * loadid_rng_normal(rng));
        omega[i] += (loadid_real_t)(noise_omega * loadid_rng_normal(rng));
        alpha[i] += (loadid_real_t)(noise_alpha * loadid_rng_normal(rng));
    }
    assert_int_equal(loadid_regressor(spec, omega, alpha, A), 0);
}

static loadid_est_t *estimator(loadid_method_t method) {
    loadid_est_config_t cfg;
    assert_int_equal(loadid_est_config_default(method, 10, &cfg), 0);
    for (int r = 0; r < 6; ++r) cfg.row_sigma[r] = (loadid_real_t)(r < 3 ? SIGMA_F : SIGMA_T);
    loadid_est_t *est = NULL;
    assert_int_equal(loadid_est_create(&cfg, &est), 0);
    return est;
}

/* The bands straight from the definition: at every sample's own time,
 * sum_k D x_k exp(-2 pi i j t_k / T) over the weighted [A y] (or C) of
 * rows row0..row0+2 at bin j, added into g as w Re(X^H X). */
typedef struct {
    int64_t t[SAMPLES];
    loadid_real_t A[SAMPLES][60], C[SAMPLES][60], y[SAMPLES][6];
} rows_t;
static rows_t kept;

static void direct_gram(int j, int row0, int instruments, double *g) {
    const int m = instruments ? 10 : 11;
    const double span = (double)(kept.t[SAMPLES - 1] - kept.t[0]) * SAMPLES / (SAMPLES - 1);
    const double w = (j == 0 ? 1.0 : 2.0) / SAMPLES;
    for (int row = row0; row < row0 + 3; ++row) {
        double re[11] = {0}, im[11] = {0};
        const double d = 1.0 / (row < 3 ? SIGMA_F : SIGMA_T);
        for (int k = 0; k < SAMPLES; ++k) {
            const double th = -TWO_PI * j * (double)(kept.t[k] - kept.t[0]) / span;
            for (int a = 0; a < m; ++a) {
                const double x = d * (double)(instruments ? kept.C[k][row * 10 + a]
                                              : a < 10    ? kept.A[k][row * 10 + a]
                                                          : kept.y[k][row]);
                re[a] += x * cos(th), im[a] += x * sin(th);
            }
        }
        for (int b = 0; b < m; ++b)
            for (int a = 0; a < m; ++a) g[b * m + a] += w * (re[a] * re[b] + im[a] * im[b]);
    }
}

static double frobenius(const double *a, int n) {
    double s = 0;
    for (int i = 0; i < n; ++i) s += a[i] * a[i];
    return sqrt(s);
}

static void test_bands_are_the_dft_of_the_rows(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 7);
    draw_t d;
    new_draw(&rng, 1, &d);
    loadid_spectrum_rows_t *rows = NULL;
    assert_int_equal(loadid_spectrum_rows_create(SAMPLES, 10, 1, &rows), 0);
    for (int k = 0; k < SAMPLES; ++k) {
        sample(&rng, &d, k, &kept.t[k], kept.A[k], kept.C[k], kept.y[k]);
        loadid_spectrum_rows_add(rows, kept.t[k], kept.A[k], kept.C[k], kept.y[k]);
    }
    assert_int_equal(loadid_spectrum_rows_transform(rows), 0);
    const loadid_real_t sigma[6] = {SIGMA_F, SIGMA_F, SIGMA_F, SIGMA_T, SIGMA_T, SIGMA_T};
    assert_int_equal(loadid_spectrum_rows_bands(rows, sigma, &bands), 0);
    assert_int_equal(bands.samples, SAMPLES);
    assert_true(bands.has_iv);
    double worst = 0, worst_iv = 0;
    for (int b = 0; b < bands.n_bands; ++b)
        for (int g = 0; g < 2; ++g) {
            double want[121] = {0}, want_iv[100] = {0}, diff[121], diff_iv[100];
            for (int j = bands.first_bin[b]; j < bands.first_bin[b + 1]; ++j) {
                direct_gram(j, 3 * g, 0, want);
                direct_gram(j, 3 * g, 1, want_iv);
            }
            for (int i = 0; i < 121; ++i) diff[i] = bands.gram[b][g][i] - want[i];
            for (int i = 0; i < 100; ++i) diff_iv[i] = bands.iv_gram[b][g][i] - want_iv[i];
            const double e = frobenius(diff, 121) / frobenius(want, 121);
            const double e_iv = frobenius(diff_iv, 100) / frobenius(want_iv, 100);
            worst = fmax(worst, e), worst_iv = fmax(worst_iv, e_iv);
        }
    print_message("bands against the direct DFT: worst relative error %.2e ([A y]), %.2e (C)\n",
                  worst, worst_iv);
    /* (2 pi 16 / 1500)^2 (4^2 - 1) / 12 = 0.6 % of the power at the last bin */
    assert_true(worst < 0.006 && worst_iv < 0.006);
    /* The rows apart: each bin's weighted rows give its bands' Gram again. */
    assert_true(bands.has_rows);
    for (int b = 0; b < bands.n_bands; ++b)
        for (int g = 0; g < 2; ++g) {
            double again[121] = {0}, diff[121];
            for (int j = bands.first_bin[b]; j < bands.first_bin[b + 1]; ++j)
                for (int part = 0; part < 2; ++part)
                    for (int row = 3 * g; row < 3 * g + 3; ++row) {
                        const double *x = bands.row_dft[j][part] + row * 11;
                        for (int c = 0; c < 11; ++c)
                            for (int a = 0; a < 11; ++a) again[c * 11 + a] += x[a] * x[c];
                    }
            for (int i = 0; i < 121; ++i) diff[i] = again[i] - bands.gram[b][g][i];
            assert_true(frobenius(diff, 121) <= 1e-12 * frobenius(bands.gram[b][g], 121));
        }
    loadid_spectrum_rows_destroy(rows);
}

/* Over DRAWS draws, least squares' and RIV's z = (phi - phi_true) / std
 * with the white sandwich, with the bands' and with the bands' without
 * the rows apart (one level per row group): RMS per parameter and the
 * share within 2 pooled. */
typedef struct {
    double rms_white[2][10], rms_bands[2][10], rms_group[2][10];
    double cover_white[2], cover_bands[2], cover_group[2];
} z_stats_t;

static void z_stats(int misfit, z_stats_t *out) {
    static const loadid_method_t methods[2] = {LOADID_METHOD_RLS, LOADID_METHOD_RIV};
    memset(out, 0, sizeof *out);
    loadid_rng_t rng;
    loadid_rng_seed(&rng, misfit ? 11 : 12);
    loadid_spectrum_rows_t *rows = NULL;
    assert_int_equal(loadid_spectrum_rows_create(SAMPLES, 10, 1, &rows), 0);
    for (int draw = 0; draw < DRAWS; ++draw) {
        draw_t d;
        new_draw(&rng, misfit, &d);
        loadid_est_t *est[2] = {estimator(methods[0]), estimator(methods[1])};
        loadid_spectrum_rows_reset(rows);
        for (int k = 0; k < SAMPLES; ++k) {
            int64_t t;
            loadid_real_t A[60], C[60], y[6];
            sample(&rng, &d, k, &t, A, C, y);
            assert_int_equal(loadid_est_update(est[0], A, NULL, y), 0);
            assert_int_equal(loadid_est_update(est[1], A, C, y), 0);
            loadid_spectrum_rows_add(rows, t, A, C, y);
        }
        assert_int_equal(loadid_spectrum_rows_transform(rows), 0);
        for (int m = 0; m < 2; ++m) {
            loadid_real_t phi[10], white[10], banded[10], grouped[10], s;
            assert_int_equal(loadid_est_estimate(est[m], phi, NULL), 0);
            assert_int_equal(loadid_est_uncertainty(est[m], phi, white, NULL), 0);
            assert_int_equal(
                loadid_spectrum_rows_bands(rows, loadid_est_config(est[m])->row_sigma, &bands), 0);
            assert_int_equal(loadid_est_uncertainty_spectral(est[m], phi, &bands, banded, &s), 0);
            assert_true(bands.has_rows);
            bands.has_rows = 0;
            assert_int_equal(loadid_est_uncertainty_spectral(est[m], phi, &bands, grouped, &s), 0);
            for (int i = 0; i < 10; ++i) {
                const double e = (double)phi[i] - phi_true[i];
                const double zw = e / (double)white[i], zb = e / (double)banded[i],
                             zg = e / (double)grouped[i];
                out->rms_white[m][i] += zw * zw / DRAWS;
                out->rms_bands[m][i] += zb * zb / DRAWS;
                out->rms_group[m][i] += zg * zg / DRAWS;
                out->cover_white[m] += (fabs(zw) <= 2) / (10.0 * DRAWS);
                out->cover_bands[m] += (fabs(zb) <= 2) / (10.0 * DRAWS);
                out->cover_group[m] += (fabs(zg) <= 2) / (10.0 * DRAWS);
            }
        }
        loadid_est_destroy(est[0]);
        loadid_est_destroy(est[1]);
    }
    loadid_spectrum_rows_destroy(rows);
    for (int m = 0; m < 2; ++m) {
        for (int i = 0; i < 10; ++i) {
            out->rms_white[m][i] = sqrt(out->rms_white[m][i]);
            out->rms_bands[m][i] = sqrt(out->rms_bands[m][i]);
            out->rms_group[m][i] = sqrt(out->rms_group[m][i]);
        }
        print_message(
            "%s %s: coverage white %.3f, bands %.3f (one level a group %.3f); "
            "RMS z white / bands / one level a group:",
            misfit ? "misfit" : "white noise", loadid_method_name(methods[m]), out->cover_white[m],
            out->cover_bands[m], out->cover_group[m]);
        for (int i = 0; i < 10; ++i)
            print_message(" %.2f/%.2f/%.2f", out->rms_white[m][i], out->rms_bands[m][i],
                          out->rms_group[m][i]);
        print_message("\n");
    }
}

static void test_bands_size_a_misfit_at_tens_of_hz(void **state) {
    (void)state;
    z_stats_t z;
    z_stats(1, &z);
    for (int m = 0; m < 2; ++m) {
        assert_true(z.cover_bands[m] >= 0.90 && z.cover_bands[m] <= 0.985);
        for (int i = 0; i < 10; ++i) {
            assert_true(z.rms_white[m][i] < 0.5);
            assert_true(z.rms_bands[m][i] > 0.7 && z.rms_bands[m][i] < 1.35);
        }
    }
}

static void test_bands_keep_white_noise_calibrated(void **state) {
    (void)state;
    z_stats_t z;
    z_stats(0, &z);
    for (int m = 0; m < 2; ++m) {
        assert_true(z.cover_bands[m] >= 0.90 && z.cover_bands[m] <= 0.985);
        for (int i = 0; i < 10; ++i)
            assert_true(z.rms_bands[m][i] > 0.7 && z.rms_bands[m][i] < 1.35);
    }
}

/* The sensor's own accelerometer as a - g and alpha (paper noise: 0.5
 * m/s^2, 5 rad/s^2) under a heavy load off the flange: the regressor's
 * noise, not the wrench's, fills the residual, and reaches a sample's force
 * and torque rows together (m (a - g) and (m c) x (a - g)). RIV (whose
 * instruments see none of it) is calibrated with the rows apart, and one
 * level per row group is narrow. */
static void test_rows_apart_count_a_noise_the_rows_share(void **state) {
    (void)state;
    phi_true = kHeavy, noise_spec = 0.5, noise_alpha = 5;
    z_stats_t z;
    z_stats(0, &z);
    phi_true = kPhi, noise_spec = 0.02, noise_alpha = 0.05;
    const int riv = 1;
    double worst_group = 0;
    assert_true(z.cover_bands[riv] >= 0.92 && z.cover_bands[riv] <= 0.985);
    for (int i = 0; i < 10; ++i) {
        assert_true(z.rms_bands[riv][i] > 0.8 && z.rms_bands[riv][i] < 1.2);
        worst_group = fmax(worst_group, z.rms_group[riv][i]);
    }
    assert_true(worst_group > 1.2);
    /* without the bands, one level per row group (a pooled one: 0.44 on m,
     * 1.57 at worst) */
    for (int i = 0; i < 10; ++i)
        assert_true(z.rms_white[riv][i] > 0.6 && z.rms_white[riv][i] < 1.35);
}

/* With the joint filter's columns (counted exact) the rows apart are not
 * used: least squares' bands give the same std with and without them. */
static void test_exact_columns_keep_one_level_a_group(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 17);
    draw_t d;
    new_draw(&rng, 0, &d);
    phi_true = kHeavy, noise_spec = 0.5, noise_alpha = 5;
    /* the same data, the columns counted exact and measured (the default) */
    loadid_est_t *est[2] = {estimator(LOADID_METHOD_RLS), estimator(LOADID_METHOD_RLS)};
    loadid_real_t exact[11];
    for (int j = 0; j < 11; ++j) exact[j] = j < 10 ? 4 : 1;
    assert_int_equal(loadid_est_set_exact(est[0], exact), 0);
    loadid_spectrum_rows_t *rows = NULL;
    assert_int_equal(loadid_spectrum_rows_create(SAMPLES, 10, 0, &rows), 0);
    for (int k = 0; k < SAMPLES; ++k) {
        int64_t t;
        loadid_real_t A[60], C[60], y[6];
        sample(&rng, &d, k, &t, A, C, y);
        for (int m = 0; m < 2; ++m) assert_int_equal(loadid_est_update(est[m], A, NULL, y), 0);
        loadid_spectrum_rows_add(rows, t, A, NULL, y);
    }
    phi_true = kPhi, noise_spec = 0.02, noise_alpha = 0.05;
    assert_int_equal(loadid_spectrum_rows_transform(rows), 0);
    double moved[2] = {0, 0};
    for (int m = 0; m < 2; ++m) {
        const loadid_real_t *sigma = loadid_est_config(est[m])->row_sigma;
        assert_int_equal(loadid_spectrum_rows_bands(rows, sigma, &bands), 0);
        loadid_real_t phi[10], apart[10], grouped[10], s;
        assert_int_equal(loadid_est_estimate(est[m], phi, NULL), 0);
        assert_int_equal(loadid_est_uncertainty_spectral(est[m], phi, &bands, apart, &s), 0);
        bands.has_rows = 0;
        assert_int_equal(loadid_est_uncertainty_spectral(est[m], phi, &bands, grouped, &s), 0);
        for (int i = 0; i < 10; ++i)
            moved[m] = fmax(moved[m], fabs((double)apart[i] / (double)grouped[i] - 1));
        loadid_est_destroy(est[m]);
    }
    print_message("the rows apart move std by up to %.1f %% (exact columns), %.1f %% (measured)\n",
                  100 * moved[0], 100 * moved[1]);
    assert_true(moved[0] == 0);
    assert_true(moved[1] > 0.05);
    loadid_spectrum_rows_destroy(rows);
}

static void test_spectra_that_do_not_fit_are_refused(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 13);
    draw_t d;
    new_draw(&rng, 0, &d);
    loadid_est_t *rls = estimator(LOADID_METHOD_RLS), *riv = estimator(LOADID_METHOD_RIV);
    loadid_spectrum_rows_t *rows = NULL, *no_c = NULL;
    assert_int_equal(loadid_spectrum_rows_create(SAMPLES, 10, 1, &rows), 0);
    assert_int_equal(loadid_spectrum_rows_create(SAMPLES, 10, 0, &no_c), 0);
    assert_int_equal(loadid_spectrum_rows_bands(rows, (loadid_real_t[6]){1, 1, 1, 1, 1, 1}, &bands),
                     -EINVAL); /* not transformed */
    for (int k = 0; k < SAMPLES; ++k) {
        int64_t t;
        loadid_real_t A[60], C[60], y[6];
        sample(&rng, &d, k, &t, A, C, y);
        if (k == 0) { /* a sample with a NaN reaches neither */
            loadid_real_t bad[6] = {NAN, 0, 0, 0, 0, 0};
            assert_int_equal(loadid_est_update(rls, A, NULL, bad), LOADID_E_NONFINITE);
            loadid_spectrum_rows_add(rows, t, A, C, bad);
        }
        assert_int_equal(loadid_est_update(rls, A, NULL, y), 0);
        assert_int_equal(loadid_est_update(riv, A, C, y), 0);
        loadid_spectrum_rows_add(rows, t, A, C, y);
        loadid_spectrum_rows_add(no_c, t, A, NULL, y);
    }
    assert_int_equal(loadid_spectrum_rows_count(rows), SAMPLES);
    /* a full store counts the sample as lost: its bands are not the data */
    loadid_spectrum_rows_add(rows, 2000000, kept.A[0], kept.C[0], kept.y[0]);
    assert_int_equal(loadid_spectrum_rows_transform(rows), -ENOSPC);
    loadid_spectrum_rows_reset(rows);
    assert_int_equal(loadid_spectrum_rows_transform(rows), LOADID_E_NOT_EXCITED);
    assert_int_equal(loadid_spectrum_rows_transform(no_c), 0);
    const loadid_real_t *sigma = loadid_est_config(rls)->row_sigma;
    assert_int_equal(loadid_spectrum_rows_bands(no_c, sigma, &bands), 0);
    assert_false(bands.has_iv);
    loadid_real_t phi[10], std[10];
    assert_int_equal(loadid_est_estimate(rls, phi, NULL), 0);
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, &bands, std, NULL), 0);
    assert_int_equal(loadid_est_uncertainty_spectral(riv, phi, &bands, std, NULL), -EINVAL);
    bands.samples--;
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, &bands, std, NULL), -EINVAL);
    bands.samples++;
    bands.first_bin[3] = bands.first_bin[2];
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, &bands, std, NULL), -EINVAL);
    assert_int_equal(loadid_spectrum_rows_bands(no_c, sigma, &bands), 0);
    bands.gram[2][1][5] = NAN;
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, &bands, std, NULL),
                     LOADID_E_NONFINITE);
    assert_int_equal(loadid_spectrum_rows_bands(no_c, sigma, &bands), 0);
    bands.row_dft[16][1][7] = NAN;
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, &bands, std, NULL),
                     LOADID_E_NONFINITE);
    bands.has_rows = 0; /* the rows apart are optional */
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, &bands, std, NULL), 0);
    assert_int_equal(loadid_spectrum_rows_bands(no_c, sigma, &bands), 0);
    bands.first_bin[bands.n_bands] = LOADID_SPECTRUM_BINS + 1; /* more bins than the rows have */
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, &bands, std, NULL), -EINVAL);
    assert_int_equal(loadid_est_uncertainty_spectral(rls, phi, NULL, std, NULL), -EINVAL);
    loadid_spectrum_rows_destroy(rows);
    loadid_spectrum_rows_destroy(no_c);
    loadid_est_destroy(rls);
    loadid_est_destroy(riv);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bands_are_the_dft_of_the_rows),
        cmocka_unit_test(test_bands_size_a_misfit_at_tens_of_hz),
        cmocka_unit_test(test_bands_keep_white_noise_calibrated),
        cmocka_unit_test(test_rows_apart_count_a_noise_the_rows_share),
        cmocka_unit_test(test_exact_columns_keep_one_level_a_group),
        cmocka_unit_test(test_spectra_that_do_not_fit_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
