// One standard deviation of every element of an estimate, from the
// information matrix the excitation gate keeps (excitation.hpp), so every
// method gets its own covariance at no per-sample cost:
//   LS   (RLS, LS_BATCH)  s^2 (A^T W A)^-1, RLS's own Sigma of eq. (17);
//   IV   (RIV)            s^2 M^-1 (C^T W C) M^-T, M = C^T W A (eqs. 20-22);
//   TLS  (RTLS, TLS_BATCH, REFINED) the first-order covariance of the TLS
//        solution in the weighted coordinates (Van Huffel & Vandewalle 1991,
//        sec. 8.2): s^2 (1 + |x|^2) (A~^T A~ - sigma_{n+1}^2 I)^-1, mapped
//        back through the column weights T.
// W = D^2 are the row weights, so with noise levels that match the data the
// scale s is 1 (for TLS the orthogonal residual per weighted entry, for the
// others the vertical one). s is measured a posteriori (the weighted residual of the
// method's own estimate over the degrees of freedom), so a noise model off
// by a factor, or a vibration it does not know, widens the band instead of
// leaving it wrong. It is measured for the force rows and the torque rows
// apart, and LS and TLS take the sandwich H^-1 (s_f^2 G_f + s_t^2 G_t) H^-1
// (G_f, G_t the two row groups' A^T W A, H the whole, for TLS less the
// noise's share): the errors of a - g, omega and alpha reach the two groups
// differently, and one pooled s gave 83 % coverage on Izz and 98 % on m.
// IV takes M^-1 (s_f^2 C_f^T W C_f + s_t^2 C_t^T W C_t) M^-T likewise
// (RIV keeps C^T W C over the torque rows beside the whole): with the
// sensor's accelerometer as a - g and alpha the pooled s had RMS error /
// std 0.44 on m and up to 1.57 on the rest (test_spectrum_rows), the
// groups' 0.73-1.21.
// A correlated (low-pass filtered) wrench noise averages out less than
// white: for regressors that vary slowly against the noise's correlation
// time its share of the score's variance is its variance times the
// long-run factor (1 + r) / (1 - r) of an AR(1) noise of lag-1 correlation
// r; so each row group's residual variance gains that noise's variance
// (in the weighted units) times (1 + r) / (1 - r) - 1.
// The zeroing offset's error adds J Sigma_y0 J^T, J = H^-1 sum_k A_k^T W
// (M^-1 for IV, with A's sum standing in for the instruments'): first order
// in the offset error, it moved the RX60's m and m c by 1.1 to 1.6 sigma.
// Columns taken as exact (col_exact != 1: a joint filter's, whose error
// is a conditional mean's, uncorrelated with the estimate, while the
// filter's motion model fits the motion) would, were their error that of
// a plain measurement, pull LS and TLS towards zero by b = H^-1 C phi,
// C = sum_k E[dA_k^T W dA_k] (diagonal: each column's noise as its own
// weight has it, 6 / t_j^2 a sample); b b^T is added, a bias that may be
// there. It is nothing on an excitation trajectory (4e-4 of the weakest
// direction's information on the RX60) and all on slow motion, where a
// filter tuned for fast motion puts as much noise into a - g as the
// motion varies it, and its error is the measurement's: a UR5 at |omega|
// <= 0.2 rad/s lost 26 % of the mass at 3.4 % phi_std. IV's instruments
// do not see the columns' noise. Least squares on columns with a
// measurement's noise (the accelerometer: signals sensor or mixed) is
// biased the same way, by (h - C)^-1 C phi_LS exactly in expectation; when
// the wrench noise was measured (noise_sigma, so the column weights are
// noise levels) that b b^T is added too: RLS with the mixed source lost
// 24 % of the mass at paper noise and claimed it in 26 of 90 recordings.
// A column counted exact whose noise is in part a measurement's (mixed: m
// c's, the filter's alpha beside the accelerometer's a - g) has that share
// (col_measured) counted so, the rest to first order: RLS's m c, 47-76 %
// attenuated at high noise, had RMS error / std up to 4.1, now 1.62.
// TLS takes the columns' share K = lmin T^-2 off; its estimate moves by
// d = (h - K)^-1 K phi per relative error of that share, taken as
// |1 - s^2| (s TLS's own misfit): delta^2 d d^T is added. With the
// accelerometer's columns and a vibration coherent across its axes, which
// the diagonal weights do not describe, RTLS claimed a mass 8-10 % off in
// 29 of 54 claims, now 3 of 15. One scale for what is a channel's error
// is a first-order remedy: the accelerometer weighted as 1.6 times its
// noise (test_uncertainty) left Izz covered in 15 % of the draws, now 79 %.
// A misfit of the motion model puts the residual's power at tens of Hz
// (backlash: 30-100 times the noise at 5-100 Hz on the simulated RX60),
// while the regressor's lies below a few Hz, and what reaches phi is the
// residual's level where the regressor has power: sum_f |A(f)|^2 S(f), not
// S's mean times A^T W A. Given the data's DFT in bands (spectrum), the
// meat is sum over bands and row groups of S_gb G_gb, S_gb measured per
// band (the fit's leverage there taken off its degrees of freedom); the
// backlash cells' 99-100 % coverage at RMS error / std 0.3-0.6 came from
// the white meat. A sample's six rows share the regressor's noise (a - g's
// in m (a - g) and (m c) x (a - g), alpha's in alpha x (m c) and I alpha),
// so with the rows apart (the DFT per row) and columns with a measurement's
// noise (col_exact 1) a band's meat is sum_j Re(X_j^H S_b X_j), S_b the
// residual's covariance between rows over bins 1.. (its shape) at the
// band's two levels. Not with exact columns (the joint filter's): there
// the residual is the wrench's own noise and the misfit, and the shape
// the fit leaves of them at low frequencies made the 7-joint chain's Ixz
// 80 % covered, not 96 %. IV's oblique fit takes 2 tr(M^-1 C_b^T W A_b) - tr(G_b M^-1
// C^T W C M^-T) off a band's degrees of freedom, not least squares'
// tr(H^-1 G_b), whose H the noisy columns inflate. RIV with the sensor's
// accelerometer under a 2 kg load 11 cm off (test_spectrum_rows): RMS
// error / std 0.85-1.45 per parameter with one level per row group, now
// 0.96-1.13.
// With the offset estimated, a constant offset is all the on-line methods
// fit, but an F/T sensor's offset drifts (warming up), and on slow motion
// a drift of 0.05 N/s and 0.002 N m/s moved RIV's COM by 26 mm at 5 mm
// phi_std. The witness d = phi_16 - phi_22, the least-squares estimates
// without and with a linear drift of the offset (6 columns t E6, from
// sums the excitation keeps), is that drift's pull plus noise of
// variance Var_22 - Var_16 (the cost of fitting it); d d^T is added. IV
// takes its own: the IV estimates without and with the drift columns,
// which are their own instruments (the least-squares d left RIV's COM
// 32 mm off at 8 mm phi_std on a slow 7-joint recording).
// A final estimate takes the drift out instead (phi_fitted below): phi - d
// is the estimate of the model with the drift's columns, and its
// covariance that model's, without d d^T; without a drift it costs
// what fitting the six columns costs.
#pragma once

#include <cstdint>

#include "eigen_types.hpp"
#include "loadid/estimator.h"

namespace loadid {

enum class CovKind { LS, IV, TLS };

struct CovInput {
    CovKind kind;
    int n;                   // parameters (10 or 16)
    const Real *gram;        // (n+1) x (n+1) column-major, lower triangle: sum of
                             // (D [A y] T)^T (D [A y] T)
    const Real *gram_torque; // the same over the torque rows only
    const Real *t;           // the n + 1 column weights T
    int64_t samples;         // k: 6 k rows
    const Real *phi;         // the method's estimate (n values)
    const Real *iv_m;        // IV: n x n column-major C^T W A, else nullptr
    const Real *iv_cc;       // IV: n x n column-major C^T W C, else nullptr
    // The zeroing offset y0 of eq. (7) is a mean over the zeroing window:
    // its error is one wrench error shared by every row, which no residual
    // shows and more samples do not average out. Its covariance
    // (offset_cov, 6 x 6 row-major, N^2 / Nm^2; nullptr or zeros when the
    // offset is estimated or exact) reaches phi through sum_k A_k^T W,
    // from row_sum = sum_k D A_k T1 (6 x n column-major) and the row
    // weights D (row_weight, 6 values).
    const Real *row_sum = nullptr;
    const Real *row_weight = nullptr;
    const Real *offset_cov = nullptr;
    // The wrench noise measured apart, force and torque rows (2 values
    // each; nullptr: none): its standard deviation and lag-1 correlation.
    const Real *noise_sigma = nullptr;
    const Real *noise_corr = nullptr;
    // The estimator's col_exact (n + 1 values; nullptr: all 1): T / E, the
    // column weights over those of the columns' own noise.
    const Real *col_exact = nullptr;
    // With the offset estimated (n = 16; nullptr: no drift witness):
    // sum_k t_k D A_k T1 (6 x n, column-major), sum_k t_k D y_k (6) and
    // sum_k t_k^2, t_k the sample's time (excitation.hpp).
    const double *drift_cross = nullptr;
    const double *drift_y = nullptr;
    double drift_tt = 0;
    // IV, with the offset estimated: sum_k t_k C_k^T W (n x 6,
    // column-major) and sum_k C_k^T W y_k (n); nullptr: the least-squares d.
    const double *iv_drift = nullptr;
    const Real *iv_b = nullptr;
    // IV: iv_cc over the torque rows only (nullptr: one level for all rows
    // in the white meat).
    const Real *iv_cc_torque = nullptr;
    // Of an exact column's noise variance, the share that is a
    // measurement's (n + 1 values; nullptr: none).
    const Real *col_measured = nullptr;
    // Non-null (with the drift sums): the drift fitted rather than
    // witnessed. phi_fitted (n values) gets phi less d, and std is that
    // estimate's: the covariance of the model with the six drift columns
    // (exact, for TLS eliminated before the noise's share comes off), at
    // its own residual.
    Real *phi_fitted = nullptr;
    // Non-null: the residual's level per band of frequency (estimator.h,
    // loadid_spectrum_t) in the sandwich's meat instead of one level per
    // row group; used for the estimate's own problem (not the drift's).
    const loadid_spectrum_t *spectrum = nullptr;
};

// Fills std (n values) and *scale (s). Returns 0, or LOADID_E_NOT_EXCITED
// when the information matrix is singular (std then +Inf).
int covariance_std(const CovInput &in, Real *std, Real *scale);

// loadid_est_signal_to_noise from the same information matrix (in.gram,
// in.t, in.samples, in.phi; the rest unused).
int group_snr(const CovInput &in, Real snr[3]);

// loadid_est_weakest_direction (in.gram, in.t, in.samples).
int weakest_direction(const CovInput &in, Real *dir, Real *ratio);

} // namespace loadid
