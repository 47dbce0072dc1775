// Recursive total least squares, eqs. (24)-(36): Brand's incremental SVD of
// M = [D [A y] T]^T (one 6-column block N_k per sample, eq. 26), keeping the
// left singular vectors U and singular values S only (V is never needed for
// the TLS solution), then the Householder step and eq. (36).
//
// U is stored as a full (N+1)x(N+1) matrix whose first r columns are the
// current basis (r = rank of M so far) and whose other columns are zero, so
// every product has a compile-time size: no heap, in any branch.
//
// Once M has full rank, the blocks N_k of up to kBlock samples wait and are
// taken into one update together (Brand's update holds for a block of any
// width: eqs. 27-33 with N_k = [N_k1 ... N_kb]); an estimate first applies
// those waiting. The result is the same SVD of M up to rounding, and a
// sample costs less than half: one Jacobi on [S L] with 24 columns takes
// about as many sweeps as one with 6 (3.4 against 3.0 on the benchmark's
// recording), and U U_Z and the orthogonality check run once a block. An
// estimate after every sample makes every block one sample long.
#pragma once

#include <algorithm>
#include <cmath>

#include "brand_jacobi.hpp"
#include "estimator_base.hpp"
#include "excitation.hpp"
#include "linalg.hpp"
#include "tls_solution.hpp"

namespace loadid {

template <int N>
class Rtls final : public loadid_est {
    static constexpr int N1 = N + 1;
    static constexpr int kMaxInit = 3 * LOADID_NROWS;
    using MatU = Eigen::Matrix<Real, N1, N1>;
    using Block = Eigen::Matrix<Real, N1, LOADID_NROWS>;
    static constexpr int kBlock = 4; // samples per deferred update, at most
    using Pending = Eigen::Matrix<Real, N1, LOADID_NROWS * kBlock>;

  public:
    explicit Rtls(const loadid_est_config_t &c)
        : loadid_est(c),
          d_(row_weights(c)),
          t_(col_weights<N>(c)),
          excitation_(d_, t_),
          exact_((col_exact<N>(c).template head<N>().array() != Real(1)).any()) {
        reset();
    }

    void reweight() override {
        d_ = row_weights(cfg);
        t_ = col_weights<N>(cfg);
        exact_ = (col_exact<N>(cfg).template head<N>().array() != Real(1)).any();
        excitation_.set_weights(d_, t_);
        reset();
    }

    void reset() override {
        gate_at_ = -1;
        U_.setZero();
        s_.setZero();
        init_.setZero();
        rank_ = 0;
        init_count_ = 0;
        samples_ = 0;
        reorth_ = 0;
        ortho_error_ = 0;
        since_check_ = 0;
        pending_count_ = 0;
    }

    // Brand's SVD cannot weigh its past again, but M M^T is the
    // information matrix the excitation gate keeps with its force and
    // torque parts apart: U and S restart from the eigenproblem of that
    // matrix re-weighted (which squares the condition number, once), and
    // Brand's update goes on from there with the new weights.
    int rescale(Real force, Real torque, Real columns) override {
        apply_pending();
        if (init_count_ < cfg.rtls_init_samples || rank_ < N1) return LOADID_E_NOT_EXCITED;
        d_ = row_weights(cfg);
        t_ = col_weights<N>(cfg);
        excitation_.rescale(force, torque, columns);
        gate_at_ = -1;
        linalg::Square V;
        linalg::Values l;
        const MatU G = excitation_.gram().template selfadjointView<Eigen::Lower>();
        linalg::sym_eigen(linalg::Square(G), V, l);
        for (int j = 0; j < N1; ++j) { // ascending eigenvalues: descending s
            U_.col(j) = V.col(N - j);
            s_(j) = std::sqrt(std::max(l(N - j), Real(0)));
        }
        // A direction the re-weighting left (numerically) empty: rank
        // deficient, as initial_svd keeps it (brand_jacobi wants s > 0).
        const Real tol = rank_tol(s_(0));
        while (rank_ > 0 && !(s_(rank_ - 1) > tol)) --rank_;
        U_.rightCols(N1 - rank_).setZero();
        s_.tail(N1 - rank_).setZero();
        since_check_ = 0;
        ortho_error_ = orthogonality_error();
        return 0;
    }

    int update(const Real *a, const Real *, const Real *y) override {
        const ConstRegressorMap<N> A(a);
        Eigen::Matrix<Real, LOADID_NROWS, N1, Eigen::RowMajor> Ay;
        Ay.template leftCols<N>() = A;
        Ay.col(N) = Eigen::Map<const Vec6>(y);
        // N_k = [D [A_k y_k] T]^T, eq. (26).
        const Block Nk = (d_.asDiagonal() * Ay * t_.asDiagonal()).transpose();
        excitation_.add(Regressor<N>(A), Eigen::Map<const Vec6>(y));
        ++samples_;
        if (init_count_ < cfg.rtls_init_samples) {
            init_.template block<N1, LOADID_NROWS>(0, LOADID_NROWS * init_count_) = Nk;
            if (++init_count_ == cfg.rtls_init_samples) initial_svd();
            return 0;
        }
        if (rank_ < N1) {
            brand_update(Nk);
            check_orthogonality();
            return 0;
        }
        pending_.template middleCols<LOADID_NROWS>(LOADID_NROWS * pending_count_) = Nk;
        if (++pending_count_ == kBlock) apply_pending();
        return 0;
    }

    int estimate(Real *phi, loadid_est_info_t *info, bool ratio_gate) const override {
        apply_pending();
        Eigen::Map<Vec<N>> out(phi);
        out.setZero();
        const int gate =
            excitation_gate(excitation_, noise_ratio(), cfg, samples_, info, ratio_gate);
        if (info) {
            info->sigma_min = rank_ == N1 ? s_(N) : Real(0);
            info->reorthogonalisations = reorth_;
            info->orthogonality_error = ortho_error_;
        }
        if (gate) return gate;
        if (init_count_ < cfg.rtls_init_samples) return LOADID_E_NOT_EXCITED;
        // The directions M has not reached (rank r < N+1) are the orthogonal
        // complement of U, with singular value 0.
        MatU W = U_;
        if (rank_ < N1) {
            linalg::Square Q;
            linalg::Values rd;
            linalg::householder_q(linalg::Square(U_), Q, rd);
            W.rightCols(N1 - rank_) = Q.rightCols(N1 - rank_);
        }
        const TlsSolution<N> sol = tls_solution<N>(W, s_, t_, cfg.rtls_eps);
        if (info) info->sigma_min_multiplicity = sol.multiplicity;
        if (sol.status) return sol.status;
        out = sol.phi;
        return 0;
    }

    CovInput information(const Real *phi) const override {
        return cov_input<N>(CovKind::TLS, excitation_, t_.data(), samples_, phi, cfg);
    }

  private:
    // Eq. (24): SVD of the first 2-3 blocks (zero-padded to 18 columns,
    // which adds zero singular values and changes nothing else).
    void initial_svd() {
        const int cols = LOADID_NROWS * cfg.rtls_init_samples;
        // svd_left wants rows <= columns: zero columns add only zero
        // singular values.
        linalg::Work M = linalg::Work::Zero(N1, std::max(N1, cols));
        M.leftCols(cols) = init_.leftCols(cols);
        linalg::Square Um;
        linalg::Values sv;
        linalg::svd_left(M, Um, sv);
        const Real tol = rank_tol(sv(0));
        rank_ = 0;
        while (rank_ < N1 && sv(rank_) > tol) ++rank_;
        U_.setZero();
        s_.setZero();
        U_.leftCols(rank_) = Um.leftCols(rank_);
        s_.head(rank_) = sv.head(rank_);
    }

    // sigma_{n+1} / sigma_n from the singular values the update keeps (no
    // second decomposition per estimate): 0 when the data are exact (rank n),
    // 1 when even sigma_n is 0 (nothing stands out, as Excitation has it).
    // With columns counted as exact (col_exact != 1) the ratio must be that
    // of the noise's own weights, T / E, which these singular values do
    // not give: it comes from the excitation's Gram matrix (an 11 x 11
    // eigen-solve, 2-3 us), on every estimate while the last figure did
    // not pass the gate, then once per kGateEvery samples (the figure
    // reported may be that many samples old; with more data it falls, but
    // for a jump in the data). Exactness then does not make weak data look
    // excited.
    Real noise_ratio() const {
        if (!exact_) {
            if (rank_ < N) return Real(1);
            if (rank_ == N) return Real(0);
            return s_(N) / s_(N - 1);
        }
        const bool passed = gate_at_ >= 0 && gate_ratio_ <= noise_ratio_bound<N>(cfg, gate_at_);
        if (gate_at_ < 0 ||
            (samples_ != gate_at_ && (!passed || samples_ - gate_at_ >= kGateEvery))) {
            gate_ratio_ = excitation_.noise_ratio(col_exact<N>(cfg));
            gate_at_ = samples_;
        }
        return gate_ratio_;
    }

    Real rank_tol(Real scale) const { return cfg.rtls_eps * Real(N1) * scale; }

    // Full rank: nothing of the waiting blocks lies outside span(U), so
    // eqs. (27) and (29)-(33) for N = [N_k1 ... N_kb]: Z = [S L], L = U^T N,
    // U' = U U_Z. The Jacobi is instantiated for 1, 2 and 4 samples; 3 are
    // padded with zero columns, which change nothing.
    void apply_pending() const {
        if (pending_count_ == 0) return;
        if (pending_count_ == 1)
            apply_block<1>();
        else if (pending_count_ == 2)
            apply_block<2>();
        else
            apply_block<kBlock>();
        pending_count_ = 0;
        check_orthogonality();
    }

    template <int B>
    void apply_block() const {
        constexpr int C = LOADID_NROWS * B;
        const int used = LOADID_NROWS * pending_count_;
        pending_.middleCols(used, C - used).setZero();
        const Eigen::Matrix<Real, N1, C> L =
            U_.transpose().lazyProduct(pending_.template leftCols<C>());
        MatU Uz;
        Vec<N1> sz;
        brand_jacobi<N1, C>(s_, L, Uz, sz);
        const MatU basis = U_;
        U_.noalias() = basis.lazyProduct(Uz);
        s_ = sz;
    }

    // Eqs. (25)-(35) for one block while M has rank r < N + 1.
    void brand_update(const Block &Nk) {
        Block L = U_.transpose().lazyProduct(Nk);                   // eq. (27); rows >= r are 0
        MatU basis = U_;                                            // [U_k J_k], eq. (34)
        linalg::Work Z = linalg::Work::Zero(N1, N1 + LOADID_NROWS); // eq. (29), zero-padded
        // Eq. (28): the part of N_k outside span(U), projected twice
        // (classical Gram-Schmidt with re-orthogonalisation).
        Block H = Nk - U_.lazyProduct(L);
        const Block L2 = U_.transpose().lazyProduct(H);
        L += L2;
        H -= U_.lazyProduct(L2);
        // Eq. (31) asks whether the volume of H orthogonal to U is zero.
        // A rank-revealing QR answers it column by column: the leading p
        // columns with |G_ii| above the tolerance have non-zero volume
        // and extend U (eqs. 34-35); p = 0 is the paper's v < eps branch
        // (eqs. 32-33). Brand (2002) keeps exactly this numerical rank.
        linalg::Square Q;
        linalg::Tall R;
        Eigen::Matrix<int, LOADID_NROWS, 1> perm;
        linalg::colpiv_qr(linalg::Tall(H), Q, R, perm);
        const Real tol = rank_tol(std::max(s_(0), Nk.norm()));
        const int pmax = std::min(LOADID_NROWS, N1 - rank_);
        int p = 0;
        while (p < pmax && std::abs(R(p, p)) > tol) ++p;
        if (p > 0) {
            basis.middleCols(rank_, p) = Q.leftCols(p);
            for (int j = 0; j < LOADID_NROWS; ++j)
                for (int i = 0; i < p; ++i) Z(rank_ + i, N1 + perm(j)) = R(i, j); // G_k = R P^T
        }
        Z.topLeftCorner(N1, N1).diagonal() = s_;                                // S_k
        Z.template rightCols<LOADID_NROWS>().topRows(rank_) = L.topRows(rank_); // L_k
        // Eq. (30): only U' and S' are needed.
        linalg::Square Uz;
        linalg::Values sz;
        linalg::svd_left(Z, Uz, sz);
        rank_ += p;
        U_.noalias() = basis.lazyProduct(Uz.template topLeftCorner<N1, N1>()); // eqs. (32) / (34)
        s_ = sz;                                                               // eqs. (33) / (35)
        if (rank_ < N1) {
            U_.rightCols(N1 - rank_).setZero();
            s_.tail(N1 - rank_).setZero();
        }
    }

    // Brand's re-orthogonalisation, when ||U^T U - I|| drifts past the bound.
    // Measuring it costs a fifth of a one-sample update, and an update (one
    // product by U') adds at most kDrift to it (about 16 eps observed), so it
    // is measured when the last figure plus kDrift per update since could
    // have reached the bound, and at least every kCheckEvery updates.
    void check_orthogonality() const {
        static constexpr Real kDrift = Real(50) * kEps;
        static constexpr int kCheckEvery = 64;
        ++since_check_;
        const bool could_pass = cfg.rtls_ortho_tol > 0 &&
                                ortho_error_ + kDrift * Real(since_check_) >= cfg.rtls_ortho_tol;
        if (!could_pass && since_check_ < kCheckEvery && rank_ == N1) return;
        since_check_ = 0;
        ortho_error_ = orthogonality_error();
        if (!(cfg.rtls_ortho_tol > 0) || ortho_error_ <= cfg.rtls_ortho_tol) return;
        linalg::Square Q;
        linalg::Values rd;
        linalg::householder_q(linalg::Square(U_), Q, rd);
        for (int j = 0; j < rank_; ++j) U_.col(j) = (rd(j) < 0 ? Real(-1) : Real(1)) * Q.col(j);
        ++reorth_;
        ortho_error_ = orthogonality_error();
    }

    // ||U^T U - I||_F (I on the first r columns) from the lower triangle of
    // the symmetric U^T U: half the products of the whole, once an update.
    Real orthogonality_error() const {
        Real diag = 0, off = 0;
        for (int j = 0; j < N1; ++j) {
            const Real e = U_.col(j).squaredNorm() - (j < rank_ ? Real(1) : Real(0));
            diag += e * e;
            for (int i = j + 1; i < N1; ++i) {
                const Real o = U_.col(i).dot(U_.col(j));
                off += o * o;
            }
        }
        return std::sqrt(diag + Real(2) * off);
    }

    Vec6 d_;
    Vec<N1> t_;
    Excitation<N> excitation_;
    // estimate() applies the waiting blocks: the data M holds do not change,
    // only how far its SVD has been brought up to date.
    mutable MatU U_;
    mutable Vec<N1> s_;
    mutable Pending pending_;
    mutable int pending_count_ = 0;
    Eigen::Matrix<Real, N1, kMaxInit> init_;
    int rank_ = 0;
    int init_count_ = 0;
    int64_t samples_ = 0;
    mutable int reorth_ = 0;
    mutable Real ortho_error_ = 0;
    mutable int since_check_ = 0;
    // The noise-ratio gate with exact columns (noise_ratio()).
    static constexpr int64_t kGateEvery = 64;
    bool exact_ = false;
    mutable Real gate_ratio_ = 1;
    mutable int64_t gate_at_ = -1;
};

} // namespace loadid
