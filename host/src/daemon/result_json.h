/* The result file of loadidd --offline (docs/INTERFACE.md): a JSON array, one
 * object per configured method. */
#ifndef LOADID_RESULT_JSON_H
#define LOADID_RESULT_JSON_H

#include <stdio.h>

#include "loadid/pipeline.h"

/* Writes the array; numbers that are not finite (a method without an
 * estimate, a phi_std the data do not bound) are written as null, and an
 * object without an estimate also carries "error": "<reason>". Besides the
 * contract's keys every object has "noise_scale" (the a-posteriori scale
 * of its covariance), "model" (mass, com, inertia_com of model_phi) and
 * "noise" (the levels the on-line weights used, and where each came from);
 * REFINED's also "refined" (its sources and levels; ref may be NULL).
 * Returns 0 or -EIO (a stdio error; errno says which). */
int loadid_result_json_write(FILE *out, const loadid_pipeline_estimate_t *est, int n,
                             const loadid_pipeline_status_t *st,
                             const loadid_refined_report_t *ref);

#endif /* LOADID_RESULT_JSON_H */
