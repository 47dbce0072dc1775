/*
 * Fuzz target lcm_wire: the decoders of the six LCM types on fixed buffers
 * (drivers/src/lcm_wire.c). Input: one message as received (it starts with
 * its type's 8-byte fingerprint). Every decoder gets it; at most one may
 * take it (the fingerprints differ), and a message taken must encode back
 * to exactly the same bytes: decode and encode are inverse on valid input,
 * so nothing is lost or invented.
 */
#include <math.h>
#include <string.h>

#include "fuzz_check.h"
#include "loadid/lcm_wire.h"

static void check_code(int rc) {
    FUZZ_CHECK(rc == 0 || rc == LOADID_LCM_NONFINITE || rc == LOADID_LCM_ESHORT ||
               rc == LOADID_LCM_ELONG || rc == LOADID_LCM_EFINGERPRINT || rc == LOADID_LCM_ECOUNT ||
               rc == LOADID_LCM_ESTRING);
}

static int finite_all(const double *v, int n) {
    for (int i = 0; i < n; ++i) {
        if (!isfinite(v[i])) return 0;
    }
    return 1;
}

/* rc of a decoder; when it took the message, the re-encoded bytes must be
 * the input's. */
#define ROUND_TRIP(type, cap, decode, encode, nonfinite_expr)                       \
    do {                                                                            \
        type m;                                                                     \
        memset(&m, 0x5A, sizeof m);                                                 \
        const int rc = decode(data, size, &m);                                      \
        check_code(rc);                                                             \
        if (rc >= 0) {                                                              \
            ++taken;                                                                \
            FUZZ_CHECK((rc == LOADID_LCM_NONFINITE) == (nonfinite_expr));           \
            uint8_t out[cap];                                                       \
            const int n = encode(&m, out, sizeof out);                              \
            FUZZ_CHECK(n > 0 && (size_t)n == size && memcmp(out, data, size) == 0); \
            FUZZ_CHECK(encode(&m, out, size - 1) == LOADID_LCM_ENOSPC);             \
        }                                                                           \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    int taken = 0;
    ROUND_TRIP(loadid_lcm_joint_state_t, LOADID_LCM_JOINT_STATE_MAX, loadid_lcm_decode_joint_state,
               loadid_lcm_encode_joint_state,
               !(finite_all(m.position, m.num_joints) && finite_all(m.setpoint, m.num_joints)));
    ROUND_TRIP(loadid_lcm_command_t, LOADID_LCM_COMMAND_MAX, loadid_lcm_decode_command,
               loadid_lcm_encode_command, 0);
    ROUND_TRIP(loadid_lcm_estimate_t, LOADID_LCM_ESTIMATE_MAX, loadid_lcm_decode_estimate,
               loadid_lcm_encode_estimate,
               !(finite_all(m.phi, 10) && finite_all(m.offset, 6) && finite_all(&m.mass, 1) &&
                 finite_all(m.com, 3) && finite_all(m.inertia_com, 6) &&
                 finite_all(&m.condition_number, 1) && finite_all(&m.sigma_min, 1)));
    ROUND_TRIP(loadid_lcm_wrench_t, LOADID_LCM_WRENCH_SIZE, loadid_lcm_decode_wrench,
               loadid_lcm_encode_wrench, !(finite_all(m.force, 3) && finite_all(m.torque, 3)));
    ROUND_TRIP(loadid_lcm_status_t, LOADID_LCM_STATUS_SIZE, loadid_lcm_decode_status,
               loadid_lcm_encode_status,
               !(finite_all(&m.loop_us_p50, 1) && finite_all(&m.loop_us_p99, 1) &&
                 finite_all(&m.loop_us_max, 1)));
    ROUND_TRIP(loadid_lcm_load_model_t, LOADID_LCM_LOAD_MODEL_MAX, loadid_lcm_decode_load_model,
               loadid_lcm_encode_load_model,
               !(finite_all(m.phi, 10) && finite_all(m.phi_std, 10) && finite_all(&m.mass, 1) &&
                 finite_all(m.com, 3) && finite_all(m.inertia_com, 6)));
    FUZZ_CHECK(taken <= 1);
    return 0;
}
