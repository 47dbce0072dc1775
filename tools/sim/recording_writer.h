/*
 * Writes a recording folder (docs/INTERFACE.md "Recordings"):
 * can.log in the candump format of can-utils and lcm.log as an LCM event
 * log (lcm-logger's format, through liblcm's eventlog API), with the
 * channels LOADID_JOINTS (joint_state_t) and LOADID_COMMAND (command_t).
 */
#ifndef LOADID_SIM_RECORDING_WRITER_H
#define LOADID_SIM_RECORDING_WRITER_H

#include <stdint.h>
#include <stdio.h>

#include "loadid/can_frame.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct loadid_recording_writer loadid_recording_writer_t; /* opaque */

/* Whether dir may receive a new recording: it does not exist, or is an
 * empty directory, or force is set and it is a directory (its can.log,
 * lcm.log and truth.yaml are then overwritten, other files stay). A
 * recording is data that may have cost a session on the robot: the
 * programs never overwrite one unasked. Returns 0, -EEXIST (not empty and
 * not force), -ENOTDIR, or another -errno, with a one-line message in err
 * that says how to overwrite (force_option, e.g. "--force"). */
int loadid_recording_dir_check(const char *dir, int force, const char *force_option, char *err,
                               size_t errlen);

/* Creates dir (if missing) and opens dir/can.log and dir/lcm.log for
 * writing. ifname is the interface named on every can.log line. Returns
 * 0, or -errno with a message in err. */
int loadid_recording_open(const char *dir, const char *ifname, loadid_recording_writer_t **out,
                          char *err, size_t errlen);

int loadid_recording_can(loadid_recording_writer_t *w, const loadid_can_frame_t *frame);

/* A joint_state_t on LOADID_JOINTS, logged at utime. */
int loadid_recording_joints(loadid_recording_writer_t *w, int64_t utime, int num_joints,
                            const double *position, const double *setpoint);

/* A command_t on LOADID_COMMAND (action: 1 ZERO, 2 START, 3 STOP, 4 RESET). */
int loadid_recording_command(loadid_recording_writer_t *w, int64_t utime, int action,
                             const char *load_name);

/* Counts of what was written. */
typedef struct {
    int64_t can_frames, joint_msgs, commands;
} loadid_recording_counts_t;
void loadid_recording_counts(const loadid_recording_writer_t *w, loadid_recording_counts_t *c);

/* Flushes and closes both files. Returns 0 or -errno (a write failed). */
int loadid_recording_close(loadid_recording_writer_t *w);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SIM_RECORDING_WRITER_H */
