/*
 * The estimate trace of loadidd --offline --trace: every method's
 * intermediate estimates as CSV, for how an estimate converges (the study's
 * time to a usable estimate). One header, then one row per method per
 * publication (every publish_every-th sample while estimating) and, at DONE,
 * one per method with its final estimate (REFINED has only that one):
 *
 *   t_s,method,valid,samples,mass,com_x,com_y,com_z,ixx,ixy,ixz,iyy,iyz,izz,
 *   phi0,...,phi9,phi_std0,...,phi_std9
 *
 * t_s: the estimate's newest sample time minus START's [s]; mass, com and
 * the inertia about the COM (inertia_com, axes of S) and phi are the load's
 * (distal part removed), "nan" when !valid; phi_std one standard deviation
 * of each element of phi (loadidd asks the pipeline for it in every row,
 * loadid_pipeline_std_always; "inf" where the data do not determine it).
 * Numbers %.9g. Offline only: stdio, buffered.
 */
#ifndef LOADID_TRACE_CSV_H
#define LOADID_TRACE_CSV_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "loadid/pipeline.h"

typedef struct {
    FILE *out;
    const char *path;
    int64_t start_us;             /* START of the current run */
    int errnum;                   /* the first failed write's errno */
} loadid_trace_csv_t;

/* Creates path and writes the header. Returns 0, or -errno with
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
