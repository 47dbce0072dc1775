/*
 * The hand-written LCM codecs (drivers/lcm_wire.h) against lcm-gen's
 * generated C (loadid_lcmtypes, linked here only):
 *  - the fingerprints equal the generated __*_get_hash();
 *  - for many random messages of each type (random bit patterns for the
 *    doubles, NaN and infinities among them; random names, 0..127
 *    characters; 1..16 joints) the bytes equal lcm-gen's *_encode, lcm-gen's
 *    bytes decode to the same fields, and ours decode with lcm-gen's
 *    decoder;
 *  - truncated (every prefix), oversized, wrong-fingerprint, bad-count
 *    and bad-string inputs (command_t's and load_model_t's strings) are refused with their codes; each decode reads
 *    an exact-size heap copy, so the sanitizers see any read past it;
 *  - encoders refuse buffers too small and fields out of range;
 *  - the udpm framing (lcm_udpm.h): URL and datagram parsing.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "lcmtypes/loadid_command_t.h"
#include "lcmtypes/loadid_estimate_t.h"
#include "lcmtypes/loadid_joint_state_t.h"
#include "lcmtypes/loadid_load_model_t.h"
#include "lcmtypes/loadid_status_t.h"
#include "lcmtypes/loadid_wrench_t.h"
#include "loadid/lcm_udpm.h"
#include "loadid/lcm_wire.h"

enum { ROUNDS = 400 };

/* ---- random fields (xorshift64*, fixed seed: reproducible) ---- */
static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static uint64_t rnd(void) {
    rng_state ^= rng_state >> 12, rng_state ^= rng_state << 25, rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}
/* Mostly ordinary values, sometimes any bit pattern (NaN, inf, subnormal). */
static double rnd_double(void) {
    if (rnd() % 8 == 0) {
        const uint64_t u = rnd();
        double d;
        memcpy(&d, &u, 8);
        return d;
    }
    return ((double)(rnd() >> 11) / 9007199254740992.0 - 0.5) * 1e3;
}
static void rnd_doubles(double *v, int n) {
    for (int i = 0; i < n; ++i) v[i] = rnd_double();
}
static int64_t rnd_i64(void) {
    return (int64_t)rnd();
}
static int8_t rnd_i8(void) {
    return (int8_t)rnd();
}
/* 0..127 printable characters and bytes >= 0x80, never a NUL. */
static void rnd_name(char *s) {
    const int n = (int)(rnd() % LOADID_LCM_NAME_MAX);
    for (int i = 0; i < n; ++i) s[i] = (char)(1 + rnd() % 255);
    s[n] = 0;
}
static int same_bits(const double *a, const double *b, int n) {
    return !memcmp(a, b, 8 * (size_t)n);
}

/* Decodes from an exact-size heap copy (the sanitizers see over-reads). */
typedef int (*decode_fn)(const uint8_t *, size_t, void *);
typedef int (*encode_fn)(const void *, uint8_t *, size_t);
static int decode_copy(decode_fn f, const uint8_t *bytes, size_t n, void *out) {
    uint8_t *copy = malloc(n ? n : 1);
    assert_non_null(copy);
    if (n) memcpy(copy, bytes, n);
    const int rc = f(copy, n, out);
    free(copy);
    return rc;
}
/* Type-erased wrappers (a call through a cast function pointer is not C). */
#define WRAP(type)                                                 \
    static int dec_##type(const uint8_t *b, size_t n, void *out) { \
        return loadid_lcm_decode_##type(b, n, out);                \
    }                                                              \
    static int enc_##type(const void *m, uint8_t *b, size_t cap) { \
        return loadid_lcm_encode_##type(m, b, cap);                \
    }
WRAP(joint_state)
WRAP(command)
WRAP(estimate)
WRAP(wrench)
WRAP(status)
WRAP(load_model)

static void test_fingerprints(void **state) {
    (void)state;
    assert_true(loadid_lcm_fingerprint(LOADID_LCM_JOINT_STATE) ==
                (uint64_t)__loadid_joint_state_t_get_hash());
    assert_true(loadid_lcm_fingerprint(LOADID_LCM_COMMAND) ==
                (uint64_t)__loadid_command_t_get_hash());
    assert_true(loadid_lcm_fingerprint(LOADID_LCM_ESTIMATE) ==
                (uint64_t)__loadid_estimate_t_get_hash());
    assert_true(loadid_lcm_fingerprint(LOADID_LCM_WRENCH) ==
                (uint64_t)__loadid_wrench_t_get_hash());
    assert_true(loadid_lcm_fingerprint(LOADID_LCM_STATUS) ==
                (uint64_t)__loadid_status_t_get_hash());
    assert_true(loadid_lcm_fingerprint(LOADID_LCM_LOAD_MODEL) ==
                (uint64_t)__loadid_load_model_t_get_hash());
    assert_true(loadid_lcm_fingerprint((loadid_lcm_type_t)6) == 0);
}

/* Every refusal a message of n bytes must give: each shorter prefix, one
 * byte more, and a flipped bit in each fingerprint byte. */
static void refuse_damaged(decode_fn f, const uint8_t *bytes, size_t n, void *out) {
    uint8_t buf[1024];
    assert_true(n + 1 <= sizeof buf);
    for (size_t k = 0; k < n; ++k) {
        const int rc = decode_copy(f, bytes, k, out);
        if (rc != LOADID_LCM_ESHORT) {
            print_error("prefix of %zu of %zu bytes: %d (%s)\n", k, n, rc, loadid_lcm_strerror(rc));
            fail();
        }
    }
    memcpy(buf, bytes, n);
    buf[n] = 0;
    assert_int_equal(decode_copy(f, buf, n + 1, out), LOADID_LCM_ELONG);
    for (int b = 0; b < 8; ++b) {
        memcpy(buf, bytes, n);
        buf[b] ^= (uint8_t)(1u << (rnd() % 8));
        assert_int_equal(decode_copy(f, buf, n, out), LOADID_LCM_EFINGERPRINT);
    }
    assert_int_equal(f(NULL, 0, out), LOADID_LCM_ESHORT);
}

/* The encoder refuses every buffer smaller than its message. */
static void refuse_small(encode_fn f, const void *m, int n) {
    uint8_t buf[1024];
    for (int cap = 0; cap < n; ++cap) assert_int_equal(f(m, buf, (size_t)cap), LOADID_LCM_ENOSPC);
    assert_int_equal(f(m, NULL, 0), LOADID_LCM_ENOSPC);
    assert_int_equal(f(m, buf, (size_t)n), n);
}

static int any_nonfinite(const double *v, int n) {
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 1;
    return 0;
}

/* ---- joint_state_t ---- */
static void test_joint_state(void **state) {
    (void)state;
    for (int r = 0; r < ROUNDS; ++r) {
        loadid_lcm_joint_state_t m;
        memset(&m, 0, sizeof m);
        m.utime = rnd_i64();
        m.num_joints = 1 + (int32_t)(rnd() % LOADID_LCM_MAX_JOINTS);
        rnd_doubles(m.position, m.num_joints);
        rnd_doubles(m.setpoint, m.num_joints);
        loadid_joint_state_t g = {m.utime, m.num_joints, m.position, m.setpoint};
        uint8_t ours[LOADID_LCM_JOINT_STATE_MAX], gen[1024];
        const int n = loadid_lcm_encode_joint_state(&m, ours, sizeof ours);
        const int gn = loadid_joint_state_t_encode(gen, 0, sizeof gen, &g);
        assert_int_equal(n, gn);
        assert_int_equal(n, loadid_joint_state_t_encoded_size(&g));
        assert_memory_equal(ours, gen, (size_t)n);
        loadid_lcm_joint_state_t d;
        const int rc = decode_copy(dec_joint_state, gen, (size_t)gn, &d);
        const int nonfinite =
            any_nonfinite(m.position, m.num_joints) || any_nonfinite(m.setpoint, m.num_joints);
        assert_int_equal(rc, nonfinite ? LOADID_LCM_NONFINITE : 0);
        assert_true(d.utime == m.utime && d.num_joints == m.num_joints);
        assert_true(same_bits(d.position, m.position, m.num_joints));
        assert_true(same_bits(d.setpoint, m.setpoint, m.num_joints));
        loadid_joint_state_t gd;
        assert_int_equal(loadid_joint_state_t_decode(ours, 0, n, &gd), n);
        assert_true(gd.utime == m.utime && gd.num_joints == m.num_joints);
        assert_true(same_bits(gd.position, m.position, m.num_joints));
        assert_true(same_bits(gd.setpoint, m.setpoint, m.num_joints));
        loadid_joint_state_t_decode_cleanup(&gd);
        if (r < 20) {
            refuse_damaged(dec_joint_state, ours, (size_t)n, &d);
            refuse_small(enc_joint_state, &m, n);
        }
    }
}

/* num_joints: negative, 0, above the maximum, and not matching the length. */
static void test_joint_state_counts(void **state) {
    (void)state;
    loadid_lcm_joint_state_t m;
    memset(&m, 0, sizeof m);
    m.num_joints = 4;
    uint8_t buf[LOADID_LCM_JOINT_STATE_MAX + 8 * 64];
    memset(buf, 0, sizeof buf);
    const int n = loadid_lcm_encode_joint_state(&m, buf, sizeof buf);
    assert_int_equal(n, 8 + 8 + 4 + 2 * 8 * 4);
    loadid_lcm_joint_state_t d;
    const int32_t bad[] = {-1, 0, LOADID_LCM_MAX_JOINTS + 1, 1000, INT32_MAX, INT32_MIN};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        uint8_t b[sizeof buf];
        memcpy(b, buf, sizeof b);
        const uint32_t u = (uint32_t)bad[i];
        b[16] = (uint8_t)(u >> 24), b[17] = (uint8_t)(u >> 16), b[18] = (uint8_t)(u >> 8),
        b[19] = (uint8_t)u;
        assert_int_equal(decode_copy(dec_joint_state, b, (size_t)n, &d), LOADID_LCM_ECOUNT);
        /* a long enough buffer does not make such a count acceptable */
        assert_int_equal(decode_copy(dec_joint_state, b, sizeof b, &d), LOADID_LCM_ECOUNT);
    }
    buf[19] = 3; /* fewer joints than the bytes hold */
    assert_int_equal(decode_copy(dec_joint_state, buf, (size_t)n, &d), LOADID_LCM_ELONG);
    buf[19] = 5; /* more */
    assert_int_equal(decode_copy(dec_joint_state, buf, (size_t)n, &d), LOADID_LCM_ESHORT);
    m.num_joints = 0;
    assert_int_equal(loadid_lcm_encode_joint_state(&m, buf, sizeof buf), LOADID_LCM_EINVAL);
    m.num_joints = LOADID_LCM_MAX_JOINTS + 1;
    assert_int_equal(loadid_lcm_encode_joint_state(&m, buf, sizeof buf), LOADID_LCM_EINVAL);
    m.num_joints = -3;
    assert_int_equal(loadid_lcm_encode_joint_state(&m, buf, sizeof buf), LOADID_LCM_EINVAL);
}

/* ---- command_t ---- */
static void test_command(void **state) {
    (void)state;
    for (int r = 0; r < ROUNDS; ++r) {
        loadid_lcm_command_t m;
        memset(&m, 0, sizeof m);
        m.utime = rnd_i64();
        m.action = rnd_i8();
        rnd_name(m.load_name);
        if (r == 0) m.load_name[0] = 0; /* empty: 4 + 1 bytes */
        loadid_command_t g = {m.utime, m.action, m.load_name};
        uint8_t ours[LOADID_LCM_COMMAND_MAX], gen[1024];
        const int n = loadid_lcm_encode_command(&m, ours, sizeof ours);
        const int gn = loadid_command_t_encode(gen, 0, sizeof gen, &g);
        assert_int_equal(n, gn);
        assert_memory_equal(ours, gen, (size_t)n);
        loadid_lcm_command_t d;
        assert_int_equal(decode_copy(dec_command, gen, (size_t)gn, &d), 0);
        assert_true(d.utime == m.utime && d.action == m.action);
        assert_string_equal(d.load_name, m.load_name);
        loadid_command_t gd;
        assert_int_equal(loadid_command_t_decode(ours, 0, n, &gd), n);
        assert_true(gd.utime == m.utime && gd.action == m.action);
        assert_string_equal(gd.load_name, m.load_name);
        loadid_command_t_decode_cleanup(&gd);
        if (r < 20) {
            refuse_damaged(dec_command, ours, (size_t)n, &d);
            refuse_small(enc_command, &m, n);
        }
    }
}

/* Writes a command_t with a string field of length field len and the
 * given bytes (not necessarily NUL-terminated); returns its size. */
static size_t command_bytes(uint8_t *b, int32_t len, const uint8_t *s, size_t ns) {
    loadid_lcm_command_t m;
    memset(&m, 0, sizeof m);
    const int n = loadid_lcm_encode_command(&m, b, 64);
    assert_int_equal(n, 8 + 8 + 1 + 4 + 1);
    const uint32_t u = (uint32_t)len;
    b[17] = (uint8_t)(u >> 24), b[18] = (uint8_t)(u >> 16), b[19] = (uint8_t)(u >> 8),
    b[20] = (uint8_t)u;
    memcpy(b + 21, s, ns);
    return 21 + ns;
}

static void test_command_strings(void **state) {
    (void)state;
    uint8_t b[512], s[300];
    loadid_lcm_command_t d;
    memset(s, 'a', sizeof s);
    s[0] = 0;
    /* length 0: LCM always sends the NUL */
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, 0, s, 0), &d),
                     LOADID_LCM_ESTRING);
    /* negative length */
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, -1, s, 1), &d),
                     LOADID_LCM_ESTRING);
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, INT32_MIN, s, 1), &d),
                     LOADID_LCM_ESTRING);
    /* unterminated: the last byte is not a NUL */
    s[0] = 'x';
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, 3, s, 3), &d),
                     LOADID_LCM_ESTRING);
    /* a NUL inside */
    s[0] = 'x', s[1] = 0, s[2] = 'y', s[3] = 0;
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, 4, s, 4), &d),
                     LOADID_LCM_ESTRING);
    /* a length beyond the buffer */
    s[3] = 'z', s[4] = 0;
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, 6, s, 5), &d), LOADID_LCM_ESHORT);
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, INT32_MAX, s, 5), &d),
                     LOADID_LCM_ESHORT);
    /* the longest name that fits: 127 characters; 128 is refused */
    memset(s, 'n', sizeof s);
    s[127] = 0;
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, 128, s, 128), &d), 0);
    assert_int_equal((int)strlen(d.load_name), 127);
    s[127] = 'n', s[128] = 0;
    assert_int_equal(decode_copy(dec_command, b, command_bytes(b, 129, s, 129), &d),
                     LOADID_LCM_ESTRING);
    /* lcm-gen's encoder writes such a name; ours refuses to */
    loadid_command_t g = {1, 2, (char *)s};
    const int gn = loadid_command_t_encode(b, 0, sizeof b, &g);
    assert_int_equal(gn, 8 + 8 + 1 + 4 + 129);
    assert_int_equal(decode_copy(dec_command, b, (size_t)gn, &d), LOADID_LCM_ESTRING);
    loadid_lcm_command_t m;
    memset(m.load_name, 'n', sizeof m.load_name); /* no NUL within the array */
    m.utime = 0, m.action = 1;
    assert_int_equal(loadid_lcm_encode_command(&m, b, sizeof b), LOADID_LCM_EINVAL);
}

/* ---- estimate_t ---- */
static void test_estimate(void **state) {
    (void)state;
    for (int r = 0; r < ROUNDS; ++r) {
        loadid_lcm_estimate_t m;
        memset(&m, 0, sizeof m);
        m.utime = rnd_i64(), m.samples = rnd_i64();
        m.method = rnd_i8(), m.state = rnd_i8();
        rnd_name(m.load_name);
        rnd_doubles(m.phi, 10), rnd_doubles(m.offset, 6), rnd_doubles(&m.mass, 1);
        rnd_doubles(m.com, 3), rnd_doubles(m.inertia_com, 6);
        rnd_doubles(&m.condition_number, 1), rnd_doubles(&m.sigma_min, 1);
        m.physically_consistent = (int8_t)(rnd() % 2);
        loadid_estimate_t g;
        memset(&g, 0, sizeof g);
        g.utime = m.utime, g.samples = m.samples, g.method = m.method, g.state = m.state;
        g.load_name = m.load_name;
        memcpy(g.phi, m.phi, sizeof g.phi), memcpy(g.offset, m.offset, sizeof g.offset);
        g.mass = m.mass;
        memcpy(g.com, m.com, sizeof g.com),
            memcpy(g.inertia_com, m.inertia_com, sizeof g.inertia_com);
        g.condition_number = m.condition_number, g.sigma_min = m.sigma_min;
        g.physically_consistent = m.physically_consistent;
        uint8_t ours[LOADID_LCM_ESTIMATE_MAX], gen[1024];
        const int n = loadid_lcm_encode_estimate(&m, ours, sizeof ours);
        const int gn = loadid_estimate_t_encode(gen, 0, sizeof gen, &g);
        assert_int_equal(n, gn);
        assert_memory_equal(ours, gen, (size_t)n);
        loadid_lcm_estimate_t d;
        const int rc = decode_copy(dec_estimate, gen, (size_t)gn, &d);
        assert_true(rc == 0 || rc == LOADID_LCM_NONFINITE);
        assert_true(d.utime == m.utime && d.samples == m.samples && d.method == m.method &&
                    d.state == m.state && d.physically_consistent == m.physically_consistent);
        assert_string_equal(d.load_name, m.load_name);
        assert_true(same_bits(d.phi, m.phi, 10) && same_bits(d.offset, m.offset, 6));
        assert_true(same_bits(&d.mass, &m.mass, 1) && same_bits(d.com, m.com, 3));
        assert_true(same_bits(d.inertia_com, m.inertia_com, 6));
        assert_true(same_bits(&d.condition_number, &m.condition_number, 1));
        assert_true(same_bits(&d.sigma_min, &m.sigma_min, 1));
        loadid_estimate_t gd;
        assert_int_equal(loadid_estimate_t_decode(ours, 0, n, &gd), n);
        assert_string_equal(gd.load_name, m.load_name);
        assert_true(same_bits(gd.phi, m.phi, 10) && gd.samples == m.samples);
        loadid_estimate_t_decode_cleanup(&gd);
        if (r < 20) {
            refuse_damaged(dec_estimate, ours, (size_t)n, &d);
            refuse_small(enc_estimate, &m, n);
        }
    }
}

/* ---- wrench_t ---- */
static void test_wrench(void **state) {
    (void)state;
    for (int r = 0; r < ROUNDS; ++r) {
        loadid_lcm_wrench_t m;
        m.utime = rnd_i64();
        rnd_doubles(m.force, 3), rnd_doubles(m.torque, 3);
        loadid_wrench_t g;
        g.utime = m.utime;
        memcpy(g.force, m.force, sizeof g.force), memcpy(g.torque, m.torque, sizeof g.torque);
        uint8_t ours[LOADID_LCM_WRENCH_SIZE], gen[256];
        const int n = loadid_lcm_encode_wrench(&m, ours, sizeof ours);
        const int gn = loadid_wrench_t_encode(gen, 0, sizeof gen, &g);
        assert_int_equal(n, LOADID_LCM_WRENCH_SIZE);
        assert_int_equal(n, gn);
        assert_memory_equal(ours, gen, (size_t)n);
        loadid_lcm_wrench_t d;
        const int rc = decode_copy(dec_wrench, gen, (size_t)gn, &d);
        assert_int_equal(
            rc, any_nonfinite(m.force, 3) || any_nonfinite(m.torque, 3) ? LOADID_LCM_NONFINITE : 0);
        assert_true(d.utime == m.utime && same_bits(d.force, m.force, 3) &&
                    same_bits(d.torque, m.torque, 3));
        loadid_wrench_t gd;
        assert_int_equal(loadid_wrench_t_decode(ours, 0, n, &gd), n);
        assert_true(gd.utime == m.utime && same_bits(gd.torque, m.torque, 3));
        if (r < 20) {
            refuse_damaged(dec_wrench, ours, (size_t)n, &d);
            refuse_small(enc_wrench, &m, n);
        }
    }
}

/* ---- status_t ---- */
static void test_status(void **state) {
    (void)state;
    for (int r = 0; r < ROUNDS; ++r) {
        loadid_lcm_status_t m;
        m.utime = rnd_i64(), m.state = rnd_i8();
        m.samples_ok = rnd_i64(), m.frames_bad = rnd_i64(), m.samples_incomplete = rnd_i64();
        m.samples_saturated = rnd_i64(), m.sequence_gaps = rnd_i64(), m.joint_msgs_bad = rnd_i64();
        rnd_doubles(&m.loop_us_p50, 1), rnd_doubles(&m.loop_us_p99, 1),
            rnd_doubles(&m.loop_us_max, 1);
        loadid_status_t g = {m.utime,
                             m.state,
                             m.samples_ok,
                             m.frames_bad,
                             m.samples_incomplete,
                             m.samples_saturated,
                             m.sequence_gaps,
                             m.joint_msgs_bad,
                             m.loop_us_p50,
                             m.loop_us_p99,
                             m.loop_us_max};
        uint8_t ours[LOADID_LCM_STATUS_SIZE], gen[256];
        const int n = loadid_lcm_encode_status(&m, ours, sizeof ours);
        const int gn = loadid_status_t_encode(gen, 0, sizeof gen, &g);
        assert_int_equal(n, LOADID_LCM_STATUS_SIZE);
        assert_int_equal(n, gn);
        assert_memory_equal(ours, gen, (size_t)n);
        loadid_lcm_status_t d;
        const int rc = decode_copy(dec_status, gen, (size_t)gn, &d);
        assert_true(rc == 0 || rc == LOADID_LCM_NONFINITE);
        assert_true(d.utime == m.utime && d.state == m.state && d.samples_ok == m.samples_ok &&
                    d.frames_bad == m.frames_bad && d.samples_incomplete == m.samples_incomplete &&
                    d.samples_saturated == m.samples_saturated &&
                    d.sequence_gaps == m.sequence_gaps && d.joint_msgs_bad == m.joint_msgs_bad);
        assert_true(same_bits(&d.loop_us_p50, &m.loop_us_p50, 1) &&
                    same_bits(&d.loop_us_p99, &m.loop_us_p99, 1) &&
                    same_bits(&d.loop_us_max, &m.loop_us_max, 1));
        loadid_status_t gd;
        assert_int_equal(loadid_status_t_decode(ours, 0, n, &gd), n);
        assert_true(gd.joint_msgs_bad == m.joint_msgs_bad);
        if (r < 20) {
            refuse_damaged(dec_status, ours, (size_t)n, &d);
            refuse_small(enc_status, &m, n);
        }
    }
}

/* ---- load_model_t ---- */
/* lcm-gen's struct with m's fields (its load_name points into m). */
static loadid_load_model_t gen_load_model(loadid_lcm_load_model_t *m) {
    loadid_load_model_t g;
    memset(&g, 0, sizeof g);
    g.utime = m->utime, g.method = m->method, g.load_name = m->load_name;
    g.identified = m->identified, g.projected = m->projected;
    memcpy(g.phi, m->phi, sizeof g.phi), memcpy(g.phi_std, m->phi_std, sizeof g.phi_std);
    g.mass = m->mass;
    memcpy(g.com, m->com, sizeof g.com),
        memcpy(g.inertia_com, m->inertia_com, sizeof g.inertia_com);
    return g;
}

static void test_load_model(void **state) {
    (void)state;
    for (int r = 0; r < ROUNDS; ++r) {
        loadid_lcm_load_model_t m;
        memset(&m, 0, sizeof m);
        m.utime = rnd_i64();
        m.method = rnd_i8();
        rnd_name(m.load_name);
        if (r == 0) m.load_name[0] = 0;
        m.identified = rnd_i8();
        m.projected = (int8_t)(rnd() % 2);
        rnd_doubles(m.phi, 10), rnd_doubles(m.phi_std, 10), rnd_doubles(&m.mass, 1);
        rnd_doubles(m.com, 3), rnd_doubles(m.inertia_com, 6);
        loadid_load_model_t g = gen_load_model(&m);
        uint8_t ours[LOADID_LCM_LOAD_MODEL_MAX], gen[1024];
        const int n = loadid_lcm_encode_load_model(&m, ours, sizeof ours);
        const int gn = loadid_load_model_t_encode(gen, 0, sizeof gen, &g);
        assert_int_equal(n, gn);
        assert_int_equal(n, loadid_load_model_t_encoded_size(&g));
        assert_memory_equal(ours, gen, (size_t)n);
        loadid_lcm_load_model_t d;
        const int rc = decode_copy(dec_load_model, gen, (size_t)gn, &d);
        const int nonfinite = any_nonfinite(m.phi, 10) || any_nonfinite(m.phi_std, 10) ||
                              any_nonfinite(&m.mass, 1) || any_nonfinite(m.com, 3) ||
                              any_nonfinite(m.inertia_com, 6);
        assert_int_equal(rc, nonfinite ? LOADID_LCM_NONFINITE : 0);
        assert_true(d.utime == m.utime && d.method == m.method && d.identified == m.identified &&
                    d.projected == m.projected);
        assert_string_equal(d.load_name, m.load_name);
        assert_true(same_bits(d.phi, m.phi, 10) && same_bits(d.phi_std, m.phi_std, 10));
        assert_true(same_bits(&d.mass, &m.mass, 1) && same_bits(d.com, m.com, 3));
        assert_true(same_bits(d.inertia_com, m.inertia_com, 6));
        loadid_load_model_t gd;
        assert_int_equal(loadid_load_model_t_decode(ours, 0, n, &gd), n);
        assert_true(gd.utime == m.utime && gd.method == m.method && gd.identified == m.identified &&
                    gd.projected == m.projected);
        assert_string_equal(gd.load_name, m.load_name);
        assert_true(same_bits(gd.phi, m.phi, 10) && same_bits(gd.phi_std, m.phi_std, 10));
        assert_true(same_bits(&gd.mass, &m.mass, 1) && same_bits(gd.com, m.com, 3));
        assert_true(same_bits(gd.inertia_com, m.inertia_com, 6));
        loadid_load_model_t_decode_cleanup(&gd);
        if (r < 20) {
            refuse_damaged(dec_load_model, ours, (size_t)n, &d);
            refuse_small(enc_load_model, &m, n);
        }
    }
}

/* load_model_t's string (after utime and method, at byte 17): the refusals
 * of test_command_strings, on this decoder. */
static void test_load_model_strings(void **state) {
    (void)state;
    loadid_lcm_load_model_t m, d;
    memset(&m, 0, sizeof m);
    strcpy(m.load_name, "xyz");
    uint8_t ok[LOADID_LCM_LOAD_MODEL_MAX], b[LOADID_LCM_LOAD_MODEL_MAX + 8];
    const int n = loadid_lcm_encode_load_model(&m, ok, sizeof ok);
    assert_int_equal(n, 8 + 8 + 1 + 4 + 4 + 1 + 1 + 8 * 30);
    assert_int_equal(LOADID_LCM_LOAD_MODEL_MAX, n - 4 + LOADID_LCM_NAME_MAX);
    assert_int_equal(decode_copy(dec_load_model, ok, (size_t)n, &d), 0);
    assert_string_equal(d.load_name, "xyz");
    assert_true(ok[17] == 0 && ok[18] == 0 && ok[19] == 0 && ok[20] == 4);
    /* unterminated, a NUL inside, length 0, negative */
    memcpy(b, ok, (size_t)n);
    b[24] = 'w';
    assert_int_equal(decode_copy(dec_load_model, b, (size_t)n, &d), LOADID_LCM_ESTRING);
    memcpy(b, ok, (size_t)n);
    b[22] = 0;
    assert_int_equal(decode_copy(dec_load_model, b, (size_t)n, &d), LOADID_LCM_ESTRING);
    memcpy(b, ok, (size_t)n);
    b[20] = 0;
    assert_int_equal(decode_copy(dec_load_model, b, (size_t)n, &d), LOADID_LCM_ESTRING);
    memcpy(b, ok, (size_t)n);
    b[17] = 0x80;
    assert_int_equal(decode_copy(dec_load_model, b, (size_t)n, &d), LOADID_LCM_ESTRING);
    /* a length beyond the buffer */
    memcpy(b, ok, (size_t)n);
    b[17] = 0x7f;
    assert_int_equal(decode_copy(dec_load_model, b, (size_t)n, &d), LOADID_LCM_ESHORT);
    /* the longest name: 127 characters; lcm-gen writes 128, ours refuses both ways */
    memset(m.load_name, 'n', sizeof m.load_name - 1);
    m.load_name[sizeof m.load_name - 1] = 0;
    const int nmax = loadid_lcm_encode_load_model(&m, ok, sizeof ok);
    assert_int_equal(nmax, LOADID_LCM_LOAD_MODEL_MAX);
    assert_int_equal(decode_copy(dec_load_model, ok, (size_t)nmax, &d), 0);
    assert_int_equal((int)strlen(d.load_name), 127);
    char long_name[LOADID_LCM_NAME_MAX + 1];
    memset(long_name, 'n', LOADID_LCM_NAME_MAX);
    long_name[LOADID_LCM_NAME_MAX] = 0;
    loadid_load_model_t g = gen_load_model(&m);
    g.load_name = long_name;
    uint8_t gen[1024];
    const int gn = loadid_load_model_t_encode(gen, 0, sizeof gen, &g);
    assert_int_equal(gn, LOADID_LCM_LOAD_MODEL_MAX + 1);
    assert_int_equal(decode_copy(dec_load_model, gen, (size_t)gn, &d), LOADID_LCM_ESTRING);
    memset(m.load_name, 'n', sizeof m.load_name); /* no NUL within the array */
    assert_int_equal(loadid_lcm_encode_load_model(&m, ok, sizeof ok), LOADID_LCM_EINVAL);
}

/* A message of one type is refused by every other type's decoder. */
static void test_types_not_confused(void **state) {
    (void)state;
    enum { NT = 6 };
    uint8_t b[NT][LOADID_LCM_LOAD_MODEL_MAX];
    int n[NT];
    loadid_lcm_joint_state_t js = {1, 2, {0}, {0}};
    loadid_lcm_command_t c = {1, 2, "x"};
    loadid_lcm_estimate_t e;
    memset(&e, 0, sizeof e);
    loadid_lcm_wrench_t w = {1, {0}, {0}};
    loadid_lcm_status_t s;
    memset(&s, 0, sizeof s);
    loadid_lcm_load_model_t lm;
    memset(&lm, 0, sizeof lm);
    n[0] = loadid_lcm_encode_joint_state(&js, b[0], sizeof b[0]);
    n[1] = loadid_lcm_encode_command(&c, b[1], sizeof b[1]);
    n[2] = loadid_lcm_encode_estimate(&e, b[2], sizeof b[2]);
    n[3] = loadid_lcm_encode_wrench(&w, b[3], sizeof b[3]);
    n[4] = loadid_lcm_encode_status(&s, b[4], sizeof b[4]);
    n[5] = loadid_lcm_encode_load_model(&lm, b[5], sizeof b[5]);
    const decode_fn dec[NT] = {dec_joint_state, dec_command, dec_estimate,
                               dec_wrench,      dec_status,  dec_load_model};
    union {
        loadid_lcm_joint_state_t js;
        loadid_lcm_command_t c;
        loadid_lcm_estimate_t e;
        loadid_lcm_wrench_t w;
        loadid_lcm_status_t s;
        loadid_lcm_load_model_t lm;
    } out;
    for (int i = 0; i < NT; ++i)
        for (int j = 0; j < NT; ++j)
            assert_int_equal(decode_copy(dec[j], b[i], (size_t)n[i], &out),
                             i == j ? 0 : LOADID_LCM_EFINGERPRINT);
    for (int code = LOADID_LCM_EINVAL; code <= LOADID_LCM_NONFINITE; ++code)
        assert_non_null(loadid_lcm_strerror(code));
}

/* ---- udpm framing ---- */
static void test_udpm_url(void **state) {
    (void)state;
    loadid_lcm_udpm_url_t u;
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://239.255.76.67:7667?ttl=0", &u), 0);
    assert_true(u.group[0] == 239 && u.group[1] == 255 && u.group[2] == 76 && u.group[3] == 67);
    assert_int_equal(u.port, 7667);
    assert_int_equal(u.recv_buf_size, 0);
    assert_int_equal(loadid_lcm_udpm_parse_url("", &u), 0);
    assert_int_equal(u.port, 7667);
    assert_int_equal(loadid_lcm_udpm_parse_url(NULL, &u), 0);
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://224.1.2.3", &u), 0);
    assert_int_equal(u.port, 7667);
    assert_int_equal(
        loadid_lcm_udpm_parse_url("udpm://224.1.2.3:1234?ttl=1&recv_buf_size=200000", &u), 0);
    assert_int_equal(u.port, 1234);
    assert_int_equal(u.recv_buf_size, 200000);
    assert_int_equal(loadid_lcm_udpm_parse_url("memq://", &u), -EPROTONOSUPPORT);
    assert_int_equal(loadid_lcm_udpm_parse_url("file:///tmp/x.log", &u), -EPROTONOSUPPORT);
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://10.0.0.1:7667", &u), -EINVAL); /* unicast */
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://239.255.76.67:0", &u), -EINVAL);
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://239.255.76.67:70000", &u), -EINVAL);
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://239.255.76.67:76x", &u), -EINVAL);
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://:7667", &u), -EINVAL);
    assert_int_equal(loadid_lcm_udpm_parse_url("udpm://239.255.76.67?recv_buf_size=x", &u),
                     -EINVAL);
    assert_int_equal(loadid_lcm_udpm_parse_url("239.255.76.67", &u), -EINVAL);
}

static void test_udpm_datagrams(void **state) {
    (void)state;
    const uint8_t dg[] = {'L', 'C', '0', '2', 0, 0, 0, 7, 'A', 'B', 0, 1, 2, 3};
    const char *ch;
    const uint8_t *p;
    size_t n;
    assert_int_equal(loadid_lcm_udpm_parse(dg, sizeof dg, &ch, &p, &n), 0);
    assert_string_equal(ch, "AB");
    assert_int_equal(n, 3);
    assert_true(p == dg + 11);
    assert_int_equal(loadid_lcm_udpm_parse(dg, 11, &ch, &p, &n), 0); /* empty payload */
    assert_int_equal(n, 0);
    assert_int_equal(loadid_lcm_udpm_parse(dg, 10, &ch, &p, &n), -EBADMSG); /* no NUL */
    assert_int_equal(loadid_lcm_udpm_parse(dg, 8, &ch, &p, &n), -EBADMSG);
    assert_int_equal(loadid_lcm_udpm_parse(dg, 3, &ch, &p, &n), -EBADMSG);
    uint8_t bad[sizeof dg];
    memcpy(bad, dg, sizeof dg);
    bad[3] = '3'; /* a fragment of a long message */
    assert_int_equal(loadid_lcm_udpm_parse(bad, sizeof bad, &ch, &p, &n), 1);
    bad[3] = 'X';
    assert_int_equal(loadid_lcm_udpm_parse(bad, sizeof bad, &ch, &p, &n), -EBADMSG);
    /* a channel of 63 characters is LCM's longest; 64 without a NUL is refused */
    uint8_t longch[8 + 65];
    memcpy(longch, dg, 8);
    memset(longch + 8, 'c', 65);
    longch[8 + 63] = 0;
    assert_int_equal(loadid_lcm_udpm_parse(longch, sizeof longch, &ch, &p, &n), 0);
    assert_int_equal((int)strlen(ch), 63);
    longch[8 + 63] = 'c';
    assert_int_equal(loadid_lcm_udpm_parse(longch, sizeof longch, &ch, &p, &n), -EBADMSG);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fingerprints),
        cmocka_unit_test(test_joint_state),
        cmocka_unit_test(test_joint_state_counts),
        cmocka_unit_test(test_command),
        cmocka_unit_test(test_command_strings),
        cmocka_unit_test(test_estimate),
        cmocka_unit_test(test_wrench),
        cmocka_unit_test(test_status),
        cmocka_unit_test(test_load_model),
        cmocka_unit_test(test_load_model_strings),
        cmocka_unit_test(test_types_not_confused),
        cmocka_unit_test(test_udpm_url),
        cmocka_unit_test(test_udpm_datagrams),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
