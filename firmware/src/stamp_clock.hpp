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
// n = 4 / g stamps, where the loop takes over from the line. A second
// stamp under half a period after the first (a bunched message) starts
// the acquisition again there; a first interval of kOtherRate periods or
// more is another rate. The periods a stamp is counted
// as are those from the line's own time for the last stamp (at first the
// period the clock started from, from kStampSlopeFrom stamps on the line's
// slope): counted from the raw interval, a jitter over a quarter period
// made an interval round to 0 or 2 every few dozen stamps, each restarted
// the acquisition, the loop never locked, and with 300-500 us of jitter at
// 1 kHz the on-line estimates lost 20-65 % of the mass.
//
// A later stamp more than half a period off the next period that is no
// clean lost message (whole periods on, within a quarter period) is an
// outlier (next()): a message delayed or bunched in transport, stamped on
// arrival. It is taken as the next period, at the line's or loop's time,
// which it leaves alone (but onto a line of under kStampSlopeFrom stamps,
// whose time is as jittered as they are); only kRestartAfter of them in a
// row (a stream that moved) start the clock again (restarts()). Restarted
// from each such stamp, the line began at a delayed one: 80 us of
// exponential transport delay at 1 kHz restarted it once in the window and
// cost the on-line estimates 3 % of the mass, 100 us 17 %.
//
// A stamp over 1.5 periods past the last time (far()) is lost messages, a
// message delayed, or the first of a burst (a stall, then the held
// messages at once); only the stamps after it tell which: a loss moves
// every later stamp on by a period, a delay or a burst does not. So the
// caller holds it and those after it (up to kLookAhead) and counts it by
// count_ahead(), from the earliest of their offsets (delays are
// one-sided). Counted from the stamp alone, one delayed 0.75-1.25 periods
// passed for a lost message, every later stamp was then a period early,
// and three such outliers restarted the clock: at 150 us of mean delay it
// restarted in the window (RTLS 39 % off), and a 5 ms stall every time.
//
// Jitter of 0.7-0.95 of a period (uniform; a stream stamped on arrival by
// a busy host) makes a third to half of the stamps outliers or held off.
// Left off the line while it acquires, they cut its stamps' spread at
// half a period and the line drifted from the stream a period in some
// tens of stamps: it restarted on nearly every draw, or locked on a grid
// with a period inserted every 10-70 stamps, and the on-line estimates
// were 19-59 % off in mass (3 of 4 slow-motion draws at 800 us, flagged).
// Once the stream's outlier rate is over kJitterRate, the line takes them
// too (at the next period), and a lost message is counted only when every
// one of the kLookAhead held stamps says so: 4 of 16 within a quarter
// period of 2 periods came about by chance, and such a count, a period
// the joints never stood still, put them 4-39 % off, claimed (950 us).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace loadid {

// Welford's least-squares line through points (i, y): running means and
// co-moments, and the residual sum of squares.
struct StampLine {
    int n = 0;
    double mean_i = 0, mean_t = 0, c_ii = 0, c_it = 0, c_tt = 0;
    void add(double i, double y) {
        const double di = i - mean_i, dy = y - mean_t;
        ++n;
        mean_i += di / n;
        mean_t += dy / n;
        c_ii += di * (i - mean_i);
        c_it += di * (y - mean_t);
        c_tt += dy * (y - mean_t);
    }
    double slope() const { return c_it / c_ii; }
    double at(double i) const { return mean_t + slope() * (i - mean_i); }
    double rms() const { return std::sqrt(std::max(c_tt - c_it * c_it / c_ii, 0.0) / n); }
};

// Stamps on a line before its slope, not the period it started from,
// counts their periods.
constexpr int kStampSlopeFrom = 8;

// Whole periods p from a stamp's predecessor dt before it: the nearest
// count, so the stamp lies within half a period of it; under 1 (NaN for a
// period not known) a bunched stamp that fits no count.
inline double periods_on(double dt, double p) {
    return p > 0 ? std::round(dt / p) : std::numeric_limits<double>::quiet_NaN();
}

// The periods a stamp dt after its predecessor's time lies on (period p):
// 1 within half a period of the next; k >= 2 within a quarter period of k
// periods on (k - 1 lost messages); 0 for an outlier (neither: a message
// delayed or bunched in transport).
inline double periods_of(double dt, double p) {
    if (!(p > 0)) return 0;
    if (std::abs(dt - p) <= 0.5 * p) return 1;
    const double k = periods_on(dt, p);
    return k >= 2 && std::abs(dt - k * p) <= 0.25 * p ? k : 0;
}

class StampClock {
  public:
    void reset() { s_.last_raw = INT64_MIN, s_.restarts = 0, s_.outlier_rate = 0, s_.rated = 0; }

    // The newest stamp taken (INT64_MIN: none) and the period now.
    int64_t last_raw() const { return s_.last_raw; }
    double period() const { return s_.period; }
    // Times the clock started again since reset(): kRestartAfter outliers
    // in a row, a bunched second stamp, held stamps no count fits
    // (count_ahead), or kRestartHeldOff counted ones off in a row.
    int64_t restarts() const { return s_.restarts; }
    // Taking the stamps from their line: not locked yet (since start or
    // the last restart).
    bool acquiring() const { return s_.last_raw != INT64_MIN && s_.acquiring; }

    // Stamps held to count one by those after it (far, count_ahead), and
    // those that confirm lost messages sooner.
    static constexpr int kLookAhead = 16;
    static constexpr int kConfirm = 4;

    // Is t_raw over 1.5 periods past the last time (lost messages, or a
    // delay or a burst), to be counted by the stamps after it? Not before
    // the line has two stamps (its second interval tells the rate), nor
    // with gain >= 1.
    bool far(int64_t t_raw, double gain) const {
        if (gain >= 1 || s_.last_raw == INT64_MIN || (s_.acquiring && s_.line.n < 2)) return false;
        return double(t_raw) - s_.t > 1.5 * counting_period(s_);
    }

    // The periods the first of the held stamps r[0..n) lies on after the
    // last time, from their offsets r[j] - t - j periods (each later
    // stamp's moved back to the first; a delay only adds): 1 once the
    // earliest is within 1.5 periods (no later stamp can undo it: a delay,
    // or a burst, whose offsets fall a period a stamp); k >= 2 once
    // kConfirm of them lie within a quarter period of k periods on and none
    // before (k - 1 lost messages: every later stamp moved on); else 0
    // (not decided) until full (kLookAhead held: kNoFit, no count fits,
    // the stream moved) or ended (the stream stalled: k, the time it
    // stopped was real; taken as 1, the first state after a 50 ms stall
    // put the clock 49 periods behind until it restarted). Counted by the
    // offsets' median when full, a stream under 450 us of jitter at 1 kHz
    // lost a period every 50 stamps to a line that fell 2 % short. The
    // period is the one stamps are counted with (counting_period): the
    // probed one, 1.1 % off, miscounted an 80 ms stall by a period.
    int count_ahead(const int64_t *r, int n, bool full, bool ended) const {
        const double p = counting_period(s_);
        double earliest = std::numeric_limits<double>::infinity();
        for (int j = 0; j < n; ++j) earliest = std::min(earliest, double(r[j]) - s_.t - j * p);
        if (earliest <= 1.5 * p) return 1;
        const double k = std::min(periods_on(earliest, p), double(kMaxCount));
        int near = 0;
        for (int j = 0; j < n; ++j)
            near += std::abs(double(r[j]) - s_.t - j * p - k * p) <= 0.25 * p;
        // Under heavy jitter kConfirm near ones are chance.
        if (near >= kConfirm && earliest >= (k - 0.25) * p && (full || ended || !jittery(s_)))
            return int(k);
        return full ? kNoFit : ended ? int(k) : 0;
    }
    static constexpr int kNoFit = -1;

    // The time to use for t_raw; nominal: the period to start from [us]
    // (the filters'); counted: its periods after the last time as
    // count_ahead() found them (0: from the stamp alone; kNoFit: start
    // again from it). The clock takes the stamp only at commit(), once the
    // filters have. gain >= 1: the stamps as they are, nothing kept.
    int64_t propose(int64_t t_raw, double nominal, double gain, int counted = 0) {
        next_ = s_;
        if (gain >= 1) return t_raw;
        State &s = next_;
        if (s.last_raw == INT64_MIN) {
            start(s, t_raw, nominal);
        } else if (s.acquiring) {
            acquire(s, t_raw, nominal, gain, counted);
        } else {
            track(s, t_raw, gain, counted);
        }
        s.last_raw = t_raw;
        return int64_t(std::llround(s.t));
    }
    void commit() { s_ = next_; }

  private:
    struct State {
        double t = 0, period = 0; // the last regularised time, the period [us]
        int64_t last_raw = INT64_MIN;
        // Acquisition (until locked): the line through (i, t - t0), i the
        // periods since t0, i of the last stamp, and the period counted
        // with while the line is short.
        bool acquiring = false;
        StampLine line;
        int64_t t0 = 0;
        double i = 0, base = 0;
        int64_t restarts = 0;
        int outliers = 0; // in a row
        // The share of stamps that were outliers or held off (their mean
        // over the last kRateWindow, over all of them until there are
        // that many; kept through restarts: the stream's jitter, not its
        // phase). Averaged from 0 with the full window, it stayed under
        // its level for hundreds of stamps, just while the line acquires.
        double outlier_rate = 0;
        int rated = 0;    // stamps the rate has seen, up to kRateWindow
        int held_off = 0; // counted stamps off their period, in a row
    };
    static constexpr int kMaxAcquire = 1000000;
    static constexpr double kOtherRate = 1.75;  // a first interval this many periods: another rate
    static constexpr int kRestartAfter = 3;     // outliers in a row, at least
    static constexpr int kRestartAfterMax = 16; // and at most (restart_run)
    static constexpr int kRateWindow = 256;     // stamps the outlier rate averages
    // An outlier rate over this is the stream's jitter (uniform over half a
    // period: 550 us at 1 kHz makes 0.1, 800 us 0.35), not a message now
    // and then delayed in transport.
    static constexpr double kJitterRate = 0.05;
    static constexpr int kMaxCount = 1000000; // periods one stamp may count
    // Counted stamps off their period in a row that start the clock again:
    // a burst of kLookAhead makes kLookAhead - 1; more is a clock that
    // counts every stamp a period short (jitter of half a period).
    static constexpr int kRestartHeldOff = 2 * kLookAhead;

    // The period stamps are counted with: the line's slope once it has
    // kStampSlopeFrom stamps, before that the period it started from.
    static double counting_period(const State &s) {
        return !s.acquiring || s.line.n >= kStampSlopeFrom ? s.period : s.base;
    }

    // Outliers in a row that start the clock again: kRestartAfter, or as
    // many as jitter of the stream's outlier rate q makes in a row once in
    // 1e6 stamps (q^n <= 1e-6). Jitter over half a period makes early
    // stamps outliers at random (uniform +-550 us at 1 kHz: 5 %; q 0.1 with
    // the late ones held off): three in a row restarted the clock several
    // times in a 3 s recording, each restart put the filters on raw
    // jittered stamps, and the on-line estimates lost 10-16 % of the mass
    // on three of four draws of the test trajectory. A stream that moved
    // makes outliers every stamp, and still restarts within
    // kRestartAfterMax.
    static int restart_run(double q) {
        if (!(q > 0.01)) return kRestartAfter;
        const double n = std::ceil(std::log(1e-6) / std::log(std::min(q, 0.5)));
        return int(std::clamp(n, double(kRestartAfter), double(kRestartAfterMax)));
    }

    // The stream's outlier rate over kJitterRate: its jitter, over half a
    // period.
    static bool jittery(const State &s) { return s.outlier_rate > kJitterRate; }

    // t_raw onto the acquiring line at the last stamp's count s.i.
    static void on_line(State &s, int64_t t_raw) {
        s.line.add(s.i, double(t_raw - s.t0));
        s.period = s.line.slope();
    }

    // The outlier rate with one more stamp.
    static void seen(State &s, bool outlier) {
        if (s.rated < kRateWindow) ++s.rated;
        s.outlier_rate += ((outlier ? 1.0 : 0.0) - s.outlier_rate) / s.rated;
    }

    // An outlier stamp: the next period, when not the restart_run-th in a
    // row (then false: start again).
    static bool next(State &s) {
        seen(s, true);
        return ++s.outliers < restart_run(s.outlier_rate);
    }

    // A stamp counted k periods on by count_ahead() but over half a period
    // off them (delayed, or in a burst): taken there, at the line's or
    // loop's time, which it leaves alone; false (start again) when the
    // kRestartHeldOff-th in a row.
    static bool held_off(State &s) {
        s.outliers = 0;
        seen(s, true);
        return ++s.held_off < kRestartHeldOff;
    }

    static void start(State &s, int64_t t_raw, double period) {
        s.t = double(t_raw);
        s.period = s.base = period;
        s.acquiring = true;
        s.line = StampLine{};
        s.line.add(0, 0);
        s.t0 = t_raw;
        s.i = 0;
        s.outliers = s.held_off = 0;
    }

    static void restart(State &s, int64_t t_raw, double period) {
        ++s.restarts;
        start(s, t_raw, period);
    }

    static void acquire(State &s, int64_t t_raw, double nominal, double gain, int counted) {
        const double interval = double(t_raw - s.last_raw);
        const double p0 = nominal > 0 ? nominal : interval; // to start again from
        double p = counting_period(s);
        // The first interval well over the nominal period is a stream at
        // another rate (a 250 Hz stream for filters set for 1 kHz), not
        // lost messages: its period is that interval.
        if (s.line.n == 1 && !(interval < kOtherRate * p)) s.period = s.base = p = interval;
        // Counted as the nearest whole periods, but for an outlier: a
        // stamp bunched, or between the next period and the one after
        // (delayed, or one lost?), not clean; a longer gap is lost messages
        // (a stall), counted with the period as known so far. While the
        // line has under kStampSlopeFrom stamps its time is as jittered as
        // they are, and an outlier is the next period, on the line: taken
        // off it, 450 us of jitter at 1 kHz made three in a row and
        // restarted the line again and again, and the stamps of a whole
        // second were as jittered as the raw ones. A stamp count_ahead()
        // counted goes as counted: off its count by over half a period, it
        // goes onto a short line as an outlier does, beside a longer one.
        const double dt = double(t_raw) - s.t;
        if (counted == kNoFit) return restart(s, t_raw, p0);
        double k = counted > 0 ? counted : periods_on(dt, p);
        const bool off = counted > 0 && std::abs(dt - k * p) > 0.5 * p;
        if (off && !held_off(s)) return restart(s, t_raw, p0);
        if (off && s.line.n >= kStampSlopeFrom) {
            s.i += k;
            // Under heavy jitter, on the line (not a burst's first stamp).
            if (k == 1 && dt < 2 * p && jittery(s)) on_line(s, t_raw);
            s.t = double(s.t0) + s.line.at(s.i);
            return;
        }
        if (counted == 0 && s.line.n >= 2 && k <= 2 && periods_of(dt, p) == 0)
            k = s.line.n < kStampSlopeFrom ? 1 : 0;
        if (!(k >= 1)) {
            if (s.line.n >= 2 && next(s)) {
                s.i += 1;
                // Under heavy jitter, on the line at the next period.
                if (jittery(s) && dt > 0) on_line(s, t_raw);
                s.t = double(s.t0) + s.line.at(s.i);
                return;
            }
            return restart(s, t_raw, p0);
        }
        if (!off) s.outliers = s.held_off = 0, seen(s, false);
        s.i += k;
        on_line(s, t_raw);
        s.t = double(s.t0) + s.line.at(s.i);
        const double lock = std::min(std::ceil(4 / gain), double(kMaxAcquire));
        if (double(s.line.n) >= lock) s.acquiring = false;
    }

    static void track(State &s, int64_t t_raw, double g, int counted) {
        // Lost messages: the stamp lands k whole periods on, no new rate.
        const double dt = double(t_raw) - s.t;
        if (counted == kNoFit) return restart(s, t_raw, s.period);
        const double k = counted > 0 ? counted : periods_of(dt, s.period);
        if (counted > 0 && std::abs(dt - k * s.period) > 0.5 * s.period) {
            if (!held_off(s)) return restart(s, t_raw, s.period);
            s.t += k * s.period;
        } else if (k >= 1) {
            const double err = dt - k * s.period;
            s.t += k * s.period + g * err;
            s.period += g * g / 4 * err / k;
            s.outliers = s.held_off = 0;
            seen(s, false);
        } else if (next(s)) {
            s.t += s.period;
        } else {
            restart(s, t_raw, s.period);
        }
    }

    State s_, next_;
};

// The period of one stream's stamps t[0..n], some jittered (by up to half a
// period), some lost: the least-squares slope of the stamps against their
// period counts. Counted one apart (none lost), unless counting them as
// the clock's acquisition does leaves under a third of that line's RMS
// residual (a lost state shifts every later stamp by a period; 16
// intervals with 400 us of jitter at 1 kHz fitted a 0.85 ms grid with
// three lost at half of it): from the line so
// far (with p0, the intervals' median, until the line has kStampSlopeFrom
// stamps; t[0] starts it), a stamp that fits no count left out. Counted
// that way alone, a jittered long interval among few stamps passed for a
// lost state and put the period 15 % short. p0 when fewer than two fit.
inline double stamp_period(const int64_t *t, int n, double p0) {
    if (!(p0 > 0) || n < 1) return p0;
    StampLine single, counted;
    for (int j = 0; j <= n; ++j) single.add(j, double(t[j] - t[0]));
    const bool fits = single.slope() > 0;
    counted.add(0, 0);
    double i_last = 0, t_last = 0;
    for (int j = 1; j <= n; ++j) {
        const double y = double(t[j] - t[0]);
        const double p = counted.n >= kStampSlopeFrom ? counted.slope() : p0;
        const double k = periods_on(y - t_last, p);
        if (!(k >= 1)) continue;
        i_last += k;
        counted.add(i_last, y);
        t_last = counted.at(i_last);
    }
    if (counted.n < 2) return fits ? single.slope() : p0;
    // Any grid of period p' fits counts within p' / 2 (RMS p' / sqrt(12)):
    // lost states need a closer fit. Under 800 us of jitter 16 stamps fitted
    // a 749 us grid with every fourth state "lost" 3 times closer than the
    // line, and the filters ran at that period.
    if (fits && !(counted.rms() < counted.slope() / 8)) return single.slope();
    return fits && !(counted.rms() < single.rms() / 3) ? single.slope() : counted.slope();
}

} // namespace loadid
