/*
 * Input backend: the serial F/T sensor over Modbus RTU (sensor.type
 * modbus). Its poller thread (modbus_input.h) keeps libmodbus' blocking
 * transactions off the loop and hands samples over through a lock-free
 * ring and an eventfd, which is the descriptor the loop waits on. A sample
 * arrives when the poller got the sensor's answer (its CLOCK_REALTIME
 * stamp) and becomes the pipeline's sensor sample without accelerometer.
 * Its faults in status_t's terms: a bad frame (CRC, wrong slave, a
 * malformed status) or an exception is a bad frame, a transaction without
 * an answer an incomplete sample. Measurements the sensor's counter says
 * were skipped are not sequence gaps: polling slower than the sensor
 * measures skips them by design (--verbose's summary has them).
 */
#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../clock.h"
#include "../log.h"
#include "input.h"
#include "modbus_input.h"

typedef struct {
    loadid_modbus_input_t *ft;
    int64_t connected; /* the poller's last reported state */
} modbus_t;

static int open_(loadid_input_t *in, const loadid_input_options_t *opt, char *err, size_t errlen) {
    (void)opt;
    modbus_t *m = calloc(1, sizeof *m);
    if (!m) {
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    in->state = m;
    in->late_measured = 1;
    char why[512];
    const int rc = loadid_modbus_input_start(in->cfg, &m->ft, why, sizeof why);
    if (rc != 0) snprintf(err, errlen, "modbus: %s", why);
    return rc;
}

static int fd_(const loadid_input_t *in) {
    return loadid_modbus_input_fd(((const modbus_t *)in->state)->ft);
}

static void on_sample(void *ctx, const loadid_modbus_ft_sample_t *s) {
    loadid_input_t *in = ctx;
    loadid_sensor_sample_t x = {.t_us = s->t_us, .saturated = s->saturated, .faulty = s->faulty};
    memcpy(x.force, s->force, sizeof x.force);
    memcpy(x.torque, s->torque, sizeof x.torque);
    loadid_pipeline_sample(in->pipe, &x);
    loadid_input_late(in, (double)(loadid_wall_us() - s->t_us));
}

static void read_(loadid_input_t *in) {
    loadid_modbus_input_drain(((modbus_t *)in->state)->ft, on_sample, in);
}

/* Says when the sensor was lost or came back (both within the second: the
 * poller reopens after a response timeout). */
static void second(loadid_input_t *in) {
    modbus_t *m = in->state;
    const bool lost = loadid_modbus_input_take_lost(m->ft);
    loadid_modbus_input_stats_t ms;
    loadid_modbus_input_stats(m->ft, &ms);
    if (lost)
        loadidd_log("modbus %s lost: %s; reopening", in->cfg->modbus_device,
                    loadid_modbus_ft_strerror((int)ms.lost_error));
    if (ms.connected && (!m->connected || lost))
        loadidd_log("modbus %s open", in->cfg->modbus_device);
    m->connected = ms.connected;
}

static void counters(const loadid_input_t *in, loadid_input_counters_t *out) {
    loadid_modbus_input_stats_t ms;
    if (loadid_modbus_input_stats(((const modbus_t *)in->state)->ft, &ms) != 0) return;
    out->frames_bad = ms.ft.bad_frames + ms.ft.exceptions + ms.ft.samples_malformed;
    out->samples_incomplete = ms.ft.timeouts;
}

static void summary(const loadid_input_t *in) {
    loadid_modbus_input_stats_t ms;
    if (loadid_modbus_input_stats(((const modbus_t *)in->state)->ft, &ms) != 0) return;
    loadidd_log(
        "modbus reads %lld, samples ok %lld, rejected %lld, stale %lld, gaps %lld, "
        "malformed %lld, timeouts %lld, bad frames %lld (CRC %lld), exceptions %lld, "
        "device lost %lld, ring overruns %lld, cycles missed %lld",
        (long long)ms.ft.reads, (long long)ms.ft.samples_ok, (long long)ms.ft.samples_rejected,
        (long long)ms.ft.samples_stale, (long long)ms.ft.counter_gaps,
        (long long)ms.ft.samples_malformed, (long long)ms.ft.timeouts, (long long)ms.ft.bad_frames,
        (long long)ms.ft.crc_errors, (long long)ms.ft.exceptions, (long long)ms.ft.device_lost,
        (long long)ms.ring_overruns, (long long)ms.cycles_missed);
}

static void close_(loadid_input_t *in) {
    modbus_t *m = in->state;
    if (!m) return;
    loadid_modbus_input_stop(m->ft);
    free(m);
    in->state = NULL;
}

/* A loss or a reopen since the last once-a-second look is said at the
 * stop too. */
const loadid_input_backend_t loadid_input_modbus_rtu = {.name = "modbus-rtu",
                                                        .open = open_,
                                                        .fd = fd_,
                                                        .read = read_,
                                                        .second = second,
                                                        .finish = second,
                                                        .counters = counters,
                                                        .summary = summary,
                                                        .close = close_};
