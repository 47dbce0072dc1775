// Covariance of an estimate from the information matrix (uncertainty.hpp).
// Computed in double whatever the core's scalar: the information matrix
// squares the condition number.
#include "uncertainty.hpp"

#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace loadid {
namespace {

constexpr int kMax = LOADID_MAX_PARAMS + 1;
using Md = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMax, kMax>;
using Vd = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMax, 1>;

// The symmetric matrix from its lower triangle.
Md symmetric(const Real *lower, int n1) {
    Md g(n1, n1);
    for (int j = 0; j < n1; ++j)
        for (int i = j; i < n1; ++i) g(i, j) = g(j, i) = static_cast<double>(lower[j * n1 + i]);
    return g;
}

// Inverse of a symmetric positive definite S through its eigen-decomposition;
// false when an eigenvalue is not clearly positive.
bool spd_inverse(const Md &S, Md &inv) {
    Eigen::SelfAdjointEigenSolver<Md> es(S);
    const Vd l = es.eigenvalues();
    const double lmax = l.cwiseAbs().maxCoeff();
    if (!(l.minCoeff() > lmax * 1e-14 * S.rows())) return false;
    inv = es.eigenvectors() * l.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    return true;
}

}  // namespace

int covariance_std(const CovInput &in, Real *std, Real *scale) {
    const int n = in.n, n1 = n + 1;
    for (int i = 0; i < n; ++i) std[i] = std::numeric_limits<Real>::infinity();
    *scale = std::numeric_limits<Real>::quiet_NaN();
    const double dof = 6.0 * static_cast<double>(in.samples) - n;
    if (!(dof >= 1)) return LOADID_E_NOT_EXCITED;
    const Md gs = symmetric(in.gram, n1);  // D [A y] T, weighted and scaled
    Vd t(n1);
    for (int j = 0; j < n1; ++j) t(j) = static_cast<double>(in.t[j]);
    Vd phi(n);
    for (int j = 0; j < n; ++j) phi(j) = static_cast<double>(in.phi[j]);
    // Without the column weights: sum [A y]^T D^2 [A y].
    const Md g = t.cwiseInverse().asDiagonal() * gs * t.cwiseInverse().asDiagonal();
    Md cov(n, n);
    double s2 = 0;
    if (in.kind == CovKind::TLS) {
        // x in the scaled coordinates: D A T1 x ~ D y t_{n+1}.
        Vd x(n);
        for (int j = 0; j < n; ++j) x(j) = phi(j) * t(n) / t(j);
        Eigen::SelfAdjointEigenSolver<Md> es(gs, Eigen::EigenvaluesOnly);
        const double lmin = std::max(es.eigenvalues()(0), 0.0);
        s2 = lmin / dof;  // per-entry noise variance of the scaled data
        Md a0 = gs.topLeftCorner(n, n);
        a0.diagonal().array() -= lmin;  // A0^T A0 of the noise-free data
        Md inv;
        if (!spd_inverse(a0, inv)) return LOADID_E_NOT_EXCITED;
        const Md cx = s2 * (1.0 + x.squaredNorm()) * inv;
        const Vd back = t.head(n) / t(n);
        cov = back.asDiagonal() * cx * back.asDiagonal();
    } else {
        Vd v(n1);
        v.head(n) = phi;
        v(n) = -1;
        s2 = std::max(v.dot(g * v), 0.0) / dof;  // weighted residual / dof
        Md inv;
        if (in.kind == CovKind::LS) {
            if (!spd_inverse(g.topLeftCorner(n, n), inv)) return LOADID_E_NOT_EXCITED;
            cov = s2 * inv;
        } else {
            Md m(n, n), cc(n, n);
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    m(i, j) = static_cast<double>(in.iv_m[j * n + i]);
                    cc(i, j) = static_cast<double>(in.iv_cc[j * n + i]);
                }
            Eigen::PartialPivLU<Md> lu(m);
            const Md mi = lu.inverse();
            if (!mi.allFinite()) return LOADID_E_NOT_EXCITED;
            cov = s2 * mi * cc * mi.transpose();
        }
    }
    if (!cov.allFinite()) return LOADID_E_NOT_EXCITED;
    for (int i = 0; i < n; ++i) std[i] = static_cast<Real>(std::sqrt(std::max(cov(i, i), 0.0)));
    *scale = static_cast<Real>(std::sqrt(s2));
    return 0;
}

}  // namespace loadid
