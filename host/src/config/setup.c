/* Settings derived from the configuration (setup.h). */
#include "loadid/setup.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "loadid/urdf.h"

int loadid_setup_load(const char *config_path, loadid_config_t *cfg, loadid_chain_t *chain,
                      loadid_config_warn_fn warn, void *warn_ctx, char *err, size_t errlen) {
    loadid_config_default(cfg);
    int rc = config_path ? loadid_config_load(config_path, cfg, err, errlen, warn, warn_ctx) : 0;
    if (rc != 0) return rc;
    char why[1024];
    rc = loadid_urdf_load_file(cfg->robot_urdf, cfg->robot_base_link, cfg->robot_sensor_link, chain,
                               why, sizeof why);
    /* The key and line that named the file: the URDF reader knows only
     * the file. */
    if (rc != 0) snprintf(err, errlen, "%s: %s", cfg->robot_urdf_origin, why);
    return rc;
}

void loadid_setup_jr3(const loadid_config_t *cfg, loadid_jr3_config_t *jr3) {
    memset(jr3, 0, sizeof *jr3);
    jr3->base_id = cfg->can_base_id;
    memcpy(jr3->full_scale[LOADID_JR3_FORCE], cfg->jr3_fs_force, sizeof cfg->jr3_fs_force);
    memcpy(jr3->full_scale[LOADID_JR3_MOMENT], cfg->jr3_fs_moment, sizeof cfg->jr3_fs_moment);
    memcpy(jr3->full_scale[LOADID_JR3_LINEAR], cfg->jr3_fs_linear, sizeof cfg->jr3_fs_linear);
    memcpy(jr3->full_scale[LOADID_JR3_ANGULAR], cfg->jr3_fs_angular, sizeof cfg->jr3_fs_angular);
}

/* Joint intervals the stream's period is measured over (kalman.joint_period_s
 * auto; signals.h): 16, the most, for the slope's sake: under 0.4 periods
 * of jitter its spread is about 1 % (3 % with 8). */
#define JOINT_PERIOD_PROBE 16

void loadid_setup_signals(const loadid_config_t *cfg, loadid_signal_source_t source,
                          loadid_signals_config_t *out) {
    loadid_signals_config_default(out);
    out->source = source;
    out->measured.jerk_psd = out->setpoint.jerk_psd = (loadid_real_t)cfg->kalman_jerk_psd;
    out->measured.meas_sigma = out->setpoint.meas_sigma = (loadid_real_t)cfg->kalman_meas_sigma;
    out->max_joint_age_us = (int64_t)llround(cfg->kalman_max_joint_age_s * 1e6);
    out->stamp_gain = cfg->kalman_stamp_gain;
    /* The fixed-lag smoother, on both banks so that the instruments and the
     * motion are of the same instant. */
    const int64_t period = llround(cfg->kalman_joint_period_s * 1e6);
    out->measured.nominal_step_us = out->setpoint.nominal_step_us = period > 0 ? period : 1000;
    int lag = (int)llround(cfg->kalman_lag_s * 1e6 / (double)out->measured.nominal_step_us);
    if (period <= 0) { /* auto: these until the stream's own period is measured */
        out->period_probe = JOINT_PERIOD_PROBE;
        out->lag_us = llround(cfg->kalman_lag_s * 1e6);
        if (lag > LOADID_JF_MAX_LAG) lag = LOADID_JF_MAX_LAG;
    }
    out->measured.lag_steps = out->setpoint.lag_steps = lag;
    /* Joint data too old to serve a sample cannot carry the filters across
     * a stall either: a step longer than max_joint_age restarts them (the
     * samples after it wait for them to settle, joint_filter.h). At least
     * two periods, so that one lost joint state is bridged. */
    const int64_t step = out->max_joint_age_us > 2 * out->measured.nominal_step_us
                             ? out->max_joint_age_us
                             : 2 * out->measured.nominal_step_us;
    out->measured.max_step_us = out->setpoint.max_step_us = step;
}

int loadid_setup_weights(const loadid_config_t *cfg, loadid_signal_source_t source,
                         loadid_est_config_t *est) {
    const int jr3_spec = source == LOADID_SIGNALS_SENSOR || source == LOADID_SIGNALS_MIXED;
    const int jr3_alpha = source == LOADID_SIGNALS_SENSOR;
    return loadid_est_weights_from_noise(
        est, (loadid_real_t)cfg->noise_force, (loadid_real_t)cfg->noise_torque,
        (loadid_real_t)(jr3_spec ? cfg->noise_linear : cfg->kalman_spec_sigma),
        (loadid_real_t)(jr3_alpha ? cfg->noise_angular : cfg->kalman_alpha_sigma),
        (loadid_real_t)cfg->noise_omega, (loadid_real_t)cfg->omega_typical);
}
