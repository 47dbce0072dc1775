/*
 * Fuzz target jr3: the JR3 decoder (drivers/src/jr3.c) fed a stream of CAN
 * frames, as the daemon feeds it from the bus. Input: 11 bytes a frame,
 *   id (2 bytes, little-endian): bits 0-14 the identifier, bit 15 extended
 *       (a standard frame keeps bits 0-10); 0xFFFF resets the decoder;
 *   dlc (1 byte, any value: above 8 is a malformed frame);
 *   data (8 bytes);
 * frames 1 ms apart. Beyond the sanitizers it checks what jr3.h promises:
 * only the documented return codes, the counter invariants after every
 * frame, the counters against a tally of the return codes, and samples
 * that are consistent with their result and in range.
 */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "fuzz_check.h"
#include "loadid/jr3.h"

#define FRAME_BYTES 11

typedef struct {
    int64_t fed, bad, sample, rejected, saturated, faulty, duplicate, full_scale;
} tally_t;

static void check_stats(const loadid_jr3_decoder_t *dec, const tally_t *t) {
    loadid_jr3_stats_t st;
    FUZZ_CHECK(loadid_jr3_decoder_stats(dec, &st) == 0);
    FUZZ_CHECK(st.frames_total == st.frames_bad + st.frames_sample + st.frames_duplicate +
                                      st.frames_discarded + st.full_scale_frames);
    FUZZ_CHECK(st.frames_bad ==
               st.frames_unknown_id + st.frames_bad_dlc + st.frames_malformed + st.frames_reserved);
    const int64_t open =
        st.samples_started - st.samples_ok - st.samples_rejected - st.samples_incomplete;
    FUZZ_CHECK(open == 0 || open == 1);
    FUZZ_CHECK(st.samples_saturated <= st.samples_rejected &&
               st.samples_faulty <= st.samples_rejected);
    FUZZ_CHECK(st.samples_rejected <= st.samples_saturated + st.samples_faulty);
    FUZZ_CHECK(st.full_scale_changes <= st.full_scale_frames);
    FUZZ_CHECK(st.sequence_gaps >= 0 && st.sequence_gaps <= 255 * st.samples_started);
    FUZZ_CHECK(st.frames_total == t->fed);
    FUZZ_CHECK(st.frames_bad == t->bad);
    FUZZ_CHECK(st.samples_ok == t->sample);
    FUZZ_CHECK(st.samples_rejected == t->rejected);
    FUZZ_CHECK(st.samples_faulty == t->faulty);
    /* E_FAULT wins over E_SATURATED: a faulty and saturated sample counts
     * in both but returns E_FAULT. */
    FUZZ_CHECK(st.samples_saturated >= t->saturated);
    FUZZ_CHECK(st.frames_duplicate == t->duplicate);
    FUZZ_CHECK(st.full_scale_changes == t->full_scale);
}

static void check_sample(const loadid_jr3_sample_t *s, int64_t t_first, int64_t t_now) {
    FUZZ_CHECK(s->t_us >= t_first && s->t_us <= t_now);
    bool saturated = false, faulty = false;
    for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
        FUZZ_CHECK((s->status[g] & LOADID_JR3_STATUS_RESERVED) == 0);
        saturated |= (s->status[g] & LOADID_JR3_STATUS_SATURATED) != 0;
        faulty |= (s->status[g] & LOADID_JR3_STATUS_FAULT) != 0;
        for (int k = 0; k < 3; ++k) {
            /* |counts| <= 32768 and a full scale at most 65535 units of
             * 0.1 (base+4) or the configured one (<= 1000 here). */
            FUZZ_CHECK(isfinite(s->value[g][k]));
            FUZZ_CHECK(fabs(s->value[g][k]) <= 2.0 * 6553.5);
            FUZZ_CHECK((s->value[g][k] == 0) == (s->counts[g][k] == 0));
            FUZZ_CHECK((s->value[g][k] < 0) == (s->counts[g][k] < 0));
        }
    }
    FUZZ_CHECK(s->saturated == saturated && s->faulty == faulty);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    loadid_jr3_decoder_t *dec = NULL;
    FUZZ_CHECK(loadid_jr3_decoder_create(&cfg, &dec) == 0);
    tally_t t;
    memset(&t, 0, sizeof t);
    const int64_t t0 = 1700000000000000;
    int64_t t_reset = t0;
    for (size_t i = 0; i + FRAME_BYTES <= size; i += FRAME_BYTES) {
        const uint8_t *b = data + i;
        const uint16_t raw = (uint16_t)(b[0] | b[1] << 8);
        const int64_t t_us = t0 + 1000 * (int64_t)(i / FRAME_BYTES);
        if (raw == 0xFFFF) {
            loadid_jr3_decoder_reset(dec);
            memset(&t, 0, sizeof t);
            t_reset = t_us;
            continue;
        }
        loadid_can_frame_t f;
        memset(&f, 0, sizeof f);
        f.extended = (raw & 0x8000) != 0;
        f.id = f.extended ? raw & 0x7FFFu : raw & LOADID_CAN_SFF_MASK;
        f.dlc = b[2];
        memcpy(f.data, b + 3, 8);
        f.t_us = t_us;

        double fs_before[LOADID_JR3_NUM_GROUPS][3];
        FUZZ_CHECK(loadid_jr3_decoder_full_scale(dec, fs_before) == 0);
        loadid_jr3_output_t out;
        memset(&out, 0xA5, sizeof out); /* what the decoder did not write shows */
        const int rc = loadid_jr3_decoder_feed(dec, &f, &out);
        ++t.fed;
        double fs_after[LOADID_JR3_NUM_GROUPS][3];
        FUZZ_CHECK(loadid_jr3_decoder_full_scale(dec, fs_after) == 0);
        const bool fs_changed = memcmp(fs_before, fs_after, sizeof fs_before) != 0;
        FUZZ_CHECK(fs_changed == (rc == LOADID_JR3_FULL_SCALE));
        switch (rc) {
            case LOADID_JR3_NONE:
                break;
            case LOADID_JR3_SAMPLE:
                ++t.sample;
                check_sample(&out.sample, t_reset, t_us);
                FUZZ_CHECK(!out.sample.saturated && !out.sample.faulty);
                FUZZ_CHECK(out.sample.sequence == f.data[6]);
                break;
            case LOADID_JR3_FULL_SCALE: {
                ++t.full_scale;
                const int g = out.full_scale.group;
                FUZZ_CHECK(g >= 0 && g < LOADID_JR3_NUM_GROUPS);
                FUZZ_CHECK(f.id == LOADID_JR3_DEFAULT_BASE_ID + LOADID_JR3_FULL_SCALE_OFFSET);
                FUZZ_CHECK(out.full_scale.t_us == t_us);
                for (int k = 0; k < 3; ++k) {
                    FUZZ_CHECK(out.full_scale.previous[k] == fs_before[g][k]);
                    FUZZ_CHECK(out.full_scale.current[k] == fs_after[g][k]);
                    FUZZ_CHECK(out.full_scale.current[k] > 0 &&
                               isfinite(out.full_scale.current[k]));
                }
                break;
            }
            case LOADID_JR3_E_SATURATED:
            case LOADID_JR3_E_FAULT:
                ++t.rejected;
                check_sample(&out.sample, t_reset, t_us);
                if (rc == LOADID_JR3_E_FAULT) {
                    FUZZ_CHECK(out.sample.faulty);
                } else {
                    FUZZ_CHECK(out.sample.saturated && !out.sample.faulty);
                    ++t.saturated;
                }
                if (out.sample.faulty) ++t.faulty;
                break;
            case LOADID_JR3_E_DUPLICATE:
                ++t.duplicate;
                break;
            case LOADID_JR3_E_UNKNOWN_ID:
            case LOADID_JR3_E_DLC:
            case LOADID_JR3_E_MALFORMED:
            case LOADID_JR3_E_RESERVED:
                ++t.bad;
                FUZZ_CHECK(strcmp(loadid_jr3_strerror(rc), loadid_jr3_strerror(-EINVAL)) != 0);
                break;
            default:
                FUZZ_CHECK(!"a return code jr3.h does not document");
        }
        check_stats(dec, &t);
    }
    loadid_jr3_decoder_destroy(dec);
    return 0;
}
