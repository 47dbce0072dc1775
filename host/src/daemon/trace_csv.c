/* The estimate trace of loadidd --offline --trace and results.trace
 * (trace_csv.h). */
#define _POSIX_C_SOURCE 200809L /* O_CLOEXEC */
#include "trace_csv.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "loadid/core.h"

/* A row is at most about 70 numbers of up to 16 characters. */
enum { ROW_MAX = 2048 };
_Static_assert(sizeof(((loadid_trace_csv_t *)0)->buf) > 2 * ROW_MAX, "room for a row");

static void flush(loadid_trace_csv_t *t) {
    size_t done = 0;
    while (done < t->len && !t->errnum) {
        const ssize_t n = write(t->fd, t->buf + done, t->len - done);
        if (n > 0)
            done += (size_t)n;
        else if (n < 0 && errno != EINTR)
            t->errnum = errno;
        else if (n == 0)
            t->errnum = EIO;
    }
    t->len = 0;
}

/* printf into the buffer, written out when a row might not fit. */
static void put(loadid_trace_csv_t *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void put(loadid_trace_csv_t *t, const char *fmt, ...) {
    if (sizeof t->buf - t->len < ROW_MAX) flush(t);
    va_list ap;
    va_start(ap, fmt);
    const int n = vsnprintf(t->buf + t->len, sizeof t->buf - t->len, fmt, ap);
    va_end(ap);
    if (n > 0) t->len += (size_t)n < sizeof t->buf - t->len ? (size_t)n : 0;
}

int loadid_trace_csv_open(loadid_trace_csv_t *t, const char *path, char *err, size_t errlen) {
    t->path = path;
    t->start_us = 0;
    t->errnum = 0;
    t->len = 0;
    t->fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (t->fd < 0) {
        const int e = errno;
        snprintf(err, errlen, "cannot write %s: %s", path, strerror(e));
        return -e;
    }
    put(t, "%s", "t_s,method,valid,samples,mass,com_x,com_y,com_z,ixx,ixy,ixz,iyy,iyz,izz");
    for (int i = 0; i < 10; ++i) put(t, ",phi%d", i);
    for (int i = 0; i < 10; ++i) put(t, ",phi_std%d", i);
    for (int i = 0; i < 6; ++i) put(t, ",offset%d", i);
    put(t, "%s",
        ",fx,fy,fz,tx,ty,tz,spec_x,spec_y,spec_z,omega_x,omega_y,omega_z,alpha_x,alpha_y,alpha_z"
        ",g_init_x,g_init_y,g_init_z,res_fx,res_fy,res_fz,res_tx,res_ty,res_tz\n");
    return 0;
}

void loadid_trace_csv_start(loadid_trace_csv_t *t, int64_t utime) {
    t->start_us = utime;
}

void loadid_trace_csv_row(loadid_trace_csv_t *t, const loadid_pipeline_estimate_t *e) {
    if (t->fd < 0) return;
    /* An estimate with no sample since START carries an older time. */
    const double t_s = e->utime >= t->start_us ? (double)(e->utime - t->start_us) / 1e6 : 0.0;
    double v[4 + 6 + 10 + 10];
    v[0] = e->mass;
    for (int i = 0; i < 3; ++i) v[1 + i] = e->com[i];
    for (int i = 0; i < 6; ++i) v[4 + i] = e->inertia_com[i];
    for (int i = 0; i < 10; ++i) v[10 + i] = e->phi[i];
    for (int i = 0; i < 10; ++i) v[20 + i] = e->phi_std[i];
    put(t, "%.9g,%s,%d,%lld", t_s, loadid_method_name((loadid_method_t)e->method), e->valid ? 1 : 0,
        (long long)e->samples);
    for (int i = 0; i < 30; ++i) put(t, ",%.9g", e->valid ? v[i] : NAN);
    for (int i = 0; i < 6; ++i) put(t, ",%.9g", e->valid ? e->offset[i] : NAN);
    /* The newest sample's row (loadid_pipeline_trace_rows) and the
     * residual this estimate leaves on it (NaN when !valid). */
    double r[6 + 9 + 3 + 6];
    memcpy(r, e->row_wrench, sizeof e->row_wrench);
    memcpy(r + 6, e->row_motion, sizeof e->row_motion);
    memcpy(r + 15, e->row_g_init, sizeof e->row_g_init);
    memcpy(r + 18, e->residual, sizeof e->residual);
    for (int i = 0; i < 24; ++i) put(t, ",%.9g", e->has_row ? r[i] : NAN);
    put(t, "\n");
}

int loadid_trace_csv_close(loadid_trace_csv_t *t, char *err, size_t errlen) {
    if (t->fd < 0) return 0;
    flush(t); /* a full disk shows here at the latest */
    if (close(t->fd) != 0 && !t->errnum) t->errnum = errno;
    t->fd = -1;
    if (t->errnum) {
        snprintf(err, errlen, "cannot write %s: %s", t->path, strerror(t->errnum));
        return -t->errnum;
    }
    return 0;
}
