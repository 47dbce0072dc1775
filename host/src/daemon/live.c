/*
 * The live service of loadidd (live.h): epoll over
 *   - the LCM socket: joint_state_t on LOADID_JOINTS, command_t on
 *     LOADID_COMMAND (commands act when received; with
 *     lcm.command_sources, only those from the senders listed);
 *   - the CAN input: a SocketCAN raw socket (frames carry the kernel's
 *     receive time), or a candump log replayed in real time with its times
 *     rewritten to now;
 *   - or, with sensor.type modbus, the eventfd of the Modbus F/T poller
 *     thread (modbus_input.h: the serial line's blocking transactions stay
 *     off this loop; samples arrive through a lock-free ring);
 *   - a 10 ms timerfd that ends zeroing and estimation windows on time and
 *     publishes status_t once a second;
 *   (status_t also goes out at every state change, once the event that made
 *   it is handled, with the change's time as its utime: a command's change
 *   carries the command's own utime, which is how the CLI knows the
 *   acknowledgement of its command, even of a state as short as ZEROING);
 *   - a signalfd for SIGTERM and SIGINT (a clean stop).
 * Estimates go out as estimate_t on LOADID_ESTIMATE, compensated wrenches
 * as wrench_t on LOADID_WRENCH. The loop time, the handling of each input
 * event (a CAN read, an LCM message, a tick), is kept in a histogram:
 * status_t's p50, p99 and max over the last second.
 *
 * REFINED, when configured, runs on the pipeline's worker thread
 * (worker.h); its end comes in as one more fd of the epoll set.
 *
 * After start-up (the first epoll_wait) the loop allocates nothing
 * (tests/python/test_live_no_alloc.py proves it under an
 * allocation-counting LD_PRELOAD): messages are encoded and decoded by
 * drivers/lcm_wire.h on static buffers, and on udpm:// (the provider in
 * use) sent and received by drivers/lcm_udpm.h on the daemon's own two
 * sockets: liblcm 1.3.1's receive thread allocates on the first message of
 * every channel name it sees (the daemon's own output channels among them,
 * mid-session) and its lcm_publish on its first message (a lazily made
 * mutex), so liblcm is not used for udpm at all. Other providers
 * (memq://, file://) fall back to liblcm: lcm_subscribe with raw handlers,
 * lcm_handle and lcm_publish, not proven allocation-free. A finished
 * estimate is saved without stdio (saved_result.c).
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

#include "loadid/candump.h"
#include "loadid/chain.h"
#include "loadid/lcm_udpm.h"
#include "loadid/lcm_wire.h"
#include "loadid/pipeline.h"
#include "loadid/setup.h"
#include "loadid/socketcan.h"
#include "modbus_input.h"
#include "realtime.h"
#include "saved_result.h"

#define HIST_BINS 20001 /* 0.5 us bins up to 10 ms; the last holds the rest */
#define LATE_US 1000.0  /* a sample handled later than this after arrival missed its deadline */

_Static_assert(LOADID_LCM_MAX_JOINTS == LOADID_MAX_JOINTS, "joint_state_t holds every joint");
_Static_assert(LOADID_LCM_NAME_MAX == LOADID_LOAD_NAME_MAX, "load_name fits both ways");

/* The loop's LCM buffers: one message out at a time, one datagram in
 * (65536 holds any UDP datagram). */
#define TX_MAX (LOADID_LCM_ESTIMATE_MAX > LOADID_LCM_LOAD_MODEL_MAX ? LOADID_LCM_ESTIMATE_MAX \
                                                                   : LOADID_LCM_LOAD_MODEL_MAX)
static uint8_t tx_buf[TX_MAX];

/* The channels, with lcm.channel_prefix, made once at start-up. */
enum { CH_JOINTS, CH_COMMAND, CH_ESTIMATE, CH_WRENCH, CH_STATUS, CH_MODEL, CH_COUNT };
static char channels[CH_COUNT][128];
static uint8_t rx_buf[65536];

typedef struct {
    const loadid_config_t *cfg;
    const loadid_live_options_t *opt;
    loadid_pipeline_t *pipe;
    int udpm;                     /* udpm://: the daemon's own sockets; else liblcm */
    loadid_lcm_udpm_tx_t lcm_tx;  /* udpm://: sending */
    int lcm_rx_fd;                /* udpm://: receiving, or -1 */
    lcm_t *lcm;                   /* other providers, else NULL */
    double command_warned_us;     /* throttles the log line of a malformed command */
    int64_t commands_refused;     /* command_t from senders not in lcm.command_sources */
    double refused_warned_us;     /* throttles their log line */
    int can_fd;                   /* SocketCAN, or -1 */
    FILE *can_file;
    loadid_candump_reader_t *can_reader;
    int have_next;                /* file: the next frame is read ahead */
    loadid_can_frame_t next;
    int64_t file_t0, wall_t0;     /* file: first frame's time, its wall time */
    double mono_t0;
    int file_done;                /* the file is replayed; the CAN input is quiet */
    int64_t can_errors, can_reopens, error_frames;
    double can_lost_us;           /* when the CAN socket failed (mono) */
    int64_t can_frames;           /* frames read from the CAN socket */
    uint32_t can_drops_seen;      /* the socket's cumulative drop count (SO_RXQ_OVFL) */
    int64_t can_drops;            /* frames the kernel dropped, over every socket */
    int64_t can_drops_logged, can_drops_frames; /* logged so far; frames read when last grown */
    double can_drops_warned_us;   /* throttles their log line */
    int64_t samples_late;         /* handled more than LATE_US after arrival */
    double late_max_us;           /* the worst lateness of any sample */
    int64_t late_logged;          /* samples_late at the last log line */
    double late_warned_us;        /* throttles that line */
    loadid_modbus_input_t *ft;    /* sensor.type modbus, else NULL */
    int64_t ft_connected;         /* the poller's last reported state */
    uint32_t hist[HIST_BINS];
    double loop_max_us;
    int ticks;
    int done_pending;             /* DONE reached: save the estimate */
    struct {
        int64_t utime;
        int8_t state;
    } changes[8];                 /* states entered since the last event, each
                                     published as a status_t of its own */
    int num_changes;
    struct {
        int64_t acted, sent;
    } moved[8];                   /* commands whose utime was too far from now:
                                     the time they acted at, and their own */
    int moved_next;
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

/* n: what an encoder returned (it cannot fail on these buffers and
 * fields; a failure would be a bug, logged). */
static void publish(live_t *L, const char *channel, int n) {
    if (n <= 0)
        fprintf(stderr, "loadidd: %s: cannot encode: %s\n", channel, loadid_lcm_strerror(n));
    else if (L->udpm) loadid_lcm_udpm_send(&L->lcm_tx, channel, tx_buf, (size_t)n);
    else lcm_publish(L->lcm, channel, tx_buf, (unsigned)n);
}

static void on_estimate(void *ctx, const loadid_pipeline_estimate_t *e) {
    live_t *L = ctx;
    loadid_lcm_estimate_t m;
    memset(&m, 0, sizeof m);
    m.utime = e->utime;
    m.samples = e->samples;
    m.method = (int8_t)e->method;
    m.state = (int8_t)e->state;
    memcpy(m.load_name, e->load_name, sizeof m.load_name);
    m.load_name[sizeof m.load_name - 1] = 0;
    memcpy(m.phi, e->phi, sizeof m.phi);
    memcpy(m.offset, e->offset, sizeof m.offset);
    m.mass = e->mass;
    memcpy(m.com, e->com, sizeof m.com);
    memcpy(m.inertia_com, e->inertia_com, sizeof m.inertia_com);
    m.condition_number = e->condition_number;
    m.sigma_min = e->sigma_min;
    m.physically_consistent = (int8_t)e->physically_consistent;
    publish(L, channels[CH_ESTIMATE], loadid_lcm_encode_estimate(&m, tx_buf, sizeof tx_buf));
}

static void on_wrench(void *ctx, int64_t utime, const double f[3], const double t[3]) {
    live_t *L = ctx;
    loadid_lcm_wrench_t m;
    m.utime = utime;
    memcpy(m.force, f, sizeof m.force);
    memcpy(m.torque, t, sizeof m.torque);
    publish(L, channels[CH_WRENCH], loadid_lcm_encode_wrench(&m, tx_buf, sizeof tx_buf));
}

static void on_state(void *ctx, int64_t utime, int state, const char *reason) {
    live_t *L = ctx;
    static const char *names[] = {"IDLE", "ZEROING", "ESTIMATING", "DONE", "FAILED"};
    if (state == LOADID_STATE_DONE) L->done_pending = 1;
    /* Published after the event (the pipeline is mid-call here); more
     * changes than room within one event keep the first ones and the last. */
    const int k = L->num_changes < 8 ? L->num_changes++ : 7;
    L->changes[k].utime = utime;
    L->changes[k].state = (int8_t)state;
    if (L->opt->verbose || state == LOADID_STATE_FAILED)
        fprintf(stderr, "loadidd: %lld: %s%s%s\n", (long long)utime, names[state],
                *reason ? ": " : "", reason);
}

static void on_log(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "loadidd: %s\n", msg);
}

/* p50, p99, max of the loop times since the last periodic status; then
 * cleared when periodic. */
static void loop_stats(live_t *L, int periodic, double *p50, double *p99, double *max) {
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
    if (!periodic) return;
    memset(L->hist, 0, sizeof L->hist);
    L->loop_max_us = 0;
}

/* periodic: the 1 Hz status (the loop times' second ends), utime now;
 * else one at a state change, with the state entered, the change's utime
 * (a command's own, where the command acted at another: on_command) and
 * the loop times of the second so far. */
static void publish_status(live_t *L, int periodic, int state, int64_t utime) {
    loadid_pipeline_status_t st;
    loadid_pipeline_status(L->pipe, &st);
    loadid_lcm_status_t m;
    memset(&m, 0, sizeof m);
    m.utime = periodic ? wall_us() : utime;
    if (!periodic)
        for (int i = 0; i < 8; ++i)
            if (L->moved[i].acted == utime && utime != 0) m.utime = L->moved[i].sent;
    m.state = (int8_t)(periodic ? st.state : state);
    m.samples_ok = st.samples_ok;
    m.frames_bad = st.frames_bad + L->error_frames;
    m.samples_incomplete = st.samples_incomplete;
    /* status_t has no field for faults: a sample saturated or faulty (or
     * both, counted once) never reaches an estimator (docs/INTERFACE.md). */
    m.samples_saturated = st.samples_rejected;
    m.sequence_gaps = st.sequence_gaps;
    if (L->ft) {
        /* The serial sensor's faults in status_t's terms: a bad frame (CRC,
         * wrong slave, malformed status) or an exception is a bad frame, a
         * transaction without answer an incomplete sample. Measurements
         * the sensor's counter says were skipped are not sequence gaps:
         * polling slower than the sensor measures skips them by design
         * (--verbose and the poller's counters have them). */
        loadid_modbus_input_stats_t ms;
        loadid_modbus_input_stats(L->ft, &ms);
        m.frames_bad += ms.ft.bad_frames + ms.ft.exceptions + ms.ft.samples_malformed;
        m.samples_incomplete += ms.ft.timeouts;
    }
    m.joint_msgs_bad = st.joint_msgs_bad;
    loop_stats(L, periodic, &m.loop_us_p50, &m.loop_us_p99, &m.loop_us_max);
    publish(L, channels[CH_STATUS], loadid_lcm_encode_status(&m, tx_buf, sizeof tx_buf));
}

/* ------------------------------------------------------------- inputs */

/* A malformed joint state is counted with the refused ones
 * (status_t.joint_msgs_bad); NaN and infinities go on, for the pipeline
 * counts them. */
static void on_joints(live_t *L, const uint8_t *data, size_t len) {
    static loadid_lcm_joint_state_t m; /* two arrays of 16 doubles: off the stack */
    if (loadid_lcm_decode_joint_state(data, len, &m) < 0)
        loadid_pipeline_joint_state(L->pipe, wall_us(), 0, NULL, NULL);
    else
        loadid_pipeline_joint_state(L->pipe, m.utime, m.num_joints, m.position, m.setpoint);
}

static void on_command(live_t *L, const uint8_t *data, size_t len) {
    loadid_lcm_command_t m;
    const int rc = loadid_lcm_decode_command(data, len, &m);
    if (rc < 0) {
        const double now_mono = mono_us();
        if (now_mono - L->command_warned_us > 1e6) { /* at most one line a second */
            fprintf(stderr, "loadidd: %s: %s; ignored\n", channels[CH_COMMAND], loadid_lcm_strerror(rc));
            L->command_warned_us = now_mono;
        }
        return;
    }
    /* A command acts at its own utime, as in a recording, unless that is
     * more than a second away from now (a sender's clock off): then now. */
    const int64_t now = wall_us();
    const int64_t t = m.utime > now - 1000000 && m.utime < now + 1000000 ? m.utime : now;
    if (t != m.utime) { /* its state change still answers with its own utime */
        L->moved[L->moved_next].acted = t;
        L->moved[L->moved_next].sent = m.utime;
        L->moved_next = (L->moved_next + 1) % 8;
    }
    loadid_pipeline_command(L->pipe, t, m.action, m.load_name);
}

/* lcm.command_sources: whether a command from source (IPv4, host order)
 * may act. One that may not is refused before it is decoded, counted, and
 * logged with its sender and the count so far (the first at once, then at
 * most a line a second). status_t has no field for it (its fields are
 * fixed; frames_bad and joint_msgs_bad count other inputs' faults). */
static int command_allowed(live_t *L, uint32_t source) {
    if (loadid_ipv4_allow_match(L->cfg->lcm_command_sources, L->cfg->lcm_num_command_sources,
                                source))
        return 1;
    const double now = mono_us();
    if (L->commands_refused++ == 0 || now - L->refused_warned_us > 1e6) {
        fprintf(stderr, "loadidd: %s from %u.%u.%u.%u refused: not in lcm.command_sources "
                        "(%lld refused so far)\n", channels[CH_COMMAND], source >> 24,
                (source >> 16) & 255, (source >> 8) & 255, source & 255,
                (long long)L->commands_refused);
        L->refused_warned_us = now;
    }
    return 0;
}

/* One LCM message from source (the sender's IPv4 address, host order; 0
 * on liblcm's providers, which do not say, and which refuse
 * lcm.command_sources at start-up); other channels (the daemon's own
 * output, looped back by multicast, and anyone else's) are ignored.
 * Returns 1 when it was an input. */
static int on_message(live_t *L, const char *name, const uint8_t *data, size_t len,
                      uint32_t source) {
    if (strcmp(name, channels[CH_JOINTS]) == 0) on_joints(L, data, len);
    else if (strcmp(name, channels[CH_COMMAND]) == 0) {
        if (command_allowed(L, source)) on_command(L, data, len);
    } else return 0;
    return 1;
}

/* udpm://: one datagram per event (as lcm_handle dispatched one message);
 * epoll is level-triggered, so the next comes with the next wait. Returns
 * 1 for an input: what else arrives (above all the daemon's own output,
 * which liblcm's receive thread dropped before the loop saw it) is not a
 * loop event in status_t's loop times. */
static int read_lcm(live_t *L) {
    uint32_t source = 0;
    const int n = loadid_lcm_udpm_read_from(L->lcm_rx_fd, rx_buf, sizeof rx_buf, &source);
    const char *channel;
    const uint8_t *data;
    size_t len;
    return n > 0 && loadid_lcm_udpm_parse(rx_buf, (size_t)n, &channel, &data, &len) == 0 &&
           on_message(L, channel, data, len, source);
}

/* Other providers: liblcm's raw subscription. */
static void on_lcm_raw(const lcm_recv_buf_t *rbuf, const char *channel, void *ctx) {
    (void)on_message(ctx, channel, rbuf->data, rbuf->data_size, 0);
}

/* The loop time: handling one input event (a CAN read, an LCM message,
 * which is where waiting samples are estimated, or a tick). */
static void record_loop_time(live_t *L, double dt) {
    int bin = (int)(dt * 2);
    L->hist[bin < HIST_BINS ? bin : HIST_BINS - 1]++;
    if (dt > L->loop_max_us) L->loop_max_us = dt;
}

/* Frames the kernel dropped for a full receive buffer (the loop held up):
 * logged when the count grew, the first time at once, then at most a line
 * a second (the 1 Hz tick logs what waited). status_t has no field for
 * them; what they cost shows there as incomplete samples and sequence gaps. */
static void log_can_drops(live_t *L) {
    const double now = mono_us();
    if (L->can_drops == L->can_drops_logged ||
        (L->can_drops_logged > 0 && now - L->can_drops_warned_us < 1e6))
        return;
    fprintf(stderr, "loadidd: CAN %s: %lld frames dropped by the kernel, the socket's receive "
                    "buffer full (%lld in all, learnt after %lld frames read)\n",
            L->cfg->can_interface, (long long)(L->can_drops - L->can_drops_logged),
            (long long)L->can_drops, (long long)L->can_drops_frames);
    L->can_drops_logged = L->can_drops;
    L->can_drops_warned_us = now;
}

static void read_socket(live_t *L) {
    loadid_can_frame_t f;
    int rc;
    uint32_t drops = L->can_drops_seen;
    while ((rc = loadid_socketcan_read(L->can_fd, &f, &drops)) > 0) {
        if (drops != L->can_drops_seen) { /* cumulative, wrapping: the difference */
            L->can_drops += (uint32_t)(drops - L->can_drops_seen);
            L->can_drops_seen = drops;
            L->can_drops_frames = L->can_frames;
            log_can_drops(L);
        }
        L->can_frames++;
        if (rc == 2) L->error_frames++;
        else loadid_pipeline_can_frame(L->pipe, &f);
    }
    if (rc < 0) {
        fprintf(stderr, "loadidd: CAN %s: %s; reopening\n", L->cfg->can_interface, strerror(-rc));
        L->can_errors++;
        close(L->can_fd);
        L->can_fd = -1;
        L->can_lost_us = mono_us();
        L->can_drops_seen = 0; /* a new socket counts from 0 */
    }
}

/* Deadlines: late_us is how long after its arrival a sample was handled
 * (taken in by the pipeline: decoded, counted, queued for the joint data
 * the fixed-lag smoother waits for, which is by design and not lateness).
 * More than LATE_US is a missed deadline: counted, logged at most once a
 * second while the count grows, and in --verbose's summary with the worst. */
static void note_lateness(live_t *L, double late_us) {
    if (late_us > L->late_max_us) L->late_max_us = late_us;
    if (late_us <= LATE_US) return;
    L->samples_late++;
    const double now_mono = mono_us();
    if (now_mono - L->late_warned_us >= 1e6) {
        fprintf(stderr, "loadidd: %lld samples handled more than %.0f ms after arrival so far "
                        "(%lld new, worst %.0f us)\n", (long long)L->samples_late, LATE_US / 1e3,
                (long long)(L->samples_late - L->late_logged), L->late_max_us);
        L->late_logged = L->samples_late;
        L->late_warned_us = now_mono;
    }
}

/* Modbus: a sample arrives when the poller got the sensor's answer (its
 * t_us, CLOCK_REALTIME). */
static void on_ft_sample(void *ctx, const loadid_modbus_ft_sample_t *s) {
    live_t *L = ctx;
    loadid_sensor_sample_t x = {.t_us = s->t_us, .saturated = s->saturated, .faulty = s->faulty};
    memcpy(x.force, s->force, sizeof x.force);
    memcpy(x.torque, s->torque, sizeof x.torque);
    loadid_pipeline_sample(L->pipe, &x);
    note_lateness(L, (double)(wall_us() - s->t_us));
}

/* Once a second: say when the serial sensor was lost or came back (both
 * within the second: the poller reopens after a response timeout). */
static void watch_ft(live_t *L) {
    const bool lost = loadid_modbus_input_take_lost(L->ft);
    loadid_modbus_input_stats_t ms;
    loadid_modbus_input_stats(L->ft, &ms);
    if (lost)
        fprintf(stderr, "loadidd: modbus %s lost: %s; reopening\n", L->cfg->modbus_device,
                loadid_modbus_ft_strerror((int)ms.lost_error));
    if (ms.connected && (!L->ft_connected || lost))
        fprintf(stderr, "loadidd: modbus %s open\n", L->cfg->modbus_device);
    L->ft_connected = ms.connected;
}

/* File source: feeds every frame due by now, then arms the timer for the
 * next one. A sample arrives when the frame that completes it is due. */
static void read_file(live_t *L, int timer_fd) {
    const double now = mono_us();
    while (L->have_next) {
        const double due = L->mono_t0 + (double)(L->next.t_us - L->file_t0);
        if (due > now) break;
        loadid_can_frame_t f = L->next;
        f.t_us = L->wall_t0 + (L->next.t_us - L->file_t0);
        if (loadid_pipeline_can_frame(L->pipe, &f)) note_lateness(L, mono_us() - due);
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

static void close_lcm(live_t *L) {
    if (L->lcm_rx_fd >= 0) close(L->lcm_rx_fd);
    loadid_lcm_udpm_close_tx(&L->lcm_tx);
    if (L->lcm) lcm_destroy(L->lcm);
}

static int add_fd(int ep, int fd, uint32_t tag) {
    struct epoll_event ev = {.events = EPOLLIN, .data.u32 = tag};
    return epoll_ctl(ep, EPOLL_CTL_ADD, fd, &ev);
}

/* load_model_t of the primary estimate on LOADID_MODEL. */
static void publish_model(live_t *L, const loadid_pipeline_estimate_t *e) {
    loadid_lcm_load_model_t m;
    memset(&m, 0, sizeof m);
    m.utime = e->utime;
    m.method = (int8_t)e->method;
    memcpy(m.load_name, e->load_name, sizeof m.load_name);
    m.load_name[sizeof m.load_name - 1] = 0;
    m.identified = (int8_t)e->identified;
    m.projected = (int8_t)e->projected;
    memcpy(m.phi, e->model_phi, sizeof m.phi);
    memcpy(m.phi_std, e->phi_std, sizeof m.phi_std);
    m.mass = e->model_mass;
    memcpy(m.com, e->model_com, sizeof m.com);
    memcpy(m.inertia_com, e->model_inertia_com, sizeof m.inertia_com);
    publish(L, channels[CH_MODEL], loadid_lcm_encode_load_model(&m, tx_buf, sizeof tx_buf));
}

/* DONE: the best load model out on LOADID_MODEL, and the estimate into
 * results.directory (when configured). */
static void save_done(live_t *L) {
    L->done_pending = 0;
    loadid_pipeline_estimate_t e;
    loadid_pipeline_compensation_t c;
    if (loadid_pipeline_final(L->pipe, &e, &c) != 0) return;
    if (e.has_model) publish_model(L, &e);
    if (!L->cfg->results_directory[0]) return;
    char path[4400], err[4600];
    if (loadid_saved_result_write(L->cfg->results_directory, &e, &c, path, sizeof path, err,
                                  sizeof err) != 0)
        fprintf(stderr, "loadidd: %s\n", err);
    else
        fprintf(stderr, "loadidd: saved %s\n", path);
}

enum { TAG_LCM = 1, TAG_CAN, TAG_FILE, TAG_TICK, TAG_SIGNAL, TAG_FT, TAG_REFINED };

int loadid_live_run(const loadid_config_t *cfg, const loadid_chain_t *chain,
                    const loadid_live_options_t *opt) {
    static live_t L; /* large (the histogram); one per process */
    memset(&L, 0, sizeof L);
    static const char *const names[CH_COUNT] = {"LOADID_JOINTS", "LOADID_COMMAND",
                                                "LOADID_ESTIMATE", "LOADID_WRENCH",
                                                "LOADID_STATUS", "LOADID_MODEL"};
    for (int i = 0; i < CH_COUNT; ++i) loadid_config_channel(cfg, names[i], channels[i], sizeof channels[i]);
    L.cfg = cfg;
    L.opt = opt;
    L.can_fd = -1;
    L.lcm_rx_fd = -1;
    L.lcm_tx.fd = -1;
    char err[512];
    loadid_pipeline_sink_t sink = {.ctx = &L, .estimate = on_estimate, .wrench = on_wrench,
                                   .state = on_state, .log = on_log};
    if (loadid_pipeline_create(cfg, chain, &sink, opt->publish_every, &L.pipe, err, sizeof err) != 0) {
        fprintf(stderr, "loadidd: %s\n", err);
        return 1;
    }
    /* An empty lcm.url is liblcm's: LCM_DEFAULT_URL, else its default. */
    const char *url = cfg->lcm_url[0] ? cfg->lcm_url : getenv("LCM_DEFAULT_URL");
    loadid_lcm_udpm_url_t udpm;
    const int udpm_rc = loadid_lcm_udpm_parse_url(url, &udpm);
    if (udpm_rc == -EINVAL) {
        fprintf(stderr, "loadidd: cannot open LCM at %s: malformed udpm URL\n", url);
        loadid_pipeline_destroy(L.pipe);
        return 1;
    }
    L.udpm = udpm_rc == 0;
    if (L.udpm) {
        L.lcm_rx_fd = loadid_lcm_udpm_open(&udpm, err, sizeof err);
        if (L.lcm_rx_fd < 0 || loadid_lcm_udpm_open_tx(&udpm, &L.lcm_tx, err, sizeof err) != 0) {
            fprintf(stderr, "loadidd: cannot open LCM at %s: %s\n", url ? url : "", err);
            if (L.lcm_rx_fd >= 0) close(L.lcm_rx_fd);
            loadid_pipeline_destroy(L.pipe);
            return 1;
        }
    } else if (cfg->lcm_num_command_sources > 0) {
        /* liblcm's providers do not say who sent a message. */
        fprintf(stderr, "loadidd: lcm.command_sources needs a udpm:// lcm.url, not %s\n",
                url ? url : "");
        loadid_pipeline_destroy(L.pipe);
        return 1;
    } else if (!(L.lcm = lcm_create(cfg->lcm_url))) {
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
            close_lcm(&L);
            loadid_pipeline_destroy(L.pipe);
            return 1;
        }
        fprintf(stderr, "loadidd: loaded %s (%s): wrench_t flows\n", cfg->results_load, e.load_name);
        if (e.has_model) publish_model(&L, &e);
    }
    int lcm_fd = L.lcm_rx_fd;
    if (!L.udpm) {
        lcm_subscribe(L.lcm, channels[CH_JOINTS], on_lcm_raw, &L);
        lcm_subscribe(L.lcm, channels[CH_COMMAND], on_lcm_raw, &L);
        lcm_fd = lcm_get_fileno(L.lcm);
    }

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
        add_fd(ep, tick_fd, TAG_TICK) || add_fd(ep, lcm_fd, TAG_LCM)) {
        fprintf(stderr, "loadidd: cannot set up the event loop: %s\n", strerror(errno));
        rc = 1;
    }
    /* REFINED on its worker thread, created with the signals blocked (so
     * that they reach the signalfd only) and before the real-time set-up. */
    if (rc == 0) {
        const int refined_fd = loadid_pipeline_refined_async(L.pipe);
        if (refined_fd != -ENOENT && (refined_fd < 0 || add_fd(ep, refined_fd, TAG_REFINED) != 0)) {
            fprintf(stderr, "loadidd: cannot start REFINED's worker: %s\n",
                    strerror(refined_fd < 0 ? -refined_fd : errno));
            rc = 1;
        }
    }
    if (rc == 0 && cfg->sensor_type == LOADID_SENSOR_MODBUS) {
        if (opt->can_file) {
            fprintf(stderr, "loadidd: --can-file replays JR3 frames; sensor.type is modbus\n");
            rc = 1;
        } else if (loadid_modbus_input_start(cfg, &L.ft, err, sizeof err) != 0) {
            fprintf(stderr, "loadidd: modbus: %s\n", err);
            rc = 1;
        } else if (add_fd(ep, loadid_modbus_input_fd(L.ft), TAG_FT) != 0) {
            fprintf(stderr, "loadidd: cannot set up the event loop: %s\n", strerror(errno));
            rc = 1;
        }
    } else if (rc == 0 && opt->can_file) {
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
            const int absent = L.can_fd == -EAFNOSUPPORT || L.can_fd == -EPROTONOSUPPORT ||
                               L.can_fd == -ENODEV;
            fprintf(stderr, "loadidd: %s%s\n", err,
                    absent ? "; or, without a CAN bus, JR3 frames from a candump log "
                             "(--can-file CAN.LOG) or a whole recording (--offline DIR)"
                           : "");
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
            int timed = evs[i].data.u32 != TAG_SIGNAL;
            switch (evs[i].data.u32) {
                case TAG_LCM:
                    if (L.udpm) timed = read_lcm(&L);
                    else lcm_handle(L.lcm);
                    break;
                case TAG_CAN: read_socket(&L); break;
                case TAG_FT: loadid_modbus_input_drain(L.ft, on_ft_sample, &L); break;
                case TAG_FILE:
                    if (read(file_fd, &v, sizeof v) < 0) break;
                    read_file(&L, file_fd);
                    break;
                case TAG_TICK:
                    if (read(tick_fd, &v, sizeof v) < 0) break;
                    loadid_pipeline_tick(L.pipe, wall_us());
                    loadid_notify_watchdog((int64_t)mono_us());
                    if (++L.ticks % 100 == 0) {
                        publish_status(&L, 1, 0, 0);
                        if (L.ft) watch_ft(&L);
                        else if (L.can_fd < 0 && !opt->can_file) { /* reopen a vanished interface */
                            L.can_fd = loadid_socketcan_open(cfg->can_interface, cfg->can_base_id,
                                                             err, sizeof err);
                            if (L.can_fd >= 0) {
                                add_fd(ep, L.can_fd, TAG_CAN), L.can_reopens++;
                                fprintf(stderr, "loadidd: CAN %s open again after %.3f s\n",
                                        cfg->can_interface, (mono_us() - L.can_lost_us) / 1e6);
                            }
                        }
                        log_can_drops(&L); /* what waited for the throttle */
                    }
                    break;
                case TAG_SIGNAL: stop = 1; break;
                case TAG_REFINED: loadid_pipeline_refined_collect(L.pipe); break;
            }
            if (timed) record_loop_time(&L, mono_us() - t_event);
        }
        for (int k = 0; k < L.num_changes; ++k)
            publish_status(&L, 0, L.changes[k].state, L.changes[k].utime);
        L.num_changes = 0;
        /* The model and the saved result wait for REFINED, which may be the best. */
        if (L.done_pending && !loadid_pipeline_refined_pending(L.pipe)) save_done(&L);
        if (stop) break;
    }
    loadid_notify_stopping();
    /* A loss or a reopen since the last once-a-second look is said too. */
    if (L.ft) watch_ft(&L);
    if (opt->verbose) {
        loadid_pipeline_status_t st;
        loadid_pipeline_status(L.pipe, &st);
        fprintf(stderr,
                "loadidd: samples ok %lld, used %lld, frames bad %lld, incomplete %lld, "
                "saturated %lld, faulty %lld, gaps %lld, joint msgs bad %lld, stale %lld, "
                "CAN errors %lld, CAN drops %lld, error frames %lld, commands refused %lld\n",
                (long long)st.samples_ok, (long long)st.samples_used, (long long)st.frames_bad,
                (long long)st.samples_incomplete, (long long)st.samples_saturated,
                (long long)st.samples_faulty, (long long)st.sequence_gaps,
                (long long)st.joint_msgs_bad, (long long)st.samples_stale,
                (long long)L.can_errors, (long long)L.can_drops, (long long)L.error_frames,
                (long long)L.commands_refused);
        if (opt->can_file || L.ft) /* measured there (SocketCAN: not yet) */
            fprintf(stderr, "loadidd: samples late %lld (handled more than %.0f ms after "
                            "arrival), worst lateness %.0f us\n",
                    (long long)L.samples_late, LATE_US / 1e3, L.late_max_us);
        loadid_modbus_input_stats_t ms;
        if (L.ft && loadid_modbus_input_stats(L.ft, &ms) == 0)
            fprintf(stderr,
                    "loadidd: modbus reads %lld, samples ok %lld, rejected %lld, stale %lld, "
                    "gaps %lld, malformed %lld, timeouts %lld, bad frames %lld (CRC %lld), "
                    "exceptions %lld, device lost %lld, ring overruns %lld, cycles missed %lld\n",
                    (long long)ms.ft.reads, (long long)ms.ft.samples_ok,
                    (long long)ms.ft.samples_rejected, (long long)ms.ft.samples_stale,
                    (long long)ms.ft.counter_gaps, (long long)ms.ft.samples_malformed,
                    (long long)ms.ft.timeouts, (long long)ms.ft.bad_frames,
                    (long long)ms.ft.crc_errors, (long long)ms.ft.exceptions,
                    (long long)ms.ft.device_lost, (long long)ms.ring_overruns,
                    (long long)ms.cycles_missed);
    }
    publish_status(&L, 1, 0, 0);
    loadid_modbus_input_stop(L.ft);
    if (L.can_fd >= 0) close(L.can_fd);
    loadid_candump_reader_close(L.can_reader);
    if (L.can_file) fclose(L.can_file);
    close(ep), close(file_fd), close(tick_fd), close(sig_fd);
    close_lcm(&L);
    loadid_pipeline_destroy(L.pipe);
    return rc;
}
