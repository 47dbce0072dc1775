/*
 * Excitation trajectories of the paper's sec. III: per joint a finite
 * Fourier series (eqs. 10-11) of N harmonics of one base frequency f,
 *   s_i(t) = sum_k rho_ik sin(2 pi k f t) + delta_ik cos(2 pi k f t),
 *   q_i(t) = s_i(t) + q_i0,
 * over the active part, faded in and out (eqs. 14-15) by multiplying s_i
 * with a polynomial, so that the robot starts and ends at rest at q_0 with
 * position, velocity, acceleration and jerk continuous everywhere:
 *   fade-in   q_i = f(tau) s_i(t) + q_i0,   tau = t / T_fade,
 *   fade-out  q_i = f(1 - tau) s_i(t) + q_i0, tau = (t - t_2) / T_fade,
 *   f(tau) = 35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7,
 * f(0) = f'(0) = f''(0) = f'''(0) = 0 and f(1) = 1, f'(1) = f''(1) =
 * f'''(1) = 0: eq. (15)'s conditions on f s (value, velocity, acceleration
 * zero at t_0 and equal to s's at t_1), plus a continuous jerk at both
 * ends. The paper's 6th order leaves one of the two jerk conditions out;
 * where the jerk steps, at t_1 and t_2, the estimation window starts and
 * ends, and a joint smoother narrow enough for coarse encoders rounds the
 * acceleration's kink there (REFINED's mass 0.3 % low on 2^14 counts).
 * Time t runs from 0 (t_0, start of the fade-in) to 2 T_fade + T_active
 * (t_3); the series' own time origin is t_1, the start of the active part.
 * Plain C11, no allocation.
 */
#ifndef LOADID_FOURIER_TRAJ_H
#define LOADID_FOURIER_TRAJ_H

#include "loadid/chain.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_TRAJ_MAX_HARMONICS 8

typedef struct {
    int num_joints;
    int harmonics;         /* N */
    double base_frequency; /* f [Hz] */
    double active_s;       /* T_active = t_2 - t_1 */
    double fade_s;         /* T_fade = t_1 - t_0 = t_3 - t_2 */
    double q0[LOADID_MAX_JOINTS];
    double rho[LOADID_MAX_JOINTS][LOADID_TRAJ_MAX_HARMONICS];   /* sine */
    double delta[LOADID_MAX_JOINTS][LOADID_TRAJ_MAX_HARMONICS]; /* cosine */
} loadid_fourier_traj_t;

/* Total duration t_3 [s]. */
double loadid_traj_duration(const loadid_fourier_traj_t *tr);

/* Start of the active part t_1 [s]. */
double loadid_traj_active_start(const loadid_fourier_traj_t *tr);

/* Joint positions, velocities, accelerations and jerks at time t (any
 * output may be NULL). Before 0 and after t_3 the robot rests at q_0. */
void loadid_traj_eval(const loadid_fourier_traj_t *tr, double t, double *q, double *qd, double *qdd,
                      double *jerk);

/* The fade polynomial f(tau), as trajectory files name it. */
#define LOADID_TRAJ_FADE_POLYNOMIAL "35 tau^4 - 84 tau^5 + 70 tau^6 - 20 tau^7"

/* The fade polynomial f(tau) and its first three derivatives in tau,
 * clamped to 0 below tau = 0 and 1 above tau = 1. */
void loadid_traj_fade(double tau, double d[4]);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_FOURIER_TRAJ_H */
