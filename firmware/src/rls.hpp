// Recursive least squares, eqs. (17)-(19), and recursive instrumental
// variables, eqs. (20)-(22). Sigma_0 = p0 I and phi_0 = 0 make the recursion
// equal to least squares with a vanishing ridge 1 / p0.
//
// RLS runs eqs. (17)-(19) in Bierman's UD-factorised form: Sigma = U D U^T
// (U unit upper triangular, D diagonal) and, Lambda being diagonal, one
// sample's six rows as six scalar updates. Gain and estimate are those of
// eqs. (17)-(19) in exact arithmetic, but Sigma stays positive definite and
// keeps its small elements when it falls from p0 by many orders (the plain
// Sigma - K A Sigma loses eps * p0 to rounding; Bierman 1977, ch. V).
// RIV's Sigma is not symmetric, so UD does not apply; it keeps
// M = Sigma^-1 = lambda M + C^T Lambda^-1 B and b = lambda b + C^T Lambda^-1 y
// (Sigma_0^-1 = I / p0) and solves M phi = b by LU when an estimate is
// asked for: the value eqs. (20)-(22) reach through the matrix inversion
// lemma, without their cancellation (which costs 1e-3 of phi after 100
// samples at p0 = 1e6).
#pragma once

#include <cerrno>

#include "estimator_base.hpp"
#include "excitation.hpp"

namespace loadid {

template <int N>
class RecursiveLs final : public loadid_est {
  public:
    explicit RecursiveLs(const loadid_est_config_t &c)
        : loadid_est(c),
          instrumental_(c.method == LOADID_METHOD_RIV),
          excitation_(row_weights(c), col_weights<N>(c)) {
        reweight();
    }

    void reweight() override {
        for (int i = 0; i < 6; ++i) lambda_(i) = cfg.row_sigma[i] * cfg.row_sigma[i];
        inv_lambda_ = lambda_.cwiseInverse();
        excitation_.set_weights(row_weights(cfg), col_weights<N>(cfg));
        reset();
    }

    void reset() override {
        phi_.setZero();
        M_ = Eigen::Matrix<Real, N, N>::Identity() / cfg.p0; // RIV: Sigma^-1
        CC_.setZero();
        CCt_.setZero();
        b_.setZero();
        iv_drift_.setZero();
        U_.setIdentity(); // RLS: Sigma = U D U^T
        D_.setConstant(cfg.p0);
        excitation_.reset();
        samples_ = 0;
    }

    // The recursion has folded the past in with its weights.
    int rescale(Real, Real, Real) override { return -ENOTSUP; }

    int update(const Real *a, const Real *c, const Real *y) override {
        const ConstRegressorMap<N> B(a); // data matrix (A_k, or B_k of RIV)
        const Eigen::Map<const Vec6> yk(y);
        if (instrumental_)
            update_riv(B, ConstRegressorMap<N>(c), yk);
        else
            update_rls_ud(B, yk);
        excitation_.add(Regressor<N>(B), yk, cfg.forgetting);
        ++samples_;
        return 0;
    }

    int estimate(Real *phi, loadid_est_info_t *info, bool ratio_gate) const override {
        Eigen::Map<Vec<N>> out(phi);
        out.setZero();
        const int rc = excitation_gate(excitation_, excitation_.noise_ratio(col_exact<N>(cfg)), cfg,
                                       samples_, info, ratio_gate);
        if (rc) return rc;
        // RIV keeps M and b (information form): its phi is solved here,
        // when asked for, not after every sample.
        const Vec<N> solved = instrumental_ ? Vec<N>(M_.partialPivLu().solve(b_)) : phi_;
        if (!solved.allFinite()) return LOADID_E_NOT_EXCITED;
        out = solved;
        return 0;
    }

    CovInput information(const Real *phi) const override {
        if (!instrumental_)
            return cov_input<N>(CovKind::LS, excitation_, excitation_.col_weight().data(), samples_,
                                phi, cfg);
        return cov_input<N>(CovKind::IV, excitation_, excitation_.col_weight().data(), samples_,
                            phi, cfg, M_.data(), CC_.data(), kDrift ? iv_drift_.data() : nullptr,
                            b_.data(), CCt_.data());
    }

  private:
    // Eqs. (17)-(19), one row h (variance r) at a time, Bierman's update.
    void update_rls_ud(const ConstRegressorMap<N> &A, const Vec6 &y) {
        // Forgetting: Sigma / lambda before the update (eq. 17 with lambda Lambda).
        if (cfg.forgetting != Real(1)) D_ /= cfg.forgetting; // x / 1 is x to the bit
        for (int row = 0; row < LOADID_NROWS; ++row) {
            const Vec<N> h = A.row(row).transpose();
            const Vec<N> f = U_.transpose().lazyProduct(h);
            const Vec<N> v = D_.cwiseProduct(f);
            Vec<N> b;
            Real alpha = lambda_(row) + v(0) * f(0);
            D_(0) *= lambda_(row) / alpha;
            b(0) = v(0);
            for (int j = 1; j < N; ++j) {
                const Real alpha_prev = alpha;
                alpha += v(j) * f(j);
                const Real p = -f(j) / alpha_prev;
                D_(j) *= alpha_prev / alpha;
                b(j) = v(j);
                for (int i = 0; i < j; ++i) {
                    const Real u = U_(i, j);
                    U_(i, j) = u + b(i) * p;
                    b(i) += u * v(j);
                }
            }
            // K = b / alpha is the column of eq. (17) for this row; eq. (19).
            phi_ += (b / alpha) * (y(row) - h.dot(phi_));
        }
    }

    // Eqs. (20)-(22) in information form.
    void update_riv(const ConstRegressorMap<N> &B, const ConstRegressorMap<N> &C, const Vec6 &y) {
        const Real lam = cfg.forgetting;
        const Eigen::Matrix<Real, N, 6> CtLi = C.transpose() * inv_lambda_.asDiagonal();
        if (lam != Real(1)) { // x * 1 is x to the bit
            M_ = lam * M_;
            CC_ = lam * CC_;
            CCt_ = lam * CCt_;
            b_ = lam * b_;
            iv_drift_ *= double(lam);
        }
        M_.noalias() += CtLi.lazyProduct(B);
        CC_.noalias() += CtLi.lazyProduct(C); // C^T W C: the instruments' part of RIV's covariance
        CCt_.noalias() += CtLi.template rightCols<3>().lazyProduct(C.template bottomRows<3>());
        b_.noalias() += CtLi * y;
        if constexpr (kDrift) // the drift witness's IV sums, on the excitation's clock
            iv_drift_ += (double(samples_) * 1e-3) * CtLi.template cast<double>();
    }

    const bool instrumental_;
    Vec6 lambda_, inv_lambda_;
    Vec<N> phi_;
    Eigen::Matrix<Real, N, N> M_;
    Eigen::Matrix<Real, N, N> CC_;
    Eigen::Matrix<Real, N, N> CCt_; // CC_ over the torque rows
    Vec<N> b_;
    // sum_k t_k C_k^T W (uncertainty.hpp), with the offset estimated only
    static constexpr bool kDrift = N == LOADID_NPHI_OFFSET;
    Eigen::Matrix<double, kDrift ? N : 1, 6> iv_drift_;
    Eigen::Matrix<Real, N, N> U_;
    Vec<N> D_;
    Excitation<N> excitation_;
    int64_t samples_ = 0;
};

} // namespace loadid
