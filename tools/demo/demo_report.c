/* What loadid-demo found, in words and numbers (demo_report.h). */
#define _POSIX_C_SOURCE 200809L

#include "demo_report.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/core.h"
#include "loadid/signals.h"

static const char *const kParams[10] = {"m",   "m*cx", "m*cy", "m*cz", "Ixx",
                                        "Ixy", "Ixz",  "Iyy",  "Iyz",  "Izz"};
static const char *const kUnits[10] = {"kg",     "kg m",   "kg m",   "kg m",   "kg m^2",
                                       "kg m^2", "kg m^2", "kg m^2", "kg m^2", "kg m^2"};
/* The study's usable estimate (loadid-study, time to a usable estimate). */
static const double kUsableMassPct = 1.0, kUsableComMm = 2.0, kUsableInertiaPct = 15.0;
/* What the paper's Fig. 6 shows (o1, tr2, the JR3's accelerations): RTLS's
 * mass error under 1 %, Ixx 21 % for RTLS and 39 % for RLS; and its text:
 * RTLS better than RIV in all but one of the ten parameters. */
static const double kPaperRtlsMass = 1.0, kPaperRtlsIxx = 21.0, kPaperRlsIxx = 39.0;

static int cmp_double(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double demo_median(const double *v, int n) {
    double s[DEMO_MAX_SEEDS];
    int k = 0;
    for (int i = 0; i < n && k < DEMO_MAX_SEEDS; ++i)
        if (!isnan(v[i])) s[k++] = v[i];
    if (!k) return NAN;
    qsort(s, (size_t)k, sizeof *s, cmp_double);
    return k % 2 ? s[k / 2] : 0.5 * (s[k / 2 - 1] + s[k / 2]);
}

/* The Frobenius norm of a symmetric 3x3 given as [xx xy xz yy yz zz]. */
static double frob6(const double v[6]) {
    return sqrt(v[0] * v[0] + v[3] * v[3] + v[5] * v[5] +
                2 * (v[1] * v[1] + v[2] * v[2] + v[4] * v[4]));
}

void demo_est_fill(demo_est_t *e, const loadid_pipeline_estimate_t *p, const double truth[10]) {
    memset(e, 0, sizeof *e);
    e->samples = p->samples;
    e->condition_number = p->condition_number;
    e->sigma_min = p->sigma_min;
    e->valid = p->valid;
    if (!p->valid) {
        snprintf(e->why, sizeof e->why, "%s", p->why[0] ? p->why : loadid_strerror(p->error));
        for (int i = 0; i < 10; ++i) e->phi[i] = e->err[i] = NAN;
        e->mass_pct = e->com_mm = e->inertia_pct = NAN;
        return;
    }
    e->consistent = p->physically_consistent;
    e->identified = p->identified;
    for (int g = 0; g < 3; ++g)
        loadid_pipeline_why_not(p, g, e->not_identified[g], sizeof e->not_identified[g]);
    loadid_real_t t[10];
    for (int i = 0; i < 10; ++i) {
        e->phi[i] = p->phi[i];
        e->err[i] = 100.0 * fabs((p->phi[i] - truth[i]) / truth[i]); /* eq. (37) */
        t[i] = (loadid_real_t)truth[i];
    }
    loadid_physical_t pt;
    loadid_phi_to_physical(t, &pt);
    double d[6], it[6], dc = 0;
    for (int i = 0; i < 6; ++i) it[i] = (double)pt.inertia_com[i], d[i] = p->inertia_com[i] - it[i];
    for (int i = 0; i < 3; ++i)
        dc += (p->com[i] - (double)pt.com[i]) * (p->com[i] - (double)pt.com[i]);
    e->mass_pct = 100.0 * fabs(p->mass - (double)pt.mass) / (double)pt.mass;
    e->com_mm = 1000.0 * sqrt(dc);
    e->inertia_pct = 100.0 * frob6(d) / frob6(it);
}

/* ---------------------------------------------------------------- figures */

/* The medians over the seeds of one source and method. */
typedef struct {
    int runs;             /* with an estimate */
    double err[10], mean; /* eq. (37) per parameter, and their mean [%] */
    double mass_pct, com_mm, inertia_pct;
    int usable; /* runs within the study's bounds */
} stats_t;

static double run_mean(const demo_est_t *e) {
    if (!e->valid) return NAN;
    double s = 0;
    for (int i = 0; i < 10; ++i) s += e->err[i] / 10;
    return s;
}

static stats_t stats_of(const demo_results_t *r, int k, int m) {
    const demo_source_t *s = &r->src[k];
    stats_t st;
    memset(&st, 0, sizeof st);
    double v[DEMO_MAX_SEEDS];
    for (int i = 0; i < 10; ++i) {
        for (int j = 0; j < r->seeds; ++j) v[j] = s->est[j][m].err[i];
        st.err[i] = demo_median(v, r->seeds);
    }
    for (int j = 0; j < r->seeds; ++j) v[j] = run_mean(&s->est[j][m]);
    st.mean = demo_median(v, r->seeds);
    for (int j = 0; j < r->seeds; ++j) v[j] = s->est[j][m].mass_pct;
    st.mass_pct = demo_median(v, r->seeds);
    for (int j = 0; j < r->seeds; ++j) v[j] = s->est[j][m].com_mm;
    st.com_mm = demo_median(v, r->seeds);
    for (int j = 0; j < r->seeds; ++j) v[j] = s->est[j][m].inertia_pct;
    st.inertia_pct = demo_median(v, r->seeds);
    for (int j = 0; j < r->seeds; ++j) {
        const demo_est_t *e = &s->est[j][m];
        st.runs += e->valid;
        st.usable += e->valid && e->mass_pct <= kUsableMassPct && e->com_mm <= kUsableComMm &&
                     e->inertia_pct <= kUsableInertiaPct;
    }
    return st;
}

/* A percentage with the digits it deserves. */
static const char *pct(char *buf, size_t len, double x) {
    if (isnan(x))
        snprintf(buf, len, "-");
    else
        snprintf(buf, len, x < 10 ? "%.2f" : x < 100 ? "%.1f" : "%.0f", x);
    return buf;
}

static int method_index(const demo_results_t *r, int method) {
    for (int m = 0; m < DEMO_METHODS; ++m)
        if (r->methods[m] == method) return m;
    return -1;
}

static const char *mname(const demo_results_t *r, int m) {
    return loadid_method_name((loadid_method_t)r->methods[m]);
}

void demo_print_timing(FILE *out, const demo_results_t *r) {
    for (int k = 0; k < r->num_sources; ++k) {
        const demo_source_t *s = &r->src[k];
        /* The runs that wrote a trace (every 10th sample's estimates with
         * their phi_std, to a file) are left out when there are others. */
        int untraced = 0, n = 0;
        for (int j = 0; j < r->seeds; ++j) untraced += !s->traced[j];
        double win[DEMO_MAX_SEEDS], cpu[DEMO_MAX_SEEDS], run[DEMO_MAX_SEEDS];
        double wsamples[DEMO_MAX_SEEDS], rsamples[DEMO_MAX_SEEDS];
        for (int j = 0; j < r->seeds; ++j) {
            if (untraced && s->traced[j]) continue;
            win[n] = s->window_wall_s[j], cpu[n] = s->window_cpu_s[j], run[n] = s->run_wall_s[j];
            wsamples[n] = (double)s->window_samples[j], rsamples[n++] = (double)s->run_samples[j];
        }
        const double w = demo_median(win, n), c = demo_median(cpu, n), t = demo_median(run, n);
        const double ws = demo_median(wsamples, n), rs = demo_median(rsamples, n);
        fprintf(out,
                "   %-8s the window (START to DONE: %.0f samples, all %d methods, REFINED's batch "
                "at its end) %.1f ms wall, %.1f us a sample (CPU %.1f us); the whole recording "
                "from its files %.1f ms, %.1f us a sample of %.0f; medians of %d run%s%s\n",
                s->name, ws, DEMO_METHODS, w * 1e3, w / ws * 1e6, c / ws * 1e6, t * 1e3,
                t / rs * 1e6, rs, n, n == 1 ? "" : "s",
                untraced && untraced < r->seeds ? " (the one that wrote the trace left out)" : "");
    }
}

void demo_print_table(FILE *out, const demo_results_t *r, int k) {
    stats_t st[DEMO_METHODS];
    for (int m = 0; m < DEMO_METHODS; ++m) st[m] = stats_of(r, k, m);
    char b[32];
    fprintf(out, "   %-6s %-7s %11s", "param", "unit", "truth");
    for (int m = 0; m < DEMO_METHODS; ++m) fprintf(out, " %9s", mname(r, m));
    fprintf(out, "\n");
    for (int i = 0; i < 10; ++i) {
        fprintf(out, "   %-6s %-7s %11.4g", kParams[i], kUnits[i], r->truth[i]);
        for (int m = 0; m < DEMO_METHODS; ++m) fprintf(out, " %9s", pct(b, sizeof b, st[m].err[i]));
        fprintf(out, "\n");
    }
    fprintf(out, "   %-26s", "mean of the ten [%]");
    for (int m = 0; m < DEMO_METHODS; ++m) fprintf(out, " %9s", pct(b, sizeof b, st[m].mean));
    fprintf(out, "\n");
    /* o1 as published is not consistent itself (README): estimates close
     * to it often are not either. */
    fprintf(out, "   %-26s", "physically consistent");
    for (int m = 0; m < DEMO_METHODS; ++m) {
        int n = 0;
        for (int j = 0; j < r->seeds; ++j) n += r->src[k].est[j][m].consistent;
        snprintf(b, sizeof b, "%d/%d", n, r->seeds);
        fprintf(out, " %9s", b);
    }
    fprintf(out, "   (o1 itself is not: 0.6 %% off the triangle inequality)\n");
    for (int m = 0; m < DEMO_METHODS; ++m)
        for (int j = 0; j < r->seeds; ++j)
            if (!r->src[k].est[j][m].valid)
                fprintf(out, "   %s, seed %llu: no estimate: %s\n", mname(r, m),
                        (unsigned long long)(r->first_seed + (uint64_t)j), r->src[k].est[j][m].why);
}

/* Parameters on which a's median error is below b's. */
static int params_better(const stats_t *a, const stats_t *b) {
    int n = 0;
    for (int i = 0; i < 10; ++i) n += a->err[i] < b->err[i];
    return n;
}

/* Runs in which a's mean error is below b's. */
static int runs_better(const demo_results_t *r, int k, int a, int b) {
    int n = 0;
    for (int j = 0; j < r->seeds; ++j)
        n += run_mean(&r->src[k].est[j][a]) < run_mean(&r->src[k].est[j][b]);
    return n;
}

/* printf onto the end of s. */
static void add(char *s, size_t len, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void add(char *s, size_t len, const char *fmt, ...) {
    const size_t n = strlen(s);
    if (n >= len) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(s + n, len - n, fmt, ap);
    va_end(ap);
}

/* "better than B on p/10 parameters (q/N runs)" */
static void better(char *s, size_t len, const demo_results_t *r, int k, const stats_t *st, int a,
                   int b) {
    add(s, len, "better than %s on %d/10 parameters (%d/%d runs)", mname(r, b),
        params_better(&st[a], &st[b]), runs_better(r, k, a, b), r->seeds);
}

/* Whether a and b's mean errors are within 10 % of each other. */
static int close_to(const stats_t *a, const stats_t *b) {
    return fabs(a->mean - b->mean) <= 0.1 * fmin(a->mean, b->mean);
}

void demo_print_verdicts(FILE *out, const demo_results_t *r, int k) {
    stats_t st[DEMO_METHODS];
    for (int m = 0; m < DEMO_METHODS; ++m) st[m] = stats_of(r, k, m);
    const int rls = method_index(r, LOADID_METHOD_RLS), riv = method_index(r, LOADID_METHOD_RIV),
              rtls = method_index(r, LOADID_METHOD_RTLS);
    const int sensor = r->src[k].source == LOADID_SIGNALS_SENSOR;
    int best = -1;
    for (int m = 0; m < DEMO_METHODS; ++m)
        if (!isnan(st[m].mean) && (best < 0 || st[m].mean < st[best].mean)) best = m;
    char a[32], b[32];
    for (int m = 0; m < DEMO_METHODS; ++m) {
        char l[1024] = "";
        const int method = r->methods[m];
        if (!st[m].runs) {
            fprintf(out, "   %-9s no estimate in any run\n", mname(r, m));
            continue;
        }
        /* against the truth */
        add(l, sizeof l, "mass %s %%, COM %.2f mm, inertia %s %%, usable %d/%d%s | ",
            pct(a, sizeof a, st[m].mass_pct), st[m].com_mm, pct(b, sizeof b, st[m].inertia_pct),
            st[m].usable, r->seeds, m == best ? ", the best here" : "");
        /* against the paper */
        if (m == rtls) {
            add(l, sizeof l, "paper%s: mass < %.0f %% -> %s %%%s, Ixx %.0f %% -> %s %%%s; ",
                sensor ? " (Fig. 6)" : "'s figures (JR3 signals)", kPaperRtlsMass,
                pct(a, sizeof a, st[m].err[0]), st[m].err[0] < kPaperRtlsMass ? "" : " NOT met",
                kPaperRtlsIxx, pct(b, sizeof b, st[m].err[4]),
                st[m].err[4] <= kPaperRtlsIxx ? "" : " NOT met");
            int sep = 0;
            for (int o = 0; o < DEMO_METHODS; ++o) {
                if (o != rls && o != riv) continue;
                add(l, sizeof l, "%s", sep++ ? "; " : "");
                better(l, sizeof l, r, k, st, m, o);
                if (params_better(&st[m], &st[o]) < 5)
                    add(l, sizeof l, ": %s %s RTLS, the paper has RTLS ahead%s", mname(r, o),
                        close_to(&st[m], &st[o]) ? "slightly ahead of" : "BEAT",
                        sensor && o == riv ? " on 9/10" : "");
            }
        } else if (m == rls || m == riv) {
            if (sensor && m == rls)
                add(l, sizeof l, "paper (Fig. 6): Ixx %.0f %% -> %s %% (RTLS's %.0f %% -> %s %%); ",
                    kPaperRlsIxx, pct(a, sizeof a, st[m].err[4]), kPaperRtlsIxx,
                    rtls >= 0 ? pct(b, sizeof b, st[rtls].err[4]) : "-");
            else if (sensor)
                add(l, sizeof l, "paper (Fig. 6): better than RLS, behind RTLS on 9/10; ");
            else
                add(l, sizeof l, "paper: behind RTLS with every source; ");
            if (sensor && m == riv && rls >= 0) {
                better(l, sizeof l, r, k, st, m, rls);
                add(l, sizeof l, "; ");
            }
            if (rtls >= 0) {
                const int ahead = params_better(&st[rtls], &st[m]);
                const int behind = params_better(&st[m], &st[rtls]);
                const int joints = r->src[k].source == LOADID_SIGNALS_KF ||
                                   r->src[k].source == LOADID_SIGNALS_SETPOINT;
                if (ahead > 5) {
                    add(l, sizeof l,
                        "RTLS better on %d/10 parameters (%d/%d runs), as in the paper", ahead,
                        runs_better(r, k, rtls, m), r->seeds);
                } else {
                    better(l, sizeof l, r, k, st, m, rtls);
                    add(l, sizeof l,
                        behind > 5 ? ": %s %s RTLS, unlike the paper" : ": %s and RTLS even%s",
                        mname(r, m),
                        behind > 5 ? (close_to(&st[m], &st[rtls]) ? "slightly ahead of" : "BEAT")
                                   : "");
                }
                if (close_to(&st[m], &st[rtls]) && joints)
                    add(l, sizeof l,
                        " (mean errors within 10 %%: the joints' columns count as "
                        "exact, so TLS has little to correct)");
                else if (behind > 5 && m == riv && sensor)
                    add(l, sizeof l,
                        " (its instruments, the setpoints, are close to the simulated "
                        "motion and free of the accelerometer's noise)");
            }
        } else if (method == LOADID_METHOD_LS_BATCH || method == LOADID_METHOD_TLS_BATCH) {
            const int twin = method == LOADID_METHOD_LS_BATCH ? rls : rtls;
            add(l, sizeof l, "not in the paper: the batch form of %s, mean error %s %% vs %s %%",
                twin >= 0 ? mname(r, twin) : "-", pct(a, sizeof a, st[m].mean),
                twin >= 0 ? pct(b, sizeof b, st[twin].mean) : "-");
        } else if (method == LOADID_METHOD_REFINED) {
            add(l, sizeof l,
                "not in the paper: batch TLS on the joints smoothed without lag "
                "(whatever the source), mean error %s %% vs RTLS's %s %%",
                pct(a, sizeof a, st[m].mean), rtls >= 0 ? pct(b, sizeof b, st[rtls].mean) : "-");
        }
        fprintf(out, "   %-9s %s\n", mname(r, m), l);
    }
}

int demo_write_runs(const char *dir, const demo_results_t *r) {
    char path[4200];
    snprintf(path, sizeof path, "%s/runs.csv", dir);
    FILE *f = fopen(path, "w");
    if (!f) return -errno;
    fprintf(f,
            "signals,seed,method,valid,samples,condition_number,sigma_min,"
            "physically_consistent,mass_pct,com_mm,inertia_pct");
    for (int i = 0; i < 10; ++i) fprintf(f, ",phi%d", i);
    for (int i = 0; i < 10; ++i) fprintf(f, ",err%d", i);
    for (int i = 0; i < 10; ++i) fprintf(f, ",truth%d", i);
    fprintf(f, ",window_wall_ms,window_cpu_ms,window_samples\n");
    for (int k = 0; k < r->num_sources; ++k)
        for (int j = 0; j < r->seeds; ++j)
            for (int m = 0; m < DEMO_METHODS; ++m) {
                const demo_source_t *s = &r->src[k];
                const demo_est_t *e = &s->est[j][m];
                fprintf(f, "%s,%llu,%s,%d,%lld,%.9g,%.9g,%d,%.9g,%.9g,%.9g", s->name,
                        (unsigned long long)(r->first_seed + (uint64_t)j), mname(r, m), e->valid,
                        (long long)e->samples, e->condition_number, e->sigma_min, e->consistent,
                        e->mass_pct, e->com_mm, e->inertia_pct);
                for (int i = 0; i < 10; ++i) fprintf(f, ",%.17g", e->phi[i]);
                for (int i = 0; i < 10; ++i) fprintf(f, ",%.9g", e->err[i]);
                for (int i = 0; i < 10; ++i) fprintf(f, ",%.17g", r->truth[i]);
                fprintf(f, ",%.6f,%.6f,%lld\n", s->window_wall_s[j] * 1e3, s->window_cpu_s[j] * 1e3,
                        (long long)s->window_samples[j]);
            }
    const int bad = ferror(f);
    if (fclose(f) != 0 || bad) return -EIO;
    return 0;
}

void demo_print_claims(FILE *out, const demo_results_t *r, int k) {
    const demo_source_t *s = &r->src[k];
    for (int m = 0; m < DEMO_METHODS; ++m) {
        char l[1024] = "";
        int n[3] = {0, 0, 0}, first[3] = {-1, -1, -1}, runs = 0;
        for (int j = 0; j < r->seeds; ++j) {
            const demo_est_t *e = &s->est[j][m];
            if (!e->valid) continue;
            ++runs;
            for (int g = 0; g < 3; ++g) {
                if (e->identified & (1 << g))
                    ++n[g];
                else if (first[g] < 0)
                    first[g] = j;
            }
        }
        if (!runs) continue;
        add(l, sizeof l, "mass %d/%d, COM %d/%d, inertia %d/%d", n[0], runs, n[1], runs, n[2],
            runs);
        for (int g = 0; g < 3; ++g) {
            if (first[g] < 0) continue;
            add(l, sizeof l, "; %s not (seed %llu: %s)", g == 1 ? "COM" : loadid_ident_name(1 << g),
                (unsigned long long)(r->first_seed + (uint64_t)first[g]),
                s->est[first[g]][m].not_identified[g]);
        }
        fprintf(out, "   %-9s %s\n", mname(r, m), l);
    }
}
