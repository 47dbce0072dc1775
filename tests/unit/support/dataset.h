/*
 * Test data sets: (A_k, C_k, y_k) for a load on the synthetic trajectory of
 * tools/synth, in the core's scalar. A is built from the measured (noisy)
 * state by the core's regressor; C (RIV instruments) from the exact state;
 * y is the wrench of eqs. (1)-(2) evaluated directly (tools/synth), with
 * offset and noise. n_params 10: zeroed wrench with the zeroing term of
 * eqs. (7)-(9), zeroed exactly in the still start pose; 16: raw wrench and
 * [A E6], truth = [phi; offset].
 */
#ifndef LOADID_TEST_DATASET_H
#define LOADID_TEST_DATASET_H

#include <stdint.h>

#include "loadid/core.h"
#include "loadid_synth.h"

typedef struct {
    uint64_t seed;              /* trajectory and noise */
    int n_samples;              /* at 1 kHz */
    int n_params;               /* 10 or 16 */
    const double *phi;          /* load, eq. (5); NULL = the paper's o1 */
    loadid_synth_noise_t noise; /* all zero = exact data */
    int still;                  /* 1: every sample in the still start pose (degenerate) */
} dataset_spec_t;

typedef struct {
    int n_samples, n_params;
    loadid_real_t *A, *C, *y; /* 6 x n_params, 6 x n_params, 6 per sample */
    double truth[LOADID_MAX_PARAMS];
} dataset_t;

/* Returns 0, or -1 (bad spec, out of memory). */
int dataset_make(const dataset_spec_t *spec, dataset_t *out);
void dataset_free(dataset_t *d);

/* Pointers to sample k. */
const loadid_real_t *dataset_A(const dataset_t *d, int k);
const loadid_real_t *dataset_C(const dataset_t *d, int k);
const loadid_real_t *dataset_y(const dataset_t *d, int k);

/* A configuration for method with the spec's noise turned into weights
 * (loadid_est_weights_from_noise; unit weights when the data is exact) and
 * a batch capacity that holds the whole set. */
void dataset_config(const dataset_spec_t *spec, loadid_method_t method, loadid_est_config_t *cfg);

/* Feeds samples [from, to) to est; returns the first non-zero update code
 * or 0. */
int dataset_feed(const dataset_t *d, loadid_est_t *est, int from, int to);

/* Creates an estimator from cfg, feeds it every sample, estimates into phi
 * (and info, may be NULL) and destroys it. Returns the first non-zero code of
 * create, update or estimate, or 0. */
int dataset_estimate(const dataset_t *d, const loadid_est_config_t *cfg, loadid_real_t *phi,
                     loadid_est_info_t *info);

/* max_i |a_i - b_i| / max(|b_i|, floor) */
double max_rel_diff(const loadid_real_t *a, const double *b, int n, double floor);

#endif /* LOADID_TEST_DATASET_H */
