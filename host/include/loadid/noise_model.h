/*
 * The measured noise model (configuration "noise: auto"): how noisy each
 * input of the estimators really is, so that the weights D and T of eq. (24)
 * fit the sensor at hand rather than a data sheet.
 *
 *   wrench and accelerometer channels (12: f, tau, a - g, alpha; x y z):
 *     - in the zeroing window, the spread about the median (the load is
 *       still, so all that moves is noise, vibration included);
 *     - at any time, also without a still phase, from third differences:
 *       x_k - 3 x_k-1 + 3 x_k-2 - x_k-3 has variance 20 sigma^2 for white
 *       noise, while 2 Hz motion sampled at 1 kHz leaves (2 pi f dt)^3 ~ 2e-6
 *       of its amplitude in it (the residual of a local quadratic fit);
 *       over the last 1024 consecutive samples.
 *     Both use the median absolute deviation (sigma = 1.4826 MAD), so a
 *     bit error or a spike in the window does not pass for noise (a
 *     standard deviation read 18 N for 0.1 N of noise with 5 % bit errors).
 *   joint-derived signals (omega, alpha, a - g of the kf/mixed/setpoint
 *     sources): the joint filter's own steady-state covariance of qd and qdd
 *     (loadid_jf_steady_sigma), mapped into S through the kinematics: alpha
 *     and a - g are linear in qdd, so each joint's column of that map comes
 *     from two forward-kinematics evaluations at the pose.
 * Each level the configuration gives (noise.*, kalman.spec_sigma,
 * kalman.alpha_sigma) overrides the measured one. What was measured and
 * what was used is reported (loadid_noise_levels_t).
 * Nothing here allocates or makes a system call.
 */
#ifndef LOADID_NOISE_MODEL_H
#define LOADID_NOISE_MODEL_H

#include <stdint.h>

#include "loadid/config.h"
#include "loadid/core.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { LOADID_NOISE_CHANNELS = 12 }; /* f xyz, tau xyz, a - g xyz, alpha xyz */

/* Where a channel's level came from. */
enum {
    LOADID_NOISE_FALLBACK = 0,    /* nothing measured: the configuration's fallback */
    LOADID_NOISE_STILL = 1,       /* the zeroing window */
    LOADID_NOISE_DIFFERENCES = 2, /* third differences while moving */
    LOADID_NOISE_CONFIGURED = 3,  /* given in the configuration */
    LOADID_NOISE_FILTER = 4       /* the joint filter's covariance */
};

#define LOADID_NOISE_STILL_MAX 4096 /* zeroing-window samples kept (the first) */
#define LOADID_NOISE_D3_RING 1024   /* third differences kept (the last) */

typedef struct {
    /* still window */
    int still_n;
    double still[LOADID_NOISE_STILL_MAX][LOADID_NOISE_CHANNELS];
    /* third differences */
    double hist[3][LOADID_NOISE_CHANNELS];
    int hist_n;
    int64_t last_t_us;
    double d3[LOADID_NOISE_D3_RING][LOADID_NOISE_CHANNELS];
    int d3_n, d3_head;
    double scratch[LOADID_NOISE_STILL_MAX], scratch2[LOADID_NOISE_STILL_MAX]; /* medians */
    /* The load moved in the still window (loadid_noise_acc_moved): its
     * statistics are then those of what a cubic in time leaves, per
     * channel (trend: the cubics' coefficients). */
    int moved;
    double trend[LOADID_NOISE_CHANNELS][4];
} loadid_noise_acc_t;

/* The levels the estimators use (standard deviations). */
typedef struct {
    double force, torque; /* [N], [N m] */
    double spec, alpha;   /* a - g [m/s^2], alpha [rad/s^2], of the source used */
    double omega;         /* [rad/s] */
    int source[5];        /* LOADID_NOISE_* of force, torque, spec, alpha, omega */
    /* what was measured, for the report */
    double channel[LOADID_NOISE_CHANNELS];       /* per channel, 0 when not measured */
    int channel_source;                          /* LOADID_NOISE_STILL, _DIFFERENCES or _FALLBACK */
    double joint_spec, joint_alpha, joint_omega; /* from the joint filter; 0 if none */
    double correlation[2];                       /* lag-1 correlation of the force and the torque
                              noise in the zeroing window; 0 if none */
    double tone_share[2], tone_hz[2];            /* a - g, alpha: loadid_noise_tone; 0 if none */
    double notch_hz[2];    /* a - g, alpha: the notch on the rows at its tone; 0 if none */
    double joint_position; /* the joint positions' own noise over the window (the largest
                              joint's, loadid_signals_position_noise); 0 until DONE */
} loadid_noise_levels_t;

void loadid_noise_acc_reset(loadid_noise_acc_t *a);
/* Only the still-window part (a new ZERO). */
void loadid_noise_acc_reset_still(loadid_noise_acc_t *a);
/* One sample in the zeroing window. */
void loadid_noise_acc_still(loadid_noise_acc_t *a, const double x[LOADID_NOISE_CHANNELS]);
/* Every usable sample (any state): third differences of consecutive ones;
 * a step over 3 nominal periods (period_us) restarts the history. */
void loadid_noise_acc_moving(loadid_noise_acc_t *a, int64_t t_us, int64_t period_us,
                             const double x[LOADID_NOISE_CHANNELS]);
/* The load moved while it was zeroed (no still phase): the window's
 * wrench then varies with the motion as well, slowly against the noise,
 * and the still window's figures below become those of each channel less
 * its least-squares cubic in time over the window. Only on evidence of
 * motion: a cubic over the window would also take in the slow part of a
 * low-pass filtered sensor's noise, which sets the zeroing offset's error.
 * Cleared by loadid_noise_acc_reset_still. */
void loadid_noise_acc_moved(loadid_noise_acc_t *a);

/* Per-channel standard deviations (the root mean square of the values
 * within 5 of their median absolute deviation's sigma: robust to bit
 * errors, and a variance, which the weights need, for noise that is not
 * normal): the still window when it has at least min_still samples, else
 * the third differences when they have 100, else 0; returns the source
 * (LOADID_NOISE_STILL / _DIFFERENCES / _FALLBACK).
 * Uses a's scratch space. */
int loadid_noise_acc_sigma(loadid_noise_acc_t *a, int min_still,
                           double sigma[LOADID_NOISE_CHANNELS]);

/* The covariance of the zeroing offset y0 (the wrench channels' mean over
 * n_mean still samples; 6 x 6 row-major, N^2, N Nm, Nm^2) from the still
 * window: the channels' sample covariance over n_mean, each channel's
 * share widened by its long-run factor sqrt((1 + r) / (1 - r)), r its
 * lag-1 autocorrelation in [-0.5, 0.95] (an AR(1) noise: a sensor's low-pass
 * filter makes successive samples alike, and their mean then varies more
 * than sigma^2 / n). rho (may be NULL): the six r. Returns 0, or -EAGAIN
 * with fewer than 2 still samples or n_mean < 1 (cov zero). */
int loadid_noise_offset_cov(const loadid_noise_acc_t *a, int64_t n_mean, double cov[36],
                            double rho[6]);

/* How much of a channel group's noise in the still window is one tone (a
 * structural vibration): of the window's first LOADID_NOISE_TONE_N
 * samples of x, y and z (each less its mean, or its cubic when the load
 * moved), the share of their variance that one least-squares sinusoid
 * explains, and its frequency (within a bin of the transform's largest).
 * White noise spreads its variance over the n / 2 bins (the best sinusoid
 * about 4 % at n = 256); a vibration is most of it. group: 0 force, 1 torque, 2 a - g, 3 alpha;
 * period_s: the samples' spacing. Returns 0, -EINVAL (a bad group or
 * period), or -EAGAIN with fewer than 32 still samples (share, hz 0). */
#define LOADID_NOISE_TONE_N 256
int loadid_noise_tone(const loadid_noise_acc_t *a, int group, double period_s, double *share,
                      double *hz);
/* The same over any three channels, x[3 k + c] for n samples period_s
 * apart: the largest tone of its consecutive blocks of
 * LOADID_NOISE_TONE_N samples (one block of all n when fewer; a tail
 * shorter than a block is left out), each block less its mean. Returns 0,
 * -EINVAL or -EAGAIN (n < 32; share, hz 0). */
int loadid_noise_tone_blocks(const double *x, int n, double period_s, double *share, double *hz);

/* Per-channel standard deviations of the still window (as
 * loadid_noise_acc_sigma's, about the fit) once each channel's
 * least-squares sinusoids at hz[0..n_hz) and its mean are taken out: the
 * noise a notch on those tones leaves, before the notch's own gain on it.
 * Uses a's scratch space. Returns 0, -EINVAL (n_hz out of 0 ..
 * LOADID_NOISE_TONES_MAX, a frequency not above 0, a bad period), -EAGAIN
 * (fewer than 4 samples per fitted parameter) or -EDOM (two tones closer
 * than 1 / (n period_s), or a fit that fails). */
#define LOADID_NOISE_TONES_MAX 2
int loadid_noise_still_sigma_without(loadid_noise_acc_t *a, const double *hz, int n_hz,
                                     double period_s, double sigma[LOADID_NOISE_CHANNELS]);

/* The joint-derived levels at one pose: omega from the filter's qd error,
 * alpha and a - g from its qdd error through the kinematics (kin at q).
 * sigma_qd, sigma_qdd: loadid_jf_steady_sigma's [1] and [2]. Returns 0 or
 * the kinematics' code. */
int loadid_noise_joint_levels(const loadid_kin_t *kin, const loadid_real_t *q, double sigma_qd,
                              double sigma_qdd, double *spec, double *alpha, double *omega);

/* The root mean square of three channels' levels (a group's level). */
double loadid_noise_rms3(const double v[3]);

/* Combines the configuration's overrides, the measured channels and the
 * joint levels for a signal source into the estimators' levels.
 * jr3_spec / jr3_alpha: the source takes a - g / alpha from the sensor's
 * accelerometer. */
void loadid_noise_combine(const loadid_config_t *cfg, int jr3_spec, int jr3_alpha,
                          const double channel[LOADID_NOISE_CHANNELS], int channel_source,
                          double joint_spec, double joint_alpha, double joint_omega,
                          loadid_noise_levels_t *out);

/* loadid_est_weights_from_noise with these levels; a level measured from
 * the joint filter (LOADID_NOISE_FILTER) enters a thousandth of itself,
 * so its columns count as exact (noise_model.c says why), and col_exact
 * says by how much each column's weight exceeds its noise's (for the
 * excitation gates; set it with loadid_est_set_exact), col_measured the
 * share of each column's noise variance from the measured sources (for
 * least squares' phi_std; loadid_est_set_measured). */
int loadid_noise_weights(const loadid_noise_levels_t *lv, double omega_typical,
                         loadid_est_config_t *est);

const char *loadid_noise_source_name(int source);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_NOISE_MODEL_H */
