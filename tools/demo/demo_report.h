/*
 * What loadid-demo found, and how it says it: per signal source, seed and
 * method the estimate and its errors against the truth; the table of
 * eq. (37) errors (median over the seeds), a one-line verdict per method
 * against the truth and against the paper's figures, and runs.csv for the
 * plots and demo_check.py. Printing only; the runs are loadid_demo.c's.
 */
#ifndef LOADID_DEMO_REPORT_H
#define LOADID_DEMO_REPORT_H

#include <stdint.h>
#include <stdio.h>

#include "loadid/pipeline.h"

#define DEMO_MAX_SEEDS 64
#define DEMO_MAX_SOURCES 4
#define DEMO_METHODS 6

/* One method's final estimate of one run, with its errors. */
typedef struct {
    int valid;
    char why[256]; /* when !valid */
    int64_t samples;
    double phi[10];          /* the load (distal part removed) */
    double err[10];          /* eq. (37): |x - x_true| / |x_true| [%] */
    double mass_pct;         /* |m - m_true| / m_true [%] */
    double com_mm;           /* |c - c_true| [mm] */
    double inertia_pct;      /* ||I_C - I_C,true||_F / ||I_C,true||_F [%] */
    double condition_number; /* dimensionless */
    double sigma_min;        /* TLS methods, dimensionless (noise-weighted) */
    int consistent;
    int identified;             /* LOADID_IDENT_* bits of its load model */
    char not_identified[3][96]; /* mass, COM, inertia: why not ("" when it is) */
} demo_est_t;

/* One signal source's runs. */
typedef struct {
    int source; /* loadid_signal_source_t */
    const char *name;
    demo_est_t est[DEMO_MAX_SEEDS][DEMO_METHODS];
    double window_wall_s[DEMO_MAX_SEEDS]; /* START to DONE */
    double window_cpu_s[DEMO_MAX_SEEDS];
    double run_wall_s[DEMO_MAX_SEEDS];      /* the whole recording, files read */
    int64_t window_samples[DEMO_MAX_SEEDS]; /* samples estimated */
    int64_t run_samples[DEMO_MAX_SEEDS];    /* JR3 samples in the recording */
    int traced[DEMO_MAX_SEEDS];             /* the run wrote a trace (slower) */
} demo_source_t;

typedef struct {
    int methods[DEMO_METHODS]; /* loadid_method_t, in the table's order */
    double truth[10];
    uint64_t first_seed;
    int seeds;
    int num_sources;
    demo_source_t src[DEMO_MAX_SOURCES];
} demo_results_t;

/* Fills e from a pipeline estimate and the truth. */
void demo_est_fill(demo_est_t *e, const loadid_pipeline_estimate_t *p, const double truth[10]);

/* The timing lines of every source. */
void demo_print_timing(FILE *out, const demo_results_t *r);

/* Source k's table: truth with units, the median eq. (37) error of every
 * parameter and method, the mean of the ten. */
void demo_print_table(FILE *out, const demo_results_t *r, int k);

/* Source k's verdicts, one line a method: against the truth (medians of
 * mass, COM and inertia errors; seeds within the study's usable bounds)
 * and against the paper (its Fig. 6 for the JR3's signals; its claim that
 * RTLS wins with every source), saying plainly where another method beat
 * RTLS. */
void demo_print_verdicts(FILE *out, const demo_results_t *r, int k);

/* What each method claimed (identified groups over the runs) and, for a
 * group some run did not claim, the first such run's reason. */
void demo_print_claims(FILE *out, const demo_results_t *r, int k);

/* dir/runs.csv: a row per source, seed and method. Returns 0 or -errno. */
int demo_write_runs(const char *dir, const demo_results_t *r);

/* The median of n values (NaN left out; NaN when none). */
double demo_median(const double *v, int n);

#endif /* LOADID_DEMO_REPORT_H */
