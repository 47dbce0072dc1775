/* Fourier excitation trajectories with polynomial fades (fourier_traj.h). */
#include "fourier_traj.h"

#include <math.h>

static const double kTwoPi = 6.28318530717958647692;

double loadid_traj_duration(const loadid_fourier_traj_t *tr) {
    return 2 * tr->fade_s + tr->active_s;
}

double loadid_traj_active_start(const loadid_fourier_traj_t *tr) {
    return tr->fade_s;
}

void loadid_traj_fade(double tau, double d[4]) {
    if (tau <= 0) {
        d[0] = d[1] = d[2] = d[3] = 0;
        return;
    }
    if (tau >= 1) {
        d[0] = 1;
        d[1] = d[2] = d[3] = 0;
        return;
    }
    /* f' = 140 p^3, f'' = 420 p^2 p', f''' = 840 p (1 - 5 p), p = tau (1 - tau). */
    const double p = tau * (1 - tau), t2 = tau * tau;
    d[0] = t2 * t2 * (35 - 84 * tau + 70 * t2 - 20 * t2 * tau);
    d[1] = 140 * p * p * p;
    d[2] = 420 * p * p * (1 - 2 * tau);
    d[3] = 840 * p * (1 - 5 * p);
}

/* s and its first three time derivatives for joint i at series time ts. */
static void series(const loadid_fourier_traj_t *tr, int i, double ts, double s[4]) {
    s[0] = s[1] = s[2] = s[3] = 0;
    for (int k = 1; k <= tr->harmonics; ++k) {
        const double w = kTwoPi * k * tr->base_frequency;
        const double sn = sin(w * ts), cs = cos(w * ts);
        const double a = tr->rho[i][k - 1], b = tr->delta[i][k - 1];
        s[0] += a * sn + b * cs;
        s[1] += w * (a * cs - b * sn);
        s[2] += -w * w * (a * sn + b * cs);
        s[3] += -w * w * w * (a * cs - b * sn);
    }
}

void loadid_traj_eval(const loadid_fourier_traj_t *tr, double t, double *q, double *qd, double *qdd,
                      double *jerk) {
    const double t1 = tr->fade_s, t2 = tr->fade_s + tr->active_s;
    /* The envelope e(t) and its time derivatives. */
    double e[4] = {1, 0, 0, 0};
    if (t < t1 || t > t2) {
        const double T = tr->fade_s;
        const int in = t < t1;
        double f[4];
        loadid_traj_fade(in ? t / T : 1 - (t - t2) / T, f);
        const double sign = in ? 1 : -1; /* d/dt of (1 - tau) is -1/T */
        e[0] = f[0];
        e[1] = sign * f[1] / T;
        e[2] = f[2] / (T * T);
        e[3] = sign * f[3] / (T * T * T);
    }
    for (int i = 0; i < tr->num_joints; ++i) {
        double s[4];
        series(tr, i, t - t1, s);
        /* Leibniz: (e s)^(n) = sum_j C(n, j) e^(j) s^(n - j). */
        if (q) q[i] = tr->q0[i] + e[0] * s[0];
        if (qd) qd[i] = e[0] * s[1] + e[1] * s[0];
        if (qdd) qdd[i] = e[0] * s[2] + 2 * e[1] * s[1] + e[2] * s[0];
        if (jerk) jerk[i] = e[0] * s[3] + 3 * e[1] * s[2] + 3 * e[2] * s[1] + e[3] * s[0];
    }
}
