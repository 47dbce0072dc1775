/*
 * The sensor's side of proto/modbus_ft.md (loadid/modbus_ft_server.h): a
 * libmodbus RTU server on a descriptor, with fault injection.
 */
#define _POSIX_C_SOURCE 200809L

#include "loadid/modbus_ft_server.h"

#include <errno.h>
#include <modbus.h>
#include <poll.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct loadid_modbus_ft_server {
    modbus_t *ctx;
    modbus_mapping_t *map;
    int fd;
    int nb_input, nb_holding;
    pthread_mutex_t lock; /* map, mode, stats, hook */
    int mode;
    loadid_modbus_ft_server_hook_fn hook;
    void *hook_ctx;
    loadid_modbus_ft_server_stats_t st;
};

uint16_t loadid_modbus_crc16(const uint8_t *p, int n) {
    uint16_t crc = 0xFFFFu;
    for (int i = 0; i < n; ++i) {
        crc ^= p[i];
        for (int b = 0; b < 8; ++b) {
            crc = (crc & 1u) ? (uint16_t)((crc >> 1) ^ 0xA001u) : (uint16_t)(crc >> 1);
        }
    }
    return crc;
}

int loadid_modbus_ft_server_create(int fd, int slave_id, int nb_input, int nb_holding,
                                   loadid_modbus_ft_server_t **out) {
    if (fd < 0 || !out || slave_id < 1 || slave_id > 247 || nb_input < 0 || nb_holding < 0 ||
        nb_input > 125 || nb_holding > 125) {
        return -EINVAL;
    }
    loadid_modbus_ft_server_t *s = calloc(1, sizeof *s);
    if (!s) {
        return -ENOMEM;
    }
    s->fd = fd;
    s->nb_input = nb_input;
    s->nb_holding = nb_holding;
    /* The device name is never opened: the descriptor is handed over. */
    s->ctx = modbus_new_rtu("/dev/null", 115200, 'N', 8, 1);
    s->map = modbus_mapping_new(0, 0, nb_holding, nb_input);
    if (!s->ctx || !s->map || modbus_set_slave(s->ctx, slave_id) != 0 ||
        modbus_set_socket(s->ctx, fd) != 0 || pthread_mutex_init(&s->lock, NULL) != 0) {
        if (s->map) modbus_mapping_free(s->map);
        if (s->ctx) modbus_free(s->ctx);
        free(s);
        return -ENOMEM;
    }
    *out = s;
    return 0;
}

void loadid_modbus_ft_server_destroy(loadid_modbus_ft_server_t *s) {
    if (!s) {
        return;
    }
    modbus_mapping_free(s->map);
    modbus_free(s->ctx); /* not modbus_close: the descriptor is the caller's */
    pthread_mutex_destroy(&s->lock);
    free(s);
}

void loadid_modbus_ft_server_set_input(loadid_modbus_ft_server_t *s,
                                       const uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT]) {
    pthread_mutex_lock(&s->lock);
    for (int i = 0; i < LOADID_MODBUS_FT_INPUT_COUNT && i < s->nb_input; ++i) {
        s->map->tab_input_registers[i] = regs[i];
    }
    pthread_mutex_unlock(&s->lock);
}

void loadid_modbus_ft_server_set_holding(loadid_modbus_ft_server_t *s,
                                         const uint16_t regs[LOADID_MODBUS_FT_HOLDING_COUNT]) {
    pthread_mutex_lock(&s->lock);
    for (int i = 0; i < LOADID_MODBUS_FT_HOLDING_COUNT && i < s->nb_holding; ++i) {
        s->map->tab_registers[i] = regs[i];
    }
    pthread_mutex_unlock(&s->lock);
}

void loadid_modbus_ft_server_set_mode(loadid_modbus_ft_server_t *s, int mode) {
    pthread_mutex_lock(&s->lock);
    s->mode = mode;
    pthread_mutex_unlock(&s->lock);
}

void loadid_modbus_ft_server_set_hook(loadid_modbus_ft_server_t *s,
                                      loadid_modbus_ft_server_hook_fn fn, void *ctx) {
    pthread_mutex_lock(&s->lock);
    s->hook = fn;
    s->hook_ctx = ctx;
    pthread_mutex_unlock(&s->lock);
}

/* The answer to "read input registers addr, qty" with its CRC inverted.
 * Lock held. */
static int write_bad_crc(loadid_modbus_ft_server_t *s, const uint8_t *req) {
    const int addr = (req[2] << 8) | req[3];
    const int qty = (req[4] << 8) | req[5];
    uint8_t rsp[3 + 2 * 125 + 2];
    if (qty < 1 || qty > 125) {
        return 0;
    }
    rsp[0] = req[0];
    rsp[1] = req[1];
    rsp[2] = (uint8_t)(2 * qty);
    for (int i = 0; i < qty; ++i) {
        const int r = addr + i;
        const uint16_t v = r < s->nb_input ? s->map->tab_input_registers[r] : 0;
        rsp[3 + 2 * i] = (uint8_t)(v >> 8);
        rsp[4 + 2 * i] = (uint8_t)(v & 0xFFu);
    }
    const int n = 3 + 2 * qty;
    const uint16_t crc = (uint16_t)~loadid_modbus_crc16(rsp, n);
    rsp[n] = (uint8_t)(crc & 0xFFu);
    rsp[n + 1] = (uint8_t)(crc >> 8);
    return write(s->fd, rsp, (size_t)n + 2) == n + 2 ? 0 : -errno;
}

int loadid_modbus_ft_server_poll(loadid_modbus_ft_server_t *s, int timeout_ms) {
    struct pollfd pfd = {.fd = s->fd, .events = POLLIN};
    const int pr = poll(&pfd, 1, timeout_ms);
    if (pr < 0) {
        return errno == EINTR ? 0 : -errno;
    }
    if (pr == 0) {
        return 0;
    }
    if (!(pfd.revents & POLLIN)) {
        /* POLLHUP alone: a pty master whose slave nobody holds open. */
        return -EIO;
    }
    uint8_t req[MODBUS_RTU_MAX_ADU_LENGTH];
    const int n = modbus_receive(s->ctx, req);
    if (n < 0) {
        return -errno;
    }
    if (n == 0) {
        return 1; /* for another slave */
    }
    /* RTU: req[0] slave, req[1] function. */
    const int function = req[1];
    pthread_mutex_lock(&s->lock);
    ++s->st.requests;
    s->st.input_reads += function == MODBUS_FC_READ_INPUT_REGISTERS;
    s->st.holding_reads += function == MODBUS_FC_READ_HOLDING_REGISTERS;
    loadid_modbus_ft_server_hook_fn hook = s->hook;
    void *hook_ctx = s->hook_ctx;
    pthread_mutex_unlock(&s->lock);
    if (hook && function == MODBUS_FC_READ_INPUT_REGISTERS) {
        hook(hook_ctx, s);
    }
    int rc = 0;
    pthread_mutex_lock(&s->lock);
    if (s->mode == LOADID_MODBUS_FT_SERVER_SILENT) {
        ++s->st.silent;
    } else if (s->mode == LOADID_MODBUS_FT_SERVER_BAD_CRC &&
               function == MODBUS_FC_READ_INPUT_REGISTERS && n >= 8) {
        ++s->st.bad_crc;
        rc = write_bad_crc(s, req);
    } else {
        ++s->st.replies;
        rc = modbus_reply(s->ctx, req, n, s->map) < 0 ? -errno : 0;
    }
    pthread_mutex_unlock(&s->lock);
    return rc < 0 ? rc : 1;
}

void loadid_modbus_ft_server_stats(loadid_modbus_ft_server_t *s,
                                   loadid_modbus_ft_server_stats_t *out) {
    pthread_mutex_lock(&s->lock);
    *out = s->st;
    pthread_mutex_unlock(&s->lock);
}
