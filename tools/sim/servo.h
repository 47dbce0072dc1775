/*
 * The joint servo of the simulated robot: why measured joint positions and
 * the real motion of the sensor differ from the setpoints (paper sec. III
 * and IV.A: controller imperfections, backlash).
 *
 * Motor side, per joint, a second-order servo with velocity feed-forward:
 *   q_m'' = w^2 (q_sp - q_m) + 2 zeta w (q_sp' - q_m'),  w = 2 pi bandwidth,
 * integrated by classical Runge-Kutta at a fixed sub-step with the
 * setpoints evaluated exactly at each stage. The encoders read q_m.
 * Link side, the gear's backlash b as a smoothed play: the link lags the
 * motor by half the play in the direction of motion,
 *   q_l = q_m - (b / 2) tanh(q_m' / v_b),
 * with its velocity and acceleration by the chain rule (v_b = 0.05 rad/s
 * sets how fast the play is crossed at a reversal). The load moves with q_l.
 */
#ifndef LOADID_SIM_SERVO_H
#define LOADID_SIM_SERVO_H

#include "fourier_traj.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double bandwidth_hz;      /* natural frequency of the servo */
    double damping;           /* zeta */
    double backlash;          /* play b [rad or m] */
    double backlash_velocity; /* v_b [rad/s or m/s], default 0.05 */
    double substep_s;         /* integration step, default 1e-4 */
} loadid_servo_config_t;

typedef struct {
    loadid_servo_config_t cfg;
    const loadid_fourier_traj_t *traj; /* the setpoints */
    double t0;                         /* trajectory time 0 in simulation time */
    int n;
    double t;                                          /* simulation time [s] */
    double q[LOADID_MAX_JOINTS], v[LOADID_MAX_JOINTS]; /* motor state */
} loadid_servo_t;

/* Motor and link state of every joint at one instant. */
typedef struct {
    double motor[LOADID_MAX_JOINTS]; /* what the encoders see */
    double link[LOADID_MAX_JOINTS], link_d[LOADID_MAX_JOINTS], link_dd[LOADID_MAX_JOINTS];
    double setpoint[LOADID_MAX_JOINTS];
} loadid_servo_state_t;

/* Starts at rest on the trajectory's q_0 at simulation time 0; the
 * trajectory's own time 0 is at simulation time t0. */
void loadid_servo_init(loadid_servo_t *s, const loadid_servo_config_t *cfg,
                       const loadid_fourier_traj_t *traj, double t0);

/* Integrates to simulation time t (>= the current time) and reports the
 * state there. */
void loadid_servo_advance(loadid_servo_t *s, double t, loadid_servo_state_t *out);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SIM_SERVO_H */
