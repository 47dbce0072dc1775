#include "notch.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#define TWO_PI 6.283185307179586

int loadid_notch_design(double hz, double period_s, double q, loadid_biquad_t *bq) {
    if (!(hz > 0) || !(period_s > 0) || !(hz * period_s < 0.5) || !(q > 0)) return -EINVAL;
    /* H(s) = (s^2 + w0^2) / (s^2 + s w0 / q + w0^2), bilinear with w0
     * prewarped: zeros on the unit circle at +-w0, poles inside it. */
    const double w0 = TWO_PI * hz * period_s, c = cos(w0), alpha = sin(w0) / (2 * q);
    const double a0 = 1 + alpha;
    bq->b[0] = 1 / a0, bq->b[1] = -2 * c / a0, bq->b[2] = 1 / a0;
    bq->a[0] = 1, bq->a[1] = -2 * c / a0, bq->a[2] = (1 - alpha) / a0;
    return 0;
}

double loadid_biquad_gain(const loadid_biquad_t *bq, double hz, double period_s) {
    const double w = TWO_PI * hz * period_s;
    /* B(e^jw) / A(e^jw) with z^-1 = cos w - j sin w */
    double br = 0, bi = 0, ar = 0, ai = 0;
    for (int k = 0; k < 3; ++k) {
        br += bq->b[k] * cos(k * w), bi -= bq->b[k] * sin(k * w);
        ar += bq->a[k] * cos(k * w), ai -= bq->a[k] * sin(k * w);
    }
    return sqrt((br * br + bi * bi) / (ar * ar + ai * ai));
}

/* One stage, transposed direct form II; unprimed, its state is that of a
 * constant input x held forever (output x: the DC gain is 1). */
static double step(const loadid_biquad_t *f, double z[2], int primed, double x) {
    if (!primed) {
        z[1] = (f->b[2] - f->a[2]) * x;
        z[0] = (f->b[1] - f->a[1]) * x + z[1];
    }
    const double y = f->b[0] * x + z[0];
    z[0] = f->b[1] * x - f->a[1] * y + z[1];
    z[1] = f->b[2] * x - f->a[2] * y;
    return y;
}

void loadid_notch_bank_clear(loadid_notch_bank_t *nb) {
    memset(nb, 0, sizeof *nb);
}

int loadid_notch_bank_add(loadid_notch_bank_t *nb, const loadid_biquad_t *bq) {
    if (nb->stages >= LOADID_NOTCH_STAGES) return -ENOSPC;
    nb->bq[nb->stages++] = *bq;
    loadid_notch_bank_restart(nb);
    return 0;
}

double loadid_notch_bank_noise_gain(const loadid_notch_bank_t *nb) {
    if (nb->stages == 0) return 1;
    /* The cascade's impulse response until its states have emptied (the
     * poles lie inside the unit circle, at radius sqrt(a[2])). */
    double z[LOADID_NOTCH_STAGES][2] = {{0}}, sum = 0;
    for (int k = 0; k < 200000; ++k) {
        double v = k == 0 ? 1.0 : 0.0;
        for (int s = 0; s < nb->stages; ++s) v = step(&nb->bq[s], z[s], 1, v);
        sum += v * v;
        double left = 0; /* what the states still hold */
        for (int s = 0; s < nb->stages; ++s) left += z[s][0] * z[s][0] + z[s][1] * z[s][1];
        if (left < 1e-24) break;
    }
    return sum;
}

void loadid_notch_bank_restart(loadid_notch_bank_t *nb) {
    memset(nb->primed, 0, sizeof nb->primed);
}

void loadid_notch_bank_apply(loadid_notch_bank_t *nb, int first, int n, loadid_real_t *x) {
    if (nb->stages == 0) return;
    for (int i = 0; i < n; ++i) {
        const int ch = first + i;
        if (ch < 0 || ch >= LOADID_NOTCH_CHANNELS) continue;
        double v = (double)x[i];
        for (int s = 0; s < nb->stages; ++s) v = step(&nb->bq[s], nb->z[s][ch], nb->primed[ch], v);
        x[i] = (loadid_real_t)v;
        nb->primed[ch] = 1;
    }
}
