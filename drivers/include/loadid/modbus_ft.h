/*
 * loadid drivers: a serial force-torque sensor over Modbus RTU (libmodbus),
 * the register map of proto/modbus_ft.md:
 *
 *   input registers 0..7 (function 0x04, ONE transaction per sample):
 *     Fx Fy Fz Tx Ty Tz (int16 counts), status (bit 0 saturated, bit 1
 *     sensor fault, bits 2-15 reserved = 0), counter (uint16, +1 per new
 *     measurement, wraps)
 *   holding registers 0..5 (function 0x03, read at open): full scales,
 *     uint16 in 0.1 N (force) and 0.01 N m (moment); they override the
 *     configured ones.
 *   value = counts * full_scale / 16384 (the JR3 convention).
 *
 * Two halves, split as jr3.h is:
 *   - the decoder: pure, no I/O, no clock; a register block in, an SI
 *     sample and counters out (unit-testable with register vectors);
 *   - the client: libmodbus RTU on a serial device (open, one-transaction
 *     read, close, reopen after the device vanished), which counts every
 *     transport fault and uses the decoder.
 *
 * Return convention (loadid/error_text.h): 0 or a positive result code on success, a
 * negated errno or a LOADID_MODBUS_FT_E_* code (all below -1200) otherwise;
 * loadid_modbus_ft_strerror() names each.
 */
#ifndef LOADID_MODBUS_FT_H
#define LOADID_MODBUS_FT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- The register map (proto/modbus_ft.md) ------------------------------ */

#define LOADID_MODBUS_FT_INPUT_ADDR 0  /* first input register of a sample */
#define LOADID_MODBUS_FT_INPUT_COUNT 8 /* Fx Fy Fz Tx Ty Tz status counter */
#define LOADID_MODBUS_FT_REG_STATUS 6
#define LOADID_MODBUS_FT_REG_COUNTER 7
#define LOADID_MODBUS_FT_HOLDING_ADDR 0   /* first full-scale holding register */
#define LOADID_MODBUS_FT_HOLDING_COUNT 6  /* fs Fx Fy Fz [0.1 N], Tx Ty Tz [0.01 N m] */
#define LOADID_MODBUS_FT_FORCE_UNIT 0.1   /* N per holding-register unit */
#define LOADID_MODBUS_FT_MOMENT_UNIT 0.01 /* N m per holding-register unit */
#define LOADID_MODBUS_FT_COUNTS_PER_FULL_SCALE 16384.0

#define LOADID_MODBUS_FT_STATUS_SATURATED 0x0001u
#define LOADID_MODBUS_FT_STATUS_FAULT 0x0002u
#define LOADID_MODBUS_FT_STATUS_RESERVED 0xFFFCu /* must be 0 */

#define LOADID_MODBUS_FT_DEFAULT_SLAVE 1
#define LOADID_MODBUS_FT_DEVICE_MAX 256

/* Results (non-negative). */
enum loadid_modbus_ft_result {
    LOADID_MODBUS_FT_SAMPLE = 1,    /* out is a new, usable sample: the ONLY
                                          result after which a sample may go
                                          to an estimator */
    LOADID_MODBUS_FT_FULL_SCALE = 2 /* full scales taken from the registers */
};

/* Errors (negative). The first two come with a decoded sample in *out that
 * must not be used (for logging, and for the pipeline's counters). */
enum loadid_modbus_ft_error {
    LOADID_MODBUS_FT_E_SATURATED = -1201, /* new sample, a channel saturated */
    LOADID_MODBUS_FT_E_FAULT = -1202,     /* new sample, sensor fault (wins
                                             over E_SATURATED) */
    LOADID_MODBUS_FT_E_STALE = -1203,     /* counter unchanged: no new sample */
    LOADID_MODBUS_FT_E_MALFORMED = -1204, /* reserved status bits set, or a
                                             zero full scale */
    LOADID_MODBUS_FT_E_TIMEOUT = -1205,   /* no response in timeout_ms */
    LOADID_MODBUS_FT_E_BAD_FRAME = -1206, /* CRC error, wrong slave, bad data */
    LOADID_MODBUS_FT_E_EXCEPTION = -1207, /* a Modbus exception response */
    LOADID_MODBUS_FT_E_GONE = -1208,      /* the device vanished or failed: it
                                             is closed now; reopen it */
    LOADID_MODBUS_FT_E_CLOSED = -1209     /* read on a closed client */
};

/* ---- Decoder (pure) ------------------------------------------------------ */

/* One decoded sample. */
typedef struct {
    int64_t t_us;      /* time of the response [us since the epoch] */
    uint16_t counter;  /* input register 7 */
    uint16_t status;   /* input register 6 */
    bool saturated;    /* status bit 0 */
    bool faulty;       /* status bit 1 */
    int16_t counts[6]; /* Fx Fy Fz Tx Ty Tz */
    double force[3];   /* counts * fs / 16384 [N] */
    double torque[3];  /* counts * fs / 16384 [N m] */
} loadid_modbus_ft_sample_t;

/* Counters since init (decoder) or create (client). Invariants (checked by
 * the tests):
 *   blocks = samples_ok + samples_rejected + samples_stale + samples_malformed
 *   max(saturated, faulty) <= samples_rejected <= saturated + faulty
 *   reads + full_scale_requests = blocks + full_scale_reads
 *       + full_scale_malformed + timeouts + bad_frames + exceptions + io_errors */
typedef struct {
    /* decoder */
    int64_t blocks;               /* register blocks decoded */
    int64_t samples_ok;           /* new and usable (LOADID_MODBUS_FT_SAMPLE) */
    int64_t samples_rejected;     /* new, saturated or faulty or both */
    int64_t samples_saturated;    /* new, status bit 0 */
    int64_t samples_faulty;       /* new, status bit 1 */
    int64_t samples_stale;        /* counter unchanged: the same sample again */
    int64_t samples_malformed;    /* reserved status bits set */
    int64_t counter_gaps;         /* measurements skipped: sum of (step - 1) */
    int64_t full_scale_reads;     /* full-scale blocks taken */
    int64_t full_scale_malformed; /* full-scale blocks with a zero value */
    /* client */
    int64_t reads;               /* sample transactions attempted */
    int64_t full_scale_requests; /* holding-register transactions (at open) */
    int64_t timeouts;            /* ETIMEDOUT */
    int64_t bad_frames;          /* EMBBADCRC, EMBBADSLAVE, EMBBADDATA, ... */
    int64_t crc_errors;          /* ... of which EMBBADCRC */
    int64_t exceptions;          /* EMBXILFUN .. EMBXGTAR (any transaction) */
    int64_t io_errors;           /* other errno: the device is closed */
    int64_t opens;               /* successful opens (1 + reopens) */
    int64_t open_failures;       /* failed open attempts */
    int64_t device_lost;         /* an open device that vanished or failed */
} loadid_modbus_ft_stats_t;

/* The decoder's state: caller-owned (no allocation); fields are private. */
typedef struct {
    double fs_force[3];   /* in force [N] */
    double fs_moment[3];  /* in force [N m] */
    double cfg_force[3];  /* configured [N] */
    double cfg_moment[3]; /* configured [N m] */
    bool begun;           /* a counter was seen */
    uint16_t last_counter;
    loadid_modbus_ft_stats_t st;
} loadid_modbus_ft_decoder_t;

/* Sets the configured full scales (> 0 and finite, else -EINVAL) and
 * clears the history and the counters. Returns 0 or -EINVAL. */
int loadid_modbus_ft_decoder_init(loadid_modbus_ft_decoder_t *dec, const double fs_force[3],
                                  const double fs_moment[3]);

/* Forgets the counter history (after a reopen: the next block is a new
 * sample, no gap counted); counters and full scales stay. */
void loadid_modbus_ft_decoder_restart(loadid_modbus_ft_decoder_t *dec);

/* Decodes one input-register block regs[0..7] read at t_us. Returns:
 *   LOADID_MODBUS_FT_SAMPLE        *out: new and usable.
 *   LOADID_MODBUS_FT_E_SATURATED,
 *   LOADID_MODBUS_FT_E_FAULT       *out: new but NOT usable (logging only).
 *   LOADID_MODBUS_FT_E_STALE       *out: the same sample again; not to be fed.
 *   LOADID_MODBUS_FT_E_MALFORMED   nothing: reserved status bits set; the
 *                                  counter is not taken.
 *   -EINVAL                        NULL argument, nothing counted.
 * Constant time, allocation-free. */
int loadid_modbus_ft_decode(loadid_modbus_ft_decoder_t *dec,
                            const uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT], int64_t t_us,
                            loadid_modbus_ft_sample_t *out);

/* Takes the full scales from holding registers 0..5 (0.1 N, 0.01 N m).
 * Returns LOADID_MODBUS_FT_FULL_SCALE; LOADID_MODBUS_FT_E_MALFORMED when a
 * register is 0 (full scales unchanged); -EINVAL for NULL. */
int loadid_modbus_ft_decode_full_scale(loadid_modbus_ft_decoder_t *dec,
                                       const uint16_t regs[LOADID_MODBUS_FT_HOLDING_COUNT]);

/* ---- Encoder (the sensor's side: tests and loadid-modbus-sim) ----------- */

/* SI -> counts = round(value * 16384 / fs), half away from zero; clamped to
 * int16 with the saturated bit set; NaN gives 0 counts and the fault bit.
 * Writes regs[0..7] with status | (fault ? bit 1 : 0) and counter. Returns
 * 0, or -EINVAL (NULL, a full scale not > 0). */
int loadid_modbus_ft_encode(const double fs_force[3], const double fs_moment[3],
                            const double force[3], const double torque[3], bool fault,
                            uint16_t counter, uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT]);

/* Full scales [N, N m] -> holding registers 0..5 (rounded to the unit).
 * Returns 0, or -ERANGE (rounds to 0 or above 65535), -EINVAL (NULL). */
int loadid_modbus_ft_encode_full_scale(const double fs_force[3], const double fs_moment[3],
                                       uint16_t regs[LOADID_MODBUS_FT_HOLDING_COUNT]);

/* ---- Client (libmodbus RTU) --------------------------------------------- */

/* Configuration (immutable after create); the YAML keys are modbus.*. */
typedef struct {
    char device[LOADID_MODBUS_FT_DEVICE_MAX]; /* modbus.device, default /dev/ttyUSB0 */
    int baud;                                 /* modbus.baud [bit/s], default 115200 */
    char parity;                              /* 'N', 'E', 'O' (modbus.parity none/even/odd) */
    int data_bits;                            /* modbus.data_bits 5..8, default 8 */
    int stop_bits;                            /* modbus.stop_bits 1..2, default 1 */
    int slave_id;                             /* modbus.slave_id 1..247, default 1 */
    int timeout_ms;                           /* modbus.timeout_ms, response timeout, default 20 */
    double fs_force[3];                       /* modbus.full_scale.force [N], default 200 */
    double fs_moment[3];                      /* modbus.full_scale.moment [N m], default 12 */
} loadid_modbus_ft_config_t;

typedef struct loadid_modbus_ft loadid_modbus_ft_t; /* opaque */

void loadid_modbus_ft_config_default(loadid_modbus_ft_config_t *cfg);

/* 0 when usable, -EINVAL otherwise (empty device, a baud rate libmodbus
 * does not know on Linux, parity, bits, slave id, timeout <= 0, full scales). */
int loadid_modbus_ft_config_check(const loadid_modbus_ft_config_t *cfg);

/* Whether libmodbus' RTU backend maps this baud rate onto a termios speed
 * (it silently uses 9600 for others). */
bool loadid_modbus_ft_baud_supported(int baud);

/* Allocates the client (and the libmodbus context); opens nothing. The
 * only allocation. Returns 0, -EINVAL (invalid cfg), -ENOMEM. */
int loadid_modbus_ft_create(const loadid_modbus_ft_config_t *cfg, loadid_modbus_ft_t **out);

/* Closes the device if open, frees; NULL allowed. */
void loadid_modbus_ft_destroy(loadid_modbus_ft_t *ft);

/* Opens the device (also again after E_GONE or close: reopen), sets the
 * line and the response timeout, and reads the full-scale holding
 * registers, which then override the configured ones (a Modbus exception
 * there keeps the configured ones). Returns 0 or LOADID_MODBUS_FT_FULL_SCALE
 * (taken from the sensor); on failure the device is closed and the code is
 * -errno of open/tcsetattr (-ENOENT: no such device), or
 * LOADID_MODBUS_FT_E_TIMEOUT / _E_BAD_FRAME (nothing sensible answers), and
 * open_failures is counted. A message for logs is in
 * loadid_modbus_ft_last_error(). */
int loadid_modbus_ft_open(loadid_modbus_ft_t *ft);

bool loadid_modbus_ft_is_open(const loadid_modbus_ft_t *ft);

/* Closes the device; counters and full scales stay. */
void loadid_modbus_ft_close(loadid_modbus_ft_t *ft);

/* One sample: ONE read of input registers 0..7, time stamped with
 * CLOCK_REALTIME when the response is in, then decoded. Blocks up to
 * timeout_ms. Returns what loadid_modbus_ft_decode returns, or
 * LOADID_MODBUS_FT_E_TIMEOUT, _E_BAD_FRAME, _E_EXCEPTION (input buffer
 * flushed, still open), _E_GONE (device closed; reopen), _E_CLOSED,
 * -EINVAL. Every outcome is counted. */
int loadid_modbus_ft_read(loadid_modbus_ft_t *ft, loadid_modbus_ft_sample_t *out);

/* Copies the counters. Returns 0, -EINVAL for NULL. */
int loadid_modbus_ft_stats(const loadid_modbus_ft_t *ft, loadid_modbus_ft_stats_t *out);

/* The full scales in force [N], [N m]. Returns 0, -EINVAL for NULL. */
int loadid_modbus_ft_full_scale(const loadid_modbus_ft_t *ft, double force[3], double moment[3]);

/* The last failure as a line for logs ("/dev/ttyUSB0: open: No such file or
 * directory"); "" when none. */
const char *loadid_modbus_ft_last_error(const loadid_modbus_ft_t *ft);

/* A static text for any return code of this module (or a negated errno).
 * Never NULL. */
const char *loadid_modbus_ft_strerror(int code);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_MODBUS_FT_H */
