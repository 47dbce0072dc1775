/* The estimate trace of loadidd --offline --trace (trace_csv.h). */
#include "trace_csv.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "loadid/core.h"

int loadid_trace_csv_open(loadid_trace_csv_t *t, const char *path, char *err, size_t errlen) {
    memset(t, 0, sizeof *t);
    t->path = path;
    t->out = fopen(path, "w");
    if (!t->out) {
        const int e = errno;
        snprintf(err, errlen, "cannot write %s: %s", path, strerror(e));
        return -e;
    }
    fputs("t_s,method,valid,samples,mass,com_x,com_y,com_z,ixx,ixy,ixz,iyy,iyz,izz", t->out);
    for (int i = 0; i < 10; ++i) fprintf(t->out, ",phi%d", i);
    for (int i = 0; i < 10; ++i) fprintf(t->out, ",phi_std%d", i);
    for (int i = 0; i < 6; ++i) fprintf(t->out, ",offset%d", i);
    fputs(
        ",fx,fy,fz,tx,ty,tz,spec_x,spec_y,spec_z,omega_x,omega_y,omega_z,alpha_x,alpha_y,alpha_z"
        ",g_init_x,g_init_y,g_init_z,res_fx,res_fy,res_fz,res_tx,res_ty,res_tz",
        t->out);
    fputc('\n', t->out);
    return 0;
}

void loadid_trace_csv_start(loadid_trace_csv_t *t, int64_t utime) {
    t->start_us = utime;
}

void loadid_trace_csv_row(loadid_trace_csv_t *t, const loadid_pipeline_estimate_t *e) {
    if (!t->out) return;
    /* An estimate with no sample since START carries an older time. */
    const double t_s = e->utime >= t->start_us ? (double)(e->utime - t->start_us) / 1e6 : 0.0;
    double v[4 + 6 + 10 + 10];
    v[0] = e->mass;
    for (int i = 0; i < 3; ++i) v[1 + i] = e->com[i];
    for (int i = 0; i < 6; ++i) v[4 + i] = e->inertia_com[i];
    for (int i = 0; i < 10; ++i) v[10 + i] = e->phi[i];
    for (int i = 0; i < 10; ++i) v[20 + i] = e->phi_std[i];
    fprintf(t->out, "%.9g,%s,%d,%lld", t_s, loadid_method_name((loadid_method_t)e->method),
            e->valid ? 1 : 0, (long long)e->samples);
    for (int i = 0; i < 30; ++i) fprintf(t->out, ",%.9g", e->valid ? v[i] : NAN);
    for (int i = 0; i < 6; ++i) fprintf(t->out, ",%.9g", e->valid ? e->offset[i] : NAN);
    /* The newest sample's row (loadid_pipeline_trace_rows) and the
     * residual this estimate leaves on it (NaN when !valid). */
    double r[6 + 9 + 3 + 6];
    memcpy(r, e->row_wrench, sizeof e->row_wrench);
    memcpy(r + 6, e->row_motion, sizeof e->row_motion);
    memcpy(r + 15, e->row_g_init, sizeof e->row_g_init);
    memcpy(r + 18, e->residual, sizeof e->residual);
    for (int i = 0; i < 24; ++i) fprintf(t->out, ",%.9g", e->has_row ? r[i] : NAN);
    if (fputc('\n', t->out) == EOF && !t->errnum) t->errnum = errno ? errno : EIO;
}

int loadid_trace_csv_close(loadid_trace_csv_t *t, char *err, size_t errlen) {
    if (!t->out) return 0;
    const int bad = ferror(t->out);
    errno = 0;
    const int rc = fclose(t->out); /* flushes: a full disk shows here */
    const int e = t->errnum ? t->errnum : errno ? errno : EIO;
    t->out = NULL;
    if (bad || rc != 0) {
        snprintf(err, errlen, "cannot write %s: %s", t->path, strerror(e));
        return -e;
    }
    return 0;
}
