/*
 * Unit tests of loadid/jr3.h: the JR3 CAN layout of docs/INTERFACE.md ("JR3 over
 * CAN") as byte vectors.
 *
 * Independent references: frames written out byte by byte in this file from
 * docs/INTERFACE.md's table (little-endian int16 counts, byte 6 sequence, byte 7
 * status; base+4 with uint16 units of 0.1 N, 0.01 N m, 0.01 m/s^2,
 * 0.1 rad/s^2), SI values computed by hand as decimal literals (all exact
 * in binary: counts * full_scale / 16384 with the default full scales),
 * the encode -> decode round trip, and counters checked against a tally of
 * the return codes kept by the test over random garbage.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "loadid/jr3.h"
#include "random_util.h"

#define BASE 0x1A0u
#define COUNT_FS 16384.0

/* splitmix64: the test's own generator of bytes and choices. */
static uint64_t mix_state;
static uint64_t next_u64(void) {
    uint64_t z = (mix_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static unsigned next_below(unsigned n) {
    return (unsigned)(next_u64() % n);
}
static double next_unit(void) /* [0, 1) */
{
    return (double)(next_u64() >> 11) * 0x1.0p-53;
}

static loadid_can_frame_t make_frame(uint32_t id, int64_t t_us, const uint8_t bytes[8]) {
    loadid_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = 8;
    f.t_us = t_us;
    memcpy(f.data, bytes, 8);
    return f;
}

static loadid_jr3_decoder_t *new_decoder(void) {
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    loadid_jr3_decoder_t *dec = NULL;
    assert_int_equal(loadid_jr3_decoder_create(&cfg, &dec), 0);
    assert_non_null(dec);
    return dec;
}

static loadid_jr3_stats_t stats_of(const loadid_jr3_decoder_t *dec) {
    loadid_jr3_stats_t st;
    assert_int_equal(loadid_jr3_decoder_stats(dec, &st), 0);
    return st;
}

/* The invariants of loadid_jr3_stats_t. */
static void check_invariants(const loadid_jr3_stats_t *st) {
    assert_int_equal(st->frames_total, st->frames_bad + st->frames_sample + st->frames_duplicate +
                                           st->frames_discarded + st->full_scale_frames);
    assert_int_equal(st->frames_bad, st->frames_unknown_id + st->frames_bad_dlc +
                                         st->frames_malformed + st->frames_reserved);
    int64_t open =
        st->samples_started - (st->samples_ok + st->samples_rejected + st->samples_incomplete);
    assert_true(open == 0 || open == 1);
    assert_true(st->samples_rejected >= st->samples_saturated);
    assert_true(st->samples_rejected >= st->samples_faulty);
    assert_true(st->samples_rejected <= st->samples_saturated + st->samples_faulty);
    assert_true(st->full_scale_changes <= st->full_scale_frames);
    assert_true(st->sequence_gaps >= 0);
}

/* ---- The hand-written sample ------------------------------------------ */

/* Sequence 7, status 0. Counts and their SI values with the defaults
 * (200 N, 12 N m, 98.1 m/s^2, 1000 rad/s^2 over 16384 counts). */
static const uint8_t HAND[4][8] = {
    /* force: 16384, -16384, 1 */
    {0x00, 0x40, 0x00, 0xC0, 0x01, 0x00, 0x07, 0x00},
    /* moment: 8192, -1, 32767 */
    {0x00, 0x20, 0xFF, 0xFF, 0xFF, 0x7F, 0x07, 0x00},
    /* linear: 4096, -32768, 0 */
    {0x00, 0x10, 0x00, 0x80, 0x00, 0x00, 0x07, 0x00},
    /* angular: 100, -100, 16 */
    {0x64, 0x00, 0x9C, 0xFF, 0x10, 0x00, 0x07, 0x00},
};
static const int16_t HAND_COUNTS[4][3] = {
    {16384, -16384, 1}, {8192, -1, 32767}, {4096, -32768, 0}, {100, -100, 16}};
static const double HAND_SI[4][3] = {
    {200.0, -200.0, 0.01220703125},          /* 200/16384 */
    {6.0, -0.000732421875, 23.999267578125}, /* 12/16384, 32767*12/16384 */
    {24.525, -196.2, 0.0},                   /* 4096*98.1/16384 = 98.1/4 */
    {6.103515625, -6.103515625, 0.9765625},  /* 100000/16384, 16000/16384 */
};

static void assert_hand_sample(const loadid_jr3_sample_t *s, int64_t t_us) {
    assert_int_equal(s->t_us, t_us);
    assert_int_equal(s->sequence, 7);
    assert_false(s->saturated);
    assert_false(s->faulty);
    for (int g = 0; g < 4; ++g) {
        assert_int_equal(s->status[g], 0);
        for (int k = 0; k < 3; ++k) {
            assert_int_equal(s->counts[g][k], HAND_COUNTS[g][k]);
            /* 98.1/4 and 98.1*2: within one rounding of the decimal. */
            ASSERT_CLOSE(s->value[g][k], HAND_SI[g][k], 1e-13 * fabs(HAND_SI[g][k]), "SI value");
        }
    }
}

static void test_decode_hand_frames(void **state) {
    (void)state;
    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;
    for (int g = 0; g < 3; ++g) {
        loadid_can_frame_t f = make_frame(BASE + (uint32_t)g, 1000 + g, HAND[g]);
        assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    }
    loadid_can_frame_t f3 = make_frame(BASE + 3, 1003, HAND[3]);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f3, &out), LOADID_JR3_SAMPLE);
    assert_hand_sample(&out.sample, 1000);

    /* Any order; the time is base+0's receive time even when it comes
     * third. Sequence 8 so that it is a new sample. */
    const int order[4] = {3, 1, 0, 2};
    int rc = 0;
    for (int i = 0; i < 4; ++i) {
        uint8_t b[8];
        memcpy(b, HAND[order[i]], 8);
        b[6] = 8;
        loadid_can_frame_t f = make_frame(BASE + (uint32_t)order[i], 5000 + i, b);
        rc = loadid_jr3_decoder_feed(dec, &f, &out);
        assert_int_equal(rc, i < 3 ? LOADID_JR3_NONE : LOADID_JR3_SAMPLE);
    }
    assert_int_equal(out.sample.t_us, 5002);
    assert_int_equal(out.sample.sequence, 8);

    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.frames_total, 8);
    assert_int_equal(st.frames_sample, 8);
    assert_int_equal(st.samples_started, 2);
    assert_int_equal(st.samples_ok, 2);
    assert_int_equal(st.frames_bad, 0);
    assert_int_equal(st.samples_incomplete, 0);
    assert_int_equal(st.sequence_gaps, 0);
    check_invariants(&st);
    loadid_jr3_decoder_destroy(dec);
}

static void test_encode_hand_frames(void **state) {
    (void)state;
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    loadid_can_frame_t fr[4];
    assert_int_equal(loadid_jr3_encode(&cfg, HAND_SI, 7, 0, 123456789, fr), 0);
    for (int g = 0; g < 4; ++g) {
        assert_int_equal(fr[g].id, BASE + (uint32_t)g);
        assert_int_equal(fr[g].dlc, 8);
        assert_false(fr[g].extended);
        assert_int_equal(fr[g].t_us, 123456789);
        assert_memory_equal(fr[g].data, HAND[g], 8);
    }

    /* Rounding half away from zero, one force count = 200/16384 N. */
    const double c = 200.0 / COUNT_FS;
    double v[4][3] = {{0.5 * c, -0.5 * c, 0.49 * c}, {0}, {0}, {0}};
    assert_int_equal(loadid_jr3_encode(&cfg, v, 255, 0, 0, fr), 0);
    const uint8_t want[8] = {0x01, 0x00, 0xFF, 0xFF, 0x00, 0x00, 0xFF, 0x00};
    assert_memory_equal(fr[0].data, want, 8);

    /* Another base id. */
    cfg.base_id = 0x300;
    assert_int_equal(loadid_jr3_encode(&cfg, HAND_SI, 7, 0, 0, fr), 0);
    for (int g = 0; g < 4; ++g) {
        assert_int_equal(fr[g].id, 0x300u + (uint32_t)g);
    }
}

static void test_round_trip_random(void **state) {
    (void)state;
    mix_state = 42;
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    /* Non-default full scales, per axis, so that X/Y/Z mix-ups show. */
    for (int g = 0; g < 4; ++g) {
        for (int k = 0; k < 3; ++k) {
            cfg.full_scale[g][k] *= 0.5 + next_unit();
        }
    }
    loadid_jr3_decoder_t *dec = NULL;
    assert_int_equal(loadid_jr3_decoder_create(&cfg, &dec), 0);
    loadid_jr3_output_t out;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        double v[4][3];
        for (int g = 0; g < 4; ++g) {
            for (int k = 0; k < 3; ++k) {
                /* Within the int16 range: |v| < 1.99 full scales. */
                v[g][k] = (2.0 * next_unit() - 1.0) * 1.99 * cfg.full_scale[g][k];
            }
        }
        loadid_can_frame_t fr[4];
        uint8_t seq = (uint8_t)i;
        assert_int_equal(loadid_jr3_encode(&cfg, v, seq, 0, 1000 * (int64_t)i, fr), 0);
        int rc = LOADID_JR3_NONE;
        for (int g = 0; g < 4; ++g) {
            rc = loadid_jr3_decoder_feed(dec, &fr[g], &out);
        }
        assert_int_equal(rc, LOADID_JR3_SAMPLE);
        assert_int_equal(out.sample.sequence, seq);
        assert_int_equal(out.sample.t_us, 1000 * (int64_t)i);
        for (int g = 0; g < 4; ++g) {
            for (int k = 0; k < 3; ++k) {
                double count = cfg.full_scale[g][k] / COUNT_FS;
                /* Rounding to the nearest count: half a count at most. */
                ASSERT_CLOSE(out.sample.value[g][k], v[g][k], 0.5 * count * (1 + 1e-12),
                             "round trip within half a count");
                assert_int_equal(out.sample.counts[g][k],
                                 (int)round(v[g][k] * COUNT_FS / cfg.full_scale[g][k]));
            }
        }
    }
    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.samples_ok, n);
    assert_int_equal(st.sequence_gaps, 0); /* 255 -> 0 wraps without a gap */
    check_invariants(&st);
    loadid_jr3_decoder_destroy(dec);
}

static void test_saturation(void **state) {
    (void)state;
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    const double fc = 200.0 / COUNT_FS;
    double v[4][3] = {{0}};
    loadid_can_frame_t fr[4];

    /* At the edges: 32767.4 and -32768.4 counts round into range. */
    v[0][0] = 32767.4 * fc;
    v[0][1] = -32768.4 * fc;
    assert_int_equal(loadid_jr3_encode(&cfg, v, 1, 0, 0, fr), 0);
    const uint8_t edge[8] = {0xFF, 0x7F, 0x00, 0x80, 0x00, 0x00, 0x01, 0x00};
    assert_memory_equal(fr[0].data, edge, 8);

    /* 32767.5 rounds to 32768: clamped, saturated. Angular -3 fs too. */
    v[0][0] = 32767.5 * fc;
    v[0][1] = 0;
    v[3][2] = -3.0 * 1000.0;
    assert_int_equal(loadid_jr3_encode(&cfg, v, 2, 0, 0, fr), 0x1 | 0x8);
    const uint8_t sat0[8] = {0xFF, 0x7F, 0x00, 0x00, 0x00, 0x00, 0x02, 0x01};
    const uint8_t sat3[8] = {0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x02, 0x01};
    assert_memory_equal(fr[0].data, sat0, 8);
    assert_memory_equal(fr[3].data, sat3, 8);
    assert_int_equal(fr[1].data[7], 0);
    assert_int_equal(fr[2].data[7], 0);

    /* +-Inf saturates; NaN is refused. */
    v[0][0] = 0;
    v[3][2] = 0;
    v[1][1] = INFINITY;
    v[2][0] = -INFINITY;
    assert_int_equal(loadid_jr3_encode(&cfg, v, 3, 0, 0, fr), 0x2 | 0x4);
    assert_int_equal(fr[1].data[2] | fr[1].data[3] << 8, 0x7FFF);
    assert_int_equal(fr[2].data[0] | fr[2].data[1] << 8, 0x8000);
    v[1][1] = NAN;
    assert_int_equal(loadid_jr3_encode(&cfg, v, 3, 0, 0, fr), -EINVAL);

    /* Decoding a saturated sample: flagged, not usable, counted. */
    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;
    int rc = 0;
    for (int g = 0; g < 4; ++g) {
        uint8_t b[8];
        memcpy(b, HAND[g], 8);
        if (g == 2) {
            b[7] = LOADID_JR3_STATUS_SATURATED;
        }
        loadid_can_frame_t f = make_frame(BASE + (uint32_t)g, 10, b);
        rc = loadid_jr3_decoder_feed(dec, &f, &out);
    }
    assert_int_equal(rc, LOADID_JR3_E_SATURATED);
    assert_true(out.sample.saturated);
    assert_false(out.sample.faulty);
    assert_int_equal(out.sample.status[2], 1);
    assert_int_equal(out.sample.counts[0][0], 16384); /* still there for logging */
    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.samples_ok, 0);
    assert_int_equal(st.samples_saturated, 1);
    assert_int_equal(st.samples_rejected, 1);
    assert_int_equal(st.samples_faulty, 0);
    check_invariants(&st);
    loadid_jr3_decoder_destroy(dec);
}

static void test_fault(void **state) {
    (void)state;
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    double v[4][3] = {{1, 2, 3}, {0.1, 0.2, 0.3}, {0, 0, 9.81}, {1, 2, 3}};
    loadid_can_frame_t fr[4];
    assert_int_equal(loadid_jr3_encode(&cfg, v, 9, LOADID_JR3_ALL_GROUPS, 0, fr), 0);
    for (int g = 0; g < 4; ++g) {
        assert_int_equal(fr[g].data[7], LOADID_JR3_STATUS_FAULT);
    }
    assert_int_equal(loadid_jr3_encode(&cfg, v, 9, 1u << LOADID_JR3_LINEAR, 0, fr), 0);
    for (int g = 0; g < 4; ++g) {
        assert_int_equal(fr[g].data[7], g == LOADID_JR3_LINEAR ? 0x02 : 0x00);
    }
    assert_int_equal(loadid_jr3_encode(&cfg, v, 9, 16, 0, fr), -EINVAL);

    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;
    int rc = 0;
    assert_int_equal(loadid_jr3_encode(&cfg, v, 9, 1u << LOADID_JR3_LINEAR, 0, fr), 0);
    for (int g = 0; g < 4; ++g) {
        rc = loadid_jr3_decoder_feed(dec, &fr[g], &out);
    }
    assert_int_equal(rc, LOADID_JR3_E_FAULT);
    assert_true(out.sample.faulty);
    assert_false(out.sample.saturated);

    /* Saturated and faulty: E_FAULT, counted in both, rejected once. */
    v[0][2] = 1e6;
    assert_int_equal(loadid_jr3_encode(&cfg, v, 10, LOADID_JR3_ALL_GROUPS, 0, fr), 0x1);
    assert_int_equal(fr[0].data[7], 0x03);
    for (int g = 0; g < 4; ++g) {
        rc = loadid_jr3_decoder_feed(dec, &fr[g], &out);
    }
    assert_int_equal(rc, LOADID_JR3_E_FAULT);
    assert_true(out.sample.faulty);
    assert_true(out.sample.saturated);
    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.samples_faulty, 2);
    assert_int_equal(st.samples_saturated, 1);
    assert_int_equal(st.samples_rejected, 2);
    assert_int_equal(st.samples_ok, 0);
    check_invariants(&st);
    loadid_jr3_decoder_destroy(dec);
}

static void test_full_scale_frame_encode(void **state) {
    (void)state;
    loadid_can_frame_t f;
    double sent[3];
    /* Linear: 98.1, 50, 9.81 m/s^2 -> 9810, 5000, 981 units of 0.01. */
    const double lin[3] = {98.1, 50.0, 9.81};
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, LOADID_JR3_LINEAR, lin, 77, &f, sent), 0);
    const uint8_t want[8] = {0x02, 0x00, 0x52, 0x26, 0x88, 0x13, 0xD5, 0x03};
    assert_int_equal(f.id, 0x1A4);
    assert_int_equal(f.dlc, 8);
    assert_false(f.extended);
    assert_int_equal(f.t_us, 77);
    assert_memory_equal(f.data, want, 8);
    assert_true(sent[0] == 98.1 && sent[1] == 50.0 && sent[2] == 9.81);

    /* Unit rounding: force in 0.1 N (200.04 -> 2000), moment 0.01 N m. */
    const double force[3] = {200.04, 0.05, 6553.5};
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, LOADID_JR3_FORCE, force, 0, &f, sent), 0);
    const uint8_t wantf[8] = {0x00, 0x00, 0xD0, 0x07, 0x01, 0x00, 0xFF, 0xFF};
    assert_memory_equal(f.data, wantf, 8);
    assert_true(sent[0] == 200.0 && sent[1] == 0.1 && sent[2] == 6553.5);
    const double ang[3] = {1000.0, 1000.0, 1000.0};
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, LOADID_JR3_ANGULAR, ang, 0, &f, NULL), 0);
    const uint8_t wanta[8] = {0x03, 0x00, 0x10, 0x27, 0x10, 0x27, 0x10, 0x27};
    assert_memory_equal(f.data, wanta, 8);

    /* Out of range: rounds to 0 or above 65535 units. */
    const double tiny[3] = {12.0, 0.004, 12.0};
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, LOADID_JR3_MOMENT, tiny, 0, &f, NULL),
                     LOADID_JR3_E_RANGE);
    const double huge[3] = {6553.6, 1, 1};
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, LOADID_JR3_FORCE, huge, 0, &f, NULL),
                     LOADID_JR3_E_RANGE);
    const double neg[3] = {-1, 1, 1};
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, LOADID_JR3_FORCE, neg, 0, &f, NULL),
                     LOADID_JR3_E_RANGE);
    const double nan3[3] = {NAN, 1, 1};
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, LOADID_JR3_FORCE, nan3, 0, &f, NULL),
                     -EINVAL);
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, 4, ang, 0, &f, NULL), -EINVAL);
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, -1, ang, 0, &f, NULL), -EINVAL);
    assert_int_equal(loadid_jr3_encode_full_scale(0x7FC, 0, ang, 0, &f, NULL), -EINVAL);
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, 0, NULL, 0, &f, NULL), -EINVAL);
    assert_int_equal(loadid_jr3_encode_full_scale(BASE, 0, ang, 0, NULL, NULL), -EINVAL);
}

static void feed_sample(loadid_jr3_decoder_t *dec, const uint8_t frames[4][8], uint8_t seq,
                        int expect_rc, loadid_jr3_output_t *out) {
    int rc = 0;
    for (int g = 0; g < 4; ++g) {
        uint8_t b[8];
        memcpy(b, frames[g], 8);
        b[6] = seq;
        loadid_can_frame_t f = make_frame(BASE + (uint32_t)g, 100 * seq + g, b);
        rc = loadid_jr3_decoder_feed(dec, &f, out);
    }
    assert_int_equal(rc, expect_rc);
}

static void test_full_scale_override(void **state) {
    (void)state;
    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;

    /* Force full scales 100, 200, 400 N: 1000, 2000, 4000 units of 0.1 N. */
    const uint8_t fs_frame[8] = {0x00, 0x00, 0xE8, 0x03, 0xD0, 0x07, 0xA0, 0x0F};
    loadid_can_frame_t f = make_frame(BASE + 4, 4242, fs_frame);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_FULL_SCALE);
    assert_int_equal(out.full_scale.group, LOADID_JR3_FORCE);
    assert_int_equal(out.full_scale.t_us, 4242);
    for (int k = 0; k < 3; ++k) {
        assert_true(out.full_scale.previous[k] == 200.0);
    }
    assert_true(out.full_scale.current[0] == 100.0);
    assert_true(out.full_scale.current[1] == 200.0);
    assert_true(out.full_scale.current[2] == 400.0);

    /* The hand sample now reads force 16384 -> 100 N, -16384 -> -200 N,
     * 1 -> 400/16384 N; the other groups as before. */
    feed_sample(dec, HAND, 7, LOADID_JR3_SAMPLE, &out);
    assert_true(out.sample.value[0][0] == 100.0);
    assert_true(out.sample.value[0][1] == -200.0);
    assert_true(out.sample.value[0][2] == 0.0244140625);
    assert_true(out.sample.value[1][0] == 6.0);
    assert_true(out.sample.value[3][2] == 0.9765625);

    /* The periodic repetition: valid, counted, not a change. */
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    double fs[4][3];
    assert_int_equal(loadid_jr3_decoder_full_scale(dec, fs), 0);
    assert_true(fs[0][0] == 100.0 && fs[0][2] == 400.0 && fs[1][0] == 12.0 && fs[2][1] == 98.1 &&
                fs[3][2] == 1000.0);

    /* Linear 9.81 m/s^2 (981 units): counts 16384 -> 9.81. Arriving between
     * the frames of one sample, it applies to the frames after it. */
    const uint8_t lin_frame[8] = {0x02, 0x00, 0xD5, 0x03, 0xD5, 0x03, 0xD5, 0x03};
    uint8_t b[8];
    memcpy(b, HAND[2], 8);
    b[0] = 0x00;
    b[1] = 0x40; /* linear X = 16384 counts */
    b[6] = 9;
    loadid_can_frame_t l1 = make_frame(BASE + 2, 1, b);
    loadid_can_frame_t fl = make_frame(BASE + 4, 2, lin_frame);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &l1, &out), LOADID_JR3_NONE);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &fl, &out), LOADID_JR3_FULL_SCALE);
    assert_int_equal(out.full_scale.group, LOADID_JR3_LINEAR);
    assert_true(out.full_scale.previous[0] == 98.1 && out.full_scale.current[0] == 9.81);
    int rc = 0;
    for (int g = 0; g < 4; ++g) {
        if (g == 2) {
            continue;
        }
        memcpy(b, HAND[g], 8);
        b[6] = 9;
        loadid_can_frame_t fg = make_frame(BASE + (uint32_t)g, 3, b);
        rc = loadid_jr3_decoder_feed(dec, &fg, &out);
    }
    assert_int_equal(rc, LOADID_JR3_SAMPLE);
    assert_true(out.sample.value[2][0] == 98.1); /* came before the change */
    feed_sample(dec, HAND, 10, LOADID_JR3_SAMPLE, &out);
    assert_true(out.sample.value[2][0] == 2.4525); /* 4096 * 9.81 / 16384 */
    assert_true(out.sample.value[2][1] == -19.62);

    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.full_scale_frames, 3);
    assert_int_equal(st.full_scale_changes, 2);
    assert_int_equal(st.samples_ok, 3);
    check_invariants(&st);

    /* Reset: back to the configured full scales and zero counters. */
    loadid_jr3_decoder_reset(dec);
    assert_int_equal(loadid_jr3_decoder_full_scale(dec, fs), 0);
    assert_true(fs[0][0] == 200.0 && fs[2][0] == 98.1);
    st = stats_of(dec);
    assert_int_equal(st.frames_total, 0);
    feed_sample(dec, HAND, 7, LOADID_JR3_SAMPLE, &out);
    assert_hand_sample(&out.sample, 700);
    loadid_jr3_decoder_destroy(dec);
}

static void test_malformed_counted(void **state) {
    (void)state;
    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;
    const uint8_t ok_fs[8] = {0x01, 0x00, 0xB0, 0x04, 0xB0, 0x04, 0xB0, 0x04}; /* 12 N m */

    /* Start a sample: bad frames in between must not disturb it. */
    loadid_can_frame_t f0 = make_frame(BASE, 1, HAND[0]);
    loadid_can_frame_t f1 = make_frame(BASE + 1, 2, HAND[1]);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f0, &out), LOADID_JR3_NONE);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f1, &out), LOADID_JR3_NONE);

    int64_t n_unknown = 0, n_dlc = 0, n_malformed = 0, n_reserved = 0;
    /* Unknown ids: below, above, far, the same id extended. */
    const uint32_t unknown[] = {BASE - 1, BASE + 5, 0x000, 0x7FF, 0x123};
    for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
        loadid_can_frame_t f = make_frame(unknown[i], 0, HAND[0]);
        assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_UNKNOWN_ID);
        ++n_unknown;
    }
    for (uint32_t off = 0; off <= 4; ++off) {
        loadid_can_frame_t f = make_frame(BASE + off, 0, off == 4 ? ok_fs : HAND[off]);
        f.extended = true;
        assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_UNKNOWN_ID);
        ++n_unknown;
    }
    /* An extended id that is base after masking to 11 bits. */
    loadid_can_frame_t fe = make_frame(0x800u | BASE, 0, HAND[0]);
    fe.extended = true;
    assert_int_equal(loadid_jr3_decoder_feed(dec, &fe, &out), LOADID_JR3_E_UNKNOWN_ID);
    ++n_unknown;
    fe.extended = false; /* a standard id above 0x7FF cannot exist */
    assert_int_equal(loadid_jr3_decoder_feed(dec, &fe, &out), LOADID_JR3_E_UNKNOWN_ID);
    ++n_unknown;

    /* Wrong DLC on every id, including 9..15 and 0. */
    const uint8_t dlcs[] = {0, 1, 7, 9, 15, 255};
    for (uint32_t off = 0; off <= 4; ++off) {
        for (size_t i = 0; i < sizeof dlcs; ++i) {
            loadid_can_frame_t f = make_frame(BASE + off, 0, off == 4 ? ok_fs : HAND[off]);
            f.dlc = dlcs[i];
            assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_DLC);
            ++n_dlc;
        }
    }

    /* Malformed base+4: group > 3, byte 1 != 0, a zero full scale. */
    const uint8_t bad_fs[][8] = {
        {0x04, 0x00, 0xB0, 0x04, 0xB0, 0x04, 0xB0, 0x04},
        {0xFF, 0x00, 0xB0, 0x04, 0xB0, 0x04, 0xB0, 0x04},
        {0x01, 0x01, 0xB0, 0x04, 0xB0, 0x04, 0xB0, 0x04},
        {0x01, 0x80, 0xB0, 0x04, 0xB0, 0x04, 0xB0, 0x04},
        {0x01, 0x00, 0x00, 0x00, 0xB0, 0x04, 0xB0, 0x04},
        {0x01, 0x00, 0xB0, 0x04, 0x00, 0x00, 0xB0, 0x04},
        {0x01, 0x00, 0xB0, 0x04, 0xB0, 0x04, 0x00, 0x00},
    };
    for (size_t i = 0; i < sizeof bad_fs / sizeof bad_fs[0]; ++i) {
        loadid_can_frame_t f = make_frame(BASE + 4, 0, bad_fs[i]);
        assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_MALFORMED);
        ++n_malformed;
    }

    /* Reserved status bits, each of 2..7, on each data frame. */
    for (uint32_t off = 0; off < 4; ++off) {
        for (int bit = 2; bit < 8; ++bit) {
            uint8_t b[8];
            memcpy(b, HAND[off], 8);
            b[7] = (uint8_t)(1u << bit);
            loadid_can_frame_t f = make_frame(BASE + off, 0, b);
            assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_RESERVED);
            ++n_reserved;
        }
    }

    /* The valid base+4 (12 N m, the default) is no change. */
    loadid_can_frame_t ffs = make_frame(BASE + 4, 0, ok_fs);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &ffs, &out), LOADID_JR3_NONE);

    /* The sample started before completes undisturbed. */
    loadid_can_frame_t f2 = make_frame(BASE + 2, 3, HAND[2]);
    loadid_can_frame_t f3 = make_frame(BASE + 3, 4, HAND[3]);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f2, &out), LOADID_JR3_NONE);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f3, &out), LOADID_JR3_SAMPLE);
    assert_hand_sample(&out.sample, 1);

    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.frames_unknown_id, n_unknown);
    assert_int_equal(st.frames_bad_dlc, n_dlc);
    assert_int_equal(st.frames_malformed, n_malformed);
    assert_int_equal(st.frames_reserved, n_reserved);
    assert_int_equal(st.frames_bad, n_unknown + n_dlc + n_malformed + n_reserved);
    assert_int_equal(st.full_scale_frames, 1);
    assert_int_equal(st.full_scale_changes, 0);
    assert_int_equal(st.samples_ok, 1);
    assert_int_equal(st.samples_incomplete, 0);
    assert_int_equal(st.frames_total, st.frames_bad + 5);
    check_invariants(&st);
    /* Bad frames changed no full scale. */
    double fs[4][3];
    assert_int_equal(loadid_jr3_decoder_full_scale(dec, fs), 0);
    assert_true(fs[0][0] == 200.0 && fs[1][0] == 12.0 && fs[1][1] == 12.0);
    loadid_jr3_decoder_destroy(dec);
}

static void test_sequence_wrap_and_gaps(void **state) {
    (void)state;
    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;
    /* 254, 255, 0, 1: consecutive across the wrap, no gap. */
    const uint8_t seqs[] = {254, 255, 0, 1};
    for (size_t i = 0; i < sizeof seqs; ++i) {
        feed_sample(dec, HAND, seqs[i], LOADID_JR3_SAMPLE, &out);
        assert_int_equal(out.sample.sequence, seqs[i]);
    }
    assert_int_equal(stats_of(dec).sequence_gaps, 0);
    /* 1 -> 5: 2, 3, 4 missing. */
    feed_sample(dec, HAND, 5, LOADID_JR3_SAMPLE, &out);
    assert_int_equal(stats_of(dec).sequence_gaps, 3);
    /* 5 -> 250 -> 2: 244 missing, then 251..255, 0, 1 = 7 across the wrap. */
    feed_sample(dec, HAND, 250, LOADID_JR3_SAMPLE, &out);
    assert_int_equal(stats_of(dec).sequence_gaps, 3 + 244);
    feed_sample(dec, HAND, 2, LOADID_JR3_SAMPLE, &out);
    assert_int_equal(stats_of(dec).sequence_gaps, 3 + 244 + 7);
    /* 2 -> 3 again consecutive. */
    feed_sample(dec, HAND, 3, LOADID_JR3_SAMPLE, &out);
    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.sequence_gaps, 254);
    assert_int_equal(st.samples_ok, 8);
    assert_int_equal(st.samples_incomplete, 0);
    check_invariants(&st);
    loadid_jr3_decoder_destroy(dec);
}

static loadid_can_frame_t seq_frame(int g, uint8_t seq) {
    uint8_t b[8];
    memcpy(b, HAND[g], 8);
    b[6] = seq;
    return make_frame(BASE + (uint32_t)g, seq, b);
}

static void test_incomplete_and_duplicates(void **state) {
    (void)state;
    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;
    loadid_can_frame_t f;

    /* Sequence 10 loses its base+3; 11 arrives complete. */
    for (int g = 0; g < 3; ++g) {
        f = seq_frame(g, 10);
        assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    }
    feed_sample(dec, HAND, 11, LOADID_JR3_SAMPLE, &out);
    loadid_jr3_stats_t st = stats_of(dec);
    assert_int_equal(st.samples_incomplete, 1);
    assert_int_equal(st.samples_ok, 1);
    assert_int_equal(st.sequence_gaps, 0);

    /* Interleaved 20 and 21: every switch abandons the open sample; the
     * gap from 21 back to 20 is 254 (modulo 256). */
    f = seq_frame(0, 20);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(0, 21);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(1, 20);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(1, 21);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    st = stats_of(dec);
    assert_int_equal(st.samples_incomplete, 1 + 3);
    assert_int_equal(st.sequence_gaps, 8 + 0 + 254 + 0); /* 11 -> 20: 12..19 */
    /* 21 then completes from its last two frames? No: its base+0 went with
     * the abandoned first 21. It is open with base+1 only. */
    f = seq_frame(2, 21);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(3, 21);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(0, 21);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_SAMPLE);
    assert_int_equal(out.sample.t_us, 21);

    /* A duplicate while open: E_DUPLICATE, the sample is abandoned, the rest
     * of its frames are discarded, and the next one is fine. */
    int64_t inc0 = stats_of(dec).samples_incomplete;
    f = seq_frame(0, 30);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(1, 30);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_DUPLICATE);
    f = seq_frame(2, 30);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(3, 30);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    f = seq_frame(0, 30);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_NONE);
    st = stats_of(dec);
    assert_int_equal(st.samples_incomplete, inc0 + 1);
    assert_int_equal(st.frames_duplicate, 1);
    assert_int_equal(st.frames_discarded, 3);
    feed_sample(dec, HAND, 31, LOADID_JR3_SAMPLE, &out);

    /* A duplicate after completion: counted, the sample stays delivered. */
    f = seq_frame(2, 31);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_DUPLICATE);
    st = stats_of(dec);
    assert_int_equal(st.samples_incomplete, inc0 + 1);
    assert_int_equal(st.frames_duplicate, 2);
    feed_sample(dec, HAND, 32, LOADID_JR3_SAMPLE, &out);

    st = stats_of(dec);
    assert_int_equal(st.samples_ok, 4); /* 11, 21, 31, 32 */
    assert_int_equal(st.sequence_gaps, 8 + 254 + (30 - 21 - 1));
    check_invariants(&st);
    /* Nothing open now. */
    assert_int_equal(st.samples_started,
                     st.samples_ok + st.samples_rejected + st.samples_incomplete);
    loadid_jr3_decoder_destroy(dec);
}

/* Random frames, mostly near the JR3's ids with plausible contents so that
 * every path runs: no crash (ASan/UBSan in the asan build), counters equal
 * the tally of return codes, invariants hold after every frame, and every
 * usable sample is finite and unflagged. */
static void test_fuzz(void **state) {
    (void)state;
    mix_state = 2024;
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    loadid_jr3_decoder_t *dec = NULL;
    assert_int_equal(loadid_jr3_decoder_create(&cfg, &dec), 0);

    int64_t tally[8] = {0}; /* by result */
    enum { T_SAMPLE, T_SAT, T_FAULT, T_FS, T_DUP, T_BAD, T_NONE };
    int64_t bad_by_code[4] = {0};
    const int n = 300000;
    loadid_jr3_output_t out;
    /* A clean stream from the encoder (random values, some saturated or
     * faulty), with frames dropped, repeated and swapped, mixed with
     * garbage. */
    loadid_can_frame_t stream[4];
    int stream_pos = 4;
    uint8_t stream_seq = 0;
    for (int i = 0; i < n; ++i) {
        loadid_can_frame_t f;
        memset(&f, 0, sizeof f);
        if (next_below(10) < 6) {
            if (stream_pos == 4) {
                double v[4][3];
                for (int g = 0; g < 4; ++g) {
                    for (int k = 0; k < 3; ++k) {
                        v[g][k] = (2.0 * next_unit() - 1.0) * 2.05 * cfg.full_scale[g][k];
                    }
                }
                unsigned fault = next_below(20) == 0 ? 1u << next_below(4) : 0;
                stream_seq = (uint8_t)(stream_seq + 1 + (next_below(20) == 0));
                assert_true(loadid_jr3_encode(&cfg, v, stream_seq, fault, i, stream) >= 0);
                if (next_below(10) == 0) { /* swap two frames */
                    unsigned a = next_below(4), b = next_below(4);
                    loadid_can_frame_t t = stream[a];
                    stream[a] = stream[b];
                    stream[b] = t;
                }
                stream_pos = 0;
            }
            unsigned r = next_below(100);
            f = stream[stream_pos];
            if (r < 2) {
                /* repeat this frame (a duplicate next time) */
            } else {
                ++stream_pos;
                if (r < 4 && stream_pos < 4) {
                    ++stream_pos; /* drop one */
                }
            }
            if (next_below(200) == 0) {
                f.data[next_below(8)] ^= (uint8_t)(1u << next_below(8)); /* a bit flip */
            }
        } else {
            for (int k = 0; k < 8; ++k) {
                f.data[k] = (uint8_t)next_u64();
            }
            unsigned r = next_below(100);
            if (r < 5) {
                f.id = (uint32_t)next_u64() & LOADID_CAN_EFF_MASK;
                f.extended = true;
            } else if (r < 10) {
                f.id = (uint32_t)next_u64(); /* even out-of-range ids */
                f.extended = next_below(2);
            } else if (r < 25) {
                f.id = (uint32_t)next_below(0x800);
            } else {
                f.id = BASE - 2 + next_below(8);
            }
            f.dlc = next_below(10) == 0 ? (uint8_t)next_u64() : 8;
            f.t_us = (int64_t)next_u64();
            /* Plausible fields most of the time. */
            if (next_below(4) != 0) {
                f.data[6] = (uint8_t)(stream_seq + next_below(3));
                unsigned s = next_below(20);
                f.data[7] = s < 15 ? 0 : s < 17 ? 1 : s < 19 ? 2 : (uint8_t)next_u64();
            }
            if (f.id == BASE + 4 && next_below(2)) {
                f.data[0] = (uint8_t)next_below(5);
                f.data[1] = next_below(8) ? 0 : 1;
            }
        }
        int rc = loadid_jr3_decoder_feed(dec, &f, &out);
        switch (rc) {
            case LOADID_JR3_SAMPLE:
                ++tally[T_SAMPLE];
                assert_false(out.sample.saturated);
                assert_false(out.sample.faulty);
                for (int g = 0; g < 4; ++g) {
                    assert_int_equal(out.sample.status[g], 0);
                    for (int k = 0; k < 3; ++k) {
                        assert_true(isfinite(out.sample.value[g][k]));
                        /* |counts| <= 32768, full scale <= 65535 units. */
                        assert_true(fabs(out.sample.value[g][k]) <= 2.0 * 6553.5);
                    }
                }
                break;
            case LOADID_JR3_E_SATURATED:
                ++tally[T_SAT];
                assert_true(out.sample.saturated);
                assert_false(out.sample.faulty);
                break;
            case LOADID_JR3_E_FAULT:
                ++tally[T_FAULT];
                assert_true(out.sample.faulty);
                break;
            case LOADID_JR3_FULL_SCALE:
                ++tally[T_FS];
                assert_true(out.full_scale.group >= 0 && out.full_scale.group < 4);
                for (int k = 0; k < 3; ++k) {
                    assert_true(out.full_scale.current[k] > 0);
                }
                break;
            case LOADID_JR3_E_DUPLICATE:
                ++tally[T_DUP];
                break;
            case LOADID_JR3_E_UNKNOWN_ID:
                ++bad_by_code[0];
                ++tally[T_BAD];
                break;
            case LOADID_JR3_E_DLC:
                ++bad_by_code[1];
                ++tally[T_BAD];
                break;
            case LOADID_JR3_E_MALFORMED:
                ++bad_by_code[2];
                ++tally[T_BAD];
                break;
            case LOADID_JR3_E_RESERVED:
                ++bad_by_code[3];
                ++tally[T_BAD];
                break;
            case LOADID_JR3_NONE:
                ++tally[T_NONE];
                break;
            default:
                fail_msg("unexpected return %d at frame %d", rc, i);
        }
        if (i % 97 == 0 || i == n - 1) {
            loadid_jr3_stats_t st = stats_of(dec);
            check_invariants(&st);
            assert_int_equal(st.frames_total, i + 1);
            assert_int_equal(st.samples_ok, tally[T_SAMPLE]);
            assert_int_equal(st.samples_rejected, tally[T_SAT] + tally[T_FAULT]);
            assert_int_equal(st.full_scale_changes, tally[T_FS]);
            assert_int_equal(st.frames_duplicate, tally[T_DUP]);
            assert_int_equal(st.frames_bad, tally[T_BAD]);
            assert_int_equal(st.frames_unknown_id, bad_by_code[0]);
            assert_int_equal(st.frames_bad_dlc, bad_by_code[1]);
            assert_int_equal(st.frames_malformed, bad_by_code[2]);
            assert_int_equal(st.frames_reserved, bad_by_code[3]);
        }
    }
    loadid_jr3_stats_t st = stats_of(dec);
    print_message(
        "fuzz: %lld frames: ok %lld rejected %lld incomplete %lld bad %lld "
        "(id %lld dlc %lld malformed %lld reserved %lld) dup %lld discarded %lld "
        "fs changes %lld gaps %lld\n",
        (long long)st.frames_total, (long long)st.samples_ok, (long long)st.samples_rejected,
        (long long)st.samples_incomplete, (long long)st.frames_bad, (long long)st.frames_unknown_id,
        (long long)st.frames_bad_dlc, (long long)st.frames_malformed, (long long)st.frames_reserved,
        (long long)st.frames_duplicate, (long long)st.frames_discarded,
        (long long)st.full_scale_changes, (long long)st.sequence_gaps);
    /* Every path was taken. */
    for (int t = T_SAMPLE; t <= T_NONE; ++t) {
        assert_true(tally[t] > 0);
    }
    for (int c = 0; c < 4; ++c) {
        assert_true(bad_by_code[c] > 0);
    }
    assert_true(st.samples_incomplete > 0 && st.frames_discarded > 0);
    loadid_jr3_decoder_destroy(dec);
}

static void test_config_and_arguments(void **state) {
    (void)state;
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    assert_int_equal(cfg.base_id, 0x1A0);
    const double want[4] = {200.0, 12.0, 98.1, 1000.0};
    for (int g = 0; g < 4; ++g) {
        for (int k = 0; k < 3; ++k) {
            assert_true(cfg.full_scale[g][k] == want[g]);
        }
    }
    assert_int_equal(loadid_jr3_config_check(&cfg), 0);
    assert_int_equal(loadid_jr3_config_check(NULL), -EINVAL);
    loadid_jr3_config_t bad = cfg;
    bad.base_id = 0x7FB;
    assert_int_equal(loadid_jr3_config_check(&bad), 0);
    bad.base_id = 0x7FC;
    assert_int_equal(loadid_jr3_config_check(&bad), -EINVAL);
    const double bad_fs[] = {0.0, -1.0, NAN, INFINITY};
    for (size_t i = 0; i < 4; ++i) {
        bad = cfg;
        bad.full_scale[3][2] = bad_fs[i];
        assert_int_equal(loadid_jr3_config_check(&bad), -EINVAL);
        loadid_jr3_decoder_t *d = (loadid_jr3_decoder_t *)&bad; /* must be overwritten */
        assert_int_equal(loadid_jr3_decoder_create(&bad, &d), -EINVAL);
        assert_null(d);
        loadid_can_frame_t fr[4];
        assert_int_equal(loadid_jr3_encode(&bad, HAND_SI, 0, 0, 0, fr), -EINVAL);
    }

    loadid_jr3_decoder_t *dec = new_decoder();
    loadid_jr3_output_t out;
    loadid_can_frame_t f = make_frame(BASE, 0, HAND[0]);
    assert_int_equal(loadid_jr3_decoder_create(&cfg, NULL), -EINVAL);
    assert_int_equal(loadid_jr3_decoder_feed(NULL, &f, &out), -EINVAL);
    assert_int_equal(loadid_jr3_decoder_feed(dec, NULL, &out), -EINVAL);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, NULL), -EINVAL);
    assert_int_equal(stats_of(dec).frames_total, 0); /* nothing counted */
    loadid_jr3_stats_t st;
    assert_int_equal(loadid_jr3_decoder_stats(NULL, &st), -EINVAL);
    assert_int_equal(loadid_jr3_decoder_stats(dec, NULL), -EINVAL);
    double fs[4][3];
    assert_int_equal(loadid_jr3_decoder_full_scale(NULL, fs), -EINVAL);
    assert_int_equal(loadid_jr3_decoder_full_scale(dec, NULL), -EINVAL);
    loadid_can_frame_t fr[4];
    assert_int_equal(loadid_jr3_encode(NULL, HAND_SI, 0, 0, 0, fr), -EINVAL);
    assert_int_equal(loadid_jr3_encode(&cfg, NULL, 0, 0, 0, fr), -EINVAL);
    assert_int_equal(loadid_jr3_encode(&cfg, HAND_SI, 0, 0, 0, NULL), -EINVAL);
    loadid_jr3_decoder_reset(NULL);
    loadid_jr3_decoder_destroy(NULL);
    loadid_jr3_decoder_destroy(dec);

    /* A base id at the top of the 11-bit range: base+4 = 0x7FF. */
    cfg.base_id = 0x7FB;
    assert_int_equal(loadid_jr3_decoder_create(&cfg, &dec), 0);
    const uint8_t fs_frame[8] = {0x00, 0x00, 0xE8, 0x03, 0xE8, 0x03, 0xE8, 0x03};
    f = make_frame(0x7FF, 0, fs_frame);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_FULL_SCALE);
    f = make_frame(0x1A0, 0, HAND[0]);
    assert_int_equal(loadid_jr3_decoder_feed(dec, &f, &out), LOADID_JR3_E_UNKNOWN_ID);
    loadid_jr3_decoder_destroy(dec);

    /* Every code has its own text. */
    const int codes[] = {LOADID_JR3_NONE,
                         LOADID_JR3_SAMPLE,
                         LOADID_JR3_FULL_SCALE,
                         LOADID_JR3_E_SATURATED,
                         LOADID_JR3_E_FAULT,
                         LOADID_JR3_E_UNKNOWN_ID,
                         LOADID_JR3_E_DLC,
                         LOADID_JR3_E_MALFORMED,
                         LOADID_JR3_E_RESERVED,
                         LOADID_JR3_E_DUPLICATE,
                         LOADID_JR3_E_RANGE,
                         -EINVAL,
                         -ENOMEM};
    const size_t nc = sizeof codes / sizeof codes[0];
    for (size_t i = 0; i < nc; ++i) {
        const char *a = loadid_jr3_strerror(codes[i]);
        assert_non_null(a);
        assert_string_not_equal(a, "unknown error");
        for (size_t j = 0; j < i; ++j) {
            assert_string_not_equal(a, loadid_jr3_strerror(codes[j]));
        }
    }
    assert_non_null(loadid_jr3_strerror(-99999));
    assert_string_equal(loadid_jr3_group_name(0), "force");
    assert_string_equal(loadid_jr3_group_name(3), "angular");
    assert_string_equal(loadid_jr3_group_name(4), "?");
    assert_string_equal(loadid_jr3_group_name(-1), "?");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decode_hand_frames),
        cmocka_unit_test(test_encode_hand_frames),
        cmocka_unit_test(test_round_trip_random),
        cmocka_unit_test(test_saturation),
        cmocka_unit_test(test_fault),
        cmocka_unit_test(test_full_scale_frame_encode),
        cmocka_unit_test(test_full_scale_override),
        cmocka_unit_test(test_malformed_counted),
        cmocka_unit_test(test_sequence_wrap_and_gaps),
        cmocka_unit_test(test_incomplete_and_duplicates),
        cmocka_unit_test(test_fuzz),
        cmocka_unit_test(test_config_and_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
