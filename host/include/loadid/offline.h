/*
 * A recording through the pipeline (loadidd --offline, and the demo): the
 * events of can.log and lcm.log in time order, joint_state_t and
 * command_t decoded by the live path's decoder (drivers lcm_wire.h),
 * commands acting at their utime, and the pipeline finished at the last
 * event's time.
 */
#ifndef LOADID_OFFLINE_H
#define LOADID_OFFLINE_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/lcm_eventlog.h"
#include "loadid/pipeline.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a run read, for the messages of loadidd. */
typedef struct {
    int64_t t_first_us;          /* the first event's time [us], INT64_MIN
                                     before one; set before that event is
                                     fed, so a sink may count from it */
    int64_t t_last_us;           /* the last event's time [us] */
    int64_t joint_states;        /* events on LOADID_JOINTS (with the prefix) */
    int64_t joint_states_bad;    /* of which not decodable (the pipeline
                                     counts them in joint_msgs_bad) */
    int64_t commands;            /* events on LOADID_COMMAND */
    int64_t commands_bad;        /* of which not decodable (ignored) */
    int64_t zeros, starts;       /* decoded ZERO and START commands */
    int64_t other_events;        /* events on other channels (ignored) */
    char first_bad[192];         /* the first undecodable message: channel,
                                     byte offset, why; "" when none */
    loadid_eventlog_stats_t lcm; /* reading lcm.log: damage, truncation */
} loadid_offline_report_t;

/* Returns 0, or a negative code with a one-line reason in err (the
 * recording cannot be read: a file missing, lcm.log not an LCM log, a read
 * error). report (may be NULL) is filled as the run goes. */
int loadid_offline_run(loadid_pipeline_t *p, const char *dir, loadid_offline_report_t *report,
                       char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_OFFLINE_H */
