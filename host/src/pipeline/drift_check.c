/* The zeroed model's drift check (drift_check.h). */
#include "drift_check.h"

#include <math.h>
#include <string.h>

#include "spd.h"

#define N LOADID_DRIFT_COLS
#define NA 10                /* the zeroed model's columns */
#define B0 (N * (N + 1) / 2) /* b's offset in the sums */
#define YY (B0 + N)
/* A block's time at first, doubled while the window outgrows the blocks.
 * Longer blocks hold more of the misfit's correlation (below). */
#define FIRST_BLOCK_US 100000
#define IV_EVERY 4

static double sq(double x) {
    return x * x;
}

static int packed(int i, int j) {
    return i >= j ? i * (i + 1) / 2 + j : j * (j + 1) / 2 + i;
}

void loadid_drift_check_reset(loadid_drift_check_t *c, int64_t t0_us, double force_sigma,
                              double torque_sigma) {
    memset(c, 0, sizeof *c);
    c->t0_us = t0_us;
    /* Levels that cannot weigh leave the rows unweighted (the test's
     * statistic does not depend on a common scale). */
    c->w[0] = force_sigma > 0 && isfinite(force_sigma) ? 1.0 / (force_sigma * force_sigma) : 1;
    c->w[1] = torque_sigma > 0 && isfinite(torque_sigma) ? 1.0 / (torque_sigma * torque_sigma) : 1;
    c->block_us = FIRST_BLOCK_US;
    c->block_start_us = INT64_MIN;
}

/* The block just filled ends here; 32 blocks full, pairs merge (the sums
 * are cumulative, so a merge drops every other boundary). */
static void close_block(loadid_drift_check_t *c) {
    if (c->blocks == LOADID_DRIFT_MAX_BLOCKS) {
        for (int k = 1; k <= LOADID_DRIFT_MAX_BLOCKS / 2; ++k)
            memcpy(c->snap[k], c->snap[2 * k], sizeof c->snap[k]);
        c->blocks = LOADID_DRIFT_MAX_BLOCKS / 2;
        c->block_us *= 2;
        c->block_start_us = c->block_end_us - c->block_us / 2;
        return; /* the block goes on, twice as long */
    }
    memcpy(c->snap[++c->blocks], c->cum, sizeof c->cum);
    c->block_start_us = c->block_end_us;
    c->in_block = 0;
}

void loadid_drift_check_add(loadid_drift_check_t *c, int64_t t_us, const loadid_real_t A[60],
                            const loadid_real_t y[6]) {
    /* A sample the estimators would refuse does not reach the sums (a NaN
     * or an infinity makes the sum of all its numbers so). */
    double all = 0;
    for (int i = 0; i < 60; ++i) all += (double)A[i];
    for (int i = 0; i < 6; ++i) all += (double)y[i];
    if (!isfinite(all)) return;
    if (c->block_start_us == INT64_MIN) c->block_start_us = t_us;
    /* The sample after a block's time begins the next block. */
    c->block_end_us = c->block_start_us + c->block_us;
    if (t_us >= c->block_end_us && c->in_block > 0) close_block(c);
    const double tau = (double)(t_us - c->t0_us) * 1e-6;
    double *s = c->cum;
    /* Eq. (6) has A's inertia columns 0 in the force rows and its mass
     * column 0 in the torque rows: each half's three rows are summed over
     * the columns that can be nonzero (lo..hi-1), half the products. */
    for (int half = 0; half < 2; ++half) {
        const double w = c->w[half];
        const int lo = half ? 1 : 0, hi = half ? NA : 4;
        const loadid_real_t *x0 = A + 3 * half * NA, *x1 = x0 + NA, *x2 = x1 + NA;
        const double y0 = (double)y[3 * half], y1 = (double)y[3 * half + 1],
                     y2 = (double)y[3 * half + 2];
        for (int i = lo; i < hi; ++i) {
            const double w0 = w * (double)x0[i], w1 = w * (double)x1[i], w2 = w * (double)x2[i];
            double *row = s + packed(i, 0);
            for (int j = lo; j <= i; ++j)
                row[j] += w0 * (double)x0[j] + w1 * (double)x1[j] + w2 * (double)x2[j];
            s[packed(NA + 3 * half, i)] += w0 * tau;
            s[packed(NA + 3 * half + 1, i)] += w1 * tau;
            s[packed(NA + 3 * half + 2, i)] += w2 * tau;
            s[B0 + i] += w0 * y0 + w1 * y1 + w2 * y2;
        }
        for (int r = 3 * half; r < 3 * half + 3; ++r) {
            const double yr = (double)y[r];
            s[packed(NA + r, NA + r)] += w * tau * tau;
            s[B0 + NA + r] += w * tau * yr;
            s[YY] += w * yr * yr;
        }
    }
    c->samples++;
    c->in_block++;
    c->last_us = t_us;
}

void loadid_drift_check_add_instruments(loadid_drift_check_t *c, int64_t t_us,
                                        const loadid_real_t A[60], const loadid_real_t C[60]) {
    /* Every IV_EVERY-th sample: the pull needs (C^T W A)^-1 C^T W tau E6,
     * a ratio of sums of smooth signals, which a quarter of the samples
     * gives to within 3e-3 (test_drift_check), against the 4 % by which
     * the least-squares pull misses RIV's there; at a quarter of the
     * cost, which at every sample was 3 % of the pipeline's time. */
    if (c->iv_seen++ % IV_EVERY != 0) return;
    double all = 0;
    for (int i = 0; i < 60; ++i) all += (double)A[i] + (double)C[i];
    if (!isfinite(all)) return;
    const double tau = (double)(t_us - c->t0_us) * 1e-6;
    /* Force rows have A's inertia columns 0 (eq. 6), torque rows its mass
     * column: three rows at a time over the columns that can be nonzero. */
    for (int half = 0; half < 2; ++half) {
        const double w = c->w[half];
        const int lo = half ? 1 : 0, hi = half ? NA : 4;
        for (int i = lo; i < hi; ++i) {
            double *m = c->iv_m + i * NA;
            for (int r = 3 * half; r < 3 * half + 3; ++r) {
                const double wc = w * (double)C[r * NA + i];
                for (int j = lo; j < hi; ++j) m[j] += wc * (double)A[r * NA + j];
                c->iv_tau[i * 6 + r] += wc * tau;
            }
        }
    }
    c->iv_samples++;
}

int loadid_drift_check_iv_pull(const loadid_drift_check_t *c, const loadid_drift_result_t *r,
                               double pull[10]) {
    if (c->iv_samples == 0) return -1;
    double M[NA * NA], x[NA];
    memcpy(M, c->iv_m, sizeof M);
    for (int i = 0; i < NA; ++i) {
        x[i] = 0;
        for (int k = 0; k < 6; ++k) x[i] += c->iv_tau[i * 6 + k] * r->rate[k];
    }
    /* Gaussian elimination with partial pivoting: C^T W A is not symmetric. */
    double scale = 0;
    for (int i = 0; i < NA * NA; ++i) scale = fmax(scale, fabs(M[i]));
    for (int k = 0; k < NA; ++k) {
        int piv = k;
        for (int i = k + 1; i < NA; ++i)
            if (fabs(M[i * NA + k]) > fabs(M[piv * NA + k])) piv = i;
        if (!(fabs(M[piv * NA + k]) > scale * 1e-14)) return -1;
        if (piv != k) {
            for (int j = 0; j < NA; ++j) {
                const double t = M[k * NA + j];
                M[k * NA + j] = M[piv * NA + j];
                M[piv * NA + j] = t;
            }
            const double t = x[k];
            x[k] = x[piv];
            x[piv] = t;
        }
        for (int i = k + 1; i < NA; ++i) {
            const double f = M[i * NA + k] / M[k * NA + k];
            for (int j = k; j < NA; ++j) M[i * NA + j] -= f * M[k * NA + j];
            x[i] -= f * x[k];
        }
    }
    for (int i = NA - 1; i >= 0; --i) {
        for (int j = i + 1; j < NA; ++j) x[i] -= M[i * NA + j] * x[j];
        x[i] /= M[i * NA + i];
    }
    memcpy(pull, x, sizeof x);
    return 0;
}

/* The full symmetric n x n (n <= N) leading block of packed sums. */
static void unpack(const double *s, int n, double *M) {
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) M[i * n + j] = s[packed(i, j)];
}

void loadid_drift_check_result(const loadid_drift_check_t *c, loadid_drift_result_t *r) {
    memset(r, 0, sizeof *r);
    r->p_value = 1;
    /* The blocks' ends: a last block that ran at least half its time
     * counts as one, a shorter one joins the block before it. */
    const double *ends[LOADID_DRIFT_MAX_BLOCKS + 2];
    int k = 0;
    ends[k++] = c->snap[0];
    for (int i = 1; i <= c->blocks; ++i) ends[k++] = c->snap[i];
    if (c->in_block == 0) {
        /* nothing after the last boundary */
    } else if (2 * (c->last_us - c->block_start_us) >= c->block_us || c->blocks == 0)
        ends[k++] = c->cum;
    else
        ends[k - 1] = c->cum;
    const int K = k - 1;
    r->blocks = K;
    if (K < LOADID_DRIFT_MIN_BLOCKS) return;

    double L[N * N], L10[NA * NA], theta[N], phi10[NA];
    unpack(c->cum, N, L);
    unpack(c->cum, NA, L10);
    for (int i = 0; i < N; ++i) theta[i] = c->cum[B0 + i];
    for (int i = 0; i < NA; ++i) phi10[i] = c->cum[B0 + i];
    if (loadid_chol_factor(L, N) || loadid_chol_factor(L10, NA)) return;
    loadid_chol_solve(L, theta, N);
    loadid_chol_solve(L10, phi10, NA);
    for (int i = 0; i < NA; ++i) r->pull[i] = phi10[i] - theta[i];
    for (int i = 0; i < 6; ++i) r->rate[i] = theta[NA + i];
    /* What fitting the rates costs phi at the fit's residual scale. */
    double fit = 0;
    for (int i = 0; i < N; ++i) fit += c->cum[B0 + i] * theta[i];
    const double s2 = fmax(c->cum[YY] - fit, 0) / fmax(6.0 * (double)c->samples - N, 1);
    for (int i = 0; i < NA; ++i) {
        double e[N] = {0}, e10[NA] = {0};
        e[i] = e10[i] = 1;
        loadid_chol_solve(L, e, N);
        loadid_chol_solve(L10, e10, NA);
        r->extra_var[i] = s2 * fmax(e[i] - e10[i], 0);
    }

    /* V: the delete-a-block jackknife of the rates, (K - 1) / K sum_k
     * (rate_-k - mean)(rate_-k - mean)^T, rate_-k the fit without block k.
     * With as many parameters (16) as blocks (15 in 1.5 s) the blocks'
     * scores at the full fit understate the variance (p < 0.05 on 12.5 %
     * of white-noise windows); the jackknife does not (test_drift_check). */
    double rates[LOADID_DRIFT_MAX_BLOCKS + 1][6], mean[6] = {0};
    double pulls[LOADID_DRIFT_MAX_BLOCKS + 1][NA], pull_mean[NA] = {0};
    for (int b = 0; b < K; ++b) {
        double M[N * N], x[N], M10[NA * NA], x10[NA];
        for (int i = 0; i < N; ++i) {
            x[i] = c->cum[B0 + i] - (ends[b + 1][B0 + i] - ends[b][B0 + i]);
            for (int j = 0; j < N; ++j) {
                const int q = packed(i, j);
                M[i * N + j] = c->cum[q] - (ends[b + 1][q] - ends[b][q]);
            }
        }
        for (int i = 0; i < NA; ++i) {
            x10[i] = x[i];
            for (int j = 0; j < NA; ++j) M10[i * NA + j] = M[i * N + j];
        }
        if (loadid_spd_solve(M, x, N) || loadid_spd_solve(M10, x10, NA)) return;
        for (int i = 0; i < 6; ++i) {
            rates[b][i] = x[NA + i];
            mean[i] += x[NA + i] / K;
        }
        for (int i = 0; i < NA; ++i) {
            pulls[b][i] = x10[i] - x[i];
            pull_mean[i] += pulls[b][i] / K;
        }
    }
    /* The pull's own jackknife variance: the rates are the window's
     * slowest columns and take up the residual's slow part (the misfit,
     * the filter's error), which the white s^2 above counts as fast; on
     * slow motion that left the corrected estimates' errors at 1.2-1.5
     * times phi_std (RMS). The larger of the two counts. */
    for (int i = 0; i < NA; ++i) {
        double v = 0;
        for (int b = 0; b < K; ++b) v += sq(pulls[b][i] - pull_mean[i]);
        r->extra_var[i] = fmax(r->extra_var[i], v * (double)(K - 1) / (double)K);
    }
    double V[36] = {0};
    for (int b = 0; b < K; ++b)
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j)
                V[i * 6 + j] +=
                    (rates[b][i] - mean[i]) * (rates[b][j] - mean[j]) * (double)(K - 1) / (double)K;
    double x[6];
    memcpy(x, r->rate, sizeof x);
    if (loadid_spd_solve(V, x, 6)) return;
    double wald = 0;
    for (int i = 0; i < 6; ++i) wald += r->rate[i] * x[i];
    r->p_value =
        loadid_f_upper_tail((double)(K - 6) / (6.0 * (double)(K - 1)) * wald, 6.0, (double)(K - 6));
    r->tested = 1;
}

/* The continued fraction of the incomplete beta function (modified Lentz),
 * for x < (a + 1) / (a + b + 2), where it converges fast. */
static double beta_fraction(double a, double b, double x) {
    const double tiny = 1e-300;
    double cc = 1, d = 1 - (a + b) * x / (a + 1);
    if (fabs(d) < tiny) d = tiny;
    d = 1 / d;
    double h = d;
    for (int m = 1; m <= 300; ++m) {
        for (int odd = 0; odd < 2; ++odd) {
            const double num = odd ? -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))
                                   : m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m));
            d = 1 + num * d;
            if (fabs(d) < tiny) d = tiny;
            cc = 1 + num / cc;
            if (fabs(cc) < tiny) cc = tiny;
            d = 1 / d;
            h *= d * cc;
            if (odd && fabs(d * cc - 1) < 1e-15) return h;
        }
    }
    return h;
}

/* I_x(a, b), the regularised incomplete beta function. */
static double incomplete_beta(double a, double b, double x) {
    if (!(x > 0)) return 0;
    if (!(x < 1)) return 1;
    const double front = exp(lgamma(a + b) - lgamma(a) - lgamma(b) + a * log(x) + b * log1p(-x));
    if (x < (a + 1) / (a + b + 2)) return front * beta_fraction(a, b, x) / a;
    return 1 - front * beta_fraction(b, a, 1 - x) / b;
}

double loadid_f_upper_tail(double f, double d1, double d2) {
    if (!(f > 0)) return 1;
    if (!isfinite(f)) return 0;
    return incomplete_beta(d2 / 2, d1 / 2, d2 / (d2 + d1 * f));
}
