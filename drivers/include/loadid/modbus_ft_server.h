/*
 * loadid drivers: the sensor's side of proto/modbus_ft.md, a libmodbus RTU
 * server on a file descriptor (a pseudo-terminal's master end, or an open
 * serial port), for the tests and for loadid-modbus-sim. Not used by the
 * daemon.
 *
 * It answers with modbus_reply() from a modbus_mapping_t (input registers
 * 0..n-1 and holding registers 0..m-1; a mapping smaller than the map makes
 * libmodbus answer ILLEGAL DATA ADDRESS), and injects faults the way
 * libmodbus' own tests do, by mode: no answer at all (the client times
 * out), or an answer whose CRC is wrong. All setters are thread-safe, so a
 * test thread can change the registers while a server thread polls.
 */
#ifndef LOADID_MODBUS_FT_SERVER_H
#define LOADID_MODBUS_FT_SERVER_H

#include <stdint.h>

#include "loadid/modbus_ft.h"

#ifdef __cplusplus
extern "C" {
#endif

enum loadid_modbus_ft_server_mode {
    LOADID_MODBUS_FT_SERVER_NORMAL = 0, /* modbus_reply */
    LOADID_MODBUS_FT_SERVER_SILENT = 1, /* read the request, answer nothing */
    LOADID_MODBUS_FT_SERVER_BAD_CRC = 2 /* input reads: the right answer with
                                            its CRC inverted, written raw */
};

typedef struct {
    int64_t requests;      /* requests for this slave */
    int64_t input_reads;   /* of which function 0x04 */
    int64_t holding_reads; /* of which function 0x03 */
    int64_t replies;       /* answered through modbus_reply (incl. exceptions) */
    int64_t silent;        /* not answered (SILENT) */
    int64_t bad_crc;       /* answered with a wrong CRC (BAD_CRC) */
} loadid_modbus_ft_server_stats_t;

typedef struct loadid_modbus_ft_server loadid_modbus_ft_server_t; /* opaque */

/* Called for every input-register read before it is answered (the
 * simulator and the tests put the next sample in place here). */
typedef void (*loadid_modbus_ft_server_hook_fn)(void *ctx, loadid_modbus_ft_server_t *srv);

/* A server on fd (not owned: never closed here) for slave_id, with
 * nb_input input registers and nb_holding holding registers, all 0.
 * Returns 0, -EINVAL, -ENOMEM. */
int loadid_modbus_ft_server_create(int fd, int slave_id, int nb_input, int nb_holding,
                                   loadid_modbus_ft_server_t **out);

void loadid_modbus_ft_server_destroy(loadid_modbus_ft_server_t *srv);

/* Copies regs[0..7] into input registers 0..7 (as far as the mapping
 * reaches). */
void loadid_modbus_ft_server_set_input(loadid_modbus_ft_server_t *srv,
                                       const uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT]);

/* Copies regs[0..5] into holding registers 0..5 (as far as they reach). */
void loadid_modbus_ft_server_set_holding(loadid_modbus_ft_server_t *srv,
                                         const uint16_t regs[LOADID_MODBUS_FT_HOLDING_COUNT]);

void loadid_modbus_ft_server_set_mode(loadid_modbus_ft_server_t *srv, int mode);

void loadid_modbus_ft_server_set_hook(loadid_modbus_ft_server_t *srv,
                                      loadid_modbus_ft_server_hook_fn fn, void *ctx);

/* Waits up to timeout_ms for a request and handles it. Returns 1 (a
 * request handled, or a frame for another slave ignored), 0 (nothing
 * came), or -errno (-EIO: the other end of the pty is not open; a
 * malformed request gives -EMBBADCRC etc. negated and is dropped). */
int loadid_modbus_ft_server_poll(loadid_modbus_ft_server_t *srv, int timeout_ms);

void loadid_modbus_ft_server_stats(loadid_modbus_ft_server_t *srv,
                                   loadid_modbus_ft_server_stats_t *out);

/* The Modbus CRC-16 (poly 0xA001 reflected, init 0xFFFF) of n bytes; sent
 * low byte first. */
uint16_t loadid_modbus_crc16(const uint8_t *p, int n);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_MODBUS_FT_SERVER_H */
