// The steady-state gains of the joint filter's model (joint_filter_steady.cpp).
#pragma once

#include "loadid/joint_filter.h"

namespace loadid {

// The fixed-lag smoother's gains B_i, i = 0..lag, at a constant step dt [s]:
// B_i = P- [(F (I - K H))^T]^i H^T / s with P- the steady predicted
// covariance, K = P- H^T / s, s = H P- H^T + r (Anderson & Moore 1979,
// ch. 7, fixed-point smoothing in steady state).
void fixed_lag_gains(const loadid_jf_config_t &cfg, double dt, int lag, double gain[][3]);

}  // namespace loadid
