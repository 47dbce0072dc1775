/*
 * What the daemon reads from LCM: joint_state_t on LOADID_JOINTS and
 * command_t on LOADID_COMMAND (with lcm.channel_prefix), into the
 * pipeline. A command acts at its own utime, as in a recording, unless
 * that is more than a second from now (a sender's clock off): then now,
 * and its state change still answers with its own utime. With
 * lcm.command_sources, a command from a sender not listed is refused
 * before it is decoded, counted and logged. Other channels (the daemon's
 * own output looped back by multicast, anyone else's) are ignored.
 */
#ifndef LOADID_LCM_INPUTS_H
#define LOADID_LCM_INPUTS_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/config.h"
#include "loadid/lcm_wire.h"
#include "loadid/pipeline.h"

typedef struct {
    const loadid_config_t *cfg;
    loadid_pipeline_t *pipe;
    const char *joints, *command; /* the channels' names */
    int take_joints;              /* 0: joint states come from elsewhere (a replay) */
    double command_warned_us;     /* throttles the log line of a malformed command */
    int64_t commands_refused;     /* command_t from senders not in lcm.command_sources */
    double refused_warned_us;     /* throttles their log line */
    struct {
        int64_t acted, sent;
    } moved[8]; /* commands whose utime was too far from now:
                                     the time they acted at, and their own */
    int moved_next;
    loadid_lcm_joint_state_t js; /* decoded here: two arrays of 16 doubles */
} loadid_lcm_inputs_t;

void loadid_lcm_inputs_init(loadid_lcm_inputs_t *in, const loadid_config_t *cfg,
                            loadid_pipeline_t *pipe, const char *joints, const char *command,
                            int take_joints);

/* One message (lcm_link.h's callback; ctx the loadid_lcm_inputs_t).
 * Returns 1 when it was an input. */
int loadid_lcm_inputs_message(void *ctx, const char *channel, const uint8_t *data, size_t len,
                              uint32_t source);

/* The utime a state change at utime answers with: the command's own when
 * a command made it acting at another time, else utime. */
int64_t loadid_lcm_inputs_answer_utime(const loadid_lcm_inputs_t *in, int64_t utime);

#endif /* LOADID_LCM_INPUTS_H */
