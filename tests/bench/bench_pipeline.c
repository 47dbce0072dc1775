/*
 * bench_pipeline: throughput of the service's whole per-sample path over a
 * recording, as loadidd --offline runs it (JR3 decoding, joint filters,
 * kinematics, signal source, regressor, every configured estimator), and
 * the process's peak resident memory. A benchmark: prints its figures and
 * exits 0; non-zero only when it cannot set up.
 *
 *   bench_pipeline CONFIG RECORDING_DIR [REPETITIONS]
 *
 * Two figures, measured side by side in each repetition (alternating, so a
 * noisy machine weighs on both alike), each on a fresh pipeline (creating
 * it is not timed):
 *   pipeline   the recording's events already in memory (CAN frames,
 *              decoded joint states and commands): JR3 decoding, joint
 *              filters, kinematics, signal source, regressor and every
 *              configured estimator: the "whole pipeline";
 *   --offline  loadid_offline_run, as loadidd --offline: reading and
 *              parsing can.log and lcm.log included;
 *   window     the "1.5 s estimation": with the configured
 *              estimation.duration_s, only the events from START until the
 *              pipeline reaches DONE are timed (the same in-memory events;
 *              what comes before and after is fed untimed);
 *   REFINED    the window again with REFINED added to the methods (or
 *              taken out, when configured): the median over the
 *              repetitions of the paired difference is what REFINED costs
 *              at DONE (target: at most 20 ms for 1500 samples).
 * estimation.duration_s is raised so that every sample after START is
 * estimated, and each run's time is charged to those samples only:
 * estimated samples / run time, a lower bound (the zeroing and rest before
 * START cost time too). Reported: the medians over the repetitions, the
 * time a 1.5 s estimation at 1 kHz takes at the pipeline's rate, and the
 * peak resident memory. Targets: at least 200 000 estimated samples per
 * second in memory and 150 000 with --offline's parsing here (1.5 s of
 * data in 7.5 ms), under 20 MB. This machine's speed swings from run to
 * run: tools/bench_compare.sh runs this benchmark and an earlier
 * commit's alternately in one run, for before/after ratios.
 */
#define _POSIX_C_SOURCE 200809L

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "loadid/config.h"
#include "loadid/lcm_wire.h"
#include "loadid/offline.h"
#include "loadid/pipeline.h"
#include "loadid/recording.h"
#include "loadid/urdf.h"

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One recording event, decoded ahead of time. */
typedef struct {
    int kind; /* LOADID_REC_CAN, _BAD_LINE, or 0: joints, -1: command */
    int64_t t_us;
    loadid_can_frame_t can;
    int num_joints, action;
    double position[LOADID_MAX_JOINTS], setpoint[LOADID_MAX_JOINTS];
    char load_name[LOADID_LOAD_NAME_MAX];
} event_t;

/* The recording's events in memory, as offline.c would feed them. */
static event_t *load_events(const char *dir, int *count, int64_t *last) {
    loadid_recording_reader_t *rec = NULL;
    char err[1024];
    if (loadid_recording_reader_open(dir, &rec, err, sizeof err) != 0) {
        fprintf(stderr, "bench_pipeline: %s\n", err);
        return NULL;
    }
    int n = 0, cap = 1 << 14;
    event_t *evs = malloc((size_t)cap * sizeof *evs);
    loadid_rec_event_t ev;
    *last = INT64_MIN;
    while (evs && loadid_recording_reader_next(rec, &ev) == 1) {
        if (n == cap) {
            cap *= 2;
            event_t *grown = realloc(evs, (size_t)cap * sizeof *evs);
            if (!grown) free(evs);
            evs = grown;
            if (!evs) break;
        }
        event_t *e = &evs[n];
        memset(e, 0, sizeof *e);
        e->t_us = ev.t_us;
        if (ev.kind != LOADID_REC_BAD_LINE && ev.t_us > *last) *last = ev.t_us;
        if (ev.kind != LOADID_REC_LCM) {
            e->kind = (int)ev.kind;
            e->can = ev.can;
            ++n;
            continue;
        }
        if (strcmp(ev.channel, "LOADID_JOINTS") == 0) {
            loadid_lcm_joint_state_t m;
            if (loadid_lcm_decode_joint_state(ev.data, (size_t)ev.datalen, &m) < 0) continue;
            e->kind = 0;
            e->t_us = m.utime;
            e->num_joints = m.num_joints < LOADID_MAX_JOINTS ? m.num_joints : LOADID_MAX_JOINTS;
            memcpy(e->position, m.position, (size_t)e->num_joints * sizeof(double));
            memcpy(e->setpoint, m.setpoint, (size_t)e->num_joints * sizeof(double));
            ++n;
        } else if (strcmp(ev.channel, "LOADID_COMMAND") == 0) {
            loadid_lcm_command_t m;
            if (loadid_lcm_decode_command(ev.data, (size_t)ev.datalen, &m) < 0) continue;
            e->kind = -1;
            e->action = m.action;
            snprintf(e->load_name, sizeof e->load_name, "%s", m.load_name);
            ++n;
        }
    }
    loadid_recording_reader_close(rec);
    *count = n;
    return evs;
}

static void feed_one(loadid_pipeline_t *p, const event_t *e) {
    switch (e->kind) {
        case LOADID_REC_CAN:
            loadid_pipeline_can_frame(p, &e->can);
            break;
        case LOADID_REC_BAD_LINE:
            loadid_pipeline_bad_frame(p);
            break;
        case 0:
            loadid_pipeline_joint_state(p, e->t_us, e->num_joints, e->position, e->setpoint);
            break;
        default:
            loadid_pipeline_command(p, e->t_us, e->action, e->load_name);
            break;
    }
}

static void feed_events(loadid_pipeline_t *p, const event_t *evs, int n, int64_t last) {
    for (int i = 0; i < n; ++i) feed_one(p, &evs[i]);
    loadid_pipeline_finish(p, last);
}

static void note_state(void *ctx, int64_t utime, int state, const char *reason) {
    (void)utime, (void)reason;
    *(int *)ctx = state;
}

/* The estimation window alone: the time from feeding START until the
 * pipeline is DONE (or the events end); *seconds and *used. */
static int window_run(const loadid_config_t *cfg, const loadid_chain_t *chain, const event_t *evs,
                      int n, int64_t last, double *seconds, int64_t *used) {
    loadid_pipeline_t *p = NULL;
    char err[1024];
    int state = LOADID_STATE_IDLE;
    const loadid_pipeline_sink_t sink = {.ctx = &state, .state = note_state};
    if (loadid_pipeline_create(cfg, chain, &sink, 0, &p, err, sizeof err) != 0) {
        fprintf(stderr, "bench_pipeline: %s\n", err);
        return 1;
    }
    int i = 0;
    while (i < n && !(evs[i].kind == -1 && evs[i].action == LOADID_CMD_START))
        feed_one(p, &evs[i++]);
    const double t0 = now_s();
    for (; i < n; ++i) { /* START acts once the joints cover it (the fixed lag) */
        feed_one(p, &evs[i]);
        if (state == LOADID_STATE_DONE || state == LOADID_STATE_FAILED) break;
    }
    *seconds = now_s() - t0;
    loadid_pipeline_status_t st;
    for (++i; i < n; ++i) feed_one(p, &evs[i]);
    loadid_pipeline_finish(p, last);
    loadid_pipeline_status(p, &st);
    *used = st.samples_used;
    loadid_pipeline_destroy(p);
    return 0;
}

/* One timed run on a fresh pipeline: estimated samples per second. */
static int timed_run(const loadid_config_t *cfg, const loadid_chain_t *chain, const char *dir,
                     const event_t *evs, int n, int64_t last, double *rate,
                     loadid_pipeline_status_t *st) {
    loadid_pipeline_t *p = NULL;
    char err[1024];
    if (loadid_pipeline_create(cfg, chain, NULL, 0, &p, err, sizeof err) != 0) {
        fprintf(stderr, "bench_pipeline: %s\n", err);
        return 1;
    }
    const double t0 = now_s();
    if (evs) {
        feed_events(p, evs, n, last);
    } else if (loadid_offline_run(p, dir, NULL, err, sizeof err) != 0) {
        fprintf(stderr, "bench_pipeline: %s\n", err);
        loadid_pipeline_destroy(p);
        return 1;
    }
    const double dt = now_s() - t0;
    loadid_pipeline_status(p, st);
    *rate = (double)st->samples_used / dt;
    loadid_pipeline_destroy(p);
    return 0;
}

int main(int argc, char **argv) {
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printf(
            "usage: bench_pipeline CONFIG RECORDING_DIR [REPETITIONS]\n"
            "Times the service's per-sample path over a recording (REPETITIONS runs,\n"
            "default 20): in memory, as loadidd --offline, the window from START to DONE\n"
            "and REFINED's cost at DONE; prints the medians and the peak memory.\n");
        return 0;
    }
    if (argc < 3) {
        fprintf(stderr, "usage: bench_pipeline CONFIG RECORDING_DIR [REPETITIONS]\n");
        return 2;
    }
    const int reps = argc > 3 && atoi(argv[3]) > 0 ? atoi(argv[3]) : 20;
    static loadid_config_t cfg;
    loadid_chain_t chain;
    char err[1024];
    loadid_config_default(&cfg);
    if (loadid_config_load(argv[1], &cfg, err, sizeof err, NULL, NULL) != 0 ||
        loadid_urdf_load_file(cfg.robot_urdf, cfg.robot_base_link, cfg.robot_sensor_link, &chain,
                              err, sizeof err) != 0) {
        fprintf(stderr, "bench_pipeline: %s\n", err);
        return 1;
    }
    static loadid_config_t window_cfg, other_cfg;
    window_cfg = cfg; /* the configured estimation.duration_s */
    /* other_cfg: the window with REFINED added, or without it when configured. */
    other_cfg = cfg;
    int has_refined = 0;
    for (int m = 0; m < cfg.num_methods; ++m)
        has_refined |= cfg.methods[m] == LOADID_METHOD_REFINED;
    if (has_refined) {
        other_cfg.num_methods = 0;
        for (int m = 0; m < cfg.num_methods; ++m)
            if (cfg.methods[m] != LOADID_METHOD_REFINED)
                other_cfg.methods[other_cfg.num_methods++] = cfg.methods[m];
    } else if (cfg.num_methods < LOADID_MAX_METHODS) {
        other_cfg.methods[other_cfg.num_methods++] = LOADID_METHOD_REFINED;
    }
    int n = 0;
    int64_t last = 0;
    event_t *evs = load_events(argv[2], &n, &last);
    /* Everything after START is estimated: the recording's span and a
     * second (a batch method, REFINED among them, holds that much). */
    if (evs && n > 0) cfg.duration_s = (double)(last - evs[0].t_us) * 1e-6 + 1.0;
    double *mem = calloc((size_t)reps, sizeof *mem), *file = calloc((size_t)reps, sizeof *file);
    double *win = calloc((size_t)reps, sizeof *win),
           *refined = calloc((size_t)reps, sizeof *refined);
    if (!evs || !mem || !file || !win || !refined) return 1;
    int64_t win_used = 0, other_used = 0;
    loadid_pipeline_status_t st_mem, st_file;
    for (int r = 0; r < reps; ++r) {
        if (timed_run(&cfg, &chain, argv[2], evs, n, last, &mem[r], &st_mem) ||
            timed_run(&cfg, &chain, argv[2], NULL, 0, 0, &file[r], &st_file) ||
            window_run(&window_cfg, &chain, evs, n, last, &win[r], &win_used) ||
            window_run(&other_cfg, &chain, evs, n, last, &refined[r], &other_used))
            return 1;
        refined[r] = has_refined ? win[r] - refined[r] : refined[r] - win[r];
    }
    if (st_mem.samples_used != st_file.samples_used) {
        fprintf(stderr, "bench_pipeline: the two paths estimated %lld and %lld samples\n",
                (long long)st_mem.samples_used, (long long)st_file.samples_used);
        return 1;
    }
    qsort(mem, (size_t)reps, sizeof *mem, cmp);
    qsort(file, (size_t)reps, sizeof *file, cmp);
    qsort(win, (size_t)reps, sizeof *win, cmp);
    qsort(refined, (size_t)reps, sizeof *refined, cmp);
    const double med = mem[reps / 2], fmed = file[reps / 2];
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("bench_pipeline: %s, %d methods, signals %d, %d repetitions\n", argv[2], cfg.num_methods,
           cfg.signals, reps);
    printf("  samples per run           %lld (%lld estimated)\n", (long long)st_mem.samples_ok,
           (long long)st_mem.samples_used);
    printf("  pipeline median           %.0f estimated samples/s (min %.0f, max %.0f)\n", med,
           mem[0], mem[reps - 1]);
    printf(
        "  --offline median          %.0f estimated samples/s (files parsed too; %.2fx the "
        "pipeline's time; target >= 150000: %s)\n",
        fmed, med / fmed, fmed >= 150000 ? "met" : "NOT met");
    printf(
        "  1.5 s estimation at 1 kHz %.2f ms in the pipeline (target < 7.5 ms, >= 200000 "
        "samples/s: %s)\n",
        1500 / med * 1e3, med >= 200000 ? "met" : "NOT met");
    printf(
        "  estimation window median  %.2f ms for %lld samples (%.1f s configured; "
        "%.0f samples/s)\n",
        win[reps / 2] * 1e3, (long long)win_used, window_cfg.duration_s,
        (double)win_used / win[reps / 2]);
    printf(
        "  REFINED at DONE           %.2f ms for %lld samples (median of the paired window "
        "differences; p10 %.2f, p90 %.2f; target <= 20 ms: %s)\n",
        refined[reps / 2] * 1e3, (long long)win_used, refined[reps / 10] * 1e3,
        refined[reps - 1 - reps / 10] * 1e3, refined[reps / 2] <= 0.020 ? "met" : "NOT met");
    printf("  peak resident memory      %.1f MB (target < 20 MB)\n", ru.ru_maxrss / 1024.0);
    free(mem);
    free(file);
    free(win);
    free(refined);
    free(evs);
    return 0;
}
