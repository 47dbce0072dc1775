/*
 * Input backend: the JR3's frames from SocketCAN on can.interface
 * (drivers/socketcan.h: a CAN_RAW socket whose kernel filter passes only
 * base..base+4, with the kernel's receive times). Frames the kernel drops
 * for a full receive buffer are learnt from SO_RXQ_OVFL and logged (at
 * most a line a second; status_t has no field for them, and what they
 * cost shows there as sequence gaps and incomplete samples). An interface
 * that vanishes is logged, counted and reopened once a second; estimation
 * goes on without the samples lost. A sample's lateness runs from the
 * kernel's receive time of the frame that completes it (SO_TIMESTAMP: the
 * wall clock, so a step of the clock in between shows as lateness once).
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../clock.h"
#include "../log.h"
#include "input.h"
#include "loadid/socketcan.h"

typedef struct {
    int fd; /* the socket, or -1 while the interface is gone */
    int64_t errors, reopens, error_frames;
    double lost_us;                     /* when the socket failed (mono) */
    int64_t frames;                     /* frames read */
    uint32_t drops_seen;                /* the socket's cumulative drop count (SO_RXQ_OVFL) */
    int64_t drops;                      /* frames the kernel dropped, over every socket */
    int64_t drops_logged, drops_frames; /* logged so far; frames read when last grown */
    double drops_warned_us;             /* throttles their log line */
} can_t;

static int can_open(const loadid_config_t *cfg, char *err, size_t errlen) {
    return loadid_socketcan_open(cfg->can_interface, cfg->can_base_id, err, errlen);
}

static int open_(loadid_input_t *in, const loadid_input_options_t *opt, char *err, size_t errlen) {
    (void)opt;
    can_t *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    in->state = c;
    in->late_measured = 1;
    char why[512];
    c->fd = can_open(in->cfg, why, sizeof why);
    if (c->fd < 0) {
        const int absent = c->fd == -EAFNOSUPPORT || c->fd == -EPROTONOSUPPORT || c->fd == -ENODEV;
        snprintf(err, errlen, "%s%s", why,
                 absent ? "; or, without a CAN bus, JR3 frames from a candump log "
                          "(--can-file CAN.LOG) or a whole recording (--offline DIR, "
                          "--replay DIR)"
                        : "");
        return c->fd;
    }
    return 0;
}

static int fd_(const loadid_input_t *in) {
    return ((const can_t *)in->state)->fd;
}

/* Frames the kernel dropped: logged when the count grew, the first time at
 * once, then at most a line a second (second() logs what waited). */
static void log_drops(const loadid_input_t *in, can_t *c) {
    const double now = loadid_mono_us();
    if (c->drops == c->drops_logged || (c->drops_logged > 0 && now - c->drops_warned_us < 1e6))
        return;
    loadidd_log(
        "CAN %s: %lld frames dropped by the kernel, the socket's receive buffer full "
        "(%lld in all, learnt after %lld frames read)",
        in->cfg->can_interface, (long long)(c->drops - c->drops_logged), (long long)c->drops,
        (long long)c->drops_frames);
    c->drops_logged = c->drops;
    c->drops_warned_us = now;
}

static void read_(loadid_input_t *in) {
    can_t *c = in->state;
    loadid_can_frame_t f;
    int rc;
    uint32_t drops = c->drops_seen;
    while ((rc = loadid_socketcan_read(c->fd, &f, &drops)) > 0) {
        if (drops != c->drops_seen) { /* cumulative, wrapping: the difference */
            c->drops += (uint32_t)(drops - c->drops_seen);
            c->drops_seen = drops;
            c->drops_frames = c->frames;
            log_drops(in, c);
        }
        c->frames++;
        if (rc == 2)
            c->error_frames++;
        else if (loadid_pipeline_can_frame(in->pipe, &f))
            loadid_input_late(in, (double)(loadid_wall_us() - f.t_us));
    }
    if (rc < 0) {
        loadidd_log("CAN %s: %s; reopening", in->cfg->can_interface, strerror(-rc));
        c->errors++;
        close(c->fd);
        c->fd = -1;
        c->lost_us = loadid_mono_us();
        c->drops_seen = 0; /* a new socket counts from 0 */
    }
}

/* Reopens a vanished interface; logs the drops that waited for the throttle. */
static void second(loadid_input_t *in) {
    can_t *c = in->state;
    if (c->fd < 0) {
        char err[512];
        c->fd = can_open(in->cfg, err, sizeof err);
        if (c->fd >= 0) {
            c->reopens++;
            loadidd_log("CAN %s open again after %.3f s", in->cfg->can_interface,
                        (loadid_mono_us() - c->lost_us) / 1e6);
        }
    }
    log_drops(in, c);
}

/* CAN error frames are bad frames the pipeline never saw. */
static void counters(const loadid_input_t *in, loadid_input_counters_t *out) {
    const can_t *c = in->state;
    out->frames_bad = c->error_frames;
    out->errors = c->errors;
    out->drops = c->drops;
    out->error_frames = c->error_frames;
}

static void close_(loadid_input_t *in) {
    can_t *c = in->state;
    if (!c) return;
    if (c->fd >= 0) close(c->fd);
    free(c);
    in->state = NULL;
}

const loadid_input_backend_t loadid_input_jr3_socketcan = {.name = "jr3-socketcan",
                                                           .open = open_,
                                                           .fd = fd_,
                                                           .read = read_,
                                                           .second = second,
                                                           .counters = counters,
                                                           .close = close_};
