/* Joint states and commands from LCM into the pipeline (lcm_inputs.h). */
#include "lcm_inputs.h"

#include <string.h>

#include "clock.h"
#include "log.h"
#include "loadid/chain.h"
#include "loadid/ipv4_allow.h"

_Static_assert(LOADID_LCM_MAX_JOINTS == LOADID_MAX_JOINTS, "joint_state_t holds every joint");

void loadid_lcm_inputs_init(loadid_lcm_inputs_t *in, const loadid_config_t *cfg,
                            loadid_pipeline_t *pipe, const char *joints, const char *command,
                            int take_joints) {
    memset(in, 0, sizeof *in);
    in->cfg = cfg;
    in->pipe = pipe;
    in->joints = joints;
    in->command = command;
    in->take_joints = take_joints;
}

/* A malformed joint state is counted with the refused ones
 * (status_t.joint_msgs_bad); NaN and infinities go on, for the pipeline
 * counts them. */
static void on_joints(loadid_lcm_inputs_t *in, const uint8_t *data, size_t len) {
    if (loadid_lcm_decode_joint_state(data, len, &in->js) < 0)
        loadid_pipeline_joint_state(in->pipe, loadid_wall_us(), 0, NULL, NULL);
    else
        loadid_pipeline_joint_state(in->pipe, in->js.utime, in->js.num_joints, in->js.position,
                                    in->js.setpoint);
}

static void on_command(loadid_lcm_inputs_t *in, const uint8_t *data, size_t len) {
    loadid_lcm_command_t m;
    const int rc = loadid_lcm_decode_command(data, len, &m);
    if (rc < 0) {
        const double now_mono = loadid_mono_us();
        if (now_mono - in->command_warned_us > 1e6) { /* at most one line a second */
            loadidd_log("%s: %s; ignored", in->command, loadid_lcm_strerror(rc));
            in->command_warned_us = now_mono;
        }
        return;
    }
    /* A command acts at its own utime, as in a recording, unless that is
     * more than a second away from now (a sender's clock off): then now. */
    const int64_t now = loadid_wall_us();
    const int64_t t = m.utime > now - 1000000 && m.utime < now + 1000000 ? m.utime : now;
    if (t != m.utime) { /* its state change still answers with its own utime */
        in->moved[in->moved_next].acted = t;
        in->moved[in->moved_next].sent = m.utime;
        in->moved_next = (in->moved_next + 1) % 8;
    }
    loadid_pipeline_command(in->pipe, t, m.action, m.load_name);
}

/* lcm.command_sources: whether a command from source (IPv4, host order)
 * may act. One that may not is logged with its sender and the count so
 * far (the first at once, then at most a line a second). status_t has no
 * field for it (its fields are fixed; frames_bad and joint_msgs_bad count
 * other inputs' faults). */
static int command_allowed(loadid_lcm_inputs_t *in, uint32_t source) {
    if (loadid_ipv4_allow_match(in->cfg->lcm_command_sources, in->cfg->lcm_num_command_sources,
                                source))
        return 1;
    const double now = loadid_mono_us();
    if (in->commands_refused++ == 0 || now - in->refused_warned_us > 1e6) {
        loadidd_log(
            "%s from %u.%u.%u.%u refused: not in lcm.command_sources (%lld refused so "
            "far)",
            in->command, source >> 24, (source >> 16) & 255, (source >> 8) & 255, source & 255,
            (long long)in->commands_refused);
        in->refused_warned_us = now;
    }
    return 0;
}

int loadid_lcm_inputs_message(void *ctx, const char *channel, const uint8_t *data, size_t len,
                              uint32_t source) {
    loadid_lcm_inputs_t *in = ctx;
    if (strcmp(channel, in->joints) == 0) {
        if (!in->take_joints) return 0;
        on_joints(in, data, len);
    } else if (strcmp(channel, in->command) == 0) {
        if (command_allowed(in, source)) on_command(in, data, len);
    } else {
        return 0;
    }
    return 1;
}

int64_t loadid_lcm_inputs_answer_utime(const loadid_lcm_inputs_t *in, int64_t utime) {
    int64_t answer = utime;
    for (int i = 0; i < 8; ++i)
        if (in->moved[i].acted == utime && utime != 0) answer = in->moved[i].sent;
    return answer;
}
