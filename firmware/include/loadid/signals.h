/*
 * Signal sources and time alignment (paper sec. V.C, Fig. 9): what feeds
 * the regressor of eq. (6) at each sensor sample.
 *
 *   SENSOR    a - g and alpha from the JR3 accelerometers, omega from the
 *             joint Kalman filter and forward kinematics
 *   KF        a - g, omega and alpha from the encoders: Kalman filter and
 *             forward kinematics
 *   SETPOINT  the same from the commanded positions (through a filter of
 *             the same kind, or exact derivatives when the trajectory is
 *             known)
 *   MIXED     a - g from the JR3, omega and alpha from the Kalman filter
 *
 * RIV's instruments (eq. 20) always come from SETPOINT.
 *
 * Joint states and sensor samples come on their own clocks' ticks. The
 * joint quantities are evaluated at each sensor sample's time by the
 * filters' model (loadid_jf_state_at), and a sample whose nearest joint
 * state is further away than max_joint_age_us (or that comes before any
 * joint state) is refused and counted, never served from old data; so is
 * one the filters would serve while still settling after their start or
 * a restart (loadid_jf_settle_steps). With
 * the filters' lag_steps > 0 they are the fixed-lag smoother's instead
 * (loadid_jf_lagged_state_at): no lag, but a sample can be served only
 * lag_steps joint states after its time (loadid_signals_last_joint_time
 * then says up to when).
 */
#ifndef LOADID_SIGNALS_H
#define LOADID_SIGNALS_H

#include <stdint.h>

#include "loadid/chain.h"
#include "loadid/joint_filter.h"
#include "loadid/kinematics.h"
#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    LOADID_SIGNALS_SENSOR = 1,
    LOADID_SIGNALS_KF = 2,
    LOADID_SIGNALS_SETPOINT = 3,
    LOADID_SIGNALS_MIXED = 4
} loadid_signal_source_t;

/* "sensor", "kf", "setpoint", "mixed" (the configuration's names). Parse
 * returns 0 or -EINVAL; name returns NULL for an unknown value. */
int loadid_signal_source_parse(const char *name, loadid_signal_source_t *out);
const char *loadid_signal_source_name(loadid_signal_source_t source);

/* The regressor's inputs, in S. */
typedef struct {
    loadid_real_t spec[3];  /* a - g [m/s^2] */
    loadid_real_t omega[3]; /* [rad/s] */
    loadid_real_t alpha[3]; /* [rad/s^2] */
} loadid_regressor_input_t;

typedef struct {
    loadid_signal_source_t source; /* default MIXED (docs/INTERFACE.md) */
    loadid_jf_config_t measured;   /* filter of the encoder positions */
    loadid_jf_config_t setpoint;   /* filter of the commanded positions */
    /* A sensor sample further than this from the newest joint state [us]
     * (with the fixed-lag smoother: from the smoothed one it is served
     * from) is refused as stale. Default 5000 (five joint periods at 1 kHz). */
    int64_t max_joint_age_us;
    /* Joint-state time stamps that jitter about a fixed rate (a
     * controller that samples on its cycle, stamped on arrival) are
     * regularised by a phase-locked loop before the filters see them:
     * t = t_pred + stamp_gain (t_stamp - t_pred), t_pred the last t plus
     * the period, which the loop tracks (gain stamp_gain^2 / 4). Encoders
     * read to 2^-20 of a turn at 2 rad/s move 1e-4 rad in 50 us of
     * jitter: treated as exact, that made the filters' q'' useless (RLS
     * found 2 % of the mass with 200 us of jitter). A stamp over 1.5
     * periods past the prediction is held with those after it (up to 16)
     * until they tell lost messages (every later stamp a period on) from
     * a delay or a burst (one-sided: the earliest of them on time); it is
     * then counted so, and lost messages keep the period. Any other stamp
     * over half a period off the prediction (delayed, bunched) is taken
     * as the next period; three of them in a row, or counted stamps off
     * their periods 32 times in a row, restart the clock (a stream that
     * moved; stamp_restarts). Such a loop pulls in only a
     * period error small against stamp_gain, so it first acquires: the
     * stamps since (re)start are taken from their least-squares line
     * against their period counts, from the filters' period, until 4 /
     * stamp_gain of them, where the line's gain has fallen to the loop's
     * (src/stamp_clock.hpp). stamp_gain in (0, 1]; 1 keeps the stamps as
     * they are. Default 0.005: jitter divided by about 20 (sqrt(g/2)) once
     * locked; 0.02 still cost RLS 3 % of the mass with 200 us of jitter. */
    double stamp_gain;
    /* The joint stream's period measured instead of configured: with
     * period_probe > 0 the first period_probe + 1 joint states are held
     * (samples meanwhile get LOADID_E_NO_DATA; the states are counted
     * when they reach the filters), the least-squares slope of their
     * stamps against their period counts (stamp_period of
     * src/stamp_clock.hpp) is the period P, and both filter banks are configured
     * for it before the held states go in (a burst among them, stamps
     * under P / 2 before the next, dated P apart back from its newest):
     * nominal_step_us P, lag_steps
     * lag_us / P (at most LOADID_JF_MAX_LAG), and max_joint_age_us and
     * max_step_us at least 2 P, so that a sample between two joint states
     * of a slow stream is served. A controller's joint stream runs at
     * 125 Hz to 1 kHz; the filters tuned for 1 kHz on a 250 Hz stream
     * cost RLS 3.4 % of the mass, and at 125 Hz every joint step was a
     * stall (no sample served). 0 (default): the banks as configured. At
     * most LOADID_SIGNALS_MAX_PROBE. */
    int period_probe;
    int64_t lag_us; /* with period_probe: the fixed-lag smoother's lag [us] (0: none) */
} loadid_signals_config_t;

#define LOADID_SIGNALS_MAX_PROBE 16

/* Counters since create or reset. */
typedef struct {
    int64_t joint_msgs_ok;
    int64_t joint_msgs_bad;    /* wrong joint count, NaN/Inf, time order */
    int64_t stamp_restarts;    /* joint stamps off the stream's rate: the
                                  stamp clock started again from them */
    int stamp_acquiring;       /* 1: the clock has not locked on the
                                  stream since its start or last restart */
    int64_t samples_ok;        /* loadid_signals_at served them */
    int64_t samples_stale;     /* refused: joint data too old or too new */
    int64_t samples_no_joints; /* refused: no joint state yet */
    int64_t samples_bad;       /* refused: NaN/Inf sensor input */
} loadid_signals_stats_t;

typedef struct loadid_signals loadid_signals_t; /* opaque */

int loadid_signals_config_default(loadid_signals_config_t *cfg);

/* Builds the kinematics of chain (gravity in the base frame) and the two
 * filter banks. The only allocation. Returns 0, -EINVAL or -ENOMEM. */
int loadid_signals_create(const loadid_chain_t *chain, const double gravity[3],
                          const loadid_signals_config_t *cfg, loadid_signals_t **out);

void loadid_signals_destroy(loadid_signals_t *s);

/* The joint period the filters run at [us]: the configured one, or with
 * period_probe the measured one (0 while probing); -EINVAL for NULL. */
int64_t loadid_signals_joint_period_us(const loadid_signals_t *s);

/* The joint stamps' period as their phase-locked loop tracks it [us]; 0
 * before the second joint state (also for NULL). */
double loadid_signals_stream_period_us(const loadid_signals_t *s);

/* The measured joint positions' own noise since create, reset or
 * loadid_signals_position_noise_reset: the largest joint's std [rad or m]
 * from the fourth differences of consecutive states (a quantised encoder:
 * its step / sqrt(12)); 0 with fewer than 16 differences or for NULL.
 * What kalman.meas_sigma should be (src/position_noise.hpp). */
double loadid_signals_position_noise(const loadid_signals_t *s);
void loadid_signals_position_noise_reset(loadid_signals_t *s);
/* The fourth differences behind it (0 for NULL). */
int64_t loadid_signals_position_noise_count(const loadid_signals_t *s);

/* The measured positions' filter bank for encoders noisier than its
 * meas_sigma, with the fixed-lag smoother's lag lag_us (in joint periods,
 * never shorter than it is, at most LOADID_JF_MAX_LAG; a bank without the
 * smoother keeps none): loadid_jf_retune, the joint states the bank kept
 * filtered again with the new gains. The setpoints' bank is left alone
 * (commanded positions carry no encoder noise). Returns the filters'
 * settle count for the new gains (loadid_jf_settle_steps), or -EINVAL
 * (also while the period is being probed). */
int loadid_signals_retune(loadid_signals_t *s, double meas_sigma, int64_t lag_us);

/* The measured positions' filter bank's configuration as it runs now (after
 * a probe: for the measured period). Returns 0 or -EINVAL. */
int loadid_signals_filter_config(const loadid_signals_t *s, loadid_jf_config_t *out);

/* Forgets all joint data and zeroes the counters (a measured period is
 * kept). Returns 0 or -EINVAL. */
int loadid_signals_reset(loadid_signals_t *s);

int loadid_signals_num_joints(const loadid_signals_t *s);

/* One joint state (joint_state_t): measured positions and, if not NULL,
 * setpoints, num_joints each. It reaches the filters now, or with the
 * states held before it (the period probe; a stamp far past the
 * prediction, stamp_gain), or is held (counted when it reaches them).
 * Returns 0, or (counted in joint_msgs_bad, nothing changed) -EBADMSG for
 * a joint count not the chain's, LOADID_E_NONFINITE, LOADID_E_TIME_ORDER;
 * -EINVAL for a NULL s. Releasing held states, the last one's code. */
int loadid_signals_push_joints(loadid_signals_t *s, int64_t t_us, int num_joints,
                               const loadid_real_t *position, const loadid_real_t *setpoint);

/* The joint states the last loadid_signals_push_joints or
 * loadid_signals_end_piece put into the filters, oldest first: their
 * count (0 for NULL), and the i-th one's regularised time [us] (INT64_MIN
 * for a bad i) with its positions copied to position (if not NULL;
 * num_joints values). */
int loadid_signals_fed_count(const loadid_signals_t *s);
int64_t loadid_signals_fed_state(const loadid_signals_t *s, int i, loadid_real_t *position);

/* The regressor's inputs for the sensor sample at t_us, from the
 * configured source, and RIV's instruments from the setpoints.
 * jr3_spec, jr3_alpha: the JR3's a - g and alpha in S (needed by SENSOR
 * and MIXED, else may be NULL). exact_setpoint: NULL, or q, qd, qdd of
 * the commanded trajectory at t_us (3 * num_joints values), used instead
 * of the setpoint filter. motion and instruments may be NULL.
 * Returns 0 (counted in samples_ok); or, counted, nothing written:
 * LOADID_E_NO_DATA (no joint state yet, or no setpoint when one is
 * needed), LOADID_E_STALE, LOADID_E_NONFINITE; -EINVAL (NULL s, or a JR3
 * input the source needs is NULL). */
int loadid_signals_at(loadid_signals_t *s, int64_t t_us, const loadid_real_t jr3_spec[3],
                      const loadid_real_t jr3_alpha[3], const loadid_real_t *exact_setpoint,
                      loadid_regressor_input_t *motion, loadid_regressor_input_t *instruments);

/* Forward kinematics of the measured joints (filtered) at t_us: the pose,
 * and gravity in S, e.g. g_init of eq. (7) at zeroing. Same returns as
 * loadid_signals_at (not counted). */
int loadid_signals_kinematics_at(const loadid_signals_t *s, int64_t t_us,
                                 loadid_kin_state_t *state);

int loadid_signals_stats(const loadid_signals_t *s, loadid_signals_stats_t *stats);

/* Time of the newest accepted joint state [us]; INT64_MIN before the
 * first (or for a NULL s). A sensor sample no later than this has joint
 * data on both sides of it. With the fixed-lag smoother (the measured
 * filter's lag_steps > 0): the newest time it can serve now. */
int64_t loadid_signals_last_joint_time(const loadid_signals_t *s);

/* The joint stream has stalled: the held joint states go into the
 * filters, counted by the stamps there are; with the fixed-lag smoother,
 * serve what was received with the joint states that came after it
 * (loadid_jf_end_piece on both filters), once until the next joint state.
 * Returns 0 or -EINVAL. */
int loadid_signals_end_piece(loadid_signals_t *s);

/* The (regularised, stamp_gain) time of the newest accepted joint state
 * [us]; INT64_MIN before the first. */
int64_t loadid_signals_newest_joint_time(const loadid_signals_t *s);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SIGNALS_H */
