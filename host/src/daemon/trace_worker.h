/*
 * results.trace: every estimate a live session publishes, written as the
 * trace CSV of loadidd --offline --trace (trace_csv.h) beside the saved
 * result, for `loadid plot RESULT_DIR`. The rows come at up to a few
 * thousand a second and a write can wait for the disk, which a 1 kHz loop
 * cannot, so a thread of its own writes them, as save_worker.h saves: the
 * loop copies each row into a ring of LOADID_TRACE_WORKER_ROWS entries
 * allocated at start (single producer, single consumer, C11 atomics, a
 * semaphore post; no lock, no allocation, no file-system call on the
 * loop). A full ring drops the row, never waits: the drops are counted.
 * The thread writes <dir>/.trace-<START utime>.csv.tmp while the session
 * runs and at its end renames it to the saved result's name with
 * .trace.csv for .yaml (<load_name>-<final utime>.trace.csv, beside
 * <load_name>-<final utime>.yaml), or <load_name>-<START utime>.trace.csv
 * for a session that ended without a final estimate (RESET, FAILED, the
 * stop). Nothing in it allocates after start either (trace_csv.h writes
 * through a buffer of its own). SCHED_OTHER, every signal blocked.
 */
#ifndef LOADID_TRACE_WORKER_H
#define LOADID_TRACE_WORKER_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/pipeline.h"

/* 4096 rows: 1.3 s of three on-line methods publishing every sample at
 * 1 kHz, the thread's slack for a slow write (about 4.5 MB). */
#define LOADID_TRACE_WORKER_ROWS 4096

typedef struct loadid_trace_worker loadid_trace_worker_t;

/* Starts the thread that writes into dir (the string must outlive the
 * worker). Allocates everything here. Returns 0 or -errno. */
int loadid_trace_worker_start(const char *dir, loadid_trace_worker_t **out);

/* The loop's calls (one thread only; none waits, allocates or touches the
 * file system). A session: begin at ESTIMATING (START's utime: the rows'
 * t_s count from it), a row for every estimate published, end when the
 * session is over with its final estimate (its load_name and utime name
 * the file; NULL: none came). begin ends a session still open; row and end
 * do nothing outside one. begin and end return 0, or -ENOBUFS when the
 * ring was full (begin: no session; end: the session stays open, for the
 * next begin or end). row returns -ENOBUFS for the session's first row the
 * full ring dropped, else 0: the drops are counted, and end's message
 * gives their number. */
int loadid_trace_worker_begin(loadid_trace_worker_t *w, int64_t start_utime);
int loadid_trace_worker_row(loadid_trace_worker_t *w, const loadid_pipeline_estimate_t *e);
int loadid_trace_worker_end(loadid_trace_worker_t *w, const loadid_pipeline_estimate_t *final_est);
/* 1 between begin and end. */
int loadid_trace_worker_open(const loadid_trace_worker_t *w);

/* What the thread finished since the last call: 1 with msg "traced PATH
 * (N rows)" or why it could not, 0 none. The loop logs it. */
int loadid_trace_worker_collect(loadid_trace_worker_t *w, char *msg, size_t msglen);

/* Lets the entries queued be written, then ends the thread. NULL is fine. */
void loadid_trace_worker_stop(loadid_trace_worker_t *w);

/* Stops (if not yet) and frees. NULL is fine. */
void loadid_trace_worker_destroy(loadid_trace_worker_t *w);

#endif /* LOADID_TRACE_WORKER_H */
