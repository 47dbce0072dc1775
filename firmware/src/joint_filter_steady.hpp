// The steady-state gains of the joint filter's model (joint_filter_steady.cpp).
#pragma once

#include "loadid/joint_filter.h"

namespace loadid {

// The fixed-lag smoother's gains B_i, i = 0..lag, at a constant step dt [s]:
// B_i = P- [(F (I - K H))^T]^i H^T / s with P- the steady predicted
// covariance, K = P- H^T / s, s = H P- H^T + r (Anderson & Moore 1979,
// ch. 7, fixed-point smoothing in steady state).
void fixed_lag_gains(const loadid_jf_config_t &cfg, double dt, int lag, double gain[][3]);

// How many updates at a constant step dt [s] after its first measurement
// the filter needs before its predicted covariance of q, qd and qdd is
// within kSettleFactor of the steady state's on each: until then its mean
// is still its prior's (qd = qdd = 0), and the fixed-lag smoother's
// steady-state gains, applied to its large innovations, amplify that
// (loadid_jf_settle_steps). At most kMaxSettle.
constexpr double kSettleFactor = 1.5;
constexpr int kMaxSettle = 10000;
int settle_steps(const loadid_jf_config_t &cfg, double dt);

} // namespace loadid
