/* The LCM types on fixed buffers (lcm_wire.h). */
#define _POSIX_C_SOURCE 200809L /* strnlen */
#include "loadid/lcm_wire.h"

#include <math.h>
#include <string.h>

/* ------------------------------------------------------- fingerprints */

/* A member as lcm-gen sees it: name, type, and at most one dimension
 * (fixed: its size as written; variable: the name of its count member). */
typedef struct {
    const char *name, *type, *dim;
    int dim_var;
} member_t;

/* lcm-gen's hash (lcmgen.c: hash_update, hash_string_update,
 * lcm_struct_hash): v = ((v << 8) ^ (v >> 55)) + c, on int64_t, over a start value of
 * 0x12345678; per member its name, the type name when primitive (every
 * member here is), the number of dimensions, and per dimension its mode
 * (0 constant, 1 variable) and size string. Strings go in as their length,
 * then their characters. The struct's own name is deliberately not
 * hashed. */
static uint64_t hash_char(uint64_t v, char c) {
    /* lcm-gen's v is an int64_t: v >> 55 is an arithmetic shift there
     * (gcc's), so the sign bit fills the top 55 bits. */
    uint64_t shifted = v >> 55;
    if (v >> 63) shifted |= ~(uint64_t)0 << 9;
    return ((v << 8) ^ shifted) + (uint64_t)(int64_t)c;
}

static uint64_t hash_string(uint64_t v, const char *s) {
    v = hash_char(v, (char)strlen(s));
    for (; *s; ++s) v = hash_char(v, *s);
    return v;
}

static uint64_t struct_hash(const member_t *m, int n) {
    uint64_t v = 0x12345678;
    for (int i = 0; i < n; ++i) {
        v = hash_string(v, m[i].name);
        v = hash_string(v, m[i].type);
        v = hash_char(v, (char)(m[i].dim ? 1 : 0));
        if (m[i].dim) {
            v = hash_char(v, (char)m[i].dim_var);
            v = hash_string(v, m[i].dim);
        }
    }
    /* The generated __*_hash_recursive: no nested types to add, then a
     * rotation left by one bit. */
    return (v << 1) + ((v >> 63) & 1);
}

static const member_t kJointState[] = {
    {"utime", "int64_t", NULL, 0},
    {"num_joints", "int32_t", NULL, 0},
    {"position", "double", "num_joints", 1},
    {"setpoint", "double", "num_joints", 1},
};
static const member_t kCommand[] = {
    {"utime", "int64_t", NULL, 0},
    {"action", "int8_t", NULL, 0},
    {"load_name", "string", NULL, 0},
};
static const member_t kEstimate[] = {
    {"utime", "int64_t", NULL, 0},
    {"samples", "int64_t", NULL, 0},
    {"method", "int8_t", NULL, 0},
    {"state", "int8_t", NULL, 0},
    {"load_name", "string", NULL, 0},
    {"phi", "double", "10", 0},
    {"offset", "double", "6", 0},
    {"mass", "double", NULL, 0},
    {"com", "double", "3", 0},
    {"inertia_com", "double", "6", 0},
    {"condition_number", "double", NULL, 0},
    {"sigma_min", "double", NULL, 0},
    {"physically_consistent", "boolean", NULL, 0},
};
static const member_t kWrench[] = {
    {"utime", "int64_t", NULL, 0},
    {"force", "double", "3", 0},
    {"torque", "double", "3", 0},
};
static const member_t kStatus[] = {
    {"utime", "int64_t", NULL, 0},
    {"state", "int8_t", NULL, 0},
    {"samples_ok", "int64_t", NULL, 0},
    {"frames_bad", "int64_t", NULL, 0},
    {"samples_incomplete", "int64_t", NULL, 0},
    {"samples_saturated", "int64_t", NULL, 0},
    {"sequence_gaps", "int64_t", NULL, 0},
    {"joint_msgs_bad", "int64_t", NULL, 0},
    {"loop_us_p50", "double", NULL, 0},
    {"loop_us_p99", "double", NULL, 0},
    {"loop_us_max", "double", NULL, 0},
};
static const member_t kLoadModel[] = {
    {"utime", "int64_t", NULL, 0},     {"method", "int8_t", NULL, 0},
    {"load_name", "string", NULL, 0},  {"identified", "int8_t", NULL, 0},
    {"projected", "boolean", NULL, 0}, {"phi", "double", "10", 0},
    {"phi_std", "double", "10", 0},    {"mass", "double", NULL, 0},
    {"com", "double", "3", 0},         {"inertia_com", "double", "6", 0},
};

#define N(a) ((int)(sizeof(a) / sizeof((a)[0])))

uint64_t loadid_lcm_fingerprint(loadid_lcm_type_t type) {
    /* Computed once per type (a few hundred operations, no allocation). */
    enum { NTYPES = 6 };
    static uint64_t cache[NTYPES];
    static int have[NTYPES];
    static const member_t *const members[NTYPES] = {kJointState, kCommand, kEstimate,
                                                    kWrench,     kStatus,  kLoadModel};
    static const int counts[NTYPES] = {N(kJointState), N(kCommand), N(kEstimate),
                                       N(kWrench),     N(kStatus),  N(kLoadModel)};
    const unsigned t = (unsigned)type;
    if (t >= NTYPES) return 0;
    if (!have[t]) cache[t] = struct_hash(members[t], counts[t]), have[t] = 1;
    return cache[t];
}

/* ------------------------------------------------------------ writing */

typedef struct {
    uint8_t *p;
    size_t cap, n;
    int full;
} wr_t;

static void put_u64(wr_t *w, uint64_t v) {
    if (w->cap - w->n < 8) {
        w->full = 1;
        return;
    }
    for (int i = 0; i < 8; ++i) w->p[w->n++] = (uint8_t)(v >> (56 - 8 * i));
}
static void put_i64(wr_t *w, int64_t v) {
    put_u64(w, (uint64_t)v);
}
static void put_i32(wr_t *w, int32_t v) {
    if (w->cap - w->n < 4) {
        w->full = 1;
        return;
    }
    const uint32_t u = (uint32_t)v;
    for (int i = 0; i < 4; ++i) w->p[w->n++] = (uint8_t)(u >> (24 - 8 * i));
}
static void put_i8(wr_t *w, int8_t v) {
    if (w->cap == w->n) {
        w->full = 1;
        return;
    }
    w->p[w->n++] = (uint8_t)v;
}
static void put_f64s(wr_t *w, const double *v, int k) {
    for (int i = 0; i < k; ++i) {
        uint64_t u;
        memcpy(&u, &v[i], 8); /* IEEE 754 binary64, as LCM sends it */
        put_u64(w, u);
    }
}
/* LCM string: int32 length including the NUL, the bytes, the NUL. */
static int put_string(wr_t *w, const char *s, size_t room) {
    const size_t len = strnlen(s, room);
    if (len == room) return LOADID_LCM_EINVAL;
    put_i32(w, (int32_t)(len + 1));
    if (w->cap - w->n < len + 1) {
        w->full = 1;
        return 0;
    }
    memcpy(w->p + w->n, s, len + 1);
    w->n += len + 1;
    return 0;
}

static int finish(const wr_t *w) {
    return w->full ? LOADID_LCM_ENOSPC : (int)w->n;
}

static wr_t writer(loadid_lcm_type_t t, uint8_t *buf, size_t cap) {
    wr_t w = {buf, buf ? cap : 0, 0, 0};
    put_u64(&w, loadid_lcm_fingerprint(t));
    return w;
}

int loadid_lcm_encode_joint_state(const loadid_lcm_joint_state_t *m, uint8_t *buf, size_t cap) {
    if (m->num_joints < 1 || m->num_joints > LOADID_LCM_MAX_JOINTS) return LOADID_LCM_EINVAL;
    wr_t w = writer(LOADID_LCM_JOINT_STATE, buf, cap);
    put_i64(&w, m->utime);
    put_i32(&w, m->num_joints);
    put_f64s(&w, m->position, m->num_joints);
    put_f64s(&w, m->setpoint, m->num_joints);
    return finish(&w);
}

int loadid_lcm_encode_command(const loadid_lcm_command_t *m, uint8_t *buf, size_t cap) {
    wr_t w = writer(LOADID_LCM_COMMAND, buf, cap);
    put_i64(&w, m->utime);
    put_i8(&w, m->action);
    if (put_string(&w, m->load_name, sizeof m->load_name)) return LOADID_LCM_EINVAL;
    return finish(&w);
}

int loadid_lcm_encode_estimate(const loadid_lcm_estimate_t *m, uint8_t *buf, size_t cap) {
    wr_t w = writer(LOADID_LCM_ESTIMATE, buf, cap);
    put_i64(&w, m->utime);
    put_i64(&w, m->samples);
    put_i8(&w, m->method);
    put_i8(&w, m->state);
    if (put_string(&w, m->load_name, sizeof m->load_name)) return LOADID_LCM_EINVAL;
    put_f64s(&w, m->phi, 10);
    put_f64s(&w, m->offset, 6);
    put_f64s(&w, &m->mass, 1);
    put_f64s(&w, m->com, 3);
    put_f64s(&w, m->inertia_com, 6);
    put_f64s(&w, &m->condition_number, 1);
    put_f64s(&w, &m->sigma_min, 1);
    put_i8(&w, m->physically_consistent);
    return finish(&w);
}

int loadid_lcm_encode_wrench(const loadid_lcm_wrench_t *m, uint8_t *buf, size_t cap) {
    wr_t w = writer(LOADID_LCM_WRENCH, buf, cap);
    put_i64(&w, m->utime);
    put_f64s(&w, m->force, 3);
    put_f64s(&w, m->torque, 3);
    return finish(&w);
}

int loadid_lcm_encode_status(const loadid_lcm_status_t *m, uint8_t *buf, size_t cap) {
    wr_t w = writer(LOADID_LCM_STATUS, buf, cap);
    put_i64(&w, m->utime);
    put_i8(&w, m->state);
    put_i64(&w, m->samples_ok);
    put_i64(&w, m->frames_bad);
    put_i64(&w, m->samples_incomplete);
    put_i64(&w, m->samples_saturated);
    put_i64(&w, m->sequence_gaps);
    put_i64(&w, m->joint_msgs_bad);
    put_f64s(&w, &m->loop_us_p50, 1);
    put_f64s(&w, &m->loop_us_p99, 1);
    put_f64s(&w, &m->loop_us_max, 1);
    return finish(&w);
}

int loadid_lcm_encode_load_model(const loadid_lcm_load_model_t *m, uint8_t *buf, size_t cap) {
    wr_t w = writer(LOADID_LCM_LOAD_MODEL, buf, cap);
    put_i64(&w, m->utime);
    put_i8(&w, m->method);
    if (put_string(&w, m->load_name, sizeof m->load_name)) return LOADID_LCM_EINVAL;
    put_i8(&w, m->identified);
    put_i8(&w, m->projected);
    put_f64s(&w, m->phi, 10);
    put_f64s(&w, m->phi_std, 10);
    put_f64s(&w, &m->mass, 1);
    put_f64s(&w, m->com, 3);
    put_f64s(&w, m->inertia_com, 6);
    return finish(&w);
}

/* ------------------------------------------------------------ reading */

typedef struct {
    const uint8_t *p;
    size_t len, n;
    int err; /* first error, or 0 */
    int nonfinite;
} rd_t;

static int have(rd_t *r, size_t k) {
    if (r->err) return 0;
    if (r->len - r->n < k) {
        r->err = LOADID_LCM_ESHORT;
        return 0;
    }
    return 1;
}
/* Big-endian, read from a local pointer: the compiler makes it one load
 * and a byte swap (through r->n it was a load and a store per byte). */
static uint64_t get_u64(rd_t *r) {
    if (!have(r, 8)) return 0;
    const uint8_t *b = r->p + r->n;
    r->n += 8;
    return (uint64_t)b[0] << 56 | (uint64_t)b[1] << 48 | (uint64_t)b[2] << 40 |
           (uint64_t)b[3] << 32 | (uint64_t)b[4] << 24 | (uint64_t)b[5] << 16 |
           (uint64_t)b[6] << 8 | (uint64_t)b[7];
}
static int64_t get_i64(rd_t *r) {
    return (int64_t)get_u64(r);
}
static int32_t get_i32(rd_t *r) {
    if (!have(r, 4)) return 0;
    const uint8_t *b = r->p + r->n;
    r->n += 4;
    return (int32_t)((uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3]);
}
static int8_t get_i8(rd_t *r) {
    return have(r, 1) ? (int8_t)r->p[r->n++] : 0;
}
static void get_f64s(rd_t *r, double *v, int k) {
    for (int i = 0; i < k; ++i) {
        const uint64_t u = get_u64(r);
        memcpy(&v[i], &u, 8);
        if (!isfinite(v[i])) r->nonfinite = 1;
    }
}
/* An LCM string into out[room]: its length (1..room, the NUL included) must
 * fit, the last byte be the NUL and no other byte be one. */
static void get_string(rd_t *r, char *out, size_t room) {
    out[0] = 0;
    const int32_t len = get_i32(r);
    if (r->err) return;
    if (len < 1) {
        r->err = LOADID_LCM_ESTRING;
        return;
    }
    if (!have(r, (size_t)len)) return; /* ends inside the string: ESHORT */
    if ((size_t)len > room) {          /* a name too long for the fixed array */
        r->err = LOADID_LCM_ESTRING;
        return;
    }
    const uint8_t *s = r->p + r->n;
    if (s[len - 1] != 0 || memchr(s, 0, (size_t)len - 1)) {
        r->err = LOADID_LCM_ESTRING;
        return;
    }
    memcpy(out, s, (size_t)len);
    r->n += (size_t)len;
}

/* The fingerprint first (a wrong one says more than a wrong length). */
static rd_t reader(loadid_lcm_type_t t, const uint8_t *buf, size_t len) {
    rd_t r = {buf, buf ? len : 0, 0, 0, 0};
    const uint64_t fp = get_u64(&r);
    if (!r.err && fp != loadid_lcm_fingerprint(t)) r.err = LOADID_LCM_EFINGERPRINT;
    return r;
}

static int done(const rd_t *r) {
    if (r->err) return r->err;
    if (r->n != r->len) return LOADID_LCM_ELONG;
    return r->nonfinite ? LOADID_LCM_NONFINITE : 0;
}

int loadid_lcm_decode_joint_state(const uint8_t *buf, size_t len, loadid_lcm_joint_state_t *out) {
    rd_t r = reader(LOADID_LCM_JOINT_STATE, buf, len);
    out->utime = get_i64(&r);
    out->num_joints = get_i32(&r);
    if (r.err) return r.err;
    if (out->num_joints < 1 || out->num_joints > LOADID_LCM_MAX_JOINTS) return LOADID_LCM_ECOUNT;
    get_f64s(&r, out->position, out->num_joints);
    get_f64s(&r, out->setpoint, out->num_joints);
    return done(&r);
}

int loadid_lcm_decode_command(const uint8_t *buf, size_t len, loadid_lcm_command_t *out) {
    rd_t r = reader(LOADID_LCM_COMMAND, buf, len);
    out->utime = get_i64(&r);
    out->action = get_i8(&r);
    get_string(&r, out->load_name, sizeof out->load_name);
    return done(&r);
}

int loadid_lcm_decode_estimate(const uint8_t *buf, size_t len, loadid_lcm_estimate_t *out) {
    rd_t r = reader(LOADID_LCM_ESTIMATE, buf, len);
    out->utime = get_i64(&r);
    out->samples = get_i64(&r);
    out->method = get_i8(&r);
    out->state = get_i8(&r);
    get_string(&r, out->load_name, sizeof out->load_name);
    get_f64s(&r, out->phi, 10);
    get_f64s(&r, out->offset, 6);
    get_f64s(&r, &out->mass, 1);
    get_f64s(&r, out->com, 3);
    get_f64s(&r, out->inertia_com, 6);
    get_f64s(&r, &out->condition_number, 1);
    get_f64s(&r, &out->sigma_min, 1);
    out->physically_consistent = get_i8(&r);
    return done(&r);
}

int loadid_lcm_decode_wrench(const uint8_t *buf, size_t len, loadid_lcm_wrench_t *out) {
    rd_t r = reader(LOADID_LCM_WRENCH, buf, len);
    out->utime = get_i64(&r);
    get_f64s(&r, out->force, 3);
    get_f64s(&r, out->torque, 3);
    return done(&r);
}

int loadid_lcm_decode_status(const uint8_t *buf, size_t len, loadid_lcm_status_t *out) {
    rd_t r = reader(LOADID_LCM_STATUS, buf, len);
    out->utime = get_i64(&r);
    out->state = get_i8(&r);
    out->samples_ok = get_i64(&r);
    out->frames_bad = get_i64(&r);
    out->samples_incomplete = get_i64(&r);
    out->samples_saturated = get_i64(&r);
    out->sequence_gaps = get_i64(&r);
    out->joint_msgs_bad = get_i64(&r);
    get_f64s(&r, &out->loop_us_p50, 1);
    get_f64s(&r, &out->loop_us_p99, 1);
    get_f64s(&r, &out->loop_us_max, 1);
    return done(&r);
}

int loadid_lcm_decode_load_model(const uint8_t *buf, size_t len, loadid_lcm_load_model_t *out) {
    rd_t r = reader(LOADID_LCM_LOAD_MODEL, buf, len);
    out->utime = get_i64(&r);
    out->method = get_i8(&r);
    get_string(&r, out->load_name, sizeof out->load_name);
    out->identified = get_i8(&r);
    out->projected = get_i8(&r);
    get_f64s(&r, out->phi, 10);
    get_f64s(&r, out->phi_std, 10);
    get_f64s(&r, &out->mass, 1);
    get_f64s(&r, out->com, 3);
    get_f64s(&r, out->inertia_com, 6);
    return done(&r);
}

const char *loadid_lcm_strerror(int code) {
    switch (code) {
        case 0:
            return "ok";
        case LOADID_LCM_NONFINITE:
            return "decoded; a value is NaN or infinite";
        case LOADID_LCM_ESHORT:
            return "message truncated";
        case LOADID_LCM_ELONG:
            return "bytes after the message";
        case LOADID_LCM_EFINGERPRINT:
            return "fingerprint of another type";
        case LOADID_LCM_ECOUNT:
            return "num_joints out of range";
        case LOADID_LCM_ESTRING:
            return "bad string (length, NUL terminator, NUL inside)";
        case LOADID_LCM_ENOSPC:
            return "buffer too small";
        case LOADID_LCM_EINVAL:
            return "field out of range";
        default:
            return "unknown LCM wire error";
    }
}

const char *loadid_lcm_state_name(int state) {
    static const char *const names[] = {"IDLE", "ZEROING", "ESTIMATING", "DONE", "FAILED"};
    return state >= 0 && state < (int)(sizeof names / sizeof names[0]) ? names[state] : "?";
}
