/* Writing trajectory files and setpoint samples (traj_file.h). */
#include "traj_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "loadid/yaml_tree.h"

/* %.17g round-trips a double; YAML spells infinity .inf. */
static void number(FILE *out, double v) {
    if (isinf(v))
        fputs(v > 0 ? ".inf" : "-.inf", out);
    else
        fprintf(out, "%.17g", v);
}

static void list(FILE *out, const double *v, int n) {
    fputc('[', out);
    for (int i = 0; i < n; ++i) {
        if (i) fputs(", ", out);
        number(out, v[i]);
    }
    fputc(']', out);
}

static void key_list(FILE *out, const char *indent, const char *key, const double *v, int n) {
    fprintf(out, "%s%s: ", indent, key);
    list(out, v, n);
    fputc('\n', out);
}

int loadid_traj_file_write(FILE *out, const loadid_fourier_traj_t *tr,
                           const loadid_traj_limits_t *limits,
                           const loadid_traj_file_info_t *info) {
    const int n = tr->num_joints;
    fprintf(out, "# Excitation trajectory by loadid-traj (paper sec. III, eqs. 10-15).\n");
    fprintf(out, "format: loadid-trajectory-1\n");
    fprintf(out, "robot:\n  urdf: \"%s\"\n  base_link: \"%s\"\n  sensor_link: \"%s\"\n  joints: [",
            info->urdf, info->base_link, info->sensor_link);
    for (int i = 0; i < n; ++i)
        fprintf(out, "%s\"%s\"", i ? ", " : "", info->chain->joints[i].name);
    fprintf(out, "]\n");
    fprintf(out, "base_frequency: %.17g\nharmonics: %d\nactive_s: %.17g\nfade_s: %.17g\n",
            tr->base_frequency, tr->harmonics, tr->active_s, tr->fade_s);
    fprintf(out, "fade_polynomial: \"%s\"\n", LOADID_TRAJ_FADE_POLYNOMIAL);
    key_list(out, "", "q0", tr->q0, n);
    for (int c = 0; c < 2; ++c) {
        fprintf(out, "%s:\n", c ? "delta" : "rho");
        for (int i = 0; i < n; ++i) {
            fputs("  - ", out);
            list(out, c ? tr->delta[i] : tr->rho[i], tr->harmonics);
            fputc('\n', out);
        }
    }
    fprintf(out, "limits:\n");
    key_list(out, "  ", "position_lower", limits->lower, n);
    key_list(out, "  ", "position_upper", limits->upper, n);
    key_list(out, "  ", "velocity", limits->velocity, n);
    key_list(out, "  ", "acceleration", limits->acceleration, n);
    key_list(out, "  ", "workspace_min", limits->ws_min, 3);
    key_list(out, "  ", "workspace_max", limits->ws_max, 3);
    fprintf(out, "  floor_z: ");
    number(out, limits->floor_z);
    fprintf(out,
            "\nkappa_design: %.17g\nkappa_upsilon: %.17g\nkappa_set: %.17g\n"
            "kappa_monte_carlo: %.17g\n",
            info->kappa_design, info->kappa_design * info->kappa_design, info->kappa_set,
            info->kappa_monte_carlo);
    fprintf(out, "seed: %llu\n", (unsigned long long)info->seed);
    return ferror(out) ? -1 : 0;
}

int loadid_traj_setpoints_write(FILE *out, const loadid_fourier_traj_t *tr, double rate_hz) {
    const int n = tr->num_joints;
    fputs("t", out);
    const char *names[3] = {"q", "qd", "qdd"};
    for (int d = 0; d < 3; ++d)
        for (int i = 0; i < n; ++i) fprintf(out, ",%s%d", names[d], i + 1);
    fputc('\n', out);
    const long samples = lround(loadid_traj_duration(tr) * rate_hz);
    for (long k = 0; k <= samples; ++k) {
        const double t = k / rate_hz;
        double v[3][LOADID_MAX_JOINTS];
        loadid_traj_eval(tr, t, v[0], v[1], v[2], NULL);
        fprintf(out, "%.6f", t);
        for (int d = 0; d < 3; ++d)
            for (int i = 0; i < n; ++i) fprintf(out, ",%.17g", v[d][i]);
        fputc('\n', out);
    }
    return ferror(out) ? -1 : 0;
}

/* One row per joint of `harmonics` numbers: rho or delta. */
static int read_rows(loadid_yaml_node_t *root, const char *key, int n, int h,
                     double rows[][LOADID_TRAJ_MAX_HARMONICS]) {
    loadid_yaml_node_t *seq;
    int rc = loadid_yaml_get_sequence(root, key, &seq);
    if (rc == 0) return loadid_yaml_fail(root, "missing key '%s'", key);
    if (rc < 0) return rc;
    if ((int)loadid_yaml_count(seq) != n)
        return loadid_yaml_fail(seq, "expected %d rows (one per joint), got %zu", n,
                                loadid_yaml_count(seq));
    for (int i = 0; i < n; ++i) {
        rc = loadid_yaml_as_doubles(loadid_yaml_item(seq, (size_t)i), rows[i], (size_t)h, (size_t)h,
                                    NULL);
        if (rc < 0) return rc;
    }
    return 0;
}

static int required(int rc, loadid_yaml_node_t *root, const char *key) {
    if (rc == 0) return loadid_yaml_fail(root, "missing key '%s'", key);
    return rc < 0 ? rc : 0;
}

static int read_doc(loadid_yaml_doc_t *doc, loadid_fourier_traj_t *tr,
                    char names[][LOADID_NAME_MAX], double *kappa_design) {
    loadid_yaml_node_t *root = loadid_yaml_root(doc);
    if (!root || loadid_yaml_kind(root) != LOADID_YAML_MAPPING)
        return root ? loadid_yaml_fail(root, "expected a mapping") : -EINVAL;
    char format[64];
    int rc =
        required(loadid_yaml_get_string(root, "format", format, sizeof format), root, "format");
    if (rc) return rc;
    if (strcmp(format, "loadid-trajectory-1") != 0)
        return loadid_yaml_fail(loadid_yaml_get(root, "format"),
                                "unknown format '%s' (expected loadid-trajectory-1)", format);
    memset(tr, 0, sizeof *tr);
    double q0[LOADID_MAX_JOINTS];
    size_t n = 0;
    if ((rc = required(loadid_yaml_get_double_seq(root, "q0", q0, 1, LOADID_MAX_JOINTS, &n), root,
                       "q0")))
        return rc;
    tr->num_joints = (int)n;
    memcpy(tr->q0, q0, sizeof q0);
    if ((rc = required(loadid_yaml_get_double(root, "base_frequency", &tr->base_frequency), root,
                       "base_frequency")) ||
        (rc =
             required(loadid_yaml_get_int(root, "harmonics", &tr->harmonics), root, "harmonics")) ||
        (rc =
             required(loadid_yaml_get_double(root, "active_s", &tr->active_s), root, "active_s")) ||
        (rc = required(loadid_yaml_get_double(root, "fade_s", &tr->fade_s), root, "fade_s")))
        return rc;
    /* A file designed with another fade had its limits checked on a
     * different motion: design it again rather than move the robot. */
    char fade[64];
    if ((rc = loadid_yaml_get_string(root, "fade_polynomial", fade, sizeof fade)) < 0) return rc;
    if (rc == 1 && strcmp(fade, LOADID_TRAJ_FADE_POLYNOMIAL) != 0)
        return loadid_yaml_fail(loadid_yaml_get(root, "fade_polynomial"),
                                "'%s' is not this build's fade (" LOADID_TRAJ_FADE_POLYNOMIAL
                                "): design the trajectory again with loadid-traj",
                                fade);
    if (tr->harmonics < 1 || tr->harmonics > LOADID_TRAJ_MAX_HARMONICS)
        return loadid_yaml_fail(loadid_yaml_get(root, "harmonics"), "must be 1..%d",
                                LOADID_TRAJ_MAX_HARMONICS);
    if (!(tr->base_frequency > 0) || !(tr->active_s > 0) || !(tr->fade_s >= 0))
        return loadid_yaml_fail(root, "base_frequency and active_s must be > 0, fade_s >= 0");
    if ((rc = read_rows(root, "rho", tr->num_joints, tr->harmonics, tr->rho)) ||
        (rc = read_rows(root, "delta", tr->num_joints, tr->harmonics, tr->delta)))
        return rc;
    if (kappa_design) {
        *kappa_design = NAN;
        if ((rc = loadid_yaml_get_double(root, "kappa_design", kappa_design)) < 0) return rc;
    }
    if (names) {
        loadid_yaml_node_t *robot, *joints;
        if ((rc = required(loadid_yaml_get_mapping(root, "robot", &robot), root, "robot")) ||
            (rc = required(loadid_yaml_get_sequence(robot, "joints", &joints), robot, "joints")))
            return rc;
        if (loadid_yaml_count(joints) != n)
            return loadid_yaml_fail(joints, "expected %zu joint names (as q0), got %zu", n,
                                    loadid_yaml_count(joints));
        for (size_t i = 0; i < n; ++i)
            if ((rc =
                     loadid_yaml_as_string(loadid_yaml_item(joints, i), names[i], LOADID_NAME_MAX)))
                return rc;
    }
    return 0;
}

int loadid_traj_file_read(const char *path, loadid_fourier_traj_t *tr,
                          char names[][LOADID_NAME_MAX], double *kappa_design, char *err,
                          size_t errlen) {
    loadid_yaml_doc_t *doc = NULL;
    int rc = loadid_yaml_load_file(path, &doc, err, errlen);
    if (rc != 0) return rc;
    loadid_fourier_traj_t tmp;
    rc = read_doc(doc, &tmp, names, kappa_design);
    if (rc != 0) {
        if (err && errlen) snprintf(err, errlen, "%s", loadid_yaml_error(doc));
    } else {
        *tr = tmp;
    }
    loadid_yaml_free(doc);
    return rc;
}
