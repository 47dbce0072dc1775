/* REFINED: batch TLS over the window on smoothed joint signals (refined.h). */
#include "loadid/refined.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define JOINT_MARGIN_US 250000 /* joint history smoothed before the window */
/* The accelerometer is kept unless its measured error exceeds this many
 * times the smoothed joints' error: the joints' figure is the smoother's
 * covariance, which knows the encoders' quantisation but not backlash,
 * elasticity or an imprecise URDF, while the accelerometer measures the
 * load's own motion. On the simulated RX60 (2e-4 rad backlash) a - g from
 * the smoothed joints cost 2.9 % of the mass against 0.7 % from the
 * accelerometer, whose measured error was 1.9 times the joints' figure. */
#define SENSOR_PREFERENCE 3.0

typedef struct {
    int64_t t;
    loadid_real_t y[6], lin[3], ang[3];
} window_sample_t;

struct loadid_refined {
    int n_joints;
    loadid_kin_t *kin;
    loadid_jf_config_t jf;
    double smooth_sigma[3]; /* the smoother's steady q, qd, qdd errors at 1 kHz */
    /* joint ring */
    int jcap, jhead, jcount;
    int64_t *jt;
    loadid_real_t *jq; /* jcap x n_joints */
    /* window */
    int scap, scount;
    int64_t dropped;
    window_sample_t *s;
    /* run-time work, linear in time order */
    int64_t *t_lin;
    loadid_real_t *q_lin, *work, *qs, *qds, *qdds; /* qs..: jcap x n_joints */
};

int loadid_refined_create(const loadid_config_t *cfg, const loadid_chain_t *chain,
                          loadid_refined_t **out) {
    if (!cfg || !chain || !out) return -EINVAL;
    *out = NULL;
    loadid_refined_t *r = calloc(1, sizeof *r);
    if (!r) return -ENOMEM;
    int rc = loadid_kin_create(chain, cfg->robot_gravity, &r->kin);
    if (rc) {
        free(r);
        return rc;
    }
    r->n_joints = loadid_kin_num_joints(r->kin);
    loadid_jf_config_default(&r->jf);
    r->jf.jerk_psd = (loadid_real_t)cfg->kalman_jerk_psd;
    r->jf.meas_sigma = (loadid_real_t)cfg->kalman_meas_sigma;
    rc = loadid_jf_steady_sigma(&r->jf, 1e-3, 1, r->smooth_sigma);
    /* Up to 2 kHz of joints over the window and a second around it. */
    r->jcap = (int)ceil((cfg->duration_s + 1.0) * 2000.0);
    r->scap = (int)ceil(cfg->duration_s * 2000.0) + 100;
    const size_t nj = (size_t)r->jcap * (size_t)r->n_joints;
    r->jt = malloc((size_t)r->jcap * sizeof *r->jt);
    r->jq = malloc(nj * sizeof *r->jq);
    r->s = malloc((size_t)r->scap * sizeof *r->s);
    r->t_lin = malloc((size_t)r->jcap * sizeof *r->t_lin);
    r->q_lin = malloc((size_t)r->jcap * sizeof *r->q_lin);
    r->work = malloc(loadid_jf_smooth_work_size((size_t)r->jcap) * sizeof *r->work);
    r->qs = malloc(nj * sizeof *r->qs);
    r->qds = malloc(nj * sizeof *r->qds);
    r->qdds = malloc(nj * sizeof *r->qdds);
    if (rc == 0 && !(r->jt && r->jq && r->s && r->t_lin && r->q_lin && r->work && r->qs && r->qds &&
                     r->qdds))
        rc = -ENOMEM;
    if (rc) {
        loadid_refined_destroy(r);
        return rc;
    }
    *out = r;
    return 0;
}

void loadid_refined_destroy(loadid_refined_t *r) {
    if (!r) return;
    loadid_kin_destroy(r->kin);
    free(r->jt);
    free(r->jq);
    free(r->s);
    free(r->t_lin);
    free(r->q_lin);
    free(r->work);
    free(r->qs);
    free(r->qds);
    free(r->qdds);
    free(r);
}

void loadid_refined_joint(loadid_refined_t *r, int64_t t_us, const loadid_real_t *q) {
    const int slot = (r->jhead + r->jcount) % r->jcap;
    if (r->jcount == r->jcap)
        r->jhead = (r->jhead + 1) % r->jcap; /* the oldest goes */
    else
        r->jcount++;
    r->jt[slot] = t_us;
    memcpy(r->jq + (size_t)slot * (size_t)r->n_joints, q, (size_t)r->n_joints * sizeof *q);
}

void loadid_refined_start(loadid_refined_t *r) {
    r->scount = 0;
    r->dropped = 0;
}

void loadid_refined_sample(loadid_refined_t *r, int64_t t_us, const loadid_real_t y[6],
                           const loadid_real_t lin[3], const loadid_real_t ang[3]) {
    if (r->scount == r->scap) {
        r->dropped++;
        return;
    }
    window_sample_t *s = &r->s[r->scount++];
    s->t = t_us;
    memcpy(s->y, y, sizeof s->y);
    memcpy(s->lin, lin, sizeof s->lin);
    memcpy(s->ang, ang, sizeof s->ang);
}

/* Smooths every joint over the ring's entries from first_t on; returns how
 * many entries (in t_lin, and qs/qds/qdds joint-major), or a negative code. */
static int smooth_joints(loadid_refined_t *r, int64_t first_t) {
    int count = 0;
    for (int k = 0; k < r->jcount; ++k) {
        const int slot = (r->jhead + k) % r->jcap;
        if (r->jt[slot] >= first_t) r->t_lin[count++] = r->jt[slot];
    }
    if (count < 2) return LOADID_E_NO_DATA;
    const int skip = r->jcount - count;
    for (int j = 0; j < r->n_joints; ++j) {
        for (int k = 0; k < count; ++k) {
            const int slot = (r->jhead + skip + k) % r->jcap;
            r->q_lin[k] = r->jq[(size_t)slot * (size_t)r->n_joints + (size_t)j];
        }
        const size_t off = (size_t)j * (size_t)r->jcap;
        const int rc = loadid_jf_smooth(&r->jf, (size_t)count, r->t_lin, r->q_lin, r->work,
                                        r->qs + off, r->qds + off, r->qdds + off);
        if (rc) return rc;
    }
    return count;
}

/* The smoothed joint state at t by linear interpolation between the two
 * entries around it (*k: a cursor moving forward with t). */
static int joints_at(const loadid_refined_t *r, int count, int *k, int64_t t, loadid_real_t *q,
                     loadid_real_t *qd, loadid_real_t *qdd) {
    while (*k + 1 < count - 1 && r->t_lin[*k + 1] <= t) ++*k;
    const int64_t t0 = r->t_lin[*k], t1 = r->t_lin[*k + 1];
    if (t < t0 || t > t1 || t1 - t0 > r->jf.max_step_us) return LOADID_E_NO_DATA;
    const double w = (double)(t - t0) / (double)(t1 - t0);
    for (int j = 0; j < r->n_joints; ++j) {
        const size_t a = (size_t)j * (size_t)r->jcap + (size_t)*k;
        q[j] = (loadid_real_t)((1 - w) * r->qs[a] + w * r->qs[a + 1]);
        qd[j] = (loadid_real_t)((1 - w) * r->qds[a] + w * r->qds[a + 1]);
        qdd[j] = (loadid_real_t)((1 - w) * r->qdds[a] + w * r->qdds[a + 1]);
    }
    return 0;
}

static double sq(double v) { return v * v; }

int loadid_refined_run(loadid_refined_t *r, const loadid_config_t *cfg, int has_accel,
                       const double channel[LOADID_NOISE_CHANNELS], int channel_source,
                       const loadid_real_t g_init[3], int n_params, loadid_est_t *est,
                       loadid_refined_report_t *rep) {
    memset(rep, 0, sizeof *rep);
    if (r->scount < 2) return LOADID_E_NOT_EXCITED;
    const int count = smooth_joints(r, r->s[0].t - JOINT_MARGIN_US);
    if (count < 0) return count;

    /* Pass 1: the kinematics of every sample (kept in place of nothing:
     * recomputed in pass 2, which is cheaper than storing them), the
     * accelerometer's discrepancy and the RMS |omega|. */
    loadid_real_t q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
    loadid_kin_state_t ks;
    double d_spec = 0, d_alpha = 0, w2 = 0;
    int64_t used = 0;
    int k = 0;
    for (int i = 0; i < r->scount; ++i) {
        if (joints_at(r, count, &k, r->s[i].t, q, qd, qdd) || loadid_kin_eval(r->kin, q, qd, qdd, &ks))
            continue;
        for (int a = 0; a < 3; ++a) {
            d_spec += sq((double)r->s[i].lin[a] - (double)ks.spec[a]);
            d_alpha += sq((double)r->s[i].ang[a] - (double)ks.alpha[a]);
            w2 += sq((double)ks.omega[a]);
        }
        used++;
    }
    if (used < 2) return LOADID_E_NO_DATA;
    rep->omega_rms = sqrt(w2 / (double)used);

    /* The smoothed joints' own errors at the window's middle pose. */
    double js = 0, ja = 0, jw = 0;
    k = 0;
    if (joints_at(r, count, &k, r->s[r->scount / 2].t, q, qd, qdd) == 0)
        loadid_noise_joint_levels(r->kin, q, r->smooth_sigma[1], r->smooth_sigma[2], &js, &ja, &jw);
    /* The accelerometer's error: its discrepancy less the joints' part,
     * never below its white noise. */
    int spec_sensor = 0, alpha_sensor = 0;
    if (has_accel) {
        const double ws = sqrt((sq(channel[6]) + sq(channel[7]) + sq(channel[8])) / 3.0);
        const double wa = sqrt((sq(channel[9]) + sq(channel[10]) + sq(channel[11])) / 3.0);
        rep->sensor_spec_error = fmax(sqrt(fmax(d_spec / (3.0 * (double)used) - js * js, 0)), ws);
        rep->sensor_alpha_error = fmax(sqrt(fmax(d_alpha / (3.0 * (double)used) - ja * ja, 0)), wa);
        spec_sensor = rep->sensor_spec_error < SENSOR_PREFERENCE * js;
        alpha_sensor = rep->sensor_alpha_error < SENSOR_PREFERENCE * ja;
    }
    rep->spec_from_sensor = spec_sensor;
    rep->alpha_from_sensor = alpha_sensor;

    /* The levels: the wrench's as measured (or configured), the sources'
     * errors as found above. */
    loadid_config_t c = *cfg;
    c.noise_given &= LOADID_NOISE_GIVEN_FORCE | LOADID_NOISE_GIVEN_TORQUE;
    c.noise_linear = c.kalman_spec_sigma = fmax(spec_sensor ? rep->sensor_spec_error : js, 1e-9);
    c.noise_angular = c.kalman_alpha_sigma = fmax(alpha_sensor ? rep->sensor_alpha_error : ja, 1e-9);
    c.noise_omega = fmax(jw, 1e-12);
    c.noise_given |= LOADID_NOISE_GIVEN_LINEAR | LOADID_NOISE_GIVEN_ANGULAR | LOADID_NOISE_GIVEN_OMEGA |
                     LOADID_NOISE_GIVEN_KF_SPEC | LOADID_NOISE_GIVEN_KF_ALPHA;
    loadid_noise_combine(&c, spec_sensor, alpha_sensor, channel, channel_source, js, ja, jw,
                         &rep->levels);
    rep->levels.source[2] = spec_sensor ? channel_source : LOADID_NOISE_FILTER;
    rep->levels.source[3] = alpha_sensor ? channel_source : LOADID_NOISE_FILTER;
    rep->levels.source[4] = LOADID_NOISE_FILTER;
    loadid_est_config_t ec = *loadid_est_config(est);
    int rc = loadid_noise_weights(&rep->levels, fmax(rep->omega_rms, 1e-3), &ec);
    if (rc == 0) rc = loadid_est_set_weights(est, ec.row_sigma, ec.col_weight);
    if (rc) return rc;

    /* Pass 2: the regressor of every sample into the batch TLS. */
    k = 0;
    for (int i = 0; i < r->scount; ++i) {
        if (joints_at(r, count, &k, r->s[i].t, q, qd, qdd) || loadid_kin_eval(r->kin, q, qd, qdd, &ks))
            continue;
        loadid_real_t spec[3], alpha[3], A[6 * 16];
        for (int a = 0; a < 3; ++a) {
            spec[a] = spec_sensor ? r->s[i].lin[a] : ks.spec[a];
            alpha[a] = alpha_sensor ? r->s[i].ang[a] : ks.alpha[a];
        }
        if (loadid_regressor_model(spec, ks.omega, alpha, n_params, g_init, A)) continue;
        if (loadid_est_update(est, A, NULL, r->s[i].y) == 0) rep->samples++;
    }
    return rep->samples > 0 ? 0 : LOADID_E_NOT_EXCITED;
}
