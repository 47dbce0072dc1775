// Batch references: every sample's raw [A y] rows are stored (the store is
// allocated once, at create), and estimate() solves from scratch over all of
// them, with the same weights as the recursive methods:
//   LS_BATCH  min || D (A phi - y) ||, Lambda = D^-2 as in RLS;
//   TLS_BATCH one SVD of all stacked rows D [A y] T, computed as the QR of
//             the rows followed by the SVD of the triangular factor, then the
//             same Householder step and eq. (36) as RTLS.
#pragma once

#include <memory>
#include <new>

#include "estimator_base.hpp"
#include "excitation.hpp"
#include "givens_qr.hpp"
#include "linalg.hpp"
#include "tls_solution.hpp"

namespace loadid {

template <int N>
class Batch final : public loadid_est {
    static constexpr int N1 = N + 1;
    using MatR = Eigen::Matrix<Real, N1, N1>;

  public:
    explicit Batch(const loadid_est_config_t &c)
        : loadid_est(c), d_(row_weights(c)), t_(col_weights<N>(c)), excitation_(d_, t_) {}

    // The one allocation; false when out of memory.
    bool allocate() {
        const size_t n = static_cast<size_t>(cfg.batch_capacity) * LOADID_NROWS * N1;
        rows_.reset(new (std::nothrow) Real[n]);
        reset();
        return rows_ != nullptr;
    }

    void reset() override {
        samples_ = 0;
        excitation_.reset();
    }

    void reweight() override {
        d_ = row_weights(cfg);
        t_ = col_weights<N>(cfg);
        excitation_.set_weights(d_, t_);
        reset();
    }

    // The raw rows are stored: the information matrix is built again with
    // the new weights (estimate() applies them to the rows itself).
    int rescale(Real, Real, Real) override {
        d_ = row_weights(cfg);
        t_ = col_weights<N>(cfg);
        excitation_.set_weights(d_, t_);
        for (int64_t k = 0; k < samples_; ++k) {
            const Real *src = rows_.get() + static_cast<size_t>(k) * LOADID_NROWS * N1;
            Regressor<N> A;
            Vec6 y;
            for (int i = 0; i < LOADID_NROWS; ++i) {
                for (int j = 0; j < N; ++j) A(i, j) = src[i * N1 + j];
                y(i) = src[i * N1 + N];
            }
            excitation_.add(A, y);
        }
        return 0;
    }

    int update(const Real *a, const Real *, const Real *y) override {
        if (samples_ >= cfg.batch_capacity) return LOADID_E_FULL;
        Real *dst = rows_.get() + static_cast<size_t>(samples_) * LOADID_NROWS * N1;
        for (int i = 0; i < LOADID_NROWS; ++i) {
            for (int j = 0; j < N; ++j) dst[i * N1 + j] = a[i * N + j];
            dst[i * N1 + N] = y[i];
        }
        excitation_.add(Regressor<N>(ConstRegressorMap<N>(a)), Eigen::Map<const Vec6>(y));
        ++samples_;
        return 0;
    }

    int estimate(Real *phi, loadid_est_info_t *info, bool ratio_gate) const override {
        Eigen::Map<Vec<N>> out(phi);
        out.setZero();
        const int gate = excitation_gate(excitation_, excitation_.noise_ratio(col_exact<N>(cfg)),
                                         cfg, samples_, info, ratio_gate);
        if (gate) return gate;
        if (samples_ < 2) return LOADID_E_NOT_EXCITED;

        MatR R = MatR::Zero(); // QR of all rows D [A y], from scratch
        for (int64_t k = 0; k < samples_ * LOADID_NROWS; ++k) {
            const Eigen::Map<const Vec<N1>> row(rows_.get() + k * N1);
            givens_add_row<N1>(R, d_(static_cast<int>(k % LOADID_NROWS)) * row);
        }
        if (cfg.method == LOADID_METHOD_LS_BATCH) {
            // R = [R11 r12; 0 r22]: phi = R11^-1 r12.
            const auto R11 = R.template topLeftCorner<N, N>();
            Vec<N> sol = R.col(N).template head<N>();
            R11.template triangularView<Eigen::Upper>().solveInPlace(sol);
            if (!sol.allFinite()) return LOADID_E_NOT_EXCITED;
            out = sol;
            return 0;
        }
        // The right singular vectors of R T are the left ones of (R T)^T.
        const linalg::Work RTt = (R * t_.asDiagonal()).transpose();
        linalg::Square Vb;
        linalg::Values svb;
        linalg::svd_left(RTt, Vb, svb);
        const MatR V = Vb;
        const Vec<N1> sv = svb;
        const TlsSolution<N> sol = tls_solution<N>(V, sv, t_, cfg.rtls_eps);
        if (info) {
            info->sigma_min = sv(N);
            info->sigma_min_multiplicity = sol.multiplicity;
        }
        if (sol.status) return sol.status;
        out = sol.phi;
        return 0;
    }

    CovInput information(const Real *phi) const override {
        const CovKind kind = cfg.method == LOADID_METHOD_LS_BATCH ? CovKind::LS : CovKind::TLS;
        return cov_input<N>(kind, excitation_, t_.data(), samples_, phi, cfg);
    }

  private:
    Vec6 d_;
    Vec<N1> t_;
    Excitation<N> excitation_;
    std::unique_ptr<Real[]> rows_;
    int64_t samples_ = 0;
};

} // namespace loadid
