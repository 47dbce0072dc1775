// The joint stamps regularised (signals.h, stamp_gain): a controller that
// samples on its cycle and stamps on arrival gives positions at a fixed
// rate under jittered stamps, and the filters must see the rate.
//
// Locked, a second-order phase-locked loop: t = t_pred + g (t_raw - t_pred),
// the period tracked with gain g^2 / 4 (critically damped). Such a loop
// pulls in only a period error small against g: started from one
// jittered interval (or a period measured 8 % off), 200 us of jitter
// threw it out of lock on nearly every stamp, the filters saw the raw
// stamps, and the on-line estimates lost 28-72 % of the mass on slow
// motion. So it first acquires: a least-squares line through the stamps
// since (re)start, t = a + b i (i counts periods, a lost message one
// more), whose gains (about 4 / n for the phase) fall to the loop's g at
// n = 4 / g stamps, where the loop takes over from the line. A stamp more
// than half a period off the prediction (a bunched message, another
// rate) restarts the acquisition there.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace loadid {

class StampClock {
  public:
    void reset() { s_.last_raw = INT64_MIN; }

    // The newest stamp taken (INT64_MIN: none) and the period now.
    int64_t last_raw() const { return s_.last_raw; }
    double period() const { return s_.period; }

    // The time to use for t_raw; nominal: the period to start from [us]
    // (the filters'). The clock takes the stamp only at commit(), once the
    // filters have. gain >= 1: the stamps as they are, nothing kept.
    int64_t propose(int64_t t_raw, double nominal, double gain) {
        next_ = s_;
        if (gain >= 1) return t_raw;
        State &s = next_;
        if (s.last_raw == INT64_MIN) {
            start(s, t_raw, nominal);
        } else if (s.n > 0) {
            acquire(s, t_raw, gain);
        } else {
            track(s, t_raw, gain);
        }
        s.last_raw = t_raw;
        return int64_t(std::llround(s.t));
    }
    void commit() { s_ = next_; }

  private:
    struct State {
        double t = 0, period = 0; // the last regularised time, the period [us]
        int64_t last_raw = INT64_MIN;
        // Acquisition (n > 0 stamps on the line; 0: locked): periods since
        // t0, and the running means and co-moments of (i, t - t0).
        int64_t n = 0, t0 = 0;
        double i = 0, mean_i = 0, mean_t = 0, c_ii = 0, c_it = 0;
    };
    static constexpr int64_t kMaxAcquire = 1000000;

    static void start(State &s, int64_t t_raw, double period) {
        s.t = double(t_raw);
        s.period = period;
        s.n = 1;
        s.t0 = t_raw;
        s.i = s.mean_i = s.mean_t = s.c_ii = s.c_it = 0;
    }

    static void acquire(State &s, int64_t t_raw, double gain) {
        const double interval = double(t_raw - s.last_raw);
        double k = s.period > 0 ? std::round(interval / s.period) : 0;
        // The first interval whole periods off the nominal one is a stream
        // at another rate (a 250 Hz stream for filters set for 1 kHz), not
        // lost messages: its period is that interval.
        if (s.n == 1 && k >= 2) {
            s.period = interval;
            k = 1;
        }
        if (!(k >= 1) || std::abs(double(t_raw) - (s.t + k * s.period)) > 0.5 * s.period) {
            start(s, t_raw, s.period > 0 ? s.period : double(t_raw - s.last_raw));
            return;
        }
        // Welford's update of the means and co-moments.
        s.i += k;
        const double y = double(t_raw - s.t0);
        ++s.n;
        const double di = s.i - s.mean_i;
        s.mean_i += di / double(s.n);
        s.mean_t += (y - s.mean_t) / double(s.n);
        s.c_ii += di * (s.i - s.mean_i);
        s.c_it += di * (y - s.mean_t);
        const double b = s.c_it / s.c_ii;
        s.period = b;
        s.t = double(s.t0) + s.mean_t + b * (s.i - s.mean_i);
        const double lock = std::min(std::ceil(4 / gain), double(kMaxAcquire));
        if (double(s.n) >= lock) s.n = 0;
    }

    static void track(State &s, int64_t t_raw, double g) {
        const double pred = s.t + s.period;
        const double err = double(t_raw) - pred;
        // Lost messages: the stamp lands k whole periods on, no new rate.
        const double k = std::round((double(t_raw) - s.t) / s.period);
        const double err_k = double(t_raw) - (s.t + k * s.period);
        if (std::abs(err) <= 0.5 * s.period) {
            s.t = pred + g * err;
            s.period += g * g / 4 * err;
        } else if (k >= 2 && std::abs(err_k) <= 0.25 * s.period) {
            s.t = s.t + k * s.period + g * err_k;
            s.period += g * g / 4 * err_k / k;
        } else {
            start(s, t_raw, s.period);
        }
    }

    State s_, next_;
};

} // namespace loadid
