/*
 * The configuration file (loadid/config.h): defaults, then the YAML file
 * read through yaml_tree.h, every value checked where it is read so that
 * the error names its own line and key.
 */
#define _POSIX_C_SOURCE 200809L

#include "loadid/config.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "loadid/estimator.h"
#include "loadid/joint_filter.h"
#include "loadid/modbus_ft.h"
#include "loadid/signals.h"
#include "loadid/yaml_tree.h"

#ifndef LOADID_DEFAULT_URDF
#error "the build defines LOADID_DEFAULT_URDF, the path of the shipped rx60.urdf"
#endif

/* SocketCAN interface names hold at most IFNAMSIZ - 1 = 15 characters. */
#define CAN_IFNAME_MAX 15
/* base+4 (the full-scale frame) is the highest identifier of the JR3
 * group and must stay an 11-bit identifier (docs/INTERFACE.md, JR3 over CAN). */
#define CAN_BASE_ID_MAX (0x7FFu - 4u)

/* The paper's load o1 (section V.A) [kg, kg m, kg m^2], as in
 * tools/synth's loadid_synth_phi_o1. */
static const double kPhiO1[10] = {1.00,    -43.5e-3, 28.5e-3, 22.5e-3,  2.21e-3,
                                  1.22e-3, 0.96e-3,  3.74e-3, -0.63e-3, 4.95e-3};

void loadid_config_default(loadid_config_t *cfg) {
    if (!cfg) return;
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->robot_urdf, sizeof cfg->robot_urdf, "%s", LOADID_DEFAULT_URDF);
    snprintf(cfg->robot_urdf_origin, sizeof cfg->robot_urdf_origin, "robot.urdf (default)");
    snprintf(cfg->robot_base_link, sizeof cfg->robot_base_link, "base_link");
    snprintf(cfg->robot_sensor_link, sizeof cfg->robot_sensor_link, "ft_sensor");
    cfg->robot_gravity[2] = -9.81;

    snprintf(cfg->can_interface, sizeof cfg->can_interface, "vcan0");
    cfg->can_base_id = 0x1A0;
    for (int i = 0; i < 3; ++i) {
        /* the paper's JR3 85M35A3-I40-D 200N12; accelerometer full scales
         * are configuration values (docs/INTERFACE.md) */
        cfg->jr3_fs_force[i] = 200.0;
        cfg->jr3_fs_moment[i] = 12.0;
        cfg->jr3_fs_linear[i] = 98.1;
        cfg->jr3_fs_angular[i] = 1000.0;
    }
    snprintf(cfg->lcm_url, sizeof cfg->lcm_url, "udpm://239.255.76.67:7667?ttl=0");

    cfg->num_methods = 3;
    cfg->methods[0] = LOADID_METHOD_RTLS;
    cfg->methods[1] = LOADID_METHOD_RIV;
    cfg->methods[2] = LOADID_METHOD_RLS;
    /* kf with the fixed-lag smoother (kalman.lag_s), chosen by the study
     * (tools/study): on 9 cells of 2 robots, 3 loads and 3 noise levels it
     * gave RTLS 2-3 times smaller COM and inertia errors than mixed (whose
     * accelerometer a - g carries vibration), and no vibration to suffer. */
    cfg->signals = LOADID_SIGNALS_KF;
    cfg->offset_model_estimate = 0;
    cfg->duration_s = 1.5;
    cfg->publish_every = 1;
    cfg->max_missing_share = 0.02;
    cfg->max_refused_share = 0.1;
    cfg->rescale_s = 0.3;
    cfg->zeroing_window_s = 0.2;

    cfg->sensor_type = LOADID_SENSOR_JR3;
    snprintf(cfg->modbus_device, sizeof cfg->modbus_device, "/dev/ttyUSB0");
    cfg->modbus_baud = 115200;
    cfg->modbus_parity = 'N';
    cfg->modbus_data_bits = 8;
    cfg->modbus_stop_bits = 1;
    cfg->modbus_slave_id = 1;
    cfg->modbus_rate_hz = 200.0;
    cfg->modbus_timeout_ms = 20;
    for (int i = 0; i < 3; ++i) {
        cfg->modbus_fs_force[i] = 200.0;
        cfg->modbus_fs_moment[i] = 12.0;
    }

    cfg->noise_force = 0.1;
    cfg->noise_torque = 0.005;
    cfg->noise_linear = 0.5;
    cfg->noise_angular = 5.0;
    cfg->noise_omega = 0.02;
    cfg->omega_typical = 2.0;

    /* The joint side's own defaults, so the two never drift apart. */
    loadid_jf_config_t jf;
    loadid_jf_config_default(&jf);
    loadid_signals_config_t sig;
    loadid_signals_config_default(&sig);
    /* 1, not the causal filter's 1e3: behind the fixed-lag smoother a
     * narrower bandwidth (42 Hz) costs no lag, keeps out what the
     * motor-side encoders see but the load does not (backlash) and puts
     * less noise into a - g. REFINED, which picks its smoother's bandwidth
     * from the wrench fit, chooses 1 on the 2 Hz study trajectories and
     * 0.1 on slow ones; against 10, 1 left the study's fast cells as they
     * were and on 30 slow recordings (0.1-0.4 Hz, zeroing while moving)
     * took RTLS's largest mass error from 13.8 % to 3.4 %. With
     * kalman.lag_s 0, 1e3 is the causal filter's best (joint_filter.h). */
    cfg->kalman_jerk_psd = 1.0;
    cfg->kalman_meas_sigma = (double)jf.meas_sigma;
    cfg->kalman_max_joint_age_s = (double)sig.max_joint_age_us / 1e6;
    cfg->kalman_lag_s = 0.05;
    cfg->kalman_stamp_gain = (double)sig.stamp_gain;
    cfg->kalman_joint_period_s = 0; /* auto: measured from the stream */
    cfg->rt_cpu = -1;
    cfg->kalman_spec_sigma = 0.5;
    cfg->kalman_alpha_sigma = 1.0;
    cfg->model_mass_rel_std = 0.025;
    cfg->model_com_std = 0.005;
    cfg->model_inertia_rel_std = 0.15;
    cfg->model_max_gyration = 0.5;
    cfg->model_fallback_density = 2700.0;
    cfg->model_min_snr = 1.0;
    cfg->sim_noise_force = 0.1;
    cfg->sim_noise_torque = 0.005;
    cfg->sim_noise_linear = 0.5;
    cfg->sim_noise_angular = 5.0;

    cfg->traj_base_frequency = 0.5;
    cfg->traj_harmonics = 4;
    cfg->traj_max_frequency = 2.0;
    cfg->traj_active_s = 1.5;
    cfg->traj_fade_s = 0.5;
    for (int i = 0; i < LOADID_MAX_JOINTS; ++i) cfg->traj_acc_limit[i] = 20.0;
    cfg->traj_vel_scale = 1.0;
    for (int i = 0; i < 3; ++i) {
        cfg->traj_workspace_min[i] = -1e9;
        cfg->traj_workspace_max[i] = 1e9;
    }
    cfg->traj_floor_z = -1e9;
    cfg->traj_floor_clearance = 0.05;
    cfg->traj_monte_carlo = 2000;
    cfg->traj_candidates = 4;
    cfg->traj_max_evals = 3000;
    cfg->traj_seed = 1;

    cfg->sim_servo_bandwidth_hz = 15.0;
    cfg->sim_servo_damping = 0.9;
    cfg->sim_backlash = 2e-4;
    cfg->sim_encoder_counts = 1048576.0; /* 2^20 */
    cfg->sim_vibration_hz = 28.0;
    cfg->sim_vibration_linear = 0.3;
    cfg->sim_vibration_angular = 3.0;
    cfg->sim_vibration_start_s = 0.0;
    cfg->sim_still_s = 0.5;
    memcpy(cfg->sim_load_phi, kPhiO1, sizeof kPhiO1);
    static const double kOffset[6] = {2.0, -1.5, 3.0, 0.08, -0.05, 0.03};
    memcpy(cfg->sim_offset, kOffset, sizeof kOffset);
    cfg->sim_seed = 1;
    cfg->sim_zero = 1; /* sim_drift, sim_accel_bias, sim_alpha_bias, sim_jitter_us: 0 */
    cfg->sim_trajectory_scale = 1.0;
}

/* --- Checked readers: 1 read, 0 absent, -EINVAL (message in the doc) ------ */

typedef enum { ANY, POSITIVE, NON_NEGATIVE } sign_rule_t;

static int check_sign(const loadid_yaml_node_t *n, double v, sign_rule_t rule) {
    if (rule == POSITIVE && !(v > 0)) return loadid_yaml_fail(n, "must be > 0, got %g", v);
    if (rule == NON_NEGATIVE && !(v >= 0)) return loadid_yaml_fail(n, "must be >= 0, got %g", v);
    return 0;
}

static int read_number(loadid_yaml_node_t *map, const char *key, double *out, sign_rule_t rule) {
    loadid_yaml_node_t *n = loadid_yaml_get(map, key);
    double v;
    if (!n) return 0;
    if (loadid_yaml_as_double(n, &v) || check_sign(n, v, rule)) return -EINVAL;
    *out = v;
    return 1;
}

/* A share of the window: a number in [0, 1]. */
static int read_share(loadid_yaml_node_t *map, const char *key, double *out) {
    const int rc = read_number(map, key, out, NON_NEGATIVE);
    if (rc == 1 && *out > 1)
        return loadid_yaml_fail(loadid_yaml_get(map, key),
                                "a share of the window's samples: must be <= 1, got %g", *out);
    return rc;
}

/* A sequence of min..max numbers (*count of them; count may be NULL when
 * min == max), each checked at its own line. */
static int read_numbers(loadid_yaml_node_t *map, const char *key, double *out, size_t min,
                        size_t max, size_t *count, sign_rule_t rule) {
    loadid_yaml_node_t *n = loadid_yaml_get(map, key);
    double v[LOADID_MAX_JOINTS > 10 ? LOADID_MAX_JOINTS : 10];
    size_t k = 0;
    if (!n) return 0;
    if (max > sizeof v / sizeof v[0]) return loadid_yaml_fail(n, "internal: too many numbers");
    if (loadid_yaml_as_doubles(n, v, min, max, &k)) return -EINVAL;
    for (size_t i = 0; i < k; ++i)
        if (check_sign(loadid_yaml_item(n, i), v[i], rule)) return -EINVAL;
    memcpy(out, v, k * sizeof v[0]);
    if (count) *count = k;
    return 1;
}

static int read_int(loadid_yaml_node_t *map, const char *key, int *out, int min) {
    loadid_yaml_node_t *n = loadid_yaml_get(map, key);
    int v;
    if (!n) return 0;
    if (loadid_yaml_as_int(n, &v)) return -EINVAL;
    if (v < min) return loadid_yaml_fail(n, "must be >= %d, got %d", min, v);
    *out = v;
    return 1;
}

static int read_uint64(loadid_yaml_node_t *map, const char *key, uint64_t *out) {
    return loadid_yaml_get_uint64(map, key, out);
}

static int read_name(loadid_yaml_node_t *map, const char *key, char *buf, size_t size) {
    loadid_yaml_node_t *n = loadid_yaml_get(map, key);
    if (!n) return 0;
    if (loadid_yaml_as_string(n, buf, size)) return -EINVAL;
    if (buf[0] == '\0') return loadid_yaml_fail(n, "must not be empty");
    return 1;
}

static int read_section(loadid_yaml_node_t *map, const char *key, loadid_yaml_node_t **out) {
    return loadid_yaml_get_mapping(map, key, out);
}

/* rel against the directory of config_path, made absolute (against the
 * working directory when config_path is relative), so that it stays valid
 * when the daemon changes directory. Not normalised, not checked for
 * existence: the URDF reader reports a missing file with its path. */
static int resolve_path(const loadid_yaml_node_t *n, const char *config_path, const char *rel,
                        char *out, size_t size) {
    char dir[LOADID_PATH_MAX];
    size_t len;
    if (rel[0] == '/') {
        len = (size_t)snprintf(out, size, "%s", rel);
    } else {
        const char *slash = strrchr(config_path, '/');
        size_t dlen = 0;
        if (config_path[0] != '/') {
            if (!getcwd(dir, sizeof dir))
                return loadid_yaml_fail(n, "cannot resolve %s: working directory: %s", rel,
                                        strerror(errno));
            dlen = strlen(dir);
        }
        if (slash) {
            const size_t part = (size_t)(slash - config_path);
            if (dlen + 1 + part + 1 > sizeof dir)
                return loadid_yaml_fail(n, "resolved path longer than %d characters",
                                        LOADID_PATH_MAX - 1);
            if (dlen > 0 && part > 0) dir[dlen++] = '/';
            memcpy(dir + dlen, config_path, part);
            dlen += part;
            if (dlen == 0) dir[dlen++] = '/'; /* config in / */
        }
        dir[dlen] = '\0';
        const int sep = dlen > 0 && dir[dlen - 1] != '/';
        len = (size_t)snprintf(out, size, "%s%s%s", dir, sep ? "/" : "", rel);
    }
    if (len >= size)
        return loadid_yaml_fail(n, "resolved path longer than %zu characters", size - 1);
    return 0;
}

#define TRY(expr)                  \
    do {                           \
        if ((expr) < 0) goto fail; \
    } while (0)

static const char *kind_name(const loadid_yaml_node_t *n) {
    switch (loadid_yaml_kind(n)) {
        case LOADID_YAML_MAPPING:
            return "a mapping";
        case LOADID_YAML_SEQUENCE:
            return "a sequence";
        default:
            return "a scalar";
    }
}

/* The first of the nodes given that is present: where a check of several
 * keys together is reported. */
static const loadid_yaml_node_t *first_present(const loadid_yaml_node_t *a,
                                               const loadid_yaml_node_t *b,
                                               const loadid_yaml_node_t *c) {
    return a ? a : b ? b : c;
}

/* An optional integer in [lo, hi]. */
static int read_int_range(loadid_yaml_node_t *map, const char *key, int *out, int lo, int hi) {
    loadid_yaml_node_t *n = map ? loadid_yaml_get(map, key) : NULL;
    if (!n) return 0;
    int v;
    if (loadid_yaml_as_int(n, &v) < 0) return -EINVAL;
    if (v < lo || v > hi) return loadid_yaml_fail(n, "must be %d..%d, got %d", lo, hi, v);
    *out = v;
    return 0;
}

/* An optional boolean. */
static int read_bool_key(loadid_yaml_node_t *map, const char *key, int *out) {
    loadid_yaml_node_t *n = map ? loadid_yaml_get(map, key) : NULL;
    return n ? loadid_yaml_as_bool(n, out) : 0;
}

/* An optional path, resolved against the configuration file's folder. */
static int read_path(loadid_yaml_node_t *map, const char *config_path, const char *key, char *out,
                     size_t size) {
    loadid_yaml_node_t *n = map ? loadid_yaml_get(map, key) : NULL;
    if (!n) return 0;
    char rel[LOADID_PATH_MAX];
    TRY(loadid_yaml_as_string(n, rel, sizeof rel));
    if (!rel[0]) return loadid_yaml_fail(n, "must not be empty");
    TRY(resolve_path(n, config_path, rel, out, size));
    return 0;
fail:
    return -EINVAL;
}

static int read_robot(loadid_yaml_node_t *root, const char *path, loadid_config_t *c) {
    loadid_yaml_node_t *s = NULL, *n;
    TRY(read_section(root, "robot", &s));
    char urdf[LOADID_PATH_MAX];
    if ((n = loadid_yaml_get(s, "urdf"))) {
        TRY(loadid_yaml_as_string(n, urdf, sizeof urdf));
        if (!urdf[0]) return loadid_yaml_fail(n, "must not be empty");
        TRY(resolve_path(n, path, urdf, c->robot_urdf, sizeof c->robot_urdf));
        snprintf(c->robot_urdf_origin, sizeof c->robot_urdf_origin, "%s:%d: robot.urdf", path,
                 loadid_yaml_line(n));
    }
    TRY(read_name(s, "base_link", c->robot_base_link, sizeof c->robot_base_link));
    TRY(read_name(s, "sensor_link", c->robot_sensor_link, sizeof c->robot_sensor_link));
    TRY(read_numbers(s, "gravity", c->robot_gravity, 3, 3, NULL, ANY));
    return 0;
fail:
    return -EINVAL;
}

/* lcm.command_sources: a sequence of IPv4 addresses or CIDR blocks ([]
 * is every sender, as without the key). */
static int read_command_sources(loadid_yaml_node_t *seq, loadid_config_t *c) {
    const size_t count = loadid_yaml_count(seq);
    if (count > LOADID_IPV4_ALLOW_MAX)
        return loadid_yaml_fail(seq, "at most %d addresses or blocks, got %zu",
                                LOADID_IPV4_ALLOW_MAX, count);
    loadid_ipv4_net_t nets[LOADID_IPV4_ALLOW_MAX];
    for (size_t i = 0; i < count; ++i) {
        const loadid_yaml_node_t *item = loadid_yaml_item(seq, i);
        char text[64], fixed[20];
        if (loadid_yaml_as_string(item, text, sizeof text)) return -EINVAL;
        const int rc = loadid_ipv4_net_parse(text, &nets[i]);
        if (rc == -ERANGE)
            return loadid_yaml_fail(item,
                                    "'%s' has bits set after its prefix length; the block "
                                    "is %s",
                                    text, loadid_ipv4_net_format(&nets[i], fixed, sizeof fixed));
        if (rc < 0)
            return loadid_yaml_fail(item,
                                    "expected an IPv4 address (a.b.c.d) or block "
                                    "(a.b.c.d/n, n 0..32), got '%s'",
                                    text);
    }
    memcpy(c->lcm_command_sources, nets, count * sizeof nets[0]);
    c->lcm_num_command_sources = (int)count;
    return 0;
}

static int read_can_jr3_lcm(loadid_yaml_node_t *root, loadid_config_t *c) {
    loadid_yaml_node_t *s = NULL, *fs = NULL, *n;
    TRY(read_section(root, "can", &s));
    if ((n = loadid_yaml_get(s, "interface"))) {
        char name[sizeof c->can_interface];
        TRY(loadid_yaml_as_string(n, name, sizeof name));
        if (!name[0] || strlen(name) > CAN_IFNAME_MAX)
            return loadid_yaml_fail(n, "a network interface name has 1 to %d characters, got '%s'",
                                    CAN_IFNAME_MAX, name);
        snprintf(c->can_interface, sizeof c->can_interface, "%s", name); /* no bytes past the NUL */
    }
    if ((n = loadid_yaml_get(s, "base_id"))) {
        uint64_t id;
        TRY(loadid_yaml_as_uint64(n, &id));
        if (id > CAN_BASE_ID_MAX)
            return loadid_yaml_fail(n,
                                    "must be at most 0x%X (base+4 must be an 11-bit identifier, "
                                    "<= 0x7FF), got 0x%llX",
                                    CAN_BASE_ID_MAX, (unsigned long long)id);
        c->can_base_id = (uint32_t)id;
    }

    TRY(read_section(root, "jr3", &s));
    TRY(read_section(s, "full_scale", &fs));
    TRY(read_numbers(fs, "force", c->jr3_fs_force, 3, 3, NULL, POSITIVE));
    TRY(read_numbers(fs, "moment", c->jr3_fs_moment, 3, 3, NULL, POSITIVE));
    TRY(read_numbers(fs, "linear", c->jr3_fs_linear, 3, 3, NULL, POSITIVE));
    TRY(read_numbers(fs, "angular", c->jr3_fs_angular, 3, 3, NULL, POSITIVE));

    TRY(read_section(root, "lcm", &s));
    if ((n = loadid_yaml_get(s, "url"))) {
        char url[sizeof c->lcm_url];
        TRY(loadid_yaml_as_string(n, url, sizeof url));
        const char *sep = strstr(url, "://");
        if (!sep || sep == url)
            return loadid_yaml_fail(n,
                                    "expected an LCM URL such as "
                                    "udpm://239.255.76.67:7667?ttl=0, got '%s'",
                                    url);
        snprintf(c->lcm_url, sizeof c->lcm_url, "%s", url);
    }
    if ((n = loadid_yaml_get(s, "channel_prefix")) && !loadid_yaml_is_null(n)) {
        char prefix[sizeof c->lcm_channel_prefix];
        TRY(loadid_yaml_as_string(n, prefix, sizeof prefix));
        for (const char *ch = prefix; *ch; ++ch)
            if (!isalnum((unsigned char)*ch) && !strchr("_-./", *ch))
                return loadid_yaml_fail(n,
                                        "a channel name prefix of letters, digits, '_', '-', "
                                        "'.' and '/' only, got '%s'",
                                        prefix);
        snprintf(c->lcm_channel_prefix, sizeof c->lcm_channel_prefix, "%s", prefix);
    }
    if (loadid_yaml_get(s, "command_sources")) {
        TRY(loadid_yaml_get_sequence(s, "command_sources", &n));
        TRY(read_command_sources(n, c));
    }
    return 0;
fail:
    return -EINVAL;
}

/* A number > 0 or "auto" (what: the message's "expected ..."): 1 and *out
 * for a number, 2 for auto (*out unchanged), 0 when absent, -EINVAL. */
static int read_positive_or_auto(loadid_yaml_node_t *map, const char *key, double *out,
                                 const char *what) {
    loadid_yaml_node_t *n = loadid_yaml_get(map, key);
    char word[16];
    if (!n) return 0;
    if (loadid_yaml_kind(n) == LOADID_YAML_SCALAR && loadid_yaml_as_double(n, out) == 0)
        return check_sign(n, *out, POSITIVE) ? -EINVAL : 1;
    if (loadid_yaml_kind(n) != LOADID_YAML_SCALAR || loadid_yaml_as_string(n, word, sizeof word) ||
        strcmp(word, "auto") != 0)
        return loadid_yaml_fail(n, "expected %s", what);
    return 2;
}

/* kalman.joint_period_s: a period > 0, or auto (0: measured). */
static int read_period(loadid_yaml_node_t *map, const char *key, double *out) {
    const int rc = read_positive_or_auto(map, key, out, "a period in seconds > 0 or auto");
    if (rc == 2) *out = 0;
    return rc;
}

/* A noise level: a number > 0 (its bit set in noise_given) or "auto". */
static int read_level(loadid_yaml_node_t *map, const char *key, double *out, int bit,
                      loadid_config_t *c) {
    const int rc = read_positive_or_auto(map, key, out, "a number > 0 or auto");
    if (rc == 1) c->noise_given |= bit;
    return rc;
}

/* noise: auto, or a mapping of levels (each a number or auto). */
static int read_noise(loadid_yaml_node_t *root, loadid_config_t *c) {
    loadid_yaml_node_t *s = loadid_yaml_get(root, "noise");
    char word[16];
    if (!s || loadid_yaml_is_null(s)) return 0;
    if (loadid_yaml_kind(s) == LOADID_YAML_SCALAR) {
        if (loadid_yaml_as_string(s, word, sizeof word) || strcmp(word, "auto") != 0)
            return loadid_yaml_fail(s, "expected auto or a mapping of noise levels");
        return 0;
    }
    TRY(read_section(root, "noise", &s));
    TRY(read_level(s, "force", &c->noise_force, LOADID_NOISE_GIVEN_FORCE, c));
    TRY(read_level(s, "torque", &c->noise_torque, LOADID_NOISE_GIVEN_TORQUE, c));
    TRY(read_level(s, "linear", &c->noise_linear, LOADID_NOISE_GIVEN_LINEAR, c));
    TRY(read_level(s, "angular", &c->noise_angular, LOADID_NOISE_GIVEN_ANGULAR, c));
    TRY(read_level(s, "omega", &c->noise_omega, LOADID_NOISE_GIVEN_OMEGA, c));
    TRY(read_number(s, "omega_typical", &c->omega_typical, POSITIVE));
    return 0;
fail:
    return -EINVAL;
}

static int read_methods(loadid_yaml_node_t *seq, loadid_config_t *c) {
    const size_t count = loadid_yaml_count(seq);
    if (count == 0) return loadid_yaml_fail(seq, "expected at least one method, got none");
    int methods[LOADID_MAX_METHODS];
    size_t first[LOADID_METHOD_REFINED + 1] = {0}; /* 1 + index of its first listing */
    for (size_t i = 0; i < count; ++i) {
        const loadid_yaml_node_t *item = loadid_yaml_item(seq, i);
        char name[64];
        if (loadid_yaml_as_string(item, name, sizeof name)) return -EINVAL;
        const int m = loadid_method_from_name(name);
        if (m < LOADID_METHOD_RLS || m > LOADID_METHOD_REFINED)
            return loadid_yaml_fail(
                item, "unknown method '%s' (RLS, RIV, RTLS, LS_BATCH, TLS_BATCH or REFINED)", name);
        if (first[m])
            return loadid_yaml_fail(item, "method %s listed twice (first as item %zu)", name,
                                    first[m] - 1);
        first[m] = i + 1;
        /* six names and no duplicates: i < LOADID_MAX_METHODS here */
        methods[i] = m;
    }
    memcpy(c->methods, methods, count * sizeof methods[0]);
    c->num_methods = (int)count;
    return 0;
}

static int read_estimation(loadid_yaml_node_t *root, const char *path, loadid_config_t *c) {
    loadid_yaml_node_t *s = NULL, *n;
    char word[64];
    TRY(read_section(root, "estimation", &s));
    if (loadid_yaml_get(s, "methods")) {
        TRY(loadid_yaml_get_sequence(s, "methods", &n));
        TRY(read_methods(n, c));
    }
    if ((n = loadid_yaml_get(s, "signals"))) {
        TRY(loadid_yaml_as_string(n, word, sizeof word));
        loadid_signal_source_t src;
        if (loadid_signal_source_parse(word, &src))
            return loadid_yaml_fail(n, "unknown signal source '%s' (sensor, kf, setpoint or mixed)",
                                    word);
        c->signals = (int)src;
    }
    if ((n = loadid_yaml_get(s, "offset_model"))) {
        TRY(loadid_yaml_as_string(n, word, sizeof word));
        if (!strcmp(word, "zeroing"))
            c->offset_model_estimate = 0;
        else if (!strcmp(word, "estimate"))
            c->offset_model_estimate = 1;
        else
            return loadid_yaml_fail(n, "unknown offset model '%s' (zeroing or estimate)", word);
    }
    TRY(read_number(s, "duration_s", &c->duration_s, POSITIVE));
    TRY(read_int_range(s, "publish_every", &c->publish_every, 1, 1000000));
    TRY(read_number(s, "rescale_s", &c->rescale_s, NON_NEGATIVE));
    TRY(read_share(s, "max_missing_share", &c->max_missing_share));
    TRY(read_share(s, "max_refused_share", &c->max_refused_share));

    TRY(read_section(root, "zeroing", &s));
    TRY(read_number(s, "window_s", &c->zeroing_window_s, POSITIVE));

    TRY(read_section(root, "distal", &s));
    TRY(read_numbers(s, "phi", c->distal_phi, 10, 10, NULL, ANY));

    TRY(read_section(root, "realtime", &s));
    TRY(read_int_range(s, "priority", &c->rt_priority, 0, 99));
    TRY(read_bool_key(s, "lock_memory", &c->rt_lock_memory));
    TRY(read_int_range(s, "cpu", &c->rt_cpu, -1, 4095));

    TRY(read_section(root, "results", &s));
    TRY(read_path(s, path, "directory", c->results_directory, sizeof c->results_directory));
    TRY(read_path(s, path, "load", c->results_load, sizeof c->results_load));
    TRY(read_bool_key(s, "trace", &c->results_trace));
    if (c->results_trace && !c->results_directory[0])
        return loadid_yaml_fail(loadid_yaml_get(s, "trace"),
                                "needs results.directory (the trace goes beside the saved result)");

    TRY(read_noise(root, c));

    TRY(read_section(root, "kalman", &s));
    TRY(read_number(s, "jerk_psd", &c->kalman_jerk_psd, POSITIVE));
    TRY(read_level(s, "meas_sigma", &c->kalman_meas_sigma, LOADID_NOISE_GIVEN_KF_MEAS, c));
    TRY(read_number(s, "max_joint_age_s", &c->kalman_max_joint_age_s, POSITIVE));
    TRY(read_number(s, "lag_s", &c->kalman_lag_s, NON_NEGATIVE));
    if (read_number(s, "joint_delay_s", &c->kalman_joint_delay_s, ANY) == 1 &&
        fabs(c->kalman_joint_delay_s) > 0.1)
        return loadid_yaml_fail(loadid_yaml_get(s, "joint_delay_s"),
                                "must be within +-0.1 s, got %g", c->kalman_joint_delay_s);
    if (read_number(s, "stamp_gain", &c->kalman_stamp_gain, POSITIVE) == 1 &&
        c->kalman_stamp_gain > 1)
        return loadid_yaml_fail(loadid_yaml_get(s, "stamp_gain"), "must be <= 1, got %g",
                                c->kalman_stamp_gain);
    TRY(read_period(s, "joint_period_s", &c->kalman_joint_period_s));
    if (c->kalman_joint_period_s > 0 &&
        c->kalman_lag_s > c->kalman_joint_period_s * LOADID_JF_MAX_LAG + 1e-12) {
        /* Only joint_period_s may be given (the lag its default): blame the
         * key that is there. */
        loadid_yaml_node_t *lag = loadid_yaml_get(s, "lag_s");
        return loadid_yaml_fail(lag ? lag : loadid_yaml_get(s, "joint_period_s"),
                                "kalman.lag_s%s must be at most %d joint periods (%g s), got %g",
                                lag ? "" : " (its default)", LOADID_JF_MAX_LAG,
                                c->kalman_joint_period_s * LOADID_JF_MAX_LAG, c->kalman_lag_s);
    }
    TRY(read_level(s, "spec_sigma", &c->kalman_spec_sigma, LOADID_NOISE_GIVEN_KF_SPEC, c));
    TRY(read_level(s, "alpha_sigma", &c->kalman_alpha_sigma, LOADID_NOISE_GIVEN_KF_ALPHA, c));

    TRY(read_section(root, "model", &s));
    TRY(read_number(s, "mass_rel_std", &c->model_mass_rel_std, POSITIVE));
    TRY(read_number(s, "com_std", &c->model_com_std, POSITIVE));
    TRY(read_number(s, "inertia_rel_std", &c->model_inertia_rel_std, POSITIVE));
    TRY(read_number(s, "max_gyration", &c->model_max_gyration, POSITIVE));
    TRY(read_number(s, "fallback_density", &c->model_fallback_density, POSITIVE));
    TRY(read_number(s, "min_snr", &c->model_min_snr, NON_NEGATIVE));
    return 0;
fail:
    return -EINVAL;
}

/* sensor: and modbus:, after estimation: (signals is checked against the
 * sensor type). */
static int read_sensor_modbus(loadid_yaml_node_t *root, loadid_config_t *c) {
    loadid_yaml_node_t *s = NULL, *fs = NULL, *n, *type = NULL;
    char word[64];
    TRY(read_section(root, "sensor", &s));
    if ((type = loadid_yaml_get(s, "type"))) {
        TRY(loadid_yaml_as_string(type, word, sizeof word));
        if (!strcmp(word, "jr3"))
            c->sensor_type = LOADID_SENSOR_JR3;
        else if (!strcmp(word, "modbus"))
            c->sensor_type = LOADID_SENSOR_MODBUS;
        else
            return loadid_yaml_fail(type, "unknown sensor type '%s' (jr3 or modbus)", word);
    }
    if (c->sensor_type == LOADID_SENSOR_MODBUS &&
        (c->signals == LOADID_SIGNALS_SENSOR || c->signals == LOADID_SIGNALS_MIXED)) {
        loadid_yaml_node_t *sig = NULL, *est = NULL;
        if (loadid_yaml_get_mapping(root, "estimation", &est) >= 0 && est)
            sig = loadid_yaml_get(est, "signals");
        return loadid_yaml_fail(type,
                                "a Modbus F/T sensor has no accelerometer: estimation.signals "
                                "must be kf or setpoint, got %s%s",
                                c->signals == LOADID_SIGNALS_SENSOR ? "sensor" : "mixed",
                                sig ? "" : " (the default)");
    }

    TRY(read_section(root, "modbus", &s));
    if ((n = loadid_yaml_get(s, "device"))) {
        char dev[sizeof c->modbus_device];
        TRY(loadid_yaml_as_string(n, dev, sizeof dev));
        if (!dev[0]) return loadid_yaml_fail(n, "must not be empty");
        snprintf(c->modbus_device, sizeof c->modbus_device, "%s", dev);
    }
    if ((n = loadid_yaml_get(s, "baud"))) {
        int baud;
        TRY(loadid_yaml_as_int(n, &baud));
        if (!loadid_modbus_ft_baud_supported(baud))
            return loadid_yaml_fail(n,
                                    "unsupported baud rate %d (one of 1200, 2400, 4800, 9600, "
                                    "19200, 38400, 57600, 115200, 230400, 460800, 921600, ...)",
                                    baud);
        c->modbus_baud = baud;
    }
    if ((n = loadid_yaml_get(s, "parity"))) {
        TRY(loadid_yaml_as_string(n, word, sizeof word));
        if (!strcmp(word, "none"))
            c->modbus_parity = 'N';
        else if (!strcmp(word, "even"))
            c->modbus_parity = 'E';
        else if (!strcmp(word, "odd"))
            c->modbus_parity = 'O';
        else
            return loadid_yaml_fail(n, "unknown parity '%s' (none, even or odd)", word);
    }
    TRY(read_int_range(s, "data_bits", &c->modbus_data_bits, 5, 8));
    TRY(read_int_range(s, "stop_bits", &c->modbus_stop_bits, 1, 2));
    TRY(read_int_range(s, "slave_id", &c->modbus_slave_id, 1, 247));
    if ((n = loadid_yaml_get(s, "rate_hz"))) {
        TRY(read_number(s, "rate_hz", &c->modbus_rate_hz, POSITIVE));
        if (c->modbus_rate_hz > 1000)
            return loadid_yaml_fail(n, "must be <= 1000 Hz, got %g", c->modbus_rate_hz);
    }
    TRY(read_int_range(s, "timeout_ms", &c->modbus_timeout_ms, 1, 60000));
    TRY(read_section(s, "full_scale", &fs));
    TRY(read_numbers(fs, "force", c->modbus_fs_force, 3, 3, NULL, POSITIVE));
    TRY(read_numbers(fs, "moment", c->modbus_fs_moment, 3, 3, NULL, POSITIVE));
    return 0;
fail:
    return -EINVAL;
}

static int read_trajectory(loadid_yaml_node_t *root, loadid_config_t *c) {
    loadid_yaml_node_t *s = NULL, *ws = NULL, *n;
    TRY(read_section(root, "trajectory", &s));
    TRY(read_number(s, "base_frequency", &c->traj_base_frequency, POSITIVE));
    TRY(read_int(s, "harmonics", &c->traj_harmonics, 1));
    TRY(read_number(s, "max_frequency", &c->traj_max_frequency, POSITIVE));
    /* The highest harmonic N f of eq. (10) within the allowed band; the
     * relative slack keeps 3 * 0.1 <= 0.3 true in binary. */
    if (c->traj_harmonics * c->traj_base_frequency > c->traj_max_frequency * (1 + 1e-9)) {
        return loadid_yaml_fail(
            first_present(loadid_yaml_get(s, "harmonics"), loadid_yaml_get(s, "base_frequency"),
                          loadid_yaml_get(s, "max_frequency")),
            "%d harmonics of %g Hz reach %g Hz, above trajectory.max_frequency %g Hz",
            c->traj_harmonics, c->traj_base_frequency, c->traj_harmonics * c->traj_base_frequency,
            c->traj_max_frequency);
    }
    TRY(read_number(s, "active_s", &c->traj_active_s, POSITIVE));
    TRY(read_number(s, "fade_s", &c->traj_fade_s, NON_NEGATIVE));

    size_t k = 0;
    int rc;
    TRY(rc = read_numbers(s, "home", c->traj_home, 1, LOADID_MAX_JOINTS, &k, ANY));
    if (rc == 1) {
        c->traj_has_home = 1;
        c->traj_num_home = (int)k;
    }
    if ((n = loadid_yaml_get(s, "acc_limit")) && loadid_yaml_kind(n) == LOADID_YAML_SCALAR) {
        double a = 0;
        TRY(read_number(s, "acc_limit", &a, POSITIVE)); /* one limit for every joint */
        for (int i = 0; i < LOADID_MAX_JOINTS; ++i) c->traj_acc_limit[i] = a;
        c->traj_num_acc_limits = 0;
    } else {
        TRY(rc = read_numbers(s, "acc_limit", c->traj_acc_limit, 1, LOADID_MAX_JOINTS, &k,
                              POSITIVE));
        if (rc == 1) c->traj_num_acc_limits = (int)k;
    }
    if ((n = loadid_yaml_get(s, "vel_scale"))) {
        TRY(read_number(s, "vel_scale", &c->traj_vel_scale, POSITIVE));
        if (c->traj_vel_scale > 1)
            return loadid_yaml_fail(n,
                                    "a fraction of the URDF velocity limits: must be <= 1, "
                                    "got %g",
                                    c->traj_vel_scale);
    }
    TRY(read_section(s, "workspace", &ws));
    TRY(read_numbers(ws, "min", c->traj_workspace_min, 3, 3, NULL, ANY));
    TRY(read_numbers(ws, "max", c->traj_workspace_max, 3, 3, NULL, ANY));
    for (int i = 0; i < 3; ++i) {
        if (c->traj_workspace_min[i] < c->traj_workspace_max[i]) continue;
        return loadid_yaml_fail(
            first_present(loadid_yaml_get(ws, "min"), loadid_yaml_get(ws, "max"), NULL),
            "workspace min must be below max on every axis: %c: min %g >= max %g", "xyz"[i],
            c -> traj_workspace_min[i], c -> traj_workspace_max[i]);
    }
    TRY(read_number(s, "floor_z", &c->traj_floor_z, ANY));
    TRY(read_number(s, "floor_clearance", &c->traj_floor_clearance, NON_NEGATIVE));
    TRY(read_int(s, "monte_carlo", &c->traj_monte_carlo, 1));
    TRY(read_int(s, "candidates", &c->traj_candidates, 1));
    if (c->traj_candidates > c->traj_monte_carlo) {
        return loadid_yaml_fail(
            first_present(loadid_yaml_get(s, "candidates"), loadid_yaml_get(s, "monte_carlo"),
                          NULL),
            "%d candidates to optimise out of %d random ones: candidates must be <= monte_carlo",
            c->traj_candidates, c->traj_monte_carlo);
    }
    TRY(read_int(s, "max_evals", &c->traj_max_evals, 1));
    TRY(read_uint64(s, "seed", &c->traj_seed));
    return 0;
fail:
    return -EINVAL;
}

static int read_simulation(loadid_yaml_node_t *root, loadid_config_t *c) {
    loadid_yaml_node_t *s = NULL;
    TRY(read_section(root, "simulation", &s));
    TRY(read_number(s, "servo_bandwidth_hz", &c->sim_servo_bandwidth_hz, POSITIVE));
    TRY(read_number(s, "servo_damping", &c->sim_servo_damping, POSITIVE));
    TRY(read_number(s, "backlash", &c->sim_backlash, NON_NEGATIVE));
    TRY(read_number(s, "encoder_counts", &c->sim_encoder_counts, POSITIVE));
    TRY(read_number(s, "vibration_hz", &c->sim_vibration_hz, POSITIVE));
    TRY(read_number(s, "vibration_linear", &c->sim_vibration_linear, NON_NEGATIVE));
    TRY(read_number(s, "vibration_angular", &c->sim_vibration_angular, NON_NEGATIVE));
    TRY(read_number(s, "vibration_start_s", &c->sim_vibration_start_s, NON_NEGATIVE));
    TRY(read_number(s, "still_s", &c->sim_still_s, NON_NEGATIVE));
    TRY(read_numbers(s, "load_phi", c->sim_load_phi, 10, 10, NULL, ANY));
    TRY(read_numbers(s, "offset", c->sim_offset, 6, 6, NULL, ANY));
    TRY(read_bool_key(s, "zero", &c->sim_zero));
    TRY(read_numbers(s, "drift", c->sim_drift, 6, 6, NULL, ANY));
    TRY(read_numbers(s, "accel_bias", c->sim_accel_bias, 3, 3, NULL, ANY));
    TRY(read_numbers(s, "alpha_bias", c->sim_alpha_bias, 3, 3, NULL, ANY));
    TRY(read_int_range(s, "jitter_us", &c->sim_jitter_us, 0, 999));
    loadid_yaml_node_t *scale = loadid_yaml_get(s, "trajectory_scale");
    if (scale) {
        TRY(read_number(s, "trajectory_scale", &c->sim_trajectory_scale, POSITIVE));
        if (c->sim_trajectory_scale > 1)
            return loadid_yaml_fail(scale,
                                    "a fraction of the trajectory's amplitude: must "
                                    "be <= 1, got %g",
                                    c->sim_trajectory_scale);
    }
    TRY(read_uint64(s, "seed", &c->sim_seed));
    /* The simulated noise: simulation.noise, else the noise.* numbers. */
    if (c->noise_given & LOADID_NOISE_GIVEN_FORCE) c->sim_noise_force = c->noise_force;
    if (c->noise_given & LOADID_NOISE_GIVEN_TORQUE) c->sim_noise_torque = c->noise_torque;
    if (c->noise_given & LOADID_NOISE_GIVEN_LINEAR) c->sim_noise_linear = c->noise_linear;
    if (c->noise_given & LOADID_NOISE_GIVEN_ANGULAR) c->sim_noise_angular = c->noise_angular;
    loadid_yaml_node_t *n = NULL;
    TRY(read_section(s, "noise", &n));
    TRY(read_number(n, "force", &c->sim_noise_force, NON_NEGATIVE));
    TRY(read_number(n, "torque", &c->sim_noise_torque, NON_NEGATIVE));
    TRY(read_number(n, "linear", &c->sim_noise_linear, NON_NEGATIVE));
    TRY(read_number(n, "angular", &c->sim_noise_angular, NON_NEGATIVE));
    TRY(read_number(n, "ft_correlation", &c->sim_noise_ft_correlation, NON_NEGATIVE));
    if (!(c->sim_noise_ft_correlation < 1))
        return loadid_yaml_fail(loadid_yaml_get(n, "ft_correlation"),
                                "a lag-1 correlation: must be < 1, got %g",
                                c->sim_noise_ft_correlation);
    return 0;
fail:
    return -EINVAL;
}

typedef struct {
    loadid_config_warn_fn fn;
    void *ctx;
} warn_sink_t;

static void forward_warning(void *ctx, const char *msg) {
    const warn_sink_t *w = ctx;
    if (w->fn) w->fn(w->ctx, msg);
}

/* Unknown keys (config.h): in a section loadid reads, an error; at the top
 * level, a near miss of a loadid section's name is an error too, and any
 * other name another program's section, a warning. Errors first (the first
 * in file order), so that warnings come only with a successful load. */
typedef struct {
    const loadid_yaml_node_t *root;
    const char *file;
    warn_sink_t *sink; /* NULL: the error pass */
    int failed;        /* the error is in the document */
} unknown_check_t;

static void check_unknown(void *ctx, const loadid_yaml_unused_t *u) {
    unknown_check_t *k = ctx;
    if (k->failed) return;
    const int top = u->map == k->root;
    if (!k->sink) {
        if (u->suggestion) {
            loadid_yaml_fail(u->key, "unknown %s (did you mean '%s'?)", top ? "section" : "key",
                             u->suggestion);
            k->failed = 1;
        } else if (!top) {
            char section[512], known[768];
            loadid_yaml_path(u->map, section, sizeof section);
            loadid_yaml_known_keys(u->map, known, sizeof known);
            loadid_yaml_fail(u->key, "unknown key (%s has %s)", section, known);
            k->failed = 1;
        }
        return;
    }
    char key[512], line[LOADID_PATH_MAX + 600];
    loadid_yaml_path(u->key, key, sizeof key);
    snprintf(line, sizeof line, "%s:%d: %s: not a loadid section, ignored", k->file,
             loadid_yaml_line(u->key), key);
    for (char *ch = line; *ch; ++ch)
        if ((unsigned char)*ch < 0x20 || *ch == 0x7f) *ch = '?'; /* one line */
    forward_warning(k->sink, line);
}

/* The configuration from a parsed document (which it frees); path is the
 * file's, for messages and relative paths. */
static int load_doc(loadid_yaml_doc_t *doc, const char *path, loadid_config_t *cfg, char *err,
                    size_t errlen, loadid_config_warn_fn warn, void *warn_ctx) {
    loadid_config_t *c = malloc(sizeof *c); /* cfg stays untouched on failure */
    if (!c) {
        if (err && errlen) snprintf(err, errlen, "%s: out of memory", path);
        loadid_yaml_free(doc);
        return -ENOMEM;
    }
    loadid_config_default(c);
    loadid_yaml_node_t *root = loadid_yaml_root(doc);
    warn_sink_t sink = {warn, warn_ctx};
    if (!root) {
        char msg[LOADID_PATH_MAX + 96];
        snprintf(msg, sizeof msg,
                 "%s:1: (top level): empty configuration, every key takes its "
                 "default",
                 path);
        forward_warning(&sink, msg);
    } else if (loadid_yaml_kind(root) != LOADID_YAML_MAPPING) {
        loadid_yaml_fail(root, "expected a mapping of sections (robot:, can:, ...), got %s",
                         kind_name(root));
        goto fail;
    }
    TRY(read_robot(root, path, c));
    TRY(read_can_jr3_lcm(root, c));
    TRY(read_estimation(root, path, c));
    TRY(read_sensor_modbus(root, c));
    TRY(read_trajectory(root, c));
    TRY(read_simulation(root, c));
    if (root) {
        unknown_check_t check = {root, path, NULL, 0};
        loadid_yaml_each_unused(doc, check_unknown, &check);
        if (check.failed) goto fail;
        check.sink = &sink;
        loadid_yaml_each_unused(doc, check_unknown, &check);
    }

    *cfg = *c;
    free(c);
    loadid_yaml_free(doc);
    return 0;
fail:
    if (err && errlen) snprintf(err, errlen, "%s", loadid_yaml_error(doc));
    free(c);
    loadid_yaml_free(doc);
    return -EINVAL;
}

int loadid_config_load(const char *path, loadid_config_t *cfg, char *err, size_t errlen,
                       loadid_config_warn_fn warn, void *warn_ctx) {
    if (err && errlen) err[0] = '\0';
    if (!path || !cfg) {
        if (err && errlen) snprintf(err, errlen, "loadid_config_load: invalid argument");
        return -EINVAL;
    }
    loadid_yaml_doc_t *doc = NULL;
    const int rc = loadid_yaml_load_file(path, &doc, err, errlen);
    if (rc < 0) return rc;
    return load_doc(doc, path, cfg, err, errlen, warn, warn_ctx);
}

int loadid_config_load_string(const char *path, const char *text, size_t len, loadid_config_t *cfg,
                              char *err, size_t errlen, loadid_config_warn_fn warn,
                              void *warn_ctx) {
    if (err && errlen) err[0] = '\0';
    if (!path || (!text && len) || !cfg) {
        if (err && errlen) snprintf(err, errlen, "loadid_config_load_string: invalid argument");
        return -EINVAL;
    }
    loadid_yaml_doc_t *doc = NULL;
    const int rc = loadid_yaml_load_string(path, text, len, &doc, err, errlen);
    if (rc < 0) return rc;
    return load_doc(doc, path, cfg, err, errlen, warn, warn_ctx);
}

void loadid_config_channel(const loadid_config_t *cfg, const char *name, char *out, size_t len) {
    snprintf(out, len, "%s%s", cfg->lcm_channel_prefix, name);
}
