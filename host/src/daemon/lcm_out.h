/*
 * The pipeline's outputs as LCM messages (docs/INTERFACE.md's types), the
 * one serialiser of each: estimate_t, load_model_t and wrench_t, encoded
 * by drivers/lcm_wire.h into the caller's buffer (no allocation).
 * status_t is status.c's. Each returns the encoded length, or a negative
 * LOADID_LCM_E* code.
 */
#ifndef LOADID_LCM_OUT_H
#define LOADID_LCM_OUT_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/lcm_wire.h"
#include "loadid/pipeline.h"

/* The largest of the three. */
#define LOADID_LCM_OUT_MAX                                                         \
    (LOADID_LCM_ESTIMATE_MAX > LOADID_LCM_LOAD_MODEL_MAX ? LOADID_LCM_ESTIMATE_MAX \
                                                         : LOADID_LCM_LOAD_MODEL_MAX)

/* estimate_t of one method's estimate. */
int loadid_lcm_out_estimate(const loadid_pipeline_estimate_t *e, uint8_t *buf, size_t cap);

/* load_model_t of a final estimate's model (e->has_model). */
int loadid_lcm_out_load_model(const loadid_pipeline_estimate_t *e, uint8_t *buf, size_t cap);

/* wrench_t: a compensated wrench. */
int loadid_lcm_out_wrench(int64_t utime, const double force[3], const double torque[3],
                          uint8_t *buf, size_t cap);

#endif /* LOADID_LCM_OUT_H */
