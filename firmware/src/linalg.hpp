// The dense decompositions the estimators need, each instantiated once per
// scalar in linalg.cpp on a matrix type bounded by the largest problem
// (n + 1 = 17 rows, 17 + 6 columns). Eigen's SVD, QR and eigen-solvers cost
// about ten seconds of compile time per instantiation; sharing one keeps
// the core quick to build, and bounded storage keeps it off the heap.
#pragma once

#include <utility>

#include "eigen_types.hpp"

namespace loadid {
namespace linalg {

inline constexpr int kMaxDim = LOADID_MAX_PARAMS + 1;   // rows: n + 1
inline constexpr int kMaxCols = kMaxDim + LOADID_NROWS; // columns of Z, eq. (29)

using Work = BoundedMat<kMaxDim, kMaxCols>;
using Square = BoundedMat<kMaxDim, kMaxDim>;
using Tall = BoundedMat<kMaxDim, LOADID_NROWS>;
using Values = Eigen::Matrix<Real, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxDim, 1>;

// Orders the first n values s descending, and the columns of U with them
// (selection sort: n <= 17).
template <class Mat, class Vals>
void sort_descending(Mat &U, Vals &s, int n) {
    for (int j = 0; j < n - 1; ++j) {
        int best = j;
        for (int k = j + 1; k < n; ++k)
            if (s(k) > s(best)) best = k;
        if (best != j) {
            std::swap(s(j), s(best));
            U.col(j).swap(U.col(best));
        }
    }
}

// M (rows <= cols) = U S V^T: U (rows x rows) and the singular values in
// descending order (rows of them). V is not computed (eq. 30 needs U only).
void svd_left(const Work &M, Square &U, Values &s);

// Eigenvalues of the symmetric G, ascending.
void sym_eigenvalues(const Square &G, Values &lambda);

// Eigenvalues (ascending) and eigenvectors (columns, in that order) of the
// symmetric G.
void sym_eigen(const Square &G, Square &V, Values &lambda);

// A (rows x cols, rows >= cols) = Q R by Householder: the full Q
// (rows x rows) and the diagonal of R.
void householder_q(const Square &A, Square &Q, Values &r_diag);

// Rank-revealing QR with column pivoting, H P = Q R (Businger-Golub): the
// full Q (rows x rows), R (upper triangle, rows x 6) and P's indices.
void colpiv_qr(const Tall &H, Square &Q, Tall &R, Eigen::Matrix<int, LOADID_NROWS, 1> &perm);

} // namespace linalg
} // namespace loadid
