/*
 * Unit tests of the configuration loader (loadid/config.h) and of the YAML
 * tree under it (host/include/loadid/yaml_tree.h).
 *
 * The expected defaults are written here literally, from docs/INTERFACE.md and
 * config.h, not taken from loadid_config_default: the shipped example
 * host/config/loadid.yaml, the function and this list must agree. Every
 * error is checked with its full "FILE:LINE: KEY: what" prefix, line
 * numbers included. Files are written into a fresh temporary directory.
 */
#define _POSIX_C_SOURCE 200809L

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scratch_dir.h"
#include "loadid/config.h"
#include "loadid/estimator.h"
#include "loadid/signals.h"
#include "loadid/yaml_tree.h"

#ifndef LOADID_SOURCE_DIR
#error "the build defines LOADID_SOURCE_DIR"
#endif

#define EXAMPLE LOADID_SOURCE_DIR "/host/config/loadid.yaml"
#define SHIPPED_URDF LOADID_SOURCE_DIR "/host/config/robots/rx60.urdf"

/* --- Temporary files ------------------------------------------------------ */

static char g_dir[256];

static const char *tmp_path(const char *name) {
    static char buf[8][512];
    static int k;
    char *p = buf[k++ % 8];
    snprintf(p, 512, "%s/%s", g_dir, name);
    return p;
}

/* Writes text to name in the temporary directory; returns the full path. */
static const char *write_file(const char *name, const char *text) {
    const char *path = tmp_path(name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, strlen(text), f), strlen(text));
    assert_int_equal(fclose(f), 0);
    return path;
}

static const char *make_dir(const char *name) {
    const char *path = tmp_path(name);
    assert_true(mkdir(path, 0700) == 0 || errno == EEXIST);
    return path;
}

static int setup_dir(void **state) {
    (void)state;
    return scratch_dir_make(g_dir, sizeof g_dir, "test-config");
}

static int remove_dir(void **state) {
    (void)state;
    return scratch_dir_remove(g_dir);
}

/* --- Loading with captured warnings --------------------------------------- */

typedef struct {
    int count;
    char msg[8][512];
} warnings_t;

static void collect(void *ctx, const char *msg) {
    warnings_t *w = ctx;
    if (w->count < 8) snprintf(w->msg[w->count], sizeof w->msg[0], "%s", msg);
    ++w->count;
}

static void load_ok(const char *path, loadid_config_t *cfg, warnings_t *w) {
    char err[1024] = "";
    memset(w, 0, sizeof *w);
    const int rc = loadid_config_load(path, cfg, err, sizeof err, collect, w);
    if (rc != 0) print_error("unexpected error: %s\n", err);
    assert_int_equal(rc, 0);
    assert_string_equal(err, "");
}

static void assert_prefix(const char *actual, const char *expected) {
    if (strncmp(actual, expected, strlen(expected)) != 0) {
        print_error("expected a message starting with\n  %s\ngot\n  %s\n", expected, actual);
        fail();
    }
}

/* Writes text to e.yaml, loads it, expects failure with the message
 * "<dir>/e.yaml:" rest... and no warning. */
static void expect_error(const char *text, const char *rest) {
    const char *path = write_file("e.yaml", text);
    char expected[1024], err[1024] = "";
    snprintf(expected, sizeof expected, "%s:%s", path, rest);
    loadid_config_t cfg;
    warnings_t w = {0};
    assert_int_equal(loadid_config_load(path, &cfg, err, sizeof err, collect, &w), -EINVAL);
    assert_prefix(err, expected);
    assert_null(strchr(err, '\n'));
    assert_int_equal(w.count, 0);
}

static void assert_doubles(const double *a, const double *expected, int n, const char *what) {
    for (int i = 0; i < n; ++i) {
        if (!(a[i] == expected[i])) {
            print_error("%s[%d]: %.17g, expected %.17g\n", what, i, a[i], expected[i]);
            fail();
        }
    }
}

#define ASSERT_EQ_D(a, e)                                           \
    do {                                                            \
        const double a_ = (a), e_ = (e);                            \
        if (!(a_ == e_)) {                                          \
            print_error("%s: %.17g, expected %.17g\n", #a, a_, e_); \
            fail();                                                 \
        }                                                           \
    } while (0)

/* docs/INTERFACE.md's and config.h's defaults, written out. */
static void assert_defaults(const loadid_config_t *c) {
    assert_string_equal(c->robot_urdf, SHIPPED_URDF);
    assert_string_equal(c->robot_base_link, "base_link");
    assert_string_equal(c->robot_sensor_link, "ft_sensor");
    assert_doubles(c->robot_gravity, (const double[]){0.0, 0.0, -9.81}, 3, "robot_gravity");

    assert_string_equal(c->can_interface, "vcan0");
    assert_int_equal(c->can_base_id, 0x1A0);
    assert_doubles(c->jr3_fs_force, (const double[]){200, 200, 200}, 3, "jr3_fs_force");
    assert_doubles(c->jr3_fs_moment, (const double[]){12, 12, 12}, 3, "jr3_fs_moment");
    assert_doubles(c->jr3_fs_linear, (const double[]){98.1, 98.1, 98.1}, 3, "jr3_fs_linear");
    assert_doubles(c->jr3_fs_angular, (const double[]){1000, 1000, 1000}, 3, "jr3_fs_angular");
    assert_string_equal(c->lcm_url, "udpm://239.255.76.67:7667?ttl=0");
    assert_int_equal(c->lcm_num_command_sources, 0); /* every sender */

    assert_int_equal(c->num_methods, 3);
    assert_int_equal(c->methods[0], LOADID_METHOD_RTLS);
    assert_int_equal(c->methods[1], LOADID_METHOD_RIV);
    assert_int_equal(c->methods[2], LOADID_METHOD_RLS);
    assert_int_equal(c->signals, LOADID_SIGNALS_KF);
    assert_int_equal(c->offset_model_estimate, 0);
    ASSERT_EQ_D(c->duration_s, 1.5);
    assert_int_equal(c->publish_every, 1);
    ASSERT_EQ_D(c->max_missing_share, 0.02);
    ASSERT_EQ_D(c->max_refused_share, 0.1);
    ASSERT_EQ_D(c->zeroing_window_s, 0.2);
    assert_doubles(c->distal_phi, (const double[10]){0}, 10, "distal_phi");

    ASSERT_EQ_D(c->noise_force, 0.1);
    ASSERT_EQ_D(c->noise_torque, 0.005);
    ASSERT_EQ_D(c->noise_linear, 0.5);
    ASSERT_EQ_D(c->noise_angular, 5.0);
    ASSERT_EQ_D(c->noise_omega, 0.02);
    ASSERT_EQ_D(c->omega_typical, 2.0);

    /* jerk_psd: 1 behind the fixed-lag smoother (config.c); meas_sigma:
     * joint_filter.h's documented default, with a relative tolerance for
     * the float core (LOADID_SCALAR=float) */
    ASSERT_EQ_D(c->kalman_jerk_psd, 1.0);
    const double sigma = 2 * 3.14159265358979323846 / 1048576.0 / sqrt(12.0);
    assert_true(fabs(c->kalman_meas_sigma - sigma) <= 1e-6 * sigma);
    assert_int_equal(c->noise_given & LOADID_NOISE_GIVEN_KF_MEAS, 0); /* auto: retuned */
    ASSERT_EQ_D(c->kalman_max_joint_age_s, 0.005);
    ASSERT_EQ_D(c->kalman_joint_period_s, 0); /* auto: measured */
    ASSERT_EQ_D(c->kalman_joint_delay_s, 0);
    ASSERT_EQ_D(c->kalman_spec_sigma, 0.5);
    ASSERT_EQ_D(c->kalman_alpha_sigma, 1.0);

    ASSERT_EQ_D(c->traj_base_frequency, 0.5);
    assert_int_equal(c->traj_harmonics, 4);
    ASSERT_EQ_D(c->traj_max_frequency, 2.0);
    ASSERT_EQ_D(c->traj_active_s, 1.5);
    ASSERT_EQ_D(c->traj_fade_s, 0.5);
    assert_int_equal(c->traj_has_home, 0);
    assert_int_equal(c->traj_num_home, 0);
    assert_int_equal(c->traj_num_acc_limits, 0);
    for (int i = 0; i < LOADID_MAX_JOINTS; ++i) ASSERT_EQ_D(c->traj_acc_limit[i], 20.0);
    ASSERT_EQ_D(c->traj_vel_scale, 1.0);
    assert_doubles(c->traj_workspace_min, (const double[]){-1e9, -1e9, -1e9}, 3, "workspace_min");
    assert_doubles(c->traj_workspace_max, (const double[]){1e9, 1e9, 1e9}, 3, "workspace_max");
    ASSERT_EQ_D(c->traj_floor_z, -1e9);
    ASSERT_EQ_D(c->traj_floor_clearance, 0.05);
    assert_int_equal(c->traj_monte_carlo, 2000);
    assert_int_equal(c->traj_candidates, 4);
    assert_int_equal(c->traj_max_evals, 3000);
    assert_true(c->traj_seed == 1);

    ASSERT_EQ_D(c->sim_servo_bandwidth_hz, 15.0);
    ASSERT_EQ_D(c->sim_servo_damping, 0.9);
    ASSERT_EQ_D(c->sim_backlash, 2e-4);
    ASSERT_EQ_D(c->sim_encoder_counts, 1048576.0);
    ASSERT_EQ_D(c->sim_vibration_hz, 28.0);
    ASSERT_EQ_D(c->sim_vibration_linear, 0.3);
    ASSERT_EQ_D(c->sim_vibration_angular, 3.0);
    ASSERT_EQ_D(c->sim_vibration_start_s, 0.0);
    ASSERT_EQ_D(c->sim_still_s, 0.5);
    /* the paper's o1, section V.A */
    assert_doubles(c->sim_load_phi,
                   (const double[]){1.00, -43.5e-3, 28.5e-3, 22.5e-3, 2.21e-3, 1.22e-3, 0.96e-3,
                                    3.74e-3, -0.63e-3, 4.95e-3},
                   10, "sim_load_phi");
    assert_doubles(c->sim_offset, (const double[]){2, -1.5, 3, 0.08, -0.05, 0.03}, 6, "sim_offset");
    assert_true(c->sim_seed == 1);
}

/* --- Defaults and the shipped example ------------------------------------- */

static void shipped_example_is_the_defaults(void **state) {
    (void)state;
    loadid_config_t cfg;
    memset(&cfg, 0x5a, sizeof cfg);
    warnings_t w;
    load_ok(EXAMPLE, &cfg, &w);
    for (int i = 0; i < w.count && i < 8; ++i) print_error("warning: %s\n", w.msg[i]);
    assert_int_equal(w.count, 0);
    assert_defaults(&cfg);
}

static void default_function_gives_the_defaults(void **state) {
    (void)state;
    loadid_config_t cfg;
    memset(&cfg, 0x5a, sizeof cfg);
    loadid_config_default(&cfg);
    assert_defaults(&cfg);
    loadid_config_default(NULL); /* no crash */
}

static void empty_files_give_the_defaults_with_a_warning(void **state) {
    (void)state;
    static const char *const kEmpty[] = {"", "# only a comment\n\n", "---\n", "~\n"};
    for (size_t i = 0; i < sizeof kEmpty / sizeof kEmpty[0]; ++i) {
        const char *path = write_file("empty.yaml", kEmpty[i]);
        loadid_config_t cfg;
        warnings_t w;
        load_ok(path, &cfg, &w);
        assert_defaults(&cfg);
        assert_int_equal(w.count, 1);
        char expected[600];
        snprintf(expected, sizeof expected, "%s:1: (top level): empty configuration", path);
        assert_prefix(w.msg[0], expected);
    }
    /* Empty sections are sections left out; no warning. */
    const char *path = write_file("sections.yaml",
                                  "robot:\ncan:\n  # interface: can0\njr3:\n"
                                  "  full_scale: ~\ntrajectory:\n  workspace:\n");
    loadid_config_t cfg;
    warnings_t w;
    load_ok(path, &cfg, &w);
    assert_int_equal(w.count, 0);
    assert_defaults(&cfg);
}

/* --- Every key ------------------------------------------------------------ */

static const char kEveryKey[] =
    "robot:\n"
    "  urdf: /opt/robots/arm.urdf\n"
    "  base_link: world\n"
    "  sensor_link: jr3_link\n"
    "  gravity: [0.1, -0.2, -9.80665]\n"
    "can:\n"
    "  interface: can1\n"
    "  base_id: 0x2B0\n"
    "jr3:\n"
    "  full_scale:\n"
    "    force: [100, 110, 120.5]\n"
    "    moment: [5, 6, 7]\n"
    "    linear: [49.05, 50, 51]\n"
    "    angular: [500, 600, 700]\n"
    "lcm:\n"
    "  url: udpm://239.255.76.67:7668?ttl=1\n"
    "estimation:\n"
    "  methods: [TLS_BATCH, LS_BATCH, RLS, RIV, RTLS]\n"
    "  signals: kf\n"
    "  offset_model: estimate\n"
    "  duration_s: 3\n"
    "  publish_every: 20\n"
    "  max_missing_share: 0.05\n"
    "  max_refused_share: 0\n"
    "zeroing:\n"
    "  window_s: 0.5\n"
    "distal:\n"
    "  phi: [0.2, 0.001, -0.002, 0.0008, 1e-4, 0, 0, 1.5e-4, 0, 1.6e-4]\n"
    "noise:\n"
    "  force: 0.2\n"
    "  torque: 0.01\n"
    "  linear: 0.25\n"
    "  angular: 2.5\n"
    "  omega: 0.01\n"
    "  omega_typical: 3\n"
    "kalman:\n"
    "  jerk_psd: 5000\n"
    "  meas_sigma: 1e-5\n"
    "  max_joint_age_s: 0.002\n"
    "  joint_period_s: 0.004\n"
    "  joint_delay_s: -0.003\n"
    "  spec_sigma: 0.25\n"
    "  alpha_sigma: 3.0\n"
    "trajectory:\n"
    "  base_frequency: 0.25\n"
    "  harmonics: 6\n"
    "  max_frequency: 1.5\n"
    "  active_s: 4\n"
    "  fade_s: 0\n"
    "  home: [0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7]\n"
    "  acc_limit:\n"
    "    - 10\n"
    "    - 11\n"
    "    - 12.5\n"
    "  vel_scale: 0.5\n"
    "  workspace:\n"
    "    min: [-0.8, -0.9, 0.1]\n"
    "    max: [0.8, 0.9, 1.2]\n"
    "  floor_z: 0.05\n"
    "  floor_clearance: 0.1\n"
    "  monte_carlo: 500\n"
    "  candidates: 8\n"
    "  max_evals: 1000\n"
    "  seed: 0xDEADBEEF12345678\n"
    "simulation:\n"
    "  servo_bandwidth_hz: 20\n"
    "  servo_damping: 0.7\n"
    "  backlash: 0\n"
    "  encoder_counts: 4096\n"
    "  vibration_hz: 35\n"
    "  vibration_linear: 0\n"
    "  vibration_angular: 1.5\n"
    "  vibration_start_s: 0.5\n"
    "  still_s: 1\n"
    "  load_phi: [2, 0.01, 0.02, 0.03, 0.004, 0.0001, 0.0002, 0.005, 0.0003, 0.006]\n"
    "  offset: [-1, 1, -2, 0.01, 0.02, -0.03]\n"
    "  seed: 18446744073709551615\n";

static void every_key_is_read(void **state) {
    (void)state;
    const char *path = write_file("every.yaml", kEveryKey);
    loadid_config_t c;
    warnings_t w;
    load_ok(path, &c, &w);
    assert_int_equal(w.count, 0);

    assert_string_equal(c.robot_urdf, "/opt/robots/arm.urdf");
    assert_string_equal(c.robot_base_link, "world");
    assert_string_equal(c.robot_sensor_link, "jr3_link");
    assert_doubles(c.robot_gravity, (const double[]){0.1, -0.2, -9.80665}, 3, "gravity");
    assert_string_equal(c.can_interface, "can1");
    assert_int_equal(c.can_base_id, 0x2B0);
    assert_doubles(c.jr3_fs_force, (const double[]){100, 110, 120.5}, 3, "force");
    assert_doubles(c.jr3_fs_moment, (const double[]){5, 6, 7}, 3, "moment");
    assert_doubles(c.jr3_fs_linear, (const double[]){49.05, 50, 51}, 3, "linear");
    assert_doubles(c.jr3_fs_angular, (const double[]){500, 600, 700}, 3, "angular");
    assert_string_equal(c.lcm_url, "udpm://239.255.76.67:7668?ttl=1");

    assert_int_equal(c.num_methods, 5);
    static const int kMethods[5] = {LOADID_METHOD_TLS_BATCH, LOADID_METHOD_LS_BATCH,
                                    LOADID_METHOD_RLS, LOADID_METHOD_RIV, LOADID_METHOD_RTLS};
    for (int i = 0; i < 5; ++i) assert_int_equal(c.methods[i], kMethods[i]);
    assert_int_equal(c.signals, LOADID_SIGNALS_KF);
    assert_int_equal(c.offset_model_estimate, 1);
    ASSERT_EQ_D(c.duration_s, 3);
    assert_int_equal(c.publish_every, 20);
    ASSERT_EQ_D(c.max_missing_share, 0.05);
    ASSERT_EQ_D(c.max_refused_share, 0);
    ASSERT_EQ_D(c.zeroing_window_s, 0.5);
    assert_doubles(c.distal_phi,
                   (const double[]){0.2, 0.001, -0.002, 0.0008, 1e-4, 0, 0, 1.5e-4, 0, 1.6e-4}, 10,
                   "distal_phi");

    ASSERT_EQ_D(c.noise_force, 0.2);
    ASSERT_EQ_D(c.noise_torque, 0.01);
    ASSERT_EQ_D(c.noise_linear, 0.25);
    ASSERT_EQ_D(c.noise_angular, 2.5);
    ASSERT_EQ_D(c.noise_omega, 0.01);
    ASSERT_EQ_D(c.omega_typical, 3);
    ASSERT_EQ_D(c.kalman_jerk_psd, 5000);
    ASSERT_EQ_D(c.kalman_meas_sigma, 1e-5);
    assert_true(c.noise_given & LOADID_NOISE_GIVEN_KF_MEAS); /* kept as given */
    ASSERT_EQ_D(c.kalman_max_joint_age_s, 0.002);
    ASSERT_EQ_D(c.kalman_joint_period_s, 0.004);
    ASSERT_EQ_D(c.kalman_joint_delay_s, -0.003);
    ASSERT_EQ_D(c.kalman_spec_sigma, 0.25);
    ASSERT_EQ_D(c.kalman_alpha_sigma, 3.0);

    ASSERT_EQ_D(c.traj_base_frequency, 0.25);
    assert_int_equal(c.traj_harmonics, 6);
    ASSERT_EQ_D(c.traj_max_frequency, 1.5);
    ASSERT_EQ_D(c.traj_active_s, 4);
    ASSERT_EQ_D(c.traj_fade_s, 0);
    assert_int_equal(c.traj_has_home, 1);
    assert_int_equal(c.traj_num_home, 7);
    assert_doubles(c.traj_home, (const double[]){0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7}, 7, "home");
    assert_int_equal(c.traj_num_acc_limits, 3);
    assert_doubles(c.traj_acc_limit, (const double[]){10, 11, 12.5}, 3, "acc_limit");
    ASSERT_EQ_D(c.traj_vel_scale, 0.5);
    assert_doubles(c.traj_workspace_min, (const double[]){-0.8, -0.9, 0.1}, 3, "workspace.min");
    assert_doubles(c.traj_workspace_max, (const double[]){0.8, 0.9, 1.2}, 3, "workspace.max");
    ASSERT_EQ_D(c.traj_floor_z, 0.05);
    ASSERT_EQ_D(c.traj_floor_clearance, 0.1);
    assert_int_equal(c.traj_monte_carlo, 500);
    assert_int_equal(c.traj_candidates, 8);
    assert_int_equal(c.traj_max_evals, 1000);
    assert_true(c.traj_seed == 0xDEADBEEF12345678ull);

    ASSERT_EQ_D(c.sim_servo_bandwidth_hz, 20);
    ASSERT_EQ_D(c.sim_servo_damping, 0.7);
    ASSERT_EQ_D(c.sim_backlash, 0);
    ASSERT_EQ_D(c.sim_encoder_counts, 4096);
    ASSERT_EQ_D(c.sim_vibration_hz, 35);
    ASSERT_EQ_D(c.sim_vibration_linear, 0);
    ASSERT_EQ_D(c.sim_vibration_angular, 1.5);
    ASSERT_EQ_D(c.sim_vibration_start_s, 0.5);
    ASSERT_EQ_D(c.sim_still_s, 1);
    assert_doubles(
        c.sim_load_phi,
        (const double[]){2, 0.01, 0.02, 0.03, 0.004, 0.0001, 0.0002, 0.005, 0.0003, 0.006}, 10,
        "load_phi");
    assert_doubles(c.sim_offset, (const double[]){-1, 1, -2, 0.01, 0.02, -0.03}, 6, "offset");
    assert_true(c.sim_seed == UINT64_MAX);
}

static void names_and_single_values(void **state) {
    (void)state;
    static const struct {
        const char *name;
        int value;
    } kSources[] = {{"sensor", LOADID_SIGNALS_SENSOR},
                    {"kf", LOADID_SIGNALS_KF},
                    {"setpoint", LOADID_SIGNALS_SETPOINT},
                    {"mixed", LOADID_SIGNALS_MIXED}};
    char text[256];
    for (size_t i = 0; i < 4; ++i) {
        snprintf(text, sizeof text, "estimation:\n  signals: %s\n  offset_model: zeroing\n",
                 kSources[i].name);
        loadid_config_t c;
        warnings_t w;
        load_ok(write_file("s.yaml", text), &c, &w);
        assert_int_equal(c.signals, kSources[i].value);
        assert_int_equal(c.offset_model_estimate, 0);
    }
    /* One method; one acceleration limit for every joint; decimal base_id;
     * a quoted string where a string is expected; integers for reals. */
    loadid_config_t c;
    warnings_t w;
    load_ok(write_file("s.yaml",
                       "estimation:\n  methods: [RIV]\n"
                       "trajectory:\n  acc_limit: 15\n"
                       "can:\n  base_id: 416\n  interface: \"can0\"\n"
                       "robot:\n  gravity: [0, 0, -10]\n"),
            &c, &w);
    assert_int_equal(w.count, 0);
    assert_int_equal(c.num_methods, 1);
    assert_int_equal(c.methods[0], LOADID_METHOD_RIV);
    assert_int_equal(c.traj_num_acc_limits, 0);
    for (int i = 0; i < LOADID_MAX_JOINTS; ++i) ASSERT_EQ_D(c.traj_acc_limit[i], 15);
    assert_int_equal(c.can_base_id, 0x1A0);
    assert_string_equal(c.can_interface, "can0");
    assert_doubles(c.robot_gravity, (const double[]){0, 0, -10}, 3, "gravity");
}

static void hex_base_id(void **state) {
    (void)state;
    static const struct {
        const char *text;
        uint32_t id;
    } kIds[] = {{"0x1A0", 0x1A0}, {"0x1a0", 0x1A0}, {"0x000", 0}, {"0x7FB", 0x7FB}, {"2043", 2043}};
    for (size_t i = 0; i < sizeof kIds / sizeof kIds[0]; ++i) {
        char text[64];
        snprintf(text, sizeof text, "can:\n  base_id: %s\n", kIds[i].text);
        loadid_config_t c;
        warnings_t w;
        load_ok(write_file("id.yaml", text), &c, &w);
        assert_int_equal(c.can_base_id, kIds[i].id);
    }
    expect_error("can:\n  base_id: 0x7FC\n",
                 "2: can.base_id: must be at most 0x7FB (base+4 must be an 11-bit identifier, "
                 "<= 0x7FF), got 0x7FC");
    expect_error("can:\n  base_id: 0x800\n", "2: can.base_id: must be at most 0x7FB");
    expect_error("can:\n  base_id: -1\n",
                 "2: can.base_id: expected a non-negative integer, got '-1'");
    expect_error("can:\n  base_id: 0x1G0\n", "2: can.base_id: expected an integer, got '0x1G0'");
    expect_error("can:\n  base_id: 416.0\n", "2: can.base_id: expected an integer, got '416.0'");
    expect_error("can:\n  base_id: 0x1FFFFFFFFFFFFFFFF\n", "2: can.base_id: integer out of range");
}

/* --- Paths ------------------------------------------------------------------ */

static void relative_urdf_paths_follow_the_config_file(void **state) {
    (void)state;
    make_dir("sub");
    loadid_config_t c;
    warnings_t w;
    char expected[1024];

    load_ok(write_file("sub/a.yaml", "robot:\n  urdf: robots/arm.urdf\n"), &c, &w);
    snprintf(expected, sizeof expected, "%s/sub/robots/arm.urdf", g_dir);
    assert_string_equal(c.robot_urdf, expected);

    load_ok(write_file("sub/b.yaml", "robot:\n  urdf: ../arm.urdf\n"), &c, &w);
    snprintf(expected, sizeof expected, "%s/sub/../arm.urdf", g_dir);
    assert_string_equal(c.robot_urdf, expected);

    load_ok(write_file("sub/c.yaml", "robot:\n  urdf: /abs/arm.urdf\n"), &c, &w);
    assert_string_equal(c.robot_urdf, "/abs/arm.urdf");

    /* realtime: off by default; values and ranges checked. */
    assert_int_equal(c.rt_priority, 0);
    assert_int_equal(c.rt_lock_memory, 0);
    assert_int_equal(c.rt_cpu, -1);
    load_ok(write_file("sub/rt.yaml", "realtime:\n  priority: 80\n  lock_memory: true\n  cpu: 1\n"),
            &c, &w);
    assert_int_equal(c.rt_priority, 80);
    assert_int_equal(c.rt_lock_memory, 1);
    assert_int_equal(c.rt_cpu, 1);
    expect_error("realtime:\n  priority: 100\n", "2: realtime.priority: must be 0..99, got 100");
    expect_error("estimation:\n  publish_every: 0\n",
                 "2: estimation.publish_every: must be 1..1000000, got 0");

    /* results.directory and results.load follow the same rule; default "". */
    assert_string_equal(c.results_directory, "");
    assert_string_equal(c.results_load, "");
    load_ok(write_file("sub/d.yaml", "results:\n  directory: out\n  load: /r/latest.yaml\n"), &c,
            &w);
    snprintf(expected, sizeof expected, "%s/sub/out", g_dir);
    assert_string_equal(c.results_directory, expected);
    assert_string_equal(c.results_load, "/r/latest.yaml");
    /* results.trace (addition): default false, and only with a directory. */
    assert_int_equal(c.results_trace, 0);
    load_ok(write_file("sub/t.yaml", "results:\n  directory: out\n  trace: true\n"), &c, &w);
    assert_int_equal(c.results_trace, 1);
    expect_error("results:\n  trace: true\n",
                 "2: results.trace: needs results.directory (the trace goes beside the saved "
                 "result)");

    /* A relative config path: made absolute against the working directory. */
    char cwd[512], here[512];
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(g_dir), 0);
    assert_non_null(getcwd(here, sizeof here));
    char err[1024] = "";
    int rc = loadid_config_load("sub/a.yaml", &c, err, sizeof err, NULL, NULL);
    int rc2 = -2;
    char urdf2[LOADID_PATH_MAX] = "";
    if (rc == 0) {
        loadid_config_t c2;
        assert_int_equal(chdir("sub"), 0);
        rc2 = loadid_config_load("a.yaml", &c2, err, sizeof err, NULL, NULL);
        snprintf(urdf2, sizeof urdf2, "%s", c2.robot_urdf);
    }
    assert_int_equal(chdir(cwd), 0);
    assert_int_equal(rc, 0);
    snprintf(expected, sizeof expected, "%s/sub/robots/arm.urdf", here);
    assert_string_equal(c.robot_urdf, expected);
    assert_int_equal(rc2, 0);
    assert_string_equal(urdf2, expected);

    /* The shipped example's urdf is the shipped robot, next to it. */
    load_ok(EXAMPLE, &c, &w);
    assert_string_equal(c.robot_urdf, SHIPPED_URDF);
    assert_int_equal(access(c.robot_urdf, R_OK), 0);

    expect_error("robot:\n  urdf: \"\"\n", "2: robot.urdf: must not be empty");
}

/* --- Errors ------------------------------------------------------------------ */

static void syntax_errors_name_their_line(void **state) {
    (void)state;
    expect_error("robot:\n  base_link: a\n  sensor_link: b: c\n",
                 "3: robot: syntax error: mapping values are not allowed in this context");
    expect_error("robot:\n  gravity: [0, 0, -9.81\n  base_link: x\n",
                 "3: robot.gravity: syntax error: did not find expected ',' or ']' (while parsing "
                 "a flow sequence on line 2)");
    /* The tab is met while libyaml still scans "a" (a plain scalar may go
     * on over lines): the key named is base_link, the line the tab's. */
    expect_error("robot:\n  base_link: a\n\tsensor_link: b\n",
                 "3: robot.base_link: syntax error: found a tab character that violates "
                 "indentation (while scanning a plain scalar on line 2)");
    expect_error("robot:\n\tbase_link: a\n",
                 "2: robot: syntax error: found character that cannot start any token");
    expect_error("lcm:\n  url: \"udpm://x\n",
                 "3: lcm.url: syntax error: found unexpected end of stream");
    expect_error("robot:\n  base_link: a\n---\nrobot:\n  base_link: b\n",
                 "3: (top level): a second YAML document: one document per file");
    expect_error("robot:\n  base_link: &b base\n  sensor_link: *b\n",
                 "3: robot.sensor_link: alias *b: aliases are not supported");
    expect_error("robot:\n  base_link: &b base\n  gravity: [0, *b, 1]\n",
                 "3: robot.gravity[1]: alias *b: aliases are not supported");
    expect_error("robot:\n  base_link: \"a\xff\"\n",
                 "2: (top level): syntax error: invalid leading UTF-8 octet");
}

static void wrong_types_name_key_and_line(void **state) {
    (void)state;
    expect_error("- robot\n- can\n",
                 "1: (top level): expected a mapping of sections (robot:, can:, "
                 "...), got a sequence");
    expect_error("just text\n", "1: (top level): expected a mapping of sections");
    expect_error("\nrobot: 5\n", "2: robot: expected a mapping, got '5'");
    expect_error("jr3:\n  full_scale: [1, 2, 3]\n",
                 "2: jr3.full_scale: expected a mapping, got a sequence");
    expect_error("estimation:\n  duration_s:\n    seconds: 2\n",
                 "3: estimation.duration_s: expected a number, got a mapping");
    expect_error("estimation:\n  duration_s: [2]\n",
                 "2: estimation.duration_s: expected a number, got a sequence");
    expect_error("estimation:\n  duration_s: \"1.5\"\n",
                 "2: estimation.duration_s: expected a number, got the string \"1.5\"");
    expect_error("estimation:\n  duration_s:\n",
                 "2: estimation.duration_s: expected a number, got null");
    expect_error("estimation:\n  duration_s: 1.5 s\n",
                 "2: estimation.duration_s: expected a number, got '1.5 s'");
    expect_error("robot:\n  gravity: {x: 0, y: 0, z: -9.81}\n",
                 "2: robot.gravity: expected a sequence of 3 numbers, got a mapping");
    expect_error("robot:\n  gravity: -9.81\n",
                 "2: robot.gravity: expected a sequence of 3 numbers, got '-9.81'");
    expect_error("robot:\n  gravity: [0, zero, -9.81]\n",
                 "2: robot.gravity[1]: expected a number, got 'zero'");
    expect_error("robot:\n  base_link: [a]\n",
                 "2: robot.base_link: expected a string, got a sequence");
    expect_error("robot:\n  sensor_link:\n", "2: robot.sensor_link: expected a string, got null");
    expect_error("trajectory:\n  harmonics: 2.5\n",
                 "2: trajectory.harmonics: expected an integer, got '2.5'");
    expect_error("trajectory:\n  harmonics: 99999999999\n",
                 "2: trajectory.harmonics: integer out of range");
    expect_error("estimation:\n  methods: RTLS\n",
                 "2: estimation.methods: expected a sequence, got 'RTLS'");
    expect_error("estimation:\n  methods: [RTLS, [RIV]]\n",
                 "2: estimation.methods[1]: expected a string, got a sequence");
}

static void wrong_lengths_and_values(void **state) {
    (void)state;
    expect_error("jr3:\n  full_scale:\n    force: [200, 200]\n",
                 "3: jr3.full_scale.force: expected 3 numbers, got 2");
    expect_error("distal:\n  phi: [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]\n",
                 "2: distal.phi: expected 10 numbers, got 11");
    expect_error("trajectory:\n  home: []\n",
                 "2: trajectory.home: expected at least 1 number, got 0");
    expect_error("trajectory:\n  acc_limit: [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n",
                 "2: trajectory.acc_limit: expected at most 16 numbers, got 17");
    expect_error("jr3:\n  full_scale:\n    force: [200, 200, 200]\n    moment: [12, -12, 12]\n",
                 "4: jr3.full_scale.moment[1]: must be > 0, got -12");
    expect_error("jr3:\n  full_scale:\n    linear:\n      - 98.1\n      - 98.1\n      - 0\n",
                 "6: jr3.full_scale.linear[2]: must be > 0, got 0");
    expect_error("robot:\n  gravity: [0, 0, .nan]\n",
                 "2: robot.gravity[2]: expected a finite number, got '.nan'");
    expect_error("estimation:\n  duration_s: -.inf\n",
                 "2: estimation.duration_s: expected a finite number, got '-.inf'");
    expect_error("estimation:\n  duration_s: NaN\n",
                 "2: estimation.duration_s: expected a finite number, got 'NaN'");
    expect_error("estimation:\n  duration_s: 1e999\n",
                 "2: estimation.duration_s: number out of range: '1e999'");
    expect_error("estimation:\n  duration_s: 0\n", "2: estimation.duration_s: must be > 0, got 0");
    expect_error("noise:\n  force: 0.1\n  torque: -0.005\n",
                 "3: noise.torque: must be > 0, got -0.005");
    expect_error("zeroing:\n  window_s: 0\n", "2: zeroing.window_s: must be > 0, got 0");
    expect_error("estimation:\n  max_refused_share: 1.5\n",
                 "2: estimation.max_refused_share: a share of the window's samples: must be <= 1, "
                 "got 1.5");
    expect_error("estimation:\n  max_refused_share: -0.1\n",
                 "2: estimation.max_refused_share: must be >= 0, got -0.1");
    expect_error("estimation:\n  max_missing_share: 2\n",
                 "2: estimation.max_missing_share: a share of the window's samples: must be <= 1, "
                 "got 2");
    expect_error("estimation:\n  max_missing_share: -1\n",
                 "2: estimation.max_missing_share: must be >= 0, got -1");
    expect_error("kalman:\n  meas_sigma: 0\n", "2: kalman.meas_sigma: must be > 0, got 0");
    expect_error("kalman:\n  meas_sigma: fine\n",
                 "2: kalman.meas_sigma: expected a number > 0 or auto");
    expect_error("kalman:\n  joint_period_s: fast\n",
                 "2: kalman.joint_period_s: expected a period in seconds > 0 or auto");
    expect_error("kalman:\n  joint_period_s: -0.001\n",
                 "2: kalman.joint_period_s: must be > 0, got -0.001");
    expect_error("kalman:\n  joint_delay_s: 0.5\n",
                 "2: kalman.joint_delay_s: must be within +-0.1 s, got 0.5");
    expect_error("simulation:\n  backlash: -1e-4\n",
                 "2: simulation.backlash: must be >= 0, got -0.0001");
    expect_error("trajectory:\n  harmonics: 0\n", "2: trajectory.harmonics: must be >= 1, got 0");
    expect_error("trajectory:\n  base_frequency: 0.5\n  harmonics: 5\n",
                 "3: trajectory.harmonics: 5 harmonics of 0.5 Hz reach 2.5 Hz, above "
                 "trajectory.max_frequency 2 Hz");
    expect_error("trajectory:\n  max_frequency: 1\n",
                 "2: trajectory.max_frequency: 4 harmonics of 0.5 Hz reach 2 Hz");
    expect_error("trajectory:\n  vel_scale: 1.5\n",
                 "2: trajectory.vel_scale: a fraction of the URDF");
    expect_error("trajectory:\n  workspace:\n    min: [0, 0, 0]\n    max: [1, 1, 0]\n",
                 "3: trajectory.workspace.min: workspace min must be below max on every axis: z: "
                 "min 0 >= max 0");
    expect_error("trajectory:\n  workspace:\n    max: [1, -2e9, 1]\n",
                 "3: trajectory.workspace.max: workspace min must be below max on every axis: y");
    expect_error("trajectory:\n  monte_carlo: 3\n",
                 "2: trajectory.monte_carlo: 4 candidates to optimise "
                 "out of 3 random ones");
    expect_error("can:\n  interface: \"\"\n",
                 "2: can.interface: a network interface name has 1 to 15");
    expect_error("can:\n  interface: a_very_long_name0\n",
                 "2: can.interface: a network interface name has 1 to 15 characters, got "
                 "'a_very_long_name0'");
    expect_error("lcm:\n  url: 239.255.76.67\n", "2: lcm.url: expected an LCM URL");
    expect_error(
        "robot:\n  base_link: "
        "a123456789012345678901234567890123456789012345678901234567890123\n",
        "2: robot.base_link: longer than 63 characters");
}

/* simulation.zero, drift, accel_bias, alpha_bias, jitter_us, trajectory_scale,
 * noise.ft_correlation: the real-hardware-like settings of loadid-sim
 * (loadid/config.h). */
static void assert_sim_realism_defaults(const loadid_config_t *c) {
    assert_int_equal(c->sim_zero, 1);
    assert_doubles(c->sim_drift, (const double[]){0, 0, 0, 0, 0, 0}, 6, "sim_drift");
    assert_doubles(c->sim_accel_bias, (const double[]){0, 0, 0}, 3, "sim_accel_bias");
    assert_doubles(c->sim_alpha_bias, (const double[]){0, 0, 0}, 3, "sim_alpha_bias");
    assert_int_equal(c->sim_jitter_us, 0);
    ASSERT_EQ_D(c->sim_trajectory_scale, 1.0);
    ASSERT_EQ_D(c->sim_noise_ft_correlation, 0.0);
}

static void simulation_realism_keys(void **state) {
    (void)state;
    loadid_config_t c;
    warnings_t w;
    memset(&c, 0x5a, sizeof c);
    loadid_config_default(&c);
    assert_sim_realism_defaults(&c);
    memset(&c, 0x5a, sizeof c);
    load_ok(EXAMPLE, &c, &w); /* the shipped example gives every key its default */
    assert_int_equal(w.count, 0);
    assert_sim_realism_defaults(&c);

    load_ok(write_file("realism.yaml",
                       "simulation:\n"
                       "  still_s: 0\n"
                       "  zero: false\n"
                       "  drift: [0.01, -0.02, 0.03, 1e-3, -2e-3, 3e-3]\n"
                       "  accel_bias: [0.1, -0.2, 0.3]\n"
                       "  alpha_bias: [-1, 2, -3]\n"
                       "  jitter_us: 250\n"
                       "  trajectory_scale: 0.05\n"
                       "  noise:\n    ft_correlation: 0.8\n"),
            &c, &w);
    assert_int_equal(w.count, 0);
    ASSERT_EQ_D(c.sim_still_s, 0);
    assert_int_equal(c.sim_zero, 0);
    assert_doubles(c.sim_drift, (const double[]){0.01, -0.02, 0.03, 1e-3, -2e-3, 3e-3}, 6, "drift");
    assert_doubles(c.sim_accel_bias, (const double[]){0.1, -0.2, 0.3}, 3, "accel_bias");
    assert_doubles(c.sim_alpha_bias, (const double[]){-1, 2, -3}, 3, "alpha_bias");
    assert_int_equal(c.sim_jitter_us, 250);
    ASSERT_EQ_D(c.sim_trajectory_scale, 0.05);
    ASSERT_EQ_D(c.sim_noise_ft_correlation, 0.8);
    load_ok(write_file("realism_edges.yaml",
                       "simulation:\n  zero: true\n  jitter_us: 999\n  trajectory_scale: 1\n"),
            &c, &w);
    assert_int_equal(c.sim_zero, 1);
    assert_int_equal(c.sim_jitter_us, 999);
    ASSERT_EQ_D(c.sim_trajectory_scale, 1.0);

    expect_error("simulation:\n  zero: 0\n", "2: simulation.zero: expected true or false, got '0'");
    expect_error("simulation:\n  zero: [true]\n", "2: simulation.zero: expected true or false");
    expect_error("simulation:\n  drift: [0, 0, 0]\n",
                 "2: simulation.drift: expected 6 numbers, got 3");
    expect_error("simulation:\n  drift: [0, 0, 0, 0, x, 0]\n",
                 "2: simulation.drift[4]: expected a number, got 'x'");
    expect_error("simulation:\n  accel_bias: [0, 0]\n",
                 "2: simulation.accel_bias: expected 3 numbers, got 2");
    expect_error("simulation:\n  alpha_bias: [0, 0, .inf]\n",
                 "2: simulation.alpha_bias[2]: expected a finite number, got '.inf'");
    expect_error("simulation:\n  alpha_bias: 1\n",
                 "2: simulation.alpha_bias: expected a sequence of 3 numbers, got '1'");
    expect_error("simulation:\n  jitter_us: -1\n",
                 "2: simulation.jitter_us: must be 0..999, got -1");
    expect_error("simulation:\n  jitter_us: 1000\n",
                 "2: simulation.jitter_us: must be 0..999, got 1000");
    expect_error("simulation:\n  jitter_us: 2.5\n",
                 "2: simulation.jitter_us: expected an integer, got '2.5'");
    expect_error("simulation:\n  trajectory_scale: 0\n",
                 "2: simulation.trajectory_scale: must be > 0, got 0");
    expect_error(
        "simulation:\n  seed: 3\n  trajectory_scale: 1.5\n",
        "3: simulation.trajectory_scale: a fraction of the trajectory's amplitude: must be "
        "<= 1, got 1.5");
    expect_error("simulation:\n  noise:\n    ft_correlation: 1\n",
                 "3: simulation.noise.ft_correlation: a lag-1 correlation: must be < 1, got 1");
    expect_error("simulation:\n  noise:\n    ft_correlation: -0.1\n",
                 "3: simulation.noise.ft_correlation: must be >= 0, got -0.1");
}

static void bad_names(void **state) {
    (void)state;
    expect_error("estimation:\n  methods: [RTLS, FOO]\n",
                 "2: estimation.methods[1]: unknown method 'FOO' (RLS, RIV, RTLS, LS_BATCH, "
                 "TLS_BATCH or REFINED)");
    expect_error("estimation:\n  methods: [rtls]\n",
                 "2: estimation.methods[0]: unknown method 'rtls'");
    expect_error("estimation:\n  methods:\n    - RTLS\n    - RIV\n    - RTLS\n",
                 "5: estimation.methods[2]: method RTLS listed twice (first as item 0)");
    expect_error("estimation:\n  methods: [RLS, RIV, RTLS, LS_BATCH, TLS_BATCH, RLS]\n",
                 "2: estimation.methods[5]: method RLS listed twice (first as item 0)");
    expect_error("estimation:\n  methods: []\n",
                 "2: estimation.methods: expected at least one method, got none");
    expect_error("estimation:\n  signals: accelerometer\n",
                 "2: estimation.signals: unknown signal source 'accelerometer' (sensor, kf, "
                 "setpoint or mixed)");
    expect_error("estimation:\n  offset_model: both\n",
                 "2: estimation.offset_model: unknown offset model 'both' (zeroing or estimate)");
}

static void duplicate_keys(void **state) {
    (void)state;
    expect_error("robot:\n  base_link: a\ncan:\n  interface: vcan1\nrobot:\n  sensor_link: b\n",
                 "5: robot: duplicate key (first on line 1)");
    expect_error("robot:\n  base_link: a\n  gravity: [0, 0, -9.81]\n  base_link: b\n",
                 "4: robot.base_link: duplicate key (first on line 2)");
    expect_error("jr3:\n  full_scale: {force: [1, 1, 1], \"force\": [2, 2, 2]}\n",
                 "2: jr3.full_scale.force: duplicate key (first on line 2)");
}

/* A key loadid does not know inside one of its sections is a typo that
 * would leave the setting at its default without a word: an error, with
 * the closest known key, or the section's keys when none is close. */
static void unknown_keys_in_loadid_sections_are_errors(void **state) {
    (void)state;
    expect_error("robot:\n  base_link: world\n  sensorlink: tool0\n",
                 "3: robot.sensorlink: unknown key (did you mean 'sensor_link'?)");
    /* a swap of two neighbours is one edit */
    expect_error("estimation:\n  mehtods: [RLS]\n",
                 "2: estimation.mehtods: unknown key (did you mean 'methods'?)");
    /* nested sections too, at the key's own line */
    expect_error("trajectory:\n  workspace:\n    min: [-1, -1, 0]\n    mxa: [1, 1, 1]\n",
                 "4: trajectory.workspace.mxa: unknown key (did you mean 'max'?)");
    expect_error("jr3:\n  full_scale:\n    forse: [1, 1, 1]\n",
                 "3: jr3.full_scale.forse: unknown key (did you mean 'force'?)");
    /* nothing close: the keys the section has, in the order loadid reads them */
    expect_error("zeroing:\n  window_s: 0.1\n  duration: 2\n",
                 "3: zeroing.duration: unknown key (zeroing has window_s)");
    expect_error("realtime:\n  nice: 5\n",
                 "2: realtime.nice: unknown key (realtime has priority, lock_memory, cpu)");
    /* the first in file order, and an error even after valid keys */
    expect_error(
        "lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\n  chanel_prefix: R2_\n"
        "estimation:\n  duraton_s: 2\n",
        "3: lcm.chanel_prefix: unknown key (did you mean 'channel_prefix'?)");
    /* a misspelt section: a near miss of a loadid section's name */
    expect_error("estimaton:\n  methods: [RLS]\n",
                 "1: estimaton: unknown section (did you mean 'estimation'?)");
    expect_error("kalmann:\n  lag_s: 0\n", "1: kalmann: unknown section (did you mean 'kalman'?)");
    /* The lag's default over a short joint period given alone: the error
     * names the key that is there (a NULL node crashed, found by fuzz_config). */
    expect_error("kalman:\n  joint_period_s: 0.0001\n",
                 "2: kalman.joint_period_s: kalman.lag_s (its default) must be at most 200 joint "
                 "periods (0.02 s), got 0.05");
    expect_error("kalman:\n  joint_period_s: 0.0001\n  lag_s: 0.03\n",
                 "3: kalman.lag_s: kalman.lag_s must be at most 200 joint periods");
}

/* Any other top-level name is another program's section in a shared
 * file: a warning, and the rest is read. */
static void other_programs_sections_are_warnings(void **state) {
    (void)state;
    const char *path = write_file("shared.yaml",
                                  "robot:\n"
                                  "  base_link: world\n"
                                  "dashboard:\n" /* line 3: another program's */
                                  "  port: 8080\n"
                                  "  robot: x\n"
                                  "estimation:\n"
                                  "  duration_s: 2\n"
                                  "plotting: true\n"); /* line 8 */
    loadid_config_t c;
    warnings_t w;
    load_ok(path, &c, &w);
    assert_int_equal(w.count, 2);
    char expected[600];
    snprintf(expected, sizeof expected, "%s:3: dashboard: not a loadid section, ignored", path);
    assert_string_equal(w.msg[0], expected);
    snprintf(expected, sizeof expected, "%s:8: plotting: not a loadid section, ignored", path);
    assert_string_equal(w.msg[1], expected);
    assert_string_equal(c.robot_base_link, "world");
    ASSERT_EQ_D(c.duration_s, 2);

    /* No callback: still loads. */
    char err[256] = "x";
    assert_int_equal(loadid_config_load(path, &c, err, sizeof err, NULL, NULL), 0);
    assert_string_equal(err, "");

    /* An error elsewhere: no warning at all (warnings come with success). */
    const char *bad = write_file("shared_bad.yaml", "dashboard:\n  port: 1\nrobot:\n  urdff: x\n");
    memset(&w, 0, sizeof w);
    assert_int_equal(loadid_config_load(bad, &c, err, sizeof err, collect, &w), -EINVAL);
    assert_int_equal(w.count, 0);
    snprintf(expected, sizeof expected, "%s:4: robot.urdff: unknown key (did you mean 'urdf'?)",
             bad);
    assert_string_equal(err, expected);
}

/* Where robot.urdf was set, for the URDF reader's messages. */
static void urdf_origin_names_file_line_and_key(void **state) {
    (void)state;
    const char *path = write_file("origin.yaml", "# a robot\nrobot:\n  urdf: robots/none.urdf\n");
    loadid_config_t c;
    warnings_t w;
    load_ok(path, &c, &w);
    char expected[600];
    snprintf(expected, sizeof expected, "%s:3: robot.urdf", path);
    assert_string_equal(c.robot_urdf_origin, expected);
    loadid_config_default(&c);
    assert_string_equal(c.robot_urdf_origin, "robot.urdf (default)");
}

static void unreadable_files(void **state) {
    (void)state;
    const char *missing = tmp_path("does_not_exist.yaml");
    char err[1024], expected[1024];
    loadid_config_t c;
    memset(&c, 0x5a, sizeof c);
    loadid_config_t before = c;
    assert_int_equal(loadid_config_load(missing, &c, err, sizeof err, NULL, NULL), -ENOENT);
    snprintf(expected, sizeof expected, "%s: cannot read: No such file or directory", missing);
    assert_string_equal(err, expected);
    assert_memory_equal(&c, &before, sizeof c);

    const char *dir = make_dir("a_dir.yaml");
    assert_int_equal(loadid_config_load(dir, &c, err, sizeof err, NULL, NULL), -EISDIR);
    snprintf(expected, sizeof expected, "%s: cannot read: Is a directory", dir);
    assert_string_equal(err, expected);

    /* A failing load leaves cfg untouched. */
    const char *bad = write_file("bad.yaml", "robot:\n  base_link: x\ncan:\n  base_id: 0x800\n");
    assert_int_equal(loadid_config_load(bad, &c, err, sizeof err, NULL, NULL), -EINVAL);
    assert_memory_equal(&c, &before, sizeof c);

    /* Bad arguments, and a NULL error buffer. */
    assert_int_equal(loadid_config_load(NULL, &c, err, sizeof err, NULL, NULL), -EINVAL);
    assert_int_equal(loadid_config_load(EXAMPLE, NULL, err, sizeof err, NULL, NULL), -EINVAL);
    assert_int_equal(loadid_config_load(bad, &c, NULL, 0, NULL, NULL), -EINVAL);
    /* A short error buffer is truncated, NUL-terminated. */
    char small[12];
    assert_int_equal(loadid_config_load(bad, &c, small, sizeof small, NULL, NULL), -EINVAL);
    assert_int_equal(strlen(small), sizeof small - 1);
}

/* loadid_config_load_string (the fuzzer's entry): the same as the file,
 * relative paths against the given name's folder, nothing read. */
static void load_from_a_buffer(void **state) {
    (void)state;
    static char text[16384];
    FILE *f = fopen(EXAMPLE, "rb");
    assert_non_null(f);
    const size_t n = fread(text, 1, sizeof text, f);
    assert_true(n > 0 && n < sizeof text);
    fclose(f);
    loadid_config_t from_file, from_text;
    warnings_t w;
    memset(&from_file, 0, sizeof from_file);
    memset(&from_text, 0, sizeof from_text);
    load_ok(EXAMPLE, &from_file, &w);
    char err[1024] = "x";
    assert_int_equal(
        loadid_config_load_string(EXAMPLE, text, n, &from_text, err, sizeof err, collect, &w), 0);
    assert_string_equal(err, "");
    assert_memory_equal(&from_file, &from_text, sizeof from_file);

    /* Not NUL-terminated: only len bytes count ("robot:" then junk). */
    const char partial[] = "robot:\n  urdf: r.urdf\nXXXX";
    assert_int_equal(loadid_config_load_string("/nowhere/c.yaml", partial, sizeof partial - 5,
                                               &from_text, err, sizeof err, NULL, NULL),
                     0);
    assert_string_equal(from_text.robot_urdf, "/nowhere/r.urdf");

    /* Errors name the given file; cfg stays untouched. */
    loadid_config_t before = from_text;
    const char bad[] = "can:\n  base_id: 0x800\n";
    assert_int_equal(loadid_config_load_string("/nowhere/c.yaml", bad, strlen(bad), &from_text, err,
                                               sizeof err, NULL, NULL),
                     -EINVAL);
    assert_prefix(err, "/nowhere/c.yaml:2: can.base_id:");
    assert_memory_equal(&from_text, &before, sizeof before);
    assert_int_equal(
        loadid_config_load_string(NULL, bad, 1, &from_text, err, sizeof err, NULL, NULL), -EINVAL);
    assert_int_equal(
        loadid_config_load_string("c.yaml", NULL, 1, &from_text, err, sizeof err, NULL, NULL),
        -EINVAL);
}

/* --- The YAML tree itself ------------------------------------------------- */

static loadid_yaml_doc_t *parse(const char *text) {
    loadid_yaml_doc_t *doc = NULL;
    char err[512];
    const int rc = loadid_yaml_load_string("t.yaml", text, strlen(text), &doc, err, sizeof err);
    if (rc) print_error("%s\n", err);
    assert_int_equal(rc, 0);
    return doc;
}

static void yaml_tree_nodes_and_lines(void **state) {
    (void)state;
    loadid_yaml_doc_t *doc = parse(
        "# comment\n"
        "joints:\n"
        "  - name: j1\n"
        "    coeffs: [[1, 2], [3, 4.5]]\n"
        "  - name: j2\n"
        "    coeffs:\n"
        "      - [5, 6]\n"
        "label: 'a\\b'\n"
        "flag: True\n");
    loadid_yaml_node_t *root = loadid_yaml_root(doc);
    assert_int_equal(loadid_yaml_kind(root), LOADID_YAML_MAPPING);
    assert_int_equal(loadid_yaml_count(root), 3);
    assert_string_equal(loadid_yaml_file(doc), "t.yaml");
    assert_string_equal(loadid_yaml_scalar(loadid_yaml_key_at(root, 2), NULL), "flag");
    assert_null(loadid_yaml_key_at(root, 3));

    loadid_yaml_node_t *joints = NULL;
    assert_int_equal(loadid_yaml_get_sequence(root, "joints", &joints), 1);
    assert_int_equal(loadid_yaml_count(joints), 2);
    loadid_yaml_node_t *j2 = loadid_yaml_item(joints, 1);
    assert_int_equal(loadid_yaml_line(j2), 5);
    char name[8];
    assert_int_equal(loadid_yaml_get_string(j2, "name", name, sizeof name), 1);
    assert_string_equal(name, "j2");
    loadid_yaml_node_t *coeffs = loadid_yaml_get(j2, "coeffs");
    loadid_yaml_node_t *row = loadid_yaml_item(coeffs, 0);
    assert_int_equal(loadid_yaml_line(row), 7);
    char path[64];
    assert_int_equal(loadid_yaml_path(row, path, sizeof path), strlen("joints[1].coeffs[0]"));
    assert_string_equal(path, "joints[1].coeffs[0]");
    loadid_yaml_path(root, path, sizeof path);
    assert_string_equal(path, "(top level)");
    loadid_yaml_path(row, path, 8); /* truncated */
    assert_string_equal(path, "joints[");

    double v[3];
    size_t n = 0;
    assert_int_equal(loadid_yaml_as_doubles(row, v, 1, 3, &n), 0);
    assert_int_equal(n, 2);
    assert_true(v[0] == 5 && v[1] == 6);

    /* An error deep inside: its own path and line. */
    loadid_yaml_node_t *j1 = loadid_yaml_item(joints, 0);
    loadid_yaml_node_t *c1 = loadid_yaml_get(j1, "coeffs");
    assert_int_equal(loadid_yaml_as_doubles(loadid_yaml_item(c1, 1), v, 3, 3, NULL), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc),
                        "t.yaml:4: joints[0].coeffs[1]: expected 3 numbers, got 2");
    assert_int_equal(loadid_yaml_as_doubles(c1, v, 2, 2, NULL), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc),
                        "t.yaml:4: joints[0].coeffs[0]: expected a number, got a sequence");

    char s[8];
    assert_int_equal(loadid_yaml_get_string(root, "label", s, sizeof s), 1);
    assert_string_equal(s, "a\\b");
    int flag = 0;
    assert_int_equal(loadid_yaml_get_bool(root, "flag", &flag), 1);
    assert_int_equal(flag, 1);

    /* Absent keys and absent sections read as 0 and change nothing. */
    assert_int_equal(loadid_yaml_get_double(root, "nothing", &v[0]), 0);
    assert_int_equal(loadid_yaml_get_double(NULL, "nothing", &v[0]), 0);
    assert_true(v[0] == 5);
    loadid_yaml_node_t *sub = root;
    assert_int_equal(loadid_yaml_get_mapping(root, "nothing", &sub), 0);
    assert_null(sub);

    /* Unused keys: label and flag were read; j1's name was not. */
    warnings_t w = {0};
    assert_int_equal(loadid_yaml_report_unused(doc, collect, &w), 1);
    assert_string_equal(w.msg[0], "t.yaml:3: joints[0].name: unknown key, ignored");
    loadid_yaml_mark_used(loadid_yaml_value_at(j1, 0));
    assert_int_equal(loadid_yaml_report_unused(doc, NULL, NULL), 0);

    /* Suggestions: among the keys asked for in that mapping (present or
     * not), within 1 edit of a key of up to 4 characters, 2 up to 8, 3
     * beyond, and fewer edits than the typed name has characters. */
    assert_null(loadid_yaml_get(root, "cpu"));
    assert_null(loadid_yaml_get(root, "max_evals"));
    assert_string_equal(loadid_yaml_suggest(root, "cup"), "cpu"); /* a swap */
    assert_string_equal(loadid_yaml_suggest(root, "Label"), "label");
    assert_string_equal(loadid_yaml_suggest(root, "mx_evls"), "max_evals"); /* 2 of 3 */
    assert_null(loadid_yaml_suggest(root, "x"));   /* 3 edits from cpu: no typo of it */
    assert_null(loadid_yaml_suggest(root, "cxx")); /* 2 edits of a 3-character key */
    assert_null(loadid_yaml_get(root, "n"));
    assert_null(loadid_yaml_suggest(root, "m")); /* as many edits as characters */
    assert_string_equal(loadid_yaml_suggest(root, "nn"), "n");
    assert_null(loadid_yaml_suggest(j1, "cpu")); /* another mapping's keys */
    assert_null(loadid_yaml_suggest(NULL, "cpu"));
    char known[64];
    assert_int_equal(loadid_yaml_known_keys(j1, known, sizeof known), strlen("coeffs"));
    assert_string_equal(known, "coeffs");
    assert_int_equal(loadid_yaml_known_keys(root, known, sizeof known),
                     strlen("joints, label, flag, nothing, cpu, max_evals, n"));
    assert_string_equal(known, "joints, label, flag, nothing, cpu, max_evals, n");
    assert_int_equal(loadid_yaml_known_keys(root, known, 10), 47);
    assert_string_equal(known, "joints, l"); /* truncated */
    loadid_yaml_free(doc);
}

static void yaml_tree_scalars(void **state) {
    (void)state;
    loadid_yaml_doc_t *doc = parse(
        "b1: false\nb2: FALSE\nb3: yes\n"
        "u1: 18446744073709551615\nu2: 0xFFFFFFFFFFFFFFFF\n"
        "u3: 18446744073709551616\nu4: +7\n"
        "i1: -2147483648\ni2: 2147483648\ni3: -0x10\ni4: 1e3\n"
        "d1: 7\nd2: -.5e-3\nd3: 1.\nd4: .\nd5: 0x10\nd6: !!str 3\n"
        "d7: '3'\nd8: +.INF\n"
        "s1: ''\ns2: \"x\\0y\"\ns3: 12345\nn1: ~\nn2: null\nl: |\n  two\n  lines\n");
    loadid_yaml_node_t *r = loadid_yaml_root(doc);
    int b = -1, i = 0;
    uint64_t u = 0;
    double d = 0;
    char s[8];

    assert_int_equal(loadid_yaml_get_bool(r, "b1", &b), 1);
    assert_int_equal(b, 0);
    assert_int_equal(loadid_yaml_get_bool(r, "b2", &b), 1);
    assert_int_equal(loadid_yaml_get_bool(r, "b3", &b), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc), "t.yaml:3: b3: expected true or false, got 'yes'");

    assert_int_equal(loadid_yaml_get_uint64(r, "u1", &u), 1);
    assert_true(u == UINT64_MAX);
    assert_int_equal(loadid_yaml_get_uint64(r, "u2", &u), 1);
    assert_true(u == UINT64_MAX);
    assert_int_equal(loadid_yaml_get_uint64(r, "u3", &u), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc),
                        "t.yaml:6: u3: integer out of range: '18446744073709551616'");
    assert_int_equal(loadid_yaml_get_uint64(r, "u4", &u), 1);
    assert_true(u == 7);

    assert_int_equal(loadid_yaml_get_int(r, "i1", &i), 1);
    assert_int_equal(i, INT32_MIN);
    assert_int_equal(loadid_yaml_get_int(r, "i2", &i), -EINVAL);
    assert_prefix(loadid_yaml_error(doc), "t.yaml:9: i2: integer out of range");
    assert_int_equal(loadid_yaml_get_int(r, "i3", &i), 1);
    assert_int_equal(i, -16);
    assert_int_equal(loadid_yaml_get_int(r, "i4", &i), -EINVAL);

    assert_int_equal(loadid_yaml_get_double(r, "d1", &d), 1);
    assert_true(d == 7);
    assert_int_equal(loadid_yaml_get_double(r, "d2", &d), 1);
    assert_true(d == -0.5e-3);
    assert_int_equal(loadid_yaml_get_double(r, "d3", &d), 1);
    assert_true(d == 1);
    assert_int_equal(loadid_yaml_get_double(r, "d4", &d), -EINVAL);
    assert_int_equal(loadid_yaml_get_double(r, "d5", &d), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc), "t.yaml:16: d5: expected a number, got '0x10'");
    assert_int_equal(loadid_yaml_get_double(r, "d6", &d), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc),
                        "t.yaml:17: d6: expected a number, got the string \"3\"");
    assert_int_equal(loadid_yaml_get_double(r, "d7", &d), -EINVAL);
    assert_int_equal(loadid_yaml_get_double(r, "d8", &d), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc),
                        "t.yaml:19: d8: expected a finite number, got '+.INF'");
    assert_true(d == 1); /* failures wrote nothing */

    assert_int_equal(loadid_yaml_get_string(r, "s1", s, sizeof s), 1);
    assert_string_equal(s, "");
    assert_int_equal(loadid_yaml_get_string(r, "s2", s, sizeof s), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc), "t.yaml:21: s2: a string with a NUL character");
    assert_int_equal(loadid_yaml_get_string(r, "s3", s, sizeof s), 1);
    assert_string_equal(s, "12345");
    assert_int_equal(loadid_yaml_get_string(r, "s3", s, 5), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc), "t.yaml:22: s3: longer than 4 characters");
    assert_true(loadid_yaml_is_null(loadid_yaml_get(r, "n1")));
    assert_true(loadid_yaml_is_null(loadid_yaml_get(r, "n2")));
    assert_int_equal(loadid_yaml_get_string(r, "n2", s, sizeof s), -EINVAL);
    /* A block scalar: the error message stays on one line. */
    assert_int_equal(loadid_yaml_get_double(r, "l", &d), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc),
                        "t.yaml:25: l: expected a number, got the string \"two?lines?\"");
    /* Getters on something that is not a mapping. */
    assert_int_equal(loadid_yaml_get_double(loadid_yaml_get(r, "d1"), "x", &d), -EINVAL);
    assert_string_equal(loadid_yaml_error(doc), "t.yaml:12: d1: expected a mapping, got '7'");
    loadid_yaml_free(doc);
}

static void yaml_tree_refuses(void **state) {
    (void)state;
    loadid_yaml_doc_t *doc = (loadid_yaml_doc_t *)1;
    char err[1024];
    /* Deep nesting. */
    char deep[400];
    size_t k = 0;
    for (int i = 0; i < LOADID_YAML_MAX_DEPTH + 1; ++i) deep[k++] = '[';
    for (int i = 0; i < LOADID_YAML_MAX_DEPTH + 1; ++i) deep[k++] = ']';
    deep[k] = '\0';
    assert_int_equal(loadid_yaml_load_string("d.yaml", deep, k, &doc, err, sizeof err), -EINVAL);
    assert_null(doc);
    assert_prefix(err, "d.yaml:1: ");
    assert_non_null(strstr(err, ": nested deeper than 64 levels"));
    /* A complex key. */
    assert_int_equal(
        loadid_yaml_load_string("k.yaml", "a: 1\n? [x]\n: 2\n", 15, &doc, err, sizeof err),
        -EINVAL);
    assert_string_equal(err, "k.yaml:2: (top level): a key must be a scalar, not a sequence");
    /* Text that is not NUL-terminated is read up to len. */
    assert_int_equal(loadid_yaml_load_string("n.yaml", "a: 12345", 5, &doc, err, sizeof err), 0);
    int v = 0;
    assert_int_equal(loadid_yaml_get_int(loadid_yaml_root(doc), "a", &v), 1);
    assert_int_equal(v, 12);
    loadid_yaml_free(doc);
    loadid_yaml_free(NULL);
}

/* lcm.command_sources: addresses and CIDR blocks, each checked at its own
 * line; none (absent or []) accepts every sender. */
static void lcm_command_sources(void **state) {
    (void)state;
    loadid_config_t c;
    warnings_t w;
    load_ok(write_file("s.yaml",
                       "lcm:\n  command_sources: [127.0.0.1, 10.1.0.0/16, "
                       "0.0.0.0/0]\n"),
            &c, &w);
    assert_int_equal(w.count, 0);
    assert_int_equal(c.lcm_num_command_sources, 3);
    assert_int_equal(c.lcm_command_sources[0].net, 0x7F000001u);
    assert_int_equal(c.lcm_command_sources[0].mask, 0xFFFFFFFFu);
    assert_int_equal(c.lcm_command_sources[1].net, 0x0A010000u);
    assert_int_equal(c.lcm_command_sources[1].mask, 0xFFFF0000u);
    assert_int_equal(c.lcm_command_sources[2].mask, 0u);
    load_ok(write_file("s.yaml", "lcm:\n  command_sources: []\n"), &c, &w);
    assert_int_equal(c.lcm_num_command_sources, 0);
    expect_error("lcm:\n  command_sources:\n    - 127.0.0.1\n    - 10.0.0.300\n",
                 "4: lcm.command_sources[1]: expected an IPv4 address (a.b.c.d) or block "
                 "(a.b.c.d/n, n 0..32), got '10.0.0.300'");
    expect_error("lcm:\n  command_sources: [10.0.0.0/33]\n",
                 "2: lcm.command_sources[0]: expected an IPv4 address");
    expect_error("lcm:\n  command_sources: [robot-pc]\n",
                 "2: lcm.command_sources[0]: expected an IPv4 address");
    expect_error("lcm:\n  command_sources: [10.0.0.5/24]\n",
                 "2: lcm.command_sources[0]: '10.0.0.5/24' has bits set after its prefix "
                 "length; the block is 10.0.0.0/24");
    expect_error("lcm:\n  command_sources: 127.0.0.1\n",
                 "2: lcm.command_sources: expected a sequence");
    char many[1024] = "lcm:\n  command_sources: [";
    for (int i = 0; i <= LOADID_IPV4_ALLOW_MAX; ++i)
        snprintf(many + strlen(many), sizeof many - strlen(many), "%s10.0.0.%d", i ? ", " : "", i);
    strcat(many, "]\n");
    expect_error(many, "2: lcm.command_sources: at most 16 addresses or blocks, got 17");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(shipped_example_is_the_defaults),
        cmocka_unit_test(default_function_gives_the_defaults),
        cmocka_unit_test(empty_files_give_the_defaults_with_a_warning),
        cmocka_unit_test(every_key_is_read),
        cmocka_unit_test(names_and_single_values),
        cmocka_unit_test(hex_base_id),
        cmocka_unit_test(relative_urdf_paths_follow_the_config_file),
        cmocka_unit_test(syntax_errors_name_their_line),
        cmocka_unit_test(wrong_types_name_key_and_line),
        cmocka_unit_test(wrong_lengths_and_values),
        cmocka_unit_test(bad_names),
        cmocka_unit_test(duplicate_keys),
        cmocka_unit_test(unknown_keys_in_loadid_sections_are_errors),
        cmocka_unit_test(other_programs_sections_are_warnings),
        cmocka_unit_test(urdf_origin_names_file_line_and_key),
        cmocka_unit_test(unreadable_files),
        cmocka_unit_test(load_from_a_buffer),
        cmocka_unit_test(simulation_realism_keys),
        cmocka_unit_test(yaml_tree_nodes_and_lines),
        cmocka_unit_test(yaml_tree_scalars),
        cmocka_unit_test(yaml_tree_refuses),
        cmocka_unit_test(lcm_command_sources),
    };
    return cmocka_run_group_tests(tests, setup_dir, remove_dir);
}
