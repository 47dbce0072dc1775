/*
 * background_thread.h: the daemon's helper threads (the save and the trace
 * workers) are started alike: normal scheduling and every signal blocked,
 * whatever the creating thread has, so that a real-time loop preempts the
 * disk's waits and SIGTERM goes to the loop's signalfd.
 */
#ifndef LOADID_BACKGROUND_THREAD_H
#define LOADID_BACKGROUND_THREAD_H

#include <pthread.h>
#include <stddef.h>

/* pthread_create of fn(arg) with SCHED_OTHER, stack_bytes of stack and
 * all signals blocked; 0 or pthread_create's positive error number. */
int loadid_background_thread_create(pthread_t *thread, void *(*fn)(void *), void *arg,
                                    size_t stack_bytes);

#endif
