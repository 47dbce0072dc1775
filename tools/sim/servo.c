/* Joint servo with backlash (servo.h). */
#include "servo.h"

#include <math.h>
#include <string.h>

static const double kTwoPi = 6.28318530717958647692;

void loadid_servo_init(loadid_servo_t *s, const loadid_servo_config_t *cfg,
                       const loadid_fourier_traj_t *traj, double t0) {
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    if (!(s->cfg.backlash_velocity > 0)) s->cfg.backlash_velocity = 0.05;
    if (!(s->cfg.substep_s > 0)) s->cfg.substep_s = 1e-4;
    s->traj = traj;
    s->t0 = t0;
    s->n = traj->num_joints;
    memcpy(s->q, traj->q0, sizeof s->q);
}

/* Setpoint position and velocity at simulation time t. */
static void setpoint(const loadid_servo_t *s, double t, double *q, double *qd) {
    loadid_traj_eval(s->traj, t - s->t0, q, qd, NULL, NULL);
}

/* Motor acceleration of the servo law for state (q, v) at time t. */
static void accel(const loadid_servo_t *s, double t, const double *q, const double *v, double *a) {
    double sq[LOADID_MAX_JOINTS], sv[LOADID_MAX_JOINTS];
    setpoint(s, t, sq, sv);
    const double w = kTwoPi * s->cfg.bandwidth_hz, z = s->cfg.damping;
    for (int i = 0; i < s->n; ++i) a[i] = w * w * (sq[i] - q[i]) + 2 * z * w * (sv[i] - v[i]);
}

/* One classical Runge-Kutta step of (q, v)' = (v, accel). */
static void rk4(loadid_servo_t *s, double h) {
    const int n = s->n;
    double k1q[LOADID_MAX_JOINTS], k1v[LOADID_MAX_JOINTS], k2q[LOADID_MAX_JOINTS],
        k2v[LOADID_MAX_JOINTS], k3q[LOADID_MAX_JOINTS], k3v[LOADID_MAX_JOINTS],
        k4q[LOADID_MAX_JOINTS], k4v[LOADID_MAX_JOINTS], tq[LOADID_MAX_JOINTS],
        tv[LOADID_MAX_JOINTS];
    memcpy(k1q, s->v, sizeof k1q);
    accel(s, s->t, s->q, s->v, k1v);
    for (int i = 0; i < n; ++i) tq[i] = s->q[i] + h / 2 * k1q[i], tv[i] = s->v[i] + h / 2 * k1v[i];
    memcpy(k2q, tv, sizeof k2q);
    accel(s, s->t + h / 2, tq, tv, k2v);
    for (int i = 0; i < n; ++i) tq[i] = s->q[i] + h / 2 * k2q[i], tv[i] = s->v[i] + h / 2 * k2v[i];
    memcpy(k3q, tv, sizeof k3q);
    accel(s, s->t + h / 2, tq, tv, k3v);
    for (int i = 0; i < n; ++i) tq[i] = s->q[i] + h * k3q[i], tv[i] = s->v[i] + h * k3v[i];
    memcpy(k4q, tv, sizeof k4q);
    accel(s, s->t + h, tq, tv, k4v);
    for (int i = 0; i < n; ++i) {
        s->q[i] += h / 6 * (k1q[i] + 2 * k2q[i] + 2 * k3q[i] + k4q[i]);
        s->v[i] += h / 6 * (k1v[i] + 2 * k2v[i] + 2 * k3v[i] + k4v[i]);
    }
    s->t += h;
}

void loadid_servo_advance(loadid_servo_t *s, double t, loadid_servo_state_t *out) {
    while (s->t < t - 1e-12) {
        const double h = fmin(s->cfg.substep_s, t - s->t);
        rk4(s, h);
    }
    double a[LOADID_MAX_JOINTS], jerk[LOADID_MAX_JOINTS], sq[LOADID_MAX_JOINTS],
        sv[LOADID_MAX_JOINTS], sa[LOADID_MAX_JOINTS];
    accel(s, s->t, s->q, s->v, a);
    loadid_traj_eval(s->traj, s->t - s->t0, sq, sv, sa, NULL);
    const double w = kTwoPi * s->cfg.bandwidth_hz, z = s->cfg.damping;
    const double hb = s->cfg.backlash / 2, vb = s->cfg.backlash_velocity;
    for (int i = 0; i < s->n; ++i) {
        /* d/dt of the servo law: the motor's jerk. */
        jerk[i] = w * w * (sv[i] - s->v[i]) + 2 * z * w * (sa[i] - a[i]);
        const double th = tanh(s->v[i] / vb), sech2 = 1 - th * th;
        const double d1 = hb * sech2 / vb;                  /* d phi / dv */
        const double d2 = -2 * hb * sech2 * th / (vb * vb); /* d2 phi / dv2 */
        out->motor[i] = s->q[i];
        out->setpoint[i] = sq[i];
        out->link[i] = s->q[i] - hb * th;
        out->link_d[i] = s->v[i] - d1 * a[i];
        out->link_dd[i] = a[i] - d2 * a[i] * a[i] - d1 * jerk[i];
    }
}
