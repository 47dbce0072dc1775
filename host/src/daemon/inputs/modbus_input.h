/*
 * The Modbus F/T sensor as an input of the daemon's event loop. libmodbus
 * blocks in select() up to its response timeout, so one
 * thread of its own polls the sensor at modbus.rate_hz (drivers/
 * modbus_ft.h), stamps each sample with CLOCK_REALTIME microseconds at the
 * response (docs/INTERFACE.md's utime, the clock of the CAN and LCM inputs), and
 * hands it to the loop through a lock-free single-producer single-consumer
 * ring (C11 atomics, LOADID_MODBUS_INPUT_RING samples, allocated at start)
 * and an eventfd the loop puts in its epoll set.
 *
 * Into the ring go new samples: usable ones and saturated or faulty ones
 * (flagged, so the pipeline counts them; it never feeds them). Stale,
 * malformed and failed reads are only counted. When the ring is full (the
 * loop stalled for seconds) the newest sample is dropped and counted.
 * Device loss: the thread closes the device, sets a flag the loop takes
 * with loadid_modbus_input_take_lost() to log it, counts it, and tries to
 * open it again after one response timeout (modbus.timeout_ms), as
 * libmodbus' own link recovery reconnects, then after twice as long at
 * each failure, up to once a second: a device back within a few tenths of
 * a second costs about as long again, one that stays away costs an open
 * attempt a second. The first open also happens in the thread (a failure
 * there retries the same way), so start never blocks on the serial line.
 *
 * Real time (realtime.*, as the loop's): with realtime.priority P > 0 the
 * thread runs SCHED_FIFO at P - 1 (at 1 when P is 1), and with
 * realtime.cpu on that CPU. Above every normally scheduled task (builds,
 * REFINED's and the save worker's threads, kernel workers), so that its
 * poll period and its time stamp at the response hold on a loaded
 * machine; below the loop, so that it never delays the loop's 1 ms
 * deadline: a sample it reads waits for the loop anyway, so preempting
 * the loop would only hold up what the loop is handling. At P = 1 the two
 * are equal, and SCHED_FIFO does not preempt its equal either. The same
 * CPU as the loop: the one set aside for the daemon; a poll costs the
 * thread microseconds.
 */
#ifndef LOADID_MODBUS_INPUT_H
#define LOADID_MODBUS_INPUT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "loadid/config.h"
#include "loadid/modbus_ft.h"

#define LOADID_MODBUS_INPUT_RING 1024     /* samples: 5 s at 200 Hz; a power of 2 */
#define LOADID_MODBUS_INPUT_RETRY_MS 1000 /* the longest wait between open attempts */

typedef struct {
    loadid_modbus_ft_stats_t ft; /* the driver's counters (modbus_ft.h) */
    int64_t samples_delivered;   /* pushed into the ring */
    int64_t ring_overruns;       /* dropped: the ring was full */
    int64_t cycles_missed;       /* poll periods skipped: a transaction (a
                                    timeout, say) took longer than a period */
    int64_t open_attempts;
    int64_t connected;  /* 1 while the device is open */
    int64_t last_error; /* the last failure's code
                                    (loadid_modbus_ft_strerror), 0 none */
    int64_t lost_error; /* the last loss's (later failures, a
                                    reopen's say, do not change it), 0 none */
} loadid_modbus_input_stats_t;

typedef struct loadid_modbus_input loadid_modbus_input_t; /* opaque */

/* Called by drain for each sample, oldest first. */
typedef void (*loadid_modbus_input_fn)(void *ctx, const loadid_modbus_ft_sample_t *s);

/* Starts the poller on cfg's modbus.* keys (device, line, slave id,
 * timeout, full scales, rate_hz) and realtime.priority and realtime.cpu
 * (above). Allocates everything here. Returns 0, or a negative errno with
 * a one-line reason in err (invalid settings, no memory, no thread, a
 * real-time setting refused: "realtime.priority 10: SCHED_FIFO 9 for the
 * poller thread: Operation not permitted (LimitRTPRIO? root?)"). */
int loadid_modbus_input_start(const loadid_config_t *cfg, loadid_modbus_input_t **out, char *err,
                              size_t errlen);

/* The eventfd: readable when samples wait. Never -1 after a start. */
int loadid_modbus_input_fd(const loadid_modbus_input_t *in);

/* Calls fn for every waiting sample (oldest first) and returns how many.
 * The loop's side of the ring: no allocation, no lock; one read of the
 * eventfd. Call it from one thread only. */
int loadid_modbus_input_drain(loadid_modbus_input_t *in, loadid_modbus_input_fn fn, void *ctx);

/* The counters, read from the loop (each an atomic; the set is not one
 * snapshot). Returns 0, -EINVAL for NULL. */
int loadid_modbus_input_stats(const loadid_modbus_input_t *in, loadid_modbus_input_stats_t *st);

/* true once after each device loss (the flag is cleared): for a log line
 * "modbus: DEVICE lost: <loadid_modbus_ft_strerror(stats.last_error)>". */
bool loadid_modbus_input_take_lost(loadid_modbus_input_t *in);

/* The full scales the driver uses, as of the last open (from the sensor's
 * holding registers, else the configured ones). */
void loadid_modbus_input_full_scale(const loadid_modbus_input_t *in, double force[3],
                                    double moment[3]);

/* Stops the thread (within timeout_ms plus one period), closes the device,
 * frees everything. NULL allowed. */
void loadid_modbus_input_stop(loadid_modbus_input_t *in);

/* cfg's modbus.* keys as the driver's configuration. */
void loadid_modbus_input_ft_config(const loadid_config_t *cfg, loadid_modbus_ft_config_t *ft);

#endif /* LOADID_MODBUS_INPUT_H */
