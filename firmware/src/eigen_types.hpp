// Fixed-size Eigen types of the core. Every matrix here has a size known at
// compile time (or a compile-time maximum), so nothing touches the heap.
#pragma once

#include <Eigen/Dense>

#include "loadid/types.h"

namespace loadid {

using Real = loadid_real_t;

// A matrix whose size is set at run time but bounded at compile time: its
// storage is inline (no heap), and Eigen does not unroll its loops, which
// keeps the SVD and QR of the larger matrices quick to compile.
template <int MaxR, int MaxC>
using BoundedMat = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, MaxR, MaxC>;
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

// Products on the per-sample path are written a.lazyProduct(b): Eigen sends
// a fixed-size product whose three sizes add up to 20 or more (11x11 by
// 11x6, 10x6 by 6x10) to its blocked GEMM kernel, whose packing costs more
// than the product at these sizes; the coefficient-wise product is
// unrolled and vectorised instead (RTLS + RLS + RIV per sample: 1.5x faster
// in bench_pipeline).
inline constexpr Real kEps = Eigen::NumTraits<Real>::epsilon();

} // namespace loadid
