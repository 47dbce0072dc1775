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
#include <type_traits>
#if defined(__x86_64__)
#include <immintrin.h>
#endif

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

// Column operations on a work matrix of R rows (column major), portable:
// Eigen's packets (SSE2 on x86-64).
struct JacobiColumnsPortable {
    static constexpr int kRowMultiple = 2;
    template <int R>
    static Real dot(const Real *a, const Real *b) {
        return Eigen::Map<const Vec<R>>(a).dot(Eigen::Map<const Vec<R>>(b));
    }
    template <int R>
    static void rotate(Real *__restrict xp, Real *__restrict xq, Real c, Real s) {
        for (int i = 0; i < R; ++i) {
            const Real u = xp[i], v = xq[i];
            xp[i] = c * u - s * v;
            xq[i] = s * u + c * v;
        }
    }
};

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define LOADID_JACOBI_AVX2 1
// The same with 256-bit AVX2/FMA packets (R a multiple of 4), chosen at run
// time: the Jacobi is most of RTLS's per-sample cost, and 4 doubles a packet
// halve its instructions where the CPU has them.
struct JacobiColumnsAvx2 {
    static constexpr int kRowMultiple = 4;
    template <int R>
    [[gnu::target("avx2,fma")]] static double dot(const double *a, const double *b) {
        __m256d acc = _mm256_mul_pd(_mm256_load_pd(a), _mm256_load_pd(b));
        for (int i = 4; i < R; i += 4)
            acc = _mm256_fmadd_pd(_mm256_load_pd(a + i), _mm256_load_pd(b + i), acc);
        const __m128d h = _mm_add_pd(_mm256_castpd256_pd128(acc), _mm256_extractf128_pd(acc, 1));
        return _mm_cvtsd_f64(_mm_add_sd(h, _mm_unpackhi_pd(h, h)));
    }
    template <int R>
    [[gnu::target("avx2,fma")]] static void rotate(double *__restrict xp, double *__restrict xq,
                                                   double c, double s) {
        const __m256d vc = _mm256_set1_pd(c), vs = _mm256_set1_pd(s);
        for (int i = 0; i < R; i += 4) {
            const __m256d u = _mm256_load_pd(xp + i), v = _mm256_load_pd(xq + i);
            _mm256_store_pd(xp + i, _mm256_fmsub_pd(vc, u, _mm256_mul_pd(vs, v)));
            _mm256_store_pd(xq + i, _mm256_fmadd_pd(vs, u, _mm256_mul_pd(vc, v)));
        }
    }
};

// The CPU has AVX2 and FMA, and LOADID_JACOBI_KERNEL does not ask for the
// portable kernel; set once at start-up (jacobi_kernel.cpp), so the
// per-sample path tests a constant.
extern const bool kJacobiAvx2;
#endif

// The Jacobi itself, on the column operations Ops (inlined into each
// caller, so that it is compiled for that caller's instruction set).
template <class Ops, int N1, int C>
[[gnu::always_inline]] inline void brand_jacobi_on(const Vec<N1> &s,
                                                   const Eigen::Matrix<Real, N1, C> &L,
                                                   Eigen::Matrix<Real, N1, N1> &U, Vec<N1> &sv) {
    constexpr int M = Ops::kRowMultiple;
    constexpr int kRows = (N1 + C + M - 1) / M * M; // whole packets
    using Sched = RoundRobin<N1>;
    constexpr int K = Sched::kPairs;
    using Arr = Eigen::Array<Real, K, 1>;
    static constexpr Sched sched{};
    static_assert(round_robin_is_complete<N1>(), "round-robin schedule");

    // 32-byte aligned columns (kRows * 8 bytes is a multiple of 32 for AVX2).
    alignas(32) Real X[N1][kRows] = {};
    for (int j = 0; j < N1; ++j) {
        X[j][j] = s(j);
        for (int i = 0; i < C; ++i) X[j][N1 + i] = L(j, i);
    }

    Vec<N1> norm2;
    for (int j = 0; j < N1; ++j) norm2(j) = Ops::template dot<kRows>(X[j], X[j]);
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
                g(k) = q >= 0 ? Ops::template dot<kRows>(X[p], X[q]) : Real(0);
            }
            const auto on = (a > 0) && (b > 0) && (g.abs() > tol * (a * b).sqrt());
            // The rotation that zeroes the (p, q) element of X^T X, t = tan
            // of its angle: Rutishauser's t = sign(zeta) / (|zeta| +
            // sqrt(1 + zeta^2)), zeta = d / h, d = b - a, h = 2 g, times |h|
            // above and below: t = sign(d) h / w, w = |d| + sqrt(d^2 + h^2),
            // and c = w / sqrt(w^2 + h^2), s = t c. Two square roots and a
            // division in a row, where the quotient form chains three
            // divisions and two roots: each round waits on them.
            const Arr d = b - a;
            const Arr h = on.select(Real(2) * g, Arr::Zero());
            const Arr sh = (d >= 0).select(h, -h);
            const Arr w = d.abs() + (d.square() + h.square()).sqrt();
            const Arr inv_q = (w.square() + h.square()).sqrt().inverse();
            const Arr c = w * inv_q;
            const Arr sn = sh * inv_q;
            const Arr t = sh / w;
            t_max = std::max(t_max, t.abs().maxCoeff());
            for (int k = 0; k < K; ++k) {
                if (!on(k)) continue;
                rotated = true;
                const int p = sched.p[r][k], q = sched.q[r][k];
                Ops::template rotate<kRows>(X[p], X[q], c(k), sn(k));
                norm2(p) = a(k) - t(k) * g(k);
                norm2(q) = b(k) + t(k) * g(k);
            }
        }
        if (!rotated || t_max <= tiny) break;
        for (int j = 0; j < N1; ++j)
            norm2(j) = Ops::template dot<kRows>(X[j], X[j]); // refresh the running norms
    }
    const Vec<N1> inv_s = s.cwiseInverse();
    for (int j = 0; j < N1; ++j) {
        sv(j) = std::sqrt(Ops::template dot<kRows>(X[j], X[j]));
        for (int i = 0; i < N1; ++i) U(i, j) = inv_s(i) * X[j][i];
    }
    linalg::sort_descending(U, sv, N1);
}

#ifdef LOADID_JACOBI_AVX2
template <int N1, int C>
[[gnu::target("avx2,fma")]] void brand_jacobi_avx2(const Vec<N1> &s,
                                                   const Eigen::Matrix<Real, N1, C> &L,
                                                   Eigen::Matrix<Real, N1, N1> &U, Vec<N1> &sv) {
    brand_jacobi_on<JacobiColumnsAvx2, N1, C>(s, L, U, sv);
    // Clean upper halves before the SSE code that follows: without it this
    // CPU ran every later SSE2 routine (RLS, the batch) 1.5-2.5x slower.
    _mm256_zeroupper();
}
#endif

// U (N1 x N1) and sv (descending): the left singular vectors and values of
// [diag(s) L], every s_i > 0 (M of full rank: Brand's update never lowers
// a singular value). Zero columns of L change nothing.
template <int N1, int C>
void brand_jacobi(const Vec<N1> &s, const Eigen::Matrix<Real, N1, C> &L,
                  Eigen::Matrix<Real, N1, N1> &U, Vec<N1> &sv) {
#ifdef LOADID_JACOBI_AVX2
    if constexpr (std::is_same<Real, double>::value) {
        if (kJacobiAvx2) {
            brand_jacobi_avx2<N1, C>(s, L, U, sv);
            return;
        }
    }
#endif
    brand_jacobi_on<JacobiColumnsPortable, N1, C>(s, L, U, sv);
}

} // namespace loadid
