/* Recording folder reader: can.log and lcm.log merged in time order
 * (recording.h). */
#define _POSIX_C_SOURCE 200809L
#include "loadid/recording.h"

#include <errno.h>
#include <lcm/eventlog.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "loadid/candump.h"

struct loadid_recording_reader {
    FILE *can_file;
    loadid_candump_reader_t *can;
    lcm_eventlog_t *lcm;
    off_t lcm_size;
    /* one event of lookahead per stream */
    int can_state;                /* 1 pending, 0 ended, <0 a bad line pending */
    loadid_can_frame_t can_frame;
    long can_line;
    lcm_eventlog_event_t *lcm_event; /* NULL: ended */
    lcm_eventlog_event_t *lcm_given; /* handed out, freed on the next call */
    int lcm_truncated;
};

static void advance_can(loadid_recording_reader_t *r) {
    r->can_state = loadid_candump_read(r->can, &r->can_frame, NULL);
    r->can_line = loadid_candump_reader_line(r->can);
}

static void advance_lcm(loadid_recording_reader_t *r) {
    r->lcm_event = r->lcm ? lcm_eventlog_read_next_event(r->lcm) : NULL;
    if (!r->lcm_event && r->lcm) {
        /* The log ended: cleanly only if the whole file was read. */
        long pos = ftell(r->lcm->f);
        r->lcm_truncated = pos >= 0 && (off_t)pos < r->lcm_size;
    }
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
        struct stat st;
        if (stat(path, &st) != 0) {
            e = errno;
        } else {
            r->lcm_size = st.st_size;
            r->lcm = lcm_eventlog_create(path, "r");
            if (!r->lcm) e = errno ? errno : EIO;
        }
    }
    if (e) {
        if (err && errlen) snprintf(err, errlen, "%s: cannot read: %s", path, strerror(e));
        loadid_recording_reader_close(r);
        return -e;
    }
    advance_can(r);
    advance_lcm(r);
    *out = r;
    return 0;
}

void loadid_recording_reader_close(loadid_recording_reader_t *r) {
    if (!r) return;
    loadid_candump_reader_close(r->can);
    if (r->can_file) fclose(r->can_file);
    if (r->lcm_event) lcm_eventlog_free_event(r->lcm_event);
    if (r->lcm_given) lcm_eventlog_free_event(r->lcm_given);
    if (r->lcm) lcm_eventlog_destroy(r->lcm);
    free(r);
}

int loadid_recording_reader_next(loadid_recording_reader_t *r, loadid_rec_event_t *ev) {
    if (r->lcm_given) {
        lcm_eventlog_free_event(r->lcm_given);
        r->lcm_given = NULL;
    }
    if (r->can_state == -EIO) return -EIO;
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
    const int have_can = r->can_state == 1, have_lcm = r->lcm_event != NULL;
    if (!have_can && !have_lcm) return 0;
    if (have_lcm && (!have_can || r->lcm_event->timestamp <= r->can_frame.t_us)) {
        ev->kind = LOADID_REC_LCM;
        ev->t_us = r->lcm_event->timestamp;
        ev->channel = r->lcm_event->channel;
        ev->data = r->lcm_event->data;
        ev->datalen = r->lcm_event->datalen;
        r->lcm_given = r->lcm_event;
        advance_lcm(r);
        return 1;
    }
    ev->kind = LOADID_REC_CAN;
    ev->t_us = r->can_frame.t_us;
    ev->can = r->can_frame;
    ev->line = r->can_line;
    advance_can(r);
    return 1;
}

int loadid_recording_lcm_truncated(const loadid_recording_reader_t *r) {
    return r->lcm_truncated;
}
