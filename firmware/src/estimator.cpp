// C API of the estimators (loadid/estimator.h): configuration, dispatch on
// method and parameter count, and the checks at the boundary.
#include "loadid/estimator.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <new>

#include "estimator_factory.hpp"
#include "excitation.hpp"
#include "finite.hpp"

using namespace loadid;

namespace {

bool positive_finite(loadid_real_t v) {
    return std::isfinite(v) && v > 0;
}

bool valid_method(int m) {
    return m >= LOADID_METHOD_RLS && m <= LOADID_METHOD_REFINED;
}

bool valid_config(const loadid_est_config_t &c) {
    if (!valid_method(c.method)) return false;
    if (c.n_params != LOADID_NPHI && c.n_params != LOADID_NPHI_OFFSET) return false;
    for (int i = 0; i < LOADID_NROWS; ++i)
        if (!positive_finite(c.row_sigma[i])) return false;
    for (int j = 0; j <= c.n_params; ++j)
        if (!positive_finite(c.col_weight[j]) || !positive_finite(c.col_exact[j]) ||
            !(c.col_measured[j] >= 0 && c.col_measured[j] <= 1))
            return false;
    if (!positive_finite(c.p0)) return false;
    if (!(c.forgetting > 0 && c.forgetting <= 1)) return false;
    if (c.rtls_init_samples < 2 || c.rtls_init_samples > 3) return false;
    if (!positive_finite(c.rtls_eps) || !std::isfinite(c.rtls_ortho_tol) || c.rtls_ortho_tol < 0)
        return false;
    if (c.batch_capacity < 1) return false;
    if (!(c.max_noise_ratio > 0 && c.max_noise_ratio <= 1)) return false;
    return positive_finite(c.max_condition);
}

template <int N>
loadid_est *make(const loadid_est_config_t &c) {
    switch (c.method) {
        case LOADID_METHOD_RLS:
        case LOADID_METHOD_RIV:
            return make_recursive_ls<N>(c);
        case LOADID_METHOD_RTLS:
            return make_rtls<N>(c);
        case LOADID_METHOD_LS_BATCH:
        case LOADID_METHOD_TLS_BATCH:
        case LOADID_METHOD_REFINED:
            return make_batch<N>(c);
    }
    return nullptr;
}

const char *const kNames[] = {"?", "RLS", "RIV", "RTLS", "LS_BATCH", "TLS_BATCH", "REFINED"};

} // namespace

extern "C" int loadid_est_config_default(loadid_method_t method, int n_params,
                                         loadid_est_config_t *cfg) {
    if (!cfg || !valid_method(method)) return -EINVAL;
    if (n_params != LOADID_NPHI && n_params != LOADID_NPHI_OFFSET) return -EINVAL;
    std::memset(cfg, 0, sizeof *cfg);
    cfg->method = method;
    cfg->n_params = n_params;
    for (auto &s : cfg->row_sigma) s = 1;
    for (int j = 0; j <= n_params; ++j) cfg->col_weight[j] = 1;
    for (int j = 0; j <= LOADID_MAX_PARAMS; ++j) cfg->col_exact[j] = 1;
    cfg->p0 = Real(1e6);
    cfg->forgetting = 1;
    cfg->rtls_init_samples = 2;
    cfg->rtls_eps = 64 * kEps;
    cfg->rtls_ortho_tol = sizeof(Real) == sizeof(float) ? Real(1e-4) : Real(1e-10);
    cfg->batch_capacity = 4000;
    cfg->max_condition = sizeof(Real) == sizeof(float) ? Real(1e3) : Real(1e6);
    cfg->max_noise_ratio = Real(0.95);
    return 0;
}

extern "C" int loadid_est_weights_from_noise(loadid_est_config_t *cfg, loadid_real_t sigma_f,
                                             loadid_real_t sigma_tau, loadid_real_t sigma_spec,
                                             loadid_real_t sigma_alpha, loadid_real_t sigma_omega,
                                             loadid_real_t omega_typ) {
    if (!cfg) return -EINVAL;
    if (!positive_finite(sigma_f) || !positive_finite(sigma_tau) || !positive_finite(sigma_spec) ||
        !positive_finite(sigma_alpha) || !positive_finite(sigma_omega) ||
        !std::isfinite(omega_typ) || omega_typ < 0)
        return -EDOM;
    // Rows: D = diag(1/sigma_y), so the wrench column carries unit noise
    // with t_{n+1} = 1.
    for (int i = 0; i < 3; ++i) {
        cfg->row_sigma[i] = sigma_f;
        cfg->row_sigma[i + 3] = sigma_tau;
    }
    // Columns: TLS removes the bias of LS by assuming E[E^T E] of the
    // weighted error is a multiple of I. Eq. (6) has structural zeros, so
    // columns differ in how many of their entries are noisy: t_j is set so
    // that the summed noise variance of every column equals that of the
    // wrench column (6 rows of unit variance after D). Per row, an entry
    // made of alpha adds sigma_alpha^2, one of a - g sigma_spec^2, and each
    // w_i w_j product about q = 2 |w|^2 sigma_w^2 (first order).
    const Real b2 = sigma_alpha * sigma_alpha, s2 = sigma_spec * sigma_spec;
    const Real q = Real(2) * omega_typ * omega_typ * sigma_omega * sigma_omega;
    const Real if2 = Real(1) / (sigma_f * sigma_f), it2 = Real(1) / (sigma_tau * sigma_tau);
    const Real col_var[LOADID_NPHI] = {
        Real(3) * s2 * if2,                                      // m: a - g in 3 force rows
        (Real(2) * b2 + Real(3) * q) * if2 + Real(2) * s2 * it2, // m c_x: 2 alpha, 3 w w; 2 a - g
        (Real(2) * b2 + Real(3) * q) * if2 + Real(2) * s2 * it2, // m c_y
        (Real(2) * b2 + Real(3) * q) * if2 + Real(2) * s2 * it2, // m c_z
        (b2 + Real(2) * q) * it2,                                // Ixx: alpha_x, 2 w w
        (Real(2) * b2 + Real(3) * q) * it2,                      // Ixy
        (Real(2) * b2 + Real(3) * q) * it2,                      // Ixz
        (b2 + Real(2) * q) * it2,                                // Iyy
        (Real(2) * b2 + Real(3) * q) * it2,                      // Iyz
        (b2 + Real(2) * q) * it2,                                // Izz
    };
    for (int j = 0; j < LOADID_NPHI; ++j)
        cfg->col_weight[j] = std::sqrt(Real(LOADID_NROWS) / col_var[j]);
    if (cfg->n_params == LOADID_NPHI_OFFSET) {
        // The offset columns [E6] are exact: a large weight makes TLS treat
        // them as (nearly) error-free, the mixed LS-TLS limit.
        for (int j = LOADID_NPHI; j < LOADID_NPHI_OFFSET; ++j) cfg->col_weight[j] = Real(1e3);
    }
    cfg->col_weight[cfg->n_params] = 1;
    return 0;
}

extern "C" int loadid_est_create(const loadid_est_config_t *cfg, loadid_est_t **out) {
    if (!cfg || !out) return -EINVAL;
    *out = nullptr;
    if (!valid_config(*cfg)) return -EINVAL;
    loadid_est *e =
        cfg->n_params == LOADID_NPHI ? make<LOADID_NPHI>(*cfg) : make<LOADID_NPHI_OFFSET>(*cfg);
    if (!e) return -ENOMEM;
    *out = e;
    return 0;
}

extern "C" void loadid_est_destroy(loadid_est_t *est) {
    delete est;
}

extern "C" int loadid_est_reset(loadid_est_t *est) {
    if (!est) return -EINVAL;
    est->reset();
    return 0;
}

extern "C" int loadid_est_set_weights(loadid_est_t *est, const loadid_real_t row_sigma[6],
                                      const loadid_real_t *col_weight) {
    if (!est || !row_sigma || !col_weight) return -EINVAL;
    for (int i = 0; i < LOADID_NROWS; ++i)
        if (!positive_finite(row_sigma[i])) return -EINVAL;
    for (int j = 0; j <= est->cfg.n_params; ++j)
        if (!positive_finite(col_weight[j])) return -EINVAL;
    for (int i = 0; i < LOADID_NROWS; ++i) est->cfg.row_sigma[i] = row_sigma[i];
    for (int j = 0; j <= est->cfg.n_params; ++j) est->cfg.col_weight[j] = col_weight[j];
    est->reweight();
    return 0;
}

extern "C" int loadid_est_set_exact(loadid_est_t *est, const loadid_real_t *col_exact) {
    if (!est || !col_exact) return -EINVAL;
    for (int j = 0; j <= est->cfg.n_params; ++j)
        if (!positive_finite(col_exact[j])) return -EINVAL;
    for (int j = 0; j <= est->cfg.n_params; ++j) est->cfg.col_exact[j] = col_exact[j];
    est->reweight();
    return 0;
}

extern "C" int loadid_est_set_measured(loadid_est_t *est, const loadid_real_t *col_measured) {
    if (!est || !col_measured) return -EINVAL;
    for (int j = 0; j <= est->cfg.n_params; ++j)
        if (!(col_measured[j] >= 0 && col_measured[j] <= 1)) return -EINVAL;
    for (int j = 0; j <= est->cfg.n_params; ++j) est->cfg.col_measured[j] = col_measured[j];
    return 0;
}

extern "C" int loadid_est_set_offset_cov(loadid_est_t *est, const loadid_real_t cov[36]) {
    if (!est || !cov) return -EINVAL;
    for (int i = 0; i < LOADID_NROWS; ++i) {
        if (!std::isfinite(cov[7 * i]) || cov[7 * i] < 0) return -EINVAL;
        for (int j = 0; j < LOADID_NROWS; ++j)
            if (!std::isfinite(cov[6 * i + j]) || cov[6 * i + j] != cov[6 * j + i]) return -EINVAL;
    }
    std::memcpy(est->cfg.offset_cov, cov, sizeof est->cfg.offset_cov);
    return 0;
}

extern "C" int loadid_est_set_noise_corr(loadid_est_t *est, const loadid_real_t sigma[2],
                                         const loadid_real_t r[2]) {
    if (!est || !sigma || !r) return -EINVAL;
    for (int g = 0; g < 2; ++g)
        if (!(std::isfinite(sigma[g]) && sigma[g] >= 0) ||
            !(r[g] >= Real(-0.5) && r[g] <= Real(0.95)))
            return -EINVAL;
    for (int g = 0; g < 2; ++g) est->cfg.noise_sigma[g] = sigma[g], est->cfg.noise_corr[g] = r[g];
    return 0;
}

extern "C" int loadid_est_rescale(loadid_est_t *est, loadid_real_t force, loadid_real_t torque,
                                  loadid_real_t columns) {
    if (!est || !positive_finite(force) || !positive_finite(torque) || !positive_finite(columns))
        return -EINVAL;
    const loadid_est_config_t old = est->cfg;
    for (int i = 0; i < LOADID_NROWS; ++i) est->cfg.row_sigma[i] *= i < 3 ? force : torque;
    for (int j = 0; j < est->cfg.n_params; ++j) est->cfg.col_weight[j] *= columns;
    const int rc = est->rescale(force, torque, columns);
    if (rc != 0) est->cfg = old;
    return rc;
}

extern "C" int loadid_est_residual_scales(const loadid_est_t *est, const loadid_real_t *phi,
                                          loadid_real_t scales[2]) {
    if (!est || !scales) return -EINVAL;
    const int n = est->cfg.n_params;
    if (phi && !all_finite(phi, n)) return LOADID_E_NONFINITE;
    const loadid::CovInput in = est->information(nullptr);
    if (in.samples <= 0) return LOADID_E_NOT_EXCITED;
    using Vec17 = Eigen::Matrix<Real, Eigen::Dynamic, 1, 0, LOADID_MAX_PARAMS + 1, 1>;
    using Mat17 = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic, 0, LOADID_MAX_PARAMS + 1,
                                LOADID_MAX_PARAMS + 1>;
    const Mat17 g = Eigen::Map<const Mat17, 0, Eigen::OuterStride<>>(in.gram, n + 1, n + 1,
                                                                     Eigen::OuterStride<>(n + 1))
                        .selfadjointView<Eigen::Lower>();
    const Mat17 gt = Eigen::Map<const Mat17, 0, Eigen::OuterStride<>>(in.gram_torque, n + 1, n + 1,
                                                                      Eigen::OuterStride<>(n + 1))
                         .selfadjointView<Eigen::Lower>();
    // v: the direction of the weighted column space that phi stands for,
    // T^-1 [phi; -1] (eq. 36 read backwards); without phi, the weighted
    // least-squares fit of the same data, T1 x with G_AA x = G_Ay.
    Vec17 v(n + 1);
    if (phi) {
        for (int j = 0; j < n; ++j) v(j) = phi[j] / in.t[j];
    } else {
        const Eigen::LDLT<Mat17> ldlt(g.topLeftCorner(n, n));
        if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return LOADID_E_NOT_EXCITED;
        v.head(n) = ldlt.solve(g.col(n).head(n)) / in.t[n]; // T1^-1 phi_LS
    }
    v(n) = Real(-1) / in.t[n];
    const Real norm = v.norm();
    if (!(norm > 0) || !v.allFinite()) return LOADID_E_NOT_EXCITED;
    v /= norm;
    const Real all = v.dot(g * v), tq = v.dot(gt * v);
    const Real rows = Real(3) * Real(in.samples);
    scales[0] = std::sqrt(std::max(all - tq, Real(0)) / rows);
    scales[1] = std::sqrt(std::max(tq, Real(0)) / rows);
    return 0;
}

extern "C" int loadid_est_update(loadid_est_t *est, const loadid_real_t *A, const loadid_real_t *C,
                                 const loadid_real_t y[6]) {
    if (!est || !A || !y) return -EINVAL;
    const int n = est->cfg.n_params;
    const bool riv = est->cfg.method == LOADID_METHOD_RIV;
    if (riv && !C) return -EINVAL;
    if (!all_finite(A, LOADID_NROWS * n) || !all_finite(y, LOADID_NROWS) ||
        (riv && !all_finite(C, LOADID_NROWS * n)))
        return LOADID_E_NONFINITE;
    return est->update(A, C, y);
}

extern "C" int loadid_est_estimate(const loadid_est_t *est, loadid_real_t *phi,
                                   loadid_est_info_t *info) {
    if (!est || !phi) return -EINVAL;
    return est->estimate(phi, info, true);
}

extern "C" int loadid_est_estimate_unique(const loadid_est_t *est, loadid_real_t *phi,
                                          loadid_est_info_t *info) {
    if (!est || !phi) return -EINVAL;
    return est->estimate(phi, info, loadid::solution_needs_ratio(est->cfg));
}

extern "C" int loadid_est_uncertainty(const loadid_est_t *est, const loadid_real_t *phi,
                                      loadid_real_t *std, loadid_real_t *scale) {
    if (!est || !phi || !std) return -EINVAL;
    if (!all_finite(phi, est->cfg.n_params)) return LOADID_E_NONFINITE;
    loadid_real_t s;
    const int rc = covariance_std(est->information(phi), std, &s);
    if (scale) *scale = s;
    return rc;
}

// A spectrum that fits the estimator: its samples, ordered bins, band 0
// the mean alone, RIV's instruments' bands.
static int spectrum_fits(const loadid::CovInput &in, const loadid_spectrum_t &sp) {
    if (sp.n_bands < 2 || sp.n_bands > LOADID_SPECTRUM_BANDS || sp.samples != in.samples ||
        sp.first_bin[0] != 0 || sp.first_bin[1] != 1 ||
        (in.kind == loadid::CovKind::IV && !sp.has_iv))
        return -EINVAL;
    for (int b = 1; b <= sp.n_bands; ++b)
        if (sp.first_bin[b] <= sp.first_bin[b - 1]) return -EINVAL;
    const int n = in.n, n1 = n + 1;
    const bool iv = in.kind == loadid::CovKind::IV;
    for (int g = 0; g < 2; ++g) {
        for (int b = 0; b < sp.n_bands; ++b) {
            if (!all_finite(sp.gram[b][g], n1 * n1)) return LOADID_E_NONFINITE;
            if (iv && !all_finite(sp.iv_gram[b][g], n * n)) return LOADID_E_NONFINITE;
        }
        if (iv && !all_finite(sp.iv_total[g], n * n)) return LOADID_E_NONFINITE;
    }
    if (!sp.has_rows) return 0;
    if (sp.first_bin[sp.n_bands] > LOADID_SPECTRUM_BINS) return -EINVAL;
    for (int j = 0; j < sp.first_bin[sp.n_bands]; ++j)
        for (int part = 0; part < 2; ++part)
            if (!all_finite(sp.row_dft[j][part], LOADID_NROWS * n1) ||
                (iv && !all_finite(sp.iv_dft[j][part], LOADID_NROWS * n)))
                return LOADID_E_NONFINITE;
    return 0;
}

extern "C" int loadid_est_uncertainty_spectral(const loadid_est_t *est, const loadid_real_t *phi,
                                               const loadid_spectrum_t *sp, loadid_real_t *std,
                                               loadid_real_t *scale) {
    if (!est || !phi || !sp || !std) return -EINVAL;
    if (!all_finite(phi, est->cfg.n_params)) return LOADID_E_NONFINITE;
    loadid::CovInput in = est->information(phi);
    const int fit = spectrum_fits(in, *sp);
    if (fit != 0) return fit;
    in.spectrum = sp;
    loadid_real_t s;
    const int rc = covariance_std(in, std, &s);
    if (scale) *scale = s;
    return rc;
}

extern "C" int loadid_est_drift_fitted(const loadid_est_t *est, const loadid_real_t *phi,
                                       loadid_real_t *phi_fitted, loadid_real_t *std,
                                       loadid_real_t *scale) {
    if (!est || !phi || !phi_fitted || !std) return -EINVAL;
    loadid::CovInput in = est->information(phi);
    if (in.n != LOADID_NPHI_OFFSET || !in.drift_cross) return -ENOTSUP;
    if (!all_finite(phi, in.n)) return LOADID_E_NONFINITE;
    in.phi_fitted = phi_fitted;
    loadid_real_t s;
    const int rc = covariance_std(in, std, &s);
    if (scale) *scale = s;
    return rc;
}

extern "C" int loadid_est_signal_to_noise(const loadid_est_t *est, const loadid_real_t *phi,
                                          loadid_real_t snr[3]) {
    if (!est || !phi || !snr) return -EINVAL;
    if (!all_finite(phi, est->cfg.n_params)) return LOADID_E_NONFINITE;
    return group_snr(est->information(phi), snr);
}

extern "C" int loadid_est_weakest_direction(const loadid_est_t *est, loadid_real_t *dir,
                                            loadid_real_t *ratio) {
    if (!est || !dir) return -EINVAL;
    return weakest_direction(est->information(nullptr), dir, ratio);
}

extern "C" const loadid_est_config_t *loadid_est_config(const loadid_est_t *est) {
    return est ? &est->cfg : nullptr;
}

extern "C" const char *loadid_method_name(loadid_method_t method) {
    return valid_method(method) ? kNames[method] : kNames[0];
}

extern "C" int loadid_method_from_name(const char *name) {
    if (!name) return -EINVAL;
    for (int m = LOADID_METHOD_RLS; m <= LOADID_METHOD_REFINED; ++m)
        if (std::strcmp(name, kNames[m]) == 0) return m;
    return -EINVAL;
}
