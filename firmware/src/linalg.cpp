// One instantiation of each decomposition (linalg.hpp).
#include "linalg.hpp"

#include <algorithm>
#include <cmath>

namespace loadid {
namespace linalg {

// One-sided (Hestenes) Jacobi on X = M^T: rotate pairs of columns of X
// (rows of M) until all are orthogonal; the accumulated rotation V holds
// the left singular vectors of M, the column norms its singular values.
// Relative accuracy like two-sided Jacobi (Demmel & Veselic 1992); here M is
// Z = [S L] of eq. (29), whose rows are nearly orthogonal already, so a few
// sweeps converge, and every rotation runs over contiguous columns.
void svd_left(const Work &M, Square &U, Values &s) {
    const int m = static_cast<int>(M.cols()), n = static_cast<int>(M.rows());
    Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxCols, kMaxDim> X =
        M.transpose();
    Square V = Square::Identity(n, n);
    Values norm2(n);
    for (int j = 0; j < n; ++j) norm2(j) = X.col(j).squaredNorm();
    const Real tol = kEps;
    // A sweep whose rotations all had |t| <= tiny leaves off-diagonal terms
    // of X^T X of order n t^2 <= eps / 4 of the norms (quadratic
    // convergence of cyclic Jacobi): the next sweep would rotate nothing.
    const Real tiny = std::sqrt(kEps / Real(4 * n));
    for (int sweep = 0; sweep < 60; ++sweep) {
        bool rotated = false;
        Real t_max = 0;
        for (int p = 0; p < n - 1; ++p) {
            for (int q = p + 1; q < n; ++q) {
                const Real a = norm2(p), b = norm2(q);
                if (!(a > 0) || !(b > 0)) continue;
                Real *xp = X.col(p).data(), *xq = X.col(q).data();
                // Four partial sums: one chain of m dependent additions
                // was the latency of every pair.
                Real g0 = 0, g1 = 0, g2 = 0, g3 = 0;
                int k = 0;
                for (; k + 4 <= m; k += 4) {
                    g0 += xp[k] * xq[k];
                    g1 += xp[k + 1] * xq[k + 1];
                    g2 += xp[k + 2] * xq[k + 2];
                    g3 += xp[k + 3] * xq[k + 3];
                }
                for (; k < m; ++k) g0 += xp[k] * xq[k];
                const Real g = (g0 + g1) + (g2 + g3);
                if (!(std::abs(g) > tol * std::sqrt(a * b))) continue;
                rotated = true;
                // The rotation that zeroes the (p, q) element of X^T X.
                const Real zeta = (b - a) / (Real(2) * g);
                const Real t = (zeta >= 0 ? Real(1) : Real(-1)) /
                               (std::abs(zeta) + std::sqrt(Real(1) + zeta * zeta));
                const Real c = Real(1) / std::sqrt(Real(1) + t * t), sn = c * t;
                t_max = std::max(t_max, std::abs(t));
                for (int i = 0; i < m; ++i) {
                    const Real u = xp[i], v = xq[i];
                    xp[i] = c * u - sn * v;
                    xq[i] = sn * u + c * v;
                }
                Real *vp = V.col(p).data(), *vq = V.col(q).data();
                for (int i = 0; i < n; ++i) {
                    const Real u = vp[i], v = vq[i];
                    vp[i] = c * u - sn * v;
                    vq[i] = sn * u + c * v;
                }
                norm2(p) = a - t * g;
                norm2(q) = b + t * g;
            }
        }
        if (!rotated || t_max <= tiny) break;
        for (int j = 0; j < n; ++j) norm2(j) = X.col(j).squaredNorm(); // refresh the running norms
    }
    s.resize(n);
    for (int j = 0; j < n; ++j) s(j) = X.col(j).norm();
    U = V;
    sort_descending(U, s, n);
}

void sym_eigenvalues(const Square &G, Values &lambda) {
    const Eigen::SelfAdjointEigenSolver<Square> es(G, Eigen::EigenvaluesOnly);
    lambda = es.eigenvalues();
}

void sym_eigen(const Square &G, Square &V, Values &lambda) {
    const Eigen::SelfAdjointEigenSolver<Square> es(G, Eigen::ComputeEigenvectors);
    V = es.eigenvectors();
    lambda = es.eigenvalues();
}

void householder_q(const Square &A, Square &Q, Values &r_diag) {
    const Eigen::HouseholderQR<Square> qr(A);
    Q = qr.householderQ();
    r_diag = qr.matrixQR().diagonal();
}

void colpiv_qr(const Tall &H, Square &Q, Tall &R, Eigen::Matrix<int, LOADID_NROWS, 1> &perm) {
    const Eigen::ColPivHouseholderQR<Tall> qr(H);
    Q = qr.householderQ();
    R = qr.matrixQR().triangularView<Eigen::Upper>();
    perm = qr.colsPermutation().indices();
}

} // namespace linalg
} // namespace loadid
