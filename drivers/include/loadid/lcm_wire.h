/*
 * The six LCM types of docs/INTERFACE.md (proto/<type>.lcm, package loadid) on the
 * wire, hand-written on fixed buffers: encode into a caller's buffer,
 * decode a received buffer into fixed-size structs. Nothing here allocates
 * (the loop of loadidd uses these instead of lcm-gen's C, whose *_publish
 * and decoders call malloc on every message). The bytes are lcm-gen's
 * (tests/unit/test_lcm_wire.c checks them against its generated C):
 *
 *   8-byte fingerprint, then the fields in declaration order, big-endian;
 *   boolean as one int8; string as int32 length (including the NUL), the
 *   bytes, the NUL; a variable-length array has its count field earlier.
 *
 * The fingerprint is lcm-gen's: a hash over the member names, the types
 * of the primitive members and the dimensions (not the type's name), then
 * rotated left by one bit (loadid_lcm_fingerprint).
 *
 * Decoding validates everything and never reads past len: the exact
 * length, the fingerprint, num_joints in 1..LOADID_LCM_MAX_JOINTS, a
 * string's length (1..LOADID_LCM_NAME_MAX including the NUL), its NUL
 * terminator and no NUL inside. NaN and infinities are decoded (the
 * pipeline counts them) and reported by LOADID_LCM_NONFINITE.
 */
#ifndef LOADID_LCM_WIRE_H
#define LOADID_LCM_WIRE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* At most this many joints in a joint_state_t: LOADID_MAX_JOINTS of the
 * core (firmware chain.h; host/src/daemon/lcm_inputs.c asserts they agree). */
#define LOADID_LCM_MAX_JOINTS 16
/* A load_name's room including its NUL (LOADID_LOAD_NAME_MAX of the
 * pipeline): at most 127 characters. */
#define LOADID_LCM_NAME_MAX 128

/* Largest encoded sizes [bytes]. */
#define LOADID_LCM_JOINT_STATE_MAX (8 + 8 + 4 + 2 * 8 * LOADID_LCM_MAX_JOINTS)
#define LOADID_LCM_COMMAND_MAX (8 + 8 + 1 + 4 + LOADID_LCM_NAME_MAX)
#define LOADID_LCM_ESTIMATE_MAX (8 + 8 + 8 + 1 + 1 + 4 + LOADID_LCM_NAME_MAX + 8 * 28 + 1)
#define LOADID_LCM_WRENCH_SIZE (8 + 8 + 8 * 6)
#define LOADID_LCM_STATUS_SIZE (8 + 8 + 1 + 8 * 6 + 8 * 3)
#define LOADID_LCM_LOAD_MODEL_MAX (8 + 8 + 1 + 4 + LOADID_LCM_NAME_MAX + 1 + 1 + 8 * 30)

/* Return codes (-1401.., loadid/error_text.h; loadid_lcm_strerror). */
enum {
    LOADID_LCM_NONFINITE = 1,        /* decoded; a double is NaN or infinite */
    LOADID_LCM_ESHORT = -1401,       /* buffer ends inside the message */
    LOADID_LCM_ELONG = -1402,        /* bytes after the message */
    LOADID_LCM_EFINGERPRINT = -1403, /* another type (or another version of it) */
    LOADID_LCM_ECOUNT = -1404,       /* num_joints outside 1..LOADID_LCM_MAX_JOINTS */
    LOADID_LCM_ESTRING = -1405,      /* string length, NUL terminator or NUL inside */
    LOADID_LCM_ENOSPC = -1406,       /* encode: the buffer is too small */
    LOADID_LCM_EINVAL = -1407        /* encode: a field out of range (count, name) */
};

typedef enum {
    LOADID_LCM_JOINT_STATE,
    LOADID_LCM_COMMAND,
    LOADID_LCM_ESTIMATE,
    LOADID_LCM_WRENCH,
    LOADID_LCM_STATUS,
    LOADID_LCM_LOAD_MODEL
} loadid_lcm_type_t;

typedef struct {
    int64_t utime;                          /* [us] sample time */
    int32_t num_joints;                     /* 1 .. LOADID_LCM_MAX_JOINTS */
    double position[LOADID_LCM_MAX_JOINTS]; /* [rad or m], num_joints used */
    double setpoint[LOADID_LCM_MAX_JOINTS]; /* [rad or m], num_joints used */
} loadid_lcm_joint_state_t;

typedef struct {
    int64_t utime; /* [us] */
    int8_t action; /* ZERO 1, START 2, STOP 3, RESET 4 */
    char load_name[LOADID_LCM_NAME_MAX];
} loadid_lcm_command_t;

typedef struct {
    int64_t utime; /* [us] newest sample used */
    int64_t samples;
    int8_t method; /* RLS 1, RIV 2, RTLS 3, LS_BATCH 4, TLS_BATCH 5 */
    int8_t state;  /* IDLE 0 .. FAILED 4 */
    char load_name[LOADID_LCM_NAME_MAX];
    double phi[10];        /* eq. (5) [kg, kg m, kg m^2] */
    double offset[6];      /* [N, N m] */
    double mass;           /* [kg] */
    double com[3];         /* [m] */
    double inertia_com[6]; /* [kg m^2] */
    double condition_number;
    double sigma_min;
    int8_t physically_consistent; /* LCM boolean: 0 or 1 (any non-zero decoded as is) */
} loadid_lcm_estimate_t;

typedef struct {
    int64_t utime;    /* [us] */
    double force[3];  /* [N] */
    double torque[3]; /* [N m] */
} loadid_lcm_wrench_t;

typedef struct {
    int64_t utime; /* [us] */
    int8_t state;
    int64_t samples_ok, frames_bad, samples_incomplete, samples_saturated, sequence_gaps,
        joint_msgs_bad;
    double loop_us_p50, loop_us_p99, loop_us_max; /* [us] */
} loadid_lcm_status_t;

/* load_model_t, channel LOADID_MODEL: the load a controller should use. */
typedef struct {
    int64_t utime; /* [us] newest sample used */
    int8_t method; /* the estimate it was made from: RLS 1 .. REFINED 6 */
    char load_name[LOADID_LCM_NAME_MAX];
    int8_t identified;     /* bits MASS 1 | COM 2 | INERTIA 4: the groups determined */
    int8_t projected;      /* LCM boolean: phi differs from the method's estimate */
    double phi[10];        /* eq. (5), physically consistent [kg, kg m, kg m^2] */
    double phi_std[10];    /* one standard deviation of the estimate's elements */
    double mass;           /* [kg] */
    double com[3];         /* [m], in S */
    double inertia_com[6]; /* [kg m^2] about the COM, axes of S */
} loadid_lcm_load_model_t;

/* The type's 8-byte fingerprint as lcm-gen computes it (the first 8 bytes
 * of every message, big-endian). */
uint64_t loadid_lcm_fingerprint(loadid_lcm_type_t type);

/* Encoders: write the message into buf (cap bytes). Return the number of
 * bytes written (> 0), LOADID_LCM_ENOSPC, or LOADID_LCM_EINVAL
 * (num_joints out of range; a load_name not NUL-terminated within
 * LOADID_LCM_NAME_MAX). */
int loadid_lcm_encode_joint_state(const loadid_lcm_joint_state_t *m, uint8_t *buf, size_t cap);
int loadid_lcm_encode_command(const loadid_lcm_command_t *m, uint8_t *buf, size_t cap);
int loadid_lcm_encode_estimate(const loadid_lcm_estimate_t *m, uint8_t *buf, size_t cap);
int loadid_lcm_encode_wrench(const loadid_lcm_wrench_t *m, uint8_t *buf, size_t cap);
int loadid_lcm_encode_status(const loadid_lcm_status_t *m, uint8_t *buf, size_t cap);
int loadid_lcm_encode_load_model(const loadid_lcm_load_model_t *m, uint8_t *buf, size_t cap);

/* Decoders: buf holds exactly one message of len bytes. Return 0,
 * LOADID_LCM_NONFINITE (decoded; a double is not finite), or a negative
 * LOADID_LCM_E* code (out is then unspecified). */
int loadid_lcm_decode_joint_state(const uint8_t *buf, size_t len, loadid_lcm_joint_state_t *out);
int loadid_lcm_decode_command(const uint8_t *buf, size_t len, loadid_lcm_command_t *out);
int loadid_lcm_decode_estimate(const uint8_t *buf, size_t len, loadid_lcm_estimate_t *out);
int loadid_lcm_decode_wrench(const uint8_t *buf, size_t len, loadid_lcm_wrench_t *out);
int loadid_lcm_decode_status(const uint8_t *buf, size_t len, loadid_lcm_status_t *out);
int loadid_lcm_decode_load_model(const uint8_t *buf, size_t len, loadid_lcm_load_model_t *out);

/* A one-line description of a return code above. */
const char *loadid_lcm_strerror(int code);

/* The name of estimate_t's and status_t's state constants (IDLE 0 ..
 * FAILED 4, docs/INTERFACE.md): "IDLE", ..., "FAILED"; "?" for another
 * value. The one table of them, for every program's messages. */
const char *loadid_lcm_state_name(int state);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_LCM_WIRE_H */
