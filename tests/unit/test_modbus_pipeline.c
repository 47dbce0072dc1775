/*
 * The Modbus F/T sensor's side of host/: the configuration keys sensor.*
 * and modbus.* (errors as "FILE:LINE: KEY: what", checked in full), and the
 * pipeline's entry for a decoded F/T sample without accelerometer
 * (loadid_pipeline_sample): saturated and faulty samples are counted and
 * never reach an estimator. Expected counts are tallied by this test from
 * the samples it feeds.
 */
#define _POSIX_C_SOURCE 200809L

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scratch_dir.h"
#include "loadid/config.h"
#include "loadid/modbus_ft.h"
#include "loadid/pipeline.h"
#include "loadid/signals.h"
#include "loadid/urdf.h"

#ifndef LOADID_SOURCE_DIR
#error "the build defines LOADID_SOURCE_DIR"
#endif

static char g_dir[128];
static char g_file[256];

static int setup_dir(void **state) {
    (void)state;
    if (scratch_dir_make(g_dir, sizeof g_dir, "test-modbus-cfg") != 0) return -1;
    snprintf(g_file, sizeof g_file, "%s/c.yaml", g_dir);
    return 0;
}

static int teardown_dir(void **state) {
    (void)state;
    return scratch_dir_remove(g_dir);
}

static int warnings;
static void count_warning(void *ctx, const char *msg) {
    (void)ctx;
    print_message("    warning: %s\n", msg);
    ++warnings;
}

static int load_text(const char *text, loadid_config_t *cfg, char *err, size_t len) {
    FILE *f = fopen(g_file, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    warnings = 0;
    return loadid_config_load(g_file, cfg, err, len, count_warning, NULL);
}

/* The whole message: "<file>:" rest. */
static void expect_error(const char *text, const char *rest, int whole) {
    loadid_config_t cfg;
    char err[512], want[512];
    assert_int_equal(load_text(text, &cfg, err, sizeof err), -EINVAL);
    snprintf(want, sizeof want, "%s:%s", g_file, rest);
    if (whole ? strcmp(err, want) != 0 : strncmp(err, want, strlen(want)) != 0) {
        print_error("expected%s\n  %s\ngot\n  %s\n", whole ? "" : " a prefix", want, err);
        fail();
    }
}

static void config_errors(void **state) {
    (void)state;
    /* The default source, kf, takes a - g and alpha from the joints. */
    loadid_config_t ok;
    char okerr[512];
    assert_int_equal(load_text("sensor:\n  type: modbus\n", &ok, okerr, sizeof okerr), 0);
    assert_int_equal(ok.signals, LOADID_SIGNALS_KF);
    expect_error("estimation:\n  signals: sensor\nsensor:\n  type: modbus\n",
                 "4: sensor.type: a Modbus F/T sensor has no accelerometer: estimation.signals "
                 "must be kf or setpoint, got sensor",
                 1);
    expect_error("estimation:\n  signals: mixed\nsensor:\n  type: modbus\n",
                 "4: sensor.type: a Modbus F/T sensor has no accelerometer: estimation.signals "
                 "must be kf or setpoint, got mixed",
                 1);
    expect_error("sensor:\n  type: can\n",
                 "2: sensor.type: unknown sensor type 'can' (jr3 or modbus)", 1);
    expect_error("modbus:\n  device: /dev/ttyS0\n  baud: 12345\n",
                 "3: modbus.baud: unsupported baud rate 12345 (", 0);
    expect_error("modbus:\n  baud: fast\n", "2: modbus.baud: ", 0);
    expect_error("modbus:\n  parity: mark\n",
                 "2: modbus.parity: unknown parity 'mark' (none, even or odd)", 1);
    expect_error("modbus:\n  parity: N\n",
                 "2: modbus.parity: unknown parity 'N' (none, even or odd)", 1);
    expect_error("modbus:\n  slave_id: 0\n", "2: modbus.slave_id: must be 1..247, got 0", 1);
    expect_error("modbus:\n  data_bits: 9\n", "2: modbus.data_bits: must be 5..8, got 9", 1);
    expect_error("modbus:\n  stop_bits: 3\n", "2: modbus.stop_bits: must be 1..2, got 3", 1);
    expect_error("modbus:\n  rate_hz: 0\n", "2: modbus.rate_hz: must be > 0, got 0", 1);
    expect_error("modbus:\n  rate_hz: 2000\n", "2: modbus.rate_hz: must be <= 1000 Hz, got 2000",
                 1);
    expect_error("modbus:\n  timeout_ms: 0\n", "2: modbus.timeout_ms: must be 1..60000, got 0", 1);
    expect_error("modbus:\n  device: \"\"\n", "2: modbus.device: must not be empty", 1);
    expect_error("modbus:\n  full_scale:\n    force: [1, 2]\n", "3: modbus.full_scale.force: ", 0);
    expect_error("modbus:\n  full_scale:\n    moment: [1, -2, 3]\n",
                 "3: modbus.full_scale.moment[1]: must be > 0, got -2", 1);
}

static void config_every_key_and_defaults(void **state) {
    (void)state;
    loadid_config_t c;
    char err[512];
    assert_int_equal(load_text("sensor:\n  type: modbus\nestimation:\n  signals: kf\nmodbus:\n"
                               "  device: /dev/ttyS3\n  baud: 9600\n  parity: even\n"
                               "  data_bits: 7\n  stop_bits: 2\n  slave_id: 17\n  rate_hz: 100\n"
                               "  timeout_ms: 35\n  full_scale:\n    force: [100, 110, 120]\n"
                               "    moment: [5, 6, 7.5]\n",
                               &c, err, sizeof err),
                     0);
    assert_int_equal(warnings, 0);
    assert_int_equal(c.sensor_type, LOADID_SENSOR_MODBUS);
    assert_int_equal(c.signals, LOADID_SIGNALS_KF);
    assert_string_equal(c.modbus_device, "/dev/ttyS3");
    assert_int_equal(c.modbus_baud, 9600);
    assert_int_equal(c.modbus_parity, 'E');
    assert_int_equal(c.modbus_data_bits, 7);
    assert_int_equal(c.modbus_stop_bits, 2);
    assert_int_equal(c.modbus_slave_id, 17);
    assert_true(c.modbus_rate_hz == 100.0);
    assert_int_equal(c.modbus_timeout_ms, 35);
    assert_true(c.modbus_fs_force[0] == 100 && c.modbus_fs_force[2] == 120);
    assert_true(c.modbus_fs_moment[2] == 7.5);
    assert_int_equal(load_text("sensor:\n  type: modbus\nestimation:\n  signals: setpoint\n"
                               "modbus:\n  parity: odd\n",
                               &c, err, sizeof err),
                     0);
    assert_int_equal(c.modbus_parity, 'O');

    /* the shipped example: every new key at its default, no warning */
    warnings = 0;
    assert_int_equal(loadid_config_load(LOADID_SOURCE_DIR "/host/config/loadid.yaml", &c, err,
                                        sizeof err, count_warning, NULL),
                     0);
    assert_int_equal(warnings, 0);
    assert_int_equal(c.sensor_type, LOADID_SENSOR_JR3);
    assert_string_equal(c.modbus_device, "/dev/ttyUSB0");
    assert_int_equal(c.modbus_baud, 115200);
    assert_int_equal(c.modbus_parity, 'N');
    assert_int_equal(c.modbus_data_bits, 8);
    assert_int_equal(c.modbus_stop_bits, 1);
    assert_int_equal(c.modbus_slave_id, 1);
    assert_true(c.modbus_rate_hz == 200.0);
    assert_int_equal(c.modbus_timeout_ms, 20);
    for (int i = 0; i < 3; ++i)
        assert_true(c.modbus_fs_force[i] == 200.0 && c.modbus_fs_moment[i] == 12.0);
    loadid_config_t d;
    loadid_config_default(&d);
    assert_string_equal(d.modbus_device, c.modbus_device);
    assert_int_equal(d.modbus_baud, c.modbus_baud);
    assert_true(d.modbus_rate_hz == c.modbus_rate_hz);
}

/* modbus.baud: the configuration accepts exactly the rates the driver can
 * set (libmodbus' list), and the 19 of these candidates that it holds. */
static void config_bauds_match_the_driver(void **state) {
    (void)state;
    const int cand[] = {0,       50,      110,     134,     300,    1200,    9600,    14400,
                        19200,   28800,   38400,   57600,   76800,  115200,  128000,  230400,
                        250000,  460800,  500000,  576000,  921600, 1000000, 1152000, 1500000,
                        2000000, 3000000, 4000000, 5000000, -9600};
    int accepted = 0;
    for (size_t i = 0; i < sizeof cand / sizeof cand[0]; ++i) {
        char text[128], err[512];
        loadid_config_t c;
        snprintf(text, sizeof text, "modbus:\n  baud: %d\n", cand[i]);
        const int ok = load_text(text, &c, err, sizeof err) == 0;
        if (ok != loadid_modbus_ft_baud_supported(cand[i]))
            fail_msg("baud %d: config %s, driver %s", cand[i], ok ? "accepts" : "refuses",
                     ok ? "refuses" : "accepts");
        accepted += ok;
    }
    assert_int_equal(
        accepted,
        19); /* 110 300 1200 9600 19200 38400 57600 115200 230400 460800 500000 576000 921600 1e6 1152000 1.5e6 2e6 3e6 4e6 */
}

/* ------------------------------------------------------------ pipeline */

/* A Modbus F/T sample as the daemon hands it over: no accelerometer. */
static void ft_sample(loadid_pipeline_t *p, int64_t t_us, const double f[3], const double tq[3],
                      int sat, int bad) {
    loadid_sensor_sample_t s = {.t_us = t_us, .saturated = sat != 0, .faulty = bad != 0};
    memcpy(s.force, f, sizeof s.force);
    memcpy(s.torque, tq, sizeof s.torque);
    loadid_pipeline_sample(p, &s);
}

typedef struct {
    int64_t fed_saturated, fed_faulty, clean, clean_in_window;
} tally_t;

/* Feeds 1 kHz joint states of a still robot and F/T samples 0.5 ms before
 * each; ZERO at 1 ms, START at 300 ms, STOP at 800 ms. Sample i (time
 * i ms - 0.5 ms) is saturated when i % 5 == 0 and faulty when i % 7 == 0,
 * and then carries an absurd wrench. */
static void run(loadid_pipeline_t *p, tally_t *t, int64_t t0) {
    const double q[6] = {0.1, -0.4, 1.2, 0.0, 0.6, 0.0};
    memset(t, 0, sizeof *t);
    for (int i = 1; i < 1000; ++i) {
        const int64_t now = t0 + (int64_t)i * 1000;
        const int sat = i % 5 == 0, bad = i % 7 == 0;
        const double big = sat || bad ? 1e4 : 1.0;
        const double f[3] = {0.2 * big, -0.1 * big, 9.81 * big};
        const double tq[3] = {0.01 * big, 0.02, -0.01};
        /* in time order: the sample (now - 0.5 ms), a command, the joints */
        ft_sample(p, now - 500, f, tq, sat, bad);
        if (i == 1) loadid_pipeline_command(p, now, LOADID_CMD_ZERO, "");
        if (i == 300) loadid_pipeline_command(p, now, LOADID_CMD_START, "modbus");
        if (i == 800) loadid_pipeline_command(p, now, LOADID_CMD_STOP, "");
        loadid_pipeline_joint_state(p, now, 6, q, q);
        t->fed_saturated += sat;
        t->fed_faulty += bad;
        if (!sat && !bad) {
            ++t->clean;
            /* ESTIMATING from START (300 ms) until STOP (800 ms) */
            const int64_t ts = now - 500 - t0;
            if (ts >= 300000 && ts < 800000) ++t->clean_in_window;
        }
    }
    loadid_pipeline_finish(p, t0 + 1000000);
}

static void pipeline_never_feeds_saturated_or_faulty(void **state) {
    (void)state;
    loadid_config_t cfg;
    loadid_config_default(&cfg);
    cfg.sensor_type = LOADID_SENSOR_MODBUS;
    cfg.signals = LOADID_SIGNALS_KF;
    loadid_chain_t chain;
    char err[256];
    assert_int_equal(loadid_urdf_load_file(cfg.robot_urdf, cfg.robot_base_link,
                                           cfg.robot_sensor_link, &chain, err, sizeof err),
                     0);
    loadid_pipeline_t *p = NULL;
    assert_int_equal(loadid_pipeline_create(&cfg, &chain, NULL, 0, &p, err, sizeof err), 0);
    tally_t t;
    run(p, &t, 1700000000000000LL);
    loadid_pipeline_status_t st;
    loadid_pipeline_status(p, &st);
    print_message(
        "    fed %lld clean (%lld in the window), %lld saturated, %lld faulty; "
        "pipeline: ok %lld used %lld saturated %lld faulty %lld, state %d\n",
        (long long)t.clean, (long long)t.clean_in_window, (long long)t.fed_saturated,
        (long long)t.fed_faulty, (long long)st.samples_ok, (long long)st.samples_used,
        (long long)st.samples_saturated, (long long)st.samples_faulty, st.state);
    assert_int_equal(t.clean_in_window,
                     500 - 100 - 72 + 14); /* i = 301..800: 100 x5, 72 x7, 14 x35 */
    assert_int_equal(st.samples_saturated, t.fed_saturated);
    assert_int_equal(st.samples_faulty, t.fed_faulty);
    assert_int_equal(st.samples_ok, t.clean);
    assert_int_equal(st.samples_used, t.clean_in_window);
    assert_int_equal(st.samples_stale, 0);
    assert_int_equal(st.frames_bad, 0);
    assert_int_equal(st.state, LOADID_STATE_DONE);
    loadid_pipeline_estimate_t e[LOADID_MAX_METHODS];
    const int n = loadid_pipeline_estimates(p, e, LOADID_MAX_METHODS);
    assert_true(n >= 1);
    for (int m = 0; m < n; ++m) {
        /* Every clean sample of the window reached every method, and none
         * other; a still robot excites nothing, and each estimate says so. */
        assert_int_equal(e[m].samples, t.clean_in_window);
        assert_false(e[m].valid);
        assert_int_equal(e[m].error, LOADID_E_NOT_EXCITED);
    }
    /* non-finite values: counted as bad, not fed */
    const double nanf[3] = {0, 0, 0.0 / 0.0}, zero[3] = {0, 0, 0};
    ft_sample(p, 1700000001000000LL, nanf, zero, 0, 0);
    loadid_pipeline_sample(p, NULL); /* a read without a sample */
    loadid_pipeline_status(p, &st);
    assert_int_equal(st.frames_bad, 2);
    assert_int_equal(st.samples_ok, t.clean);
    loadid_pipeline_destroy(p);

    /* a source that needs the JR3's accelerometer refuses them all */
    cfg.signals = LOADID_SIGNALS_MIXED;
    assert_int_equal(loadid_pipeline_create(&cfg, &chain, NULL, 0, &p, err, sizeof err), 0);
    run(p, &t, 1700000000000000LL);
    loadid_pipeline_status(p, &st);
    assert_int_equal(st.samples_used, 0);
    assert_int_equal(st.frames_bad, t.clean);
    assert_int_equal(st.samples_saturated, t.fed_saturated);
    loadid_pipeline_destroy(p);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(config_errors),
        cmocka_unit_test(config_every_key_and_defaults),
        cmocka_unit_test(config_bauds_match_the_driver),
        cmocka_unit_test(pipeline_never_feeds_saturated_or_faulty),
    };
    return cmocka_run_group_tests(tests, setup_dir, teardown_dir);
}
