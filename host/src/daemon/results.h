/*
 * The daemon's saved estimates (results.* keys; the file format is
 * saved_result.h): at start-up the one results.load names, restored into
 * the pipeline so that wrench_t flows at once; at DONE the primary
 * estimate into results.directory.
 */
#ifndef LOADID_RESULTS_H
#define LOADID_RESULTS_H

#include <stddef.h>

#include "loadid/config.h"
#include "loadid/pipeline.h"

/* results.load into the pipeline (state DONE). e receives the estimate
 * (for its load model). Returns 0, or a negative code with a one-line
 * reason in err. */
int loadid_results_restore(const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                           loadid_pipeline_estimate_t *e, char *err, size_t errlen);

/* A final estimate into results.directory (when set), without stdio;
 * logs where, or why not. */
void loadid_results_save(const loadid_config_t *cfg, const loadid_pipeline_estimate_t *e,
                         const loadid_pipeline_compensation_t *c);

#endif /* LOADID_RESULTS_H */
