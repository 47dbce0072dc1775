/*
 * Modbus F/T sensor: the libmodbus RTU client of loadid/modbus_ft.h. Every
 * transaction's outcome is counted; the pure decoding is modbus_ft.c's.
 */
#define _POSIX_C_SOURCE 200809L

#include "loadid/modbus_ft.h"

#include <errno.h>
#include <modbus.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct loadid_modbus_ft {
    loadid_modbus_ft_config_t cfg;
    modbus_t *ctx;
    bool open;
    loadid_modbus_ft_decoder_t dec; /* holds every counter */
    char last_error[LOADID_MODBUS_FT_DEVICE_MAX + 128];
};

void loadid_modbus_ft_config_default(loadid_modbus_ft_config_t *cfg) {
    if (!cfg) {
        return;
    }
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->device, sizeof cfg->device, "/dev/ttyUSB0");
    cfg->baud = 115200;
    cfg->parity = 'N';
    cfg->data_bits = 8;
    cfg->stop_bits = 1;
    cfg->slave_id = LOADID_MODBUS_FT_DEFAULT_SLAVE;
    cfg->timeout_ms = 20;
    for (int i = 0; i < 3; ++i) {
        cfg->fs_force[i] = 200.0;
        cfg->fs_moment[i] = 12.0;
    }
}

int loadid_modbus_ft_config_check(const loadid_modbus_ft_config_t *cfg) {
    loadid_modbus_ft_decoder_t probe;
    if (!cfg || !cfg->device[0] || memchr(cfg->device, 0, sizeof cfg->device) == NULL ||
        !loadid_modbus_ft_baud_supported(cfg->baud) ||
        (cfg->parity != 'N' && cfg->parity != 'E' && cfg->parity != 'O') || cfg->data_bits < 5 ||
        cfg->data_bits > 8 || cfg->stop_bits < 1 || cfg->stop_bits > 2 || cfg->slave_id < 1 ||
        cfg->slave_id > 247 || cfg->timeout_ms <= 0 || cfg->timeout_ms > 60000 ||
        loadid_modbus_ft_decoder_init(&probe, cfg->fs_force, cfg->fs_moment) != 0) {
        return -EINVAL;
    }
    return 0;
}

int loadid_modbus_ft_create(const loadid_modbus_ft_config_t *cfg, loadid_modbus_ft_t **out) {
    if (!out || loadid_modbus_ft_config_check(cfg) != 0) {
        return -EINVAL;
    }
    loadid_modbus_ft_t *ft = calloc(1, sizeof *ft);
    if (!ft) {
        return -ENOMEM;
    }
    ft->cfg = *cfg;
    loadid_modbus_ft_decoder_init(&ft->dec, cfg->fs_force, cfg->fs_moment);
    ft->ctx = modbus_new_rtu(cfg->device, cfg->baud, cfg->parity, cfg->data_bits, cfg->stop_bits);
    if (!ft->ctx) {
        free(ft);
        return -ENOMEM;
    }
    const uint32_t us = (uint32_t)cfg->timeout_ms * 1000u;
    if (modbus_set_slave(ft->ctx, cfg->slave_id) != 0 ||
        modbus_set_response_timeout(ft->ctx, us / 1000000u, us % 1000000u) != 0 ||
        /* A frame's bytes come back to back; a pause longer than the whole
         * response time means the rest is not coming. */
        modbus_set_byte_timeout(ft->ctx, us / 1000000u, us % 1000000u) != 0) {
        modbus_free(ft->ctx);
        free(ft);
        return -EINVAL;
    }
    *out = ft;
    return 0;
}

void loadid_modbus_ft_destroy(loadid_modbus_ft_t *ft) {
    if (!ft) {
        return;
    }
    loadid_modbus_ft_close(ft);
    modbus_free(ft->ctx);
    free(ft);
}

bool loadid_modbus_ft_is_open(const loadid_modbus_ft_t *ft) {
    return ft && ft->open;
}

void loadid_modbus_ft_close(loadid_modbus_ft_t *ft) {
    if (ft && ft->open) {
        modbus_close(ft->ctx);
        ft->open = false;
    }
}

static int64_t now_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static void set_error(loadid_modbus_ft_t *ft, const char *what, int e) {
    snprintf(ft->last_error, sizeof ft->last_error, "%s: %s: %s", ft->cfg.device, what,
             modbus_strerror(e));
}

/* Counts a failed transaction by libmodbus' errno e and says what to do.
 * Transport faults flush what is left of the frame so that the next
 * transaction starts clean; anything not a Modbus-level fault means the
 * device itself failed (a pty whose master closed gives EIO on write and
 * ECONNRESET on read; a USB adapter unplugged gives EIO or ENXIO). */
static int classify(loadid_modbus_ft_t *ft, const char *what, int e) {
    loadid_modbus_ft_stats_t *st = &ft->dec.st;
    set_error(ft, what, e);
    if (e == ETIMEDOUT) {
        ++st->timeouts;
        modbus_flush(ft->ctx);
        return LOADID_MODBUS_FT_E_TIMEOUT;
    }
    if (e >= EMBXILFUN && e <= EMBXGTAR) {
        ++st->exceptions;
        return LOADID_MODBUS_FT_E_EXCEPTION;
    }
    if (e == EMBBADCRC || e == EMBBADDATA || e == EMBBADEXC || e == EMBUNKEXC || e == EMBMDATA ||
        e == EMBBADSLAVE) {
        ++st->bad_frames;
        st->crc_errors += e == EMBBADCRC;
        modbus_flush(ft->ctx);
        return LOADID_MODBUS_FT_E_BAD_FRAME;
    }
    ++st->io_errors;
    ++st->device_lost;
    loadid_modbus_ft_close(ft);
    return LOADID_MODBUS_FT_E_GONE;
}

int loadid_modbus_ft_open(loadid_modbus_ft_t *ft) {
    if (!ft) {
        return -EINVAL;
    }
    loadid_modbus_ft_close(ft);
    if (modbus_connect(ft->ctx) != 0) {
        const int e = errno ? errno : EIO;
        set_error(ft, "open", e);
        ++ft->dec.st.open_failures;
        return -e;
    }
    ft->open = true;
    modbus_flush(ft->ctx); /* whatever the line held before us */
    loadid_modbus_ft_decoder_restart(&ft->dec);

    uint16_t regs[LOADID_MODBUS_FT_HOLDING_COUNT];
    ++ft->dec.st.full_scale_requests;
    const int n = modbus_read_registers(ft->ctx, LOADID_MODBUS_FT_HOLDING_ADDR,
                                        LOADID_MODBUS_FT_HOLDING_COUNT, regs);
    int rc;
    if (n == LOADID_MODBUS_FT_HOLDING_COUNT) {
        rc = loadid_modbus_ft_decode_full_scale(&ft->dec, regs);
        if (rc < 0) {
            snprintf(ft->last_error, sizeof ft->last_error,
                     "%s: a full-scale holding register is 0: configured full scales kept",
                     ft->cfg.device);
            rc = 0;
        }
    } else {
        rc = classify(ft, "reading the full scales", n < 0 ? errno : EMBBADDATA);
        if (rc == LOADID_MODBUS_FT_E_EXCEPTION) {
            rc = 0; /* a sensor without the registers: configured full scales */
        }
    }
    if (rc < 0) {
        loadid_modbus_ft_close(ft);
        ++ft->dec.st.open_failures;
        return rc == LOADID_MODBUS_FT_E_GONE ? -EIO : rc;
    }
    ++ft->dec.st.opens;
    return rc;
}

int loadid_modbus_ft_read(loadid_modbus_ft_t *ft, loadid_modbus_ft_sample_t *out) {
    if (!ft || !out) {
        return -EINVAL;
    }
    if (!ft->open) {
        return LOADID_MODBUS_FT_E_CLOSED;
    }
    uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT];
    ++ft->dec.st.reads;
    /* One transaction: the sensor latched all eight registers together. */
    const int n = modbus_read_input_registers(ft->ctx, LOADID_MODBUS_FT_INPUT_ADDR,
                                              LOADID_MODBUS_FT_INPUT_COUNT, regs);
    const int64_t t = now_us();
    if (n != LOADID_MODBUS_FT_INPUT_COUNT) {
        return classify(ft, "reading a sample", n < 0 ? errno : EMBBADDATA);
    }
    return loadid_modbus_ft_decode(&ft->dec, regs, t, out);
}

int loadid_modbus_ft_stats(const loadid_modbus_ft_t *ft, loadid_modbus_ft_stats_t *out) {
    if (!ft || !out) {
        return -EINVAL;
    }
    *out = ft->dec.st;
    return 0;
}

int loadid_modbus_ft_full_scale(const loadid_modbus_ft_t *ft, double force[3], double moment[3]) {
    if (!ft || !force || !moment) {
        return -EINVAL;
    }
    memcpy(force, ft->dec.fs_force, sizeof ft->dec.fs_force);
    memcpy(moment, ft->dec.fs_moment, sizeof ft->dec.fs_moment);
    return 0;
}

const char *loadid_modbus_ft_last_error(const loadid_modbus_ft_t *ft) {
    return ft ? ft->last_error : "";
}
