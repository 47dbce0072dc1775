/*
 * Input backend: the JR3's frames from a candump log replayed in real time
 * (--can-file), with their times rewritten to now: the file's first frame
 * is due at --can-file-epoch (wall time; 0: when opened), every other one
 * as long after as in the file. A timerfd wakes the loop when the next is
 * due. A sample arrives when the frame that completes it is due, and is
 * late by the time from then until the pipeline has it. Lines that are no
 * frame are the pipeline's bad frames. At the end the input falls silent.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "../clock.h"
#include "input.h"
#include "loadid/candump.h"

typedef struct {
    int timer_fd;
    FILE *file;
    loadid_candump_reader_t *reader;
    int have_next; /* the next frame is read ahead */
    loadid_can_frame_t next;
    int64_t file_t0, wall_t0; /* the first frame's time, its wall time */
    double mono_t0;
} candump_t;

/* The next frame, counting the lines that are none; 0 at the end. */
static int next_frame(loadid_input_t *in, candump_t *c) {
    int rc;
    while ((rc = loadid_candump_read(c->reader, &c->next, NULL)) < 0 && rc != -EIO)
        loadid_pipeline_bad_frame(in->pipe);
    return rc == 1;
}

/* Feeds every frame due by now, then arms the timer for the next one. */
static void feed_due(loadid_input_t *in) {
    candump_t *c = in->state;
    const double now = loadid_mono_us();
    while (c->have_next) {
        const double due = c->mono_t0 + (double)(c->next.t_us - c->file_t0);
        if (due > now) break;
        loadid_can_frame_t f = c->next;
        f.t_us = c->wall_t0 + (c->next.t_us - c->file_t0);
        if (loadid_pipeline_can_frame(in->pipe, &f)) loadid_input_late(in, loadid_mono_us() - due);
        c->have_next = next_frame(in, c);
    }
    if (!c->have_next) return; /* replayed: the input is quiet */
    const double due = c->mono_t0 + (double)(c->next.t_us - c->file_t0);
    struct itimerspec its = {
        {0, 0}, {(time_t)(due / 1e6), (long)(due - (double)(time_t)(due / 1e6) * 1e6) * 1000}};
    timerfd_settime(c->timer_fd, TFD_TIMER_ABSTIME, &its, NULL);
}

static int open_(loadid_input_t *in, const loadid_input_options_t *opt, char *err, size_t errlen) {
    candump_t *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    in->state = c;
    in->late_measured = 1;
    c->timer_fd = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
    if (c->timer_fd < 0) {
        const int e = errno;
        snprintf(err, errlen, "cannot set up the event loop: %s", strerror(e));
        return -e;
    }
    c->file = fopen(opt->path, "r");
    if (!c->file || loadid_candump_reader_open(c->file, &c->reader) != 0) {
        const int e = errno;
        snprintf(err, errlen, "%s: cannot read: %s", opt->path, strerror(e));
        return -e;
    }
    c->have_next = next_frame(in, c);
    c->file_t0 = c->next.t_us;
    /* The file's first frame is replayed at epoch_us (wall time, so that a
     * test can time its joint states to it). */
    const int64_t wall_now = loadid_wall_us();
    c->wall_t0 = opt->epoch_us > 0 ? opt->epoch_us : wall_now;
    c->mono_t0 = loadid_mono_us() + (double)(c->wall_t0 - wall_now);
    feed_due(in);
    return 0;
}

static int fd_(const loadid_input_t *in) {
    return ((const candump_t *)in->state)->timer_fd;
}

static void read_(loadid_input_t *in) {
    candump_t *c = in->state;
    uint64_t v;
    if (read(c->timer_fd, &v, sizeof v) < 0) return;
    feed_due(in);
}

static void counters(const loadid_input_t *in, loadid_input_counters_t *out) {
    (void)in, (void)out; /* its bad lines are the pipeline's bad frames */
}

static void close_(loadid_input_t *in) {
    candump_t *c = in->state;
    if (!c) return;
    loadid_candump_reader_close(c->reader);
    if (c->file) fclose(c->file);
    if (c->timer_fd >= 0) close(c->timer_fd);
    free(c);
    in->state = NULL;
}

const loadid_input_backend_t loadid_input_jr3_candump = {.name = "jr3-candump",
                                                         .open = open_,
                                                         .fd = fd_,
                                                         .read = read_,
                                                         .counters = counters,
                                                         .close = close_};
