// Excitation of the data so far: the information matrix Upsilon of eq. (12)
// of the weighted data matrix, Upsilon = sum_k (D A_k T1)^T (D A_k T1), kept
// by a rank-6 update per sample. Its eigenvalues give the condition number
// that every method reports and that gates LOADID_E_NOT_EXCITED.
#pragma once

#include <cmath>
#include <limits>

#include "eigen_types.hpp"

namespace loadid {

template <int N>
class Excitation {
public:
    Excitation(const Vec6 &row_weight, const Vec<N> &col_weight)
        : d_(row_weight), t_(col_weight) { reset(); }

    void reset() { gram_.setZero(); }

    void add(const Regressor<N> &A, Real forgetting = Real(1)) {
        const Regressor<N> W = d_.asDiagonal() * A * t_.asDiagonal();
        gram_ = forgetting * gram_;
        gram_.noalias() += W.transpose() * W;
    }

    // kappa(D A_Xi T1) = sqrt(lambda_max / lambda_min of Upsilon); +Inf when
    // Upsilon is singular to working precision.
    Real condition() const {
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Real, N, N>> es(gram_, Eigen::EigenvaluesOnly);
        const Real lmax = es.eigenvalues()(N - 1);
        const Real lmin = es.eigenvalues()(0);
        if (!(lmax > 0) || !(lmin > lmax * Real(N) * kEps)) return std::numeric_limits<Real>::infinity();
        return std::sqrt(lmax / lmin);
    }

private:
    Vec6 d_;
    Vec<N> t_;
    Eigen::Matrix<Real, N, N> gram_;
};

template <int N>
inline Vec6 row_weights(const loadid_est_config_t &cfg) {
    Vec6 d;
    for (int i = 0; i < 6; ++i) d(i) = Real(1) / cfg.row_sigma[i];
    return d;
}

template <int N>
inline Vec<N + 1> col_weights(const loadid_est_config_t &cfg) {
    return Eigen::Map<const Vec<N + 1>>(cfg.col_weight);
}

}  // namespace loadid
