/* A notch on the estimators' rows: takes a structural vibration (one tone
 * in the accelerometer's noise, loadid_noise_tone) out of the regressor's
 * accelerometer columns.
 *
 * The same linear time-invariant filter on every column of A and on the
 * wrench keeps A phi = y exact (phi is constant), so it may be causal and
 * still leave no lag between the two sides; its DC gain is 1 (the offset
 * and the zeroing term pass unchanged). A second-order notch (the audio
 * cookbook's, bilinear with prewarping) at f0 with quality q removes the
 * tone and, at the motion's few hertz, changes the rows by well under 1 %.
 * Within its band the rows lose what excitation they had there: little,
 * for a tone well above the trajectory's harmonics (NOTCH_MIN_HZ).
 * Nothing here allocates; the state is fixed-size. */
#ifndef LOADID_PIPELINE_NOTCH_H
#define LOADID_PIPELINE_NOTCH_H

#include "loadid/types.h"

#define LOADID_NOTCH_STAGES 2 /* a - g's tone and alpha's, when they differ */
/* The bank's channels: A (6 x 16), RIV's C (6 x 16), y (6). */
#define LOADID_NOTCH_A 0
#define LOADID_NOTCH_C 96
#define LOADID_NOTCH_Y 192
#define LOADID_NOTCH_CHANNELS 198

typedef struct {
    double b[3], a[3]; /* a[0] = 1 */
} loadid_biquad_t;

/* The notch at hz for samples period_s apart, quality q (f0 over the
 * -3 dB bandwidth). Returns 0, or -EINVAL unless 0 < hz < the Nyquist
 * frequency and q > 0. */
int loadid_notch_design(double hz, double period_s, double q, loadid_biquad_t *bq);

/* The response |H| at hz (samples period_s apart), from the coefficients. */
double loadid_biquad_gain(const loadid_biquad_t *bq, double hz, double period_s);

typedef struct {
    int stages; /* 0: passes everything unchanged */
    loadid_biquad_t bq[LOADID_NOTCH_STAGES];
    int primed[LOADID_NOTCH_CHANNELS];
    double z[LOADID_NOTCH_STAGES][LOADID_NOTCH_CHANNELS][2]; /* transposed direct form II */
} loadid_notch_bank_t;

/* No stages, every channel unprimed. */
void loadid_notch_bank_clear(loadid_notch_bank_t *nb);
/* Adds a stage; returns 0, or -ENOSPC with LOADID_NOTCH_STAGES already. */
int loadid_notch_bank_add(loadid_notch_bank_t *nb, const loadid_biquad_t *bq);
/* The stages' gain on white noise: the sum of their impulse response's
 * squares (1 without stages). */
double loadid_notch_bank_noise_gain(const loadid_notch_bank_t *nb);
/* Unprimes every channel (a new run): each starts again as if its first
 * value had always been there (no transient for a constant). */
void loadid_notch_bank_restart(loadid_notch_bank_t *nb);
/* Filters x[0..n) in place as channels first .. first + n - 1 (in double;
 * channels outside the bank pass unchanged). */
void loadid_notch_bank_apply(loadid_notch_bank_t *nb, int first, int n, loadid_real_t *x);

#endif
