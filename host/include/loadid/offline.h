/*
 * A recording through the pipeline (loadidd --offline, and the demo): the
 * events of can.log and lcm.log in time order, joint_state_t and
 * command_t decoded, commands acting at their utime, and the pipeline
 * finished at the last event's time.
 */
#ifndef LOADID_OFFLINE_H
#define LOADID_OFFLINE_H

#include <stddef.h>

#include "loadid/pipeline.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Returns 0, or a negative code with a one-line reason in err (the
 * recording cannot be read). *lcm_truncated (may be NULL) is set when
 * lcm.log ended in a damaged event. */
int loadid_offline_run(loadid_pipeline_t *p, const char *dir, int *lcm_truncated, char *err,
                       size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_OFFLINE_H */
