/* A recording through the pipeline (offline.h). */
#include "loadid/offline.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "lcmtypes/loadid_command_t.h"
#include "lcmtypes/loadid_joint_state_t.h"
#include "loadid/recording.h"
#include "loadid/setup.h"

/* Feeds one recording event to the pipeline (channels with
 * lcm.channel_prefix, as live). */
static void feed(loadid_pipeline_t *p, const loadid_rec_event_t *ev, const char *joints,
                 const char *command) {
    switch (ev->kind) {
        case LOADID_REC_CAN: loadid_pipeline_can_frame(p, &ev->can); return;
        case LOADID_REC_BAD_LINE: loadid_pipeline_bad_frame(p); return;
        case LOADID_REC_LCM: break;
    }
    if (strcmp(ev->channel, joints) == 0) {
        loadid_joint_state_t m;
        if (loadid_joint_state_t_decode(ev->data, 0, ev->datalen, &m) < 0) {
            loadid_pipeline_joint_state(p, ev->t_us, -1, NULL, NULL); /* counted bad */
            return;
        }
        loadid_pipeline_joint_state(p, m.utime, m.num_joints, m.position, m.setpoint);
        loadid_joint_state_t_decode_cleanup(&m);
    } else if (strcmp(ev->channel, command) == 0) {
        loadid_command_t m;
        if (loadid_command_t_decode(ev->data, 0, ev->datalen, &m) < 0) return;
        /* Commands act when their utime is reached: the log's order. */
        loadid_pipeline_command(p, ev->t_us, m.action, m.load_name);
        loadid_command_t_decode_cleanup(&m);
    }
}

int loadid_offline_run(loadid_pipeline_t *p, const char *dir, int *lcm_truncated, char *err,
                       size_t errlen) {
    loadid_recording_reader_t *rec = NULL;
    int rc = loadid_recording_reader_open(dir, &rec, err, errlen);
    if (rc != 0) return rc;
    loadid_rec_event_t ev;
    int64_t last = INT64_MIN;
    char joints[128], command[128];
    loadid_config_channel(loadid_pipeline_config(p), "LOADID_JOINTS", joints, sizeof joints);
    loadid_config_channel(loadid_pipeline_config(p), "LOADID_COMMAND", command, sizeof command);
    while ((rc = loadid_recording_reader_next(rec, &ev)) == 1) {
        feed(p, &ev, joints, command);
        if (ev.kind != LOADID_REC_BAD_LINE && ev.t_us > last) last = ev.t_us;
    }
    if (lcm_truncated) *lcm_truncated = loadid_recording_lcm_truncated(rec);
    loadid_recording_reader_close(rec);
    if (rc < 0) {
        snprintf(err, errlen, "%s/can.log: read error", dir);
        return rc;
    }
    loadid_pipeline_finish(p, last);
    return 0;
}
