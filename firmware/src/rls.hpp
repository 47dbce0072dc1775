// Recursive least squares, eqs. (17)-(19), and recursive instrumental
// variables, eqs. (20)-(22). They differ only in the matrix on the left of
// the gain: A_k itself (RLS) or the instruments C_k (RIV), so one template
// serves both. Sigma_0 = p0 I and phi_0 = 0 make the recursion equal to
// least squares with a vanishing ridge p0^-1.
#pragma once

#include "estimator_base.hpp"
#include "excitation.hpp"

namespace loadid {

template <int N>
class RecursiveLs final : public loadid_est {
public:
    explicit RecursiveLs(const loadid_est_config_t &c)
        : loadid_est(c),
          instrumental_(c.method == LOADID_METHOD_RIV),
          excitation_(row_weights<N>(c), col_weights<N>(c).template head<N>()) {
        for (int i = 0; i < 6; ++i) lambda_(i) = c.row_sigma[i] * c.row_sigma[i];
        reset();
    }

    void reset() override {
        phi_.setZero();
        P_ = Eigen::Matrix<Real, N, N>::Identity() * cfg.p0;
        excitation_.reset();
        samples_ = 0;
    }

    int update(const Real *a, const Real *c, const Real *y) override {
        const ConstRegressorMap<N> B(a);  // data matrix (A_k, or B_k of RIV)
        const Eigen::Map<const Vec6> yk(y);
        const Real lam = cfg.forgetting;
        // P B^T and P C^T: C_k = A_k for RLS (eq. 17), instruments for RIV (eq. 20).
        const Eigen::Matrix<Real, N, 6> PCt = instrumental_
            ? Eigen::Matrix<Real, N, 6>(P_ * ConstRegressorMap<N>(c).transpose())
            : Eigen::Matrix<Real, N, 6>(P_ * B.transpose());
        Eigen::Matrix<Real, 6, 6> S = B * PCt;
        S.diagonal() += lam * lambda_;
        Eigen::Matrix<Real, N, 6> K;
        if (instrumental_) {
            // K = Sigma C^T [B Sigma C^T + Lambda]^-1, eq. (20); S is not symmetric.
            K = S.transpose().partialPivLu().solve(PCt.transpose()).transpose();
        } else {
            // K = Sigma A^T [A Sigma A^T + Lambda]^-1, eq. (17); S is SPD.
            K = S.llt().solve(PCt.transpose()).transpose();
        }
        phi_ += K * (yk - B * phi_);                       // eqs. (19), (22)
        const Eigen::Matrix<Real, N, N> KBP = K * (B * P_);
        P_ = (P_ - KBP) / lam;                              // eqs. (18), (21)
        if (!instrumental_) P_ = Real(0.5) * (P_ + P_.transpose()).eval();  // keep RLS's P symmetric
        excitation_.add(Regressor<N>(B), lam);
        ++samples_;
        return 0;
    }

    int estimate(Real *phi, loadid_est_info_t *info) const override {
        const Real kappa = excitation_.condition();
        if (info) {
            *info = loadid_est_info_t{};
            info->samples = samples_;
            info->condition_number = kappa;
        }
        Eigen::Map<Vec<N>> out(phi);
        if (!(kappa <= cfg.max_condition) || !phi_.allFinite()) {
            out.setZero();
            return LOADID_E_NOT_EXCITED;
        }
        out = phi_;
        return 0;
    }

private:
    const bool instrumental_;
    Vec6 lambda_;
    Vec<N> phi_;
    Eigen::Matrix<Real, N, N> P_;
    Excitation<N> excitation_;
    int64_t samples_ = 0;
};

}  // namespace loadid
