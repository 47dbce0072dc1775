/* The daemon's saved estimates (results.h). */
#include "results.h"

#include <errno.h>
#include <stdio.h>

#include "log.h"
#include "saved_result.h"

int loadid_results_restore(const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                           loadid_pipeline_estimate_t *e, char *err, size_t errlen) {
    loadid_pipeline_compensation_t c;
    int rc = loadid_saved_result_read(cfg->results_load, e, &c, err, errlen);
    if (rc == 0 && loadid_pipeline_restore(pipe, e, &c) != 0) {
        snprintf(err, errlen, "%s: not an estimate of this configuration (method, "
                              "estimation.offset_model)", cfg->results_load);
        rc = -EINVAL;
    }
    return rc;
}

void loadid_results_save(const loadid_config_t *cfg, const loadid_pipeline_estimate_t *e,
                         const loadid_pipeline_compensation_t *c) {
    if (!cfg->results_directory[0]) return;
    char path[4400], err[4600];
    if (loadid_saved_result_write(cfg->results_directory, e, c, path, sizeof path, err,
                                  sizeof err) != 0)
        loadidd_log("%s", err);
    else
        loadidd_log("saved %s", path);
}
