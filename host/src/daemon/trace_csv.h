/*
 * The estimate trace of loadidd --offline --trace: every method's
 * intermediate estimates as CSV, for how an estimate converges (the study's
 * time to a usable estimate). One header, then one row per method per
 * publication (every publish_every-th sample while estimating) and, at DONE,
 * one per method with its final estimate (REFINED has only that one):
 *
 *   t_s,method,valid,samples,mass,com_x,com_y,com_z,ixx,ixy,ixz,iyy,iyz,izz,
 *   phi0,...,phi9,phi_std0,...,phi_std9,offset0,...,offset5,
 *   fx,fy,fz,tx,ty,tz,spec_x,spec_y,spec_z,omega_x,omega_y,omega_z,
 *   alpha_x,alpha_y,alpha_z,g_init_x,g_init_y,g_init_z,
 *   res_fx,res_fy,res_fz,res_tx,res_ty,res_tz
 *
 * t_s: the estimate's newest sample time minus START's [s]; mass, com and
 * the inertia about the COM (inertia_com, axes of S) and phi are the load's
 * (distal part removed), "nan" when !valid; phi_std one standard deviation
 * of each element of phi (loadidd asks the pipeline for it in every row,
 * loadid_pipeline_std_always; "inf" where the data do not determine it);
 * offset the estimated F/T offset (0 when zeroing).
 * From fx on, the row's newest sample (loadid_pipeline_trace_rows; "nan"
 * when the pipeline was not asked for it): its wrench as the estimators
 * take it less the distal part's (zeroed by eq. 7 when zeroing) [N, N m],
 * the motion of its regressor (a - g [m/s^2], omega [rad/s], alpha
 * [rad/s^2]), gravity in S at zeroing (0 with the offset model), and the
 * residual wrench this row's estimate leaves on it, f - A(a - g + g_init,
 * omega, alpha) phi - offset ("nan" when !valid), so it can be checked
 * from the row alone. Numbers %.9g. Written through a buffer of its own
 * with open and write, no stdio: nothing here allocates, so loadidd's trace
 * writer (trace_worker.h, results.trace) can use it after start-up too.
 */
#ifndef LOADID_TRACE_CSV_H
#define LOADID_TRACE_CSV_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/pipeline.h"

typedef struct {
    int fd; /* -1: closed */
    const char *path;
    int64_t start_us; /* START of the current run */
    int errnum;       /* the first failed write's errno */
    size_t len;       /* of buf, not yet written */
    char buf[32768];
} loadid_trace_csv_t;

/* Creates path (truncated; path must outlive t) and writes the header.
 * Returns 0, or -errno with
 * "cannot write PATH: reason" in err. */
int loadid_trace_csv_open(loadid_trace_csv_t *t, const char *path, char *err, size_t errlen);

/* START at utime: t_s counts from here. */
void loadid_trace_csv_start(loadid_trace_csv_t *t, int64_t utime);

/* One row (the pipeline's estimate sink). */
void loadid_trace_csv_row(loadid_trace_csv_t *t, const loadid_pipeline_estimate_t *e);

/* Closes the file. Returns 0, or -errno with "cannot write PATH: reason"
 * in err when a write failed. */
int loadid_trace_csv_close(loadid_trace_csv_t *t, char *err, size_t errlen);

#endif /* LOADID_TRACE_CSV_H */
