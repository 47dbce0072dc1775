/*
 * Input backend: a whole recording (docs/INTERFACE.md's folder: can.log and
 * lcm.log) replayed in real time (loadidd --replay DIR), for demos, lcm-spy
 * and a robot controller's integration on a machine without CAN. The
 * events come in the recording's time order (drivers/recording.h, as
 * --offline reads them), each when as long after the first as in the
 * recording, on the monotonic clock (a timerfd wakes the loop), with every
 * time shifted by one constant so that the first event is now:
 *
 *   JR3 frames      to the pipeline's decoder, as from SocketCAN
 *   joint states    (LOADID_JOINTS) to the pipeline, decoded as live; the
 *                   LCM network's joint states are then not taken
 *                   (live.c), so a robot's own stream does not mix in
 *   commands        (LOADID_COMMAND) at their event's time, as --offline
 *                   has them act, unless options.with_commands is 0
 *                   (--replay-without-commands: commands over LCM only,
 *                   which are obeyed either way)
 *
 * So the pipeline sees what --offline gives it, the times shifted, and
 * the final estimates are --offline's (test_live_replay.py). A sample
 * arrives when its completing frame is due. At the end the input falls
 * silent and the daemon goes on (its wrench_t, status_t and commands).
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "../clock.h"
#include "../log.h"
#include "input.h"
#include "loadid/lcm_wire.h"
#include "loadid/recording.h"

typedef struct {
    int timer_fd;
    const char *dir;
    loadid_recording_reader_t *rec;
    int have_next; /* the next event is read ahead */
    loadid_rec_event_t next;
    int64_t rec_t0; /* the first event's time in the recording */
    int64_t shift;  /* wall time less the recording's */
    double mono_t0; /* when the first event is due (mono) */
    int with_commands;
    char joints[128], command[128];
    loadid_lcm_joint_state_t js; /* decoded here: two arrays of 16 doubles */
    int64_t events, joint_states, joint_states_bad, commands, commands_bad;
} replay_t;

/* The next event; 0 at the end or after a read error (logged). */
static int next_event(replay_t *r) {
    const int rc = loadid_recording_reader_next(r->rec, &r->next);
    if (rc >= 0) return rc == 1;
    const char *lcm_err = loadid_recording_lcm_error(r->rec);
    if (*lcm_err)
        loadidd_log("replay: %s/lcm.log: %s; the rest is not replayed", r->dir, lcm_err);
    else
        loadidd_log("replay: %s/can.log: read error; the rest is not replayed", r->dir);
    return 0;
}

/* One event to the pipeline, its times shifted to now. */
static void feed(loadid_input_t *in, replay_t *r, const loadid_rec_event_t *ev, double due) {
    r->events++;
    switch (ev->kind) {
        case LOADID_REC_CAN: {
            loadid_can_frame_t f = ev->can;
            f.t_us += r->shift;
            if (loadid_pipeline_can_frame(in->pipe, &f))
                loadid_input_late(in, loadid_mono_us() - due);
            return;
        }
        case LOADID_REC_BAD_LINE:
            loadid_pipeline_bad_frame(in->pipe);
            return;
        case LOADID_REC_LCM:
            break;
    }
    const size_t len = ev->datalen < 0 ? 0 : (size_t)ev->datalen;
    if (strcmp(ev->channel, r->joints) == 0) {
        r->joint_states++;
        if (loadid_lcm_decode_joint_state(ev->data, len, &r->js) < 0) {
            r->joint_states_bad++; /* and the pipeline counts it, as --offline */
            loadid_pipeline_joint_state(in->pipe, ev->t_us + r->shift, -1, NULL, NULL);
        } else {
            loadid_pipeline_joint_state(in->pipe, r->js.utime + r->shift, r->js.num_joints,
                                        r->js.position, r->js.setpoint);
        }
    } else if (r->with_commands && strcmp(ev->channel, r->command) == 0) {
        loadid_lcm_command_t m;
        r->commands++;
        if (loadid_lcm_decode_command(ev->data, len, &m) < 0)
            r->commands_bad++;
        else
            loadid_pipeline_command(in->pipe, ev->t_us + r->shift, m.action, m.load_name);
    }
}

/* Feeds every event due by now; arms the timer for the next one. */
static void feed_due(loadid_input_t *in) {
    replay_t *r = in->state;
    const double now = loadid_mono_us();
    while (r->have_next) {
        /* A can.log line that is no frame has no time: at once. */
        const double due = r->next.kind == LOADID_REC_BAD_LINE
                               ? now
                               : r->mono_t0 + (double)(r->next.t_us - r->rec_t0);
        if (due > now) break;
        feed(in, r, &r->next, due);
        r->have_next = next_event(r);
        if (!r->have_next)
            loadidd_log("replay: %s replayed (%lld events)", r->dir, (long long)r->events);
    }
    if (!r->have_next) return;
    const double due = r->mono_t0 + (double)(r->next.t_us - r->rec_t0);
    struct itimerspec its = {
        {0, 0}, {(time_t)(due / 1e6), (long)(due - (double)(time_t)(due / 1e6) * 1e6) * 1000}};
    timerfd_settime(r->timer_fd, TFD_TIMER_ABSTIME, &its, NULL);
}

static int open_(loadid_input_t *in, const loadid_input_options_t *opt, char *err, size_t errlen) {
    replay_t *r = calloc(1, sizeof *r);
    if (!r) {
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    in->state = r;
    in->late_measured = 1;
    r->dir = opt->path;
    r->with_commands = opt->with_commands;
    loadid_config_channel(in->cfg, "LOADID_JOINTS", r->joints, sizeof r->joints);
    loadid_config_channel(in->cfg, "LOADID_COMMAND", r->command, sizeof r->command);
    /* Non-blocking: catch_up may re-arm the timer after epoll saw it
     * expire, and read must not then wait for the next event. */
    r->timer_fd = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC | TFD_NONBLOCK);
    if (r->timer_fd < 0) {
        const int e = errno;
        snprintf(err, errlen, "cannot set up the event loop: %s", strerror(e));
        return -e;
    }
    const int rc = loadid_recording_reader_open(opt->path, &r->rec, err, errlen);
    if (rc != 0) return rc;
    /* The recording's clock starts at its first timed event. */
    while ((r->have_next = next_event(r)) && r->next.kind == LOADID_REC_BAD_LINE)
        feed(in, r, &r->next, loadid_mono_us());
    r->rec_t0 = r->have_next ? r->next.t_us : 0;
    const int64_t wall_now = loadid_wall_us();
    const int64_t wall_t0 = opt->epoch_us > 0 ? opt->epoch_us : wall_now;
    r->shift = wall_t0 - r->rec_t0;
    r->mono_t0 = loadid_mono_us() + (double)(wall_t0 - wall_now);
    loadidd_log("replay: %s, its times shifted by %+.6f s to now%s", r->dir, (double)r->shift / 1e6,
                r->with_commands ? "" : "; its commands not replayed");
    feed_due(in);
    return 0;
}

static int fd_(const loadid_input_t *in) {
    return ((const replay_t *)in->state)->timer_fd;
}

static void read_(loadid_input_t *in) {
    replay_t *r = in->state;
    uint64_t v;
    ssize_t n = read(r->timer_fd, &v, sizeof v); /* EAGAIN after a catch_up: harmless */
    (void)n;
    feed_due(in);
}

static void counters(const loadid_input_t *in, loadid_input_counters_t *out) {
    (void)in, (void)out; /* its bad lines and joint states are the pipeline's */
}

static void summary(const loadid_input_t *in) {
    const replay_t *r = in->state;
    loadidd_log(
        "replay events %lld, joint states %lld (undecodable %lld), commands %lld "
        "(undecodable %lld)",
        (long long)r->events, (long long)r->joint_states, (long long)r->joint_states_bad,
        (long long)r->commands, (long long)r->commands_bad);
}

static void close_(loadid_input_t *in) {
    replay_t *r = in->state;
    if (!r) return;
    loadid_recording_reader_close(r->rec);
    if (r->timer_fd >= 0) close(r->timer_fd);
    free(r);
    in->state = NULL;
}

const loadid_input_backend_t loadid_input_replay = {.name = "replay",
                                                    .open = open_,
                                                    .fd = fd_,
                                                    .read = read_,
                                                    .catch_up = feed_due,
                                                    .counters = counters,
                                                    .summary = summary,
                                                    .close = close_};
