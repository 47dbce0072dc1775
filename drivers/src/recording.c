/* Recording folder reader: can.log and lcm.log merged in time order
 * (recording.h). */
#define _POSIX_C_SOURCE 200809L
#include "loadid/recording.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/candump.h"
#include "loadid/lcm_eventlog.h"

struct loadid_recording_reader {
    FILE *can_file;
    loadid_candump_reader_t *can;
    FILE *lcm_file;
    loadid_eventlog_t *lcm;
    /* one event of lookahead per stream */
    int can_state; /* 1 pending, 0 ended, <0 a bad line pending */
    loadid_can_frame_t can_frame;
    long can_line;
    int lcm_state; /* 1 pending, 0 ended, <0 a read error */
    loadid_eventlog_event_t lcm_event;
    int lcm_given; /* lcm_event was handed out: read the next
                                     one on the next call (the reader has
                                     one buffer, which the caller's event
                                     points into until then) */
};

static void advance_can(loadid_recording_reader_t *r) {
    r->can_state = loadid_candump_read(r->can, &r->can_frame, NULL);
    r->can_line = loadid_candump_reader_line(r->can);
}

static void advance_lcm(loadid_recording_reader_t *r) {
    r->lcm_state = loadid_eventlog_next(r->lcm, &r->lcm_event);
}

int loadid_recording_reader_open(const char *dir, loadid_recording_reader_t **out, char *err,
                                 size_t errlen) {
    loadid_recording_reader_t *r = calloc(1, sizeof *r);
    if (!r) return -ENOMEM;
    char path[4200];
    int e = 0;
    snprintf(path, sizeof path, "%s/can.log", dir);
    r->can_file = fopen(path, "r");
    if (!r->can_file) {
        e = errno;
    } else if ((e = -loadid_candump_reader_open(r->can_file, &r->can)) == 0) {
        snprintf(path, sizeof path, "%s/lcm.log", dir);
        r->lcm_file = fopen(path, "rb");
        if (!r->lcm_file) {
            e = errno;
        } else {
            const int rc = loadid_eventlog_open(r->lcm_file, 0, &r->lcm);
            if (rc != 0) e = rc == LOADID_EVENTLOG_E_SEEK ? ESPIPE : -rc;
        }
    }
    if (e) {
        if (err && errlen) snprintf(err, errlen, "%s: cannot read: %s", path, strerror(e));
        loadid_recording_reader_close(r);
        return -e;
    }
    advance_can(r);
    advance_lcm(r);
    if (r->lcm_state < 0) {
        /* Not an LCM log at all, or unreadable: nothing to merge. */
        if (err && errlen) snprintf(err, errlen, "%s: %s", path, loadid_eventlog_error(r->lcm));
        e = r->lcm_state == LOADID_EVENTLOG_E_NOT_LOG ? EBADMSG : EIO;
        loadid_recording_reader_close(r);
        return -e;
    }
    *out = r;
    return 0;
}

void loadid_recording_reader_close(loadid_recording_reader_t *r) {
    if (!r) return;
    loadid_candump_reader_close(r->can);
    if (r->can_file) fclose(r->can_file);
    loadid_eventlog_close(r->lcm);
    if (r->lcm_file) fclose(r->lcm_file);
    free(r);
}

int loadid_recording_reader_next(loadid_recording_reader_t *r, loadid_rec_event_t *ev) {
    if (r->lcm_given) {
        r->lcm_given = 0;
        advance_lcm(r);
    }
    if (r->can_state == -EIO || r->lcm_state < 0) return -EIO;
    memset(ev, 0, sizeof *ev);
    /* A bad line has no time of its own: hand it on at once. */
    if (r->can_state < 0) {
        ev->kind = LOADID_REC_BAD_LINE;
        ev->line = r->can_line;
        ev->error = r->can_state;
        ev->t_us = INT64_MIN;
        advance_can(r);
        return 1;
    }
    const int have_can = r->can_state == 1, have_lcm = r->lcm_state == 1;
    if (!have_can && !have_lcm) return 0;
    if (have_lcm && (!have_can || r->lcm_event.timestamp <= r->can_frame.t_us)) {
        ev->kind = LOADID_REC_LCM;
        ev->t_us = r->lcm_event.timestamp;
        ev->channel = r->lcm_event.channel;
        ev->data = r->lcm_event.data;
        ev->datalen = r->lcm_event.data_len;
        ev->offset = r->lcm_event.offset;
        r->lcm_given = 1;
        return 1;
    }
    ev->kind = LOADID_REC_CAN;
    ev->t_us = r->can_frame.t_us;
    ev->can = r->can_frame;
    ev->line = r->can_line;
    advance_can(r);
    return 1;
}

void loadid_recording_lcm_stats(const loadid_recording_reader_t *r, loadid_eventlog_stats_t *st) {
    loadid_eventlog_stats(r->lcm, st);
}

const char *loadid_recording_lcm_error(const loadid_recording_reader_t *r) {
    return loadid_eventlog_error(r->lcm);
}
