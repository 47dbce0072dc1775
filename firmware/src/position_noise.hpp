// The joint positions' own noise, measured from the stream: the fourth
// difference of consecutive states, d = q0 - 4 q1 + 6 q2 - 4 q3 + q4,
// takes out the motion (its share, q'''' dt^4, is some 1e-12 rad at 1 kHz)
// and leaves white noise of std s at variance 70 s^2. An encoder's
// quantisation step h moving through several steps a state gives
// h / sqrt(12); the joint filters assume kalman.meas_sigma, and a stream
// much noisier than that (a coarser encoder) reaches a - g, omega and
// alpha uncounted. A step over 1.5 periods (a lost state) starts the
// differences again, and so does a refused state (gap()). No allocation.
#pragma once

#include <cmath>
#include <cstdint>

#include "loadid/chain.h"

namespace loadid {

class PositionNoise {
  public:
    void reset() {
        have_ = 0, count_ = 0, last_ = INT64_MIN;
        for (double &v : sum_) v = 0;
    }

    void add(int64_t t_us, const loadid_real_t *q, int n, int64_t period_us) {
        if (last_ != INT64_MIN && period_us > 0 && 2 * (t_us - last_) > 3 * period_us) have_ = 0;
        last_ = t_us;
        for (int k = kDepth - 1; k > 0; --k)
            for (int j = 0; j < n; ++j) hist_[k][j] = hist_[k - 1][j];
        for (int j = 0; j < n; ++j) hist_[0][j] = double(q[j]);
        if (have_ < kDepth) ++have_;
        if (have_ < kDepth) return;
        for (int j = 0; j < n; ++j) {
            const double d =
                hist_[0][j] - 4 * hist_[1][j] + 6 * hist_[2][j] - 4 * hist_[3][j] + hist_[4][j];
            sum_[j] += d * d;
        }
        ++count_;
        n_ = n;
    }

    int64_t count() const { return count_; } // differences since reset

    // A state left out (refused): the differences start again after it.
    void gap() { have_ = 0; }

    // The largest joint's std [rad or m]; 0 with fewer than kMinCount.
    double sigma() const {
        if (count_ < kMinCount) return 0;
        double worst = 0;
        for (int j = 0; j < n_; ++j) worst = std::fmax(worst, sum_[j]);
        return std::sqrt(worst / (70.0 * double(count_)));
    }

  private:
    static constexpr int kDepth = 5, kMinCount = 16;
    double hist_[kDepth][LOADID_MAX_JOINTS] = {};
    double sum_[LOADID_MAX_JOINTS] = {};
    int have_ = 0, n_ = 0;
    int64_t count_ = 0, last_ = INT64_MIN;
};

} // namespace loadid
