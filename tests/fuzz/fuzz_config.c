/*
 * Fuzz target config: the YAML configuration loader (host/src/config/config.c on
 * host/src/config/yaml_tree.c and libyaml), from a buffer as if it were the file
 * /etc/loadid/loadid.yaml (loadid_config_load_string: nothing is read
 * from disk, relative paths resolve against /etc/loadid). Beyond the
 * sanitizers it checks what config.h and yaml_tree.h promise: a failure
 * leaves the configuration untouched and says why on one line without
 * control characters; a success gives a configuration whose parts pass
 * their own modules' checks, and warnings of one line each.
 */
#define _POSIX_C_SOURCE 200809L /* strnlen */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "fuzz_check.h"
#include "loadid/config.h"
#include "loadid/modbus_ft.h"

#define NAME "/etc/loadid/loadid.yaml"

static void check_line(const char *msg, size_t room) {
    const size_t n = strnlen(msg, room);
    FUZZ_CHECK(n < room);
    for (size_t i = 0; i < n; ++i) {
        FUZZ_CHECK((unsigned char)msg[i] >= 0x20 && msg[i] != 0x7f);
    }
}

static void on_warning(void *ctx, const char *msg) {
    int *count = ctx;
    ++*count;
    FUZZ_CHECK(strncmp(msg, NAME ":", strlen(NAME ":")) == 0);
    check_line(msg, 1 << 16);
}

static int finite_positive(const double *v, int n) {
    for (int i = 0; i < n; ++i) {
        if (!isfinite(v[i]) || !(v[i] > 0)) return 0;
    }
    return 1;
}

#define TERMINATED(field) FUZZ_CHECK(strnlen(field, sizeof(field)) < sizeof(field))

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size > 256 * 1024) {
        return 0; /* a configuration is a few KB; keeps runs fast */
    }
    static loadid_config_t cfg, before;
    memset(&cfg, 0x5A, sizeof cfg);
    memcpy(&before, &cfg, sizeof cfg);
    char err[512];
    int warnings = 0;
    const int rc = loadid_config_load_string(NAME, (const char *)data, size, &cfg, err, sizeof err,
                                             on_warning, &warnings);
    FUZZ_CHECK(rc == 0 || rc == -EINVAL || rc == -ENOMEM); /* config.h: nothing is read */
    check_line(err, sizeof err);
    if (rc != 0) {
        FUZZ_CHECK(err[0] != '\0');
        FUZZ_CHECK(memcmp(&cfg, &before, sizeof cfg) == 0);
        FUZZ_CHECK(warnings == 0);
        return 0;
    }
    FUZZ_CHECK(err[0] == '\0');
    TERMINATED(cfg.robot_urdf);
    TERMINATED(cfg.robot_base_link);
    TERMINATED(cfg.robot_sensor_link);
    TERMINATED(cfg.can_interface);
    TERMINATED(cfg.lcm_url);
    TERMINATED(cfg.lcm_channel_prefix);
    TERMINATED(cfg.modbus_device);
    FUZZ_CHECK(cfg.robot_urdf[0] == '/');
    FUZZ_CHECK(cfg.can_base_id + 4 <= 0x7FF);
    FUZZ_CHECK(finite_positive(cfg.jr3_fs_force, 3) && finite_positive(cfg.jr3_fs_moment, 3) &&
               finite_positive(cfg.jr3_fs_linear, 3) && finite_positive(cfg.jr3_fs_angular, 3));
    FUZZ_CHECK(cfg.num_methods >= 1 && cfg.num_methods <= LOADID_MAX_METHODS);
    FUZZ_CHECK(isfinite(cfg.duration_s) && cfg.duration_s > 0);
    FUZZ_CHECK(cfg.publish_every >= 1 && cfg.publish_every <= 1000000);
    FUZZ_CHECK(cfg.max_missing_share >= 0 && cfg.max_missing_share <= 1);
    for (int i = 0; i < 3; ++i) FUZZ_CHECK(isfinite(cfg.robot_gravity[i]));
    for (int i = 0; i < 10; ++i) FUZZ_CHECK(isfinite(cfg.distal_phi[i]));

    /* The Modbus part as loadid_modbus_ft_create will check it. */
    loadid_modbus_ft_config_t mb;
    loadid_modbus_ft_config_default(&mb);
    memcpy(mb.device, cfg.modbus_device, sizeof mb.device);
    mb.baud = cfg.modbus_baud;
    mb.parity = cfg.modbus_parity;
    mb.data_bits = cfg.modbus_data_bits;
    mb.stop_bits = cfg.modbus_stop_bits;
    mb.slave_id = cfg.modbus_slave_id;
    mb.timeout_ms = cfg.modbus_timeout_ms;
    memcpy(mb.fs_force, cfg.modbus_fs_force, sizeof mb.fs_force);
    memcpy(mb.fs_moment, cfg.modbus_fs_moment, sizeof mb.fs_moment);
    FUZZ_CHECK(loadid_modbus_ft_config_check(&mb) == 0);
    FUZZ_CHECK(cfg.modbus_rate_hz > 0 && cfg.modbus_rate_hz <= 1000);
    return 0;
}
