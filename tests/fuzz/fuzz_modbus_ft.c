/*
 * Fuzz target modbus_ft: the Modbus F/T register-block decoder
 * (drivers/src/modbus_ft.c) fed a sensor's responses. Input: a stream of
 * operations, each a selector byte and its registers (big-endian, as on
 * the Modbus wire):
 *   selector % 4 == 0, 1: an input-register block, 8 registers;
 *   selector % 4 == 2:    the full-scale holding registers, 6 registers;
 *   selector % 4 == 3:    a reopen (loadid_modbus_ft_decoder_restart).
 * Beyond the sanitizers it checks what modbus_ft.h promises: only the
 * documented return codes, the counter invariants and a tally of the
 * return codes, SI values that are counts * full scale / 16384 with the
 * full scale in force, and the encoder giving the registers back.
 */
#include <errno.h>
#include <string.h>

#include "fuzz_check.h"
#include "loadid/modbus_ft.h"

static uint16_t be16(const uint8_t *b) {
    return (uint16_t)(b[0] << 8 | b[1]);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    double fs_force[3] = {200, 200, 200}, fs_moment[3] = {12, 12, 12};
    loadid_modbus_ft_decoder_t dec;
    FUZZ_CHECK(loadid_modbus_ft_decoder_init(&dec, fs_force, fs_moment) == 0);
    int64_t ok = 0, rejected = 0, stale = 0, malformed = 0, fs_reads = 0, fs_bad = 0;
    bool begun = false;
    uint16_t last = 0;
    size_t i = 0;
    for (int64_t t_us = 1700000000000000; i < size; t_us += 1000) {
        const int op = data[i++] % 4;
        if (op == 3) {
            loadid_modbus_ft_decoder_restart(&dec);
            begun = false;
            continue;
        }
        const size_t nregs =
            op == 2 ? LOADID_MODBUS_FT_HOLDING_COUNT : LOADID_MODBUS_FT_INPUT_COUNT;
        if (size - i < 2 * nregs) break;
        uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT];
        for (size_t k = 0; k < nregs; ++k) regs[k] = be16(data + i + 2 * k);
        i += 2 * nregs;

        if (op == 2) {
            const int rc = loadid_modbus_ft_decode_full_scale(&dec, regs);
            bool zero = false;
            for (size_t k = 0; k < nregs; ++k) zero |= regs[k] == 0;
            FUZZ_CHECK(rc == (zero ? LOADID_MODBUS_FT_E_MALFORMED : LOADID_MODBUS_FT_FULL_SCALE));
            if (zero) {
                ++fs_bad;
            } else {
                ++fs_reads;
                for (int k = 0; k < 3; ++k) {
                    fs_force[k] = regs[k] / 10.0;
                    fs_moment[k] = regs[3 + k] / 100.0;
                }
            }
        } else {
            loadid_modbus_ft_sample_t s;
            memset(&s, 0xA5, sizeof s);
            const int rc = loadid_modbus_ft_decode(&dec, regs, t_us, &s);
            const uint16_t status = regs[LOADID_MODBUS_FT_REG_STATUS];
            const uint16_t counter = regs[LOADID_MODBUS_FT_REG_COUNTER];
            if (status & LOADID_MODBUS_FT_STATUS_RESERVED) {
                FUZZ_CHECK(rc == LOADID_MODBUS_FT_E_MALFORMED);
                ++malformed;
            } else {
                FUZZ_CHECK(s.t_us == t_us && s.counter == counter && s.status == status);
                FUZZ_CHECK(s.saturated == ((status & LOADID_MODBUS_FT_STATUS_SATURATED) != 0));
                FUZZ_CHECK(s.faulty == ((status & LOADID_MODBUS_FT_STATUS_FAULT) != 0));
                for (int k = 0; k < 3; ++k) {
                    FUZZ_CHECK(s.counts[k] == (int16_t)regs[k]);
                    FUZZ_CHECK(s.counts[3 + k] == (int16_t)regs[3 + k]);
                    FUZZ_CHECK(s.force[k] == s.counts[k] * fs_force[k] / 16384.0);
                    FUZZ_CHECK(s.torque[k] == s.counts[3 + k] * fs_moment[k] / 16384.0);
                }
                if (begun && counter == last) {
                    FUZZ_CHECK(rc == LOADID_MODBUS_FT_E_STALE);
                    ++stale;
                } else if (!s.saturated && !s.faulty) {
                    FUZZ_CHECK(rc == LOADID_MODBUS_FT_SAMPLE);
                    ++ok;
                } else {
                    FUZZ_CHECK(
                        rc == (s.faulty ? LOADID_MODBUS_FT_E_FAULT : LOADID_MODBUS_FT_E_SATURATED));
                    ++rejected;
                }
                if (!(begun && counter == last)) {
                    begun = true;
                    last = counter;
                }
                if (rc == LOADID_MODBUS_FT_SAMPLE) {
                    /* The sensor's side gives these registers back. */
                    uint16_t again[LOADID_MODBUS_FT_INPUT_COUNT];
                    FUZZ_CHECK(loadid_modbus_ft_encode(fs_force, fs_moment, s.force, s.torque,
                                                       false, counter, again) == 0);
                    FUZZ_CHECK(memcmp(again, regs, sizeof again) == 0);
                }
            }
        }
        const loadid_modbus_ft_stats_t *st = &dec.st;
        FUZZ_CHECK(st->blocks == st->samples_ok + st->samples_rejected + st->samples_stale +
                                     st->samples_malformed);
        FUZZ_CHECK(st->samples_saturated <= st->samples_rejected &&
                   st->samples_faulty <= st->samples_rejected);
        FUZZ_CHECK(st->samples_rejected <= st->samples_saturated + st->samples_faulty);
        FUZZ_CHECK(st->samples_ok == ok && st->samples_rejected == rejected &&
                   st->samples_stale == stale && st->samples_malformed == malformed);
        FUZZ_CHECK(st->full_scale_reads == fs_reads && st->full_scale_malformed == fs_bad);
        FUZZ_CHECK(st->counter_gaps >= 0 && st->counter_gaps <= 65534 * st->blocks);
    }
    return 0;
}
