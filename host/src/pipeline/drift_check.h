/* Does the F/T offset drift after zeroing? (the zeroed model, eqs. 7-9)
 *
 * Zeroing takes the offset as constant from the zeroing window on; a
 * sensor that warms up drifts, and on slow motion the fit turns that
 * drift into phi (a UR5's mass 6 % off at 0.8 % phi_std, 0.05 N/s). The
 * check fits weighted least squares on [A  tau E6], tau the time since
 * the zeroing window's mean sample time (the offset is zero there), beside
 * the zeroed model's A alone: their difference in phi is the drift's
 * pull. Whether the drift is there at all is a Wald test of its six rates
 * whose variance is the delete-a-block jackknife over blocks of 100 ms:
 * the misfit of the motion model (servo lag, backlash) is correlated over
 * many samples, and a white-noise variance found a drift in most fast
 * trajectories. Even so the test is liberal there (p < 1e-4 in 8 % of
 * the study's fast recordings with backlash, README); a drift of 0.05 N/s
 * on slow motion gave p under 3e-6. The per-sample work is sums (about
 * 250 multiply-adds, no allocation); the test runs once, at DONE. */
#ifndef LOADID_PIPELINE_DRIFT_CHECK_H
#define LOADID_PIPELINE_DRIFT_CHECK_H

#include <stdint.h>

#include "loadid/types.h"

#define LOADID_DRIFT_COLS 16 /* A's 10, tau E6 */
#define LOADID_DRIFT_SUMS (LOADID_DRIFT_COLS * (LOADID_DRIFT_COLS + 1) / 2 + LOADID_DRIFT_COLS + 1)
#define LOADID_DRIFT_MAX_BLOCKS 32
#define LOADID_DRIFT_MIN_BLOCKS 10 /* fewer: the jackknife is too rough to test */

typedef struct {
    int64_t t0_us;
    double w[2];            /* the force and the torque rows' weights, 1 / sigma^2 */
    int64_t block_us;       /* a block's time */
    int64_t block_start_us; /* the current block's, INT64_MIN before the first sample */
    int64_t block_end_us, last_us;
    int blocks, in_block; /* blocks closed; samples in the current one */
    int64_t samples;
    double cum[LOADID_DRIFT_SUMS];                               /* G (packed lower), b, y^T W y */
    double snap[LOADID_DRIFT_MAX_BLOCKS + 1][LOADID_DRIFT_SUMS]; /* cum at the blocks' ends */
    /* RIV's: sum C^T W A (10 x 10, row-major) and sum tau C^T W E6 (10 x 6) */
    double iv_m[100], iv_tau[60];
    int64_t iv_samples, iv_seen;
} loadid_drift_check_t;

typedef struct {
    int tested;           /* enough blocks and a solvable fit */
    int blocks;           /* K */
    double rate[6];       /* the drift, N/s and N m/s */
    double pull[10];      /* phi without the drift columns less phi with them */
    double extra_var[10]; /* what fitting the rates adds to phi's variance: the larger of
                             the white s^2 cost and the pull's block jackknife */
    double p_value;       /* of F = (K - 6) / (6 (K - 1)) W on F(6, K - 6), W = rate^T V^-1
                             rate, V the jackknife's */
} loadid_drift_result_t;

/* Empty sums; tau from t0_us; rows weighted by the noise levels. */
void loadid_drift_check_reset(loadid_drift_check_t *c, int64_t t0_us, double force_sigma,
                              double torque_sigma);

/* One sample: A the zeroed model's 6 x 10 regressor (row-major), y the
 * zeroed wrench (eq. 7). */
void loadid_drift_check_add(loadid_drift_check_t *c, int64_t t_us, const loadid_real_t A[60],
                            const loadid_real_t y[6]);

/* One sample's instruments C (6 x 10, row-major; RIV's, eq. 20) beside its
 * A, for loadid_drift_check_iv_pull. */
void loadid_drift_check_add_instruments(loadid_drift_check_t *c, int64_t t_us,
                                        const loadid_real_t A[60], const loadid_real_t C[60]);

/* What the drift of r moves an IV estimate by: (sum C^T W A)^-1 (sum tau
 * C^T W E6) rate, RIV's counterpart of r->pull (10 values). Returns 0, or
 * -1 without instruments or when their sum is singular. */
int loadid_drift_check_iv_pull(const loadid_drift_check_t *c, const loadid_drift_result_t *r,
                               double pull[10]);

/* The fit and the test over what was added; r->tested 0 when there are
 * too few blocks or the fit is singular. */
void loadid_drift_check_result(const loadid_drift_check_t *c, loadid_drift_result_t *r);

/* P(F > f) for F on F(d1, d2) (a regularised incomplete beta function). */
double loadid_f_upper_tail(double f, double d1, double d2);

#endif
