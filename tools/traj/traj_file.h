/*
 * The trajectory file of loadid-traj (YAML), read by loadid-sim: the
 * Fourier coefficients and fades (fourier_traj.h), the limits it was
 * designed for, and the achieved condition numbers. Also the 1 kHz
 * setpoint samples as CSV.
 *
 *   format: loadid-trajectory-1
 *   robot: {urdf: ..., base_link: ..., sensor_link: ..., joints: [names]}
 *   base_frequency: 0.5       # Hz, f of eq. (10)
 *   harmonics: 4
 *   active_s: 1.5
 *   fade_s: 0.5
 *   fade_polynomial: "35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7"
 *                             # f of fourier_traj.h; another one is refused
 *   q0: [n numbers]           # eq. (11)
 *   rho: [[N numbers] x n]    # sine coefficients, eq. (10)
 *   delta: [[N numbers] x n]  # cosine coefficients
 *   limits: {position_lower, position_upper, velocity, acceleration,
 *            workspace_min, workspace_max, floor_z}
 *   kappa_design: x           # kappa(D A T) over the active part at 1 kHz, the
 *                             # weights from noise.*: what the designer minimises
 *   kappa_upsilon: x          # kappa of eq. (12) with the weights, = kappa_design^2
 *   kappa_set: x              # kappa(A) without weights: Table I's (loadid-kappa's)
 *   kappa_monte_carlo: x      # best Monte Carlo start (objective rate)
 *   seed: n
 */
#ifndef LOADID_TRAJ_FILE_H
#define LOADID_TRAJ_FILE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "fourier_traj.h"
#include "loadid/chain.h"
#include "traj_design.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const char *urdf, *base_link, *sensor_link;
    const loadid_chain_t *chain;            /* joint names */
    double kappa_design, kappa_monte_carlo; /* kappa(D A T) */
    double kappa_set;                       /* kappa of A without weights (Table I) */
    uint64_t seed;
} loadid_traj_file_info_t;

/* Writes the YAML. Returns 0 or -1 (errno set by stdio). */
int loadid_traj_file_write(FILE *out, const loadid_fourier_traj_t *tr,
                           const loadid_traj_limits_t *limits, const loadid_traj_file_info_t *info);

/* Reads a trajectory file: the series and fades into tr, the joint names
 * into names (LOADID_MAX_JOINTS x LOADID_NAME_MAX, may be NULL), kappa_design
 * (may be NULL; NAN when absent). Returns 0, or a negative code with
 * "FILE:LINE: KEY: what" (or "FILE: cannot read: ...") in err. */
int loadid_traj_file_read(const char *path, loadid_fourier_traj_t *tr,
                          char names[][LOADID_NAME_MAX], double *kappa_design, char *err,
                          size_t errlen);

/* Writes "t,q1..qn,qd1..qdn,qdd1..qddn" at rate_hz over [0, t_3]. */
int loadid_traj_setpoints_write(FILE *out, const loadid_fourier_traj_t *tr, double rate_hz);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_TRAJ_FILE_H */
