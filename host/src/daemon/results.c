/* The daemon's saved estimates (results.h). */
#include "results.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "log.h"
#include "saved_result.h"

int loadid_results_restore(const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                           loadid_pipeline_estimate_t *e, char *err, size_t errlen) {
    loadid_pipeline_compensation_t c;
    int rc = loadid_saved_result_read(cfg->results_load, e, &c, err, errlen);
    if (rc == 0 && loadid_pipeline_restore(pipe, e, &c) != 0) {
        snprintf(err, errlen,
                 "%s: not an estimate of this configuration (method, "
                 "estimation.offset_model)",
                 cfg->results_load);
        rc = -EINVAL;
    }
    return rc;
}

int loadid_results_start(const loadid_config_t *cfg, loadid_save_worker_t **saver) {
    *saver = NULL;
    if (!cfg->results_directory[0]) return 0;
    const int rc = loadid_save_worker_start(cfg->results_directory, saver);
    if (rc != 0) {
        loadidd_log("cannot start the save worker: %s", strerror(-rc));
        return 1;
    }
    return 0;
}

void loadid_results_save(const loadid_config_t *cfg, loadid_save_worker_t *saver,
                         const loadid_pipeline_estimate_t *e,
                         const loadid_pipeline_compensation_t *c) {
    if (saver && loadid_save_worker_submit(saver, e, c) != 0)
        loadidd_log("%s: estimate of %lld not saved: %d saves before it still wait for the disk",
                    cfg->results_directory, (long long)e->utime, LOADID_SAVE_WORKER_SLOTS);
}

void loadid_results_log(loadid_save_worker_t *saver) {
    char msg[4608];
    while (saver && loadid_save_worker_collect(saver, msg, sizeof msg) != 0) loadidd_log("%s", msg);
}

void loadid_results_stop(loadid_save_worker_t *saver) {
    loadid_save_worker_stop(saver); /* the saves submitted end first */
    loadid_results_log(saver);
    loadid_save_worker_destroy(saver);
}

int loadid_results_trace_start(const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                               loadid_trace_worker_t **tracer) {
    *tracer = NULL;
    if (!cfg->results_trace) return 0;
    loadid_pipeline_std_always(pipe, 1);
    loadid_pipeline_trace_rows(pipe, 1);
    const int rc = loadid_trace_worker_start(cfg->results_directory, tracer);
    if (rc != 0) {
        loadidd_log("cannot start the trace writer: %s", strerror(-rc));
        return 1;
    }
    return 0;
}

void loadid_results_trace_state(loadid_trace_worker_t *tracer, int64_t utime, int state) {
    if (!tracer) return;
    if (state == LOADID_STATE_ESTIMATING && loadid_trace_worker_begin(tracer, utime) != 0)
        loadidd_log("results.trace: the session of %lld not traced: %d entries wait for the disk",
                    (long long)utime, LOADID_TRACE_WORKER_ROWS);
    if (state == LOADID_STATE_IDLE || state == LOADID_STATE_FAILED)
        loadid_results_trace_end(tracer, NULL);
}

void loadid_results_trace_row(loadid_trace_worker_t *tracer, const loadid_pipeline_estimate_t *e) {
    if (tracer && loadid_trace_worker_row(tracer, e) != 0)
        loadidd_log("results.trace: %d rows wait for the disk: rows dropped (counted)",
                    LOADID_TRACE_WORKER_ROWS);
}

void loadid_results_trace_end(loadid_trace_worker_t *tracer,
                              const loadid_pipeline_estimate_t *final_est) {
    if (tracer && loadid_trace_worker_end(tracer, final_est) != 0)
        loadidd_log("results.trace: %d entries wait for the disk: the trace stays open",
                    LOADID_TRACE_WORKER_ROWS);
}

void loadid_results_trace_log(loadid_trace_worker_t *tracer) {
    char msg[4608];
    while (tracer && loadid_trace_worker_collect(tracer, msg, sizeof msg) != 0)
        loadidd_log("%s", msg);
}

void loadid_results_trace_stop(loadid_trace_worker_t *tracer) {
    if (!tracer) return;
    loadid_trace_worker_end(tracer, NULL);
    loadid_trace_worker_stop(tracer);
    loadid_results_trace_log(tracer);
    loadid_trace_worker_destroy(tracer);
}
