/*
 * REFINED (method 6): when the estimation window ends, one batch TLS over
 * the whole window with zero-lag joint signals and measured weights.
 *
 *   joints   every accepted joint state is kept (a ring of the last
 *            duration + 1 s); at the end each joint's measured positions
 *            are smoothed by the RTS smoother of the joint filter's model
 *            (no lag, a quarter of the filter's qdd error), and q, qd, qdd
 *            interpolated to each sensor sample's time; forward kinematics
 *            gives omega, alpha and a - g.
 *   sources  omega always from the smoothed joints. a - g and alpha from
 *            the sensor's accelerometer unless its measured error is over
 *            3 times the smoothed joints' (then from the joints): the
 *            joints' error is the smoother's own steady-state covariance
 *            (loadid_jf_steady_sigma through the kinematics), which does
 *            not know backlash, elasticity or URDF errors, hence the
 *            preference for the direct measurement; the accelerometer's is
 *            its RMS difference to the smoothed joints over the window less
 *            the joints' part, and never below its white noise, so a
 *            vibration or a bias in a channel counts against it, which its
 *            noise figure alone would not show.
 *   weights  loadid_est_weights_from_noise with the wrench's measured noise,
 *            the chosen sources' errors, and the RMS |omega| of the window.
 *            A source far better than the wrench gets a large column weight:
 *            TLS then treats its columns as nearly exact (the mixed LS-TLS
 *            limit), which is what they are.
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
    int64_t samples;           /* fed to the estimator */
    int spec_from_sensor;      /* a - g from the accelerometer (else joints) */
    int alpha_from_sensor;     /* alpha from the accelerometer (else joints) */
    double sensor_spec_error;  /* the accelerometer's measured errors [m/s^2, */
    double sensor_alpha_error; /*   rad/s^2]; 0 without an accelerometer */
    double omega_rms;          /* [rad/s], the column scale used */
    loadid_noise_levels_t levels; /* the levels the weights used */
} loadid_refined_report_t;

/* Allocates the stores for cfg's window. Returns 0, -EINVAL or -ENOMEM. */
int loadid_refined_create(const loadid_config_t *cfg, const loadid_chain_t *chain,
                          loadid_refined_t **out);
void loadid_refined_destroy(loadid_refined_t *r);

/* An accepted joint state (measured positions). */
void loadid_refined_joint(loadid_refined_t *r, int64_t t_us, const loadid_real_t *q);
/* START: forget the window's samples. */
void loadid_refined_start(loadid_refined_t *r);
/* A usable sample of the window: y the (zeroed) wrench, lin and ang the
 * accelerometer's a - g and alpha (0 without one). A full store drops the
 * sample and counts it. */
void loadid_refined_sample(loadid_refined_t *r, int64_t t_us, const loadid_real_t y[6],
                           const loadid_real_t lin[3], const loadid_real_t ang[3]);

/* Runs the refinement into est (a TLS batch estimator with room for the
 * window; it is re-weighted and reset first): has_accel says whether lin
 * and ang are real; channel/channel_source the measured wrench and
 * accelerometer noise (noise_model.h); g_init and n_params the regressor's
 * model. Returns 0 or a negative code (no samples: LOADID_E_NOT_EXCITED;
 * joints missing around the window: LOADID_E_NO_DATA). */
int loadid_refined_run(loadid_refined_t *r, const loadid_config_t *cfg, int has_accel,
                       const double channel[LOADID_NOISE_CHANNELS], int channel_source,
                       const loadid_real_t g_init[3], int n_params, loadid_est_t *est,
                       loadid_refined_report_t *rep);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_REFINED_H */
