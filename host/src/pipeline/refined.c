/* REFINED: batch TLS over the window on smoothed joint signals (refined.h). */
#include "loadid/refined.h"

#include "spd.h"
#include "spectrum_rows.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define JOINT_MARGIN_US 250000 /* joint history smoothed before the window */
#define JOINT_STEP_US 500      /* joint states kept at least this far apart: 2 kHz */

typedef struct {
    int64_t t;
    loadid_real_t y[6], lin[3], ang[3];
} window_sample_t;

struct loadid_refined {
    int n_joints;
    loadid_kin_t *kin;
    loadid_jf_config_t jf;
    /* joint ring */
    int jcap, jhead, jcount;
    int64_t *jt;
    loadid_real_t *jq; /* jcap x n_joints */
    /* window */
    int scap, scount;
    int count; /* joint entries smoothed (t_lin, qs, qds, qdds) */
    int64_t dropped;
    window_sample_t *s;
    loadid_real_t *kin_store; /* per sample: a - g, omega, alpha from the smoothed joints */
    unsigned char *kin_ok;
    loadid_real_t *best_kin, *best_q[3]; /* the best trial's, swapped with the above */
    unsigned char *best_ok;
    double *tone_x; /* scap x 3: the accelerometer less the smoothed joints, one group */
    double *pred;   /* scap x 6: the predicted wrench, for the delay's derivative */
    loadid_spectrum_rows_t *rows; /* the rows fed to the estimator (phi_std by band) */
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
    /* Up to 2 kHz of joints over the window and a second around it. */
    r->jcap = (int)ceil((cfg->duration_s + 1.0) * 2000.0);
    r->scap = (int)ceil(cfg->duration_s * 2000.0) + 100;
    const size_t nj = (size_t)r->jcap * (size_t)r->n_joints;
    r->jt = malloc((size_t)r->jcap * sizeof *r->jt);
    r->jq = malloc(nj * sizeof *r->jq);
    r->s = malloc((size_t)r->scap * sizeof *r->s);
    r->kin_store = malloc((size_t)r->scap * 9 * sizeof *r->kin_store);
    r->kin_ok = malloc((size_t)r->scap);
    r->best_kin = malloc((size_t)r->scap * 9 * sizeof *r->best_kin);
    r->best_ok = malloc((size_t)r->scap);
    r->tone_x = malloc((size_t)r->scap * 3 * sizeof *r->tone_x);
    r->pred = malloc((size_t)r->scap * 6 * sizeof *r->pred);
    r->t_lin = malloc((size_t)r->jcap * sizeof *r->t_lin);
    r->q_lin = malloc((size_t)r->jcap * sizeof *r->q_lin);
    r->work = malloc(loadid_jf_smooth_work_size((size_t)r->jcap) * sizeof *r->work);
    r->qs = malloc(nj * sizeof *r->qs);
    r->qds = malloc(nj * sizeof *r->qds);
    r->qdds = malloc(nj * sizeof *r->qdds);
    for (int i = 0; i < 3; ++i) r->best_q[i] = malloc(nj * sizeof *r->best_q[i]);
    rc = loadid_spectrum_rows_create(
        r->scap, cfg->offset_model_estimate ? LOADID_NPHI_OFFSET : LOADID_NPHI, 0, &r->rows);
    if (rc == 0 && !(r->jt && r->jq && r->s && r->kin_store && r->kin_ok && r->best_kin &&
                     r->best_ok && r->tone_x && r->pred && r->best_q[0] && r->best_q[1] &&
                     r->best_q[2] && r->t_lin && r->q_lin && r->work && r->qs && r->qds && r->qdds))
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
    free(r->kin_store);
    free(r->kin_ok);
    free(r->pred);
    free(r->best_kin);
    free(r->best_ok);
    free(r->tone_x);
    for (int i = 0; i < 3; ++i) free(r->best_q[i]);
    free(r->t_lin);
    free(r->q_lin);
    free(r->work);
    free(r->qs);
    free(r->qds);
    free(r->qdds);
    loadid_spectrum_rows_destroy(r->rows);
    free(r);
}

void loadid_refined_set_meas_sigma(loadid_refined_t *r, double sigma) {
    if (r && sigma > 0 && isfinite(sigma)) r->jf.meas_sigma = (loadid_real_t)sigma;
}

void loadid_refined_joint(loadid_refined_t *r, int64_t t_us, const loadid_real_t *q) {
    /* At most 2 kHz, what the ring holds over the window and a second: a
     * faster stream's states are thinned (at 4 kHz, kept whole, the
     * window's first fifth had none). */
    if (r->jcount > 0 && t_us - r->jt[(r->jhead + r->jcount - 1) % r->jcap] < JOINT_STEP_US) return;
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
    loadid_spectrum_rows_reset(r->rows);
}

const loadid_spectrum_rows_t *loadid_refined_rows(const loadid_refined_t *r) {
    return r ? r->rows : NULL;
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
static int smooth_joints(loadid_refined_t *r, const loadid_jf_config_t *jf, int64_t first_t) {
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
        const int rc = loadid_jf_smooth(jf, (size_t)count, r->t_lin, r->q_lin, r->work, r->qs + off,
                                        r->qds + off, r->qdds + off);
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

static double sq(double v) {
    return v * v;
}

/* The estimator's levels: the wrench rows as given, the smoothed joints'
 * columns exact (loadid_noise_weights). */
static int weigh(loadid_est_t *est, const loadid_noise_levels_t *lv, double omega_rms) {
    loadid_est_config_t ec = *loadid_est_config(est);
    int rc = loadid_noise_weights(lv, fmax(omega_rms, 1e-3), &ec);
    if (rc == 0) rc = loadid_est_set_weights(est, ec.row_sigma, ec.col_weight);
    if (rc == 0) rc = loadid_est_set_exact(est, ec.col_exact);
    return rc;
}

/* Feeds every sample with kinematics to est; returns the samples fed. */
static int64_t feed(loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                    const double drift[6], int64_t t_mid, loadid_est_t *est) {
    int64_t fed = 0;
    for (int i = 0; i < r->scount; ++i) {
        if (!r->kin_ok[i]) continue;
        const loadid_real_t *k = r->kin_store + 9 * (size_t)i; /* a - g, omega, alpha */
        loadid_real_t A[6 * 16], y[6];
        if (loadid_regressor_model_zeroed(k, k + 3, k + 6, n_params, zero_a, A)) continue;
        const double dt = (double)(r->s[i].t - t_mid) * 1e-6;
        for (int row = 0; row < 6; ++row)
            y[row] = (loadid_real_t)((double)r->s[i].y[row] - drift[row] * dt);
        if (loadid_est_update(est, A, NULL, y) == 0) {
            loadid_spectrum_rows_add(r->rows, r->s[i].t, A, NULL, y);
            fed++;
        }
    }
    return fed;
}

/* Swaps the working stores (kinematics, smoothed joints) with the best
 * trial's. */
static void swap_best(loadid_refined_t *r) {
    loadid_real_t *t = r->kin_store;
    r->kin_store = r->best_kin, r->best_kin = t;
    unsigned char *o = r->kin_ok;
    r->kin_ok = r->best_ok, r->best_ok = o;
    loadid_real_t *sj[3] = {r->qs, r->qds, r->qdds};
    r->qs = r->best_q[0], r->qds = r->best_q[1], r->qdds = r->best_q[2];
    r->best_q[0] = sj[0], r->best_q[1] = sj[1], r->best_q[2] = sj[2];
}

/* The smoothed joints' kinematics of every sample at its time plus
 * delay_us (kin_store, kin_ok), from the count smoothed entries; returns
 * the samples with kinematics. */
static int64_t kinematics_at(loadid_refined_t *r, int count, int64_t delay_us) {
    loadid_real_t q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
    loadid_kin_state_t ks;
    int64_t used = 0;
    int k = 0;
    for (int i = 0; i < r->scount; ++i) {
        r->kin_ok[i] = joints_at(r, count, &k, r->s[i].t + delay_us, q, qd, qdd) == 0 &&
                       loadid_kin_eval(r->kin, q, qd, qdd, &ks) == 0;
        if (!r->kin_ok[i]) continue;
        loadid_real_t *store = r->kin_store + 9 * (size_t)i;
        for (int a = 0; a < 3; ++a)
            store[a] = ks.spec[a], store[3 + a] = ks.omega[a], store[6 + a] = ks.alpha[a];
        used++;
    }
    r->count = count;
    return used;
}

/* The samples whose kinematics are in kin_store. */
static int64_t kin_count(const loadid_refined_t *r) {
    int64_t n = 0;
    for (int i = 0; i < r->scount; ++i) n += r->kin_ok[i];
    return n;
}

/* The normal equations of a weighted least-squares fit on the stored
 * kinematics (rows weighted by force_sigma, torque_sigma): M (lower
 * triangle, row-major, cols x cols) and b summed, *yy = y^T W y; cols is
 * n_params, or n_params + 6 with columns (t - t_mid) E6 of the offset's
 * drift. Returns the rows summed. */
#define MAX_COLS (LOADID_NPHI_OFFSET + 6)
static double normal_equations(const loadid_refined_t *r, int n_params, int cols,
                               const loadid_real_t *zero_a, double force_sigma, double torque_sigma,
                               int64_t t_mid, double *M, double *b, double *yy) {
    memset(M, 0, (size_t)cols * (size_t)cols * sizeof *M);
    memset(b, 0, (size_t)cols * sizeof *b);
    double rows = 0;
    *yy = 0;
    for (int i = 0; i < r->scount; ++i) {
        if (!r->kin_ok[i]) continue;
        const loadid_real_t *k = r->kin_store + 9 * (size_t)i;
        loadid_real_t A[6 * 16];
        if (loadid_regressor_model_zeroed(k, k + 3, k + 6, n_params, zero_a, A)) continue;
        const double dt = (double)(r->s[i].t - t_mid) * 1e-6;
        for (int row = 0; row < 6; ++row) {
            const double w = 1.0 / sq(row < 3 ? force_sigma : torque_sigma);
            const double y = (double)r->s[i].y[row];
            double a[MAX_COLS];
            for (int p = 0; p < n_params; ++p) a[p] = (double)A[row * n_params + p];
            for (int p = n_params; p < cols; ++p) a[p] = p - n_params == row ? dt : 0;
            for (int p = 0; p < cols; ++p) {
                if (a[p] == 0) continue;
                b[p] += w * a[p] * y;
                for (int q = 0; q <= p; ++q) M[p * cols + q] += w * a[p] * a[q];
            }
            *yy += w * y * y;
            rows += 1;
        }
    }
    return rows;
}

/* The columns of the fits below: n_params, and with t_ref not INT64_MIN
 * six more, (t - t_ref) E6, the offset's drift (fit_drift): a drift the
 * fits leave out steers the bandwidth and the delay (on slow motion 0.05
 * N/s of it passed for a 16.5 ms joint delay at 6 standard errors). */
static int fit_cols(int n_params, int64_t t_ref) {
    return t_ref == INT64_MIN ? n_params : n_params + 6;
}

/* Sample i's seconds after t_ref (0 without drift columns). */
static double drift_dt(const loadid_refined_t *r, int i, int64_t t_ref) {
    return t_ref == INT64_MIN ? 0 : (double)(r->s[i].t - t_ref) * 1e-6;
}

/* The fitted drift's part of row's wrench dt after t_ref (x: a fit's
 * solution of cols columns, the drift's after the n parameters). */
static double drift_part(const double *x, int n, int cols, int row, double dt) {
    return cols > n ? x[n + row] * dt : 0;
}

/* Sample i's residual under a fit x of fit_cols(n, t_ref) columns (phi:
 * its first n, as reals): y - A phi less the drift's part, per row.
 * Returns 0, or -1 when the sample has no kinematics or regressor. */
static int sample_residual(const loadid_refined_t *r, int i, int n, const loadid_real_t *zero_a,
                           int64_t t_ref, const double *x, const loadid_real_t *phi,
                           double res[6]) {
    if (!r->kin_ok[i]) return -1;
    const loadid_real_t *k = r->kin_store + 9 * (size_t)i;
    loadid_real_t A[6 * 16], pred[6];
    if (loadid_regressor_model_zeroed(k, k + 3, k + 6, n, zero_a, A)) return -1;
    loadid_regressor_apply(A, n, phi, pred);
    const int cols = fit_cols(n, t_ref);
    const double dt = drift_dt(r, i, t_ref);
    for (int row = 0; row < 6; ++row)
        res[row] = (double)r->s[i].y[row] - (double)pred[row] - drift_part(x, n, cols, row, dt);
    return 0;
}

/* The weighted residual of a least-squares fit on the stored kinematics
 * (rows weighted by force_sigma, torque_sigma; fit_cols columns), by the
 * normal equations; +Inf when they are singular. rss_group (may be NULL):
 * the force and the torque rows' unweighted residual sums of squares;
 * x_out (may be NULL): the solution; normal (may be NULL): the normal
 * matrix (cols x cols, full, row-major). */
static double fit_residual(const loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                           double force_sigma, double torque_sigma, int64_t t_ref,
                           double rss_group[2], double x_out[MAX_COLS],
                           double normal[MAX_COLS * MAX_COLS]) {
    const int n = n_params, cols = fit_cols(n, t_ref);
    double M[MAX_COLS * MAX_COLS], b[MAX_COLS], yy;
    normal_equations(r, n, cols, zero_a, force_sigma, torque_sigma, t_ref == INT64_MIN ? 0 : t_ref,
                     M, b, &yy);
    for (int p = 0; p < cols; ++p)
        for (int q = 0; q < p; ++q) M[q * cols + p] = M[p * cols + q];
    if (normal) memcpy(normal, M, (size_t)cols * (size_t)cols * sizeof *M);
    double x[MAX_COLS];
    memcpy(x, b, (size_t)cols * sizeof *x);
    if (loadid_spd_solve(M, x, cols)) return INFINITY;
    if (x_out) memcpy(x_out, x, (size_t)cols * sizeof *x);
    double fit = 0; /* rss = y^T W y - b^T x at the solution */
    for (int p = 0; p < cols; ++p) fit += b[p] * x[p];
    if (rss_group) {
        loadid_real_t phi[16];
        for (int p = 0; p < n; ++p) phi[p] = (loadid_real_t)x[p];
        rss_group[0] = rss_group[1] = 0;
        for (int i = 0; i < r->scount; ++i) {
            double res[6];
            if (sample_residual(r, i, n, zero_a, t_ref, x, phi, res)) continue;
            for (int row = 0; row < 6; ++row) rss_group[row / 3] += sq(res[row]);
        }
    }
    return yy - fit;
}

/* The weighted residual of the fit x (fit_cols columns) in the motion's
 * band: per stretch of BAND_BLOCK_US of the samples' time and per row, the
 * residual's sum squared over the stretch's samples, summed. White noise
 * gives one per row and stretch whatever the smoother; what a smoother's
 * noise adds above the band averages out of the stretches as it does out
 * of phi, while its blunting, or a narrow smoother's slow error, stays in
 * them as it stays in phi. */
#define BAND_BLOCK_US 100000

/* Adds a stretch's sums (sum[6] over *count samples) to *out, squared
 * over the count, and empties it. */
static void band_flush(double sum[6], int *count, double *out) {
    if (*count > 0)
        for (int row = 0; row < 6; ++row) *out += sq(sum[row]) / *count, sum[row] = 0;
    *count = 0;
}

static double band_residual(const loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                            double force_sigma, double torque_sigma, int64_t t_ref,
                            const double *x) {
    loadid_real_t phi[16];
    for (int p = 0; p < n_params; ++p) phi[p] = (loadid_real_t)x[p];
    double sum[6] = {0}, out = 0;
    int count = 0;
    int64_t block = 0;
    for (int i = 0; i < r->scount; ++i) {
        const int64_t b = (r->s[i].t - r->s[0].t) / BAND_BLOCK_US;
        if (b != block) band_flush(sum, &count, &out), block = b;
        double res[6];
        if (sample_residual(r, i, n_params, zero_a, t_ref, x, phi, res)) continue;
        for (int row = 0; row < 6; ++row)
            sum[row] += res[row] / (row < 3 ? force_sigma : torque_sigma);
        count++;
    }
    band_flush(sum, &count, &out);
    return out;
}

/* One Gauss-Newton step of the joint stamps' delay against the wrench's,
 * and its standard error. With phi the least-squares fit at delay d, the
 * residual r = y - A(t + d) phi is to first order (D - d) c, c the
 * predicted wrench's time derivative (a central difference over
 * stencil_half samples each side), D the true delay; phi takes up the part of c inside the span
 * of A, so the step is c_p^T W r / c_p^T W c_p, c_p = c - A b,
 * b = (A^T W A)^-1 A^T W c. Its variance is a cluster sandwich over
 * DELAY_BLOCKS stretches of the window: the residual's misfit (servo lag,
 * backlash) is correlated over many samples, which white rows would not
 * count. It is never below white rows' at the residual's scale,
 * rss / (rows - cols) / J: ten blocks of a smooth c_p, whose scores the
 * fit's columns (offset, drift) tie together, said half of that on slow
 * motion (1.5 s, |omega| 0.37 rad/s RMS: 2.6 ms where 60 noise draws of
 * one trajectory spread 5.6 ms and white rows said 4.7), and a delay of
 * 5-14 ms was used in 7 of 40 draws simulated without one. step and std
 * in us; step 0 when it cannot be taken. */
#define DELAY_BLOCKS 10

/* Half the span of the central difference that gives c, in samples: 20
 * ms. Over one sample's step it differenced the kinematics' noise, whose
 * share of c then weighed in c^T W c and in nothing of the score (errors
 * in the variable): the step fell short and the standard error with it,
 * the more the less the joints were smoothed. Slow motion, 40 noise draws
 * with 10 ms simulated: fits at -4.4 to 25 ms, 2.9 standard errors off in
 * RMS, the draws with the least smoothing lowest (-3.2 ms at 1.1 ms);
 * over 20 ms 1.33 (and 1.34 against 1.49 with none simulated). A motion's
 * derivative loses 2.4 % of it at 3 Hz. */
#define DELAY_STENCIL_US 20000
static int stencil_half(const loadid_refined_t *r) {
    if (r->scount < 3) return 1;
    const double period = (double)(r->s[r->scount - 1].t - r->s[0].t) / (double)(r->scount - 1);
    const double half = period > 0 ? (double)DELAY_STENCIL_US / period : 1.0;
    return (int)fmax(1.0, fmin(round(half), (double)(r->scount - 1) / 4.0));
}

typedef struct {
    double step, std;
    double b[LOADID_NPHI]; /* phi's part of b: phi's move per us of delay */
} delay_step_t;

static delay_step_t delay_step(const loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                               double force_sigma, double torque_sigma, int64_t t_ref) {
    const int n = n_params, cols = fit_cols(n, t_ref);
    delay_step_t out = {0, INFINITY, {0}};
    double x[MAX_COLS], M[MAX_COLS * MAX_COLS];
    const double rss = fit_residual(r, n, zero_a, force_sigma, torque_sigma, t_ref, NULL, x, M);
    const double dof = 6.0 * (double)kin_count(r) - cols;
    if (!isfinite(rss) || !(dof > 0)) return out;
    loadid_real_t phi[16];
    for (int p = 0; p < n; ++p) phi[p] = (loadid_real_t)x[p];
    /* The predicted wrench at every sample (NaN where there is none). */
    loadid_real_t A[6 * 16], pred[6];
    for (int i = 0; i < r->scount; ++i) {
        const loadid_real_t *k = r->kin_store + 9 * (size_t)i;
        const int ok =
            r->kin_ok[i] && !loadid_regressor_model_zeroed(k, k + 3, k + 6, n, zero_a, A);
        if (ok) loadid_regressor_apply(A, n, phi, pred);
        for (int row = 0; row < 6; ++row) r->pred[6 * (size_t)i + row] = ok ? pred[row] : NAN;
    }
    const int h = stencil_half(r);
    double g[MAX_COLS] = {0}, cc = 0;
    double block_cr[DELAY_BLOCKS] = {0}, block_ar[DELAY_BLOCKS][MAX_COLS] = {{0}};
    for (int m = h; m + h < r->scount; ++m) {
        const double *lo = r->pred + 6 * (size_t)(m - h), *mid = r->pred + 6 * (size_t)m,
                     *hi = r->pred + 6 * (size_t)(m + h);
        const int64_t span = r->s[m + h].t - r->s[m - h].t;
        if (isnan(lo[0]) || isnan(mid[0]) || isnan(hi[0]) || span <= 0) continue;
        const loadid_real_t *k = r->kin_store + 9 * (size_t)m;
        if (loadid_regressor_model_zeroed(k, k + 3, k + 6, n, zero_a, A)) continue;
        const int blk = (int)((int64_t)m * DELAY_BLOCKS / r->scount);
        const double dt = drift_dt(r, m, t_ref);
        for (int row = 0; row < 6; ++row) {
            const double w = 1.0 / sq(row < 3 ? force_sigma : torque_sigma);
            /* The kinematics' part of the prediction moves with the delay,
             * the drift's does not. */
            const double c = (hi[row] - lo[row]) / (double)span;
            const double res = (double)r->s[m].y[row] - mid[row] - drift_part(x, n, cols, row, dt);
            double a[MAX_COLS];
            for (int p = 0; p < n; ++p) a[p] = (double)A[row * n + p];
            for (int p = n; p < cols; ++p) a[p] = p - n == row ? dt : 0;
            cc += w * c * c;
            block_cr[blk] += w * c * res;
            for (int p = 0; p < cols; ++p) {
                if (a[p] == 0) continue;
                g[p] += w * a[p] * c;
                block_ar[blk][p] += w * a[p] * res;
            }
        }
    }
    double b[MAX_COLS]; /* M: fit_residual's normal matrix, over every sample */
    memcpy(b, g, sizeof b);
    if (loadid_spd_solve(M, b, cols)) return out;
    double J = cc; /* c_p^T W c_p */
    for (int p = 0; p < cols; ++p) J -= g[p] * b[p];
    if (!(J > 0)) return out;
    /* Each block's score c_p^T W r; their sum is the step's numerator. */
    double score[DELAY_BLOCKS], sum = 0;
    for (int k = 0; k < DELAY_BLOCKS; ++k) {
        score[k] = block_cr[k];
        for (int p = 0; p < cols; ++p) score[k] -= b[p] * block_ar[k][p];
        sum += score[k];
    }
    double var = 0;
    for (int k = 0; k < DELAY_BLOCKS; ++k) var += sq(score[k] - sum / DELAY_BLOCKS);
    out.step = sum / J;
    memcpy(out.b, b, sizeof out.b); /* n is 10 or 16 */
    out.std = fmax(sqrt(var * DELAY_BLOCKS / (DELAY_BLOCKS - 1.0)) / J, sqrt(rss / dof / J));
    return out;
}

/* The joint stamps' delay against the wrench's (a transport or clock
 * offset the recording carries): Gauss-Newton on the kinematics at the
 * samples' times plus the delay, from 0, each step evaluated again, on the
 * joints smoothed last (r->count entries, their kinematics at 0 in place;
 * left at the delay). Returns the delay [us], its standard error (*std_us,
 * Inf when no step could be taken) and phi's move per us of it (b[10], of
 * the last step). */
#define DELAY_MAX_US 50000
static double fit_delay(loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                        double force_sigma, double torque_sigma, int64_t t_ref, double *std_us,
                        double b[LOADID_NPHI]) {
    double d = 0;
    *std_us = INFINITY;
    for (int it = 0; it < 4; ++it) {
        const delay_step_t step = delay_step(r, n_params, zero_a, force_sigma, torque_sigma, t_ref);
        d = fmax(-DELAY_MAX_US, fmin(DELAY_MAX_US, d + step.step));
        *std_us = step.std;
        memcpy(b, step.b, LOADID_NPHI * sizeof *b);
        if (kinematics_at(r, r->count, llround(d)) < 2) break;
        if (fabs(step.step) < 20) break; /* 20 us: far below what moves the estimate */
    }
    return d;
}

/* Whether a delay d (std: its standard error) is one to use: at least
 * DELAY_USE_US and DELAY_SIGNIFICANT standard errors. Below 1 ms the fit
 * mostly sees the misfit's phase (servo lag, backlash): simulated without
 * a delay, -1.0 to +0.35 ms, and using it left REFINED's median inertia
 * error 5 % worse (2.35 % against 2.24 %, 120 recordings). */
#define DELAY_USE_US 1000
#define DELAY_SIGNIFICANT 3.0
static int delay_stands_out(double d, double std) {
    return fabs(d) >= fmax(DELAY_USE_US, DELAY_SIGNIFICANT * std);
}

/* Whether the kinematics in place (the delay d's) leave a lower residual
 * than those at delay 0; leaves those at 0 in place. */
static int lowers_residual(loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                           double force_sigma, double torque_sigma, int64_t t_ref) {
    const int64_t at_d = kin_count(r);
    const double rss = at_d > 1 ? fit_residual(r, n_params, zero_a, force_sigma, torque_sigma,
                                               t_ref, NULL, NULL, NULL) /
                                      (double)at_d
                                : INFINITY;
    const int64_t at_0 = kinematics_at(r, r->count, 0);
    return at_0 > 1 && rss < fit_residual(r, n_params, zero_a, force_sigma, torque_sigma, t_ref,
                                          NULL, NULL, NULL) /
                                 (double)at_0;
}

/* What the delay d (std: its standard error; b[10]: phi's move per us of
 * it) does to phi on the smoothing in place, whose kinematics are at
 * trial_us (d's, when the trials took it, else 0): uses it when trial_us
 * is not 0 and it lowers the residual here too (returns 1; the kinematics
 * left at it, else at 0). var[10] gets b^2 std^2 for a used delay, what
 * fitting it costs phi, and b^2 (d^2 + std^2) for one not told from 0
 * (below). */
static int use_delay(loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                     double force_sigma, double torque_sigma, int64_t t_ref, int64_t trial_us,
                     double d, double std, const double b[LOADID_NPHI], double var[LOADID_NPHI]) {
    memset(var, 0, LOADID_NPHI * sizeof *var);
    int used = 0;
    if (trial_us != 0) {
        used = lowers_residual(r, n_params, zero_a, force_sigma, torque_sigma, t_ref);
        if (used) kinematics_at(r, r->count, trial_us);
    }
    if (!isfinite(std)) return used;
    /* Not used: phi stays at delay 0. One the fit cannot tell from 0
     * (under DELAY_SIGNIFICANT standard errors) may still be there: the
     * error b D of phi at 0, D about N(d, std^2), has mean square
     * b^2 (d^2 + std^2). On slow motion (UR5, |omega| 0.37 rad/s RMS, a
     * 10 ms delay fitted at 2-24 ms with std 1-7 ms) it was used in 11 of
     * 40 draws and the others' mass was 2-4.5 % off at up to 3.5 phi_std
     * (coverage 65 %). A significant one left (under DELAY_USE_US: the
     * misfit's phase, or not lowering the residual) adds b^2 std^2. */
    const double d2 = fabs(d) < DELAY_SIGNIFICANT * std ? d * d : 0.0;
    for (int p = 0; p < LOADID_NPHI; ++p) var[p] = sq(b[p]) * (d2 + sq(std));
    return used;
}

/* A linear drift of the F/T offset (a sensor warming up): weighted least
 * squares on [A E6 (t - t_ref) E6] with the offset estimated (22 columns,
 * t_ref the window's middle), on [A (t - t_ref) E6] with zeroing (16, t_ref
 * the zeroing window's middle, where the offset is zero), gives the drift
 * (drift[6], N/s and N m/s), and what estimating it costs phi: per
 * parameter the fit's variance less that without the drift columns
 * (extra_var[10]), both at the fit's residual scale. A drift of 0.05 N/s
 * and 0.002 N m/s, which a constant offset does not fit, moved the COM of
 * a slow motion by 12 to 26 mm (2-3 mm without it) while phi_std said 5.
 * Returns 0, or -1 when the fit is singular. */
static int fit_drift(const loadid_refined_t *r, int n_params, const loadid_real_t *zero_a,
                     double force_sigma, double torque_sigma, int64_t t_ref, double drift[6],
                     double extra_var[10]) {
    const int n = n_params, N = n_params + 6;
    double M[MAX_COLS * MAX_COLS], b[MAX_COLS], yy;
    const double rows =
        normal_equations(r, n, N, zero_a, force_sigma, torque_sigma, t_ref, M, b, &yy);
    if (!(rows > N + 2)) return -1;
    for (int p = 0; p < N; ++p)
        for (int q = 0; q < p; ++q) M[q * N + p] = M[p * N + q];
    double Ln[LOADID_NPHI_OFFSET * LOADID_NPHI_OFFSET], x[MAX_COLS];
    for (int p = 0; p < n; ++p)
        for (int q = 0; q < n; ++q) Ln[p * n + q] = M[p * N + q];
    double *L = M; /* factored in place */
    if (loadid_chol_factor(L, N) || loadid_chol_factor(Ln, n)) return -1;
    memcpy(x, b, (size_t)N * sizeof *x);
    loadid_chol_solve(L, x, N);
    double fit = 0;
    for (int p = 0; p < N; ++p) fit += b[p] * x[p];
    const double s2 = fmax(yy - fit, 0) / (rows - N);
    for (int j = 0; j < 6; ++j) drift[j] = x[n + j];
    for (int i = 0; i < LOADID_NPHI; ++i) {
        double e[MAX_COLS] = {0}, en[LOADID_NPHI_OFFSET] = {0};
        e[i] = en[i] = 1;
        loadid_chol_solve(L, e, N);
        loadid_chol_solve(Ln, en, n);
        extra_var[i] = s2 * fmax(e[i] - en[i], 0);
    }
    return 0;
}

/* A vibration while estimating: the largest tone of the accelerometer's
 * difference to the smoothed joints (a - g, alpha), over blocks of the
 * window (loadid_noise_tone_blocks; the zeroing window's tone is measured
 * when the load is still, and a vibration the motion excites is not in
 * it). Samples without kinematics are left out, the rest taken as evenly
 * spaced. */
static void sensor_tones(loadid_refined_t *r, loadid_refined_report_t *rep) {
    for (int g = 0; g < 2; ++g) {
        int n = 0;
        int64_t t0 = 0, t1 = 0;
        for (int i = 0; i < r->scount; ++i) {
            if (!r->kin_ok[i]) continue;
            const loadid_real_t *k = r->kin_store + 9 * (size_t)i + (g ? 6 : 0);
            const loadid_real_t *v = g ? r->s[i].ang : r->s[i].lin;
            for (int a = 0; a < 3; ++a) r->tone_x[3 * n + a] = (double)v[a] - (double)k[a];
            if (n == 0) t0 = r->s[i].t;
            t1 = r->s[i].t;
            ++n;
        }
        if (n < 2 || t1 <= t0) return;
        loadid_noise_tone_blocks(r->tone_x, n, (double)(t1 - t0) * 1e-6 / (n - 1),
                                 &rep->sensor_tone_share[g], &rep->sensor_tone_hz[g]);
    }
}

/* The smoother's bandwidth trials (loadid_refined_run): the best so far
 * (its band residual, PSD, kinematics' sample count and joints' count),
 * its kinematics and smoothed joints kept in the best stores. */
#define BANDWIDTH_GRID 5
typedef struct {
    double band, psd;
    int64_t used;
    int count;
} bandwidth_pick_t;

/* Fits the joints smoothed last (at jerk PSD psd) with their kinematics
 * at the samples' times plus delay_us, and keeps the trial in *pick when
 * its band residual is the least so far. Returns the band residual, +Inf
 * when the trial is unusable. */
static double pick_trial(loadid_refined_t *r, double psd, int n_params, const loadid_real_t *zero_a,
                         const loadid_noise_levels_t *levels, int64_t t_ref, int64_t delay_us,
                         bandwidth_pick_t *pick) {
    const int64_t n = kinematics_at(r, r->count, delay_us);
    if (n < 2) return INFINITY;
    double x[MAX_COLS];
    if (!isfinite(
            fit_residual(r, n_params, zero_a, levels->force, levels->torque, t_ref, NULL, x, NULL)))
        return INFINITY;
    const double band = band_residual(r, n_params, zero_a, levels->force, levels->torque, t_ref, x);
    if (band < pick->band) {
        *pick = (bandwidth_pick_t){band, psd, n, r->count};
        swap_best(r); /* keep this trial's kinematics and smoothed joints */
    }
    return band;
}

/* Smooths at jerk PSD psd (jf: the joint filter's model, its PSD set);
 * returns the entries smoothed (r->count), or a negative code. */
static int smooth_at(loadid_refined_t *r, loadid_jf_config_t *jf, double psd) {
    jf->jerk_psd = (loadid_real_t)psd;
    const int count = smooth_joints(r, jf, r->s[0].t - JOINT_MARGIN_US);
    if (count >= 0) r->count = count;
    return count;
}

/* Smooths at psd, then pick_trial. */
static double bandwidth_trial(loadid_refined_t *r, loadid_jf_config_t *jf, double psd, int n_params,
                              const loadid_real_t *zero_a, const loadid_noise_levels_t *levels,
                              int64_t t_ref, int64_t delay_us, bandwidth_pick_t *pick) {
    if (smooth_at(r, jf, psd) < 2) return INFINITY;
    return pick_trial(r, psd, n_params, zero_a, levels, t_ref, delay_us, pick);
}

int loadid_refined_run(loadid_refined_t *r, const loadid_config_t *cfg, int has_accel,
                       const double channel[LOADID_NOISE_CHANNELS], int channel_source,
                       const loadid_real_t *zero_a, int n_params, int64_t zeroed_drift_from_us,
                       loadid_est_t *est, loadid_refined_report_t *rep) {
    memset(rep, 0, sizeof *rep);
    if (r->scount < 2) return LOADID_E_NOT_EXCITED;
    /* The wrench's measured (or configured) noise, for the rows. */
    loadid_config_t c = *cfg;
    c.noise_given &= LOADID_NOISE_GIVEN_FORCE | LOADID_NOISE_GIVEN_TORQUE;
    loadid_noise_combine(&c, 0, 0, channel, channel_source, 1, 1, 1, &rep->levels);

    /* The smoother's bandwidth from the data: of ten times the configured
     * jerk PSD, it and three lower ones (each a factor 10, the bandwidth
     * 1.47 times lower), and half a decade beside the best of those (below),
     * the one whose kinematics explain the measured
     * wrench best in the motion's band (band_residual). A smoother too
     * wide keeps what the encoders see but the load does not (backlash,
     * noise); one too narrow blunts the motion. The whole residual weighs
     * the first's noise, which averages out of phi, as much as the
     * blunting, which does not: at 2^14 counts on the UR5 its least (a
     * PSD of 0.1) left REFINED's inertia 1.5-2.5 times the reference's
     * error (the study's medians over the loads), the band's (1) about
     * equal to it. */
    /* With the offset estimated, its drift too; with zeroing, the drift
     * since zeroing when the caller found one: in every fit below. */
    const int64_t t_ref =
        n_params == LOADID_NPHI_OFFSET ? r->s[r->scount / 2].t : zeroed_drift_from_us;
    loadid_jf_config_t jf = r->jf;
    double band[BANDWIDTH_GRID], psd[BANDWIDTH_GRID];
    for (int trial = 0; trial < BANDWIDTH_GRID; ++trial)
        psd[trial] = (double)r->jf.jerk_psd * pow(10.0, 1 - trial);

    /* The joints' delay first, on the narrowest smoothing: the trials
     * below, and the delay's use, are then judged at it. A wide smoother
     * leaves noise in the kinematics that is in both the residual and its
     * derivative the fit steps along: slow motion (|omega| 0.37 rad/s RMS),
     * every joint state 20 ms late, 20 noise draws: fitted on the chosen
     * smoothing (PSD 0.001 to 1, picked at delay 0), 1.9 standard errors
     * off in RMS, two fits near 0 that the residual did not prefer, mass
     * within 2 phi_std in 85 % of the draws; on the narrowest, 1.2, none
     * near 0, 90 %. Without a delay, the same draws: 1.31 standard errors
     * in RMS (1.34 before). phi's move per us of delay (b) is the narrowest
     * fit's too: with the chosen smoothing's, the slow draws' mass error /
     * phi_std were within 3 % of these. */
    const int narrowest = BANDWIDTH_GRID - 1;
    double delay = 0, delay_std = INFINITY, delay_b[LOADID_NPHI] = {0};
    int64_t trial_delay = 0;
    const int narrow_ok = smooth_at(r, &jf, psd[narrowest]) >= 2;
    if (narrow_ok && kinematics_at(r, r->count, 0) >= 2) {
        delay = fit_delay(r, n_params, zero_a, rep->levels.force, rep->levels.torque, t_ref,
                          &delay_std, delay_b);
        if (delay_stands_out(delay, delay_std) &&
            lowers_residual(r, n_params, zero_a, rep->levels.force, rep->levels.torque, t_ref))
            trial_delay = llround(delay);
    }
    /* The narrowest's joints are in place: its trial first, then the
     * others'. */
    bandwidth_pick_t pick = {INFINITY, 0, 0, 0};
    band[narrowest] = narrow_ok ? pick_trial(r, psd[narrowest], n_params, zero_a, &rep->levels,
                                             t_ref, trial_delay, &pick)
                                : INFINITY;
    int best_trial = isfinite(pick.band) ? narrowest : -1;
    for (int trial = 0; trial < narrowest; ++trial) {
        const double least = pick.band;
        band[trial] = bandwidth_trial(r, &jf, psd[trial], n_params, zero_a, &rep->levels, t_ref,
                                      trial_delay, &pick);
        if (pick.band < least) best_trial = trial;
    }
    /* Then half a decade towards the best's better neighbour: a decade
     * is coarse where blunting and the columns' noise pull phi opposite
     * ways. With 2^14 counts on the RX60 the hollow load's mass was off by
     * +0.09 % at a PSD of 1 (blunted motion), -0.06 % at 10 (the noise in
     * the columns, which count as exact), +0.02 % at 3.2 (means over 20
     * seeds; the reference -0.02 %). */
    if (best_trial >= 0) {
        const int lo = best_trial - 1, hi = best_trial + 1;
        const int nb = lo < 0 ? hi : hi >= BANDWIDTH_GRID ? lo : band[lo] <= band[hi] ? lo : hi;
        if (isfinite(band[nb]))
            bandwidth_trial(r, &jf, sqrt(psd[best_trial] * psd[nb]), n_params, zero_a, &rep->levels,
                            t_ref, trial_delay, &pick);
    }
    if (pick.used < 2) return LOADID_E_NO_DATA;
    swap_best(r); /* the best back in place */
    r->count = pick.count;
    jf.jerk_psd = (loadid_real_t)pick.psd;
    rep->jerk_psd = pick.psd;
    rep->joint_delay_us = llround(delay);
    rep->joint_delay_std_us = delay_std;
    rep->joint_delay_used =
        use_delay(r, n_params, zero_a, rep->levels.force, rep->levels.torque, t_ref, trial_delay,
                  delay, delay_std, delay_b, rep->delay_var);
    const int64_t used = kin_count(r);
    double smooth_sigma[3];
    loadid_jf_steady_sigma(&jf, 1e-3, 1, smooth_sigma);

    /* The accelerometer's difference to the smoothed joints (reported) and
     * the RMS |omega| (omega's column scale). */
    double d_spec = 0, d_alpha = 0, w2 = 0;
    for (int i = 0; i < r->scount; ++i) {
        if (!r->kin_ok[i]) continue;
        const loadid_real_t *k = r->kin_store + 9 * (size_t)i;
        for (int a = 0; a < 3; ++a) {
            d_spec += sq((double)r->s[i].lin[a] - (double)k[a]);
            d_alpha += sq((double)r->s[i].ang[a] - (double)k[6 + a]);
            w2 += sq((double)k[3 + a]);
        }
    }
    rep->omega_rms = sqrt(w2 / (double)used);
    if (has_accel) {
        rep->sensor_spec_error = sqrt(d_spec / (3.0 * (double)used));
        rep->sensor_alpha_error = sqrt(d_alpha / (3.0 * (double)used));
        sensor_tones(r, rep);
    }
    loadid_real_t q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
    int k = 0;

    /* The smoothed joints' own errors at the window's middle pose; as
     * conditional means, their columns count as exact in the weights
     * (loadid_noise_weights; with the smoother's own figure TLS
     * over-corrected 2.9 % of the mass on the simulated RX60). */
    double js = 0, ja = 0, jw = 0;
    if (joints_at(r, r->count, &k, r->s[r->scount / 2].t, q, qd, qdd) == 0)
        loadid_noise_joint_levels(r->kin, q, smooth_sigma[1], smooth_sigma[2], &js, &ja, &jw);
    loadid_noise_combine(&c, 0, 0, channel, channel_source, fmax(js, 1e-9), fmax(ja, 1e-9),
                         fmax(jw, 1e-12), &rep->levels);

    /* The rows' noise raised by what of a least-squares fit's residual the
     * wrench's noise does not explain, then the TLS fit. */
    double rss[2];
    fit_residual(r, n_params, zero_a, rep->levels.force, rep->levels.torque, t_ref, rss, NULL,
                 NULL);
    const double dof = fmax(3.0 * (double)used - fit_cols(n_params, t_ref) / 2.0, 1.0);
    rep->unexplained[0] = sqrt(fmax(rss[0] / dof - sq(rep->levels.force), 0));
    rep->unexplained[1] = sqrt(fmax(rss[1] / dof - sq(rep->levels.torque), 0));
    rep->levels.force = hypot(rep->levels.force, rep->unexplained[0]);
    rep->levels.torque = hypot(rep->levels.torque, rep->unexplained[1]);
    const int rc = weigh(est, &rep->levels, rep->omega_rms);
    if (rc) return rc;
    rep->drift_fitted =
        t_ref != INT64_MIN && fit_drift(r, n_params, zero_a, rep->levels.force, rep->levels.torque,
                                        t_ref, rep->drift, rep->drift_var) == 0;
    if (!rep->drift_fitted) memset(rep->drift, 0, sizeof rep->drift);
    /* Without a drift the reference time is unused (drift 0; INT64_MIN
     * would overflow the difference). */
    loadid_spectrum_rows_reset(r->rows);
    rep->samples = feed(r, n_params, zero_a, rep->drift, rep->drift_fitted ? t_ref : 0, est);
    loadid_spectrum_rows_transform(r->rows); /* else phi_std has one level per row group */
    return rep->samples > 1 ? 0 : LOADID_E_NOT_EXCITED;
}
