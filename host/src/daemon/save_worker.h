/*
 * Saving finished estimates (saved_result.h) off the daemon's loop. Open,
 * write, fsync and rename wait for the disk, milliseconds and on a busy or
 * failing one far more, which a 1 kHz loop cannot give; so one thread of
 * its own writes them. The loop hands each estimate over in a ring of
 * LOADID_SAVE_WORKER_SLOTS slots allocated at start (single producer,
 * single consumer, C11 atomics: the loop takes no lock, allocates nothing
 * and makes no file-system call) and wakes the thread with a semaphore
 * post; the outcome comes back in the same slot for the loop to collect
 * and log. The thread runs SCHED_OTHER with every signal blocked, so a
 * real-time loop preempts it and signals reach the loop's signalfd only.
 */
#ifndef LOADID_SAVE_WORKER_H
#define LOADID_SAVE_WORKER_H

#include <stddef.h>

#include "loadid/pipeline.h"

/* Saves submitted and not yet collected: one a session, so 4 leave room
 * for a disk stalled over several sessions. */
#define LOADID_SAVE_WORKER_SLOTS 4

typedef struct loadid_save_worker loadid_save_worker_t;

/* Starts the thread that saves into dir (results.directory; the string
 * must outlive the worker). Allocates everything here. Returns 0 or
 * -errno. */
int loadid_save_worker_start(const char *dir, loadid_save_worker_t **out);

/* Copies est and comp into a free slot and wakes the thread; returns at
 * once, whatever the disk does. 0, or -EBUSY when every slot holds a save
 * not yet collected (nothing is saved then). From one thread only. */
int loadid_save_worker_submit(loadid_save_worker_t *w, const loadid_pipeline_estimate_t *est,
                              const loadid_pipeline_compensation_t *comp);

/* The oldest ended save not yet collected: 1 saved (msg "saved PATH"),
 * -1 failed (msg the reason, "FILE: cannot write: ..."), 0 none ended.
 * No lock, no allocation: one atomic load when none has. From the
 * thread that submits. */
int loadid_save_worker_collect(loadid_save_worker_t *w, char *msg, size_t msglen);

/* Lets the saves submitted end, then ends the thread; collect still gives
 * their outcomes afterwards. NULL is fine. */
void loadid_save_worker_stop(loadid_save_worker_t *w);

/* Stops (if not yet) and frees. NULL is fine. */
void loadid_save_worker_destroy(loadid_save_worker_t *w);

#endif /* LOADID_SAVE_WORKER_H */
