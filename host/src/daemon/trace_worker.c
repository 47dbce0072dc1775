/* The thread that writes results.trace, and its ring (trace_worker.h). */
#define _GNU_SOURCE /* pthread_setname_np */
#include "trace_worker.h"

#include "background_thread.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <semaphore.h>
#include <signal.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "saved_result.h"
#include "trace_csv.h"

/* The thread's own buffers (paths, messages) are in the worker, not on
 * its stack; snprintf's needs are small. */
#define STACK_BYTES (128 * 1024)

/* Rows leave this many entries free, for the begin and end of sessions. */
enum { RESERVED = 2, MSGS = 4, MSG_LEN = 4608 };

enum { BEGIN, ROW, END, END_NONE };

typedef struct {
    int kind;
    int64_t utime;                /* BEGIN: START's */
    int64_t dropped;              /* END: rows the full ring dropped in the session */
    loadid_pipeline_estimate_t e; /* ROW: the row; END: the final estimate */
} entry_t;

/* An entry is the loop's until submitted passes it, the thread's until
 * ended does; a message the thread's until made passes it, the loop's
 * until taken does. */
struct loadid_trace_worker {
    const char *dir;
    entry_t *ring;
    sem_t wake;
    pthread_t thread;
    bool running;
    /* the loop's alone */
    bool open;
    int64_t dropped;
    /* the thread's alone */
    loadid_trace_csv_t csv;
    bool writing;
    int64_t start_utime, rows;
    char load_name[LOADID_LOAD_NAME_MAX];
    char tmp[4400], final_path[4400];
    char msgs[MSGS][MSG_LEN];
    _Alignas(64) atomic_size_t submitted;
    _Alignas(64) atomic_size_t ended;
    _Alignas(64) atomic_size_t made;
    _Alignas(64) atomic_size_t taken;
    atomic_bool quit;
};

/* A message for the loop to log; dropped when MSGS wait already. */
static void say(loadid_trace_worker_t *w, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void say(loadid_trace_worker_t *w, const char *fmt, ...) {
    const size_t m = atomic_load_explicit(&w->made, memory_order_relaxed);
    if (m - atomic_load_explicit(&w->taken, memory_order_acquire) >= MSGS) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(w->msgs[m % MSGS], MSG_LEN, fmt, ap);
    va_end(ap);
    atomic_store_explicit(&w->made, m + 1, memory_order_release);
}

static void begin(loadid_trace_worker_t *w, int64_t utime) {
    w->start_utime = utime;
    w->rows = 0;
    w->load_name[0] = 0;
    w->writing = false;
    char err[4600];
    if (mkdir(w->dir, 0777) != 0 && errno != EEXIST) {
        say(w, "results.trace: %s: cannot create: %s", w->dir, strerror(errno));
        return;
    }
    snprintf(w->tmp, sizeof w->tmp, "%s/.trace-%lld.csv.tmp", w->dir, (long long)utime);
    if (loadid_trace_csv_open(&w->csv, w->tmp, err, sizeof err) != 0) {
        say(w, "results.trace: %s", err);
        return;
    }
    loadid_trace_csv_start(&w->csv, utime);
    w->writing = true;
}

static void row(loadid_trace_worker_t *w, const loadid_pipeline_estimate_t *e) {
    if (!w->writing) return;
    loadid_trace_csv_row(&w->csv, e);
    snprintf(w->load_name, sizeof w->load_name, "%s", e->load_name);
    ++w->rows;
}

/* The session's end: closed, and renamed to its final name. */
static void end(loadid_trace_worker_t *w, const entry_t *x) {
    if (!w->writing) return;
    w->writing = false;
    char err[4600];
    if (loadid_trace_csv_close(&w->csv, err, sizeof err) != 0) {
        say(w, "results.trace: %s", err);
        return;
    }
    if (x->kind == END)
        loadid_saved_result_name(w->dir, x->e.load_name, x->e.utime, ".trace.csv", w->final_path,
                                 sizeof w->final_path);
    else
        loadid_saved_result_name(w->dir, w->load_name, w->start_utime, ".trace.csv", w->final_path,
                                 sizeof w->final_path);
    if (rename(w->tmp, w->final_path) != 0) {
        say(w, "results.trace: cannot rename %s to %s: %s", w->tmp, w->final_path, strerror(errno));
        return;
    }
    if (x->dropped)
        say(w, "traced %s (%lld rows; %lld more dropped: the writer fell behind)", w->final_path,
            (long long)w->rows, (long long)x->dropped);
    else
        say(w, "traced %s (%lld rows)", w->final_path, (long long)w->rows);
}

static void *run(void *arg) {
    loadid_trace_worker_t *w = arg;
    pthread_setname_np(pthread_self(), "loadid-trace"); /* a prctl: see save_worker.c */
    for (;;) {
        /* quit is read before the ring: what was queued before it is written. */
        const bool quit = atomic_load(&w->quit);
        size_t e = atomic_load_explicit(&w->ended, memory_order_relaxed);
        const size_t sub = atomic_load_explicit(&w->submitted, memory_order_acquire);
        for (; e != sub; ++e) {
            const entry_t *x = &w->ring[e % LOADID_TRACE_WORKER_ROWS];
            if (x->kind == BEGIN)
                begin(w, x->utime);
            else if (x->kind == ROW)
                row(w, &x->e);
            else
                end(w, x);
            atomic_store_explicit(&w->ended, e + 1, memory_order_release);
        }
        if (quit) break;
        while (sem_wait(&w->wake) != 0 && errno == EINTR) {}
    }
    return NULL;
}

int loadid_trace_worker_start(const char *dir, loadid_trace_worker_t **out) {
    *out = NULL;
    loadid_trace_worker_t *w = calloc(1, sizeof *w);
    if (!w) return -ENOMEM;
    w->dir = dir;
    w->csv.fd = -1;
    w->ring = calloc(LOADID_TRACE_WORKER_ROWS, sizeof *w->ring);
    if (!w->ring || sem_init(&w->wake, 0, 0) != 0) {
        const int e = w->ring ? errno : ENOMEM;
        free(w->ring);
        free(w);
        return -e;
    }
    atomic_init(&w->submitted, 0);
    atomic_init(&w->ended, 0);
    atomic_init(&w->made, 0);
    atomic_init(&w->taken, 0);
    atomic_init(&w->quit, false);
    const int rc = loadid_background_thread_create(&w->thread, run, w, STACK_BYTES);
    if (rc != 0) {
        sem_destroy(&w->wake);
        free(w->ring);
        free(w);
        return -rc;
    }
    w->running = true;
    *out = w;
    return 0;
}

/* The next free entry when more than keep are free, else NULL. */
static entry_t *slot(loadid_trace_worker_t *w, size_t keep) {
    const size_t sub = atomic_load_explicit(&w->submitted, memory_order_relaxed);
    const size_t used = sub - atomic_load_explicit(&w->ended, memory_order_acquire);
    return LOADID_TRACE_WORKER_ROWS - used > keep ? &w->ring[sub % LOADID_TRACE_WORKER_ROWS] : NULL;
}

static void submit(loadid_trace_worker_t *w) {
    const size_t sub = atomic_load_explicit(&w->submitted, memory_order_relaxed);
    atomic_store_explicit(&w->submitted, sub + 1, memory_order_release);
    sem_post(&w->wake); /* an atomic increment, and a futex wake when the thread waits */
}

int loadid_trace_worker_begin(loadid_trace_worker_t *w, int64_t start_utime) {
    if (w->open) loadid_trace_worker_end(w, NULL);
    entry_t *x = slot(w, 0);
    if (!x) return -ENOBUFS;
    x->kind = BEGIN;
    x->utime = start_utime;
    submit(w);
    w->open = true;
    w->dropped = 0;
    return 0;
}

int loadid_trace_worker_row(loadid_trace_worker_t *w, const loadid_pipeline_estimate_t *e) {
    if (!w->open) return 0;
    entry_t *x = slot(w, RESERVED);
    if (!x) return ++w->dropped == 1 ? -ENOBUFS : 0;
    x->kind = ROW;
    x->e = *e;
    submit(w);
    return 0;
}

int loadid_trace_worker_end(loadid_trace_worker_t *w, const loadid_pipeline_estimate_t *final_est) {
    if (!w->open) return 0;
    entry_t *x = slot(w, 0);
    if (!x) return -ENOBUFS; /* still open: the next begin or end closes it */
    x->kind = final_est ? END : END_NONE;
    x->dropped = w->dropped;
    if (final_est) {
        snprintf(x->e.load_name, sizeof x->e.load_name, "%s", final_est->load_name);
        x->e.utime = final_est->utime;
    }
    submit(w);
    w->open = false;
    return 0;
}

int loadid_trace_worker_open(const loadid_trace_worker_t *w) {
    return w && w->open;
}

int loadid_trace_worker_collect(loadid_trace_worker_t *w, char *msg, size_t msglen) {
    const size_t t = atomic_load_explicit(&w->taken, memory_order_relaxed);
    if (t == atomic_load_explicit(&w->made, memory_order_acquire)) return 0;
    snprintf(msg, msglen, "%s", w->msgs[t % MSGS]);
    atomic_store_explicit(&w->taken, t + 1, memory_order_release);
    return 1;
}

void loadid_trace_worker_stop(loadid_trace_worker_t *w) {
    if (!w || !w->running) return;
    atomic_store(&w->quit, true);
    sem_post(&w->wake);
    pthread_join(w->thread, NULL);
    w->running = false;
}

void loadid_trace_worker_destroy(loadid_trace_worker_t *w) {
    if (!w) return;
    loadid_trace_worker_stop(w);
    if (w->csv.fd >= 0) {
        char err[4600];
        loadid_trace_csv_close(&w->csv, err, sizeof err);
    }
    sem_destroy(&w->wake);
    free(w->ring);
    free(w);
}
