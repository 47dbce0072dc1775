/*
 * The daemon's saved estimates (results.* keys; the file format is
 * saved_result.h): at start-up the one results.load names, restored into
 * the pipeline so that wrench_t flows at once; at DONE the primary
 * estimate into results.directory, handed to the save worker
 * (save_worker.h), so that the disk's waits stay off the loop.
 */
#ifndef LOADID_RESULTS_H
#define LOADID_RESULTS_H

#include <stddef.h>

#include "loadid/config.h"
#include "loadid/pipeline.h"
#include "save_worker.h"

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

#endif /* LOADID_RESULTS_H */
