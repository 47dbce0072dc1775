/*
 * The pipeline's state machine (pipeline.h: IDLE -> ZEROING -> ESTIMATING
 * -> DONE, FAILED with a reason), table-driven: each case is a script of
 * commands, clock ticks, a stop of the inputs and a restored result, fed to
 * a still robot with an F/T sensor at 1 kHz (the Modbus sample path: no
 * accelerometer needed), and the states the sink must have been told, in
 * order, plus the end state, its reason and the run's completeness. The
 * expected sequences are written from the interface (docs/INTERFACE.md,
 * pipeline.h), not from the code's output.
 */
#define _POSIX_C_SOURCE 200809L

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "loadid/config.h"
#include "loadid/pipeline.h"
#include "loadid/regressor.h"
#include "loadid/urdf.h"

enum {
    IDLE = LOADID_STATE_IDLE,
    ZEROING = LOADID_STATE_ZEROING,
    ESTIMATING = LOADID_STATE_ESTIMATING,
    DONE = LOADID_STATE_DONE,
    FAILED = LOADID_STATE_FAILED
};

/* One step of a script, at t_ms after the first sample. */
typedef enum {
    END,     /* end of the script */
    CMD,     /* a command (arg: LOADID_CMD_*) */
    QUIET,   /* the inputs stop from t_ms on (the clock goes on in ticks) */
    RESUME,  /* the inputs come again from t_ms */
    RESTORE, /* loadid_pipeline_restore of a saved estimate */
    FINISH,  /* loadid_pipeline_finish: the input ended (offline) */
} step_kind_t;

typedef struct {
    step_kind_t kind;
    int t_ms;
    int arg;
} step_t;

typedef struct {
    const char *name;
    step_t steps[10];
    int run_to_ms;  /* samples (unless QUIET) and 10 ms ticks until then */
    int states[10]; /* the sink's state changes in order, -1 ends */
    int end_state;
    const char *reason; /* FAILED's reason contains this ("" for none) */
    int complete;       /* -1: not checked */
    int wrenches;       /* at least this many compensated wrenches; 0: none
                               (a still robot excites nothing: no model, so
                               nothing is compensated after its runs) */
} case_t;

/* Windows: zeroing.window_s 0.1, estimation.duration_s 0.3. */
static const case_t kCases[] = {
    {"ZERO: zeroing for its window, then IDLE",
     {{CMD, 10, LOADID_CMD_ZERO}, {END, 0, 0}},
     300,
     {ZEROING, IDLE, -1},
     IDLE,
     "",
     -1,
     0},
    {"ZERO, START: estimating for its window, then DONE, complete",
     {{CMD, 10, LOADID_CMD_ZERO}, {CMD, 200, LOADID_CMD_START}, {END, 0, 0}},
     700,
     {ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     1,
     0},
    {"START during zeroing ends it and starts",
     {{CMD, 10, LOADID_CMD_ZERO}, {CMD, 60, LOADID_CMD_START}, {END, 0, 0}},
     500,
     {ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     1,
     0},
    {"START too early in zeroing: FAILED, too few samples",
     {{CMD, 10, LOADID_CMD_ZERO}, {CMD, 14, LOADID_CMD_START}, {END, 0, 0}},
     300,
     {ZEROING, FAILED, -1},
     FAILED,
     "zeroing:",
     0,
     0},
    {"START without ZERO: FAILED",
     {{CMD, 10, LOADID_CMD_START}, {END, 0, 0}},
     300,
     {FAILED, -1},
     FAILED,
     "START before a completed ZERO",
     0,
     0},
    {"after FAILED, RESET is IDLE and a ZERO starts over",
     {{CMD, 10, LOADID_CMD_START},
      {CMD, 20, LOADID_CMD_RESET},
      {CMD, 30, LOADID_CMD_ZERO},
      {CMD, 200, LOADID_CMD_START},
      {END, 0, 0}},
     600,
     {FAILED, IDLE, ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     1,
     0},
    {"STOP ends the window early: DONE, complete",
     {{CMD, 10, LOADID_CMD_ZERO},
      {CMD, 200, LOADID_CMD_START},
      {CMD, 300, LOADID_CMD_STOP},
      {END, 0, 0}},
     600,
     {ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     1,
     0},
    {"STOP, ZERO and START ignored where they mean nothing",
     {{CMD, 5, LOADID_CMD_STOP},
      {CMD, 10, LOADID_CMD_ZERO},
      {CMD, 200, LOADID_CMD_START},
      {CMD, 250, LOADID_CMD_ZERO},
      {CMD, 260, LOADID_CMD_START},
      {END, 0, 0}},
     700,
     {ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     1,
     0},
    {"RESET while estimating: IDLE, nothing estimated",
     {{CMD, 10, LOADID_CMD_ZERO},
      {CMD, 200, LOADID_CMD_START},
      {CMD, 300, LOADID_CMD_RESET},
      {END, 0, 0}},
     700,
     {ZEROING, IDLE, ESTIMATING, IDLE, -1},
     IDLE,
     "",
     0,
     0},
    {"RESET after DONE, then a second run",
     {{CMD, 10, LOADID_CMD_ZERO},
      {CMD, 200, LOADID_CMD_START},
      {CMD, 600, LOADID_CMD_RESET},
      {CMD, 620, LOADID_CMD_ZERO},
      {CMD, 800, LOADID_CMD_START},
      {END, 0, 0}},
     1300,
     {ZEROING, IDLE, ESTIMATING, DONE, IDLE, ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     1,
     0},
    {"ZERO after DONE zeroes again",
     {{CMD, 10, LOADID_CMD_ZERO},
      {CMD, 200, LOADID_CMD_START},
      {CMD, 600, LOADID_CMD_ZERO},
      {END, 0, 0}},
     900,
     {ZEROING, IDLE, ESTIMATING, DONE, ZEROING, IDLE, -1},
     IDLE,
     "",
     -1,
     0},
    {"inputs stop while estimating: the clock ends the window, incomplete",
     {{CMD, 10, LOADID_CMD_ZERO}, {CMD, 200, LOADID_CMD_START}, {QUIET, 300, 0}, {END, 0, 0}},
     1000,
     {ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     0,
     0},
    {"inputs stop while zeroing: the clock ends it",
     {{CMD, 10, LOADID_CMD_ZERO}, {QUIET, 60, 0}, {END, 0, 0}},
     600,
     {ZEROING, IDLE, -1},
     IDLE,
     "",
     -1,
     0},
    {"inputs stop at once after ZERO: the clock fails it, too few samples",
     {{CMD, 10, LOADID_CMD_ZERO}, {QUIET, 12, 0}, {END, 0, 0}},
     600,
     {ZEROING, FAILED, -1},
     FAILED,
     "zeroing:",
     0,
     0},
    {"the input ends while estimating (offline): DONE, incomplete",
     {{CMD, 10, LOADID_CMD_ZERO}, {CMD, 200, LOADID_CMD_START}, {FINISH, 300, 0}, {END, 0, 0}},
     300,
     {ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     0,
     0},
    /* A restore starts in DONE (pipeline.h): no change for the sink. The
     * samples up to 250 ms (the smoother's 50 ms before the last joint
     * state) less the 15 the joint filters serve none of while they
     * settle (joint_filter.h, at the default jerk_psd). */
    {"a restored result: DONE at once, wrenches compensated",
     {{RESTORE, 0, 0}, {END, 0, 0}},
     300,
     {-1},
     DONE,
     "",
     -1,
     235},
    /* The restored model compensates the samples before ZERO (100 ms) less
     * the 15 of the filters' settling; the new run on a still robot leaves
     * no model. */
    {"a restored result, then a new run",
     {{RESTORE, 0, 0}, {CMD, 100, LOADID_CMD_ZERO}, {CMD, 300, LOADID_CMD_START}, {END, 0, 0}},
     800,
     {ZEROING, IDLE, ESTIMATING, DONE, -1},
     DONE,
     "",
     1,
     85},
};

typedef struct {
    int states[32], n;
    char reason[256];
    long wrenches;
} record_t;

static void on_state(void *ctx, int64_t utime, int state, const char *reason) {
    (void)utime;
    record_t *r = ctx;
    if (r->n < 32) r->states[r->n++] = state;
    snprintf(r->reason, sizeof r->reason, "%s", reason ? reason : "");
}
static void on_wrench(void *ctx, int64_t utime, const double f[3], const double t[3]) {
    (void)utime, (void)f, (void)t;
    ++((record_t *)ctx)->wrenches;
}
static void on_log(void *ctx, const char *msg) {
    (void)ctx, (void)msg;
}

static const int64_t T0 = 1700000000000000LL;
static const double Q[6] = {0.1, -0.4, 1.2, 0.0, 0.6, 0.0};

static void make(loadid_config_t *cfg, loadid_chain_t *chain) {
    loadid_config_default(cfg);
    cfg->sensor_type = LOADID_SENSOR_MODBUS;
    cfg->signals = LOADID_SIGNALS_KF;
    cfg->num_methods = 1;
    cfg->methods[0] = LOADID_METHOD_RLS;
    cfg->zeroing_window_s = 0.1;
    cfg->duration_s = 0.3;
    char err[256];
    assert_int_equal(loadid_urdf_load_file(cfg->robot_urdf, cfg->robot_base_link,
                                           cfg->robot_sensor_link, chain, err, sizeof err),
                     0);
}

/* A saved estimate of a 1 kg load at the origin's COM offset (what
 * results.load restores), with its zeroing. */
static void restore(loadid_pipeline_t *p) {
    loadid_pipeline_estimate_t e;
    memset(&e, 0, sizeof e);
    e.method = LOADID_METHOD_RLS;
    e.state = LOADID_STATE_DONE;
    e.valid = 1;
    e.samples = 1500;
    const double phi[10] = {1.0, 0, 0, 0.02, 2e-3, 0, 0, 2e-3, 0, 1e-3};
    memcpy(e.phi, phi, sizeof phi);
    loadid_pipeline_compensation_t c;
    memset(&c, 0, sizeof c);
    c.n_params = 10;
    memcpy(c.phi_total, phi, sizeof phi);
    c.zeroed = 1;
    c.g_init[2] = -9.81;
    /* zeroed at rest: eq. (6) there is A(-g_init, 0, 0) */
    const loadid_real_t spec[3] = {0, 0, 9.81}, zero[3] = {0, 0, 0};
    loadid_real_t a[60];
    assert_int_equal(loadid_regressor(spec, zero, zero, a), 0);
    for (int i = 0; i < 60; ++i) c.zero_a[i] = (double)a[i];
    assert_int_equal(loadid_pipeline_restore(p, &e, &c), 0);
}

static void run_case(const case_t *tc) {
    loadid_config_t cfg;
    loadid_chain_t chain;
    make(&cfg, &chain);
    record_t rec;
    memset(&rec, 0, sizeof rec);
    const loadid_pipeline_sink_t sink = {&rec, NULL, on_wrench, on_state, on_log};
    loadid_pipeline_t *p = NULL;
    char err[256];
    assert_int_equal(loadid_pipeline_create(&cfg, &chain, &sink, 0, &p, err, sizeof err), 0);
    int quiet = 0, finished = 0, s = 0;
    for (int ms = 0; ms <= tc->run_to_ms && !finished; ++ms) {
        const int64_t now = T0 + (int64_t)ms * 1000;
        for (; tc->steps[s].kind != END && tc->steps[s].t_ms == ms; ++s) {
            switch (tc->steps[s].kind) {
                case CMD:
                    loadid_pipeline_command(p, now, tc->steps[s].arg, "box");
                    break;
                case QUIET:
                    quiet = 1;
                    break;
                case RESUME:
                    quiet = 0;
                    break;
                case RESTORE:
                    restore(p);
                    break;
                case FINISH:
                    loadid_pipeline_finish(p, now), finished = 1;
                    break;
                case END:
                    break;
            }
        }
        if (finished) break;
        if (!quiet) {
            /* the F/T sample 0.5 ms before the joint state of the same ms */
            const loadid_sensor_sample_t x = {
                .t_us = now - 500, .force = {0.2, -0.1, 9.81}, .torque = {0.01, 0.02, -0.01}};
            loadid_pipeline_sample(p, &x);
            loadid_pipeline_joint_state(p, now, 6, Q, Q);
        }
        if (ms % 10 == 0) loadid_pipeline_tick(p, now);
    }
    loadid_pipeline_status_t st;
    loadid_pipeline_status(p, &st);
    int want_n = 0;
    while (want_n < 10 && tc->states[want_n] >= 0) ++want_n;
    char got[160] = "", want[160] = "";
    for (int i = 0; i < rec.n; ++i)
        snprintf(got + strlen(got), sizeof got - strlen(got), " %d", rec.states[i]);
    for (int i = 0; i < want_n; ++i)
        snprintf(want + strlen(want), sizeof want - strlen(want), " %d", tc->states[i]);
    print_message("    %-68s states%s (reason \"%s\", complete %d, %ld wrenches)\n", tc->name, got,
                  st.state == FAILED ? rec.reason : "", st.complete, rec.wrenches);
    if (strcmp(got, want) != 0) fail_msg("%s: states%s, expected%s", tc->name, got, want);
    assert_int_equal(st.state, tc->end_state);
    if (tc->reason[0] && !strstr(rec.reason, tc->reason))
        fail_msg("%s: reason \"%s\" lacks \"%s\"", tc->name, rec.reason, tc->reason);
    if (tc->complete >= 0) assert_int_equal(st.complete, tc->complete);
    if (tc->wrenches)
        assert_true(rec.wrenches >= tc->wrenches);
    else
        assert_int_equal(rec.wrenches, 0);
    loadid_pipeline_destroy(p);
}

static void every_case(void **state) {
    (void)state;
    for (size_t i = 0; i < sizeof kCases / sizeof kCases[0]; ++i) run_case(&kCases[i]);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(every_case)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
