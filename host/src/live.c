/*
 * The live service of loadidd (live.h): epoll over
 *   - the LCM socket: joint_state_t on LOADID_JOINTS, command_t on
 *     LOADID_COMMAND (commands act when received);
 *   - the CAN input: a SocketCAN raw socket (frames carry the kernel's
 *     receive time), or a candump log replayed in real time with its times
 *     rewritten to now;
 *   - a 10 ms timerfd that ends zeroing and estimation windows on time and
 *     publishes status_t once a second;
 *   - a signalfd for SIGTERM and SIGINT (a clean stop).
 * Estimates go out as estimate_t on LOADID_ESTIMATE, compensated wrenches
 * as wrench_t on LOADID_WRENCH. The loop time, the handling of each input
 * event (a CAN read, an LCM message, a tick), is kept in a histogram:
 * status_t's p50, p99 and max over the last second.
 */
#define _GNU_SOURCE
#include "live.h"

#include <errno.h>
#include <lcm/lcm.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "lcmtypes/loadid_command_t.h"
#include "lcmtypes/loadid_estimate_t.h"
#include "lcmtypes/loadid_joint_state_t.h"
#include "lcmtypes/loadid_status_t.h"
#include "lcmtypes/loadid_wrench_t.h"
#include "loadid/candump.h"
#include "loadid/pipeline.h"
#include "loadid/socketcan.h"
#include "realtime.h"
#include "saved_result.h"

#define HIST_BINS 20001 /* 0.5 us bins up to 10 ms; the last holds the rest */

typedef struct {
    const loadid_config_t *cfg;
    const loadid_live_options_t *opt;
    loadid_pipeline_t *pipe;
    lcm_t *lcm;
    int can_fd;                   /* SocketCAN, or -1 */
    FILE *can_file;
    loadid_candump_reader_t *can_reader;
    int have_next;                /* file: the next frame is read ahead */
    loadid_can_frame_t next;
    int64_t file_t0, wall_t0;     /* file: first frame's time, its wall time */
    double mono_t0;
    int file_done;                /* the file is replayed; the CAN input is quiet */
    int64_t can_errors, can_reopens, error_frames;
    uint32_t hist[HIST_BINS];
    double loop_max_us;
    int ticks;
    int done_pending;             /* DONE reached: save the estimate */
} live_t;

static int64_t wall_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static double mono_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e6 + ts.tv_nsec * 1e-3;
}

/* ------------------------------------------------------------ outputs */

static void on_estimate(void *ctx, const loadid_pipeline_estimate_t *e) {
    live_t *L = ctx;
    loadid_estimate_t m;
    memset(&m, 0, sizeof m);
    m.utime = e->utime;
    m.samples = e->samples;
    m.method = (int8_t)e->method;
    m.state = (int8_t)e->state;
    m.load_name = (char *)e->load_name;
    memcpy(m.phi, e->phi, sizeof m.phi);
    memcpy(m.offset, e->offset, sizeof m.offset);
    m.mass = e->mass;
    memcpy(m.com, e->com, sizeof m.com);
    memcpy(m.inertia_com, e->inertia_com, sizeof m.inertia_com);
    m.condition_number = e->condition_number;
    m.sigma_min = e->sigma_min;
    m.physically_consistent = (int8_t)e->physically_consistent;
    loadid_estimate_t_publish(L->lcm, "LOADID_ESTIMATE", &m);
}

static void on_wrench(void *ctx, int64_t utime, const double f[3], const double t[3]) {
    live_t *L = ctx;
    loadid_wrench_t m;
    m.utime = utime;
    memcpy(m.force, f, sizeof m.force);
    memcpy(m.torque, t, sizeof m.torque);
    loadid_wrench_t_publish(L->lcm, "LOADID_WRENCH", &m);
}

static void on_state(void *ctx, int64_t utime, int state, const char *reason) {
    live_t *L = ctx;
    static const char *names[] = {"IDLE", "ZEROING", "ESTIMATING", "DONE", "FAILED"};
    if (state == LOADID_STATE_DONE) L->done_pending = 1;
    if (L->opt->verbose || state == LOADID_STATE_FAILED)
        fprintf(stderr, "loadidd: %lld: %s%s%s\n", (long long)utime, names[state],
                *reason ? ": " : "", reason);
}

static void on_log(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "loadidd: %s\n", msg);
}

/* p50, p99, max of the loop times since the last status; then cleared. */
static void loop_stats(live_t *L, double *p50, double *p99, double *max) {
    uint64_t n = 0;
    for (int i = 0; i < HIST_BINS; ++i) n += L->hist[i];
    *p50 = *p99 = 0;
    *max = L->loop_max_us;
    if (n) {
        uint64_t acc = 0, k50 = (n + 1) / 2, k99 = (n * 99 + 99) / 100;
        int got50 = 0;
        for (int i = 0; i < HIST_BINS; ++i) {
            acc += L->hist[i];
            if (!got50 && acc >= k50) *p50 = (i + 0.5) * 0.5, got50 = 1;
            if (acc >= k99) {
                *p99 = (i + 0.5) * 0.5;
                break;
            }
        }
    }
    memset(L->hist, 0, sizeof L->hist);
    L->loop_max_us = 0;
}

static void publish_status(live_t *L) {
    loadid_pipeline_status_t st;
    loadid_pipeline_status(L->pipe, &st);
    loadid_status_t m;
    memset(&m, 0, sizeof m);
    m.utime = wall_us();
    m.state = (int8_t)st.state;
    m.samples_ok = st.samples_ok;
    m.frames_bad = st.frames_bad + L->error_frames;
    m.samples_incomplete = st.samples_incomplete;
    /* status_t has no field for faults: saturated or faulty, both never
     * reach an estimator (DESIGN.md). */
    m.samples_saturated = st.samples_saturated + st.samples_faulty;
    m.sequence_gaps = st.sequence_gaps;
    m.joint_msgs_bad = st.joint_msgs_bad;
    loop_stats(L, &m.loop_us_p50, &m.loop_us_p99, &m.loop_us_max);
    loadid_status_t_publish(L->lcm, "LOADID_STATUS", &m);
}

/* ------------------------------------------------------------- inputs */

static void on_joints(const lcm_recv_buf_t *rbuf, const char *channel,
                      const loadid_joint_state_t *msg, void *ctx) {
    (void)rbuf, (void)channel;
    live_t *L = ctx;
    loadid_pipeline_joint_state(L->pipe, msg->utime, msg->num_joints, msg->position,
                                msg->setpoint);
}

static void on_command(const lcm_recv_buf_t *rbuf, const char *channel,
                       const loadid_command_t *msg, void *ctx) {
    (void)rbuf, (void)channel;
    live_t *L = ctx;
    /* A command acts at its own utime, as in a recording, unless that is
     * more than a second away from now (a sender's clock off): then now. */
    const int64_t now = wall_us();
    const int64_t t = msg->utime > now - 1000000 && msg->utime < now + 1000000 ? msg->utime : now;
    loadid_pipeline_command(L->pipe, t, msg->action, msg->load_name);
}

/* The loop time: handling one input event (a CAN read, an LCM message,
 * which is where waiting samples are estimated, or a tick). */
static void record_loop_time(live_t *L, double dt) {
    int bin = (int)(dt * 2);
    L->hist[bin < HIST_BINS ? bin : HIST_BINS - 1]++;
    if (dt > L->loop_max_us) L->loop_max_us = dt;
}

static void read_socket(live_t *L) {
    loadid_can_frame_t f;
    int rc;
    while ((rc = loadid_socketcan_read(L->can_fd, &f)) > 0) {
        if (rc == 2) L->error_frames++;
        else loadid_pipeline_can_frame(L->pipe, &f);
    }
    if (rc < 0) {
        fprintf(stderr, "loadidd: CAN %s: %s; reopening\n", L->cfg->can_interface, strerror(-rc));
        L->can_errors++;
        close(L->can_fd);
        L->can_fd = -1;
    }
}

/* File source: feeds every frame due by now, then arms the timer for the
 * next one. */
static void read_file(live_t *L, int timer_fd) {
    const double now = mono_us();
    while (L->have_next) {
        const double due = L->mono_t0 + (double)(L->next.t_us - L->file_t0);
        if (due > now) break;
        loadid_can_frame_t f = L->next;
        f.t_us = L->wall_t0 + (L->next.t_us - L->file_t0);
        loadid_pipeline_can_frame(L->pipe, &f);
        int rc;
        while ((rc = loadid_candump_read(L->can_reader, &L->next, NULL)) < 0 && rc != -EIO)
            loadid_pipeline_bad_frame(L->pipe);
        L->have_next = rc == 1;
    }
    if (!L->have_next) {
        L->file_done = 1;
        return;
    }
    const double due = L->mono_t0 + (double)(L->next.t_us - L->file_t0);
    struct itimerspec its = {{0, 0}, {(time_t)(due / 1e6), (long)(due - (double)(time_t)(due / 1e6) * 1e6) * 1000}};
    timerfd_settime(timer_fd, TFD_TIMER_ABSTIME, &its, NULL);
}

static int add_fd(int ep, int fd, uint32_t tag) {
    struct epoll_event ev = {.events = EPOLLIN, .data.u32 = tag};
    return epoll_ctl(ep, EPOLL_CTL_ADD, fd, &ev);
}

/* A finished estimate into results.directory (when configured). */
static void save_done(live_t *L) {
    L->done_pending = 0;
    loadid_pipeline_estimate_t e;
    loadid_pipeline_compensation_t c;
    if (!L->cfg->results_directory[0] || loadid_pipeline_final(L->pipe, &e, &c) != 0) return;
    char path[4400], err[4600];
    if (loadid_saved_result_write(L->cfg->results_directory, &e, &c, path, sizeof path, err,
                                  sizeof err) != 0)
        fprintf(stderr, "loadidd: %s\n", err);
    else
        fprintf(stderr, "loadidd: saved %s\n", path);
}

enum { TAG_LCM = 1, TAG_CAN, TAG_FILE, TAG_TICK, TAG_SIGNAL };

int loadid_live_run(const loadid_config_t *cfg, const loadid_chain_t *chain,
                    const loadid_live_options_t *opt) {
    static live_t L; /* large (the histogram); one per process */
    memset(&L, 0, sizeof L);
    L.cfg = cfg;
    L.opt = opt;
    L.can_fd = -1;
    char err[512];
    loadid_pipeline_sink_t sink = {.ctx = &L, .estimate = on_estimate, .wrench = on_wrench,
                                   .state = on_state, .log = on_log};
    if (loadid_pipeline_create(cfg, chain, &sink, opt->publish_every, &L.pipe, err, sizeof err) != 0) {
        fprintf(stderr, "loadidd: %s\n", err);
        return 1;
    }
    L.lcm = lcm_create(cfg->lcm_url);
    if (!L.lcm) {
        fprintf(stderr, "loadidd: cannot open LCM at %s\n", cfg->lcm_url);
        loadid_pipeline_destroy(L.pipe);
        return 1;
    }
    if (cfg->results_load[0]) {
        loadid_pipeline_estimate_t e;
        loadid_pipeline_compensation_t c;
        char lerr[4600];
        int lr = loadid_saved_result_read(cfg->results_load, &e, &c, lerr, sizeof lerr);
        if (lr == 0 && loadid_pipeline_restore(L.pipe, &e, &c) != 0) {
            snprintf(lerr, sizeof lerr, "%s: not an estimate of this configuration (method, "
                                        "estimation.offset_model)", cfg->results_load);
            lr = -EINVAL;
        }
        if (lr != 0) {
            fprintf(stderr, "loadidd: results.load: %s\n", lerr);
            lcm_destroy(L.lcm);
            loadid_pipeline_destroy(L.pipe);
            return 1;
        }
        fprintf(stderr, "loadidd: loaded %s (%s): wrench_t flows\n", cfg->results_load, e.load_name);
    }
    loadid_joint_state_t_subscribe(L.lcm, "LOADID_JOINTS", on_joints, &L);
    loadid_command_t_subscribe(L.lcm, "LOADID_COMMAND", on_command, &L);

    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGTERM);
    sigaddset(&mask, SIGINT);
    sigprocmask(SIG_BLOCK, &mask, NULL);
    const int sig_fd = signalfd(-1, &mask, SFD_CLOEXEC);
    const int tick_fd = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
    const int file_fd = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
    const int ep = epoll_create1(EPOLL_CLOEXEC);
    struct itimerspec tick = {{0, 10000000}, {0, 10000000}};
    int rc = 0;
    if (sig_fd < 0 || tick_fd < 0 || file_fd < 0 || ep < 0 ||
        timerfd_settime(tick_fd, 0, &tick, NULL) != 0 || add_fd(ep, sig_fd, TAG_SIGNAL) ||
        add_fd(ep, tick_fd, TAG_TICK) || add_fd(ep, lcm_get_fileno(L.lcm), TAG_LCM)) {
        fprintf(stderr, "loadidd: cannot set up the event loop: %s\n", strerror(errno));
        rc = 1;
    }
    if (rc == 0 && opt->can_file) {
        L.can_file = fopen(opt->can_file, "r");
        if (!L.can_file || loadid_candump_reader_open(L.can_file, &L.can_reader) != 0) {
            fprintf(stderr, "loadidd: %s: cannot read: %s\n", opt->can_file, strerror(errno));
            rc = 1;
        } else {
            int r;
            while ((r = loadid_candump_read(L.can_reader, &L.next, NULL)) < 0 && r != -EIO)
                loadid_pipeline_bad_frame(L.pipe);
            L.have_next = r == 1;
            L.file_t0 = L.next.t_us;
            /* The file's first frame is replayed at can_file_epoch (wall
             * time, so that a test can time its joint states to it). */
            const int64_t wall_now = wall_us();
            L.wall_t0 = opt->can_file_epoch > 0 ? opt->can_file_epoch : wall_now;
            L.mono_t0 = mono_us() + (double)(L.wall_t0 - wall_now);
            add_fd(ep, file_fd, TAG_FILE);
            read_file(&L, file_fd);
        }
    } else if (rc == 0) {
        L.can_fd = loadid_socketcan_open(cfg->can_interface, cfg->can_base_id, err, sizeof err);
        if (L.can_fd < 0) {
            fprintf(stderr, "loadidd: %s\n", err);
            rc = 1;
        } else {
            add_fd(ep, L.can_fd, TAG_CAN);
        }
    }
    if (rc == 0 && loadid_realtime_setup(cfg, err, sizeof err) != 0) {
        fprintf(stderr, "loadidd: %s\n", err);
        rc = 1;
    }
    if (rc == 0) loadid_notify_ready("estimating loads; LCM and CAN open");
    while (rc == 0) {
        struct epoll_event evs[8];
        int n = epoll_wait(ep, evs, 8, 1000);
        if (n < 0 && errno != EINTR) {
            fprintf(stderr, "loadidd: epoll: %s\n", strerror(errno));
            rc = 1;
            break;
        }
        int stop = 0;
        for (int i = 0; i < n; ++i) {
            uint64_t v;
            const double t_event = mono_us();
            switch (evs[i].data.u32) {
                case TAG_LCM: lcm_handle(L.lcm); break;
                case TAG_CAN: read_socket(&L); break;
                case TAG_FILE:
                    if (read(file_fd, &v, sizeof v) < 0) break;
                    read_file(&L, file_fd);
                    break;
                case TAG_TICK:
                    if (read(tick_fd, &v, sizeof v) < 0) break;
                    loadid_pipeline_tick(L.pipe, wall_us());
                    loadid_notify_watchdog((int64_t)mono_us());
                    if (++L.ticks % 100 == 0) {
                        publish_status(&L);
                        if (L.can_fd < 0 && !opt->can_file) { /* reopen a vanished interface */
                            L.can_fd = loadid_socketcan_open(cfg->can_interface, cfg->can_base_id,
                                                             err, sizeof err);
                            if (L.can_fd >= 0) add_fd(ep, L.can_fd, TAG_CAN), L.can_reopens++;
                        }
                    }
                    break;
                case TAG_SIGNAL: stop = 1; break;
            }
            if (evs[i].data.u32 != TAG_SIGNAL) record_loop_time(&L, mono_us() - t_event);
        }
        if (L.done_pending) save_done(&L);
        if (stop) break;
    }
    loadid_notify_stopping();
    if (opt->verbose) {
        loadid_pipeline_status_t st;
        loadid_pipeline_status(L.pipe, &st);
        fprintf(stderr,
                "loadidd: samples ok %lld, used %lld, frames bad %lld, incomplete %lld, "
                "saturated %lld, faulty %lld, gaps %lld, joint msgs bad %lld, stale %lld, "
                "CAN errors %lld, error frames %lld\n",
                (long long)st.samples_ok, (long long)st.samples_used, (long long)st.frames_bad,
                (long long)st.samples_incomplete, (long long)st.samples_saturated,
                (long long)st.samples_faulty, (long long)st.sequence_gaps,
                (long long)st.joint_msgs_bad, (long long)st.samples_stale,
                (long long)L.can_errors, (long long)L.error_frames);
    }
    publish_status(&L);
    if (L.can_fd >= 0) close(L.can_fd);
    loadid_candump_reader_close(L.can_reader);
    if (L.can_file) fclose(L.can_file);
    close(ep), close(file_fd), close(tick_fd), close(sig_fd);
    lcm_destroy(L.lcm);
    loadid_pipeline_destroy(L.pipe);
    return rc;
}
