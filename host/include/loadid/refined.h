/*
 * REFINED (method 6): when the estimation window ends, one batch TLS over
 * the whole window with zero-lag joint signals and measured weights.
 *
 *   joints   every accepted joint state is kept (a ring of the last
 *            duration + 1 s at 2 kHz; a faster stream is thinned to
 *            that); at the end each joint's measured positions
 *            are smoothed by the RTS smoother of the joint filter's model
 *            (no lag), and q, qd, qdd interpolated to each sensor sample's
 *            time; forward kinematics gives omega, alpha and a - g. The
 *            smoother's bandwidth is chosen from the data: of ten times
 *            kalman.jerk_psd, it and three lower ones (factors of 10),
 *            then half a decade beside the best, the one whose kinematics
 *            let a least-squares fit explain the measured wrench best in
 *            the motion's band (too wide keeps backlash and noise the load
 *            does not feel, too narrow blunts the motion).
 *   delay    the joint stamps' delay against the wrench's (a transport
 *            or clock offset: 5 ms of it cost 14 % of Ixx about the COM),
 *            fitted by Gauss-Newton on the predicted wrench's time
 *            derivative, on the narrowest smoothing of the grid (a wide
 *            one's noise, in the residual and in its derivative alike,
 *            drew the fit towards 0), before the bandwidth trials, which
 *            are then judged at it; a standard error from its scores over
 *            ten stretches of the window; used when 1 ms or more, at
 *            least 3 standard errors, and it lowers the residual
 *            (below 1 ms, the fit sees the misfit's phase too), and then
 *            phi_std gains what its standard error moves phi by;
 *            reported, and warned about when used: the on-line methods
 *            carry it unless kalman.joint_delay_s says it.
 *   sources  a - g, omega and alpha all from the smoothed joints. The
 *            accelerometer's a - g and alpha are not used: in the study
 *            (tools/study) a batch TLS on them had 3.8 times the mass error
 *            and 16 times the inertia error of one on smoothed encoders, and
 *            a vibration or a bias in a channel (which its noise figure
 *            does not show) cannot reach REFINED. Their RMS difference to
 *            the smoothed joints is reported.
 *   drift    with the offset estimated (no zeroing), a linear drift of it
 *            too (a sensor warming up): least squares with columns
 *            (t - t_mid) E6 beside [A E6]; the wrench fed is detrended by
 *            it, and phi_std gains what estimating it costs. With zeroing,
 *            the same with columns (t - t_zero) E6 beside A when the
 *            caller's check found a drift since zeroing (t_zero the
 *            zeroing window's middle, where the zeroed offset is exact).
 *   weights  the smoothed joints' columns are treated as exact (the mixed
 *            LS-TLS limit: their noise set 1e-3 of the smoother's own
 *            covariance, whose white-jerk model overstates the error of a
 *            smooth motion, and with which TLS over-corrected), the rows by
 *            the wrench's measured noise plus what of a first fit's residual
 *            that noise does not explain (backlash between the motor-side
 *            encoders and the load, elasticity, URDF errors); then the final
 *            fit. omega's column scale is the window's RMS |omega|.
 * Runs once, off the per-sample path, on storage allocated at create.
 */
#ifndef LOADID_REFINED_H
#define LOADID_REFINED_H

#include <stdint.h>

#include "loadid/chain.h"
#include "loadid/config.h"
#include "loadid/core.h"
#include "loadid/noise_model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct loadid_refined loadid_refined_t; /* opaque */

typedef struct {
    int64_t samples;              /* fed to the estimator */
    double sensor_spec_error;     /* the accelerometer's RMS difference to the */
    double sensor_alpha_error;    /*   smoothed joints [m/s^2, rad/s^2]; 0 without one */
    double sensor_tone_share[2];  /* a - g, alpha: that difference's largest tone */
    double sensor_tone_hz[2];     /*   (loadid_noise_tone_blocks); 0 without one */
    double unexplained[2];        /* force [N] and torque [N m] residual beyond the
                                  wrench's noise, added to the rows' levels */
    double omega_rms;             /* [rad/s], the column scale used */
    double jerk_psd;              /* the smoother's, chosen from the data */
    int64_t joint_delay_us;       /* the joint stamps' delay against the wrench's,
                                  fitted */
    double joint_delay_std_us;    /* its standard error (Inf when not fitted) */
    int joint_delay_used;         /* REFINED took its kinematics that much later
                                  (a delay of 1 ms or more, at least 3 standard
                                  errors, that lowers the residual) */
    double delay_var[10];         /* what the delay adds to phi's variance: fitting a
                                  used one, or one not told from 0 left out */
    int drift_fitted;             /* the offset's linear drift was fitted (refined_run) */
    double drift[6];              /* [N/s, N m/s], taken out of the wrench fed */
    double drift_var[10];         /* what estimating it adds to phi's variance */
    loadid_noise_levels_t levels; /* the levels the final weights used */
} loadid_refined_report_t;

/* Allocates the stores for cfg's window. Returns 0, -EINVAL or -ENOMEM. */
int loadid_refined_create(const loadid_config_t *cfg, const loadid_chain_t *chain,
                          loadid_refined_t **out);
void loadid_refined_destroy(loadid_refined_t *r);

/* An accepted joint state (measured positions); one less than 0.5 ms after
 * the last kept is left out (the ring holds 2 kHz). */
void loadid_refined_joint(loadid_refined_t *r, int64_t t_us, const loadid_real_t *q);
/* START: forget the window's samples. */
void loadid_refined_start(loadid_refined_t *r);
/* The joint positions' noise its smoother assumes from the next run on
 * [rad or m] (create: kalman.meas_sigma; the pipeline sets it before each
 * run, to what the window measured when that is clearly more); a value
 * <= 0 or not finite leaves it as it is. */
void loadid_refined_set_meas_sigma(loadid_refined_t *r, double sigma);

/* The rows the last run fed its estimator, for phi_std by band of
 * frequency (spectrum_rows.h): transformed when the run had enough
 * (loadid_spectrum_rows_bands refuses them otherwise). */
struct loadid_spectrum_rows;
const struct loadid_spectrum_rows *loadid_refined_rows(const loadid_refined_t *r);
/* A usable sample of the window: y the (zeroed) wrench, lin and ang the
 * accelerometer's a - g and alpha (0 without one). A full store drops the
 * sample and counts it. */
void loadid_refined_sample(loadid_refined_t *r, int64_t t_us, const loadid_real_t y[6],
                           const loadid_real_t lin[3], const loadid_real_t ang[3]);

/* Runs the refinement into est (a TLS batch estimator with room for the
 * window; it is re-weighted and reset first): has_accel says whether lin
 * and ang are real; channel/channel_source the measured wrench and
 * accelerometer noise (noise_model.h); n_params the regressor's model,
 * zero_a (6 x 10, n_params 10) eq. (6) averaged over the zeroing window
 * (loadid_regressor_subtract_zeroing); zeroed_drift_from_us (n_params 10)
 * t_zero of a drift to fit since zeroing, INT64_MIN for none. Returns 0
 * or a negative code (no samples: LOADID_E_NOT_EXCITED; joints missing
 * around the window: LOADID_E_NO_DATA). */
int loadid_refined_run(loadid_refined_t *r, const loadid_config_t *cfg, int has_accel,
                       const double channel[LOADID_NOISE_CHANNELS], int channel_source,
                       const loadid_real_t *zero_a, int n_params, int64_t zeroed_drift_from_us,
                       loadid_est_t *est, loadid_refined_report_t *rep);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_REFINED_H */
