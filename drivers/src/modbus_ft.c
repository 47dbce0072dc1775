/*
 * Modbus F/T sensor: the pure half of loadid/modbus_ft.h (register blocks
 * <-> SI samples, proto/modbus_ft.md). No I/O, no clock, no allocation.
 */
#include "loadid/modbus_ft.h"

#include <errno.h>
#include <math.h>
#include <string.h>

static bool fs_ok(const double fs[3]) {
    for (int i = 0; i < 3; ++i) {
        if (!isfinite(fs[i]) || !(fs[i] > 0)) {
            return false;
        }
    }
    return true;
}

/* A register as int16 without implementation-defined conversion. */
static int16_t as_i16(uint16_t u) {
    return u >= 0x8000u ? (int16_t)((int32_t)u - 65536) : (int16_t)u;
}

int loadid_modbus_ft_decoder_init(loadid_modbus_ft_decoder_t *dec, const double fs_force[3],
                                  const double fs_moment[3]) {
    if (!dec || !fs_force || !fs_moment || !fs_ok(fs_force) || !fs_ok(fs_moment)) {
        return -EINVAL;
    }
    memset(dec, 0, sizeof *dec);
    memcpy(dec->fs_force, fs_force, sizeof dec->fs_force);
    memcpy(dec->fs_moment, fs_moment, sizeof dec->fs_moment);
    memcpy(dec->cfg_force, fs_force, sizeof dec->cfg_force);
    memcpy(dec->cfg_moment, fs_moment, sizeof dec->cfg_moment);
    return 0;
}

void loadid_modbus_ft_decoder_restart(loadid_modbus_ft_decoder_t *dec) {
    if (dec) {
        dec->begun = false;
    }
}

int loadid_modbus_ft_decode(loadid_modbus_ft_decoder_t *dec,
                            const uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT], int64_t t_us,
                            loadid_modbus_ft_sample_t *out) {
    if (!dec || !regs || !out) {
        return -EINVAL;
    }
    ++dec->st.blocks;
    const uint16_t status = regs[LOADID_MODBUS_FT_REG_STATUS];
    const uint16_t counter = regs[LOADID_MODBUS_FT_REG_COUNTER];
    if (status & LOADID_MODBUS_FT_STATUS_RESERVED) {
        ++dec->st.samples_malformed;
        return LOADID_MODBUS_FT_E_MALFORMED;
    }

    memset(out, 0, sizeof *out);
    out->t_us = t_us;
    out->counter = counter;
    out->status = status;
    out->saturated = (status & LOADID_MODBUS_FT_STATUS_SATURATED) != 0;
    out->faulty = (status & LOADID_MODBUS_FT_STATUS_FAULT) != 0;
    for (int k = 0; k < 3; ++k) {
        out->counts[k] = as_i16(regs[k]);
        out->counts[3 + k] = as_i16(regs[3 + k]);
        out->force[k] = out->counts[k] * dec->fs_force[k] / LOADID_MODBUS_FT_COUNTS_PER_FULL_SCALE;
        out->torque[k] =
            out->counts[3 + k] * dec->fs_moment[k] / LOADID_MODBUS_FT_COUNTS_PER_FULL_SCALE;
    }

    if (dec->begun && counter == dec->last_counter) {
        ++dec->st.samples_stale;
        return LOADID_MODBUS_FT_E_STALE;
    }
    if (dec->begun) {
        /* uint16 arithmetic: 65535 -> 0 is a step of 1, no gap. */
        const uint16_t step = (uint16_t)(counter - dec->last_counter);
        dec->st.counter_gaps += step - 1;
    }
    dec->begun = true;
    dec->last_counter = counter;

    if (!out->saturated && !out->faulty) {
        ++dec->st.samples_ok;
        return LOADID_MODBUS_FT_SAMPLE;
    }
    ++dec->st.samples_rejected;
    dec->st.samples_saturated += out->saturated;
    dec->st.samples_faulty += out->faulty;
    return out->faulty ? LOADID_MODBUS_FT_E_FAULT : LOADID_MODBUS_FT_E_SATURATED;
}

int loadid_modbus_ft_decode_full_scale(loadid_modbus_ft_decoder_t *dec,
                                       const uint16_t regs[LOADID_MODBUS_FT_HOLDING_COUNT]) {
    if (!dec || !regs) {
        return -EINVAL;
    }
    for (int i = 0; i < LOADID_MODBUS_FT_HOLDING_COUNT; ++i) {
        if (regs[i] == 0) {
            ++dec->st.full_scale_malformed;
            return LOADID_MODBUS_FT_E_MALFORMED;
        }
    }
    /* Dividing by 10 and 100 gives the double nearest the decimal value
     * (as jr3.c does for base+4). */
    for (int k = 0; k < 3; ++k) {
        dec->fs_force[k] = regs[k] / 10.0;
        dec->fs_moment[k] = regs[3 + k] / 100.0;
    }
    ++dec->st.full_scale_reads;
    return LOADID_MODBUS_FT_FULL_SCALE;
}

/* Half away from zero, clamped to int16; *sat set when clamped. Rounded
 * before the range test (as jr3.c does): a value within half a count of
 * the limit is that count, not saturated, so that every decoded sample
 * encodes back to its own registers. Compared as doubles before the
 * conversion, so +-Inf and huge values never reach it. */
static uint16_t to_counts(double v, double fs, bool *sat, bool *bad) {
    if (isnan(v)) {
        *bad = true;
        return 0;
    }
    const double c = round(v * LOADID_MODBUS_FT_COUNTS_PER_FULL_SCALE / fs);
    long r;
    if (c > 32767.0) {
        *sat = true;
        r = 32767;
    } else if (c < -32768.0) {
        *sat = true;
        r = -32768;
    } else {
        r = (long)c;
    }
    return (uint16_t)(r < 0 ? r + 65536 : r);
}

int loadid_modbus_ft_encode(const double fs_force[3], const double fs_moment[3],
                            const double force[3], const double torque[3], bool fault,
                            uint16_t counter, uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT]) {
    if (!fs_force || !fs_moment || !force || !torque || !regs || !fs_ok(fs_force) ||
        !fs_ok(fs_moment)) {
        return -EINVAL;
    }
    bool sat = false, bad = false;
    for (int k = 0; k < 3; ++k) {
        regs[k] = to_counts(force[k], fs_force[k], &sat, &bad);
        regs[3 + k] = to_counts(torque[k], fs_moment[k], &sat, &bad);
    }
    regs[LOADID_MODBUS_FT_REG_STATUS] =
        (uint16_t)((sat ? LOADID_MODBUS_FT_STATUS_SATURATED : 0u) |
                   (fault || bad ? LOADID_MODBUS_FT_STATUS_FAULT : 0u));
    regs[LOADID_MODBUS_FT_REG_COUNTER] = counter;
    return 0;
}

int loadid_modbus_ft_encode_full_scale(const double fs_force[3], const double fs_moment[3],
                                       uint16_t regs[LOADID_MODBUS_FT_HOLDING_COUNT]) {
    if (!fs_force || !fs_moment || !regs) {
        return -EINVAL;
    }
    for (int k = 0; k < 6; ++k) {
        const double v = k < 3 ? fs_force[k] / LOADID_MODBUS_FT_FORCE_UNIT
                               : fs_moment[k - 3] / LOADID_MODBUS_FT_MOMENT_UNIT;
        if (!isfinite(v)) {
            return -EINVAL;
        }
        const double r = round(v);
        if (r < 1 || r > 65535) {
            return -ERANGE;
        }
        regs[k] = (uint16_t)r;
    }
    return 0;
}

const char *loadid_modbus_ft_strerror(int code) {
    switch (code) {
        case 0:
            return "ok";
        case LOADID_MODBUS_FT_SAMPLE:
            return "a new sample";
        case LOADID_MODBUS_FT_FULL_SCALE:
            return "full scales read from the sensor";
        case LOADID_MODBUS_FT_E_SATURATED:
            return "sample saturated (not usable)";
        case LOADID_MODBUS_FT_E_FAULT:
            return "sample with sensor fault (not usable)";
        case LOADID_MODBUS_FT_E_STALE:
            return "stale sample (counter unchanged)";
        case LOADID_MODBUS_FT_E_MALFORMED:
            return "malformed registers (reserved status bits or zero full scale)";
        case LOADID_MODBUS_FT_E_TIMEOUT:
            return "Modbus response timeout";
        case LOADID_MODBUS_FT_E_BAD_FRAME:
            return "bad Modbus frame (CRC, slave or data)";
        case LOADID_MODBUS_FT_E_EXCEPTION:
            return "Modbus exception response";
        case LOADID_MODBUS_FT_E_GONE:
            return "serial device vanished or failed (closed; reopen)";
        case LOADID_MODBUS_FT_E_CLOSED:
            return "serial device not open";
        case -EINVAL:
            return "invalid argument";
        case -ENOMEM:
            return "out of memory";
        case -ERANGE:
            return "value out of range";
        default:
            if (code < 0 && code > -4096) {
                return strerror(-code);
            }
            return code < 0 ? "unknown error" : "unknown result";
    }
}

/* The speeds libmodbus 3.1's RTU backend maps onto termios B* constants on
 * Linux (modbus-rtu.c, _modbus_rtu_connect); any other it replaces with
 * 9600 without an error, so they are refused here. */
static const int kBauds[] = {110,     300,     600,     1200,    2400,    4800,
                             9600,    19200,   38400,   57600,   115200,  230400,
                             460800,  500000,  576000,  921600,  1000000, 1152000,
                             1500000, 2000000, 2500000, 3000000, 3500000, 4000000};

bool loadid_modbus_ft_baud_supported(int baud) {
    for (size_t i = 0; i < sizeof kBauds / sizeof kBauds[0]; ++i) {
        if (kBauds[i] == baud) {
            return true;
        }
    }
    return false;
}
