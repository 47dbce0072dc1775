/*
 * lcm_encode_samples: one fixed instance of each LCM type of docs/INTERFACE.md,
 * encoded by the lcm-gen C code, for the Python cross-check
 * (tests/python/test_lcm_types.py builds the same instances with the
 * lcm-gen Python code and compares bytes). Prints, one a line:
 *
 *   <type> <fingerprint as 16 hex digits> <encoded message in hex>
 *   const <type> <NAME> <value>
 *
 * The field values here are repeated in the Python test; change both.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lcmtypes/loadid_command_t.h"
#include "lcmtypes/loadid_estimate_t.h"
#include "lcmtypes/loadid_joint_state_t.h"
#include "lcmtypes/loadid_load_model_t.h"
#include "lcmtypes/loadid_status_t.h"
#include "lcmtypes/loadid_wrench_t.h"

static void print_hex(const char *type, int64_t hash, const unsigned char *buf, int n) {
    printf("%s %016" PRIx64 " ", type, (uint64_t)hash);
    for (int i = 0; i < n; ++i) {
        printf("%02x", buf[i]);
    }
    printf("\n");
}

/* ENCODE(type, instance): encode into a buffer of its exact size, print. */
#define ENCODE(T, msg)                                                       \
    do {                                                                     \
        int size_ = loadid_##T##_encoded_size(&(msg));                       \
        unsigned char *buf_ = malloc((size_t)size_);                         \
        if (!buf_ || loadid_##T##_encode(buf_, 0, size_, &(msg)) != size_) { \
            fprintf(stderr, "lcm_encode_samples: cannot encode " #T "\n");   \
            return 1;                                                        \
        }                                                                    \
        print_hex(#T, __loadid_##T##_get_hash(), buf_, size_);               \
        free(buf_);                                                          \
    } while (0)

int main(int argc, char **argv) {
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printf(
            "usage: lcm_encode_samples\n"
            "Prints one fixed instance of each loadid LCM type as encoded by lcm-gen's\n"
            "C code ('<type> <fingerprint> <hex>') and the types' constants.\n");
        return 0;
    }
    if (argc > 1) {
        fprintf(stderr, "usage: lcm_encode_samples (see --help)\n");
        return 2;
    }
    double position[3] = {0.1, -0.2, 0.3};
    double setpoint[3] = {0.11, -0.21, 0.31};
    loadid_joint_state_t js = {.utime = INT64_C(1700000000123456),
                               .num_joints = 3,
                               .position = position,
                               .setpoint = setpoint};
    ENCODE(joint_state_t, js);

    char cmd_name[] = "o1 gripper";
    loadid_command_t cmd = {.utime = 42, .action = LOADID_COMMAND_T_START, .load_name = cmd_name};
    ENCODE(command_t, cmd);

    char est_name[] = "o1";
    loadid_estimate_t est;
    memset(&est, 0, sizeof est);
    est.utime = 7;
    est.samples = 1500;
    est.method = LOADID_ESTIMATE_T_RTLS;
    est.state = LOADID_ESTIMATE_T_DONE;
    est.load_name = est_name;
    for (int i = 0; i < 10; ++i) {
        est.phi[i] = i + 0.5;
    }
    for (int i = 0; i < 6; ++i) {
        est.offset[i] = -0.25 * i;
        est.inertia_com[i] = 0.001 * (i + 1);
    }
    est.mass = 1.25;
    est.com[0] = 0.01;
    est.com[1] = -0.02;
    est.com[2] = 0.03;
    est.condition_number = 12.5;
    est.sigma_min = 0.0625;
    est.physically_consistent = 1;
    ENCODE(estimate_t, est);

    loadid_wrench_t w = {.utime = -1, .force = {1, 2, 3}, .torque = {-0.5, 0.25, 0.125}};
    ENCODE(wrench_t, w);

    loadid_status_t st = {.utime = 99,
                          .state = 2,
                          .samples_ok = 1000,
                          .frames_bad = 3,
                          .samples_incomplete = 4,
                          .samples_saturated = 5,
                          .sequence_gaps = 6,
                          .joint_msgs_bad = 7,
                          .loop_us_p50 = 12.5,
                          .loop_us_p99 = 40.25,
                          .loop_us_max = 99.75};
    ENCODE(status_t, st);

    char model_name[] = "o1 model";
    loadid_load_model_t lm;
    memset(&lm, 0, sizeof lm);
    lm.utime = 8;
    lm.method = LOADID_ESTIMATE_T_REFINED;
    lm.load_name = model_name;
    lm.identified = LOADID_LOAD_MODEL_T_MASS | LOADID_LOAD_MODEL_T_COM;
    lm.projected = 1;
    for (int i = 0; i < 10; ++i) {
        lm.phi[i] = 0.75 - i;
        lm.phi_std[i] = 0.015625 * (i + 1);
    }
    lm.mass = 0.75;
    lm.com[0] = -0.125;
    lm.com[1] = 0.25;
    lm.com[2] = 0.5;
    for (int i = 0; i < 6; ++i) {
        lm.inertia_com[i] = 0.002 * (6 - i);
    }
    ENCODE(load_model_t, lm);

    printf("const command_t ZERO %d\n", LOADID_COMMAND_T_ZERO);
    printf("const command_t START %d\n", LOADID_COMMAND_T_START);
    printf("const command_t STOP %d\n", LOADID_COMMAND_T_STOP);
    printf("const command_t RESET %d\n", LOADID_COMMAND_T_RESET);
    printf("const estimate_t RLS %d\n", LOADID_ESTIMATE_T_RLS);
    printf("const estimate_t RIV %d\n", LOADID_ESTIMATE_T_RIV);
    printf("const estimate_t RTLS %d\n", LOADID_ESTIMATE_T_RTLS);
    printf("const estimate_t LS_BATCH %d\n", LOADID_ESTIMATE_T_LS_BATCH);
    printf("const estimate_t TLS_BATCH %d\n", LOADID_ESTIMATE_T_TLS_BATCH);
    printf("const estimate_t REFINED %d\n", LOADID_ESTIMATE_T_REFINED);
    printf("const estimate_t IDLE %d\n", LOADID_ESTIMATE_T_IDLE);
    printf("const estimate_t ZEROING %d\n", LOADID_ESTIMATE_T_ZEROING);
    printf("const estimate_t ESTIMATING %d\n", LOADID_ESTIMATE_T_ESTIMATING);
    printf("const estimate_t DONE %d\n", LOADID_ESTIMATE_T_DONE);
    printf("const estimate_t FAILED %d\n", LOADID_ESTIMATE_T_FAILED);
    printf("const load_model_t MASS %d\n", LOADID_LOAD_MODEL_T_MASS);
    printf("const load_model_t COM %d\n", LOADID_LOAD_MODEL_T_COM);
    printf("const load_model_t INERTIA %d\n", LOADID_LOAD_MODEL_T_INERTIA);
    return fflush(stdout) == 0 ? 0 : 1;
}
