/*
 * Estimators of the inertial parameters behind one small interface:
 * create (the only allocation), update with one sample, estimate, reset.
 *
 *   RLS        eqs. (17)-(19), noise covariance Lambda, optional forgetting
 *   RIV        eqs. (20)-(22), instruments C_k given as a second regressor
 *   RTLS       eqs. (24)-(36): Brand's incremental SVD of the weighted
 *              [A y] (left singular vectors and values only), the volume
 *              test of eq. (31), a Householder transform when the smallest
 *              singular value is not unique, the estimate of eq. (36)
 *   LS_BATCH   weighted least squares over all stored rows (reference)
 *   TLS_BATCH  one SVD over all stored, weighted rows (reference)
 *   REFINED    the core's TLS_BATCH; the pipeline feeds it once, when the
 *              window ends, with zero-lag (smoothed) signals and measured
 *              noise weights
 *
 * Every method works on n_params = 10 (eq. 5, zeroed wrench) or 16
 * ([phi; offset], regressor [A E6]). Matrices are row-major.
 * After create, no function here allocates, locks or makes a system call.
 * An update whose input holds NaN or Inf returns LOADID_E_NONFINITE and
 * leaves the estimator exactly as it was.
 */
#ifndef LOADID_ESTIMATOR_H
#define LOADID_ESTIMATOR_H

#include <stdint.h>

#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The values match estimate_t's constants in proto/ (docs/INTERFACE.md). */
typedef enum {
    LOADID_METHOD_RLS = 1,
    LOADID_METHOD_RIV = 2,
    LOADID_METHOD_RTLS = 3,
    LOADID_METHOD_LS_BATCH = 4,
    LOADID_METHOD_TLS_BATCH = 5,
    LOADID_METHOD_REFINED = 6
} loadid_method_t;

/* Immutable configuration of one estimator. loadid_est_config_default()
 * fills every field; change what you need before create. */
typedef struct {
    loadid_method_t method;
    int n_params; /* 10 or 16 */
    /* Standard deviation of the noise of each wrench row [N, N, N, Nm, Nm,
     * Nm]. RLS/RIV use Lambda = diag(row_sigma^2) (eqs. 17, 20); RTLS and
     * the batch methods use the row weights D = diag(1 / row_sigma) (eq. 24).
     * Default 1 for every row. */
    loadid_real_t row_sigma[LOADID_NROWS];
    /* Column weights T (eq. 24): n_params + 1 entries, the last for the
     * wrench column [-]. The estimate of RTLS and TLS_BATCH depends on
     * them; every method reports its condition number and noise ratio (and
     * gates "not excited") on the weighted data D [A y] T. Default 1. */
    loadid_real_t col_weight[LOADID_MAX_PARAMS + 1];
    /* RLS/RIV: initial covariance Sigma_0 = p0 * I [units of phi^2] and
     * initial estimate 0. Default 1e6. */
    loadid_real_t p0;
    /* RLS/RIV: exponential forgetting factor in (0, 1]; 1 = none (default).
     * Their condition number and noise ratio are then those of the
     * forgetting-weighted data, and the noise-ratio gate counts at most
     * 1 / (1 - forgetting) samples: below about 1 - 6 / (4 (n + 1))
     * (0.86 for n = 10, 0.91 for n = 16) no estimate passes it. The other
     * methods ignore this field. */
    loadid_real_t forgetting;
    /* RTLS: samples stacked for the initial SVD (eq. 24), 2 or 3. Default 2. */
    int rtls_init_samples;
    /* RTLS: relative tolerance under which the volume of eq. (31) counts as
     * zero and two singular values count as equal; a multiple of the
     * machine epsilon of loadid_real_t. Default 64 eps. */
    loadid_real_t rtls_eps;
    /* RTLS: re-orthogonalise U when ||U^T U - I||_F exceeds this; 0 turns
     * re-orthogonalisation off. Default 1e-10 (double), 1e-4 (float); U
     * drifts by about 16 eps per update. */
    loadid_real_t rtls_ortho_tol;
    /* Batch methods: how many samples the row store holds. Default 4000
     * (4 s at 1 kHz); an update beyond it returns LOADID_E_FULL. */
    int batch_capacity;
    /* Excitation: estimate() reports LOADID_E_NOT_EXCITED while the
     * condition number of the weighted data matrix D A T exceeds this [-].
     * Default 1e6 (double) / 1e3 (float). */
    loadid_real_t max_condition;
    /* Excitation: estimate() also reports LOADID_E_NOT_EXCITED while the
     * noise ratio sigma_{n+1} / sigma_n of the weighted D [A y] T exceeds
     * this [-], or exceeds 1 - 2 sqrt((n + 1) / (6 k)) after k samples (the
     * spread of the singular values of pure noise, Marchenko-Pastur): no
     * direction of the parameters stands out of the noise. A still pose
     * with noisy accelerometer signals is well conditioned but not
     * excited. In (0, 1]; 1 turns the check off. Default 0.95. */
    loadid_real_t max_noise_ratio;
    /* How many times each column's weight in col_weight exceeds what its
     * noise alone gives: > 1 for columns counted as (nearly) exact, the
     * mixed LS-TLS limit, which changes RTLS's and TLS_BATCH's estimate.
     * The excitation gates (condition number, noise ratio) take
     * col_weight / col_exact, so that exactness does not make weak data
     * look excited. n_params + 1 entries (the last, the wrench column's,
     * is ignored). Default 1. */
    loadid_real_t col_exact[LOADID_MAX_PARAMS + 1];
    /* Of a column counted exact (col_exact != 1), the share of its noise
     * variance that is a measurement's (the accelerometer's a - g beside
     * the joint filter's alpha in m c's columns with signals mixed), in
     * [0, 1]: least squares' phi_std counts that share's bias exactly, as
     * a noisy column's (loadid_est_uncertainty), the rest to first order.
     * Covariance only. Default 0. */
    loadid_real_t col_measured[LOADID_MAX_PARAMS + 1];
    /* n_params 10: the covariance of the error of the zeroing offset y0
     * subtracted from every wrench (eq. 7), 6 x 6 row-major [N^2, N Nm,
     * Nm^2]: the noise of the zeroing window's mean. One error shared by
     * every row, so no residual shows it; loadid_est_uncertainty adds its
     * share. Default 0 (the offset exact); ignored for 16. */
    loadid_real_t offset_cov[LOADID_NROWS * LOADID_NROWS];
    /* The wrench noise measured apart (the zeroing window): its standard
     * deviation in the force and the torque rows [N, N m] (noise_sigma)
     * and its lag-1 correlation (noise_corr, an AR(1) noise: a sensor's
     * low-pass filter, in [-0.5, 0.95]). Correlated rows average out less
     * than their count says: loadid_est_uncertainty adds that noise's
     * variance times (1 + r) / (1 - r) - 1 to each row group's residual
     * variance (the rest of the residual, the columns' noise and misfit,
     * as it is). Default 0, 0: no correction. A measured noise_sigma
     * also says the column weights are noise levels: least squares then
     * counts the bias noisy columns (col_exact 1) leave in phi. */
    loadid_real_t noise_sigma[2];
    loadid_real_t noise_corr[2];
} loadid_est_config_t;

/* What estimate() reports beside phi. */
typedef struct {
    int64_t samples;                   /* samples used so far */
    loadid_real_t condition_number;    /* kappa of D A_Xi T (columns of A only);
                                      +Inf when rank-deficient */
    loadid_real_t noise_ratio;         /* sigma_{n+1} / sigma_n of D [A y]_Xi T,
                                      in [0, 1]; 1 with no data */
    loadid_real_t sigma_min;           /* RTLS, TLS_BATCH: smallest singular value
                                      of D [A y] T; 0 for the others */
    int sigma_min_multiplicity;        /* RTLS, TLS_BATCH: p of the Householder
                                      step (1 = unique); 0 for the others */
    int reorthogonalisations;          /* RTLS: times U was re-orthogonalised */
    loadid_real_t orthogonality_error; /* RTLS: ||U^T U - I||_F, measured at most
                                          64 updates ago (rtls.hpp) */
} loadid_est_info_t;

typedef struct loadid_est loadid_est_t; /* opaque */

/* Fills cfg with the defaults above for this method and parameter count.
 * Returns 0, or -EINVAL for a NULL cfg, an unknown method or n_params not
 * 10 or 16. */
int loadid_est_config_default(loadid_method_t method, int n_params, loadid_est_config_t *cfg);

/* Sets row_sigma and col_weight from physical noise levels, so that after
 * weighting every entry of D [A y] T carries noise of about the same size
 * (the premise of TLS). sigma_f [N], sigma_tau [Nm]: wrench noise;
 * sigma_spec [m/s^2]: noise of a - g; sigma_alpha [rad/s^2]: noise of the
 * angular acceleration; sigma_omega [rad/s] and omega_typ [rad/s]: noise and
 * typical size of the angular velocity (its products enter eq. 6).
 * Returns 0, -EINVAL (NULL cfg) or -EDOM (a level not finite and > 0;
 * omega_typ may be 0). */
int loadid_est_weights_from_noise(loadid_est_config_t *cfg, loadid_real_t sigma_f,
                                  loadid_real_t sigma_tau, loadid_real_t sigma_spec,
                                  loadid_real_t sigma_alpha, loadid_real_t sigma_omega,
                                  loadid_real_t omega_typ);

/* Allocates and initialises an estimator (the only allocation it ever
 * makes). Returns 0 and sets *out, -EINVAL for a NULL pointer or an invalid
 * configuration (a weight or sigma not finite and > 0, forgetting outside
 * (0, 1], init samples not 2 or 3, capacity < 1, max_noise_ratio outside
 * (0, 1]), or -ENOMEM. */
int loadid_est_create(const loadid_est_config_t *cfg, loadid_est_t **out);

/* Frees it; NULL is allowed. */
void loadid_est_destroy(loadid_est_t *est);

/* Back to the state right after create. Returns 0 or -EINVAL. */
int loadid_est_reset(loadid_est_t *est);

/* New row and column weights (row_sigma, col_weight of the configuration,
 * e.g. from loadid_est_weights_from_noise on a copy), then a reset: the
 * measured noise model sets them when an estimation starts. No allocation.
 * Returns 0, or -EINVAL (NULL, or a value not finite and > 0: nothing
 * changed). */
int loadid_est_set_weights(loadid_est_t *est, const loadid_real_t row_sigma[6],
                           const loadid_real_t *col_weight);

/* New col_exact (see loadid_est_config_t; n_params + 1 entries), then a
 * reset, as loadid_est_set_weights. Returns 0, or -EINVAL (NULL, or a
 * value not finite and > 0: nothing changed). */
int loadid_est_set_exact(loadid_est_t *est, const loadid_real_t *col_exact);

/* New col_measured (see loadid_est_config_t; n_params + 1 entries); no
 * reset. Returns 0, or -EINVAL (NULL, or a value outside [0, 1]: nothing
 * changed). */
int loadid_est_set_measured(loadid_est_t *est, const loadid_real_t *col_measured);

/* New offset_cov (see loadid_est_config_t; 36 values, symmetric, with a
 * non-negative diagonal), kept through resets; no reset. The pipeline sets
 * it when a zeroing ends. Returns 0 or -EINVAL (NULL, or a value not
 * finite, a negative variance or an asymmetric matrix: nothing changed). */
int loadid_est_set_offset_cov(loadid_est_t *est, const loadid_real_t cov[36]);

/* New noise_sigma and noise_corr (see loadid_est_config_t; force,
 * torque), kept through resets; no reset. Returns 0 or -EINVAL (NULL, a
 * sigma not finite and >= 0, or an r outside [-0.5, 0.95]: nothing
 * changed). */
int loadid_est_set_noise_corr(loadid_est_t *est, const loadid_real_t sigma[2],
                              const loadid_real_t r[2]);

/* Multiplies the noise level of the force rows (row_sigma[0..2]) by force,
 * of the torque rows by torque, and the regressor columns' weights
 * (col_weight[0..n-1]) by columns, for the samples already taken as well,
 * as if configured so from the first: the pipeline's answer to a residual
 * the measured noise does not explain (loadid_est_residual_scales). RTLS
 * restarts its SVD from the re-weighted information matrix (one symmetric
 * eigen-solve, squaring the condition number once); LS_BATCH and TLS_BATCH
 * are exact. No allocation. Returns 0, -EINVAL (NULL, a factor not finite
 * and > 0), -ENOTSUP (RLS, RIV: their recursion cannot weigh its past
 * again) or LOADID_E_NOT_EXCITED (RTLS before its SVD has full rank);
 * nothing changes unless 0. */
int loadid_est_rescale(loadid_est_t *est, loadid_real_t force, loadid_real_t torque,
                       loadid_real_t columns);

/* The weighted residual of phi, RMS per row, force rows (scales[0]) and
 * torque rows (scales[1]) apart, in the direction of the weighted column
 * space phi stands for (T^-1 [phi; -1], normalised); phi NULL: of the
 * weighted least-squares fit of the same data. At a consistent estimate
 * (the truth, or LS when the columns are nearly exact) each figure is
 * about 1 when the noise levels behind the weights explain that group's
 * rows and columns, and s when they carry s times more error than the
 * levels say. (At a TLS estimate from wrong weights it is not: TLS moves
 * the error where the weights let it.) Returns 0, -EINVAL,
 * LOADID_E_NONFINITE or LOADID_E_NOT_EXCITED (no samples, or no LS fit).
 * No allocation. */
int loadid_est_residual_scales(const loadid_est_t *est, const loadid_real_t *phi,
                               loadid_real_t scales[2]);

/* Adds one sample. A: 6 x n_params data matrix (eq. 6, 9 or [A E6]);
 * y: the measured wrench [f; tau] (zeroed for n_params = 10 when the
 * zeroing term is in A). C: RIV instruments, same shape as A (required for
 * RIV, ignored by the others, may be NULL).
 * Returns 0; -EINVAL (NULL pointer); LOADID_E_NONFINITE (nothing changed);
 * LOADID_E_FULL (batch store full, nothing changed). */
int loadid_est_update(loadid_est_t *est, const loadid_real_t *A, const loadid_real_t *C,
                      const loadid_real_t y[6]);

/* The current estimate: phi (n_params values; eq. 5 then, for 16, the
 * offset) and info (may be NULL).
 * Returns 0; -EINVAL; LOADID_E_NOT_EXCITED when too few samples, the
 * weighted data matrix is rank-deficient or worse conditioned than
 * max_condition, or its noise ratio exceeds max_noise_ratio (phi is then
 * all zeros, info is filled);
 * LOADID_E_NO_SOLUTION (TLS only: eq. 36 has no solution; phi zeros).
 * phi never holds NaN or Inf. */
int loadid_est_estimate(const loadid_est_t *est, loadid_real_t *phi, loadid_est_info_t *info);

/* The estimate as loadid_est_estimate gives it, but with the noise-ratio
 * test only where the solution needs it: RTLS and TLS_BATCH with a
 * regressor column counted noisy (col_exact[j] <= 1 for a j < 10), whose
 * TLS solution is not unique when sigma_{n+1} ~ sigma_n. Least squares
 * (RLS, RIV, LS_BATCH) and TLS with every regressor column counted exact
 * are unique once the condition number passes: a direction that does not
 * stand out of the noise (the inertia, or the offset, on slow motion) is
 * then only uncertain, and loadid_est_uncertainty says how much. For a
 * caller that judges the groups from phi_std (the final estimate, with
 * loadid_load_model). Same returns as loadid_est_estimate. */
int loadid_est_estimate_unique(const loadid_est_t *est, loadid_real_t *phi,
                               loadid_est_info_t *info);

/* One standard deviation of each element of phi, this estimator's own
 * estimate (as loadid_est_estimate gave it), from its covariance on the
 * weighted data: RLS and LS_BATCH s^2 (A^T W A)^-1 (Sigma of eq. 17); RIV
 * M^-1 (s_f^2 C_f^T W C_f + s_t^2 C_t^T W C_t) M^-T (eqs. 20-22, the force
 * and torque rows apart); RTLS, TLS_BATCH and REFINED the
 * first-order covariance of the TLS solution, each row group's residual
 * variance widened for a correlated wrench noise (noise_sigma,
 * noise_corr), plus what the zeroing offset's error (offset_cov) adds. W = D^2 (row weights); the
 * scale s is measured a posteriori from the weighted residual (1 when the
 * configured noise levels match the data) and returned in *scale (may be
 * NULL). std: n_params values.
 * Returns 0; -EINVAL; LOADID_E_NONFINITE (phi not finite);
 * LOADID_E_NOT_EXCITED (too few samples, or the data leave a direction of
 * phi undetermined: std is then +Inf). No allocation, no system call. */
int loadid_est_uncertainty(const loadid_est_t *est, const loadid_real_t *phi, loadid_real_t *std,
                           loadid_real_t *scale);

/* The weighted data split by frequency, for loadid_est_uncertainty_spectral:
 * a misfit of the motion model (backlash, the joint filter's error) fills
 * the residual at tens of Hz, where the regressor has no power, so the
 * residual's total variance overstates what reaches phi (the backlash
 * cells of the study: 99-100 % coverage at RMS error / std 0.3-0.6).
 * X_j = sum_k D [A_k y_k] exp(-2 pi i j (t_k - t_0) / T), the DFT of the
 * row-weighted data (columns unweighted, W = D^2) over the window's span T
 * at bin j. Band b holds the bins first_bin[b]..first_bin[b + 1] - 1;
 * band 0 is bin 0 alone (the mean, which holds the zeroing offset's error,
 * offset_cov's part: its residual is not measured, band 1's level is used).
 * gram[b][g] = sum over the band's bins of c_j Re(X_j^H X_j) / K over the
 * force (g = 0) or torque (g = 1) rows, (n+1) x (n+1) column-major, c_0 =
 * 1, c_j = 2; K samples. The bins above the last band are the rest: the
 * estimator's own information less the bands. */
#define LOADID_SPECTRUM_BANDS 9
#define LOADID_SPECTRUM_BINS 17 /* most bins in the bands */
typedef struct {
    int n_bands;                              /* 2..LOADID_SPECTRUM_BANDS */
    int first_bin[LOADID_SPECTRUM_BANDS + 1]; /* first_bin[0] = 0, first_bin[1] = 1 */
    int64_t samples;                          /* K: must be the estimator's */
    double gram[LOADID_SPECTRUM_BANDS][2][(LOADID_MAX_PARAMS + 1) * (LOADID_MAX_PARAMS + 1)];
    /* RIV: the same of D C (n x n), and C^T W C over every bin (iv_total). */
    int has_iv;
    double iv_gram[LOADID_SPECTRUM_BANDS][2][LOADID_MAX_PARAMS * LOADID_MAX_PARAMS];
    double iv_total[2][LOADID_MAX_PARAMS * LOADID_MAX_PARAMS];
    /* The rows apart (has_rows), for the residual's covariance between a
     * sample's rows: the regressor's noise reaches them together (a - g's
     * in m (a - g) and in (m c) x (a - g), alpha's in alpha x (m c) and in
     * I alpha), which one level per row group leaves out (RIV with the
     * sensor's accelerometer: 20-30 % narrow on m c and I). row_dft[j][0]
     * and [1] are the real and imaginary parts of sqrt(c_j / K) D_r X_j,
     * row r's n + 1 values at bin j < first_bin[n_bands] (row r at
     * r (n + 1)); iv_dft the same of D C (n values a row). */
    int has_rows;
    double row_dft[LOADID_SPECTRUM_BINS][2][LOADID_NROWS * (LOADID_MAX_PARAMS + 1)];
    double iv_dft[LOADID_SPECTRUM_BINS][2][LOADID_NROWS * LOADID_MAX_PARAMS];
} loadid_spectrum_t;

/* loadid_est_uncertainty with the residual's level taken per band of
 * frequency (sp, of the same samples and row weights as the estimator's):
 * the sandwich H^-1 (sum_b sum_g S_gb G_gb) H^-1 (IV: the instruments'
 * G), S_gb the residual's power in band b of row group g over its degrees
 * of freedom less the fit's leverage there, tr(H^-1 G_gb); a band with
 * fewer than 12 left joins the next. A flat residual gives the white
 * sandwich. With the rows apart (has_rows) and columns with a
 * measurement's noise (col_exact 1) a band's meat is
 * sum_j Re(X_j^H S_b X_j) over its bins (IV: the instruments' X), S_b the
 * residual's covariance between rows over the bins 1.. (its shape) scaled
 * to the band's two levels: a residual correlated between rows, or of
 * unequal rows, is counted. With the rows apart RIV's leverage in a
 * band is its own oblique fit's.
 * S_gb is at least the wrench noise measured apart
 * (noise_sigma), which replaces the correlated-noise widening. The zeroing
 * offset's share is added as by loadid_est_uncertainty. Returns as
 * loadid_est_uncertainty, and -EINVAL for a spectrum that does not fit
 * (samples, bins, RIV without instruments' bands). No allocation. */
int loadid_est_uncertainty_spectral(const loadid_est_t *est, const loadid_real_t *phi,
                                    const loadid_spectrum_t *sp, loadid_real_t *std,
                                    loadid_real_t *scale);

/* With the offset estimated (16 parameters), the estimate had the offset's
 * linear drift over the window been fitted too: phi_fitted = phi - d, d
 * the drift's pull (this method's own: RIV's instrumental, least squares'
 * for the others; the witness loadid_est_uncertainty adds as d d^T), and
 * std that estimate's standard deviations, the covariance of the model
 * with six more (exact) columns t E6 at its own residual; the offset
 * (phi_fitted[10..15]) is the fitted line's at the window's mean time. For
 * a final estimate: the drift is taken out rather than only widening the
 * band.
 * phi, phi_fitted, std: 16 values; scale as loadid_est_uncertainty's.
 * Returns 0; -EINVAL; -ENOTSUP (10 parameters, or REFINED, which fits the
 * drift itself); LOADID_E_NONFINITE; LOADID_E_NOT_EXCITED (a fit is
 * singular; std +Inf). No allocation, no system call. */
int loadid_est_drift_fitted(const loadid_est_t *est, const loadid_real_t *phi,
                            loadid_real_t *phi_fitted, loadid_real_t *std, loadid_real_t *scale);

/* How far each group of phi stands out of the noise in this estimator's
 * data: snr[0] (mass), snr[1] (m c), snr[2] (inertia) are the RMS over the
 * rows of the wrench that group of phi explains, sqrt(phi_g^T (A_g^T W A_g)
 * phi_g / rows) with W = D^2, in units of the rows' noise (rows: 6 per
 * sample; 3, the torque rows, for the inertia). A slow, mostly
 * translational motion leaves snr[2] near or below 1: whatever the
 * statistics say, a drift or a model error of the noise's size then sets
 * the inertia. phi: n_params values. Returns 0, -EINVAL,
 * LOADID_E_NONFINITE or LOADID_E_NOT_EXCITED (no samples). */
int loadid_est_signal_to_noise(const loadid_est_t *est, const loadid_real_t *phi,
                               loadid_real_t snr[3]);

/* The direction of phi the data determine worst: the eigenvector of the
 * smallest eigenvalue of the column-weighted information matrix
 * (D A T)^T (D A T), mapped back to phi's units and normalised by the
 * largest component; with the eigenvalue ratio it says which parameters a
 * "not excited" refusal lacks. dir: n_params values; *ratio (may be NULL):
 * sqrt(lambda_min / lambda_max). Returns 0, -EINVAL or
 * LOADID_E_NOT_EXCITED (no samples). */
int loadid_est_weakest_direction(const loadid_est_t *est, loadid_real_t *dir, loadid_real_t *ratio);

/* The configuration the estimator was created with. */
const loadid_est_config_t *loadid_est_config(const loadid_est_t *est);

/* Short name of a method ("RTLS"...) or "?"; parse back with
 * loadid_method_from_name (returns the method or -EINVAL). */
const char *loadid_method_name(loadid_method_t method);
int loadid_method_from_name(const char *name);

/* The kernel RTLS's SVD update runs on: "avx2+fma" (x86-64 CPUs that have
 * them, double build) or "portable"; chosen once at start-up. The
 * environment variable LOADID_JACOBI_KERNEL=portable forces the latter
 * (for tests and comparisons); the two agree to rounding. */
const char *loadid_jacobi_kernel(void);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_ESTIMATOR_H */
