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
#include <algorithm>
#include <limits>

#include "eigen_types.hpp"
#include "linalg.hpp"
#include "uncertainty.hpp"

namespace loadid {

template <int N>
class Excitation {
    static constexpr int N1 = N + 1;

  public:
    Excitation(const Vec6 &row_weight, const Vec<N1> &col_weight) : d_(row_weight), t_(col_weight) {
        reset();
    }

    void reset() {
        warm_ = false;
        gram_.setZero();
        gram_torque_.setZero();
        row_sum_.setZero();
        drift_.reset();
    }

    void set_weights(const Vec6 &row_weight, const Vec<N1> &col_weight) {
        d_ = row_weight;
        t_ = col_weight;
        reset();
    }

    // The rows' noise levels times force (rows 0-2) and torque (3-5), the
    // regressor columns' weights times columns, for what is already in as
    // well: the force and torque parts of the Gram matrix are kept apart,
    // so this is exact.
    void rescale(Real force, Real torque, Real columns) {
        const Real wf = Real(1) / (force * force), wt = Real(1) / (torque * torque);
        Vec<N1> c = Vec<N1>::Constant(columns);
        c(N) = 1;
        gram_ = c.asDiagonal() * (wf * (gram_ - gram_torque_) + wt * gram_torque_) * c.asDiagonal();
        gram_torque_ = wt * (c.asDiagonal() * gram_torque_ * c.asDiagonal());
        for (int i = 0; i < LOADID_NROWS; ++i) {
            d_(i) /= i < 3 ? force : torque;
            row_sum_.row(i) *= columns / (i < 3 ? force : torque);
            drift_.cross.row(i) *= double(columns / (i < 3 ? force : torque));
            drift_.y(i) /= double(i < 3 ? force : torque);
        }
        t_.template head<N>() *= columns;
    }

    void add(const Regressor<N> &A, const Vec6 &y, Real forgetting = Real(1)) {
        Eigen::Matrix<Real, LOADID_NROWS, N1, Eigen::RowMajor> W;
        W.template leftCols<N>() = A;
        W.col(N) = y;
        W = d_.asDiagonal() * W * t_.asDiagonal();
        // x * 1 is x to the bit: without forgetting, no scaling.
        if (forgetting != Real(1)) {
            gram_ = forgetting * gram_;
            gram_torque_ = forgetting * gram_torque_;
            row_sum_ = forgetting * row_sum_;
            drift_.forget(double(forgetting));
        }
        row_sum_ += W.template leftCols<N>();
        if (N == LOADID_NPHI_OFFSET) drift_.add(W);
        // Only the lower triangle is computed and read (the eigen-solvers take
        // it): the Gram matrix is exactly symmetric, and half the work. The
        // loop sums in the order of Eigen's selfadjointView().rankUpdate()
        // (the same bits; the trajectory designer's search is chaotic in
        // them) at a third of its cost, which was its blocked GEMM kernel.
        // The torque rows' share is kept apart as well, for the covariance
        // (uncertainty.hpp): force and torque rows carry different residual
        // noise. gram_ itself keeps its summation order and bits.
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
    //
    // Upsilon changes by a rank-6 term a sample, so the extreme eigenvectors
    // of the last call are nearly those of this one. Each extreme eigenvalue
    // comes from shifted inverse iteration started there (extreme()),
    // stopped once the residual ||G v - rho v|| <= tol rho, tol = 1e-3: the
    // Rayleigh quotient rho is then within tol^2 rho^2 / gap of the
    // eigenvalue, and an eigenvalue within tol rho of it (Parlett, The
    // Symmetric Eigenvalue Problem, ch. 4 and 10): 1e-6 rho / gap relative,
    // the condition number to 1e-8 typically and 2.5e-5 at worst seen
    // (test_estimators, early on, where Upsilon's small eigenvalues lie
    // close together). A gate's and a report's figure: with tol 1e-6 nearly
    // every call took a step (two Cholesky factorisations), with 1e-3 most
    // take none, 0.8 us less per estimate of every method (bench_core:
    // RTLS update+estimate 5.9 -> 5.0 us). A call that does not get there
    // in a few steps (the first after a reset, a singular Upsilon, a jump in
    // the data) solves the whole eigenproblem and starts the next from its
    // vectors.
    // exact: loadid_est_config_t's col_exact; the figure is that of
    // D A (T / exact), the columns weighted by their noise alone.
    Real condition(const Vec<N1> &exact) const {
        Eigen::Matrix<Real, N, N> ups =
            gram_.template topLeftCorner<N, N>().template selfadjointView<Eigen::Lower>();
        if ((exact.template head<N>().array() != Real(1)).any()) {
            const Vec<N> inv = exact.template head<N>().cwiseInverse();
            ups = inv.asDiagonal() * ups * inv.asDiagonal();
        }
        Real lmin = 0, lmax = 0;
        if (!(warm_ && warm_extremes(ups, lmin, lmax))) {
            linalg::Square v;
            linalg::Values l;
            linalg::sym_eigen(linalg::Square(ups), v, l);
            lmin = l(0);
            lmax = l(N - 1);
            v_min_ = v.col(0);
            v_max_ = v.col(N - 1);
            warm_ = v_min_.allFinite() && v_max_.allFinite();
        }
        if (!(lmax > 0) || !(lmin > lmax * Real(N) * kEps))
            return std::numeric_limits<Real>::infinity();
        return std::sqrt(lmax / lmin);
    }

    // sigma_{n+1} / sigma_n of D [A y] (T / exact), in [0, 1]; 1 when
    // there is no data.
    Real noise_ratio(const Vec<N1> &exact) const {
        Vec<N1> inv = exact.cwiseInverse();
        inv(N) = 1;
        const linalg::Square g = inv.asDiagonal() *
                                 linalg::Square(gram_.template selfadjointView<Eigen::Lower>()) *
                                 inv.asDiagonal();
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
    const Vec6 &row_weight() const { return d_; }
    // sum_k D A_k T1, what one wrench error shared by every row (the
    // zeroing offset's) moves the estimate by (uncertainty.hpp).
    const Eigen::Matrix<Real, LOADID_NROWS, N> &row_sum() const { return row_sum_; }
    // With the offset estimated: the sums a linear drift of it needs
    // (uncertainty.hpp), time in thousands of samples.
    struct DriftSums {
        Eigen::Matrix<double, LOADID_NROWS, N> cross; // sum_k t_k D A_k T1
        Eigen::Matrix<double, LOADID_NROWS, 1> y;     // sum_k t_k D y_k
        double tt = 0;                                // sum_k t_k^2
        double k = 0;                                 // samples
        void reset() {
            cross.setZero();
            y.setZero();
            tt = k = 0;
        }
        void forget(double f) {
            cross *= f;
            y *= f;
            tt *= f;
        }
        template <class Weighted>
        void add(const Weighted &w) {
            const double tk = k * 1e-3;
            for (int r = 0; r < LOADID_NROWS; ++r) {
                for (int j = 0; j < N; ++j) cross(r, j) += tk * double(w(r, j));
                y(r) += tk * double(w(r, N));
            }
            tt += tk * tk;
            k += 1;
        }
    };
    const DriftSums &drift_sums() const { return drift_; }

  private:
    static constexpr int kWarmSteps = 4;

    // rho = v^T G v and the residual norm ||G v - rho v|| of a unit v.
    static Real rayleigh(const Eigen::Matrix<Real, N, N> &G, const Vec<N> &v, Real &rho) {
        const Vec<N> w = G.lazyProduct(v);
        rho = v.dot(w);
        return (w - rho * v).norm();
    }

    // One extreme eigenvalue (top: the largest) by shifted inverse
    // iteration from v, the shift just outside the spectrum and renewed each
    // step: sigma = rho -+ 2 ||r||. That is past the extreme eigenvalue by
    // the Kato-Temple bound (lambda_max <= rho + ||r||^2 / (rho - lambda_2))
    // once ||r|| is below the gap, so sigma I - G (or G - sigma I) is
    // positive definite and has a Cholesky factor; a shift inside the
    // spectrum shows as a failed Cholesky. A step divides the other
    // directions by about 2 ||r|| / gap, and ||r|| falls with them.
    static bool extreme(const Eigen::Matrix<Real, N, N> &G, Vec<N> &v, bool top, Real &lambda) {
        const Real tol = std::max(Real(1e-3), Real(4) * std::sqrt(kEps));
        using Mat = Eigen::Matrix<Real, N, N>;
        Real rho = 0;
        for (int k = 0;; ++k) {
            const Real r = rayleigh(G, v, rho);
            if (!(rho > 0) || !v.allFinite()) return false;
            if (r <= tol * rho) {
                lambda = rho;
                return true;
            }
            if (k == kWarmSteps) return false;
            const Real sigma = top ? rho + Real(2) * r : rho - Real(2) * r;
            Mat S = top ? Mat(sigma * Mat::Identity() - G) : Mat(G - sigma * Mat::Identity());
            if (!cholesky_solve(S, v)) return false;
            v.normalize();
        }
    }

    // S = L L^T in place (lower triangle), then v <- S^-1 v; false when S is
    // not positive definite. Written out for the compile-time N, so the
    // loops unroll: twice as quick as Eigen's LLT at N = 10.
    static bool cholesky_solve(Eigen::Matrix<Real, N, N> &S, Vec<N> &v) {
        for (int j = 0; j < N; ++j) {
            Real d = S(j, j);
            for (int k = 0; k < j; ++k) d -= S(j, k) * S(j, k);
            if (!(d > 0)) return false;
            const Real l = std::sqrt(d), inv = Real(1) / l;
            S(j, j) = l;
            for (int i = j + 1; i < N; ++i) {
                Real x = S(i, j);
                for (int k = 0; k < j; ++k) x -= S(i, k) * S(j, k);
                S(i, j) = x * inv;
            }
        }
        for (int i = 0; i < N; ++i) { // L z = v
            Real x = v(i);
            for (int k = 0; k < i; ++k) x -= S(i, k) * v(k);
            v(i) = x / S(i, i);
        }
        for (int i = N - 1; i >= 0; --i) { // L^T x = z
            Real x = v(i);
            for (int k = i + 1; k < N; ++k) x -= S(k, i) * v(k);
            v(i) = x / S(i, i);
        }
        return true;
    }

    bool warm_extremes(const Eigen::Matrix<Real, N, N> &G, Real &lmin, Real &lmax) const {
        return extreme(G, v_max_, true, lmax) && extreme(G, v_min_, false, lmin);
    }

    Vec6 d_;
    Vec<N1> t_;
    // The extreme eigenvectors of Upsilon at the last condition() call.
    mutable Vec<N> v_min_ = Vec<N>::Zero(), v_max_ = Vec<N>::Zero();
    mutable bool warm_ = false;
    Eigen::Matrix<Real, N1, N1> gram_;
    Eigen::Matrix<Real, N1, N1> gram_torque_;
    Eigen::Matrix<Real, LOADID_NROWS, N> row_sum_;
    DriftSums drift_;
};

// What an estimator hands uncertainty.hpp: the gate's matrices and sums
// (t: the column weights its estimate used), its configuration's zeroing
// and wrench-noise figures.
template <int N>
CovInput cov_input(CovKind kind, const Excitation<N> &ex, const Real *t, int64_t samples,
                   const Real *phi, const loadid_est_config_t &cfg, const Real *iv_m = nullptr,
                   const Real *iv_cc = nullptr, const double *iv_drift = nullptr,
                   const Real *iv_b = nullptr, const Real *iv_cc_torque = nullptr) {
    CovInput in{kind, N, ex.gram().data(), ex.gram_torque().data(), t, samples, phi, iv_m, iv_cc,
                ex.row_sum().data(), ex.row_weight().data(),
                N == LOADID_NPHI ? cfg.offset_cov : nullptr, cfg.noise_sigma, cfg.noise_corr,
                cfg.col_exact,
                // REFINED fits the drift itself (refined.h).
                N == LOADID_NPHI_OFFSET && cfg.method != LOADID_METHOD_REFINED
                    ? ex.drift_sums().cross.data()
                    : nullptr,
                ex.drift_sums().y.data(), ex.drift_sums().tt, iv_drift, iv_b};
    in.iv_cc_torque = iv_cc_torque;
    in.col_measured = cfg.col_measured;
    return in;
}

inline Vec6 row_weights(const loadid_est_config_t &cfg) {
    Vec6 d;
    for (int i = 0; i < 6; ++i) d(i) = Real(1) / cfg.row_sigma[i];
    return d;
}

template <int N>
inline Vec<N + 1> col_weights(const loadid_est_config_t &cfg) {
    return Eigen::Map<const Vec<N + 1>>(cfg.col_weight);
}

template <int N>
inline Vec<N + 1> col_exact(const loadid_est_config_t &cfg) {
    return Eigen::Map<const Vec<N + 1>>(cfg.col_exact);
}

// The largest noise ratio the gate lets through after samples. Pure noise
// in k samples of 6 rows has its n+1 singular values within sqrt(6k) (1 +-
// gamma), gamma = sqrt((n+1) / 6k) (the Marchenko-Pastur edge), so their
// adjacent ratio can come near 1 - 2 gamma: the weakest direction must
// stand out beyond that. RLS and RIV with forgetting remember 1 / (1 -
// lambda) samples.
template <int N>
inline Real noise_ratio_bound(const loadid_est_config_t &cfg, int64_t samples) {
    Real k = Real(samples);
    const bool forgets = cfg.method == LOADID_METHOD_RLS || cfg.method == LOADID_METHOD_RIV;
    if (forgets && cfg.forgetting < 1) k = std::min(k, Real(1) / (Real(1) - cfg.forgetting));
    const Real gamma = k > 0 ? std::sqrt(Real(N + 1) / (Real(LOADID_NROWS) * k)) : Real(1);
    return std::min(cfg.max_noise_ratio, Real(1) - Real(2) * gamma);
}

// Whether the solution itself needs the noise-ratio gate: TLS with a
// regressor column it counts as noisy has no unique solution when
// sigma_{n+1} ~ sigma_n (Golub & Van Loan), and its estimate then swings in
// every parameter. Least squares, and TLS with every regressor column
// counted exact (the mixed LS-TLS limit: least squares), are unique
// whenever the condition number passes; a direction that does not stand
// out of the noise is then only uncertain, which phi_std says
// (loadid_est_estimate_unique).
inline bool solution_needs_ratio(const loadid_est_config_t &cfg) {
    if (cfg.method != LOADID_METHOD_RTLS && cfg.method != LOADID_METHOD_TLS_BATCH) return false;
    for (int j = 0; j < LOADID_NPHI; ++j)
        if (!(cfg.col_exact[j] > 1)) return true;
    return false;
}

// The excitation gate shared by every method: fills the info fields it
// owns and returns 0 or LOADID_E_NOT_EXCITED. ratio is sigma_{n+1}/sigma_n
// of D [A y] (T / col_exact): Excitation::noise_ratio(), or RTLS's from its
// own singular values; ratio_gate false: reported, not tested.
template <int N>
inline int excitation_gate(const Excitation<N> &ex, Real ratio, const loadid_est_config_t &cfg,
                           int64_t samples, loadid_est_info_t *info, bool ratio_gate) {
    const Real kappa = ex.condition(col_exact<N>(cfg));
    if (info) {
        *info = loadid_est_info_t{};
        info->samples = samples;
        info->condition_number = kappa;
        info->noise_ratio = ratio;
    }
    if (!(kappa <= cfg.max_condition)) return LOADID_E_NOT_EXCITED;
    if (ratio_gate && cfg.max_noise_ratio < 1 && !(ratio <= noise_ratio_bound<N>(cfg, samples)))
        return LOADID_E_NOT_EXCITED;
    return 0;
}

} // namespace loadid
