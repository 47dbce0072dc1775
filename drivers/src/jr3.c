/*
 * JR3 on CAN: encoder and decoder of docs/INTERFACE.md "JR3 over CAN" (see
 * loadid/jr3.h for the layout and the contract of every function).
 */
#include "loadid/jr3.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* base+4 units per group: full scale = units / divisor, i.e. 0.1 N,
 * 0.01 N m, 0.01 m/s^2, 0.1 rad/s^2 (docs/INTERFACE.md). Dividing by 10 or 100
 * gives the double nearest the decimal value (98.1, not 98.10000000000001). */
static const double fs_divisor[LOADID_JR3_NUM_GROUPS] = {10.0, 100.0, 100.0, 10.0};

enum phase {
    PHASE_IDLE = 0,   /* no sample open: none begun yet, or the last is complete */
    PHASE_ASSEMBLING, /* sample `seq` open, groups in `mask` received */
    PHASE_DISCARDING  /* sample `seq` abandoned after a duplicate */
};

struct loadid_jr3_decoder {
    loadid_jr3_config_t cfg;
    double fs[LOADID_JR3_NUM_GROUPS][3]; /* in force [SI] */
    bool begun;                          /* a sequence number was seen */
    uint8_t seq;                         /* the last sequence number begun */
    enum phase phase;
    unsigned mask; /* groups received (bit g) */
    loadid_jr3_sample_t partial;
    loadid_jr3_stats_t st;
};

/* Little-endian helpers: explicit byte arithmetic, no type punning. */
static int16_t get_i16(const uint8_t *p) {
    uint16_t u = (uint16_t)(p[0] | (p[1] << 8));
    /* Two's complement without implementation-defined conversion. */
    return u >= 0x8000u ? (int16_t)((int32_t)u - 65536) : (int16_t)u;
}

static uint16_t get_u16(const uint8_t *p) {
    return (uint16_t)(p[0] | (p[1] << 8));
}

static void put_u16(uint8_t *p, uint16_t v) {
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

static void put_i16(uint8_t *p, int16_t v) {
    put_u16(p, (uint16_t)((int32_t)v & 0xFFFF));
}

void loadid_jr3_config_default(loadid_jr3_config_t *cfg) {
    static const double defaults[LOADID_JR3_NUM_GROUPS] = {200.0, 12.0, 98.1, 1000.0};
    if (!cfg) {
        return;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->base_id = LOADID_JR3_DEFAULT_BASE_ID;
    for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
        for (int k = 0; k < 3; ++k) {
            cfg->full_scale[g][k] = defaults[g];
        }
    }
}

int loadid_jr3_config_check(const loadid_jr3_config_t *cfg) {
    if (!cfg || cfg->base_id > LOADID_JR3_MAX_BASE_ID) {
        return -EINVAL;
    }
    for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
        for (int k = 0; k < 3; ++k) {
            double fs = cfg->full_scale[g][k];
            if (!isfinite(fs) || !(fs > 0.0)) {
                return -EINVAL;
            }
        }
    }
    return 0;
}

/* ---- Encoder ----------------------------------------------------------- */

int loadid_jr3_encode(const loadid_jr3_config_t *cfg, const double value[LOADID_JR3_NUM_GROUPS][3],
                      uint8_t sequence, unsigned fault_groups, int64_t t_us,
                      loadid_can_frame_t frames[LOADID_JR3_NUM_GROUPS]) {
    if (!value || !frames || fault_groups > LOADID_JR3_ALL_GROUPS ||
        loadid_jr3_config_check(cfg) != 0) {
        return -EINVAL;
    }
    for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
        for (int k = 0; k < 3; ++k) {
            if (isnan(value[g][k])) {
                return -EINVAL;
            }
        }
    }
    int saturated = 0;
    for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
        loadid_can_frame_t *f = &frames[g];
        memset(f, 0, sizeof *f);
        f->id = cfg->base_id + (uint32_t)g;
        f->dlc = 8;
        f->t_us = t_us;
        uint8_t status = 0;
        for (int k = 0; k < 3; ++k) {
            /* x 16384 is exact; one rounding in the division, then round()
             * half away from zero. Compared as doubles before converting,
             * so +-Inf and huge values never reach an integer conversion. */
            double c =
                round(value[g][k] * LOADID_JR3_COUNTS_PER_FULL_SCALE / cfg->full_scale[g][k]);
            int16_t counts;
            if (c > 32767.0) {
                counts = 32767;
                status |= LOADID_JR3_STATUS_SATURATED;
            } else if (c < -32768.0) {
                counts = -32768;
                status |= LOADID_JR3_STATUS_SATURATED;
            } else {
                counts = (int16_t)c;
            }
            put_i16(&f->data[2 * k], counts);
        }
        if (fault_groups & (1u << g)) {
            status |= LOADID_JR3_STATUS_FAULT;
        }
        if (status & LOADID_JR3_STATUS_SATURATED) {
            saturated |= 1 << g;
        }
        f->data[6] = sequence;
        f->data[7] = status;
    }
    return saturated;
}

int loadid_jr3_encode_full_scale(uint32_t base_id, int group, const double fs[3], int64_t t_us,
                                 loadid_can_frame_t *frame, double sent[3]) {
    if (!fs || !frame || base_id > LOADID_JR3_MAX_BASE_ID || group < 0 ||
        group >= LOADID_JR3_NUM_GROUPS) {
        return -EINVAL;
    }
    uint16_t units[3];
    for (int k = 0; k < 3; ++k) {
        if (!isfinite(fs[k])) {
            return -EINVAL;
        }
        double u = round(fs[k] * fs_divisor[group]);
        if (!(u >= 1.0 && u <= 65535.0)) {
            return LOADID_JR3_E_RANGE;
        }
        units[k] = (uint16_t)u;
    }
    memset(frame, 0, sizeof *frame);
    frame->id = base_id + LOADID_JR3_FULL_SCALE_OFFSET;
    frame->dlc = 8;
    frame->t_us = t_us;
    frame->data[0] = (uint8_t)group;
    frame->data[1] = 0;
    for (int k = 0; k < 3; ++k) {
        put_u16(&frame->data[2 + 2 * k], units[k]);
        if (sent) {
            sent[k] = units[k] / fs_divisor[group];
        }
    }
    return 0;
}

/* ---- Decoder ----------------------------------------------------------- */

int loadid_jr3_decoder_create(const loadid_jr3_config_t *cfg, loadid_jr3_decoder_t **out) {
    if (!out) {
        return -EINVAL;
    }
    *out = NULL;
    if (loadid_jr3_config_check(cfg) != 0) {
        return -EINVAL;
    }
    loadid_jr3_decoder_t *dec = calloc(1, sizeof *dec);
    if (!dec) {
        return -ENOMEM;
    }
    dec->cfg = *cfg;
    loadid_jr3_decoder_reset(dec);
    *out = dec;
    return 0;
}

void loadid_jr3_decoder_destroy(loadid_jr3_decoder_t *dec) {
    free(dec);
}

void loadid_jr3_decoder_reset(loadid_jr3_decoder_t *dec) {
    if (!dec) {
        return;
    }
    memcpy(dec->fs, dec->cfg.full_scale, sizeof dec->fs);
    dec->begun = false;
    dec->seq = 0;
    dec->phase = PHASE_IDLE;
    dec->mask = 0;
    memset(&dec->partial, 0, sizeof dec->partial);
    memset(&dec->st, 0, sizeof dec->st);
}

static int bad(loadid_jr3_decoder_t *dec, int64_t *counter, int code) {
    ++*counter;
    ++dec->st.frames_bad;
    return code;
}

/* A valid-looking base+4 frame (DLC already checked). */
static int feed_full_scale(loadid_jr3_decoder_t *dec, const loadid_can_frame_t *f,
                           loadid_jr3_output_t *out) {
    const uint8_t *d = f->data;
    if (d[0] >= LOADID_JR3_NUM_GROUPS || d[1] != 0) {
        return bad(dec, &dec->st.frames_malformed, LOADID_JR3_E_MALFORMED);
    }
    int g = d[0];
    double fs[3];
    for (int k = 0; k < 3; ++k) {
        uint16_t units = get_u16(&d[2 + 2 * k]);
        if (units == 0) {
            return bad(dec, &dec->st.frames_malformed, LOADID_JR3_E_MALFORMED);
        }
        fs[k] = units / fs_divisor[g];
    }
    ++dec->st.full_scale_frames;
    if (memcmp(fs, dec->fs[g], sizeof fs) == 0) {
        return LOADID_JR3_NONE; /* the periodic repetition: nothing new */
    }
    ++dec->st.full_scale_changes;
    loadid_jr3_full_scale_change_t *c = &out->full_scale;
    c->group = g;
    memcpy(c->previous, dec->fs[g], sizeof c->previous);
    memcpy(c->current, fs, sizeof c->current);
    c->t_us = f->t_us;
    memcpy(dec->fs[g], fs, sizeof fs);
    return LOADID_JR3_FULL_SCALE;
}

static void begin(loadid_jr3_decoder_t *dec, uint8_t seq) {
    if (dec->begun) {
        /* Numbers skipped between the last sample begun and this one;
         * uint8 arithmetic wraps, so 255 -> 0 is 0. */
        dec->st.sequence_gaps += (uint8_t)(seq - dec->seq - 1u);
    }
    dec->begun = true;
    dec->seq = seq;
    dec->phase = PHASE_ASSEMBLING;
    dec->mask = 0;
    memset(&dec->partial, 0, sizeof dec->partial);
    dec->partial.sequence = seq;
    ++dec->st.samples_started;
}

int loadid_jr3_decoder_feed(loadid_jr3_decoder_t *dec, const loadid_can_frame_t *frame,
                            loadid_jr3_output_t *out) {
    if (!dec || !frame || !out) {
        return -EINVAL;
    }
    ++dec->st.frames_total;
    const uint32_t base = dec->cfg.base_id;
    /* Unsigned: an id below base wraps to a large offset. */
    uint32_t off = frame->id - base;
    if (frame->extended || frame->id > LOADID_CAN_SFF_MASK || frame->id < base ||
        off > LOADID_JR3_FULL_SCALE_OFFSET) {
        return bad(dec, &dec->st.frames_unknown_id, LOADID_JR3_E_UNKNOWN_ID);
    }
    if (frame->dlc != 8) {
        return bad(dec, &dec->st.frames_bad_dlc, LOADID_JR3_E_DLC);
    }
    if (off == LOADID_JR3_FULL_SCALE_OFFSET) {
        return feed_full_scale(dec, frame, out);
    }
    const int g = (int)off;
    const uint8_t *d = frame->data;
    const uint8_t seq = d[6];
    const uint8_t status = d[7];
    if (status & LOADID_JR3_STATUS_RESERVED) {
        return bad(dec, &dec->st.frames_reserved, LOADID_JR3_E_RESERVED);
    }

    if (dec->begun && seq == dec->seq) {
        if (dec->phase == PHASE_DISCARDING) {
            ++dec->st.frames_discarded;
            return LOADID_JR3_NONE;
        }
        if (dec->phase == PHASE_IDLE || (dec->mask & (1u << g))) {
            /* Complete already (IDLE), or this group twice: which copy is
             * right is unknown, so the open sample goes. */
            ++dec->st.frames_duplicate;
            if (dec->phase == PHASE_ASSEMBLING) {
                ++dec->st.samples_incomplete;
                dec->phase = PHASE_DISCARDING;
            }
            return LOADID_JR3_E_DUPLICATE;
        }
    } else {
        if (dec->phase == PHASE_ASSEMBLING) {
            ++dec->st.samples_incomplete;
        }
        begin(dec, seq);
    }

    /* Take the frame: counts, and SI with the full scale in force now. */
    ++dec->st.frames_sample;
    loadid_jr3_sample_t *s = &dec->partial;
    for (int k = 0; k < 3; ++k) {
        s->counts[g][k] = get_i16(&d[2 * k]);
        s->value[g][k] = s->counts[g][k] * dec->fs[g][k] / LOADID_JR3_COUNTS_PER_FULL_SCALE;
    }
    s->status[g] = status;
    if (g == LOADID_JR3_FORCE) {
        s->t_us = frame->t_us;
    }
    dec->mask |= 1u << g;
    if (dec->mask != LOADID_JR3_ALL_GROUPS) {
        return LOADID_JR3_NONE;
    }

    /* Complete. */
    dec->phase = PHASE_IDLE;
    for (int i = 0; i < LOADID_JR3_NUM_GROUPS; ++i) {
        s->saturated = s->saturated || (s->status[i] & LOADID_JR3_STATUS_SATURATED);
        s->faulty = s->faulty || (s->status[i] & LOADID_JR3_STATUS_FAULT);
    }
    out->sample = *s;
    if (!s->saturated && !s->faulty) {
        ++dec->st.samples_ok;
        return LOADID_JR3_SAMPLE;
    }
    ++dec->st.samples_rejected;
    dec->st.samples_saturated += s->saturated;
    dec->st.samples_faulty += s->faulty;
    return s->faulty ? LOADID_JR3_E_FAULT : LOADID_JR3_E_SATURATED;
}

int loadid_jr3_decoder_stats(const loadid_jr3_decoder_t *dec, loadid_jr3_stats_t *out) {
    if (!dec || !out) {
        return -EINVAL;
    }
    *out = dec->st;
    return 0;
}

int loadid_jr3_decoder_full_scale(const loadid_jr3_decoder_t *dec,
                                  double out[LOADID_JR3_NUM_GROUPS][3]) {
    if (!dec || !out) {
        return -EINVAL;
    }
    memcpy(out, dec->fs, sizeof dec->fs);
    return 0;
}

const char *loadid_jr3_strerror(int code) {
    switch (code) {
        case LOADID_JR3_NONE:
            return "no sample";
        case LOADID_JR3_SAMPLE:
            return "a complete sample";
        case LOADID_JR3_FULL_SCALE:
            return "a full scale changed (base+4)";
        case LOADID_JR3_E_SATURATED:
            return "sample saturated (not usable)";
        case LOADID_JR3_E_FAULT:
            return "sample with sensor fault (not usable)";
        case LOADID_JR3_E_UNKNOWN_ID:
            return "CAN identifier not base..base+4 (or extended)";
        case LOADID_JR3_E_DLC:
            return "CAN frame DLC is not 8";
        case LOADID_JR3_E_MALFORMED:
            return "malformed full-scale frame (group > 3, byte 1 != 0 or zero full scale)";
        case LOADID_JR3_E_RESERVED:
            return "reserved status bits set";
        case LOADID_JR3_E_DUPLICATE:
            return "duplicate frame for a sequence number";
        case LOADID_JR3_E_RANGE:
            return "full scale out of the range of the base+4 frame";
        case -EINVAL:
            return "invalid argument";
        case -ENOMEM:
            return "out of memory";
        default:
            return code < 0 ? "unknown error" : "unknown result";
    }
}

const char *loadid_jr3_group_name(int group) {
    static const char *const names[LOADID_JR3_NUM_GROUPS] = {"force", "moment", "linear",
                                                             "angular"};
    return group >= 0 && group < LOADID_JR3_NUM_GROUPS ? names[group] : "?";
}
