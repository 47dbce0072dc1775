// Row-by-row QR: folds one row into an upper-triangular R with Givens
// rotations, so R^T R = sum of x x^T without ever forming the product (which
// would square the condition number). R has the singular values and right
// singular vectors of the stacked rows (R-SVD, Golub & Van Loan 5.4.5).
#pragma once

#include <cmath>

#include "eigen_types.hpp"

namespace loadid {

template <int N1>
void givens_add_row(Eigen::Matrix<Real, N1, N1> &R, Vec<N1> x) {
    for (int j = 0; j < N1; ++j) {
        const Real b = x(j);
        if (b == Real(0)) continue;
        const Real a = R(j, j);
        // sqrt, not hypot: libm's hypot guards against overflow that weighted
        // sensor data (|x| << 1e19) cannot reach, and was a third of REFINED's
        // batch TLS.
        const Real r = std::sqrt(a * a + b * b);
        const Real c = a / r, s = b / r;
        R(j, j) = r;
        for (int k = j + 1; k < N1; ++k) {
            const Real rk = R(j, k), xk = x(k);
            R(j, k) = c * rk + s * xk;
            x(k) = c * xk - s * rk;
        }
    }
}

} // namespace loadid
