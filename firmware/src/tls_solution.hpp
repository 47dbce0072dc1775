// The TLS estimate from an orthonormal basis of right singular vectors of
// D [A y] T (the left singular vectors of its transpose M, eq. 24), sorted
// by descending singular value: the Householder step for a repeated
// smallest singular value and eq. (36). Shared by RTLS and batch TLS.
#pragma once

#include <cmath>

#include "eigen_types.hpp"

namespace loadid {

template <int N>
struct TlsSolution {
    Vec<N> phi;
    int multiplicity; // p: how many singular values equal the smallest
    int status;       // 0 or LOADID_E_NO_SOLUTION
};

// W: (N+1) x (N+1) orthonormal, columns by descending s; t: column weights.
// Singular values within tol * s(0) of the smallest count as equal.
template <int N>
TlsSolution<N> tls_solution(const Eigen::Matrix<Real, N + 1, N + 1> &W, const Vec<N + 1> &s,
                            const Vec<N + 1> &t, Real tol) {
    constexpr int N1 = N + 1;
    TlsSolution<N> out;
    out.phi.setZero();
    const Real smin = s(N);
    int p = 1;
    while (p < N1 && s(N - p) - smin <= tol * s(0)) ++p;
    out.multiplicity = p;

    Vec<N1> w;
    if (p == 1) {
        w = W.col(N);
    } else {
        // Golub & Van Loan (TLS, non-unique case): a Householder H with
        // z H = [0 ... 0 -+|z|], z the last row of the p trailing columns,
        // so W2 H has zeros in the first p-1 elements of its last row; its
        // last column gives the minimum-norm TLS solution.
        const auto W2 = W.rightCols(p);
        Eigen::Matrix<Real, 1, Eigen::Dynamic, Eigen::RowMajor, 1, N1> z = W2.row(N);
        const Real zn = z.norm();
        if (!(zn > Real(0))) {
            out.status = LOADID_E_NO_SOLUTION;
            return out;
        }
        Eigen::Matrix<Real, Eigen::Dynamic, 1, 0, N1, 1> v = z.transpose();
        v(p - 1) += (z(p - 1) >= 0 ? zn : -zn);
        const Real vv = v.squaredNorm();
        // Last column of H = I - 2 v v^T / v^T v.
        Eigen::Matrix<Real, Eigen::Dynamic, 1, 0, N1, 1> hp = -Real(2) * v * v(p - 1) / vv;
        hp(p - 1) += Real(1);
        w = W2 * hp;
    }
    // Eq. (36): phi_i = -t_i w_i / (t_{n+1} w_{n+1}); needs w_{n+1} != 0.
    if (!(std::abs(w(N)) > Real(16) * kEps)) {
        out.status = LOADID_E_NO_SOLUTION;
        return out;
    }
    out.phi = -(t.template head<N>().cwiseProduct(w.template head<N>())) / (t(N) * w(N));
    out.status = out.phi.allFinite() ? 0 : LOADID_E_NO_SOLUTION;
    if (out.status) out.phi.setZero();
    return out;
}

} // namespace loadid
