// Rejection of NaN and Inf at the API boundary: the core never lets a
// non-finite value into its state.
#pragma once

#include <cmath>

#include "loadid/types.h"

namespace loadid {

template <typename T>
inline bool all_finite(const T *v, int n) {
    for (int i = 0; i < n; ++i) {
        if (!std::isfinite(v[i])) return false;
    }
    return true;
}

} // namespace loadid
