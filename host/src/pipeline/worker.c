/* A job thread with an eventfd for its end (worker.h). */
#define _GNU_SOURCE
#include "worker.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <stdint.h>
#include <stdlib.h>
#include <sys/eventfd.h>
#include <unistd.h>

enum { IDLE, SUBMITTED, ENDED, QUIT };

struct loadid_worker {
    void (*job)(void *ctx);
    void *ctx;
    int efd;
    pthread_t thread;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int state; /* under mu */
};

static void *run(void *arg) {
    loadid_worker_t *w = arg;
    pthread_mutex_lock(&w->mu);
    for (;;) {
        while (w->state != SUBMITTED && w->state != QUIT) pthread_cond_wait(&w->cv, &w->mu);
        if (w->state == QUIT) break;
        pthread_mutex_unlock(&w->mu);
        w->job(w->ctx);
        pthread_mutex_lock(&w->mu);
        if (w->state == SUBMITTED) w->state = ENDED;
        pthread_cond_broadcast(&w->cv);
        const uint64_t one = 1;
        (void)!write(w->efd, &one, sizeof one);
    }
    pthread_mutex_unlock(&w->mu);
    return NULL;
}

int loadid_worker_create(void (*job)(void *ctx), void *ctx, loadid_worker_t **out) {
    *out = NULL;
    loadid_worker_t *w = calloc(1, sizeof *w);
    if (!w) return -ENOMEM;
    w->job = job;
    w->ctx = ctx;
    w->efd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (w->efd < 0) {
        const int e = errno;
        free(w);
        return -e;
    }
    pthread_mutex_init(&w->mu, NULL);
    pthread_cond_init(&w->cv, NULL);
    /* Normal scheduling, whatever the creating thread has: a real-time
     * loop must preempt the job, not wait for it. */
    pthread_attr_t attr;
    pthread_attr_init(&attr);
    pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    pthread_attr_setschedpolicy(&attr, SCHED_OTHER);
    struct sched_param sp = {.sched_priority = 0};
    pthread_attr_setschedparam(&attr, &sp);
    const int rc = pthread_create(&w->thread, &attr, run, w);
    pthread_attr_destroy(&attr);
    if (rc != 0) {
        close(w->efd);
        pthread_mutex_destroy(&w->mu);
        pthread_cond_destroy(&w->cv);
        free(w);
        return -rc;
    }
    *out = w;
    return 0;
}

void loadid_worker_destroy(loadid_worker_t *w) {
    if (!w) return;
    pthread_mutex_lock(&w->mu);
    while (w->state == SUBMITTED) pthread_cond_wait(&w->cv, &w->mu);
    w->state = QUIT;
    pthread_cond_broadcast(&w->cv);
    pthread_mutex_unlock(&w->mu);
    pthread_join(w->thread, NULL);
    close(w->efd);
    pthread_mutex_destroy(&w->mu);
    pthread_cond_destroy(&w->cv);
    free(w);
}

int loadid_worker_fd(const loadid_worker_t *w) {
    return w->efd;
}

int loadid_worker_submit(loadid_worker_t *w) {
    pthread_mutex_lock(&w->mu);
    const int busy = w->state != IDLE;
    if (!busy) {
        w->state = SUBMITTED;
        pthread_cond_broadcast(&w->cv);
    }
    pthread_mutex_unlock(&w->mu);
    return busy ? -EBUSY : 0;
}

int loadid_worker_busy(loadid_worker_t *w) {
    pthread_mutex_lock(&w->mu);
    const int busy = w->state == SUBMITTED || w->state == ENDED;
    pthread_mutex_unlock(&w->mu);
    return busy;
}

/* Under mu: an ended job becomes collected. */
static int take_ended(loadid_worker_t *w) {
    if (w->state != ENDED) return 0;
    uint64_t v;
    (void)!read(w->efd, &v, sizeof v);
    w->state = IDLE;
    return 1;
}

int loadid_worker_collect(loadid_worker_t *w) {
    pthread_mutex_lock(&w->mu);
    const int ended = take_ended(w);
    pthread_mutex_unlock(&w->mu);
    return ended;
}

int loadid_worker_wait(loadid_worker_t *w) {
    pthread_mutex_lock(&w->mu);
    while (w->state == SUBMITTED) pthread_cond_wait(&w->cv, &w->mu);
    const int ended = take_ended(w);
    pthread_mutex_unlock(&w->mu);
    return ended;
}
