/*
 * The daemon's saved estimates (results.* keys; the file format is
 * saved_result.h): at start-up the one results.load names, restored into
 * the pipeline so that wrench_t flows at once; at DONE the primary
 * estimate into results.directory, handed to the save worker
 * (save_worker.h), so that the disk's waits stay off the loop; with
 * results.trace every estimate of the session too, to the trace writer
 * (trace_worker.h).
 */
#ifndef LOADID_RESULTS_H
#define LOADID_RESULTS_H

#include <stddef.h>

#include "loadid/config.h"
#include "loadid/pipeline.h"
#include "save_worker.h"
#include "trace_worker.h"

/* results.load into the pipeline (state DONE). e receives the estimate
 * (for its load model). Returns 0, or a negative code with a one-line
 * reason in err. */
int loadid_results_restore(const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                           loadid_pipeline_estimate_t *e, char *err, size_t errlen);

/* The save worker for results.directory, *saver NULL when it is not set.
 * Start-up only (it allocates). Returns 0, or 1 after logging why not. */
int loadid_results_start(const loadid_config_t *cfg, loadid_save_worker_t **saver);

/* A final estimate handed to the saver (NULL: not saving): returns at
 * once, whatever the disk does; logs when every slot still waits for it.
 * No allocation, no lock, no file-system call. */
void loadid_results_save(const loadid_config_t *cfg, loadid_save_worker_t *saver,
                         const loadid_pipeline_estimate_t *e,
                         const loadid_pipeline_compensation_t *c);

/* Logs what the saver did since the last call: "saved PATH", or why not.
 * No allocation, no lock; one atomic load when nothing ended. */
void loadid_results_log(loadid_save_worker_t *saver);

/* At the stop: lets the saves submitted end, logs them, frees the saver.
 * NULL is fine. */
void loadid_results_stop(loadid_save_worker_t *saver);

/* results.trace: asks the pipeline for the trace's columns in every
 * estimate (phi_std, the newest sample's row) and starts the trace writer;
 * *tracer NULL when results.trace is off. Start-up only. Returns 0, or 1
 * after logging why not. */
int loadid_results_trace_start(const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                               loadid_trace_worker_t **tracer);

/* The loop's side of the trace (tracer NULL: nothing): a state change
 * (ESTIMATING begins a session, IDLE and FAILED end it), a published
 * estimate, and the session's end at its final estimate (NULL: none),
 * once REFINED's, the last row, has come. Log a dropped row (once a
 * session) or entry. No allocation, no lock, no file-system call. */
void loadid_results_trace_state(loadid_trace_worker_t *tracer, int64_t utime, int state);
void loadid_results_trace_row(loadid_trace_worker_t *tracer, const loadid_pipeline_estimate_t *e);
void loadid_results_trace_end(loadid_trace_worker_t *tracer,
                              const loadid_pipeline_estimate_t *final_est);

/* Logs what the trace writer did since the last call ("traced PATH (N
 * rows)", or why not). NULL is fine. */
void loadid_results_trace_log(loadid_trace_worker_t *tracer);

/* At the stop: ends a session still open, lets the writer finish, logs,
 * frees. NULL is fine. */
void loadid_results_trace_stop(loadid_trace_worker_t *tracer);

#endif /* LOADID_RESULTS_H */
