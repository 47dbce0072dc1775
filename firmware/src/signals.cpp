// Signal sources and time alignment (loadid/signals.h, paper Fig. 9): the
// joint filters, evaluated at the sensor sample's time, and the forward
// kinematics give a - g, omega, alpha in S; the JR3 gives them directly.
#include "loadid/signals.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <new>

#include "enum_value.hpp"
#include "finite.hpp"
#include "position_noise.hpp"
#include "stamp_clock.hpp"

using namespace loadid;

struct loadid_signals {
    loadid_signals_config_t cfg;
    int n;
    loadid_kin_t *kin;
    loadid_jf_t *measured;
    loadid_jf_t *setpoint;
    loadid_signals_stats_t stats;
    StampClock clock;             // the joint stamps regularised (stamp_clock.hpp)
    PositionNoise position_noise; // of the measured positions (position_noise.hpp)
    bool piece_ended;             // loadid_signals_end_piece since the last joint state
    // The period probe (cfg.period_probe): the joint states held until the
    // period is known; period_us the filters' period, 0 while probing.
    struct Held {
        int64_t t;
        bool has_setpoint;
        loadid_real_t q[LOADID_MAX_JOINTS], setpoint[LOADID_MAX_JOINTS];
    };
    Held held[LOADID_SIGNALS_MAX_PROBE + 1];
    int held_count;
    int64_t period_us;
    // The look-ahead (StampClock::far): a stamp far past the last time and
    // those after it, held until count_ahead counts the first; oldest first.
    Held ahead[StampClock::kLookAhead];
    int ahead_count;
    // The joint states the last push or end_piece put into the filters
    // (loadid_signals_fed_state): at most all held ones and the new one.
    struct Fed {
        int64_t t;
        loadid_real_t q[LOADID_MAX_JOINTS];
    };
    static constexpr int kMaxFed = std::max(LOADID_SIGNALS_MAX_PROBE, StampClock::kLookAhead) + 1;
    Fed fed[kMaxFed];
    int fed_count;
};

namespace {

bool valid_source(int s) {
    return s >= LOADID_SIGNALS_SENSOR && s <= LOADID_SIGNALS_MIXED;
}

const char *const kNames[] = {nullptr, "sensor", "kf", "setpoint", "mixed"};

void destroy(loadid_signals *s) {
    loadid_kin_destroy(s->kin);
    loadid_jf_destroy(s->measured);
    loadid_jf_destroy(s->setpoint);
    delete s;
}

// Is a joint stream close enough to t to be evaluated there? (Without the
// fixed-lag smoother; with it, loadid_jf_lagged_state_at says so itself.)
int stream_ready(const loadid_jf_t *jf, int64_t t_us, int64_t max_age_us) {
    int64_t last = loadid_jf_last_time(jf);
    if (last == INT64_MIN) return LOADID_E_NO_DATA;
    // The distance in unsigned arithmetic: exact for any two int64 times,
    // so a corrupt stamp far away cannot wrap around into "fresh".
    uint64_t dist = t_us > last ? uint64_t(t_us) - uint64_t(last) : uint64_t(last) - uint64_t(t_us);
    if (dist > uint64_t(max_age_us)) return LOADID_E_STALE;
    return 0;
}

// The kinematics of a joint stream at t: the filter's state there (if
// t is close enough to its newest update) or, with lag_steps, the
// fixed-lag smoother's.
int kinematics_of(const loadid_signals *s, const loadid_jf_t *jf, int lag, int64_t t_us,
                  loadid_kin_state_t *out) {
    loadid_real_t q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
    int rc = lag > 0 ? loadid_jf_lagged_state_at(jf, t_us, s->cfg.max_joint_age_us, q, qd, qdd)
                     : stream_ready(jf, t_us, s->cfg.max_joint_age_us);
    // The causal filter serves only once settled (joint_filter.h).
    if (rc == 0 && lag == 0 && !loadid_jf_settled(jf)) rc = LOADID_E_STALE;
    if (rc == 0 && lag == 0) rc = loadid_jf_state_at(jf, t_us, q, qd, qdd);
    if (rc != 0) return rc;
    return loadid_kin_eval(s->kin, q, qd, qdd, out);
}

void copy3(loadid_real_t dst[3], const loadid_real_t src[3]) {
    std::memcpy(dst, src, 3 * sizeof *dst);
}

void motion_of(const loadid_kin_state_t &k, loadid_regressor_input_t &m) {
    copy3(m.spec, k.spec);
    copy3(m.omega, k.omega);
    copy3(m.alpha, k.alpha);
}

// Counts a refusal by its cause and passes the code on.
int refuse(loadid_signals *s, int rc) {
    if (rc == LOADID_E_NO_DATA)
        ++s->stats.samples_no_joints;
    else if (rc == LOADID_E_STALE)
        ++s->stats.samples_stale;
    else
        ++s->stats.samples_bad;
    return rc;
}

} // namespace

extern "C" int loadid_signal_source_parse(const char *name, loadid_signal_source_t *out) {
    if (!name || !out) return -EINVAL;
    for (int i = LOADID_SIGNALS_SENSOR; i <= LOADID_SIGNALS_MIXED; ++i) {
        if (std::strcmp(name, kNames[i]) == 0) {
            *out = static_cast<loadid_signal_source_t>(i);
            return 0;
        }
    }
    return -EINVAL;
}

extern "C" const char *loadid_signal_source_name(loadid_signal_source_t source) {
    const int v = enum_value(source);
    return valid_source(v) ? kNames[v] : nullptr;
}

extern "C" int loadid_signals_config_default(loadid_signals_config_t *cfg) {
    if (!cfg) return -EINVAL;
    std::memset(cfg, 0, sizeof *cfg);
    cfg->source = LOADID_SIGNALS_MIXED;
    loadid_jf_config_default(&cfg->measured);
    loadid_jf_config_default(&cfg->setpoint);
    cfg->max_joint_age_us = 5000;
    cfg->stamp_gain = 0.005;
    return 0;
}

extern "C" int loadid_signals_create(const loadid_chain_t *chain, const double gravity[3],
                                     const loadid_signals_config_t *cfg, loadid_signals_t **out) {
    if (!chain || !gravity || !cfg || !out) return -EINVAL;
    if (!valid_source(enum_value(cfg->source)) || cfg->max_joint_age_us < 0) return -EINVAL;
    if (!(cfg->stamp_gain > 0 && cfg->stamp_gain <= 1)) return -EINVAL;
    if (cfg->period_probe < 0 || cfg->period_probe > LOADID_SIGNALS_MAX_PROBE || cfg->lag_us < 0)
        return -EINVAL;
    auto *s = new (std::nothrow) loadid_signals{};
    if (!s) return -ENOMEM;
    s->cfg = *cfg;
    int rc = loadid_kin_create(chain, gravity, &s->kin);
    if (rc == 0) rc = loadid_jf_create(chain->num_joints, &cfg->measured, &s->measured);
    if (rc == 0) rc = loadid_jf_create(chain->num_joints, &cfg->setpoint, &s->setpoint);
    if (rc != 0) {
        destroy(s);
        return rc;
    }
    s->n = chain->num_joints;
    s->clock.reset();
    s->period_us = cfg->period_probe > 0 ? 0 : cfg->measured.nominal_step_us;
    *out = s;
    return 0;
}

extern "C" void loadid_signals_destroy(loadid_signals_t *s) {
    if (s) destroy(s);
}

extern "C" int loadid_signals_reset(loadid_signals_t *s) {
    if (!s) return -EINVAL;
    loadid_jf_reset(s->measured);
    loadid_jf_reset(s->setpoint);
    s->stats = loadid_signals_stats_t{};
    s->clock.reset();
    s->position_noise.reset();
    s->held_count = s->ahead_count = s->fed_count = 0;
    return 0;
}

extern "C" int loadid_signals_num_joints(const loadid_signals_t *s) {
    return s ? s->n : -EINVAL;
}

namespace {

// Checks a joint state as the filters would take it: 0, or the refusal.
int check_joints(const loadid_signals *s, int64_t t_us, int num_joints,
                 const loadid_real_t *position, const loadid_real_t *setpoint) {
    if (num_joints != s->n || !position) return -EBADMSG;
    if (!all_finite(position, s->n) || (setpoint && !all_finite(setpoint, s->n)))
        return LOADID_E_NONFINITE;
    if (t_us <= s->clock.last_raw()) return LOADID_E_TIME_ORDER;
    return 0;
}

// One joint state into the filters (its stamp regularised; counted: its
// periods as StampClock::count_ahead found them, 0 none); counted.
int feed(loadid_signals *s, int64_t t_us, int num_joints, const loadid_real_t *position,
         const loadid_real_t *setpoint, int counted) {
    // Everything is checked before either filter changes, so a refused
    // message leaves both exactly as they were.
    int rc = check_joints(s, t_us, num_joints, position, setpoint);
    // The regularised stamp; a loop that has not locked yet may not go
    // backwards in time.
    if (rc == 0) t_us = s->clock.propose(t_us, double(s->period_us), s->cfg.stamp_gain, counted);
    if (rc == 0 && (t_us <= loadid_jf_last_time(s->measured) ||
                    (setpoint && t_us <= loadid_jf_last_time(s->setpoint))))
        rc = LOADID_E_TIME_ORDER;
    if (rc == 0) rc = loadid_jf_update(s->measured, t_us, position);
    if (rc == 0 && setpoint) rc = loadid_jf_update(s->setpoint, t_us, setpoint);
    if (rc != 0) {
        ++s->stats.joint_msgs_bad;
        s->position_noise.gap(); // the positions go on after a hole
        return rc;
    }
    s->clock.commit();
    s->position_noise.add(t_us, position, s->n, s->period_us);
    ++s->stats.joint_msgs_ok;
    s->piece_ended = false;
    if (s->fed_count < loadid_signals::kMaxFed) {
        auto &f = s->fed[s->fed_count++];
        f.t = t_us;
        std::memcpy(f.q, position, size_t(s->n) * sizeof *position);
    }
    return 0;
}

// The held states into the filters, oldest first, as far as the stamps
// after each count it (done: no more are coming). The last one's code.
int release(loadid_signals *s, bool done) {
    int rc = 0;
    while (s->ahead_count > 0) {
        const auto &h = s->ahead[0];
        int counted = 0;
        if (s->clock.far(h.t, s->cfg.stamp_gain)) {
            int64_t r[StampClock::kLookAhead];
            for (int j = 0; j < s->ahead_count; ++j) r[j] = s->ahead[j].t;
            counted = s->clock.count_ahead(r, s->ahead_count,
                                           s->ahead_count == StampClock::kLookAhead, done);
            if (counted == 0) break;
        }
        rc = feed(s, h.t, s->n, h.q, h.has_setpoint ? h.setpoint : nullptr, counted);
        std::memmove(s->ahead, s->ahead + 1, size_t(--s->ahead_count) * sizeof s->ahead[0]);
    }
    return rc;
}

// A joint state appended to a queue of held ones (the probe's, the
// look-ahead's; room for it) once checked: 0, or the refusal, counted.
int hold(loadid_signals *s, loadid_signals::Held *queue, int *count, int64_t t_us, int num_joints,
         const loadid_real_t *position, const loadid_real_t *setpoint) {
    int rc = check_joints(s, t_us, num_joints, position, setpoint);
    if (rc == 0 && *count > 0 && t_us <= queue[*count - 1].t) rc = LOADID_E_TIME_ORDER;
    if (rc != 0) {
        ++s->stats.joint_msgs_bad;
        s->position_noise.gap();
        return rc;
    }
    auto &h = queue[(*count)++];
    h.t = t_us;
    h.has_setpoint = setpoint != nullptr;
    std::memcpy(h.q, position, size_t(s->n) * sizeof *position);
    if (setpoint) std::memcpy(h.setpoint, setpoint, size_t(s->n) * sizeof *setpoint);
    return 0;
}

// A joint state once the period is known: into the filters, or held while
// a far stamp before it (or it) waits for the stamps after it.
int take(loadid_signals *s, int64_t t_us, int num_joints, const loadid_real_t *position,
         const loadid_real_t *setpoint) {
    if (s->ahead_count == 0 && !s->clock.far(t_us, s->cfg.stamp_gain))
        return feed(s, t_us, num_joints, position, setpoint, 0);
    const int rc = hold(s, s->ahead, &s->ahead_count, t_us, num_joints, position, setpoint);
    return rc != 0 ? rc : release(s, false);
}

// The filter banks for a joint stream of period p [us] (signals.h,
// period_probe).
void configure_for(loadid_signals *s, int64_t p) {
    s->period_us = p;
    s->cfg.max_joint_age_us = std::max(s->cfg.max_joint_age_us, 2 * p);
    int lag = 0;
    if (s->cfg.lag_us > 0)
        lag = int(std::clamp<int64_t>(std::llround(double(s->cfg.lag_us) / double(p)), 1,
                                      LOADID_JF_MAX_LAG));
    for (loadid_jf_config_t *c : {&s->cfg.measured, &s->cfg.setpoint}) {
        c->nominal_step_us = p;
        c->lag_steps = lag;
        c->max_step_us = std::max(c->max_step_us, s->cfg.max_joint_age_us);
    }
    loadid_jf_configure(s->measured, &s->cfg.measured);
    loadid_jf_configure(s->setpoint, &s->cfg.setpoint);
}

// The median of the sorted d[0..k).
int64_t median_of(const int64_t *d, int k) {
    return k % 2 ? d[k / 2] : (d[k / 2 - 1] + d[k / 2]) / 2;
}

// The period of k + 1 held stamps: their intervals' median (robust to a
// lost message) to start from, then the slope of the stamps against their
// period counts (stamp_period, stamp_clock.hpp). Under 200 us of jitter
// the median alone was 8 % off at 1 kHz; the slope of 9 stamps is within
// about 1.5 %. Counted from the raw intervals by that median, 300-500 us
// of jitter put the period 15-28 % short. A median under half the mean
// interval is a bunched start (a stream that began with a burst: held
// states delivered at once), whose intervals of a few us are no period:
// the median of those over half the mean (with five of eight bunched the
// period came out 50 us, the least taken, and nothing was right).
int64_t probed_period(const loadid_signals::Held *held, int k) {
    int64_t d[LOADID_SIGNALS_MAX_PROBE], t[LOADID_SIGNALS_MAX_PROBE + 1];
    for (int i = 0; i < k; ++i) d[i] = held[i + 1].t - held[i].t;
    for (int i = 0; i <= k; ++i) t[i] = held[i].t;
    std::sort(d, d + k);
    int64_t median = median_of(d, k);
    const double mean = double(held[k].t - held[0].t) / k;
    if (double(median) < mean / 2) {
        const int64_t *longer = std::upper_bound(d, d + k, int64_t(mean / 2));
        median = median_of(longer, int(d + k - longer));
    }
    if (median <= 0) return median;
    return int64_t(std::llround(stamp_period(t, k, double(median))));
}

// Held stamps under half a period before the next one are a burst's
// (states sampled a period apart, delivered at once and stamped on
// arrival): each is dated a period before the next, from the newest back.
// Taken as they came, a stream that began with a burst restarted the stamp
// clock at once (early stamps in a row) and took 0.8 s to lock again.
void back_date_burst(loadid_signals::Held *held, int count, int64_t p) {
    for (int i = count - 2; i >= 0; --i)
        if (held[i + 1].t - held[i].t < p / 2) held[i].t = held[i + 1].t - p;
}

// A joint state while probing: held (counted when it reaches the filters);
// with period_probe + 1 of them the period is measured (probed_period), a
// burst among them dated back (back_date_burst), and they go into the
// filters.
int probe(loadid_signals *s, int64_t t_us, int num_joints, const loadid_real_t *position,
          const loadid_real_t *setpoint) {
    int rc = hold(s, s->held, &s->held_count, t_us, num_joints, position, setpoint);
    if (rc != 0) return rc;
    const int k = s->cfg.period_probe;
    if (s->held_count <= k) return 0;
    configure_for(s, std::clamp<int64_t>(probed_period(s->held, k), 50, 1000000));
    back_date_burst(s->held, s->held_count, s->period_us);
    for (int i = 0; i < s->held_count; ++i) {
        const auto &e = s->held[i];
        rc = take(s, e.t, s->n, e.q, e.has_setpoint ? e.setpoint : nullptr);
    }
    s->held_count = 0;
    return rc; // the last one's
}

} // namespace

extern "C" int loadid_signals_push_joints(loadid_signals_t *s, int64_t t_us, int num_joints,
                                          const loadid_real_t *position,
                                          const loadid_real_t *setpoint) {
    if (!s) return -EINVAL;
    s->fed_count = 0;
    if (s->period_us == 0) return probe(s, t_us, num_joints, position, setpoint);
    return take(s, t_us, num_joints, position, setpoint);
}

extern "C" int loadid_signals_fed_count(const loadid_signals_t *s) {
    return s ? s->fed_count : 0;
}

extern "C" int64_t loadid_signals_fed_state(const loadid_signals_t *s, int i,
                                            loadid_real_t *position) {
    if (!s || i < 0 || i >= s->fed_count) return INT64_MIN;
    if (position) std::memcpy(position, s->fed[i].q, size_t(s->n) * sizeof *position);
    return s->fed[i].t;
}

extern "C" int64_t loadid_signals_joint_period_us(const loadid_signals_t *s) {
    return s ? s->period_us : -EINVAL;
}

extern "C" double loadid_signals_position_noise(const loadid_signals_t *s) {
    return s ? s->position_noise.sigma() : 0;
}

extern "C" int64_t loadid_signals_position_noise_count(const loadid_signals_t *s) {
    return s ? s->position_noise.count() : 0;
}

extern "C" void loadid_signals_position_noise_reset(loadid_signals_t *s) {
    if (s) s->position_noise.reset();
}

extern "C" int loadid_signals_retune(loadid_signals_t *s, double meas_sigma, int64_t lag_us) {
    if (!s || s->period_us <= 0 || lag_us < 0) return -EINVAL;
    loadid_jf_config_t &c = s->cfg.measured;
    int lag = c.lag_steps;
    if (lag > 0)
        lag = int(std::clamp<int64_t>(std::llround(double(lag_us) / double(s->period_us)), lag,
                                      LOADID_JF_MAX_LAG));
    const int rc = loadid_jf_retune(s->measured, loadid_real_t(meas_sigma), lag);
    if (rc != 0) return rc;
    c.meas_sigma = loadid_real_t(meas_sigma);
    c.lag_steps = lag;
    return loadid_jf_settle_steps(s->measured);
}

extern "C" double loadid_signals_stream_period_us(const loadid_signals_t *s) {
    return s && s->clock.last_raw() != INT64_MIN ? s->clock.period() : 0;
}

extern "C" int loadid_signals_filter_config(const loadid_signals_t *s, loadid_jf_config_t *out) {
    if (!s || !out) return -EINVAL;
    *out = s->cfg.measured;
    return 0;
}

extern "C" int loadid_signals_at(loadid_signals_t *s, int64_t t_us, const loadid_real_t jr3_spec[3],
                                 const loadid_real_t jr3_alpha[3],
                                 const loadid_real_t *exact_setpoint,
                                 loadid_regressor_input_t *motion,
                                 loadid_regressor_input_t *instruments) {
    if (!s) return -EINVAL;
    const loadid_signal_source_t src = s->cfg.source;
    const bool uses_jr3 = src == LOADID_SIGNALS_SENSOR || src == LOADID_SIGNALS_MIXED;
    const bool uses_measured = src != LOADID_SIGNALS_SETPOINT;
    const bool uses_setpoint = src == LOADID_SIGNALS_SETPOINT || instruments;
    if (uses_jr3 && (!jr3_spec || (src == LOADID_SIGNALS_SENSOR && !jr3_alpha))) return -EINVAL;
    if (uses_jr3 &&
        (!all_finite(jr3_spec, 3) || (src == LOADID_SIGNALS_SENSOR && !all_finite(jr3_alpha, 3))))
        return refuse(s, LOADID_E_NONFINITE);
    if (exact_setpoint && !all_finite(exact_setpoint, 3 * s->n))
        return refuse(s, LOADID_E_NONFINITE);

    int rc = 0;
    loadid_kin_state_t meas{}, set{};
    if (uses_measured) {
        rc = kinematics_of(s, s->measured, s->cfg.measured.lag_steps, t_us, &meas);
        if (rc != 0) return refuse(s, rc);
    }
    if (uses_setpoint) {
        if (exact_setpoint) {
            rc = loadid_kin_eval(s->kin, exact_setpoint, exact_setpoint + s->n,
                                 exact_setpoint + 2 * s->n, &set);
        } else {
            rc = kinematics_of(s, s->setpoint, s->cfg.setpoint.lag_steps, t_us, &set);
        }
        if (rc != 0) return refuse(s, rc);
    }

    if (motion) {
        switch (src) {
            case LOADID_SIGNALS_SENSOR:
                copy3(motion->spec, jr3_spec);
                copy3(motion->omega, meas.omega);
                copy3(motion->alpha, jr3_alpha);
                break;
            case LOADID_SIGNALS_KF:
                motion_of(meas, *motion);
                break;
            case LOADID_SIGNALS_SETPOINT:
                motion_of(set, *motion);
                break;
            case LOADID_SIGNALS_MIXED:
                copy3(motion->spec, jr3_spec);
                copy3(motion->omega, meas.omega);
                copy3(motion->alpha, meas.alpha);
                break;
        }
    }
    if (instruments) motion_of(set, *instruments);
    ++s->stats.samples_ok;
    return 0;
}

extern "C" int loadid_signals_kinematics_at(const loadid_signals_t *s, int64_t t_us,
                                            loadid_kin_state_t *state) {
    if (!s || !state) return -EINVAL;
    return kinematics_of(s, s->measured, s->cfg.measured.lag_steps, t_us, state);
}

extern "C" int loadid_signals_stats(const loadid_signals_t *s, loadid_signals_stats_t *stats) {
    if (!s || !stats) return -EINVAL;
    *stats = s->stats;
    stats->stamp_restarts = s->clock.restarts();
    stats->stamp_acquiring = s->clock.acquiring();
    return 0;
}

extern "C" int64_t loadid_signals_last_joint_time(const loadid_signals_t *s) {
    if (!s) return INT64_MIN;
    return s->cfg.measured.lag_steps > 0 ? loadid_jf_lagged_time(s->measured)
                                         : loadid_jf_last_time(s->measured);
}

extern "C" int64_t loadid_signals_newest_joint_time(const loadid_signals_t *s) {
    return s ? loadid_jf_last_time(s->measured) : INT64_MIN;
}

extern "C" int loadid_signals_end_piece(loadid_signals_t *s) {
    if (!s) return -EINVAL;
    s->fed_count = 0;
    release(s, true); /* no stamps after them are coming */
    if (s->piece_ended) return 0;
    loadid_jf_end_piece(s->measured);
    loadid_jf_end_piece(s->setpoint);
    s->piece_ended = true;
    return 0;
}
