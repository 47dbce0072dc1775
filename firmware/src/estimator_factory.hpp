// Constructors of each method for N = 10 and 16, one translation unit per
// method (rls.cpp, rtls.cpp, batch.cpp) so they compile in parallel.
// Each returns nullptr when out of memory.
#pragma once

#include "estimator_base.hpp"

namespace loadid {

template <int N>
loadid_est *make_recursive_ls(const loadid_est_config_t &c);
template <int N>
loadid_est *make_rtls(const loadid_est_config_t &c);
template <int N>
loadid_est *make_batch(const loadid_est_config_t &c);

} // namespace loadid
