/*
 * Joint-space Kalman filter (paper sec. V.C): one independent filter per
 * joint turns sampled encoder positions into q, qd, qdd on-line. The model
 * is a triple integrator driven by white jerk:
 *   x = [q, qd, qdd],  x_k+1 = F(dt) x_k + w,  F = [1 dt dt^2/2; 0 1 dt; 0 0 1],
 *   Q(dt) = jerk_psd [dt^5/20 dt^4/8 dt^3/6; dt^4/8 dt^3/3 dt^2/2; dt^3/6 dt^2/2 dt],
 *   z_k = q_k + v,  var(v) = meas_sigma^2,
 * with dt taken from the time stamps, so irregular sampling is handled.
 * jerk_psd sets the bandwidth: larger follows faster trajectories with
 * less lag and more noise. loadid_jf_smooth runs the same model forwards
 * and backwards (Rauch-Tung-Striebel) over a whole recording, for offline
 * use: no lag and less noise.
 * After create nothing here allocates, locks or makes a system call.
 */
#ifndef LOADID_JOINT_FILTER_H
#define LOADID_JOINT_FILTER_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    /* Power spectral density of the white jerk [rad^2/s^5 or m^2/s^5].
     * With the measurement noise density meas_sigma^2 T (T the sample
     * period) it sets the bandwidth w_c = (jerk_psd / (meas_sigma^2 T))^(1/6)
     * rad/s: the steady-state filter is close to a third-order Butterworth
     * low pass of qdd with cut-off w_c, qdd lagging by about 2 / w_c. Each
     * factor 10 moves w_c by 10^(1/6) = 1.47.
     * Default 1e3, tuned for joint motion up to 2 Hz from 2^20-count
     * encoders at 1 kHz: w_c = 833 rad/s, qdd gain -3 dB at 135 Hz, lag
     * 2.0 ms. On a multi-sine of 0.8, 0.5, 0.3 rad at 0.5, 1.1, 2 Hz (qdd
     * 36 rad/s^2 RMS), after 50 ms of settling: qdd RMS error 1.06 rad/s^2,
     * qd 1.6e-3 rad/s (the same with +-200 us jitter and in float); the
     * smoother 0.26 rad/s^2 and 3.8e-4 rad/s, without lag. That RMS error
     * is the lowest over jerk_psd (1.34 at 1e2, 1.62 at 1e4; lag against
     * noise), tests/unit/test_joint_filter.c asserts the figures. */
    loadid_real_t jerk_psd;
    /* Standard deviation of a position measurement [rad or m]. Default
     * 2 pi / 2^20 / sqrt(12), the quantisation noise of a 2^20-count
     * encoder. */
    loadid_real_t meas_sigma;
    /* Standard deviations of the initial velocity and acceleration (the
     * first measurement sets q; qd and qdd start at 0). Default 1 and 10
     * [rad/s, rad/s^2]: the filter settles within about 10 ms anyway. */
    loadid_real_t init_sigma_vel;
    loadid_real_t init_sigma_acc;
    /* A step longer than this between two updates [us] restarts the
     * filters from the new measurement (a stream that stalled is not
     * bridged by extrapolation). Default 100000 (0.1 s); the daemon sets
     * kalman.max_joint_age_s (setup.c). */
    int64_t max_step_us;
    /* Fixed-lag smoothing (loadid_jf_lagged_state_at): the state of an
     * update is smoothed with the lag_steps updates after it, by the
     * steady-state fixed-lag smoother of this model at a step of
     * nominal_step_us (x(j|j+L) = x(j|j-1) + sum_i B_i nu(j+i), B_i =
     * P- [(F (I - K H))^T]^i H^T / s; Anderson & Moore 1979, ch. 7): no
     * lag in the result, the smoother's error instead of the filter's, for
     * L steps of delay. 0 (default) turns it off; at most
     * LOADID_JF_MAX_LAG. nominal_step_us: default 1000 (1 kHz). */
    int lag_steps;
    int64_t nominal_step_us;
} loadid_jf_config_t;

#define LOADID_JF_MAX_LAG 200

/* Fills cfg with the defaults. Returns 0 or -EINVAL. */
int loadid_jf_config_default(loadid_jf_config_t *cfg);

typedef struct loadid_jf loadid_jf_t; /* opaque: num_joints filters */

/* Returns 0, -EINVAL (NULL pointer, num_joints outside 1..16, a config
 * value not finite and > 0) or -ENOMEM. The only allocation. */
int loadid_jf_create(int num_joints, const loadid_jf_config_t *cfg, loadid_jf_t **out);

void loadid_jf_destroy(loadid_jf_t *jf);

/* A new configuration (a joint stream's period learnt after create:
 * nominal_step_us, lag_steps, max_step_us): the steady gains and settle
 * count derived again, every measurement forgotten. Allocates nothing.
 * Returns 0 or -EINVAL (NULL, or a config create would refuse; jf then
 * unchanged). */
int loadid_jf_configure(loadid_jf_t *jf, const loadid_jf_config_t *cfg);

/* Another measurement noise (the positions measured noisier than
 * configured) and fixed lag: the gains and settle count derived again, and
 * the current piece's kept updates (the last 2 LOADID_JF_MAX_LAG + 1)
 * filtered again with them, from the prior at the oldest as at a restart:
 * the state and the smoother's history are then the ones a filter so
 * tuned would have from there (settled when more than settle updates were
 * kept). Kept as they were, the state would carry the old gains' errors,
 * far beyond its covariance, for many settle counts of the new gains.
 * Allocates nothing. Returns 0 or -EINVAL (NULL, a meas_sigma or
 * lag_steps create would refuse; jf then unchanged). */
int loadid_jf_retune(loadid_jf_t *jf, loadid_real_t meas_sigma, int lag_steps);

/* Forgets every measurement. Returns 0 or -EINVAL. */
int loadid_jf_reset(loadid_jf_t *jf);

/* One measurement of all joints at time t_us. The first one (and the
 * first after a gap over max_step_us) initialises the filters.
 * Returns 0; -EINVAL (NULL pointer); LOADID_E_NONFINITE or
 * LOADID_E_TIME_ORDER (t_us not after the previous update): both leave
 * the filters unchanged. */
int loadid_jf_update(loadid_jf_t *jf, int64_t t_us, const loadid_real_t *q);

/* The filtered state propagated by the model to t_us, before or after the
 * last update (the filters themselves do not change). Any output may be
 * NULL. Returns 0, -EINVAL, or LOADID_E_NO_DATA before the first update. */
int loadid_jf_state_at(const loadid_jf_t *jf, int64_t t_us, loadid_real_t *q, loadid_real_t *qd,
                       loadid_real_t *qdd);

/* Time of the last accepted update [us]; INT64_MIN before the first. */
int64_t loadid_jf_last_time(const loadid_jf_t *jf);

/* After the first update and after every restart (a gap over
 * max_step_us) the filter serves no sample from its first settle updates:
 * it starts from its prior (qd = qdd = 0, init_sigma_*), and only
 * once its predicted covariance of q, qd and qdd is within 1.5 times the
 * steady state's is its mean the motion's; before, the fixed-lag
 * smoother's steady-state gains amplify its large innovations (after a
 * 0.3 s stall that cost RTLS 55 % of the mass). settle is the number of
 * updates at nominal_step_us from the prior until then: 15 at jerk_psd 1
 * and 1 kHz (the daemon's defaults). Returns it, or -EINVAL. */
int loadid_jf_settle_steps(const loadid_jf_t *jf);

/* 1 when the newest update is at least settle updates after the
 * filter's (re)start (its state may serve a sample), else 0 (also for
 * NULL). */
int loadid_jf_settled(const loadid_jf_t *jf);

/* With lag_steps > 0: the newest time the fixed-lag smoother can serve
 * now: 1 us before the first update of the current piece of the series
 * that has fewer than lag_steps updates after it; while the current piece
 * (since a restart after a gap, or loadid_jf_end_piece) has none with so
 * many, the newest update of the piece before it (served with the updates
 * it had); INT64_MIN when there is nothing. */
int64_t loadid_jf_lagged_time(const loadid_jf_t *jf);

/* The joint stream has stopped (no update is coming for a while): the
 * updates kept are served from now on with those after them that exist,
 * as at a gap; the filter itself goes on unchanged. Returns 0 or -EINVAL. */
int loadid_jf_end_piece(loadid_jf_t *jf);

/* With lag_steps > 0: the smoothed state at t_us, from the newest kept
 * update at or before t_us (the last 2 LOADID_JF_MAX_LAG + 1 are kept, so a
 * sensor sample that arrives late is still served), with the
 * lag_steps updates after it, or, in a piece that ended at a gap, with
 * those it had; between two updates of a piece, qdd interpolated between
 * their smoothed states (q and qd propagated with that jerk), else
 * propagated by the model to t_us. Returns 0; -EINVAL (NULL
 * jf, or lag_steps 0); LOADID_E_NO_DATA (nothing yet, or that update has
 * fewer than lag_steps after it and its piece goes on); LOADID_E_STALE
 * (that update is more than max_age_us before t_us, t_us is before
 * every kept update, or that update is one of the first settle after a
 * (re)start: loadid_jf_settle_steps). Any output may be NULL. The
 * filter keeps the smoothed sums it made (the next call adds only the
 * terms they lack): const as to the data, but not to be called on one
 * filter from two threads at once. */
int loadid_jf_lagged_state_at(const loadid_jf_t *jf, int64_t t_us, int64_t max_age_us,
                              loadid_real_t *q, loadid_real_t *qd, loadid_real_t *qdd);

/* Number of reals loadid_jf_smooth needs as work space for count samples
 * (18 per sample). */
size_t loadid_jf_smooth_work_size(size_t count);

/* Fixed-interval smoother over one joint's whole series: count samples at
 * strictly increasing times t_us with positions q; writes the smoothed
 * q_out, qd_out, qdd_out (count each; any may be NULL). work holds
 * loadid_jf_smooth_work_size(count) reals. A step over cfg->max_step_us
 * splits the series into pieces smoothed independently (the on-line filter
 * restarts there too); the last sample of a piece is the filter's. The
 * whole input is checked before anything is written. Returns 0, -EINVAL (NULL
 * pointer, count 0, bad config), LOADID_E_NONFINITE or
 * LOADID_E_TIME_ORDER. */
int loadid_jf_smooth(const loadid_jf_config_t *cfg, size_t count, const int64_t *t_us,
                     const loadid_real_t *q, loadid_real_t *work, loadid_real_t *q_out,
                     loadid_real_t *qd_out, loadid_real_t *qdd_out);

/* Standard deviations of the filter's (smoothed = 0) or the RTS
 * smoother's (smoothed = 1) errors of q, qd and qdd [rad, rad/s, rad/s^2
 * or m...] in steady state at a constant step dt_s > 0: the model's own
 * covariance, from the Riccati recursion iterated to convergence (for the
 * smoother, P^s = P + G (P^s - P^-) G^T, G = P F^T (P^-)^-1). This is the
 * noise of what the joints give the estimators, under the white-jerk
 * model. Returns 0 or -EINVAL (NULL, bad config, dt_s not finite > 0). */
int loadid_jf_steady_sigma(const loadid_jf_config_t *cfg, double dt_s, int smoothed,
                           double sigma[3]);

/* The measurement noise's share of the errors of q, qd and qdd, in steady
 * state at a constant step dt_s: the on-line filter's (cfg->lag_steps 0)
 * or the fixed-lag smoother's (lag_steps > 0), from their impulse response
 * to a position measurement (sigma^2 = meas_sigma^2 sum_k h_k^2). Unlike
 * loadid_jf_steady_sigma this leaves out the white-jerk model's process
 * noise, which a smooth motion does not have: it is the random, motion-
 * independent part of the error, what TLS's column weights are for.
 * Returns 0 or -EINVAL. */
int loadid_jf_noise_sigma(const loadid_jf_config_t *cfg, double dt_s, double sigma[3]);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_JOINT_FILTER_H */
