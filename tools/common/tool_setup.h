/*
 * What every loadid tool does first: read the configuration file (or take
 * the defaults) and the robot's chain from its URDF, reporting any problem
 * as one line "PROG: reason" on stderr; and the JR3 codec's configuration
 * from the configuration's can.* and jr3.* keys.
 */
#ifndef LOADID_TOOL_SETUP_H
#define LOADID_TOOL_SETUP_H

#include "loadid/chain.h"
#include "loadid/config.h"
#include "loadid/jr3.h"

#ifdef __cplusplus
extern "C" {
#endif

/* cfg from config_path (NULL: the defaults; unknown keys are printed as
 * warnings), then chain from cfg's robot.* keys. Returns 0, or 1 after
 * printing why. */
int loadid_tool_setup(const char *prog, const char *config_path, loadid_config_t *cfg,
                      loadid_chain_t *chain);

/* The JR3 codec's configuration: can.base_id and jr3.full_scale.*. */
void loadid_tool_jr3_config(const loadid_config_t *cfg, loadid_jr3_config_t *jr3);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_TOOL_SETUP_H */
