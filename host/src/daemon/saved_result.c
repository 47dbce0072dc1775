/* Saved estimates (saved_result.h). */
#define _POSIX_C_SOURCE 200809L
#include "saved_result.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "loadid/core.h"
#include "loadid/yaml_tree.h"

/* The writer allocates nothing (it runs on loadidd's save worker,
 * save_worker.h, inside the window where the daemon allocates nothing):
 * the document is formatted into a fixed buffer with snprintf and written
 * with open, write, fsync and rename, no stdio streams. */

typedef struct {
    char *p;
    size_t cap, n;
    int over; /* the document did not fit */
} doc_t;

__attribute__((format(printf, 2, 3))) static void add(doc_t *d, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    const int k = d->over ? 0 : vsnprintf(d->p + d->n, d->cap - d->n, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= d->cap - d->n)
        d->over = 1;
    else
        d->n += (size_t)k;
}

static void list(doc_t *d, const double *v, int n) {
    add(d, "[");
    for (int i = 0; i < n; ++i) {
        if (isfinite(v[i]))
            add(d, "%s%.17g", i ? ", " : "", v[i]);
        else /* YAML's spelling; only phi_std (not read back) can be infinite */
            add(d, "%s%s", i ? ", " : "", isnan(v[i]) ? ".nan" : v[i] > 0 ? ".inf" : "-.inf");
    }
    add(d, "]");
}

/* The load model (load_model_t): what a controller should use. */
static void format_model(doc_t *d, const loadid_pipeline_estimate_t *e) {
    add(d,
        "model:   # physically consistent; the URDF <inertial> below is this\n"
        "  identified: [");
    int first = 1;
    for (int bit = LOADID_IDENT_MASS; bit <= LOADID_IDENT_INERTIA; bit <<= 1)
        if (e->identified & bit) {
            add(d, "%s%s", first ? "" : ", ", loadid_ident_name(bit));
            first = 0;
        }
    add(d, "]\n");
    /* Why the others are not: for people (a comment, not read back). */
    for (int g = 0; g < 3; ++g) {
        char why[160];
        if (loadid_pipeline_why_not(e, g, why, sizeof why))
            add(d, "  # %s not identified: %s\n", loadid_ident_name(1 << g), why);
    }
    add(d, "  projected: %s\n  phi: ", e->projected ? "true" : "false");
    list(d, e->model_phi, 10);
    add(d, "\n  phi_std: ");
    list(d, e->phi_std, 10);
    add(d, "\n  mass: %.17g\n  com: ", e->model_mass);
    list(d, e->model_com, 3);
    add(d, "\n  inertia_com: ");
    list(d, e->model_inertia_com, 6);
    add(d, "\n");
}

static void format_doc(doc_t *d, const loadid_pipeline_estimate_t *e,
                       const loadid_pipeline_compensation_t *c) {
    add(d,
        "# A load estimated by loadidd (Kubus et al. 2008); inertia about the COM, axes\n"
        "# of the sensor frame S. compensation: what wrench_t needs after a restart.\n");
    add(d, "format: loadid-estimate-1\nmethod: %s\nload_name: \"",
        loadid_method_name((loadid_method_t)e->method));
    for (const char *s = e->load_name; *s; ++s)
        if (*s != '"' && *s != '\\' && (unsigned char)*s >= 0x20) add(d, "%c", *s);
    add(d, "\"\nutime: %lld\nsamples: %lld\nphi: ", (long long)e->utime, (long long)e->samples);
    list(d, e->phi, 10);
    add(d, "\noffset: ");
    list(d, e->offset, 6);
    add(d, "\nmass: %.17g\ncom: ", e->mass);
    list(d, e->com, 3);
    add(d, "\ninertia_com: ");
    list(d, e->inertia_com, 6);
    add(d, "\ncondition_number: %.17g\nphysically_consistent: %s\n", e->condition_number,
        e->physically_consistent ? "true" : "false");
    if (e->has_model) format_model(d, e);
    add(d, "compensation:\n  n_params: %d\n  phi_total: ", c->n_params);
    list(d, c->phi_total, c->n_params);
    add(d, "\n  zeroed: %s\n  y0: ", c->zeroed ? "true" : "false");
    list(d, c->y0, 6);
    add(d, "\n  g_init: ");
    list(d, c->g_init, 3);
    add(d, "\n  zero_regressor: ");
    list(d, c->zero_a, 60);
    /* URDF <inertial>: origin at the COM, inertia about it in S's axes; the
     * physically consistent model when there is one (a simulator or a
     * controller refuses an impossible inertia). */
    const double mass = e->has_model ? e->model_mass : e->mass;
    const double *com = e->has_model ? e->model_com : e->com;
    const double *in = e->has_model ? e->model_inertia_com : e->inertia_com;
    add(d,
        "\nurdf_inertial: |\n  <inertial>\n"
        "    <origin xyz=\"%.9g %.9g %.9g\" rpy=\"0 0 0\"/>\n    <mass value=\"%.9g\"/>\n"
        "    <inertia ixx=\"%.9g\" ixy=\"%.9g\" ixz=\"%.9g\" iyy=\"%.9g\" iyz=\"%.9g\" "
        "izz=\"%.9g\"/>\n  </inertial>\n",
        com[0], com[1], com[2], mass, in[0], in[1], in[2], in[3], in[4], in[5]);
}

/* path.tmp, synced, then renamed over path: a reader never sees half a
 * file, nor an empty one after a power loss (the rename may reach the disk
 * before the data otherwise). */
static int write_one(const char *path, const char *text, size_t n) {
    char tmp[4400];
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp", path) >= sizeof tmp) return -ENAMETOOLONG;
    const int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) return -errno;
    int rc = 0;
    for (size_t done = 0; done < n && !rc;) {
        const ssize_t w = write(fd, text + done, n - done);
        if (w < 0 && errno != EINTR)
            rc = -errno;
        else if (w > 0)
            done += (size_t)w;
    }
    if (!rc && fsync(fd) != 0) rc = -errno;
    if (close(fd) != 0 && !rc) rc = -errno;
    if (!rc && rename(tmp, path) != 0) rc = -errno;
    if (rc) unlink(tmp);
    return rc;
}

void loadid_saved_result_name(const char *dir, const char *load_name, int64_t utime,
                              const char *ext, char *out, size_t len) {
    char safe[LOADID_LOAD_NAME_MAX];
    size_t k = 0;
    for (const char *s = load_name; *s && k + 1 < sizeof safe; ++s)
        safe[k++] = (*s == '/' || *s == '.' || (unsigned char)*s < 0x20) ? '_' : *s;
    safe[k] = 0;
    snprintf(out, len, "%s/%s-%lld%s", dir, k ? safe : "load", (long long)utime, ext);
}

int loadid_saved_result_write(const char *dir, const loadid_pipeline_estimate_t *est,
                              const loadid_pipeline_compensation_t *comp, char *path,
                              size_t pathlen, char *err, size_t errlen) {
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) {
        int e = errno;
        snprintf(err, errlen, "%s: cannot create: %s", dir, strerror(e));
        return -e;
    }
    char name[4400], latest[4400];
    loadid_saved_result_name(dir, est->load_name, est->utime, ".yaml", name, sizeof name);
    snprintf(latest, sizeof latest, "%s/latest.yaml", dir);
    char text[8192]; /* about 5 kB: 144 numbers of up to 24 characters, the name, the text */
    doc_t d = {text, sizeof text, 0, 0};
    format_doc(&d, est, comp);
    int rc = d.over ? -EOVERFLOW : 0;
    if (rc == 0) rc = write_one(name, text, d.n);
    if (rc == 0) rc = write_one(latest, text, d.n);
    if (rc != 0)
        snprintf(err, errlen, "%s: cannot write: %s", name, strerror(-rc));
    else if (path)
        snprintf(path, pathlen, "%s", name);
    return rc;
}

static int need(int rc, loadid_yaml_node_t *map, const char *key) {
    if (rc == 0) return loadid_yaml_fail(map, "missing key '%s'", key);
    return rc < 0 ? rc : 0;
}

static int read_doc(loadid_yaml_doc_t *doc, loadid_pipeline_estimate_t *e,
                    loadid_pipeline_compensation_t *c) {
    loadid_yaml_node_t *root = loadid_yaml_root(doc), *comp;
    if (!root || loadid_yaml_kind(root) != LOADID_YAML_MAPPING)
        return root ? loadid_yaml_fail(root, "expected a mapping") : -EINVAL;
    char format[64], method[32];
    int rc, m;
    uint64_t samples = 0;
    memset(e, 0, sizeof *e);
    memset(c, 0, sizeof *c);
    if ((rc = need(loadid_yaml_get_string(root, "format", format, sizeof format), root, "format")))
        return rc;
    if (strcmp(format, "loadid-estimate-1") != 0)
        return loadid_yaml_fail(loadid_yaml_get(root, "format"), "unknown format '%s'", format);
    if ((rc = need(loadid_yaml_get_string(root, "method", method, sizeof method), root, "method")))
        return rc;
    if ((m = loadid_method_from_name(method)) < 0)
        return loadid_yaml_fail(loadid_yaml_get(root, "method"), "unknown method '%s'", method);
    e->method = m;
    uint64_t ut = 0;
    if ((rc = need(loadid_yaml_get_string(root, "load_name", e->load_name, sizeof e->load_name),
                   root, "load_name")) ||
        (rc = need(loadid_yaml_get_uint64(root, "utime", &ut), root, "utime")) ||
        (rc = need(loadid_yaml_get_uint64(root, "samples", &samples), root, "samples")) ||
        (rc = need(loadid_yaml_get_doubles(root, "phi", e->phi, 10), root, "phi")) ||
        (rc = need(loadid_yaml_get_doubles(root, "offset", e->offset, 6), root, "offset")) ||
        (rc = need(loadid_yaml_get_double(root, "mass", &e->mass), root, "mass")) ||
        (rc = need(loadid_yaml_get_doubles(root, "com", e->com, 3), root, "com")) ||
        (rc = need(loadid_yaml_get_doubles(root, "inertia_com", e->inertia_com, 6), root,
                   "inertia_com")) ||
        (rc = need(loadid_yaml_get_double(root, "condition_number", &e->condition_number), root,
                   "condition_number")) ||
        (rc = need(loadid_yaml_get_bool(root, "physically_consistent", &e->physically_consistent),
                   root, "physically_consistent")) ||
        (rc = need(loadid_yaml_get_mapping(root, "compensation", &comp), root, "compensation")) ||
        (rc = need(loadid_yaml_get_int(comp, "n_params", &c->n_params), comp, "n_params")))
        return rc;
    e->utime = (int64_t)ut;
    e->samples = (int64_t)samples;
    e->valid = 1;
    e->state = LOADID_STATE_DONE;
    if (c->n_params != LOADID_NPHI && c->n_params != LOADID_NPHI_OFFSET)
        return loadid_yaml_fail(loadid_yaml_get(comp, "n_params"), "must be 10 or 16");
    if ((rc = need(loadid_yaml_get_doubles(comp, "phi_total", c->phi_total, (size_t)c->n_params),
                   comp, "phi_total")) ||
        (rc = need(loadid_yaml_get_bool(comp, "zeroed", &c->zeroed), comp, "zeroed")) ||
        (rc = need(loadid_yaml_get_doubles(comp, "y0", c->y0, 6), comp, "y0")) ||
        (rc = need(loadid_yaml_get_doubles(comp, "g_init", c->g_init, 3), comp, "g_init")))
        return rc;
    /* Eq. (6) averaged at zeroing; a file without it was zeroed at rest,
     * where that is A(-g_init, 0, 0). */
    if ((rc = loadid_yaml_get_doubles(comp, "zero_regressor", c->zero_a, 60)) < 0) return rc;
    if (rc == 0) {
        loadid_real_t spec[3], zero[3] = {0, 0, 0}, a[60];
        for (int i = 0; i < 3; ++i) spec[i] = (loadid_real_t)-c->g_init[i];
        if (loadid_regressor(spec, zero, zero, a) != 0)
            return loadid_yaml_fail(loadid_yaml_get(comp, "g_init"), "not finite");
        for (int i = 0; i < 60; ++i) c->zero_a[i] = (double)a[i];
    }
    /* The model is read back for what it is used for (its values);
     * phi_std and identified are for people and other programs. */
    loadid_yaml_node_t *model = NULL;
    if ((rc = loadid_yaml_get_mapping(root, "model", &model)) < 0) return rc;
    if (model) {
        if ((rc = need(loadid_yaml_get_doubles(model, "phi", e->model_phi, 10), model, "phi")) ||
            (rc = need(loadid_yaml_get_double(model, "mass", &e->model_mass), model, "mass")) ||
            (rc = need(loadid_yaml_get_doubles(model, "com", e->model_com, 3), model, "com")) ||
            (rc = need(loadid_yaml_get_doubles(model, "inertia_com", e->model_inertia_com, 6),
                       model, "inertia_com")) ||
            (rc =
                 need(loadid_yaml_get_bool(model, "projected", &e->projected), model, "projected")))
            return rc;
        loadid_yaml_node_t *ids = loadid_yaml_get(model, "identified");
        for (size_t i = 0; ids && i < loadid_yaml_count(ids); ++i) {
            char w[16];
            const loadid_yaml_node_t *item = loadid_yaml_item(ids, i);
            if (loadid_yaml_as_string(item, w, sizeof w)) return -EINVAL;
            int bit = LOADID_IDENT_MASS;
            while (bit <= LOADID_IDENT_INERTIA && strcmp(w, loadid_ident_name(bit)) != 0) bit <<= 1;
            if (bit > LOADID_IDENT_INERTIA) return loadid_yaml_fail(item, "unknown group '%s'", w);
            e->identified |= bit;
        }
        loadid_yaml_get(model, "phi_std"); /* .inf where undetermined: not read back */
        for (int i = 0; i < 10; ++i) e->phi_std[i] = NAN;
        e->has_model = 1;
    }
    return 0;
}

int loadid_saved_result_read(const char *file, loadid_pipeline_estimate_t *est,
                             loadid_pipeline_compensation_t *comp, char *err, size_t errlen) {
    loadid_yaml_doc_t *doc = NULL;
    int rc = loadid_yaml_load_file(file, &doc, err, errlen);
    if (rc != 0) return rc;
    rc = read_doc(doc, est, comp);
    if (rc != 0) snprintf(err, errlen, "%s", loadid_yaml_error(doc));
    loadid_yaml_free(doc);
    return rc;
}
