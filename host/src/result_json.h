/* The result file of loadidd --offline (DESIGN.md): a JSON array, one
 * object per configured method. */
#ifndef LOADID_RESULT_JSON_H
#define LOADID_RESULT_JSON_H

#include <stdio.h>

#include "loadid/pipeline.h"

/* Writes the array; numbers that are not finite (a method without an
 * estimate) are written as null, and such an object also carries
 * "error": "<reason>". Returns 0 or -1 (stdio error). */
int loadid_result_json_write(FILE *out, const loadid_pipeline_estimate_t *est, int n);

#endif /* LOADID_RESULT_JSON_H */
