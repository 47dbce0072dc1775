// Excitation of the data so far, from the information matrix of the
// weighted augmented data, Upsilon+ = sum_k (D [A_k y_k] T)^T (D [A_k y_k] T),
// kept by a rank-6 update per sample (eq. 12 with the wrench column added).
// Two figures come from it, the same for every method:
//  - the condition number of the weighted data matrix D A_Xi T1 (from the
//    leading n x n block, Upsilon of eq. 12);
//  - the noise ratio sigma_{n+1} / sigma_n of D [A y] T: near 1 when no
//    direction of the parameter space stands out of the noise (a still pose
//    with noisy accelerations looks well conditioned but is not excited),
//    near 0 for well-excited data. TLS needs sigma_n > sigma_{n+1} for a
//    unique solution (Golub & Van Loan, TLS existence condition).
#pragma once

#include <cmath>
#include <limits>

#include "eigen_types.hpp"
#include "linalg.hpp"

namespace loadid {

template <int N>
class Excitation {
    static constexpr int N1 = N + 1;

public:
    Excitation(const Vec6 &row_weight, const Vec<N1> &col_weight) : d_(row_weight), t_(col_weight) { reset(); }

    void reset() {
        gram_.setZero();
        gram_torque_.setZero();
    }

    void set_weights(const Vec6 &row_weight, const Vec<N1> &col_weight) {
        d_ = row_weight;
        t_ = col_weight;
        reset();
    }

    void add(const Regressor<N> &A, const Vec6 &y, Real forgetting = Real(1)) {
        Eigen::Matrix<Real, LOADID_NROWS, N1, Eigen::RowMajor> W;
        W.template leftCols<N>() = A;
        W.col(N) = y;
        W = d_.asDiagonal() * W * t_.asDiagonal();
        gram_ = forgetting * gram_;
        // Only the lower triangle is computed and read (the eigen-solvers take
        // it): the Gram matrix is exactly symmetric, and half the work. The
        // loop sums in the order of Eigen's selfadjointView().rankUpdate()
        // (the same bits; the trajectory designer's search is chaotic in
        // them) at a third of its cost, which was its blocked GEMM kernel.
        // The torque rows' share is kept apart as well, for the covariance
        // (uncertainty.hpp): force and torque rows carry different residual
        // noise. gram_ itself keeps its summation order and bits.
        gram_torque_ = forgetting * gram_torque_;
        for (int j = 0; j < N1; ++j)
            for (int i = j; i < N1; ++i) {
                Real acc = 0, torque = 0;
                for (int k = 0; k < LOADID_NROWS; ++k) acc += W(k, i) * W(k, j);
                for (int k = 3; k < LOADID_NROWS; ++k) torque += W(k, i) * W(k, j);
                gram_(i, j) += acc;
                gram_torque_(i, j) += torque;
            }
    }

    // kappa(D A_Xi T1) = sqrt(lambda_max / lambda_min of Upsilon); +Inf when
    // Upsilon is singular to working precision.
    Real condition() const {
        const linalg::Square ups = gram_.template topLeftCorner<N, N>();
        linalg::Values l;
        linalg::sym_eigenvalues(ups, l);
        const Real lmax = l(N - 1), lmin = l(0);
        if (!(lmax > 0) || !(lmin > lmax * Real(N) * kEps)) return std::numeric_limits<Real>::infinity();
        return std::sqrt(lmax / lmin);
    }

    // sigma_{n+1} / sigma_n of D [A y] T, in [0, 1]; 1 when there is no data.
    Real noise_ratio() const {
        const linalg::Square g = gram_;
        linalg::Values l;
        linalg::sym_eigenvalues(g, l);
        const Real l0 = std::max(l(0), Real(0)), l1 = l(1);
        if (!(l1 > 0)) return Real(1);
        return std::sqrt(l0 / l1);
    }

    // The information matrix (lower triangle valid), its torque rows' part,
    // and the weights it was built with, for the covariance of an estimate
    // (uncertainty.hpp).
    const Eigen::Matrix<Real, N1, N1> &gram() const { return gram_; }
    const Eigen::Matrix<Real, N1, N1> &gram_torque() const { return gram_torque_; }
    const Vec<N1> &col_weight() const { return t_; }

private:
    Vec6 d_;
    Vec<N1> t_;
    Eigen::Matrix<Real, N1, N1> gram_;
    Eigen::Matrix<Real, N1, N1> gram_torque_;
};

inline Vec6 row_weights(const loadid_est_config_t &cfg) {
    Vec6 d;
    for (int i = 0; i < 6; ++i) d(i) = Real(1) / cfg.row_sigma[i];
    return d;
}

template <int N>
inline Vec<N + 1> col_weights(const loadid_est_config_t &cfg) {
    return Eigen::Map<const Vec<N + 1>>(cfg.col_weight);
}

// The excitation gate shared by every method: fills the info fields it
// owns and returns 0 or LOADID_E_NOT_EXCITED. ratio is sigma_{n+1}/sigma_n
// of D [A y] T: Excitation::noise_ratio(), or RTLS's own singular values.
template <int N>
inline int excitation_gate(const Excitation<N> &ex, Real ratio, const loadid_est_config_t &cfg,
                           int64_t samples, loadid_est_info_t *info) {
    const Real kappa = ex.condition();
    if (info) {
        *info = loadid_est_info_t{};
        info->samples = samples;
        info->condition_number = kappa;
        info->noise_ratio = ratio;
    }
    if (!(kappa <= cfg.max_condition)) return LOADID_E_NOT_EXCITED;
    if (cfg.max_noise_ratio < 1) {
        // Pure noise in k samples of 6 rows has its n+1 singular values
        // within sqrt(6k) (1 +- gamma), gamma = sqrt((n+1) / 6k) (the
        // Marchenko-Pastur edge), so their adjacent ratio can come near
        // 1 - 2 gamma: the weakest direction must stand out beyond that.
        // RLS and RIV with forgetting remember 1 / (1 - lambda) samples.
        Real k = Real(samples);
        const bool forgets = cfg.method == LOADID_METHOD_RLS || cfg.method == LOADID_METHOD_RIV;
        if (forgets && cfg.forgetting < 1) k = std::min(k, Real(1) / (Real(1) - cfg.forgetting));
        const Real gamma = k > 0 ? std::sqrt(Real(N + 1) / (Real(LOADID_NROWS) * k)) : Real(1);
        const Real bound = std::min(cfg.max_noise_ratio, Real(1) - Real(2) * gamma);
        if (!(ratio <= bound)) return LOADID_E_NOT_EXCITED;
    }
    return 0;
}

}  // namespace loadid
