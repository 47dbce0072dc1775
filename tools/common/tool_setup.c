/* Configuration and robot for the tools (tool_setup.h). */
#include "tool_setup.h"

#include <stdio.h>
#include <string.h>

#include "loadid/urdf.h"

static void warn(void *ctx, const char *msg) { fprintf(stderr, "%s: warning: %s\n", (const char *)ctx, msg); }

int loadid_tool_setup(const char *prog, const char *config_path, loadid_config_t *cfg,
                      loadid_chain_t *chain) {
    char err[1024];
    loadid_config_default(cfg);
    if (config_path &&
        loadid_config_load(config_path, cfg, err, sizeof err, warn, (void *)prog) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    if (loadid_urdf_load_file(cfg->robot_urdf, cfg->robot_base_link, cfg->robot_sensor_link, chain,
                              err, sizeof err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    return 0;
}

void loadid_tool_jr3_config(const loadid_config_t *cfg, loadid_jr3_config_t *jr3) {
    memset(jr3, 0, sizeof *jr3);
    jr3->base_id = cfg->can_base_id;
    memcpy(jr3->full_scale[LOADID_JR3_FORCE], cfg->jr3_fs_force, sizeof cfg->jr3_fs_force);
    memcpy(jr3->full_scale[LOADID_JR3_MOMENT], cfg->jr3_fs_moment, sizeof cfg->jr3_fs_moment);
    memcpy(jr3->full_scale[LOADID_JR3_LINEAR], cfg->jr3_fs_linear, sizeof cfg->jr3_fs_linear);
    memcpy(jr3->full_scale[LOADID_JR3_ANGULAR], cfg->jr3_fs_angular, sizeof cfg->jr3_fs_angular);
}
