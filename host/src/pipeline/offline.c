/* A recording through the pipeline (offline.h). */
#include "loadid/offline.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "loadid/lcm_wire.h"
#include "loadid/recording.h"
#include "loadid/setup.h"

/* The first undecodable message, for the report. */
static void note_bad(loadid_offline_report_t *r, const loadid_rec_event_t *ev, int rc) {
    if (r->first_bad[0]) return;
    snprintf(r->first_bad, sizeof r->first_bad, "%s at byte %lld of lcm.log: %s", ev->channel,
             (long long)ev->offset, loadid_lcm_strerror(rc));
}

/* Feeds one recording event to the pipeline (channels with
 * lcm.channel_prefix, as live), decoded by the live path's decoder
 * (lcm_wire.h), which bounds num_joints and every string. */
static void feed(loadid_pipeline_t *p, const loadid_rec_event_t *ev, const char *joints,
                 const char *command, loadid_offline_report_t *r) {
    switch (ev->kind) {
        case LOADID_REC_CAN:
            loadid_pipeline_can_frame(p, &ev->can);
            return;
        case LOADID_REC_BAD_LINE:
            loadid_pipeline_bad_frame(p);
            return;
        case LOADID_REC_LCM:
            break;
    }
    const size_t len = ev->datalen < 0 ? 0 : (size_t)ev->datalen;
    if (strcmp(ev->channel, joints) == 0) {
        loadid_lcm_joint_state_t m;
        r->joint_states++;
        const int rc = loadid_lcm_decode_joint_state(ev->data, len, &m);
        if (rc < 0) {
            /* Counted with the refused ones (joint_msgs_bad), as live;
             * NaN and infinities go on, for the pipeline counts them. */
            r->joint_states_bad++;
            note_bad(r, ev, rc);
            loadid_pipeline_joint_state(p, ev->t_us, -1, NULL, NULL);
            return;
        }
        loadid_pipeline_joint_state(p, m.utime, m.num_joints, m.position, m.setpoint);
    } else if (strcmp(ev->channel, command) == 0) {
        loadid_lcm_command_t m;
        r->commands++;
        const int rc = loadid_lcm_decode_command(ev->data, len, &m);
        if (rc < 0) {
            r->commands_bad++;
            note_bad(r, ev, rc);
            return;
        }
        r->zeros += m.action == LOADID_CMD_ZERO;
        r->starts += m.action == LOADID_CMD_START;
        /* Commands act when their utime is reached: the log's order. */
        loadid_pipeline_command(p, ev->t_us, m.action, m.load_name);
    } else {
        r->other_events++;
    }
}

int loadid_offline_run(loadid_pipeline_t *p, const char *dir, loadid_offline_report_t *report,
                       char *err, size_t errlen) {
    loadid_offline_report_t local;
    loadid_offline_report_t *r = report ? report : &local;
    memset(r, 0, sizeof *r);
    r->t_first_us = r->t_last_us = INT64_MIN;
    loadid_recording_reader_t *rec = NULL;
    int rc = loadid_recording_reader_open(dir, &rec, err, errlen);
    if (rc != 0) return rc;
    loadid_rec_event_t ev;
    char joints[128], command[128];
    loadid_config_channel(loadid_pipeline_config(p), "LOADID_JOINTS", joints, sizeof joints);
    loadid_config_channel(loadid_pipeline_config(p), "LOADID_COMMAND", command, sizeof command);
    while ((rc = loadid_recording_reader_next(rec, &ev)) == 1) {
        if (ev.kind != LOADID_REC_BAD_LINE) {
            if (r->t_first_us == INT64_MIN) r->t_first_us = ev.t_us;
            if (ev.t_us > r->t_last_us) r->t_last_us = ev.t_us;
        }
        feed(p, &ev, joints, command, r);
    }
    loadid_recording_lcm_stats(rec, &r->lcm);
    if (rc < 0) {
        const char *lcm_err = loadid_recording_lcm_error(rec);
        if (*lcm_err)
            snprintf(err, errlen, "%s/lcm.log: %s", dir, lcm_err);
        else
            snprintf(err, errlen, "%s/can.log: read error", dir);
    }
    loadid_recording_reader_close(rec);
    if (rc < 0) return rc;
    loadid_pipeline_finish(p, r->t_last_us);
    return 0;
}
