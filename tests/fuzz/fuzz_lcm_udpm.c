/*
 * Fuzz target lcm_udpm: the pure half of LCM's UDP multicast receive side
 * (drivers/src/lcm_udpm.c). Input: one datagram as the daemon's socket
 * receives it, parsed by loadid_lcm_udpm_parse, whose channel and payload
 * must lie inside it, then decoded as the daemon does (joint_state_t and
 * command_t); and the same bytes as an lcm.url, parsed by
 * loadid_lcm_udpm_parse_url, whose result must be a multicast group and a
 * port, or a documented error.
 */
#define _POSIX_C_SOURCE 200809L /* strnlen */
#include <errno.h>
#include <string.h>

#include "fuzz_check.h"
#include "loadid/lcm_udpm.h"
#include "loadid/lcm_wire.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *channel = NULL;
    const uint8_t *payload = NULL;
    size_t len = 0;
    const int rc = loadid_lcm_udpm_parse(data, size, &channel, &payload, &len);
    FUZZ_CHECK(rc == 0 || rc == 1 || rc == -EBADMSG);
    if (rc == 0) {
        const uint8_t *c = (const uint8_t *)channel;
        FUZZ_CHECK(c == data + 8);
        const size_t n = strnlen(channel, size - 8);
        FUZZ_CHECK(n < size - 8 && n <= LOADID_LCM_CHANNEL_MAX);
        FUZZ_CHECK(payload == c + n + 1 && payload + len == data + size);
        loadid_lcm_joint_state_t js;
        loadid_lcm_command_t cmd;
        const int a = loadid_lcm_decode_joint_state(payload, len, &js);
        const int b = loadid_lcm_decode_command(payload, len, &cmd);
        FUZZ_CHECK(a < 0 || b < 0);
        if (a >= 0) FUZZ_CHECK(js.num_joints >= 1 && js.num_joints <= LOADID_LCM_MAX_JOINTS);
        if (b >= 0) FUZZ_CHECK(strlen(cmd.load_name) < LOADID_LCM_NAME_MAX);
    }

    char *url = malloc(size + 1);
    FUZZ_CHECK(url);
    memcpy(url, data, size);
    url[size] = '\0';
    loadid_lcm_udpm_url_t u;
    const int urc = loadid_lcm_udpm_parse_url(url, &u);
    FUZZ_CHECK(urc == 0 || urc == -EINVAL || urc == -EPROTONOSUPPORT);
    if (urc == 0) {
        FUZZ_CHECK(u.group[0] >= 224 && u.group[0] <= 239); /* 224.0.0.0/4 */
        FUZZ_CHECK(u.port >= 1);
        FUZZ_CHECK(u.ttl >= 0 && u.ttl <= 255);
        FUZZ_CHECK(u.recv_buf_size >= 0 && u.recv_buf_size <= (1 << 30));
    }
    free(url);
    return 0;
}
