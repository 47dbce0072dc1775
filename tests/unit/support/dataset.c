/* Test data sets on the synthetic trajectory (dataset.h). */
#include "dataset.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int dataset_make(const dataset_spec_t *spec, dataset_t *out) {
    memset(out, 0, sizeof *out);
    if (!spec || spec->n_samples < 1 ||
        (spec->n_params != LOADID_NPHI && spec->n_params != LOADID_NPHI_OFFSET))
        return -1;
    const int n = spec->n_params, N = spec->n_samples;
    out->n_samples = N;
    out->n_params = n;
    out->A = calloc((size_t)N * 6 * n, sizeof *out->A);
    out->C = calloc((size_t)N * 6 * n, sizeof *out->C);
    out->y = calloc((size_t)N * 6, sizeof *out->y);
    if (!out->A || !out->C || !out->y) {
        dataset_free(out);
        return -1;
    }
    const double *phi = spec->phi ? spec->phi : loadid_synth_phi_o1;
    loadid_synth_traj_t traj;
    loadid_synth_traj_default(&traj, spec->seed);
    loadid_rng_t rng;
    loadid_rng_seed(&rng, spec->seed ^ 0x5DEECE66DULL);
    const loadid_synth_noise_t *noise = &spec->noise;

    /* Exact zeroing in the still start pose. */
    loadid_synth_sample_t z;
    loadid_synth_sample(&traj, phi, 0.0, 1, NULL, NULL, &z);
    double zero[6];
    loadid_real_t g_init[3];
    for (int i = 0; i < 6; ++i) zero[i] = z.wrench_true[i] + noise->offset[i];
    for (int i = 0; i < 3; ++i) g_init[i] = (loadid_real_t)z.truth.g[i];

    memcpy(out->truth, phi, 10 * sizeof(double));
    if (n == LOADID_NPHI_OFFSET) memcpy(out->truth + 10, noise->offset, 6 * sizeof(double));

    for (int k = 0; k < N; ++k) {
        loadid_synth_sample_t s;
        loadid_synth_sample(&traj, phi, k * 1e-3, spec->still, noise, &rng, &s);
        loadid_real_t spec3[3], w[3], al[3], ts[3], tw[3], ta[3], A10[60], C10[60];
        for (int i = 0; i < 3; ++i) {
            spec3[i] = (loadid_real_t)s.meas.spec[i];
            w[i] = (loadid_real_t)s.meas.omega[i];
            al[i] = (loadid_real_t)s.meas.alpha[i];
            ts[i] = (loadid_real_t)s.truth.spec[i];
            tw[i] = (loadid_real_t)s.truth.omega[i];
            ta[i] = (loadid_real_t)s.truth.alpha[i];
        }
        loadid_regressor(spec3, w, al, A10);
        loadid_regressor(ts, tw, ta, C10);
        loadid_real_t *A = out->A + (size_t)k * 6 * n, *C = out->C + (size_t)k * 6 * n;
        loadid_real_t *y = out->y + (size_t)k * 6;
        if (n == LOADID_NPHI) {
            loadid_regressor_add_zeroing(g_init, A10);
            loadid_regressor_add_zeroing(g_init, C10);
            memcpy(A, A10, sizeof A10);
            memcpy(C, C10, sizeof C10);
            for (int i = 0; i < 6; ++i) y[i] = (loadid_real_t)(s.wrench_meas[i] - zero[i]);
        } else {
            loadid_regressor_with_offset(A10, A);
            loadid_regressor_with_offset(C10, C);
            for (int i = 0; i < 6; ++i) y[i] = (loadid_real_t)s.wrench_meas[i];
        }
    }
    return 0;
}

void dataset_free(dataset_t *d) {
    free(d->A);
    free(d->C);
    free(d->y);
    d->A = d->C = d->y = NULL;
}

const loadid_real_t *dataset_A(const dataset_t *d, int k) {
    return d->A + (size_t)k * 6 * d->n_params;
}
const loadid_real_t *dataset_C(const dataset_t *d, int k) {
    return d->C + (size_t)k * 6 * d->n_params;
}
const loadid_real_t *dataset_y(const dataset_t *d, int k) {
    return d->y + (size_t)k * 6;
}

void dataset_config(const dataset_spec_t *spec, loadid_method_t method, loadid_est_config_t *cfg) {
    loadid_est_config_default(method, spec->n_params, cfg);
    const loadid_synth_noise_t *n = &spec->noise;
    if (n->sigma_f > 0 && n->sigma_tau > 0 && n->sigma_spec > 0 && n->sigma_alpha > 0 &&
        n->sigma_omega > 0)
        loadid_est_weights_from_noise(cfg, (loadid_real_t)n->sigma_f, (loadid_real_t)n->sigma_tau,
                                      (loadid_real_t)n->sigma_spec, (loadid_real_t)n->sigma_alpha,
                                      (loadid_real_t)n->sigma_omega, 2);
    cfg->batch_capacity = spec->n_samples;
}

int dataset_feed(const dataset_t *d, loadid_est_t *est, int from, int to) {
    for (int k = from; k < to; ++k) {
        const int rc = loadid_est_update(est, dataset_A(d, k), dataset_C(d, k), dataset_y(d, k));
        if (rc) return rc;
    }
    return 0;
}

int dataset_estimate(const dataset_t *d, const loadid_est_config_t *cfg, loadid_real_t *phi,
                     loadid_est_info_t *info) {
    loadid_est_t *e = NULL;
    int rc = loadid_est_create(cfg, &e);
    if (rc) return rc;
    rc = dataset_feed(d, e, 0, d->n_samples);
    if (!rc) rc = loadid_est_estimate(e, phi, info);
    loadid_est_destroy(e);
    return rc;
}

double max_rel_diff(const loadid_real_t *a, const double *b, int n, double floor) {
    double m = 0;
    for (int i = 0; i < n; ++i) {
        double den = fabs(b[i]) > floor ? fabs(b[i]) : floor;
        double r = fabs((double)a[i] - b[i]) / den;
        if (!(r <= m)) m = r; /* NaN propagates as a failure */
    }
    return m;
}
