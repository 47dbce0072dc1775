/*
 * Tests of the Modbus RTU F/T sensor (proto/modbus_ft.md): the pure
 * decoder with register vectors (drivers/modbus_ft.h), then the libmodbus
 * client against a real libmodbus RTU server over a real pseudo-terminal
 * pair (no mocks), then the poller thread (host/src/daemon/inputs/modbus_input.h),
 * its real-time attributes read back from the kernel.
 *
 * The pty: openpty() gives a master descriptor and a slave /dev/pts/N. The
 * sensor (loadid_modbus_ft_server, modbus_reply over a modbus_mapping_t)
 * serves on the master descriptor in a thread of its own; the driver under
 * test opens the slave through a symlink in a temporary folder, so that a
 * "device that comes back" is a new pty behind the same path. Expected SI
 * values are computed here as counts * full_scale / 16384 from the counts
 * the test itself put into the server's registers.
 */
#define _GNU_SOURCE /* cfmakeraw, openpty; sched_getaffinity, CPU_* */

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <dirent.h>
#include <pthread.h>
#include <pty.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/epoll.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "scratch_dir.h"
#include "loadid/modbus_ft.h"
#include "loadid/modbus_ft_server.h"
#include "modbus_input.h"

/* A skipped test makes the whole program exit LOADID_TEST_SKIPPED, which
 * ctest shows as skipped (SKIP_RETURN_CODE), not as passed. */
#define LOADID_TEST_SKIPPED 77
static int g_skipped;
static const double kFsForce[3] = {200.0, 100.0, 50.0};
static const double kFsMoment[3] = {12.0, 6.0, 3.0};

static double expect_si(int counts, double fs) {
    return counts * fs / 16384.0;
}

static uint16_t reg_of(int v) {
    return (uint16_t)(v < 0 ? v + 65536 : v);
}

static void block(uint16_t r[8], const int c[6], unsigned status, unsigned counter) {
    for (int i = 0; i < 6; ++i) r[i] = reg_of(c[i]);
    r[6] = (uint16_t)status;
    r[7] = (uint16_t)counter;
}

static int64_t realtime_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static int64_t mono_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

/* ======================================================= pure decoder == */

static void decoder_si_values(void **state) {
    (void)state;
    loadid_modbus_ft_decoder_t d;
    assert_int_equal(loadid_modbus_ft_decoder_init(&d, kFsForce, kFsMoment), 0);
    const int c[6] = {16384, -16384, 8192, 1, -32768, 32767};
    uint16_t r[8];
    block(r, c, 0, 7);
    loadid_modbus_ft_sample_t s;
    assert_int_equal(loadid_modbus_ft_decode(&d, r, 123456789, &s), LOADID_MODBUS_FT_SAMPLE);
    assert_int_equal(s.t_us, 123456789);
    assert_int_equal(s.counter, 7);
    for (int k = 0; k < 3; ++k) {
        assert_int_equal(s.counts[k], c[k]);
        assert_int_equal(s.counts[3 + k], c[3 + k]);
        assert_true(s.force[k] == expect_si(c[k], kFsForce[k]));
        assert_true(s.torque[k] == expect_si(c[3 + k], kFsMoment[k]));
    }
    /* literal checks of the convention: 16384 counts = full scale */
    assert_true(s.force[0] == 200.0 && s.force[1] == -100.0 && s.force[2] == 25.0);
    assert_true(s.torque[1] == -12.0);
    assert_false(s.saturated || s.faulty);
    /* bad arguments and configurations */
    assert_int_equal(loadid_modbus_ft_decode(&d, NULL, 0, &s), -EINVAL);
    const double zero[3] = {200, 0, 200}, nan3[3] = {NAN, 1, 1};
    assert_int_equal(loadid_modbus_ft_decoder_init(&d, zero, kFsMoment), -EINVAL);
    assert_int_equal(loadid_modbus_ft_decoder_init(&d, kFsForce, nan3), -EINVAL);
}

static void decoder_status_bits(void **state) {
    (void)state;
    loadid_modbus_ft_decoder_t d;
    loadid_modbus_ft_decoder_init(&d, kFsForce, kFsMoment);
    const int c[6] = {100, 200, 300, 400, 500, 600};
    uint16_t r[8];
    loadid_modbus_ft_sample_t s;
    block(r, c, 0x1, 1);
    assert_int_equal(loadid_modbus_ft_decode(&d, r, 0, &s), LOADID_MODBUS_FT_E_SATURATED);
    assert_true(s.saturated && !s.faulty);
    assert_true(s.force[2] == expect_si(300, 50.0)); /* decoded for logging */
    block(r, c, 0x2, 2);
    assert_int_equal(loadid_modbus_ft_decode(&d, r, 0, &s), LOADID_MODBUS_FT_E_FAULT);
    block(r, c, 0x3, 3);
    assert_int_equal(loadid_modbus_ft_decode(&d, r, 0, &s), LOADID_MODBUS_FT_E_FAULT);
    assert_true(s.saturated && s.faulty);
    /* each reserved bit on its own: malformed, and the counter not taken */
    int malformed = 0;
    for (int bit = 2; bit < 16; ++bit) {
        block(r, c, 1u << bit, 100 + bit);
        assert_int_equal(loadid_modbus_ft_decode(&d, r, 0, &s), LOADID_MODBUS_FT_E_MALFORMED);
        ++malformed;
    }
    block(r, c, 0, 4); /* 3 -> 4: no gap, because the malformed ones did not count */
    assert_int_equal(loadid_modbus_ft_decode(&d, r, 0, &s), LOADID_MODBUS_FT_SAMPLE);
    const loadid_modbus_ft_stats_t *st = &d.st;
    assert_int_equal(st->samples_saturated, 2);
    assert_int_equal(st->samples_faulty, 2);
    assert_int_equal(st->samples_rejected, 3);
    assert_int_equal(st->samples_malformed, malformed);
    assert_int_equal(st->samples_ok, 1);
    assert_int_equal(st->counter_gaps, 0);
    assert_int_equal(st->blocks, 4 + malformed);
}

static void decoder_stale_and_gaps(void **state) {
    (void)state;
    loadid_modbus_ft_decoder_t d;
    loadid_modbus_ft_decoder_init(&d, kFsForce, kFsMoment);
    const unsigned seq[] = {10, 10, 11, 15, 15, 15, 65535, 0, 1, 1, 3};
    const int n = (int)(sizeof seq / sizeof seq[0]);
    /* expected, computed step by step here */
    int64_t stale = 0, gaps = 0, ok = 0;
    for (int i = 0; i < n; ++i) {
        if (i > 0 && seq[i] == seq[i - 1]) {
            ++stale;
            continue;
        }
        if (i > 0) gaps += (int64_t)((seq[i] - seq[i - 1] + 65536u) % 65536u) - 1;
        ++ok;
    }
    assert_int_equal(stale, 4);
    assert_int_equal(gaps, 3 + 65519 + 1); /* 11->15, 15->65535, 1->3 */
    const int c[6] = {0};
    for (int i = 0; i < n; ++i) {
        uint16_t r[8];
        loadid_modbus_ft_sample_t s;
        block(r, c, 0, seq[i]);
        const int rc = loadid_modbus_ft_decode(&d, r, i, &s);
        const bool is_stale = i > 0 && seq[i] == seq[i - 1];
        assert_int_equal(rc, is_stale ? LOADID_MODBUS_FT_E_STALE : LOADID_MODBUS_FT_SAMPLE);
    }
    assert_int_equal(d.st.samples_stale, stale);
    assert_int_equal(d.st.counter_gaps, gaps);
    assert_int_equal(d.st.samples_ok, ok);
    /* after a restart (a reopen) the first block is new whatever its counter */
    loadid_modbus_ft_decoder_restart(&d);
    uint16_t r[8];
    loadid_modbus_ft_sample_t s;
    block(r, c, 0, 3);
    assert_int_equal(loadid_modbus_ft_decode(&d, r, 0, &s), LOADID_MODBUS_FT_SAMPLE);
    assert_int_equal(d.st.counter_gaps, gaps);
}

static void decoder_full_scale_registers(void **state) {
    (void)state;
    loadid_modbus_ft_decoder_t d;
    loadid_modbus_ft_decoder_init(&d, kFsForce, kFsMoment);
    const uint16_t fs[6] = {1500, 2000, 2505, 800, 900, 1234};
    assert_int_equal(loadid_modbus_ft_decode_full_scale(&d, fs), LOADID_MODBUS_FT_FULL_SCALE);
    const int c[6] = {16384, 8192, -4096, 16384, 1000, -1};
    uint16_t r[8];
    loadid_modbus_ft_sample_t s;
    block(r, c, 0, 1);
    assert_int_equal(loadid_modbus_ft_decode(&d, r, 0, &s), LOADID_MODBUS_FT_SAMPLE);
    assert_true(s.force[0] == 150.0); /* 1500 x 0.1 N */
    assert_true(s.force[1] == expect_si(8192, 200.0));
    assert_true(s.force[2] == expect_si(-4096, 250.5));
    assert_true(s.torque[0] == 8.0); /* 800 x 0.01 N m */
    assert_true(s.torque[1] == expect_si(1000, 9.0));
    assert_true(s.torque[2] == expect_si(-1, 12.34));
    /* a zero register: malformed, full scales unchanged */
    const uint16_t bad[6] = {1000, 1000, 0, 100, 100, 100};
    assert_int_equal(loadid_modbus_ft_decode_full_scale(&d, bad), LOADID_MODBUS_FT_E_MALFORMED);
    assert_true(d.fs_force[0] == 150.0 && d.fs_moment[2] == 12.34);
    assert_int_equal(d.st.full_scale_reads, 1);
    assert_int_equal(d.st.full_scale_malformed, 1);
}

static void encoder_round_trip_and_saturation(void **state) {
    (void)state;
    uint16_t r[8];
    const double f[3] = {300.0, -50.0, 1000.0}, t[3] = {1.5, -30.0, 0.0};
    assert_int_equal(loadid_modbus_ft_encode(kFsForce, kFsMoment, f, t, false, 42, r), 0);
    /* 300 N of 200: 24576; -50 of 100: -8192; 1000 of 50: 327680 -> clamped */
    assert_int_equal(r[0], 24576);
    assert_int_equal(r[1], reg_of(-8192));
    assert_int_equal(r[2], 32767);
    assert_int_equal(r[3], 2048);
    assert_int_equal(r[4], reg_of(-32768));
    assert_int_equal(r[5], 0);
    assert_int_equal(r[6], LOADID_MODBUS_FT_STATUS_SATURATED);
    assert_int_equal(r[7], 42);
    /* Within half a count of the limit: that count, not saturated (the
     * fuzzer's round trip found 32767 counts of a 1.9 N full scale coming
     * back saturated: 32767 * 1.9 / 16384 * 16384 / 1.9 > 32767). */
    const double fs19[3] = {1.9, 1.9, 1.9};
    const double edge[3] = {32767 * 1.9 / 16384, 32767.49 * 1.9 / 16384, -32768.49 * 1.9 / 16384};
    const double t0[3] = {0, 0, 0};
    assert_int_equal(loadid_modbus_ft_encode(fs19, kFsMoment, edge, t0, false, 7, r), 0);
    assert_int_equal(r[0], 32767);
    assert_int_equal(r[1], 32767);
    assert_int_equal(r[2], reg_of(-32768));
    assert_int_equal(r[6], 0);
    const double over[3] = {32767.5 * 1.9 / 16384, 0, 0};
    assert_int_equal(loadid_modbus_ft_encode(fs19, kFsMoment, over, t0, false, 7, r), 0);
    assert_int_equal(r[0], 32767);
    assert_int_equal(r[6], LOADID_MODBUS_FT_STATUS_SATURATED);
    const double nanf[3] = {NAN, 0, 0};
    assert_int_equal(loadid_modbus_ft_encode(kFsForce, kFsMoment, nanf, t, false, 1, r), 0);
    assert_true(r[6] & LOADID_MODBUS_FT_STATUS_FAULT);
    uint16_t h[6];
    assert_int_equal(loadid_modbus_ft_encode_full_scale(kFsForce, kFsMoment, h), 0);
    assert_int_equal(h[0], 2000);
    assert_int_equal(h[5], 300);
    const double tiny[3] = {0.01, 1, 1};
    assert_int_equal(loadid_modbus_ft_encode_full_scale(tiny, kFsMoment, h), -ERANGE);
}

/* splitmix64 garbage: never a crash, the counters' invariants hold. */
static void decoder_random_blocks(void **state) {
    (void)state;
    uint64_t x = 12345;
    loadid_modbus_ft_decoder_t d;
    loadid_modbus_ft_decoder_init(&d, kFsForce, kFsMoment);
    int64_t tally[4] = {0}; /* ok, rejected, stale, malformed */
    for (int i = 0; i < 20000; ++i) {
        uint16_t r[8];
        for (int k = 0; k < 8; ++k) {
            uint64_t z = (x += 0x9E3779B97F4A7C15ull);
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
            z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
            r[k] = (uint16_t)(z ^ (z >> 31));
        }
        if (i % 3) r[6] &= 3;                  /* mostly valid status words */
        if (i % 5 == 0) r[7] = d.last_counter; /* some stale */
        loadid_modbus_ft_sample_t s;
        const int rc = loadid_modbus_ft_decode(&d, r, i, &s);
        if (rc == LOADID_MODBUS_FT_SAMPLE)
            ++tally[0];
        else if (rc == LOADID_MODBUS_FT_E_SATURATED || rc == LOADID_MODBUS_FT_E_FAULT)
            ++tally[1];
        else if (rc == LOADID_MODBUS_FT_E_STALE)
            ++tally[2];
        else if (rc == LOADID_MODBUS_FT_E_MALFORMED)
            ++tally[3];
        else
            fail_msg("unexpected code %d", rc);
        if (rc == LOADID_MODBUS_FT_SAMPLE) {
            for (int k = 0; k < 3; ++k) assert_true(fabs(s.force[k]) <= 2 * kFsForce[k]);
        }
    }
    const loadid_modbus_ft_stats_t *st = &d.st;
    assert_int_equal(st->samples_ok, tally[0]);
    assert_int_equal(st->samples_rejected, tally[1]);
    assert_int_equal(st->samples_stale, tally[2]);
    assert_int_equal(st->samples_malformed, tally[3]);
    assert_int_equal(st->blocks, 20000);
    assert_true(tally[0] > 0 && tally[1] > 0 && tally[2] > 0 && tally[3] > 0);
    assert_true(st->samples_rejected <= st->samples_saturated + st->samples_faulty);
    assert_true(st->samples_rejected >= st->samples_saturated &&
                st->samples_rejected >= st->samples_faulty);
}

/* ============================================== the pty and the sensor == */

static char g_dir[128];
static char g_link[200];

typedef struct {
    int master, slave; /* slave kept open: the pty keeps its raw termios */
    char pts[64];
    loadid_modbus_ft_server_t *srv;
    pthread_t th;
    atomic_bool stop;
    bool running;
    /* the counting sensor: every input read is a new measurement */
    bool counting;
    uint16_t counter;
    int64_t hook_calls;
    loadid_modbus_ft_server_stats_t final; /* the server's counters at stop */
} sensor_t;

/* counts of measurement n, channel k (inside int16) */
static int counts_of(unsigned n, int k) {
    return (int)((n * 37u + (unsigned)k * 4099u) % 60000u) - 30000;
}

static void counting_hook(void *ctx, loadid_modbus_ft_server_t *srv) {
    sensor_t *s = ctx;
    ++s->counter;
    ++s->hook_calls;
    int c[6];
    for (int k = 0; k < 6; ++k) c[k] = counts_of(s->counter, k);
    uint16_t r[8];
    block(r, c, 0, s->counter);
    loadid_modbus_ft_server_set_input(srv, r);
}

/* Sensors whose thread runs, stopped by the teardown after a failure. */
static sensor_t *g_live[4];

static void *serve(void *arg) {
    sensor_t *s = arg;
    while (!atomic_load(&s->stop)) {
        if (loadid_modbus_ft_server_poll(s->srv, 20) < 0) usleep(2000);
    }
    return NULL;
}

static void sensor_start(sensor_t *s, int nb_input, int nb_holding, bool counting) {
    memset(s, 0, sizeof *s);
    struct termios tio;
    memset(&tio, 0, sizeof tio);
    cfmakeraw(&tio);
    assert_int_equal(openpty(&s->master, &s->slave, s->pts, &tio, NULL), 0);
    unlink(g_link);
    assert_int_equal(symlink(s->pts, g_link), 0);
    assert_int_equal(loadid_modbus_ft_server_create(s->master, 1, nb_input, nb_holding, &s->srv),
                     0);
    s->counting = counting;
    if (counting) loadid_modbus_ft_server_set_hook(s->srv, counting_hook, s);
    atomic_init(&s->stop, false);
    assert_int_equal(pthread_create(&s->th, NULL, serve, s), 0);
    s->running = true;
    for (int i = 0; i < 4; ++i) {
        if (!g_live[i]) {
            g_live[i] = s;
            break;
        }
    }
}

/* Stops the sensor and closes the pty: its /dev/pts node goes away. */
static void sensor_stop(sensor_t *s) {
    if (!s->running) return;
    for (int i = 0; i < 4; ++i)
        if (g_live[i] == s) g_live[i] = NULL;
    atomic_store(&s->stop, true);
    pthread_join(s->th, NULL);
    s->running = false;
    loadid_modbus_ft_server_stats(s->srv, &s->final);
    loadid_modbus_ft_server_destroy(s->srv);
    close(s->master);
    close(s->slave);
}

static void set_sample(sensor_t *s, const int c[6], unsigned status, unsigned counter) {
    uint16_t r[8];
    block(r, c, status, counter);
    loadid_modbus_ft_server_set_input(s->srv, r);
}

static loadid_modbus_ft_config_t client_cfg(int timeout_ms) {
    loadid_modbus_ft_config_t c;
    loadid_modbus_ft_config_default(&c);
    snprintf(c.device, sizeof c.device, "%s", g_link);
    c.timeout_ms = timeout_ms;
    memcpy(c.fs_force, kFsForce, sizeof c.fs_force);
    memcpy(c.fs_moment, kFsMoment, sizeof c.fs_moment);
    return c;
}

/* The sensor most tests use: 8 input and 6 holding registers, the latter
 * holding kFsForce and kFsMoment in the register units (0.1 N, 0.01 N m). */
static const uint16_t kFsRegisters[6] = {2000, 1000, 500, 1200, 600, 300};

static void sensor_start_standard(sensor_t *s, bool counting) {
    sensor_start(s, 8, 6, counting);
    loadid_modbus_ft_server_set_holding(s->srv, kFsRegisters);
}

static loadid_modbus_ft_t *client(int timeout_ms) {
    loadid_modbus_ft_config_t c = client_cfg(timeout_ms);
    loadid_modbus_ft_t *ft = NULL;
    assert_int_equal(loadid_modbus_ft_create(&c, &ft), 0);
    return ft;
}

static void check_invariant(const loadid_modbus_ft_stats_t *st) {
    assert_int_equal(st->blocks, st->samples_ok + st->samples_rejected + st->samples_stale +
                                     st->samples_malformed);
    assert_int_equal(st->reads + st->full_scale_requests,
                     st->blocks + st->full_scale_reads + st->full_scale_malformed + st->timeouts +
                         st->bad_frames + st->exceptions + st->io_errors);
}

static int setup_dir(void **state) {
    (void)state;
    if (scratch_dir_make(g_dir, sizeof g_dir, "test-modbus") != 0) return -1;
    snprintf(g_link, sizeof g_link, "%s/ft", g_dir);
    return 0;
}

static int stop_sensors(void **state) {
    (void)state;
    for (int i = 0; i < 4; ++i)
        if (g_live[i]) sensor_stop(g_live[i]);
    return 0;
}

static int teardown_dir(void **state) {
    (void)state;
    return scratch_dir_remove(g_dir);
}

/* SI values over the wire, and the holding registers' full scales
 * overriding the configured ones. */
static void pty_values_and_full_scale_override(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start(&s, 8, 6, false);
    const uint16_t fs[6] = {1500, 2000, 2505, 800, 900, 1234}; /* 150 200 250.5 N, 8 9 12.34 N m */
    loadid_modbus_ft_server_set_holding(s.srv, fs);
    const int c[6] = {16384, -8192, 12345, -16384, 1, -32768};
    set_sample(&s, c, 0, 77);
    loadid_modbus_ft_t *ft = client(200);
    assert_int_equal(loadid_modbus_ft_open(ft), LOADID_MODBUS_FT_FULL_SCALE);
    double gf[3], gm[3];
    loadid_modbus_ft_full_scale(ft, gf, gm);
    assert_true(gf[0] == 150.0 && gf[1] == 200.0 && gf[2] == 250.5);
    assert_true(gm[0] == 8.0 && gm[1] == 9.0 && gm[2] == 12.34);
    loadid_modbus_ft_sample_t out;
    const int64_t t0 = realtime_us();
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_SAMPLE);
    const int64_t t1 = realtime_us();
    assert_true(out.t_us >= t0 && out.t_us <= t1);
    assert_int_equal(out.counter, 77);
    const double efs[6] = {150.0, 200.0, 250.5, 8.0, 9.0, 12.34};
    for (int k = 0; k < 3; ++k) {
        assert_true(out.force[k] == expect_si(c[k], efs[k]));
        assert_true(out.torque[k] == expect_si(c[3 + k], efs[3 + k]));
    }
    print_message("    over the pty: Fx %g N (counts %d), Tz %g N m (counts %d)\n", out.force[0],
                  c[0], out.torque[2], c[5]);
    loadid_modbus_ft_stats_t st;
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.opens, 1);
    assert_int_equal(st.full_scale_reads, 1);
    check_invariant(&st);
    loadid_modbus_ft_destroy(ft);
    loadid_modbus_ft_server_stats_t ss;
    loadid_modbus_ft_server_stats(s.srv, &ss);
    assert_int_equal(ss.holding_reads, 1);
    assert_int_equal(ss.input_reads, 1);
    sensor_stop(&s);

    /* a sensor without holding registers answers with an exception: the
     * configured full scales stay */
    sensor_start(&s, 8, 0, false);
    set_sample(&s, c, 0, 1);
    ft = client(200);
    assert_int_equal(loadid_modbus_ft_open(ft), 0);
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_SAMPLE);
    for (int k = 0; k < 3; ++k) assert_true(out.force[k] == expect_si(c[k], kFsForce[k]));
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.exceptions, 1);
    assert_int_equal(st.full_scale_reads, 0);
    check_invariant(&st);
    loadid_modbus_ft_destroy(ft);
    sensor_stop(&s);
}

/* Status bits and the counter, through the wire. */
static void pty_status_stale_gaps(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start_standard(&s, false);
    loadid_modbus_ft_t *ft = client(200);
    assert_int_equal(loadid_modbus_ft_open(ft), LOADID_MODBUS_FT_FULL_SCALE);
    const int c[6] = {1, 2, 3, 4, 5, 6};
    struct {
        unsigned status, counter;
        int expect;
    } steps[] = {
        {0, 1, LOADID_MODBUS_FT_SAMPLE},
        {0, 1, LOADID_MODBUS_FT_E_STALE},
        {0, 1, LOADID_MODBUS_FT_E_STALE},
        {1, 2, LOADID_MODBUS_FT_E_SATURATED},
        {2, 3, LOADID_MODBUS_FT_E_FAULT},
        {4, 9, LOADID_MODBUS_FT_E_MALFORMED},
        {0x8000, 9, LOADID_MODBUS_FT_E_MALFORMED},
        {0, 8, LOADID_MODBUS_FT_SAMPLE}, /* 3->8: 4 gaps */
        {0, 9, LOADID_MODBUS_FT_SAMPLE},
    };
    for (size_t i = 0; i < sizeof steps / sizeof steps[0]; ++i) {
        set_sample(&s, c, steps[i].status, steps[i].counter);
        loadid_modbus_ft_sample_t out;
        assert_int_equal(loadid_modbus_ft_read(ft, &out), steps[i].expect);
    }
    loadid_modbus_ft_stats_t st;
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.samples_ok, 3);
    assert_int_equal(st.samples_stale, 2);
    assert_int_equal(st.samples_saturated, 1);
    assert_int_equal(st.samples_faulty, 1);
    assert_int_equal(st.samples_malformed, 2);
    assert_int_equal(st.counter_gaps, 4);
    assert_int_equal(st.reads, 9);
    check_invariant(&st);
    loadid_modbus_ft_destroy(ft);
    sensor_stop(&s);
}

/* The sensor stops answering: a timeout, counted; it answers again: fine. */
static void pty_timeout(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start_standard(&s, true);
    loadid_modbus_ft_t *ft = client(50);
    assert_true(loadid_modbus_ft_open(ft) >= 0);
    loadid_modbus_ft_sample_t out;
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_SAMPLE);
    loadid_modbus_ft_server_set_mode(s.srv, LOADID_MODBUS_FT_SERVER_SILENT);
    const int64_t t0 = mono_ms();
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_E_TIMEOUT);
    const int64_t waited = mono_ms() - t0;
    print_message("    timeout after %lld ms (timeout_ms 50)\n", (long long)waited);
    assert_true(waited >= 45 && waited < 2000);
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_E_TIMEOUT);
    assert_true(loadid_modbus_ft_is_open(ft));
    loadid_modbus_ft_server_set_mode(s.srv, LOADID_MODBUS_FT_SERVER_NORMAL);
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_SAMPLE);
    loadid_modbus_ft_stats_t st;
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.timeouts, 2);
    /* counter: 1, (2, 3 taken by the silent sensor), 4: two gaps */
    assert_int_equal(out.counter, 4);
    assert_int_equal(st.counter_gaps, 2);
    check_invariant(&st);
    loadid_modbus_ft_server_stats_t ss;
    loadid_modbus_ft_server_stats(s.srv, &ss);
    assert_int_equal(ss.silent, 2);
    loadid_modbus_ft_destroy(ft);
    sensor_stop(&s);

    /* a sensor at another slave id never answers: the open fails */
    sensor_start(&s, 8, 6, false);
    loadid_modbus_ft_config_t c = client_cfg(50);
    c.slave_id = 2;
    assert_int_equal(loadid_modbus_ft_create(&c, &ft), 0);
    assert_int_equal(loadid_modbus_ft_open(ft), LOADID_MODBUS_FT_E_TIMEOUT);
    assert_false(loadid_modbus_ft_is_open(ft));
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.open_failures, 1);
    assert_int_equal(st.timeouts, 1);
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_E_CLOSED);
    loadid_modbus_ft_destroy(ft);
    sensor_stop(&s);
}

/* Frames with a wrong CRC written raw to the pty. */
static void pty_crc_errors(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start_standard(&s, true);
    loadid_modbus_ft_t *ft = client(100);
    assert_true(loadid_modbus_ft_open(ft) >= 0);
    loadid_modbus_ft_server_set_mode(s.srv, LOADID_MODBUS_FT_SERVER_BAD_CRC);
    loadid_modbus_ft_sample_t out;
    for (int i = 0; i < 3; ++i)
        assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_E_BAD_FRAME);
    loadid_modbus_ft_server_set_mode(s.srv, LOADID_MODBUS_FT_SERVER_NORMAL);
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_SAMPLE);
    /* the good answer is the 4th measurement */
    assert_int_equal(out.counter, 4);
    for (int k = 0; k < 3; ++k)
        assert_true(out.force[k] == expect_si(counts_of(4, k), kFsForce[k]));

    /* raw garbage on the line before a request: flushed by the next
     * failure or ignored; never a crash, always counted */
    const uint8_t junk[] = {0x01, 0x04, 0x10, 0xde, 0xad, 0xbe, 0xef, 0x00, 0x11};
    assert_int_equal(write(s.master, junk, sizeof junk), (ssize_t)sizeof junk);
    usleep(10000);
    int rc = loadid_modbus_ft_read(ft, &out);
    print_message("    after raw garbage: %s\n", loadid_modbus_ft_strerror(rc));
    assert_true(rc == LOADID_MODBUS_FT_E_BAD_FRAME || rc == LOADID_MODBUS_FT_E_TIMEOUT ||
                rc == LOADID_MODBUS_FT_SAMPLE);
    for (int i = 0; i < 3 && rc != LOADID_MODBUS_FT_SAMPLE; ++i)
        rc = loadid_modbus_ft_read(ft, &out);
    assert_int_equal(rc, LOADID_MODBUS_FT_SAMPLE);
    loadid_modbus_ft_stats_t st;
    loadid_modbus_ft_stats(ft, &st);
    assert_true(st.crc_errors >= 3);
    assert_true(st.bad_frames >= 3);
    check_invariant(&st);
    loadid_modbus_ft_server_stats_t ss;
    loadid_modbus_ft_server_stats(s.srv, &ss);
    assert_int_equal(ss.bad_crc, 3);
    loadid_modbus_ft_destroy(ft);
    sensor_stop(&s);
}

/* A sensor with fewer input registers than the map: exception responses. */
static void pty_exception(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start(&s, 4, 6, false);
    loadid_modbus_ft_server_set_holding(s.srv, kFsRegisters);
    loadid_modbus_ft_t *ft = client(100);
    assert_int_equal(loadid_modbus_ft_open(ft), LOADID_MODBUS_FT_FULL_SCALE);
    loadid_modbus_ft_sample_t out;
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_E_EXCEPTION);
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_E_EXCEPTION);
    assert_true(loadid_modbus_ft_is_open(ft));
    print_message("    %s\n", loadid_modbus_ft_last_error(ft));
    assert_non_null(strstr(loadid_modbus_ft_last_error(ft), "Illegal data address"));
    loadid_modbus_ft_stats_t st;
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.exceptions, 2);
    assert_int_equal(st.blocks, 0);
    check_invariant(&st);
    loadid_modbus_ft_destroy(ft);
    sensor_stop(&s);
}

/* The device vanishes (the pty is closed), then comes back. */
static void pty_device_vanishes_and_returns(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start_standard(&s, true);
    loadid_modbus_ft_t *ft = client(100);
    assert_true(loadid_modbus_ft_open(ft) >= 0);
    loadid_modbus_ft_sample_t out;
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_SAMPLE);
    sensor_stop(&s);
    int rc = loadid_modbus_ft_read(ft, &out);
    print_message("    after the pty closed: %s (%s)\n", loadid_modbus_ft_strerror(rc),
                  loadid_modbus_ft_last_error(ft));
    assert_int_equal(rc, LOADID_MODBUS_FT_E_GONE);
    assert_false(loadid_modbus_ft_is_open(ft));
    rc = loadid_modbus_ft_open(ft);
    print_message("    reopen while gone: %s (%s)\n", loadid_modbus_ft_strerror(rc),
                  loadid_modbus_ft_last_error(ft));
    assert_int_equal(rc, -ENOENT);
    assert_non_null(strstr(loadid_modbus_ft_last_error(ft), g_link));
    loadid_modbus_ft_stats_t st;
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.device_lost, 1);
    assert_int_equal(st.io_errors, 1);
    assert_int_equal(st.open_failures, 1);

    sensor_start_standard(&s, true); /* a new pty behind the same path */
    assert_int_equal(loadid_modbus_ft_open(ft), LOADID_MODBUS_FT_FULL_SCALE);
    assert_int_equal(loadid_modbus_ft_read(ft, &out), LOADID_MODBUS_FT_SAMPLE);
    assert_int_equal(out.counter, 1); /* the new sensor's first: no gap, not stale */
    loadid_modbus_ft_stats(ft, &st);
    assert_int_equal(st.opens, 2);
    assert_int_equal(st.counter_gaps, 0);
    check_invariant(&st);
    loadid_modbus_ft_destroy(ft);
    sensor_stop(&s);
}

/* ========================================================== the poller == */

typedef struct {
    loadid_modbus_ft_sample_t got[4096];
    int n;
} collected_t;

static void collect(void *ctx, const loadid_modbus_ft_sample_t *s) {
    collected_t *c = ctx;
    if (c->n < 4096) c->got[c->n] = *s;
    c->n++;
}

static loadid_config_t poller_cfg(double rate_hz) {
    loadid_config_t c;
    loadid_config_default(&c);
    snprintf(c.modbus_device, sizeof c.modbus_device, "%s", g_link);
    c.modbus_rate_hz = rate_hz;
    c.modbus_timeout_ms = 100;
    return c;
}

/* Runs the loop's side for ms: epoll on the eventfd, drain. */
static void run_loop(loadid_modbus_input_t *in, collected_t *c, int ms) {
    const int ep = epoll_create1(0);
    assert_true(ep >= 0);
    struct epoll_event ev = {.events = EPOLLIN};
    assert_int_equal(epoll_ctl(ep, EPOLL_CTL_ADD, loadid_modbus_input_fd(in), &ev), 0);
    const int64_t end = mono_ms() + ms;
    while (mono_ms() < end) {
        struct epoll_event got;
        if (epoll_wait(ep, &got, 1, 50) == 1) loadid_modbus_input_drain(in, collect, c);
    }
    close(ep);
}

static void poller_delivers_in_order(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start(&s, 8, 6, true);
    const uint16_t fs[6] = {1000, 1000, 1000, 500, 500, 500}; /* 100 N, 5 N m */
    loadid_modbus_ft_server_set_holding(s.srv, fs);
    loadid_config_t cfg = poller_cfg(500.0);
    loadid_modbus_input_t *in = NULL;
    char err[256];
    const int64_t t_start = realtime_us();
    assert_int_equal(loadid_modbus_input_start(&cfg, &in, err, sizeof err), 0);
    assert_true(loadid_modbus_input_fd(in) >= 0);
    static collected_t c;
    c.n = 0;
    run_loop(in, &c, 400);
    loadid_modbus_input_stats_t st;
    /* wait until the thread has stopped polling... by stopping the sensor's
     * counting? No: stop the poller first, then drain what is left. The
     * ring is freed by stop, so drain after a final stats read instead:
     * the thread stops at the next cycle once stop is requested. */
    loadid_modbus_input_stats(in, &st);
    assert_int_equal(st.connected, 1);
    double gf[3], gm[3];
    loadid_modbus_input_full_scale(in, gf, gm);
    assert_true(gf[0] == 100.0 && gm[2] == 5.0);
    /* halt the sensor's answers, let the poller see timeouts only, then
     * drain: every sample the sensor made is in the ring by then */
    loadid_modbus_ft_server_set_mode(s.srv, LOADID_MODBUS_FT_SERVER_SILENT);
    usleep(300000);
    loadid_modbus_input_drain(in, collect, &c);
    loadid_modbus_input_stats(in, &st);
    loadid_modbus_input_stop(in);
    const int64_t t_end = realtime_us();
    sensor_stop(&s);

    const int64_t answered = s.final.replies - s.final.holding_reads;
    print_message(
        "    poller: %d samples in 0.4 s at 500 Hz; sensor answered %lld input reads, "
        "%lld silent; missed cycles %lld\n",
        c.n, (long long)answered, (long long)s.final.silent, (long long)st.cycles_missed);
    assert_true(c.n > 50);
    assert_int_equal(c.n, answered);
    assert_int_equal(st.samples_delivered, c.n);
    assert_int_equal(st.ft.samples_ok, c.n);
    assert_int_equal(st.ft.samples_stale, 0);
    assert_int_equal(st.ft.counter_gaps, 0);
    assert_int_equal(st.ring_overruns, 0);
    assert_true(st.ft.timeouts >= 1);
    assert_int_equal(st.last_error, LOADID_MODBUS_FT_E_TIMEOUT);
    check_invariant(&st.ft);
    for (int i = 0; i < c.n && i < 4096; ++i) {
        const loadid_modbus_ft_sample_t *g = &c.got[i];
        assert_int_equal(g->counter, i + 1); /* in order, none twice, none lost */
        for (int k = 0; k < 3; ++k) {
            assert_true(g->force[k] == expect_si(counts_of((unsigned)i + 1, k), 100.0));
            assert_true(g->torque[k] == expect_si(counts_of((unsigned)i + 1, 3 + k), 5.0));
        }
        assert_true(g->t_us >= t_start && g->t_us <= t_end);
        if (i > 0) assert_true(g->t_us > c.got[i - 1].t_us);
    }
    /* the rate: 500 Hz over about 0.4 s */
    const double span_s = (double)(c.got[c.n - 1].t_us - c.got[0].t_us) * 1e-6;
    const double rate = (c.n - 1) / span_s;
    print_message("    measured rate %.1f Hz\n", rate);
    assert_true(rate > 150 && rate < 520); /* loose below: a loaded machine */
}

static bool wait_for(loadid_modbus_input_t *in, int64_t connected, int ms) {
    const int64_t end = mono_ms() + ms;
    loadid_modbus_input_stats_t st;
    do {
        loadid_modbus_input_stats(in, &st);
        if (st.connected == connected) return true;
        usleep(10000);
    } while (mono_ms() < end);
    return false;
}

static void poller_device_loss(void **state) {
    (void)state;
    static sensor_t s; /* static: a failed assertion leaves its thread running */
    sensor_start_standard(&s, true);
    loadid_config_t cfg = poller_cfg(200.0);
    loadid_modbus_input_t *in = NULL;
    char err[256];
    assert_int_equal(loadid_modbus_input_start(&cfg, &in, err, sizeof err), 0);
    static collected_t c;
    c.n = 0;
    run_loop(in, &c, 150);
    assert_true(c.n > 5);
    assert_false(loadid_modbus_input_take_lost(in));
    sensor_stop(&s); /* the device vanishes */
    assert_true(wait_for(in, 0, 2000));
    assert_true(loadid_modbus_input_take_lost(in));
    assert_false(loadid_modbus_input_take_lost(in)); /* once per loss */
    loadid_modbus_input_stats_t st;
    usleep(1200000); /* retries while it is gone */
    loadid_modbus_input_stats(in, &st);
    print_message("    lost: %s; open attempts %lld, failures %lld\n",
                  loadid_modbus_ft_strerror((int)st.lost_error), (long long)st.open_attempts,
                  (long long)st.ft.open_failures);
    assert_int_equal(st.ft.device_lost, 1);
    /* The first retry after one response timeout (100 ms), then doubling:
     * at 0.1, 0.3 and 0.7 s, the next at 1.5 s (a loaded machine can only
     * make them later). Once a second it had been 1. */
    assert_true(st.ft.open_failures >= 2 && st.ft.open_failures <= 3);
    assert_int_equal(st.last_error, -ENOENT);
    assert_int_equal(st.lost_error, LOADID_MODBUS_FT_E_GONE);
    loadid_modbus_input_drain(in, collect, &c); /* the first sensor's last ones */
    const int before = c.n;
    for (int i = 1; i < before && i < 4096; ++i)
        assert_int_equal(c.got[i].counter, c.got[i - 1].counter + 1);
    sensor_start_standard(&s, true); /* it comes back */
    assert_true(wait_for(in, 1, 3000));
    run_loop(in, &c, 150);
    loadid_modbus_input_stats(in, &st);
    loadid_modbus_input_stop(in);
    sensor_stop(&s);
    print_message("    back: %d samples after the reopen, opens %lld\n", c.n - before,
                  (long long)st.ft.opens);
    assert_true(c.n - before > 5);
    assert_int_equal(st.ft.opens, 2);
    for (int i = before; i < c.n && i < 4096; ++i) /* the new sensor's, from its first */
        assert_int_equal(c.got[i].counter, i - before + 1);
    assert_int_equal(st.ft.counter_gaps, 0);
}

/* The poller thread's id, found by its name ("loadid-modbus", which it
 * gives itself as it starts: waits up to 2 s); 0 when there is none. */
static pid_t poller_tid(int wait_ms) {
    const int64_t end = mono_ms() + wait_ms;
    do {
        DIR *d = opendir("/proc/self/task");
        assert_non_null(d);
        struct dirent *e;
        pid_t found = 0;
        while (!found && (e = readdir(d))) {
            char path[300], comm[32] = "";
            snprintf(path, sizeof path, "/proc/self/task/%s/comm", e->d_name);
            FILE *f = fopen(path, "r");
            if (!f) continue;
            if (fgets(comm, sizeof comm, f) && !strcmp(comm, "loadid-modbus\n"))
                found = (pid_t)atoi(e->d_name);
            fclose(f);
        }
        closedir(d);
        if (found || wait_ms == 0) return found;
        usleep(10000);
    } while (mono_ms() < end);
    return 0;
}

/* realtime.priority and realtime.cpu reach the poller thread: SCHED_FIFO
 * one below the loop's priority (at 1 when that is 1), pinned to the
 * configured CPU, as the kernel reports them for its thread id; neither
 * set, it keeps the normal scheduler and the process's CPUs; a CPU that
 * does not exist is refused with the key in the reason, and no poller
 * thread is left. SCHED_FIFO needs root (or CAP_SYS_NICE): CI's tests run
 * as root. */
static void poller_realtime_attributes(void **state) {
    (void)state;
    if (geteuid() != 0) {
        const char *ci = getenv("CI");
        if (ci && !strcmp(ci, "true")) fail_msg("SCHED_FIFO needs root; CI runs as root");
        print_message("    not root: skipped\n");
        g_skipped = 1;
        skip();
    }
    cpu_set_t mine;
    assert_int_equal(sched_getaffinity(0, sizeof mine, &mine), 0);
    int cpu = -1; /* the last of ours: not what an unpinned thread has, on 2 CPUs or more */
    for (int c = 0; c < CPU_SETSIZE; ++c)
        if (CPU_ISSET(c, &mine)) cpu = c;
    const struct {
        int priority, cpu, policy, poller_priority;
    } cases[] = {{20, cpu, SCHED_FIFO, 19},
                 {1, -1, SCHED_FIFO, 1},
                 {0, cpu, SCHED_OTHER, 0},
                 {0, -1, SCHED_OTHER, 0}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        loadid_config_t cfg = poller_cfg(200.0); /* no sensor: the thread retries opens */
        cfg.rt_priority = cases[k].priority;
        cfg.rt_cpu = cases[k].cpu;
        loadid_modbus_input_t *in = NULL;
        char err[256] = "";
        assert_int_equal(loadid_modbus_input_start(&cfg, &in, err, sizeof err), 0);
        const pid_t tid = poller_tid(2000);
        assert_true(tid > 0);
        struct sched_param sp;
        cpu_set_t set;
        const int policy = sched_getscheduler(tid);
        assert_int_equal(sched_getparam(tid, &sp), 0);
        assert_int_equal(sched_getaffinity(tid, sizeof set, &set), 0);
        loadid_modbus_input_stop(in);
        print_message(
            "    realtime.priority %d, cpu %d: poller policy %d priority %d on %d "
            "CPUs\n",
            cases[k].priority, cases[k].cpu, policy, sp.sched_priority, CPU_COUNT(&set));
        assert_int_equal(policy, cases[k].policy);
        assert_int_equal(sp.sched_priority, cases[k].poller_priority);
        if (cases[k].cpu >= 0) {
            assert_int_equal(CPU_COUNT(&set), 1);
            assert_true(CPU_ISSET(cases[k].cpu, &set));
        } else {
            assert_true(CPU_EQUAL(&set, &mine));
        }
    }
    loadid_config_t cfg = poller_cfg(200.0);
    cfg.rt_cpu = 4095; /* the configuration's largest: no such CPU here */
    loadid_modbus_input_t *in = NULL;
    char err[256] = "";
    assert_int_equal(loadid_modbus_input_start(&cfg, &in, err, sizeof err), -EINVAL);
    assert_null(in);
    assert_string_equal(err, "realtime.cpu 4095: the poller thread: Invalid argument");
    assert_int_equal(poller_tid(0), 0); /* stopped and gone */
}

/* loadid-modbus-sim (tools/modbus_sim), when ctest says where it is: its
 * constant wrench read back through the driver. */
static void simulator_serves_a_constant_wrench(void **state) {
    (void)state;
    const char *exe = getenv("LOADID_MODBUS_SIM");
    if (!exe || !exe[0]) {
        const char *ci = getenv("CI");
        if (ci && !strcmp(ci, "true")) fail_msg("LOADID_MODBUS_SIM not set (ctest sets it)");
        print_message("    LOADID_MODBUS_SIM not set: skipped\n");
        g_skipped = 1;
        skip();
    }
    char link_path[200];
    snprintf(link_path, sizeof link_path, "%s/sim", g_dir);
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        dup2(fds[1], 1);
        close(fds[0]);
        execl(exe, exe, "--wrench", "12.5,-3,9.81,0.25,-0.1,0.05", "--full-scale", "100,5",
              "--link", link_path, "--duration", "20", (char *)NULL);
        _exit(127);
    }
    close(fds[1]);
    FILE *out = fdopen(fds[0], "r");
    char line[256];
    assert_non_null(fgets(line, sizeof line, out));
    print_message("    sim: %s", line);
    assert_true(strncmp(line, "pty /dev/pts/", 13) == 0);
    assert_non_null(fgets(line, sizeof line, out)); /* link ... */
    assert_non_null(fgets(line, sizeof line, out)); /* samples 1 */

    loadid_modbus_ft_config_t c = client_cfg(200);
    snprintf(c.device, sizeof c.device, "%s", link_path);
    loadid_modbus_ft_t *ft = NULL;
    assert_int_equal(loadid_modbus_ft_create(&c, &ft), 0);
    assert_int_equal(loadid_modbus_ft_open(ft), LOADID_MODBUS_FT_FULL_SCALE);
    const double w[6] = {12.5, -3, 9.81, 0.25, -0.1, 0.05};
    for (int r = 0; r < 5; ++r) {
        loadid_modbus_ft_sample_t s;
        assert_int_equal(loadid_modbus_ft_read(ft, &s), LOADID_MODBUS_FT_SAMPLE);
        assert_int_equal(s.counter, r + 1);
        for (int k = 0; k < 3; ++k) {
            const long cf = lround(w[k] * 16384.0 / 100.0), cm = lround(w[3 + k] * 16384.0 / 5.0);
            assert_true(s.force[k] == expect_si((int)cf, 100.0));
            assert_true(s.torque[k] == expect_si((int)cm, 5.0));
            assert_true(fabs(s.force[k] - w[k]) <= 100.0 / 16384 / 2);
        }
    }
    loadid_modbus_ft_destroy(ft);
    kill(pid, SIGTERM);
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    fclose(out);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(decoder_si_values),
        cmocka_unit_test(decoder_status_bits),
        cmocka_unit_test(decoder_stale_and_gaps),
        cmocka_unit_test(decoder_full_scale_registers),
        cmocka_unit_test(encoder_round_trip_and_saturation),
        cmocka_unit_test(decoder_random_blocks),
        cmocka_unit_test_teardown(pty_values_and_full_scale_override, stop_sensors),
        cmocka_unit_test_teardown(pty_status_stale_gaps, stop_sensors),
        cmocka_unit_test_teardown(pty_timeout, stop_sensors),
        cmocka_unit_test_teardown(pty_crc_errors, stop_sensors),
        cmocka_unit_test_teardown(pty_exception, stop_sensors),
        cmocka_unit_test_teardown(pty_device_vanishes_and_returns, stop_sensors),
        cmocka_unit_test_teardown(poller_delivers_in_order, stop_sensors),
        cmocka_unit_test_teardown(poller_device_loss, stop_sensors),
        cmocka_unit_test(poller_realtime_attributes),
        cmocka_unit_test_teardown(simulator_serves_a_constant_wrench, stop_sensors),
    };
    const int failed = cmocka_run_group_tests(tests, setup_dir, teardown_dir);
    return failed ? failed : g_skipped ? LOADID_TEST_SKIPPED : 0;
}
