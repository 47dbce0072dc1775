/*
 * background_thread.c: a helper thread of the daemon, started with normal
 * scheduling and every signal blocked (background_thread.h says why).
 */
#define _POSIX_C_SOURCE 200809L /* pthread_sigmask, sigfillset */

#include "background_thread.h"

#include <sched.h>
#include <signal.h>

int loadid_background_thread_create(pthread_t *thread, void *(*fn)(void *), void *arg,
                                    size_t stack_bytes) {
    pthread_attr_t attr;
    pthread_attr_init(&attr);
    pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    pthread_attr_setschedpolicy(&attr, SCHED_OTHER);
    struct sched_param sp = {.sched_priority = 0};
    pthread_attr_setschedparam(&attr, &sp);
    pthread_attr_setstacksize(&attr, stack_bytes);
    sigset_t all, old;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    const int rc = pthread_create(thread, &attr, fn, arg);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    pthread_attr_destroy(&attr);
    return rc;
}
