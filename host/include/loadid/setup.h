/*
 * What every loadid program derives from the configuration, in one place:
 * the configuration and the robot's chain, the JR3 codec's settings, the
 * joint filters' and signal sources' settings, and the estimators' weights
 * for a signal source. loadidd, its pipeline and the tools all use these, so they see
 * the same numbers.
 */
#ifndef LOADID_SETUP_H
#define LOADID_SETUP_H

#include "loadid/chain.h"
#include "loadid/config.h"
#include "loadid/core.h"
#include "loadid/jr3.h"

#ifdef __cplusplus
extern "C" {
#endif

/* cfg from config_path (NULL: the defaults; another program's section in
 * the file is a warning, for warn, which may be NULL), then chain from
 * cfg's robot.* keys. Returns 0, or the configuration's or the URDF
 * reader's negative code (loadid_error_text) with a one-line reason in
 * err: "FILE:LINE: KEY: what", or for a URDF that cannot be used the
 * file, line and key that named it (robot_urdf_origin) before the
 * reader's reason. */
int loadid_setup_load(const char *config_path, loadid_config_t *cfg, loadid_chain_t *chain,
                      loadid_config_warn_fn warn, void *warn_ctx, char *err, size_t errlen);

/* The JR3 codec: can.base_id and jr3.full_scale.*. */
void loadid_setup_jr3(const loadid_config_t *cfg, loadid_jr3_config_t *jr3);

/* The signal sources and joint filters: kalman.* and the source. */
void loadid_setup_signals(const loadid_config_t *cfg, loadid_signal_source_t source,
                          loadid_signals_config_t *out);

/* The estimators' row and column weights (loadid_est_weights_from_noise)
 * for data from source: a - g and alpha carry the JR3's noise (noise.linear,
 * noise.angular) where the source takes them from the JR3, else the noise
 * of what the joint filters derive (kalman.spec_sigma, kalman.alpha_sigma).
 * Weights that assume the JR3's noise for the filter's far smaller alpha
 * error cost RTLS 7 % of the mass on a simulated o1 with the mixed source.
 * Returns 0 or the core's code. */
int loadid_setup_weights(const loadid_config_t *cfg, loadid_signal_source_t source,
                         loadid_est_config_t *est);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SETUP_H */
