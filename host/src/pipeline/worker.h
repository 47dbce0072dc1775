/*
 * One job at a time on a thread of its own, for work that must not stall
 * the daemon's loop (REFINED at DONE: about 14 ms). The loop submits, goes
 * on serving its inputs, and learns of the end from an eventfd in its epoll
 * set. The thread is created at start-up with normal (SCHED_OTHER)
 * scheduling, so a real-time loop always preempts it; it allocates nothing
 * afterwards.
 */
#ifndef LOADID_WORKER_H
#define LOADID_WORKER_H

typedef struct loadid_worker loadid_worker_t;

/* job(ctx) runs on the thread for each submit. Returns 0 or -errno. */
int loadid_worker_create(void (*job)(void *ctx), void *ctx, loadid_worker_t **out);
/* Stops the thread (after a running job ends) and frees it; NULL is fine. */
void loadid_worker_destroy(loadid_worker_t *w);

/* Readable (an eventfd) when a job has ended; loadid_worker_collect reads it. */
int loadid_worker_fd(const loadid_worker_t *w);
/* Starts the job. -EBUSY while one is submitted and not yet collected. */
int loadid_worker_submit(loadid_worker_t *w);
/* 1 from submit until collect. */
int loadid_worker_busy(loadid_worker_t *w);
/* 1 when the submitted job has ended (it is then collected: busy is 0 and
 * what the job wrote is visible to the caller), 0 when none has. */
int loadid_worker_collect(loadid_worker_t *w);
/* Blocks until the submitted job has ended, then collects it; 0 when
 * nothing was submitted. */
int loadid_worker_wait(loadid_worker_t *w);

#endif /* LOADID_WORKER_H */
