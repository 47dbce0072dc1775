/* The Modbus F/T poller thread and its SPSC ring (modbus_input.h). */
#define _GNU_SOURCE /* pthread_setname_np, pthread_setaffinity_np */

#include "modbus_input.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

_Static_assert((LOADID_MODBUS_INPUT_RING & (LOADID_MODBUS_INPUT_RING - 1)) == 0,
               "the ring size is a power of two");

/* The driver's counters are all int64_t: mirrored field by field through
 * an array of atomics. */
#define FT_FIELDS (sizeof(loadid_modbus_ft_stats_t) / sizeof(int64_t))
_Static_assert(sizeof(loadid_modbus_ft_stats_t) % sizeof(int64_t) == 0,
               "loadid_modbus_ft_stats_t holds only int64_t");

struct loadid_modbus_input {
    loadid_modbus_ft_t *ft; /* the thread's only */
    int64_t period_ns;
    int retry_min_ms; /* the first retry after a loss: modbus.timeout_ms */
    int efd;
    pthread_t thread;
    atomic_bool stop;

    /* The ring: the thread writes tail, the loop head; a slot is the
     * producer's until tail passes it and the consumer's until head does. */
    loadid_modbus_ft_sample_t *ring;
    _Alignas(64) atomic_size_t head;
    _Alignas(64) atomic_size_t tail;

    _Alignas(64) _Atomic int64_t ft_stats[FT_FIELDS];
    _Atomic int64_t delivered, overruns, missed, open_attempts, connected, last_error, lost_error;
    atomic_bool lost;
    _Atomic double fs[6];
};

void loadid_modbus_input_ft_config(const loadid_config_t *cfg, loadid_modbus_ft_config_t *ft) {
    loadid_modbus_ft_config_default(ft);
    snprintf(ft->device, sizeof ft->device, "%s", cfg->modbus_device);
    ft->baud = cfg->modbus_baud;
    ft->parity = cfg->modbus_parity;
    ft->data_bits = cfg->modbus_data_bits;
    ft->stop_bits = cfg->modbus_stop_bits;
    ft->slave_id = cfg->modbus_slave_id;
    ft->timeout_ms = cfg->modbus_timeout_ms;
    memcpy(ft->fs_force, cfg->modbus_fs_force, sizeof ft->fs_force);
    memcpy(ft->fs_moment, cfg->modbus_fs_moment, sizeof ft->fs_moment);
}

static int64_t mono_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void sleep_until(int64_t t_ns) {
    struct timespec ts = {.tv_sec = t_ns / 1000000000, .tv_nsec = t_ns % 1000000000};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {}
}

static void mirror(loadid_modbus_input_t *in) {
    loadid_modbus_ft_stats_t st;
    int64_t v[FT_FIELDS];
    loadid_modbus_ft_stats(in->ft, &st);
    memcpy(v, &st, sizeof v);
    for (size_t i = 0; i < FT_FIELDS; ++i) {
        atomic_store_explicit(&in->ft_stats[i], v[i], memory_order_relaxed);
    }
}

static void publish_full_scale(loadid_modbus_input_t *in) {
    double f[3], m[3];
    loadid_modbus_ft_full_scale(in->ft, f, m);
    for (int i = 0; i < 3; ++i) {
        atomic_store(&in->fs[i], f[i]);
        atomic_store(&in->fs[3 + i], m[i]);
    }
}

/* Producer side. */
static void push(loadid_modbus_input_t *in, const loadid_modbus_ft_sample_t *s) {
    const size_t t = atomic_load_explicit(&in->tail, memory_order_relaxed);
    const size_t h = atomic_load_explicit(&in->head, memory_order_acquire);
    if (t - h >= LOADID_MODBUS_INPUT_RING) {
        atomic_fetch_add_explicit(&in->overruns, 1, memory_order_relaxed);
        return;
    }
    in->ring[t & (LOADID_MODBUS_INPUT_RING - 1)] = *s;
    atomic_store_explicit(&in->tail, t + 1, memory_order_release);
    atomic_fetch_add_explicit(&in->delivered, 1, memory_order_relaxed);
    const uint64_t one = 1;
    /* Cannot block (EFD_NONBLOCK) and cannot fail short of a counter at
     * 2^64 - 2: the loop reads it on every drain. */
    ssize_t w = write(in->efd, &one, sizeof one);
    (void)w;
}

/* Sleeps up to ms in short slices, returning early on stop. */
static void pause_ms(loadid_modbus_input_t *in, int ms) {
    const int64_t end = mono_ns() + (int64_t)ms * 1000000;
    while (!atomic_load(&in->stop)) {
        const int64_t now = mono_ns();
        if (now >= end) {
            return;
        }
        const int64_t slice = 20 * 1000000;
        sleep_until(now + (end - now < slice ? end - now : slice));
    }
}

/* The next wait before an open attempt: twice the last, at most
 * LOADID_MODBUS_INPUT_RETRY_MS. */
static int backoff(int ms) {
    return ms >= LOADID_MODBUS_INPUT_RETRY_MS / 2 ? LOADID_MODBUS_INPUT_RETRY_MS : 2 * ms;
}

static void *poller(void *arg) {
    loadid_modbus_input_t *in = arg;
    /* Named from inside (a prctl): another thread's name is written
     * through /proc. */
    pthread_setname_np(pthread_self(), "loadid-modbus");
    int64_t next = mono_ns();
    int retry_ms = in->retry_min_ms;
    while (!atomic_load(&in->stop)) {
        if (!loadid_modbus_ft_is_open(in->ft)) {
            atomic_fetch_add(&in->open_attempts, 1);
            const int rc = loadid_modbus_ft_open(in->ft);
            mirror(in);
            if (rc < 0) {
                atomic_store(&in->last_error, rc);
                pause_ms(in, retry_ms);
                retry_ms = backoff(retry_ms);
                continue;
            }
            publish_full_scale(in);
            atomic_store(&in->connected, 1);
            retry_ms = in->retry_min_ms;
            next = mono_ns();
        }
        loadid_modbus_ft_sample_t s;
        const int rc = loadid_modbus_ft_read(in->ft, &s);
        if (rc == LOADID_MODBUS_FT_SAMPLE || rc == LOADID_MODBUS_FT_E_SATURATED ||
            rc == LOADID_MODBUS_FT_E_FAULT) {
            push(in, &s);
        } else if (rc < 0 && rc != LOADID_MODBUS_FT_E_STALE) {
            atomic_store(&in->last_error, rc);
        }
        mirror(in);
        if (rc == LOADID_MODBUS_FT_E_GONE) {
            /* As libmodbus' link recovery: reconnect after one response
             * timeout (a USB adapter re-enumerated, a connector wiggled),
             * then back off (modbus_input.h). */
            atomic_store(&in->connected, 0);
            atomic_store(&in->lost_error, rc);
            atomic_store(&in->lost, true);
            pause_ms(in, retry_ms);
            retry_ms = backoff(retry_ms);
            continue;
        }
        /* The next period on an absolute deadline; periods a slow
         * transaction overran are skipped and counted, not made up. */
        next += in->period_ns;
        const int64_t now = mono_ns();
        if (next < now) {
            const int64_t behind = (now - next) / in->period_ns + 1;
            atomic_fetch_add(&in->missed, behind);
            next += behind * in->period_ns;
        }
        sleep_until(next);
    }
    return NULL;
}

/* realtime.cpu and realtime.priority for the poller thread (modbus_input.h
 * says why one below the loop). 0, or -errno with the reason in err. */
static int poller_realtime(const loadid_config_t *cfg, pthread_t thread, char *err, size_t errlen) {
    if (cfg->rt_cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(cfg->rt_cpu, &set);
        const int rc = pthread_setaffinity_np(thread, sizeof set, &set);
        if (rc != 0) {
            snprintf(err, errlen, "realtime.cpu %d: the poller thread: %s", cfg->rt_cpu,
                     strerror(rc));
            return -rc;
        }
    }
    if (cfg->rt_priority > 0) {
        const int prio = cfg->rt_priority > 1 ? cfg->rt_priority - 1 : 1;
        const struct sched_param sp = {.sched_priority = prio};
        const int rc = pthread_setschedparam(thread, SCHED_FIFO, &sp);
        if (rc != 0) {
            snprintf(err, errlen,
                     "realtime.priority %d: SCHED_FIFO %d for the poller thread: %s "
                     "(LimitRTPRIO? root?)",
                     cfg->rt_priority, prio, strerror(rc));
            return -rc;
        }
    }
    return 0;
}

int loadid_modbus_input_start(const loadid_config_t *cfg, loadid_modbus_input_t **out, char *err,
                              size_t errlen) {
    char dummy[1];
    if (!err || errlen == 0) {
        err = dummy;
        errlen = sizeof dummy;
    }
    err[0] = '\0';
    if (!cfg || !out || !(cfg->modbus_rate_hz > 0) || cfg->modbus_rate_hz > 1e6) {
        snprintf(err, errlen, "modbus: invalid settings");
        return -EINVAL;
    }
    loadid_modbus_ft_config_t fc;
    loadid_modbus_input_ft_config(cfg, &fc);
    loadid_modbus_input_t *in = calloc(1, sizeof *in);
    if (!in) {
        snprintf(err, errlen, "modbus: out of memory");
        return -ENOMEM;
    }
    in->efd = -1;
    int rc = loadid_modbus_ft_create(&fc, &in->ft);
    if (rc < 0) {
        snprintf(err, errlen, "modbus: %s: %s", fc.device, loadid_modbus_ft_strerror(rc));
        free(in);
        return rc;
    }
    in->ring = calloc(LOADID_MODBUS_INPUT_RING, sizeof *in->ring);
    in->efd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (!in->ring || in->efd < 0) {
        rc = in->ring ? -errno : -ENOMEM;
        snprintf(err, errlen, "modbus: %s", in->ring ? strerror(errno) : "out of memory");
        goto fail;
    }
    in->period_ns = (int64_t)(1e9 / cfg->modbus_rate_hz);
    in->retry_min_ms =
        fc.timeout_ms < LOADID_MODBUS_INPUT_RETRY_MS ? fc.timeout_ms : LOADID_MODBUS_INPUT_RETRY_MS;
    if (in->period_ns < 1) in->period_ns = 1;
    atomic_init(&in->head, 0);
    atomic_init(&in->tail, 0);
    atomic_init(&in->stop, false);
    atomic_init(&in->lost, false);
    publish_full_scale(in);
    mirror(in);
    rc = -pthread_create(&in->thread, NULL, poller, in);
    if (rc < 0) {
        snprintf(err, errlen, "modbus: cannot start the poller thread: %s", strerror(-rc));
        goto fail;
    }
    rc = poller_realtime(cfg, in->thread, err, errlen);
    if (rc < 0) {
        loadid_modbus_input_stop(in);
        return rc;
    }
    *out = in;
    return 0;
fail:
    if (in->efd >= 0) close(in->efd);
    free(in->ring);
    loadid_modbus_ft_destroy(in->ft);
    free(in);
    return rc;
}

int loadid_modbus_input_fd(const loadid_modbus_input_t *in) {
    return in ? in->efd : -1;
}

int loadid_modbus_input_drain(loadid_modbus_input_t *in, loadid_modbus_input_fn fn, void *ctx) {
    if (!in) {
        return 0;
    }
    uint64_t n;
    /* Read the eventfd first: a sample pushed after this read writes it
     * again, so no wake-up is lost. */
    ssize_t r = read(in->efd, &n, sizeof n);
    (void)r;
    size_t h = atomic_load_explicit(&in->head, memory_order_relaxed);
    const size_t t = atomic_load_explicit(&in->tail, memory_order_acquire);
    int count = 0;
    for (; h != t; ++h, ++count) {
        if (fn) {
            fn(ctx, &in->ring[h & (LOADID_MODBUS_INPUT_RING - 1)]);
        }
        atomic_store_explicit(&in->head, h + 1, memory_order_release);
    }
    return count;
}

int loadid_modbus_input_stats(const loadid_modbus_input_t *in, loadid_modbus_input_stats_t *st) {
    if (!in || !st) {
        return -EINVAL;
    }
    int64_t v[FT_FIELDS];
    for (size_t i = 0; i < FT_FIELDS; ++i) {
        v[i] = atomic_load_explicit(&in->ft_stats[i], memory_order_relaxed);
    }
    memset(st, 0, sizeof *st);
    memcpy(&st->ft, v, sizeof v);
    st->samples_delivered = atomic_load(&in->delivered);
    st->ring_overruns = atomic_load(&in->overruns);
    st->cycles_missed = atomic_load(&in->missed);
    st->open_attempts = atomic_load(&in->open_attempts);
    st->connected = atomic_load(&in->connected);
    st->last_error = atomic_load(&in->last_error);
    st->lost_error = atomic_load(&in->lost_error);
    return 0;
}

bool loadid_modbus_input_take_lost(loadid_modbus_input_t *in) {
    return in && atomic_exchange(&in->lost, false);
}

void loadid_modbus_input_full_scale(const loadid_modbus_input_t *in, double force[3],
                                    double moment[3]) {
    for (int i = 0; i < 3; ++i) {
        force[i] = atomic_load(&in->fs[i]);
        moment[i] = atomic_load(&in->fs[3 + i]);
    }
}

void loadid_modbus_input_stop(loadid_modbus_input_t *in) {
    if (!in) {
        return;
    }
    atomic_store(&in->stop, true);
    pthread_join(in->thread, NULL);
    loadid_modbus_ft_destroy(in->ft);
    close(in->efd);
    free(in->ring);
    free(in);
}
