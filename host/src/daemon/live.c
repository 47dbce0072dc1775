/*
 * The live service of loadidd (live.h): the event loop, and only that.
 * epoll over
 *   - LCM (lcm_link.c, the transport; lcm_inputs.c: joint_state_t and
 *     command_t into the pipeline);
 *   - the sensor input (inputs/input.h: one backend of SocketCAN, a
 *     candump log, the Modbus poller or a replayed recording);
 *   - a 10 ms timerfd that ends zeroing and estimation windows on time and
 *     publishes status_t once a second (status.c);
 *   - a signalfd for SIGTERM and SIGINT (a clean stop, after a REFINED
 *     run still going: finish_refined);
 *   - REFINED's worker thread (the pipeline's worker.h), when configured:
 *     its end.
 * The pipeline's outputs go out on LCM as they come (lcm_out.c): estimate_t
 * on LOADID_ESTIMATE, wrench_t on LOADID_WRENCH, and at DONE load_model_t
 * on LOADID_MODEL with the estimate handed to the save worker (results.c,
 * save_worker.h), which writes it on a thread of its own; with
 * results.trace every estimate also goes to the trace writer
 * (trace_worker.h), a thread of its own too. status_t also goes
 * out at every state change, once the event that made it is handled, with
 * the change's time as its utime: a command's change carries the command's
 * own utime, which is how the CLI knows the acknowledgement of its
 * command, even of a state as short as ZEROING. The loop's time per input
 * event goes into status_t's p50, p99 and max over the last second.
 *
 * After start-up (the first epoll_wait) the loop allocates nothing
 * (tests/python/test_live_no_alloc.py proves it under an
 * allocation-counting LD_PRELOAD): messages are encoded and decoded by
 * drivers/lcm_wire.h on static buffers, LCM on udpm:// goes through the
 * daemon's own sockets, and a finished estimate is saved by a thread of
 * its own (save_worker.h): after start-up the loop makes no file-system
 * call but --can-file's and --replay's reads
 * (tests/python/test_systemd_unit.py traces it).
 */
#define _GNU_SOURCE
#include "live.h"

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "clock.h"
#include "inputs/input.h"
#include "lcm_inputs.h"
#include "lcm_link.h"
#include "lcm_out.h"
#include "loadid/pipeline.h"
#include "log.h"
#include "realtime.h"
#include "results.h"
#include "status.h"

/* At most this many queued LCM messages are read at once (a second of
 * joint states at 1 kHz): a flood cannot hold the rest up for ever. */
#define LCM_DRAIN_MAX 1000

/* The loop's LCM buffer: one message out at a time. */
_Static_assert(LOADID_LCM_OUT_MAX >= LOADID_LCM_STATUS_SIZE, "status_t fits the buffer");
static uint8_t tx_buf[LOADID_LCM_OUT_MAX];

/* The channels, with lcm.channel_prefix, made once at start-up. */
enum { CH_JOINTS, CH_COMMAND, CH_ESTIMATE, CH_WRENCH, CH_STATUS, CH_MODEL, CH_COUNT };
static char channels[CH_COUNT][128];

typedef struct {
    const loadid_config_t *cfg;
    const loadid_live_options_t *opt;
    loadid_pipeline_t *pipe;
    loadid_lcm_link_t lcm;
    loadid_lcm_inputs_t lcm_in;
    loadid_input_t input;
    int input_fd;   /* the input's descriptor in the epoll set, or -1 */
    int refined_fd; /* REFINED's worker's end (worker.h), or -1 */
    loadid_loop_times_t times;
    int ticks;
    int done_pending;              /* DONE reached: save the estimate */
    loadid_save_worker_t *saver;   /* results.directory set, else NULL */
    loadid_trace_worker_t *tracer; /* results.trace set, else NULL */
    struct {
        int64_t utime;
        int8_t state;
    } changes[8]; /* states entered since the last event, each
                                     published as a status_t of its own */
    int num_changes;
} live_t;

/* ------------------------------------------------------------ outputs */

static void publish(live_t *L, int ch, int n) {
    loadid_lcm_link_publish(&L->lcm, channels[ch], tx_buf, n);
}

static void on_estimate(void *ctx, const loadid_pipeline_estimate_t *e) {
    live_t *L = ctx;
    publish(L, CH_ESTIMATE, loadid_lcm_out_estimate(e, tx_buf, sizeof tx_buf));
    loadid_results_trace_row(L->tracer, e);
}

static void on_wrench(void *ctx, int64_t utime, const double f[3], const double t[3]) {
    publish(ctx, CH_WRENCH, loadid_lcm_out_wrench(utime, f, t, tx_buf, sizeof tx_buf));
}

static void on_state(void *ctx, int64_t utime, int state, const char *reason) {
    live_t *L = ctx;
    if (state == LOADID_STATE_DONE) L->done_pending = 1;
    loadid_results_trace_state(L->tracer, utime, state);
    /* Published after the event (the pipeline is mid-call here); more
     * changes than room within one event keep the first ones and the last. */
    const int k = L->num_changes < 8 ? L->num_changes++ : 7;
    L->changes[k].utime = utime;
    L->changes[k].state = (int8_t)state;
    if (L->opt->verbose || state == LOADID_STATE_FAILED)
        loadidd_log("%lld: %s%s%s", (long long)utime, loadid_lcm_state_name(state),
                    *reason ? ": " : "", reason);
}

static void on_log(void *ctx, const char *msg) {
    (void)ctx;
    loadidd_log("%s", msg);
}

/* periodic: the 1 Hz status (the loop times' second ends), utime now;
 * else one at a state change, with the state entered, the change's utime
 * (a command's own, where the command acted at another) and the loop
 * times of the second so far. */
static void publish_status(live_t *L, int periodic, int state, int64_t utime) {
    loadid_pipeline_status_t st;
    loadid_pipeline_status(L->pipe, &st);
    loadid_input_counters_t in;
    loadid_input_counters(&L->input, &in);
    loadid_lcm_status_t m;
    loadid_status_make(
        &st, &in, &L->times, periodic,
        periodic ? loadid_wall_us() : loadid_lcm_inputs_answer_utime(&L->lcm_in, utime),
        periodic ? st.state : state, &m);
    publish(L, CH_STATUS, loadid_lcm_encode_status(&m, tx_buf, sizeof tx_buf));
}

/* DONE: the best load model out on LOADID_MODEL, and the estimate handed
 * to the save worker (when results.directory is configured). */
static void save_done(live_t *L) {
    L->done_pending = 0;
    loadid_pipeline_estimate_t e;
    loadid_pipeline_compensation_t c;
    const int final = loadid_pipeline_final(L->pipe, &e, &c) == 0;
    /* Every row is in: the on-line finals at DONE, REFINED's collected. */
    loadid_results_trace_end(L->tracer, final ? &e : NULL);
    if (!final) return;
    if (e.has_model) publish(L, CH_MODEL, loadid_lcm_out_load_model(&e, tx_buf, sizeof tx_buf));
    loadid_results_save(L->cfg, L->saver, &e, &c);
}

/* At the stop, a REFINED run still on its worker (SIGTERM soon after DONE:
 * the estimate the model and the saved result wait for, often the best)
 * is waited for, then published and saved as the loop would have done.
 *
 * At most 2 s. The run is a batch over the window: about 14 ms on the
 * robot's PC, some hundred ms under ASan on a loaded machine; one not
 * ended after 2 s (over a hundred times its usual time) is starved or
 * stuck, and the stop must not wait on it: systemd's watchdog is off
 * while a unit stops, so nothing but TimeoutStopSec (90 s by default,
 * then SIGKILL) would end the wait, and a restart waits for the stop.
 * 2 s is also what the unit's WatchdogSec allows a running daemon to be
 * silent. Returns 0, or 1 when the run is still going: its memory (the
 * pipeline's, which it alone uses: copies of the configuration and the
 * chain) is then left to the exit, not freed under it. poll, and what the
 * loop does at REFINED's end: nothing allocated. */
enum { REFINED_STOP_WAIT_MS = 2000 };

static int finish_refined(live_t *L) {
    if (L->refined_fd < 0 || !loadid_pipeline_refined_pending(L->pipe)) return 0;
    loadidd_log("stopping: waiting for REFINED's run (at most %d ms)", REFINED_STOP_WAIT_MS);
    const double end = loadid_mono_us() + REFINED_STOP_WAIT_MS * 1e3;
    struct pollfd pfd = {.fd = L->refined_fd, .events = POLLIN};
    double left_us;
    while (!loadid_pipeline_refined_collect(L->pipe) && (left_us = end - loadid_mono_us()) > 0) {
        if (poll(&pfd, 1, (int)(left_us / 1e3) + 1) < 0 && errno != EINTR) break;
    }
    if (loadid_pipeline_refined_pending(L->pipe)) {
        loadidd_log("REFINED's run has not ended after %d ms: stopping without its estimate",
                    REFINED_STOP_WAIT_MS);
        return 1;
    }
    if (L->done_pending) save_done(L);
    return 0;
}

/* ---------------------------------------------------------------- loop */

enum { TAG_LCM = 1, TAG_INPUT, TAG_TICK, TAG_SIGNAL, TAG_REFINED };

static int add_fd(int ep, int fd, uint32_t tag) {
    struct epoll_event ev = {.events = EPOLLIN, .data.u32 = tag};
    return epoll_ctl(ep, EPOLL_CTL_ADD, fd, &ev);
}

/* The input's descriptor in the epoll set: a SocketCAN input closes its
 * socket when the interface goes away (epoll forgets it) and opens another
 * when it is back. Called after every call into the input. */
/* Everything queued on LCM (at most LCM_DRAIN_MAX): each message handled
 * one entry of the loop times, the round's time shared out. */
static void read_lcm_queue(live_t *L) {
    const double t0 = loadid_mono_us();
    const int handled = loadid_lcm_link_drain(&L->lcm, LCM_DRAIN_MAX);
    if (handled <= 0) return;
    const double each = (loadid_mono_us() - t0) / handled;
    for (int k = 0; k < handled; ++k) loadid_loop_times_add(&L->times, each);
}

static void sync_input_fd(live_t *L, int ep) {
    const int fd = loadid_input_fd(&L->input);
    if (fd == L->input_fd) return;
    if (fd >= 0) add_fd(ep, fd, TAG_INPUT);
    L->input_fd = fd;
}

/* The sensor input the options and the configuration name. Returns 0, or
 * 1 after logging why not. */
static int open_input(live_t *L) {
    const loadid_live_options_t *opt = L->opt;
    const int modbus = L->cfg->sensor_type == LOADID_SENSOR_MODBUS;
    loadid_input_options_t io = {0};
    const loadid_input_backend_t *b = &loadid_input_jr3_socketcan;
    if (opt->replay) {
        b = &loadid_input_replay;
        io.path = opt->replay;
        io.with_commands = opt->replay_commands;
    } else if (opt->can_file) {
        b = &loadid_input_jr3_candump;
        io.path = opt->can_file;
        io.epoch_us = opt->can_file_epoch;
    } else if (modbus) {
        b = &loadid_input_modbus_rtu;
    }
    if (modbus && b != &loadid_input_modbus_rtu) {
        loadidd_log("%s replays JR3 frames; sensor.type is modbus",
                    opt->replay ? "--replay" : "--can-file");
        return 1;
    }
    char err[4600];
    if (loadid_input_open(&L->input, b, L->cfg, L->pipe, &io, err, sizeof err) != 0) {
        loadidd_log("%s", err);
        return 1;
    }
    return 0;
}

int loadid_live_run(const loadid_config_t *cfg, const loadid_chain_t *chain,
                    const loadid_live_options_t *opt) {
    static live_t L; /* large (the histogram); one per process */
    memset(&L, 0, sizeof L);
    static const char *const names[CH_COUNT] = {"LOADID_JOINTS",   "LOADID_COMMAND",
                                                "LOADID_ESTIMATE", "LOADID_WRENCH",
                                                "LOADID_STATUS",   "LOADID_MODEL"};
    for (int i = 0; i < CH_COUNT; ++i)
        loadid_config_channel(cfg, names[i], channels[i], sizeof channels[i]);
    L.cfg = cfg;
    L.opt = opt;
    L.input_fd = -1;
    L.refined_fd = -1;
    char err[4600];
    loadid_pipeline_sink_t sink = {
        .ctx = &L, .estimate = on_estimate, .wrench = on_wrench, .state = on_state, .log = on_log};
    if (loadid_pipeline_create(cfg, chain, &sink, opt->publish_every, &L.pipe, err, sizeof err) !=
        0) {
        loadidd_log("%s", err);
        return 1;
    }
    /* During a replay the joint states are the recording's (inputs/replay.c). */
    loadid_lcm_inputs_init(&L.lcm_in, cfg, L.pipe, channels[CH_JOINTS], channels[CH_COMMAND],
                           !opt->replay);
    const char *const inputs[] = {channels[CH_JOINTS], channels[CH_COMMAND]};
    if (loadid_lcm_link_open(&L.lcm, cfg, inputs, 2, loadid_lcm_inputs_message, &L.lcm_in, err,
                             sizeof err) != 0) {
        loadidd_log("%s", err);
        loadid_pipeline_destroy(L.pipe);
        return 1;
    }
    if (cfg->results_load[0]) {
        loadid_pipeline_estimate_t e;
        if (loadid_results_restore(cfg, L.pipe, &e, err, sizeof err) != 0) {
            loadidd_log("results.load: %s", err);
            loadid_lcm_link_close(&L.lcm);
            loadid_pipeline_destroy(L.pipe);
            return 1;
        }
        loadidd_log("loaded %s (%s): wrench_t flows", cfg->results_load, e.load_name);
        if (e.has_model)
            publish(&L, CH_MODEL, loadid_lcm_out_load_model(&e, tx_buf, sizeof tx_buf));
    }

    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGTERM);
    sigaddset(&mask, SIGINT);
    sigprocmask(SIG_BLOCK, &mask, NULL);
    const int sig_fd = signalfd(-1, &mask, SFD_CLOEXEC);
    const int tick_fd = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
    const int ep = epoll_create1(EPOLL_CLOEXEC);
    struct itimerspec tick = {{0, 10000000}, {0, 10000000}};
    int rc = 0;
    if (sig_fd < 0 || tick_fd < 0 || ep < 0 || timerfd_settime(tick_fd, 0, &tick, NULL) != 0 ||
        add_fd(ep, sig_fd, TAG_SIGNAL) || add_fd(ep, tick_fd, TAG_TICK) ||
        add_fd(ep, loadid_lcm_link_fd(&L.lcm), TAG_LCM)) {
        loadidd_log("cannot set up the event loop: %s", strerror(errno));
        rc = 1;
    }
    /* REFINED on its worker thread, created with the signals blocked (so
     * that they reach the signalfd only) and before the real-time set-up. */
    if (rc == 0) {
        const int refined_fd = loadid_pipeline_refined_async(L.pipe);
        if (refined_fd != -ENOENT && (refined_fd < 0 || add_fd(ep, refined_fd, TAG_REFINED) != 0)) {
            loadidd_log("cannot start REFINED's worker: %s",
                        strerror(refined_fd < 0 ? -refined_fd : errno));
            rc = 1;
        }
        if (refined_fd >= 0) L.refined_fd = refined_fd;
    }
    /* The save worker likewise (save_worker.h: the disk's waits off the
     * loop), before the Modbus poller (the input) and the real-time set-up. */
    if (rc == 0) rc = loadid_results_start(cfg, &L.saver);
    if (rc == 0) rc = loadid_results_trace_start(cfg, L.pipe, &L.tracer);
    if (rc == 0) rc = open_input(&L);
    if (rc == 0) sync_input_fd(&L, ep);
    if (rc == 0 && loadid_realtime_setup(cfg, err, sizeof err) != 0) {
        loadidd_log("%s", err);
        rc = 1;
    }
    if (rc == 0) loadid_notify_ready("estimating loads; LCM and the sensor input open");
    while (rc == 0) {
        struct epoll_event evs[8];
        int n = epoll_wait(ep, evs, 8, 1000);
        if (n < 0 && errno != EINTR) {
            loadidd_log("epoll: %s", strerror(errno));
            rc = 1;
            break;
        }
        int stop = 0;
        /* LCM first, everything queued: after a loop that did not run for
         * a while (the kernel's, or a long handler) the joint states that
         * came meanwhile must go in before the samples and the clock, as
         * either ends a joint piece whose next states seem not to come (a
         * sample by its own time, pipeline.h). */
        for (int i = 0; i < n; ++i)
            if (evs[i].data.u32 == TAG_LCM) read_lcm_queue(&L);
        for (int i = 0; i < n; ++i) {
            uint64_t v;
            const double t_event = loadid_mono_us();
            int timed = evs[i].data.u32 != TAG_SIGNAL && evs[i].data.u32 != TAG_LCM;
            switch (evs[i].data.u32) {
                case TAG_LCM:
                    break; /* read above */
                case TAG_INPUT:
                    loadid_input_read(&L.input);
                    sync_input_fd(&L, ep);
                    break;
                case TAG_TICK: {
                    if (read(tick_fd, &v, sizeof v) < 0) break;
                    /* The clock's time is the one the input catches up to,
                     * not the time after it: feeding a stalled replay's
                     * 100 ms took ASan's build over 50 ms, and the later
                     * time made the joint states just fed look stalled.
                     * LCM is not read here (it was, above): joint states
                     * read ahead of the samples change what the smoother
                     * serves them (test_live_lcm's frozen daemon). */
                    const int64_t now_us = loadid_wall_us();
                    loadid_input_catch_up(&L.input);
                    loadid_pipeline_tick(L.pipe, now_us);
                    loadid_notify_watchdog((int64_t)loadid_mono_us());
                    if (++L.ticks % 100 == 0) {
                        publish_status(&L, 1, 0, 0);
                        loadid_input_second(&L.input); /* reopen, log what grew */
                        sync_input_fd(&L, ep);
                    }
                    break;
                }
                case TAG_SIGNAL:
                    stop = 1;
                    break;
                case TAG_REFINED:
                    loadid_pipeline_refined_collect(L.pipe);
                    break;
            }
            if (timed) loadid_loop_times_add(&L.times, loadid_mono_us() - t_event);
        }
        for (int k = 0; k < L.num_changes; ++k)
            publish_status(&L, 0, L.changes[k].state, L.changes[k].utime);
        L.num_changes = 0;
        /* The model and the saved result wait for REFINED, which may be the best. */
        if (L.done_pending && !loadid_pipeline_refined_pending(L.pipe)) save_done(&L);
        loadid_results_log(L.saver);
        loadid_results_trace_log(L.tracer);
        if (stop) break;
    }
    loadid_notify_stopping();
    const int refined_running = finish_refined(&L);
    loadid_input_finish(&L.input);
    if (opt->verbose) {
        loadid_pipeline_status_t st;
        loadid_pipeline_status(L.pipe, &st);
        loadid_input_counters_t in;
        loadid_input_counters(&L.input, &in);
        loadid_status_summary(&st, &in, L.lcm_in.commands_refused);
        loadid_input_summary(&L.input);
    }
    publish_status(&L, 1, 0, 0);
    loadid_results_stop(L.saver);        /* the saves submitted end, and are logged */
    loadid_results_trace_stop(L.tracer); /* likewise the trace */
    loadid_input_close(&L.input);
    if (ep >= 0) close(ep);
    if (tick_fd >= 0) close(tick_fd);
    if (sig_fd >= 0) close(sig_fd);
    loadid_lcm_link_close(&L.lcm);
    if (!refined_running) loadid_pipeline_destroy(L.pipe); /* else its job still uses it */
    return rc;
}
