// The SVD inside Brand's update once M has full rank: Z = [S_k L_k] of
// eq. (29), S_k diagonal (N1 x N1) with every s_i > 0, L_k = U^T N_k
// (N1 x C, C = 6 per sample: C > 6 when several samples' blocks N_k are
// taken at once, as Brand's update allows). Only its left singular vectors
// and values are needed (eq. 30).
//
// One-sided (Hestenes) Jacobi on X = Z^T, as linalg::svd_left, using Z's
// shape: after rotations V, X V = [S V; L^T V], whose upper block gives V
// back as S^-1 (S V) at the end, row by row (the rotations mix columns, so
// each row keeps its own relative accuracy). A column of the work matrix
// is [(S V)(:, j); (L^T V)(:, j); 0]. (Keeping V itself instead, the dot
// products had to weigh its rows by s_i^2: 2 % more per sample.)
//
// The pairs come in round-robin order (Brent & Luk 1985): each round's
// pairs are disjoint, so their dot products, rotation angles (divisions and
// square roots, vectorised) and rotations are independent and overlap on
// the CPU. Cyclic row order chains every rotation on the one before
// through the shared column and waits on its divisions and roots.
#pragma once

#include <algorithm>
#include <cmath>

#include "eigen_types.hpp"
#include "linalg.hpp"

namespace loadid {

// The round-robin schedule for n columns: n odd adds a column that pairs
// with nothing (its pairs are marked q = -1).
template <int N1>
struct RoundRobin {
    static constexpr int kPlayers = (N1 + 1) / 2 * 2;
    static constexpr int kRounds = kPlayers - 1;
    static constexpr int kPairs = kPlayers / 2;
    int p[kRounds][kPairs];
    int q[kRounds][kPairs];
    constexpr RoundRobin() : p{}, q{} {
        for (int r = 0; r < kRounds; ++r)
            for (int k = 0; k < kPairs; ++k) {
                // Circle method: the last player stays, the others rotate.
                const int a = (r + k) % kRounds;
                const int b = k == 0 ? kPlayers - 1 : (r + kRounds - k) % kRounds;
                p[r][k] = a < b ? a : b;
                q[r][k] = a < b ? (b < N1 ? b : -1) : a;
            }
    }
};

// Every pair of the N1 columns meets exactly once a sweep, and no column
// twice in a round.
template <int N1>
constexpr bool round_robin_is_complete() {
    constexpr RoundRobin<N1> s{};
    int met[N1][N1] = {};
    for (int r = 0; r < s.kRounds; ++r) {
        int used[N1] = {};
        for (int k = 0; k < s.kPairs; ++k) {
            if (s.q[r][k] < 0) continue;
            if (s.p[r][k] >= s.q[r][k] || used[s.p[r][k]]++ || used[s.q[r][k]]++) return false;
            ++met[s.p[r][k]][s.q[r][k]];
        }
    }
    for (int i = 0; i < N1; ++i)
        for (int j = i + 1; j < N1; ++j)
            if (met[i][j] != 1) return false;
    return true;
}

// U (N1 x N1) and sv (descending): the left singular vectors and values of
// [diag(s) L], every s_i > 0 (M of full rank: Brand's update never lowers
// a singular value). Zero columns of L change nothing.
template <int N1, int C>
void brand_jacobi(const Vec<N1> &s, const Eigen::Matrix<Real, N1, C> &L,
                  Eigen::Matrix<Real, N1, N1> &U, Vec<N1> &sv) {
    constexpr int kRows = (N1 + C + 1) / 2 * 2; // even: whole SSE packets
    using Sched = RoundRobin<N1>;
    constexpr int K = Sched::kPairs;
    using Arr = Eigen::Array<Real, K, 1>;
    static constexpr Sched sched{};
    static_assert(round_robin_is_complete<N1>(), "round-robin schedule");

    Eigen::Matrix<Real, kRows, N1> X = Eigen::Matrix<Real, kRows, N1>::Zero();
    X.template topRows<N1>().diagonal() = s;
    X.template middleRows<C>(N1) = L.transpose();

    Vec<N1> norm2;
    for (int j = 0; j < N1; ++j) norm2(j) = X.col(j).squaredNorm();
    // As svd_left: pairs closer to orthogonal than eps are left; a sweep
    // whose rotations all had |t| <= sqrt(eps / 4n) leaves off-diagonal
    // terms of order eps (quadratic convergence), so the next would rotate
    // nothing.
    const Real tol = kEps;
    const Real tiny = std::sqrt(kEps / Real(4 * N1));
    for (int sweep = 0; sweep < 60; ++sweep) {
        bool rotated = false;
        Real t_max = 0;
        for (int r = 0; r < Sched::kRounds; ++r) {
            Arr g, a, b;
            for (int k = 0; k < K; ++k) {
                const int p = sched.p[r][k], q = sched.q[r][k];
                a(k) = norm2(p);
                b(k) = q >= 0 ? norm2(q) : Real(0);
                g(k) = q >= 0 ? X.col(p).dot(X.col(q)) : Real(0);
            }
            const auto on = (a > 0) && (b > 0) && (g.abs() > tol * (a * b).sqrt());
            // The rotation that zeroes the (p, q) element of X^T X.
            const Arr zeta = (b - a) / (Real(2) * on.select(g, Arr::Ones()));
            const Arr root = (Real(1) + zeta.square()).sqrt();
            const Arr sign = (zeta >= 0).select(Arr::Ones(), -Arr::Ones());
            const Arr t = on.select(sign / (zeta.abs() + root), Arr::Zero());
            const Arr c = (Real(1) + t.square()).sqrt().inverse();
            const Arr sn = c * t;
            t_max = std::max(t_max, t.abs().maxCoeff());
            for (int k = 0; k < K; ++k) {
                if (!on(k)) continue;
                rotated = true;
                const int p = sched.p[r][k], q = sched.q[r][k];
                Real *__restrict xp = X.col(p).data();
                Real *__restrict xq = X.col(q).data();
                const Real ck = c(k), sk = sn(k);
                for (int i = 0; i < kRows; ++i) {
                    const Real u = xp[i], v = xq[i];
                    xp[i] = ck * u - sk * v;
                    xq[i] = sk * u + ck * v;
                }
                norm2(p) = a(k) - t(k) * g(k);
                norm2(q) = b(k) + t(k) * g(k);
            }
        }
        if (!rotated || t_max <= tiny) break;
        for (int j = 0; j < N1; ++j) norm2(j) = X.col(j).squaredNorm(); // refresh the running norms
    }
    for (int j = 0; j < N1; ++j) sv(j) = X.col(j).norm();
    U = s.cwiseInverse().asDiagonal() * X.template topRows<N1>();
    linalg::sort_descending(U, sv, N1);
}

} // namespace loadid
