/*
 * The configuration file (docs/INTERFACE.md, "Configuration"): one YAML
 * file, read with libyaml into loadid_config_t. The keys of
 * docs/INTERFACE.md are fixed; the sections marked "loadid" below are this
 * project's additions. Keys left out take the defaults given here. Relative
 * paths are relative to the directory of the configuration file.
 *
 * Every error names the file, the line and the key, e.g.
 *   "cfg.yaml:12: jr3.full_scale.force: expected 3 numbers, got 2"
 * An unknown key inside a section loadid reads is an error, with the
 * closest known key when one is near (a typo would otherwise leave a
 * setting silently at its default):
 *   "cfg.yaml:40: trajectory.harmonic: unknown key (did you mean 'harmonics'?)"
 *   "cfg.yaml:41: estimation.foo: unknown key (estimation has methods, ...)"
 * So is a top-level name within the same edit distance of a loadid section
 * ("estimaton: unknown section (did you mean 'estimation'?)"). Any other
 * top-level name is another program's section in a shared file: reported
 * through the warning callback, "cfg.yaml:50: dashboard: not a loadid
 * section, ignored".
 *
 * Where docs/INTERFACE.md is silent:
 *   - An empty file (or one with only comments) gives every default, with a
 *     warning "FILE:1: (top level): empty configuration, ...". A section
 *     with no keys ("robot:" alone, or with every key commented out) is the
 *     same as a section left out. A key with no value is an error.
 *   - Numbers are plain YAML numbers (integers accepted where a real is
 *     expected); .nan and .inf are refused; a quoted "1.5" is a string.
 *     Integers may be hexadecimal (base_id: 0x1A0, seeds).
 *   - Method and source names are case-sensitive, as docs/INTERFACE.md spells them.
 *   - robot.urdf is made absolute (a relative config path is taken against
 *     the working directory at load), so it survives a chdir; it is not
 *     checked for existence here (the URDF reader reports that, after
 *     robot_urdf_origin: loadid_setup_load).
 *   - A file of several YAML documents, aliases (*name) and duplicate keys
 *     are errors (host/include/loadid/yaml_tree.h).
 */
#ifndef LOADID_CONFIG_H
#define LOADID_CONFIG_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/chain.h"
#include "loadid/ipv4_allow.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_PATH_MAX 4096
#define LOADID_MAX_METHODS 6

/* sensor.type */
enum { LOADID_SENSOR_JR3 = 0, LOADID_SENSOR_MODBUS = 1 };

typedef struct {
    /* robot: (docs/INTERFACE.md) */
    char robot_urdf[LOADID_PATH_MAX];             /* resolved path; default: the shipped
                                           host/config/robots/rx60.urdf */
    char robot_urdf_origin[LOADID_PATH_MAX + 32]; /* where robot_urdf was set, for
                                           messages about the file: "FILE:LINE:
                                           robot.urdf", or "robot.urdf (default)" */
    char robot_base_link[LOADID_NAME_MAX];        /* default "base_link" */
    char robot_sensor_link[LOADID_NAME_MAX];      /* default "ft_sensor" */
    double robot_gravity[3];                      /* default [0 0 -9.81] */

    /* can: */
    char can_interface[32]; /* default "vcan0" */
    uint32_t can_base_id;   /* default 0x1A0; 11-bit, base+4 <= 0x7FF */

    /* jr3.full_scale: value = counts * full_scale / 16384 */
    double jr3_fs_force[3];   /* default 200 N */
    double jr3_fs_moment[3];  /* default 12 N m */
    double jr3_fs_linear[3];  /* default 98.1 m/s^2 */
    double jr3_fs_angular[3]; /* default 1000 rad/s^2 */

    /* lcm: */
    char lcm_url[256];           /* default udpm://239.255.76.67:7667?ttl=0 */
    char lcm_channel_prefix[64]; /* default "": put before every channel name
                                           (several robots on one LCM network: "R2_"
                                           gives R2_LOADID_ESTIMATE ...); letters,
                                           digits, '_', '-', '.', '/' only */
    /* lcm.command_sources: the senders whose command_t the daemon obeys
     * (udpm:// only), IPv4 addresses or CIDR blocks; default none listed:
     * every sender (docs/SECURITY.md says why). */
    loadid_ipv4_net_t lcm_command_sources[LOADID_IPV4_ALLOW_MAX];
    int lcm_num_command_sources; /* 0: accept commands from any sender */

    /* estimation: */
    int num_methods;                 /* default 3: RTLS, RIV, RLS */
    int methods[LOADID_MAX_METHODS]; /* loadid_method_t values, in file order */
    int signals;                     /* loadid_signal_source_t; default KF (with
                                           kalman.lag_s, measured best by the study) */
    int offset_model_estimate;       /* 0: "zeroing" (default), 1: "estimate" */
    double duration_s;               /* default 1.5 */
    int publish_every;               /* estimation.publish_every: (loadid) live,
                                           estimate_t after every n-th sample while
                                           estimating (1, default: every sample);
                                           the final one always; 1..1000000 */
    double rescale_s;                /* estimation.rescale_s: (loadid) when, after START,
                                           the TLS methods weigh their rows again by
                                           the residual the noise does not explain;
                                           0: never */
    double max_missing_share;        /* estimation.max_missing_share: (loadid) a
                                           run whose window lost more than this
                                           share of its samples for want of joint
                                           data, or of its time for want of F/T
                                           samples, is incomplete; [0, 1],
                                           default 0.02 */
    double max_refused_share;        /* estimation.max_refused_share: (loadid) a
                                           run whose window's F/T samples were
                                           refused (saturated, faulty, incomplete)
                                           more often than this share is
                                           incomplete; [0, 1], default 0.1 */

    /* zeroing: */
    double zeroing_window_s; /* default 0.2 */

    /* distal: */
    double distal_phi[10]; /* default 0 */

    /* sensor: (loadid) the wrench source. type: LOADID_SENSOR_JR3 ("jr3",
     * default: the JR3 on CAN, can.* and jr3.*) or LOADID_SENSOR_MODBUS
     * ("modbus": a serial F/T sensor over Modbus RTU, modbus.*). A Modbus
     * F/T has no accelerometer, so estimation.signals must then be kf or
     * setpoint (an error otherwise). */
    int sensor_type;

    /* modbus: (loadid) the serial F/T sensor, proto/modbus_ft.md */
    char modbus_device[256];    /* serial device, default /dev/ttyUSB0 */
    int modbus_baud;            /* bit/s, default 115200 (a rate
                                           libmodbus maps on Linux) */
    char modbus_parity;         /* 'N' (default, "none"), 'E' ("even"),
                                           'O' ("odd") */
    int modbus_data_bits;       /* 5..8, default 8 */
    int modbus_stop_bits;       /* 1..2, default 1 */
    int modbus_slave_id;        /* 1..247, default 1 */
    double modbus_rate_hz;      /* poll rate, (0, 1000], default 200 */
    int modbus_timeout_ms;      /* response timeout, 1..60000, default 20 */
    double modbus_fs_force[3];  /* full scales [N], default 200; the
                                           sensor's holding registers override */
    double modbus_fs_moment[3]; /* [N m], default 12; likewise */

    /* realtime: (loadid) the live service's scheduling. priority: SCHED_FIFO
     * priority 1..99 of the loop (the Modbus poller thread: one below, at
     * least 1), 0 (default) leaves the normal scheduler; lock_memory:
     * mlockall, default false; cpu: pin the loop and the poller to this
     * CPU, -1 (default) any. A setting that cannot be applied is an error
     * at start-up. */
    int rt_priority;
    int rt_lock_memory;
    int rt_cpu;

    /* results: (loadid) saved estimates. directory: where loadidd writes
     * each finished estimate (YAML with a URDF <inertial> snippet) and
     * latest.yaml; "" (default) saves nothing. load: a saved estimate to
     * start from (state DONE, wrench_t flowing); "" (default) none. Both
     * relative to the configuration file. trace: also every estimate the
     * session published, as the trace CSV of loadidd --offline --trace,
     * beside the saved result (<name>.trace.csv); default false; needs
     * directory. */
    char results_directory[LOADID_PATH_MAX];
    char results_load[LOADID_PATH_MAX];
    int results_trace;

    /* noise: (loadid) standard deviations of the measurements, for the
     * estimators' weights (loadid_est_weights_from_noise). "noise: auto"
     * (the default, also any key given as auto) measures them
     * (host/include/loadid/noise_model.h): the wrench and accelerometer
     * channels in the zeroing window (or, without one, from the third
     * differences of the samples), the joint-derived signals from the joint
     * filter's own covariance. A number given overrides that level alone
     * (its bit in noise_given). The values below are the fallbacks used
     * when nothing could be measured. */
    int noise_given;      /* LOADID_NOISE_GIVEN_* bits */
    double noise_force;   /* [N], fallback 0.1 */
    double noise_torque;  /* [N m], fallback 0.005 */
    double noise_linear;  /* a - g [m/s^2], fallback 0.5 */
    double noise_angular; /* alpha [rad/s^2], fallback 5 */
    double noise_omega;   /* [rad/s], fallback 0.02 */
    double omega_typical; /* [rad/s], default 2 (a column scale,
                                           not a noise: always as configured) */

    /* kalman: (loadid) the joint filters (loadid/joint_filter.h) */
    double kalman_jerk_psd;        /* default 10 (behind the fixed-lag smoother;
                                           1e3 for the causal filter, lag_s 0) */
    double kalman_meas_sigma;      /* the encoders' noise [rad or m]; default
                                           (or auto): loadid_jf_config_default's,
                                           raised to the measured when the joint
                                           positions are noisier (pipeline.c,
                                           retune_joint_filters) */
    double kalman_max_joint_age_s; /* default 0.005 */
    double kalman_lag_s;           /* kalman.lag_s: the on-line fixed-lag
                                           smoother's lag [s]: the estimators run
                                           this far behind the newest joint state,
                                           on zero-lag joint signals; 0 = the
                                           causal filter; default 0.05, at most
                                           kalman.joint_period_s * 200 (auto:
                                           capped there) */
    double kalman_joint_delay_s;   /* kalman.joint_delay_s: how much later the
                                           joint states are stamped than the wrench
                                           of the same instant (transport, clocks);
                                           subtracted from every joint utime;
                                           |.| <= 0.1, default 0 (REFINED fits it
                                           and says so) */
    double kalman_stamp_gain;      /* kalman.stamp_gain: the joint stamps'
                                           phase-locked loop (loadid/signals.h),
                                           (0, 1], 1 = stamps as they are;
                                           default 0.005 */
    double kalman_joint_period_s;  /* kalman.joint_period_s: the joint
                                           stream's period [s], for the filters'
                                           steady gains; 0 = auto (the default):
                                           measured from the stream's first
                                           intervals (signals.h, period_probe) */
    /* Noise of what the filters and the kinematics derive, for the
     * estimators' weights when a - g or alpha come from the joints (the
     * kf, setpoint and mixed sources; the JR3's own are noise.linear and
     * noise.angular): a - g [m/s^2], default 0.5; alpha [rad/s^2],
     * default 1 (the filter's q'' error on a 2 Hz trajectory with 2^20
     * counts is about 1 rad/s^2 per joint). */
    double kalman_spec_sigma;
    double kalman_alpha_sigma;
    /* model: (loadid) identified groups and the load model
     * (firmware/include/loadid/load_model.h): thresholds and the fallback
     * density of an unidentified inertia */
    double model_mass_rel_std;     /* [-], default 0.025 */
    double model_com_std;          /* [m], default 0.005 */
    double model_inertia_rel_std;  /* [-], default 0.15 */
    double model_max_gyration;     /* [m], default 0.5 */
    double model_fallback_density; /* [kg/m^3], default 2700 */
    double model_min_snr;          /* [-], default 1: the inertia's torque
                                           over the torque noise, at least */

    /* trajectory: (loadid) the excitation designer, loadid-traj */
    double traj_base_frequency;               /* f of eq. (10) [Hz], default 0.5 */
    int traj_harmonics;                       /* N of eq. (10), default 4 */
    double traj_max_frequency;                /* highest allowed harmonic [Hz], default 2 */
    double traj_active_s;                     /* active part, default 1.5 */
    double traj_fade_s;                       /* each fade (eqs. 14-15), default 0.5 */
    int traj_has_home;                        /* 1 when trajectory.home is given */
    int traj_num_home;                        /* values in traj_home (1..16), 0 if not given */
    double traj_home[LOADID_MAX_JOINTS];      /* q_0 of eq. (11) [rad or m], one per
                                           joint; default mid-range */
    int traj_num_acc_limits;                  /* 0 (traj_acc_limit holds one value for
                                           every joint: the default, or a single
                                           number "acc_limit: 15"), or the count of
                                           the list "acc_limit: [...]" */
    double traj_acc_limit[LOADID_MAX_JOINTS]; /* [rad/s^2 or m/s^2] > 0; default 20 */
    double traj_vel_scale;                    /* fraction of the URDF velocity
                                           limits used, (0, 1], default 1 */
    double traj_workspace_min[3];             /* box the sensor origin stays in,
                                           base frame [m]; default -1e9 */
    double traj_workspace_max[3];             /* default +1e9 */
    double traj_floor_z;                      /* floor plane z >= floor_z + clearance,
                                           base frame [m]; default -1e9 */
    double traj_floor_clearance;              /* [m], default 0.05 */
    int traj_monte_carlo;                     /* random candidates, default 2000 */
    int traj_candidates;                      /* best ones optimised, default 4;
                                           1..monte_carlo */
    int traj_max_evals;                       /* NLopt evaluations each, default 3000 */
    uint64_t traj_seed;                       /* default 1 */

    /* simulation: (loadid) loadid-sim */
    double sim_servo_bandwidth_hz; /* joint servo natural frequency, default 15 */
    double sim_servo_damping;      /* default 0.9 */
    double sim_backlash;           /* [rad], default 2e-4 */
    double sim_encoder_counts;     /* per revolution, default 2^20 */
    double sim_vibration_hz;       /* structural vibration, default 28 */
    double sim_vibration_linear;   /* amplitude on a - g [m/s^2], default 0.3 */
    double sim_vibration_angular;  /* amplitude on alpha [rad/s^2], default 3 */
    double sim_vibration_start_s;  /* the vibration from then on [s], default 0 */
    double sim_still_s;            /* rest before the trajectory, default 0.5 */
    double sim_load_phi[10];       /* default: the paper's o1 */
    double sim_offset[6];          /* F/T offset [N, N m], default
                                           [2 -1.5 3 0.08 -0.05 0.03] */
    /* Imitating real hardware data (defaults: none of it): */
    int sim_zero;                /* zero: a ZERO command 0.05 s into the
                                           still phase; false: none (START still
                                           comes), default true */
    double sim_drift[6];         /* drift: the F/T offset grows by this
                                           times the time since the recording's
                                           start [N/s, N m/s], default 0 */
    double sim_accel_bias[3];    /* accel_bias: added to the JR3 linear
                                           channel a - g [m/s^2], default 0 */
    double sim_alpha_bias[3];    /* alpha_bias: added to the JR3 angular
                                           channel alpha [rad/s^2], default 0 */
    int sim_jitter_us;           /* jitter_us: each CAN sample's and joint
                                           state's time stamp moves by uniform
                                           integer jitter in [-N, N] us (the
                                           physics stays at the nominal time;
                                           streams kept strictly increasing),
                                           0..999, default 0 */
    double sim_trajectory_scale; /* trajectory_scale: the trajectory's
                                           s_i(t) about q_0 (eqs. 10-11) times
                                           this, (0, 1], default 1 */
    uint64_t sim_seed;           /* default 1 */
    /* simulation.noise: the simulated sensor's noise [N, N m, m/s^2,
     * rad/s^2]; default the noise.* numbers given, else 0.1, 0.005, 0.5, 5 */
    double sim_noise_force, sim_noise_torque, sim_noise_linear, sim_noise_angular;
    /* simulation.noise.ft_correlation: lag-1 correlation of the force and
     * torque noise, an AR(1) process (a sensor's low-pass filter), [0, 1);
     * default 0 (white) */
    double sim_noise_ft_correlation;
} loadid_config_t;

/* Bits of noise_given: which levels the configuration fixes. */
enum {
    LOADID_NOISE_GIVEN_FORCE = 1 << 0,
    LOADID_NOISE_GIVEN_TORQUE = 1 << 1,
    LOADID_NOISE_GIVEN_LINEAR = 1 << 2,
    LOADID_NOISE_GIVEN_ANGULAR = 1 << 3,
    LOADID_NOISE_GIVEN_OMEGA = 1 << 4,
    LOADID_NOISE_GIVEN_KF_SPEC = 1 << 5,  /* kalman.spec_sigma */
    LOADID_NOISE_GIVEN_KF_ALPHA = 1 << 6, /* kalman.alpha_sigma */
    LOADID_NOISE_GIVEN_KF_MEAS = 1 << 7   /* kalman.meas_sigma */
};

/* Fills cfg with every default (robot_urdf: the shipped RX60, given the
 * source tree root at build time). */
void loadid_config_default(loadid_config_t *cfg);

/* The LCM channel name lcm.channel_prefix + name into out (name is one of
 * the contract's: "LOADID_JOINTS", "LOADID_COMMAND", "LOADID_ESTIMATE",
 * "LOADID_WRENCH", "LOADID_STATUS", "LOADID_MODEL"). */
void loadid_config_channel(const loadid_config_t *cfg, const char *name, char *out, size_t len);

/* Called for each warning (another program's section); msg is a full line. */
typedef void (*loadid_config_warn_fn)(void *ctx, const char *msg);

/* Reads path into cfg (defaults first, then the file). Returns 0, or a
 * negative code with a one-line message in err, cfg then unchanged:
 * -EINVAL "FILE:LINE: KEY: what is wrong" (or an invalid argument),
 * -errno "FILE: cannot read: reason" (-ENOENT, -EISDIR, ...), -ENOMEM;
 * err may be NULL when errlen is 0. warn may be NULL; it is called only
 * on success. */
int loadid_config_load(const char *path, loadid_config_t *cfg, char *err, size_t errlen,
                       loadid_config_warn_fn warn, void *warn_ctx);

/* The same from text in memory (len bytes, need not be NUL-terminated),
 * as if it were the file at path (named in messages; relative paths in it
 * are resolved against its folder; nothing is read from disk). For the
 * fuzzer and tests. Returns 0, -EINVAL or -ENOMEM as loadid_config_load. */
int loadid_config_load_string(const char *path, const char *text, size_t len, loadid_config_t *cfg,
                              char *err, size_t errlen, loadid_config_warn_fn warn, void *warn_ctx);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_CONFIG_H */
