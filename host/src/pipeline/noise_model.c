/* The measured noise model (noise_model.h). */
#include "loadid/noise_model.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "spd.h"

#define D3_MIN 100
#define D3_GAIN 20.0 /* var(x_k - 3 x_k-1 + 3 x_k-2 - x_k-3) / sigma^2 = 1 + 9 + 9 + 1 */
#define MAD_TO_SIGMA 1.482602218505602 /* 1 / Phi^-1(3/4): sigma of a normal from its MAD */
#define TWO_PI 6.283185307179586

void loadid_noise_acc_reset(loadid_noise_acc_t *a) {
    a->still_n = 0;
    a->moved = 0;
    a->hist_n = 0;
    a->last_t_us = 0;
    a->d3_n = a->d3_head = 0;
}

void loadid_noise_acc_reset_still(loadid_noise_acc_t *a) {
    a->still_n = 0;
    a->moved = 0;
}

/* x of still row k in [-1, 1] (the cubic's variable). */
static double still_x(const loadid_noise_acc_t *a, int k) {
    return a->still_n > 1 ? (2.0 * k - (a->still_n - 1)) / (a->still_n - 1) : 0.0;
}

/* Channel i of still row k, less its cubic when the load moved. */
static double still_value(const loadid_noise_acc_t *a, int k, int i) {
    if (!a->moved) return a->still[k][i];
    const double x = still_x(a, k);
    const double *c = a->trend[i];
    return a->still[k][i] - (c[0] + x * (c[1] + x * (c[2] + x * c[3])));
}

/* Row k's regressors of the tone fit: 1, then cos and sin of each tone. */
static void regressors(const double *hz, int n_hz, double period_s, int k, double *r) {
    r[0] = 1;
    for (int t = 0; t < n_hz; ++t) {
        const double w = TWO_PI * hz[t] * period_s * k;
        r[1 + 2 * t] = cos(w), r[2 + 2 * t] = sin(w);
    }
}

void loadid_noise_acc_moved(loadid_noise_acc_t *a) {
    a->moved = 0;
    const int n = a->still_n;
    if (n < 8) return;
    /* Normal equations of the cubic, the same for every channel. */
    double m[4][4] = {{0}}, b[LOADID_NOISE_CHANNELS][4] = {{0}};
    for (int k = 0; k < n; ++k) {
        const double x = still_x(a, k), p[4] = {1, x, x * x, x * x * x};
        for (int r = 0; r < 4; ++r) {
            for (int s = 0; s < 4; ++s) m[r][s] += p[r] * p[s];
            for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i) b[i][r] += p[r] * a->still[k][i];
        }
    }
    /* Gauss-Jordan on [m | b^T] (x in [-1, 1]: well conditioned). */
    for (int col = 0; col < 4; ++col) {
        const double piv = m[col][col];
        if (!(fabs(piv) > 0)) return;
        for (int r = 0; r < 4; ++r) {
            if (r == col) continue;
            const double f = m[r][col] / piv;
            for (int s = 0; s < 4; ++s) m[r][s] -= f * m[col][s];
            for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i) b[i][r] -= f * b[i][col];
        }
    }
    for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i)
        for (int r = 0; r < 4; ++r) a->trend[i][r] = b[i][r] / m[r][r];
    a->moved = 1;
}

void loadid_noise_acc_still(loadid_noise_acc_t *a, const double x[LOADID_NOISE_CHANNELS]) {
    if (a->still_n == LOADID_NOISE_STILL_MAX) return; /* the first ones are enough */
    memcpy(a->still[a->still_n++], x, sizeof a->still[0]);
}

void loadid_noise_acc_moving(loadid_noise_acc_t *a, int64_t t_us, int64_t period_us,
                             const double x[LOADID_NOISE_CHANNELS]) {
    if (a->hist_n > 0 && (t_us <= a->last_t_us || t_us - a->last_t_us > 3 * period_us))
        a->hist_n = 0; /* not consecutive: start again */
    if (a->hist_n == 3) {
        double *d = a->d3[a->d3_head];
        for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i)
            d[i] = x[i] - 3.0 * a->hist[2][i] + 3.0 * a->hist[1][i] - a->hist[0][i];
        a->d3_head = (a->d3_head + 1) % LOADID_NOISE_D3_RING;
        if (a->d3_n < LOADID_NOISE_D3_RING) a->d3_n++;
        memmove(a->hist[0], a->hist[1], 2 * sizeof a->hist[0]);
        memcpy(a->hist[2], x, sizeof a->hist[2]);
    } else {
        memcpy(a->hist[a->hist_n++], x, sizeof a->hist[0]);
    }
    a->last_t_us = t_us;
}

/* The k-th smallest of v[0..n) (Wirth's selection; v is reordered). */
static double select_kth(double *v, int n, int k) {
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        const double x = v[k];
        int i = lo, j = hi;
        do {
            while (v[i] < x) ++i;
            while (x < v[j]) --j;
            if (i <= j) {
                const double t = v[i];
                v[i++] = v[j];
                v[j--] = t;
            }
        } while (i <= j);
        if (j < k) lo = i;
        if (k < i) hi = j;
    }
    return v[k];
}

/* The median of v[0..n) (the upper one for even n). */
static double median(double *v, int n) {
    return select_kth(v, n, n / 2);
}

/* The standard deviation of v[0..n) (reordered), values off center:
 * the root mean square of those within ROBUST_CUT of the median absolute
 * deviation's sigma, about their own mean when centered (n - 1 degrees of
 * freedom), else about 0. The MAD alone screens bit errors (5 % of them
 * made a plain standard deviation read 18 N for 0.1 N) but misreads noise
 * that is not normal: a vibration's sinusoid of amplitude a has a MAD
 * sigma of 1.05 a against its 0.71 a (with a normal noise of a / 3,
 * 1.25 times the root of the variance), and the TLS weights need the
 * variance. A normal's tails beyond 5 sigma are 6e-7 of it. */
#define ROBUST_CUT 5.0
static double robust_sigma(double *v, double *w, int n, int centered) {
    const double c = centered ? median(v, n) : 0.0;
    for (int k = 0; k < n; ++k) w[k] = fabs(v[k] - c);
    const double cut = ROBUST_CUT * MAD_TO_SIGMA * median(w, n);
    double sum = 0, sum2 = 0;
    int m = 0;
    for (int k = 0; k < n; ++k)
        if (fabs(v[k] - c) <= cut) sum += v[k] - c, sum2 += (v[k] - c) * (v[k] - c), ++m;
    if (m < 2) return 0;
    if (!centered) return sqrt(sum2 / m);
    return sqrt(fmax(sum2 - sum * sum / m, 0) / (m - 1));
}

/* sigma of channel i of rows[0..n) (robust_sigma). */
static double channel_sigma(loadid_noise_acc_t *a, const double (*rows)[LOADID_NOISE_CHANNELS],
                            int n, int i, int centered) {
    for (int k = 0; k < n; ++k) a->scratch[k] = rows[k][i];
    return robust_sigma(a->scratch, a->scratch2, n, centered);
}

int loadid_noise_acc_sigma(loadid_noise_acc_t *a, int min_still,
                           double sigma[LOADID_NOISE_CHANNELS]) {
    if (a->still_n >= min_still && a->still_n >= 2) {
        for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i) {
            if (!a->moved) {
                sigma[i] = channel_sigma(a, (const double(*)[LOADID_NOISE_CHANNELS])a->still,
                                         a->still_n, i, 1);
                continue;
            }
            const int n = a->still_n;
            for (int k = 0; k < n; ++k) a->scratch[k] = still_value(a, k, i);
            /* the cubic's 4 parameters: n - 4 degrees of freedom */
            sigma[i] = robust_sigma(a->scratch, a->scratch2, n, 0) * sqrt((double)n / (n - 4));
        }
        return LOADID_NOISE_STILL;
    }
    if (a->d3_n >= D3_MIN) {
        for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i)
            sigma[i] =
                channel_sigma(a, (const double(*)[LOADID_NOISE_CHANNELS])a->d3, a->d3_n, i, 0) /
                sqrt(D3_GAIN);
        return LOADID_NOISE_DIFFERENCES;
    }
    memset(sigma, 0, LOADID_NOISE_CHANNELS * sizeof sigma[0]);
    return LOADID_NOISE_FALLBACK;
}

int loadid_noise_offset_cov(const loadid_noise_acc_t *a, int64_t n_mean, double cov[36],
                            double rho[6]) {
    memset(cov, 0, 36 * sizeof cov[0]);
    if (rho) memset(rho, 0, 6 * sizeof rho[0]);
    const int n = a->still_n;
    if (n < 2 || n_mean < 1) return -EAGAIN;
    double mean[6] = {0}, c[6][6] = {{0}}, lag[6] = {0}, f[6];
    for (int k = 0; k < n; ++k)
        for (int i = 0; i < 6; ++i) mean[i] += still_value(a, k, i) / n;
    double prev[6] = {0}; /* row k - 1 less the mean */
    for (int k = 0; k < n; ++k) {
        double d[6]; /* each row's values once, not once per pair */
        for (int i = 0; i < 6; ++i) d[i] = still_value(a, k, i) - mean[i];
        for (int i = 0; i < 6; ++i) {
            for (int j = 0; j < 6; ++j) c[i][j] += d[i] * d[j];
            if (k > 0) lag[i] += d[i] * prev[i];
        }
        memcpy(prev, d, sizeof prev);
    }
    const int dof = a->moved ? n - 4 : n - 1;
    for (int i = 0; i < 6; ++i) {
        double r = c[i][i] > 0 ? lag[i] / c[i][i] : 0.0;
        r = r < -0.5 ? -0.5 : r > 0.95 ? 0.95 : r;
        if (rho) rho[i] = r;
        f[i] = sqrt((1 + r) / (1 - r));
    }
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) cov[6 * i + j] = f[i] * f[j] * c[i][j] / dof / (double)n_mean;
    return 0;
}

/* The power |X_j|^2 of x, y and z at bins j and j + 1 (j cycles per n
 * samples): Goertzel's recurrence, one multiplication a sample, its six
 * chains side by side (each step waits for the one before). */
static void group_power2(double (*x)[LOADID_NOISE_TONE_N], int n, int j, double power[2]) {
    const double coeff[2] = {2.0 * cos(TWO_PI * j / n), 2.0 * cos(TWO_PI * (j + 1) / n)};
    double s1[2][3] = {{0}}, s2[2][3] = {{0}};
    for (int k = 0; k < n; ++k)
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 3; ++c) {
                const double s0 = x[c][k] + coeff[b] * s1[b][c] - s2[b][c];
                s2[b][c] = s1[b][c], s1[b][c] = s0;
            }
    for (int b = 0; b < 2; ++b) {
        power[b] = 0;
        for (int c = 0; c < 3; ++c)
            power[b] += s1[b][c] * s1[b][c] + s2[b][c] * s2[b][c] - coeff[b] * s1[b][c] * s2[b][c];
    }
}

/* What least squares on [1, cos, sin] at f cycles per n samples explains
 * of x, y and z (their sum of squares of the fit); the twiddles by
 * recurrence from one rotation. */
static double group_fit_power(double (*x)[LOADID_NOISE_TONE_N], int n, double f) {
    const double step = TWO_PI * f / n, cs = cos(step), sn = sin(step);
    double c1 = 0, s1 = 0, cc = 0, ss = 0, sc = 0, b[3][3] = {{0}}, wr = 1, wi = 0;
    for (int k = 0; k < n; ++k) {
        c1 += wr, s1 += wi, cc += wr * wr, ss += wi * wi, sc += wr * wi;
        for (int c = 0; c < 3; ++c)
            b[c][0] += x[c][k], b[c][1] += wr * x[c][k], b[c][2] += wi * x[c][k];
        const double t = wr * cs - wi * sn;
        wi = wr * sn + wi * cs, wr = t;
    }
    const double M[9] = {(double)n, c1, s1, c1, cc, sc, s1, sc, ss};
    double power = 0;
    for (int c = 0; c < 3; ++c) {
        double M_c[9], beta[3] = {b[c][0], b[c][1], b[c][2]};
        memcpy(M_c, M, sizeof M);
        if (loadid_spd_solve(M_c, beta, 3) != 0) return 0;
        power += beta[0] * b[c][0] + beta[1] * b[c][1] + beta[2] * b[c][2];
    }
    return power;
}

/* x, y and z (n samples) each less its mean. */
static void less_means(double (*x)[LOADID_NOISE_TONE_N], int n) {
    for (int c = 0; c < 3; ++c) {
        double mean = 0;
        for (int k = 0; k < n; ++k) mean += x[c][k] / n;
        for (int k = 0; k < n; ++k) x[c][k] -= mean;
    }
}

/* The largest bin of x, y and z's transform (n samples, each less its
 * mean): its share of their variance and its index (0 if none). Bin j (1
 * .. n/2 - 1) and its mirror hold 2 |X_j|^2 / n of the sum of squares
 * (Parseval). */
static int largest_bin(double (*x)[LOADID_NOISE_TONE_N], int n, double *share, double *total) {
    *share = *total = 0;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < n; ++k) *total += x[c][k] * x[c][k];
    if (!(*total > 0)) return 0;
    int best = 0;
    for (int j = 1; j < n / 2; j += 2) {
        double pw[2];
        group_power2(x, n, j, pw);
        for (int b = 0; b < 2 && j + b < n / 2; ++b) {
            const double s = 2.0 * pw[b] / ((double)n * *total);
            if (s > *share) *share = s, best = j + b;
        }
    }
    return best;
}

/* The tone of x, y and z (n samples period_s apart, each less its mean):
 * within a bin of the transform's largest, the sinusoid that explains most
 * of them; its share of their variance and frequency. */
static void tone_of(double (*x)[LOADID_NOISE_TONE_N], int n, double period_s, double *share,
                    double *hz) {
    double total;
    const int best = largest_bin(x, n, share, &total);
    if (best == 0) return;
    /* The tone's frequency within the bin (a bin is 1 / (n period_s) wide,
     * 5 Hz for 0.2 s of samples, and a notch must sit on it): where a
     * least-squares sinusoid explains most, over bin +-1 in steps of 0.05,
     * then +-0.05 about the best in steps of 0.005 (a single tone's
     * maximum-likelihood frequency; the transform's peak is pulled by the
     * window's leakage when it holds few cycles: 7 Hz in 0.2 s was found at
     * 6.5-7.5 Hz). */
    double f = best, peak = 0;
    for (int pass = 0; pass < 2; ++pass) {
        const double centre = f, step = pass ? 0.005 : 0.05;
        const int half = pass ? 10 : 20;
        for (int i = -half; i <= half; ++i) {
            const double fi = centre + step * i, pw = fi >= 0.5 ? group_fit_power(x, n, fi) : 0;
            if (pw > peak) peak = pw, f = fi;
        }
    }
    *hz = f / ((double)n * period_s);
    /* The fitted sinusoid's share, not the bin's: a tone between two bins
     * leaks into both (28 Hz in 0.2 s of samples: 9 % of the noise in the
     * bin, 15 % fitted), so a bin's share hinged on where the tone fell. */
    if (peak > *share * total) *share = peak / total;
}

int loadid_noise_tone(const loadid_noise_acc_t *a, int group, double period_s, double *share,
                      double *hz) {
    *share = *hz = 0;
    if (group < 0 || group > 3 || !(period_s > 0)) return -EINVAL;
    const int n = a->still_n < LOADID_NOISE_TONE_N ? a->still_n : LOADID_NOISE_TONE_N;
    if (n < 32) return -EAGAIN;
    double x[3][LOADID_NOISE_TONE_N];
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < n; ++k) x[c][k] = still_value(a, k, 3 * group + c);
    less_means(x, n);
    tone_of(x, n, period_s, share, hz);
    return 0;
}

/* Block b of m samples of x (x[3 k + c]), each channel less its mean. */
static void block_of(const double *x, int b, int m, double (*v)[LOADID_NOISE_TONE_N]) {
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < m; ++k) v[c][k] = x[3 * ((size_t)b * m + k) + c];
    less_means(v, m);
}

int loadid_noise_tone_blocks(const double *x, int n, double period_s, double *share, double *hz) {
    *share = *hz = 0;
    if (n < 0 || !(period_s > 0)) return -EINVAL;
    if (n < 32) return -EAGAIN;
    const int blocks = n < LOADID_NOISE_TONE_N ? 1 : n / LOADID_NOISE_TONE_N;
    const int m = n < LOADID_NOISE_TONE_N ? n : LOADID_NOISE_TONE_N;
    /* The block whose largest bin holds most, then its sinusoid (the fit,
     * 62 frequencies, costs more than the bins). */
    double v[3][LOADID_NOISE_TONE_N], best_share = 0, total;
    int best = -1;
    for (int b = 0; b < blocks; ++b) {
        double s;
        block_of(x, b, m, v);
        if (largest_bin(v, m, &s, &total) > 0 && s > best_share) best_share = s, best = b;
    }
    if (best < 0) return 0;
    block_of(x, best, m, v);
    tone_of(v, m, period_s, share, hz);
    return 0;
}

#define TONE_FIT_MAX (1 + 2 * LOADID_NOISE_TONES_MAX) /* a mean, cos and sin per tone */
int loadid_noise_still_sigma_without(loadid_noise_acc_t *a, const double *hz, int n_hz,
                                     double period_s, double sigma[LOADID_NOISE_CHANNELS]) {
    if (n_hz < 0 || n_hz > LOADID_NOISE_TONES_MAX || !(period_s > 0)) return -EINVAL;
    const int n = a->still_n, p = 1 + 2 * n_hz;
    for (int t = 0; t < n_hz; ++t)
        if (!(hz[t] > 0)) return -EINVAL;
    if (n < 4 * p) return -EAGAIN;
    /* Two tones closer than the window's resolution are one to its fit. */
    if (n_hz == 2 && fabs(hz[0] - hz[1]) * n * period_s < 1) return -EDOM;
    for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i) {
        /* Least squares on [1, cos, sin per tone]: the normal equations. */
        double M[TONE_FIT_MAX * TONE_FIT_MAX] = {0}, b[TONE_FIT_MAX] = {0}, r[TONE_FIT_MAX];
        for (int k = 0; k < n; ++k) {
            regressors(hz, n_hz, period_s, k, r);
            const double v = still_value(a, k, i);
            for (int u = 0; u < p; ++u) {
                b[u] += r[u] * v;
                for (int w = 0; w < p; ++w) M[p * u + w] += r[u] * r[w];
            }
        }
        if (loadid_spd_solve(M, b, p) != 0) return -EDOM;
        for (int k = 0; k < n; ++k) {
            regressors(hz, n_hz, period_s, k, r);
            double fit = 0;
            for (int u = 0; u < p; ++u) fit += r[u] * b[u];
            a->scratch[k] = still_value(a, k, i) - fit;
        }
        /* p parameters: n - p degrees of freedom (about the fit, not a median) */
        sigma[i] = robust_sigma(a->scratch, a->scratch2, n, 0) * sqrt((double)n / (n - p));
    }
    return 0;
}

int loadid_noise_joint_levels(const loadid_kin_t *kin, const loadid_real_t *q, double sigma_qd,
                              double sigma_qdd, double *spec, double *alpha, double *omega) {
    const int n = loadid_kin_num_joints(kin);
    loadid_real_t zero[LOADID_MAX_JOINTS] = {0}, unit[LOADID_MAX_JOINTS] = {0};
    loadid_kin_state_t base, k;
    int rc = loadid_kin_eval(kin, q, zero, zero, &base);
    if (rc) return rc;
    double s2 = 0, a2 = 0, w2 = 0;
    for (int j = 0; j < n && rc == 0; ++j) {
        unit[j] = 1;
        /* alpha and a - g are linear in qdd (qd = 0), omega in qd. */
        rc = loadid_kin_eval(kin, q, zero, unit, &k);
        for (int i = 0; i < 3 && rc == 0; ++i) {
            const double ds = (double)(k.spec[i] - base.spec[i]),
                         da = (double)(k.alpha[i] - base.alpha[i]);
            s2 += ds * ds;
            a2 += da * da;
        }
        if (rc == 0) rc = loadid_kin_eval(kin, q, unit, zero, &k);
        for (int i = 0; i < 3 && rc == 0; ++i) w2 += (double)k.omega[i] * (double)k.omega[i];
        unit[j] = 0;
    }
    if (rc) return rc;
    /* Independent joints; per axis of S, the mean over x, y, z. */
    *spec = sigma_qdd * sqrt(s2 / 3.0);
    *alpha = sigma_qdd * sqrt(a2 / 3.0);
    *omega = sigma_qd * sqrt(w2 / 3.0);
    return 0;
}

double loadid_noise_rms3(const double v[3]) {
    return sqrt((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / 3.0);
}

/* One level: configured, else measured (never below a thousandth of the
 * fallback, so a noise-free channel does not get an infinite weight), else
 * the fallback. */
static double pick(int given, double configured, double measured, int measured_source,
                   int *source) {
    if (given) {
        *source = LOADID_NOISE_CONFIGURED;
        return configured;
    }
    if (measured_source != LOADID_NOISE_FALLBACK && measured > 0) {
        *source = measured_source;
        return fmax(measured, configured * 1e-3);
    }
    *source = LOADID_NOISE_FALLBACK;
    return configured;
}

void loadid_noise_combine(const loadid_config_t *cfg, int jr3_spec, int jr3_alpha,
                          const double channel[LOADID_NOISE_CHANNELS], int channel_source,
                          double joint_spec, double joint_alpha, double joint_omega,
                          loadid_noise_levels_t *out) {
    memset(out, 0, sizeof *out);
    const int g = cfg->noise_given;
    memcpy(out->channel, channel, sizeof out->channel);
    out->channel_source = channel_source;
    out->joint_spec = joint_spec;
    out->joint_alpha = joint_alpha;
    out->joint_omega = joint_omega;
    const int js = joint_spec > 0 ? LOADID_NOISE_FILTER : LOADID_NOISE_FALLBACK;
    out->force = pick(g & LOADID_NOISE_GIVEN_FORCE, cfg->noise_force, loadid_noise_rms3(channel),
                      channel_source, &out->source[0]);
    out->torque = pick(g & LOADID_NOISE_GIVEN_TORQUE, cfg->noise_torque,
                       loadid_noise_rms3(channel + 3), channel_source, &out->source[1]);
    out->spec = jr3_spec ? pick(g & LOADID_NOISE_GIVEN_LINEAR, cfg->noise_linear,
                                loadid_noise_rms3(channel + 6), channel_source, &out->source[2])
                         : pick(g & LOADID_NOISE_GIVEN_KF_SPEC, cfg->kalman_spec_sigma, joint_spec,
                                js, &out->source[2]);
    out->alpha = jr3_alpha ? pick(g & LOADID_NOISE_GIVEN_ANGULAR, cfg->noise_angular,
                                  loadid_noise_rms3(channel + 9), channel_source, &out->source[3])
                           : pick(g & LOADID_NOISE_GIVEN_KF_ALPHA, cfg->kalman_alpha_sigma,
                                  joint_alpha, js, &out->source[3]);
    out->omega =
        pick(g & LOADID_NOISE_GIVEN_OMEGA, cfg->noise_omega, joint_omega, js, &out->source[4]);
}

/* A level measured from the joint filter or smoother enters the weights
 * this far down, i.e. its columns count as exact (the mixed LS-TLS limit).
 * The filter's estimate is a conditional mean: its error is uncorrelated
 * with the estimate itself (a Berkson error, not a classical one), so
 * least squares on it has no attenuation bias for TLS to remove, and TLS
 * "correcting" it is wrong at any level. Measured: with the filter's own
 * figure on-line RTLS was 0.36 % off in mass on the 7-joint chain's
 * low-noise loads, RLS 0.03 %; REFINED over-corrected 2.9 % on the RX60.
 * The error still enters the residual, where estimation.rescale_s and
 * REFINED's row levels count it. A configured level is used as given. */
#define FILTER_EXACT_SCALE 1e-3

/* loadid_est_weights_from_noise into out with the joint filter's levels
 * times filter_scale (1: every level as measured). */
static int weights_scaled(const loadid_noise_levels_t *lv, double omega_typical,
                          double filter_scale, loadid_est_config_t *out) {
    double col[3] = {lv->spec, lv->alpha, lv->omega};
    for (int i = 0; i < 3; ++i)
        if (lv->source[2 + i] == LOADID_NOISE_FILTER) col[i] *= filter_scale;
    return loadid_est_weights_from_noise(out, (loadid_real_t)lv->force, (loadid_real_t)lv->torque,
                                         (loadid_real_t)col[0], (loadid_real_t)col[1],
                                         (loadid_real_t)col[2], (loadid_real_t)omega_typical);
}

int loadid_noise_weights(const loadid_noise_levels_t *lv, double omega_typical,
                         loadid_est_config_t *est) {
    /* The noise's own weights (for col_exact: the excitation gates use
     * those, so exactness does not make weak data look excited), the
     * measurements' part alone (the filter's sources at a trace: each
     * column's noise variance goes as 1 / weight^2, for col_measured), and
     * the estimator's. */
    loadid_est_config_t noise = *est, measured = *est;
    int rc = weights_scaled(lv, omega_typical, 1, &noise);
    if (rc == 0) rc = weights_scaled(lv, omega_typical, 1e-9, &measured);
    if (rc == 0) rc = weights_scaled(lv, omega_typical, FILTER_EXACT_SCALE, est);
    if (rc != 0) return rc;
    for (int j = 0; j <= est->n_params; ++j) {
        est->col_exact[j] = est->col_weight[j] / noise.col_weight[j];
        const double share = pow((double)noise.col_weight[j] / (double)measured.col_weight[j], 2);
        est->col_measured[j] = (loadid_real_t)(j < LOADID_NPHI ? fmin(share, 1.0) : 0.0);
    }
    return 0;
}

const char *loadid_noise_source_name(int source) {
    switch (source) {
        case LOADID_NOISE_STILL:
            return "zeroing";
        case LOADID_NOISE_DIFFERENCES:
            return "differences";
        case LOADID_NOISE_CONFIGURED:
            return "configured";
        case LOADID_NOISE_FILTER:
            return "joint filter";
        default:
            return "fallback";
    }
}
