// Fixed-size Eigen types of the core. Every matrix here has a size known at
// compile time (or a compile-time maximum), so nothing touches the heap.
#pragma once

#include <Eigen/Dense>

#include "loadid/types.h"

namespace loadid {

using Real = loadid_real_t;

template <int R, int C>
using Mat = Eigen::Matrix<Real, R, C, (C == 1 && R != 1) ? Eigen::ColMajor : Eigen::RowMajor>;
template <int R>
using Vec = Eigen::Matrix<Real, R, 1>;
using Vec3 = Vec<3>;
using Mat3 = Eigen::Matrix<Real, 3, 3>;
using Vec6 = Vec<6>;

// A regressor of N columns as the C API stores it: row-major, 6 x N.
template <int N>
using Regressor = Eigen::Matrix<Real, LOADID_NROWS, N, Eigen::RowMajor>;

template <int N>
using ConstRegressorMap = Eigen::Map<const Regressor<N>>;

inline constexpr Real kEps = Eigen::NumTraits<Real>::epsilon();

}  // namespace loadid
