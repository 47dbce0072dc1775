/* The thread that saves finished estimates, and its ring (save_worker.h). */
#define _GNU_SOURCE /* pthread_setname_np */
#include "save_worker.h"

#include "background_thread.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <semaphore.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "saved_result.h"

/* Enough for saved_result.c's buffers (about 22 kB) and snprintf's; the
 * default 8 MB would all be resident once loadidd locks its memory. */
#define STACK_BYTES (256 * 1024)

typedef struct {
    loadid_pipeline_estimate_t est;
    loadid_pipeline_compensation_t comp;
    int rc;         /* the thread's: 0 saved, else -errno */
    char msg[4608]; /* the thread's: "saved PATH", or the reason */
} slot_t;

/* A slot is the loop's until submitted passes it, the thread's until ended
 * does, the loop's again once collected does. */
struct loadid_save_worker {
    const char *dir;
    slot_t *slots;
    sem_t wake;
    pthread_t thread;
    bool running;
    size_t collected; /* the loop's alone */
    _Alignas(64) atomic_size_t submitted;
    _Alignas(64) atomic_size_t ended;
    atomic_bool quit;
};

static void save(const char *dir, slot_t *s) {
    char path[4400], err[4600];
    s->rc = loadid_saved_result_write(dir, &s->est, &s->comp, path, sizeof path, err, sizeof err);
    if (s->rc == 0)
        snprintf(s->msg, sizeof s->msg, "saved %s", path);
    else
        snprintf(s->msg, sizeof s->msg, "%s", err);
}

static void *run(void *arg) {
    loadid_save_worker_t *w = arg;
    /* Named from inside (a prctl): another thread's name is written
     * through /proc, which the systemd unit's ProtectSystem= may refuse. */
    pthread_setname_np(pthread_self(), "loadid-save");
    for (;;) {
        /* quit is read before the ring: what was submitted before quit was
         * set is saved before the thread ends. */
        const bool quit = atomic_load(&w->quit);
        size_t e = atomic_load_explicit(&w->ended, memory_order_relaxed);
        const size_t sub = atomic_load_explicit(&w->submitted, memory_order_acquire);
        for (; e != sub; ++e) {
            save(w->dir, &w->slots[e % LOADID_SAVE_WORKER_SLOTS]);
            atomic_store_explicit(&w->ended, e + 1, memory_order_release);
        }
        if (quit) break;
        while (sem_wait(&w->wake) != 0 && errno == EINTR) {}
    }
    return NULL;
}

int loadid_save_worker_start(const char *dir, loadid_save_worker_t **out) {
    *out = NULL;
    loadid_save_worker_t *w = calloc(1, sizeof *w);
    if (!w) return -ENOMEM;
    w->dir = dir;
    w->slots = calloc(LOADID_SAVE_WORKER_SLOTS, sizeof *w->slots);
    if (!w->slots || sem_init(&w->wake, 0, 0) != 0) {
        const int e = w->slots ? errno : ENOMEM;
        free(w->slots);
        free(w);
        return -e;
    }
    atomic_init(&w->submitted, 0);
    atomic_init(&w->ended, 0);
    atomic_init(&w->quit, false);
    const int rc = loadid_background_thread_create(&w->thread, run, w, STACK_BYTES);
    if (rc != 0) {
        sem_destroy(&w->wake);
        free(w->slots);
        free(w);
        return -rc;
    }
    w->running = true;
    *out = w;
    return 0;
}

int loadid_save_worker_submit(loadid_save_worker_t *w, const loadid_pipeline_estimate_t *est,
                              const loadid_pipeline_compensation_t *comp) {
    const size_t sub = atomic_load_explicit(&w->submitted, memory_order_relaxed);
    if (sub - w->collected >= LOADID_SAVE_WORKER_SLOTS) return -EBUSY;
    slot_t *s = &w->slots[sub % LOADID_SAVE_WORKER_SLOTS];
    s->est = *est;
    s->comp = *comp;
    atomic_store_explicit(&w->submitted, sub + 1, memory_order_release);
    sem_post(&w->wake); /* an atomic increment, and a futex wake when the thread waits */
    return 0;
}

int loadid_save_worker_collect(loadid_save_worker_t *w, char *msg, size_t msglen) {
    if (w->collected == atomic_load_explicit(&w->ended, memory_order_acquire)) return 0;
    const slot_t *s = &w->slots[w->collected % LOADID_SAVE_WORKER_SLOTS];
    snprintf(msg, msglen, "%s", s->msg);
    const int saved = s->rc == 0;
    ++w->collected;
    return saved ? 1 : -1;
}

void loadid_save_worker_stop(loadid_save_worker_t *w) {
    if (!w || !w->running) return;
    atomic_store(&w->quit, true);
    sem_post(&w->wake);
    pthread_join(w->thread, NULL);
    w->running = false;
}

void loadid_save_worker_destroy(loadid_save_worker_t *w) {
    if (!w) return;
    loadid_save_worker_stop(w);
    sem_destroy(&w->wake);
    free(w->slots);
    free(w);
}
