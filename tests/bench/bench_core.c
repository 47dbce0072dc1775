/*
 * bench_core: per-call latency of the estimation core on the paper's
 * workload, printed as a table (a benchmark, not a test: it exits 0 whatever
 * the figures are, and non-zero only when it cannot set up).
 *
 * Workload: load o1 (paper section V.A) on the default synthetic trajectory
 * of tools/synth, N samples at 1 kHz (default 1500 = the paper's 1.5 s),
 * 10-parameter model with zeroing (eqs. 7-9, g_init of the still start
 * pose), noise in the wrench and in the states, weights from the noise
 * levels (loadid_est_weights_from_noise). Every A_k, C_k (RIV instruments:
 * the noise-free regressor) and y_k is built before any timing.
 *
 * Figures, each call timed alone with clock_gettime(CLOCK_MONOTONIC):
 *   RTLS update, RTLS update+estimate, RLS update, RIV update: the N-sample
 *     workload repeated R times (reset between repetitions) after one
 *     untimed warm-up repetition: mean, median, 99.9th percentile, max.
 *     RTLS takes samples into its SVD in blocks of up to 4 (rtls.hpp), so
 *     an update alone mostly stores its sample (the median) and every 4th
 *     runs the block (the tail): the mean is its cost per sample. With an
 *     estimate after every update each block is one sample: that row is
 *     the per-sample cost of the live loop at 1 kHz. "RTLS estimate,
 *     nothing waiting" is a second estimate after that one: the gate and
 *     eq. (36) alone, without Brand's update; "exact columns" is
 *     update+estimate with the state columns counted as exact (col_exact
 *     1e3), as loadidd weighs the joint filters' columns;
 *   the Gram eigen shortcut (bench_core only, firmware/bench/gram_tls.h):
 *     the 11 x 11 Gram matrix of D [A y] T and its eigenproblem solved
 *     again after every sample, with the same gate; timed as RTLS
 *     update+estimate, and the ratio of the two medians;
 *   TLS_BATCH estimate (QR + SVD over all stored rows, from scratch) at
 *     k = 100, 500, 1000 and N stored samples, repeated;
 *   the ratio TLS_BATCH estimate at N / RTLS update+estimate, both medians
 *     of this run (each gives the estimate at sample N);
 *   the estimates after N samples (the work was real);
 *   the targets: RTLS update <= 10 us per sample (the mean), its p99.9
 *     (a block of 4) <= 40 us, batch recomputation >= 100x an RTLS
 *     update+estimate, RTLS update+estimate <= 5 us (median), and the
 *     shortcut at least 1.25x RTLS update+estimate (medians of this run:
 *     beyond the 10 % the pair varies by between runs here).
 * The RTLS update and the batch estimate at N are also timed on the thread's
 * CPU clock, which stops while the process is preempted: on a shared machine
 * the monotonic p99.9 and max measure the scheduler as much as the core, and
 * the CPU-clock rows tell the two apart (the targets use the monotonic ones).
 * The estimators use the core's defaults and the noise weights, except that
 * the noise-ratio gate is turned off (max_noise_ratio = 1) so that estimate()
 * always does its full work; the ratio is printed with the estimates.
 *
 * Built twice (tests/CMakeLists.txt): bench_core (double core) and
 * bench_core_float (float core).
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

#include "loadid/core.h"
#include "loadid_synth.h"
#ifdef LOADID_BENCH_SHORTCUT
#include "gram_tls.h"
#endif

#define NPAR LOADID_NPHI    /* 10-parameter model with zeroing */
#define BATCH_REPS 200      /* timed TLS_BATCH estimates per point */
#define MAX_CALLS 10000000L /* reps * samples: bounds the time buffer */

static const char *prog = "bench_core";

/* Targets of the real-time budget (1 kHz loop). */
static const double kTargetMedianUs = 10.0; /* the RTLS update's mean per sample */
static const double kTargetP999Us = 40.0;
static const double kTargetRatio = 100.0;
static const double kTargetLiveUs = 5.0; /* RTLS update+estimate, median */
#ifdef LOADID_BENCH_SHORTCUT
static const double kTargetShortcutRatio = 1.25; /* shortcut / RTLS, medians */
#endif

/* Noise of the measurements: JR3-like wrench, noisy accelerations (paper
 * sections I, IV.A), and a constant F/T offset removed by the zeroing. */
static const loadid_synth_noise_t kNoise = {
    .sigma_f = 0.1,
    .sigma_tau = 0.005,
    .sigma_spec = 0.5,
    .sigma_alpha = 5.0,
    .sigma_omega = 0.02,
    .offset = {2.0, -1.5, 3.0, 0.08, -0.05, 0.03},
};
static const double kOmegaTyp = 2.0; /* typical |w| for the weights [rad/s] */
static const uint64_t kSeed = 1;

/* ---------------------------------------------------------------- data -- */

typedef struct {
    int n;            /* samples */
    loadid_real_t *A; /* 6 x NPAR per sample, measured (noisy) state */
    loadid_real_t *C; /* 6 x NPAR per sample, exact state (RIV instruments) */
    loadid_real_t *y; /* 6 per sample, zeroed measured wrench */
} workload_t;

static void workload_free(workload_t *w) {
    free(w->A);
    free(w->C);
    free(w->y);
    w->A = w->C = w->y = NULL;
}

/* The same construction as tests/unit/support/dataset.c for n_params 10. */
static int workload_make(int n, workload_t *w) {
    memset(w, 0, sizeof *w);
    w->n = n;
    w->A = calloc((size_t)n * 6 * NPAR, sizeof *w->A);
    w->C = calloc((size_t)n * 6 * NPAR, sizeof *w->C);
    w->y = calloc((size_t)n * 6, sizeof *w->y);
    if (!w->A || !w->C || !w->y) {
        workload_free(w);
        return -1;
    }
    const double *phi = loadid_synth_phi_o1;
    loadid_synth_traj_t traj;
    loadid_synth_traj_default(&traj, kSeed);
    loadid_rng_t rng;
    loadid_rng_seed(&rng, kSeed ^ 0x5DEECE66DULL);

    /* Zeroing in the still start pose: the wrench read there (exact, plus
     * the offset) is subtracted from every measurement; g_init is gravity
     * in S at that pose (eq. 7). */
    loadid_synth_sample_t z;
    if (loadid_synth_sample(&traj, phi, 0.0, 1, NULL, NULL, &z) != 0) {
        workload_free(w);
        return -1;
    }
    double zero[6];
    loadid_real_t g_init[3];
    for (int i = 0; i < 6; ++i) zero[i] = z.wrench_true[i] + kNoise.offset[i];
    for (int i = 0; i < 3; ++i) g_init[i] = (loadid_real_t)z.truth.g[i];

    for (int k = 0; k < n; ++k) {
        loadid_synth_sample_t s;
        if (loadid_synth_sample(&traj, phi, k * 1e-3, 0, &kNoise, &rng, &s) != 0) {
            workload_free(w);
            return -1;
        }
        loadid_real_t sp[3], om[3], al[3], tsp[3], tom[3], tal[3];
        for (int i = 0; i < 3; ++i) {
            sp[i] = (loadid_real_t)s.meas.spec[i];
            om[i] = (loadid_real_t)s.meas.omega[i];
            al[i] = (loadid_real_t)s.meas.alpha[i];
            tsp[i] = (loadid_real_t)s.truth.spec[i];
            tom[i] = (loadid_real_t)s.truth.omega[i];
            tal[i] = (loadid_real_t)s.truth.alpha[i];
        }
        loadid_real_t *A = w->A + (size_t)k * 6 * NPAR;
        loadid_real_t *C = w->C + (size_t)k * 6 * NPAR;
        loadid_real_t *y = w->y + (size_t)k * 6;
        if (loadid_regressor(sp, om, al, A) != 0 || loadid_regressor(tsp, tom, tal, C) != 0 ||
            loadid_regressor_add_zeroing(g_init, A) != 0 ||
            loadid_regressor_add_zeroing(g_init, C) != 0) {
            workload_free(w);
            return -1;
        }
        for (int i = 0; i < 6; ++i) y[i] = (loadid_real_t)(s.wrench_meas[i] - zero[i]);
    }
    return 0;
}

static const loadid_real_t *wl_A(const workload_t *w, int k) {
    return w->A + (size_t)k * 6 * NPAR;
}
static const loadid_real_t *wl_C(const workload_t *w, int k) {
    return w->C + (size_t)k * 6 * NPAR;
}
static const loadid_real_t *wl_y(const workload_t *w, int k) {
    return w->y + (size_t)k * 6;
}

/* The default noise-ratio gate, read from the core before it is turned off. */
static double default_max_noise_ratio = -1;

/* Defaults, weights from the noise levels, a batch store that holds the
 * whole workload, and the noise-ratio gate off (max_noise_ratio = 1): the
 * benchmark times the estimators' full work, and the gate would otherwise
 * make estimate() return before it (the ratio is printed with the
 * estimates). */
static int make_estimator(loadid_method_t method, int capacity, int exact, loadid_est_t **out) {
    loadid_est_config_t cfg;
    int rc = loadid_est_config_default(method, NPAR, &cfg);
    if (rc == 0) {
        default_max_noise_ratio = (double)cfg.max_noise_ratio;
        cfg.max_noise_ratio = 1;
    }
    if (rc == 0)
        rc = loadid_est_weights_from_noise(
            &cfg, (loadid_real_t)kNoise.sigma_f, (loadid_real_t)kNoise.sigma_tau,
            (loadid_real_t)kNoise.sigma_spec, (loadid_real_t)kNoise.sigma_alpha,
            (loadid_real_t)kNoise.sigma_omega, (loadid_real_t)kOmegaTyp);
    /* exact: the state columns counted as exact, as loadidd weighs columns
     * from its joint filters (col_exact 1e3): the noise-ratio gate then
     * takes its own eigen-solve now and then (rtls.hpp). */
    for (int j = 0; rc == 0 && exact && j < NPAR; ++j)
        cfg.col_weight[j] *= 1000, cfg.col_exact[j] = 1000;
    if (rc == 0) {
        cfg.batch_capacity = capacity;
        rc = loadid_est_create(&cfg, out);
    }
    if (rc != 0)
        fprintf(stderr, "%s: cannot create %s: %s\n", prog, loadid_method_name(method),
                loadid_strerror(rc));
    return rc;
}

/* -------------------------------------------------------------- timing -- */

static int64_t clock_ns(clockid_t id) {
    struct timespec ts;
    clock_gettime(id, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static int64_t now_ns(void) {
    return clock_ns(CLOCK_MONOTONIC);
}

static int cmp_i64(const void *a, const void *b) {
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

typedef struct {
    long n;        /* timed calls */
    double mean;   /* [us] */
    double median; /* [us] */
    double p999;   /* 99.9th percentile, nearest rank [us] */
    double max;    /* [us] */
    long slow;     /* calls over 1 ms slower than the median: the
                        signature of preemption by another process */
} stats_t;

/* Sorts t (n durations in ns) in place. */
static stats_t stats_of(int64_t *t, long n) {
    stats_t s = {n, 0, 0, 0, 0, 0};
    if (n < 1) return s;
    double sum = 0;
    for (long i = 0; i < n; ++i) sum += (double)t[i];
    s.mean = sum / (double)n * 1e-3;
    qsort(t, (size_t)n, sizeof *t, cmp_i64);
    s.median = (n % 2 ? (double)t[n / 2] : 0.5 * ((double)t[n / 2 - 1] + (double)t[n / 2])) * 1e-3;
    for (long i = n - 1; i >= 0 && (double)t[i] * 1e-3 > s.median + 1000.0; --i) ++s.slow;
    long r = (long)ceil(0.999 * (double)n) - 1;
    if (r < 0) r = 0;
    if (r > n - 1) r = n - 1;
    s.p999 = (double)t[r] * 1e-3;
    s.max = (double)t[n - 1] * 1e-3;
    return s;
}

/* Cost of the two clock reads that bracket every timed call: it is included
 * in every figure below. */
static stats_t timer_overhead(clockid_t id, int64_t *buf, long n) {
    for (long i = 0; i < n; ++i) {
        const int64_t t0 = clock_ns(id);
        const int64_t t1 = clock_ns(id);
        buf[i] = t1 - t0;
    }
    return stats_of(buf, n);
}

typedef struct {
    stats_t st;
    long update_errors; /* updates that did not return 0 (should be none) */
    int last_update_rc;
    int estimate_rc; /* estimate after the last repetition */
    loadid_real_t phi[NPAR];
    loadid_est_info_t info;
} run_result_t;

/* Feeds the workload reps times (plus one untimed warm-up repetition),
 * timing every update (with_estimate: update followed by estimate) alone on
 * clock id. */
static int run_recursive(loadid_method_t method, int with_estimate, clockid_t id,
                         const workload_t *w, int reps, int64_t *buf, run_result_t *out) {
    memset(out, 0, sizeof *out);
    loadid_est_t *est = NULL;
    if (make_estimator(method, w->n, with_estimate == 3, &est) != 0) return -1;
    loadid_real_t phi[NPAR];
    long idx = 0;
    for (int r = -1; r < reps; ++r) { /* r = -1: warm-up */
        loadid_est_reset(est);
        for (int k = 0; k < w->n; ++k) {
            const loadid_real_t *A = wl_A(w, k), *C = wl_C(w, k), *y = wl_y(w, k);
            int rc;
            int64_t t0, t1;
            if (with_estimate == 2) { /* the estimate's own share: nothing waits */
                rc = loadid_est_update(est, A, C, y);
                (void)loadid_est_estimate(est, phi, NULL);
                t0 = clock_ns(id);
                (void)loadid_est_estimate(est, phi, NULL);
                t1 = clock_ns(id);
            } else if (with_estimate) {
                t0 = clock_ns(id);
                rc = loadid_est_update(est, A, C, y);
                (void)loadid_est_estimate(est, phi, NULL);
                t1 = clock_ns(id);
            } else {
                t0 = clock_ns(id);
                rc = loadid_est_update(est, A, C, y);
                t1 = clock_ns(id);
            }
            if (rc != 0) {
                ++out->update_errors;
                out->last_update_rc = rc;
            }
            if (r >= 0) buf[idx++] = t1 - t0;
        }
    }
    out->estimate_rc = loadid_est_estimate(est, out->phi, &out->info);
    loadid_est_destroy(est);
    out->st = stats_of(buf, idx);
    return 0;
}

#ifdef LOADID_BENCH_SHORTCUT
/* The Gram-eigenproblem shortcut (firmware/bench/gram_tls.h) with an
 * estimate after every update, timed as RTLS update+estimate. */
static int run_shortcut(const workload_t *w, int reps, int64_t *buf, run_result_t *out) {
    memset(out, 0, sizeof *out);
    loadid_est_config_t cfg;
    int rc = loadid_est_config_default(LOADID_METHOD_RTLS, NPAR, &cfg);
    if (rc == 0) {
        cfg.max_noise_ratio = 1;
        rc = loadid_est_weights_from_noise(
            &cfg, (loadid_real_t)kNoise.sigma_f, (loadid_real_t)kNoise.sigma_tau,
            (loadid_real_t)kNoise.sigma_spec, (loadid_real_t)kNoise.sigma_alpha,
            (loadid_real_t)kNoise.sigma_omega, (loadid_real_t)kOmegaTyp);
    }
    loadid_gram_tls_t *g = NULL;
    if (rc == 0) rc = loadid_gram_tls_create(&cfg, &g);
    if (rc != 0) {
        fprintf(stderr, "%s: cannot create the Gram shortcut: %s\n", prog, loadid_strerror(rc));
        return -1;
    }
    loadid_real_t phi[NPAR];
    long idx = 0;
    for (int r = -1; r < reps; ++r) {
        loadid_gram_tls_reset(g);
        for (int k = 0; k < w->n; ++k) {
            const int64_t t0 = clock_ns(CLOCK_MONOTONIC);
            loadid_gram_tls_update(g, wl_A(w, k), wl_y(w, k));
            (void)loadid_gram_tls_estimate(g, phi, NULL);
            const int64_t t1 = clock_ns(CLOCK_MONOTONIC);
            if (r >= 0) buf[idx++] = t1 - t0;
        }
    }
    out->estimate_rc = loadid_gram_tls_estimate(g, out->phi, &out->info);
    loadid_gram_tls_destroy(g);
    out->st = stats_of(buf, idx);
    return 0;
}
#endif

#define MAX_POINTS 4

typedef struct {
    int npoints;
    int k[MAX_POINTS];
    stats_t st[MAX_POINTS];
    stats_t cpu; /* the last point on thread CPU time */
    int have_cpu;
    int rc[MAX_POINTS];
    long update_errors;
    int last_update_rc;
    loadid_real_t phi[NPAR]; /* estimate at the last point */
    loadid_est_info_t info;
} batch_result_t;

/* TLS_BATCH: feeds the workload; at k = 100, 500, 1000 (those below N) and
 * N stored samples times estimate() BATCH_REPS times after one warm-up. At
 * N each call is also timed on the thread's CPU clock (nested inside the
 * monotonic pair; its cost is negligible against a batch solve). */
static int run_batch(const workload_t *w, int have_cpu_clock, int64_t *buf, batch_result_t *out) {
    memset(out, 0, sizeof *out);
    static const int kPoints[] = {100, 500, 1000};
    for (size_t i = 0; i < sizeof kPoints / sizeof kPoints[0]; ++i)
        if (kPoints[i] < w->n) out->k[out->npoints++] = kPoints[i];
    out->k[out->npoints++] = w->n;

    loadid_est_t *est = NULL;
    if (make_estimator(LOADID_METHOD_TLS_BATCH, w->n, 0, &est) != 0) return -1;
    loadid_real_t phi[NPAR];
    int k = 0;
    for (int p = 0; p < out->npoints; ++p) {
        for (; k < out->k[p]; ++k) {
            const int rc = loadid_est_update(est, wl_A(w, k), wl_C(w, k), wl_y(w, k));
            if (rc != 0) {
                ++out->update_errors;
                out->last_update_rc = rc;
            }
        }
        out->rc[p] = loadid_est_estimate(est, phi, NULL); /* warm-up */
        const int last = p == out->npoints - 1;
        int64_t *cpu = buf + BATCH_REPS;
        for (int r = 0; r < BATCH_REPS; ++r) {
            const int64_t t0 = now_ns();
#ifdef CLOCK_THREAD_CPUTIME_ID
            const int64_t c0 = last && have_cpu_clock ? clock_ns(CLOCK_THREAD_CPUTIME_ID) : 0;
#endif
            (void)loadid_est_estimate(est, phi, NULL);
#ifdef CLOCK_THREAD_CPUTIME_ID
            if (last && have_cpu_clock) cpu[r] = clock_ns(CLOCK_THREAD_CPUTIME_ID) - c0;
#endif
            const int64_t t1 = now_ns();
            buf[r] = t1 - t0;
        }
        out->st[p] = stats_of(buf, BATCH_REPS);
        if (last && have_cpu_clock) {
            out->cpu = stats_of(cpu, BATCH_REPS);
            out->have_cpu = 1;
        }
    }
    (void)loadid_est_estimate(est, out->phi, &out->info);
    loadid_est_destroy(est);
    return 0;
}

/* ------------------------------------------------------------- output -- */

static void print_row(const char *name, const stats_t *s, const char *note) {
    printf("  %-32s %9ld %11.3f %11.3f %11.3f %11.3f", name, s->n, s->mean, s->median, s->p999,
           s->max);
    if (note && note[0]) printf("  %s", note);
    if (s->slow) printf("%s%ld calls > median + 1 ms", note && note[0] ? "; " : "  ", s->slow);
    printf("\n");
}

static void print_machine(int reps, int samples, const stats_t *tov, const stats_t *tov_cpu) {
    long ncpu_onln = -1, ncpu_conf = -1;
#ifdef _SC_NPROCESSORS_ONLN
    ncpu_onln = sysconf(_SC_NPROCESSORS_ONLN);
#endif
#ifdef _SC_NPROCESSORS_CONF
    ncpu_conf = sysconf(_SC_NPROCESSORS_CONF);
#endif
    struct utsname u;
    const int have_uname = uname(&u) == 0;
    char model[128] = "";
    FILE *f = fopen("/proc/cpuinfo", "r"); /* Linux only; optional */
    if (f) {
        char line[256];
        while (fgets(line, sizeof line, f)) {
            if (strncmp(line, "model name", 10) == 0) {
                const char *colon = strchr(line, ':');
                if (colon) {
                    colon += (colon[1] == ' ') ? 2 : 1;
                    snprintf(model, sizeof model, "%s", colon);
                    model[strcspn(model, "\n")] = '\0';
                }
                break;
            }
        }
        fclose(f);
    }
    char load[64] = "";
    f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fgets(load, sizeof load, f)) load[strcspn(load, "\n")] = '\0';
        fclose(f);
    }
    struct timespec res;
    const int have_res = clock_getres(CLOCK_MONOTONIC, &res) == 0;

    printf("%s: loadid core latency (RTLS after Kubus, Kroeger, Wahl, IROS 2008)\n", prog);
    printf("  scalar     %s (loadid_real_t, %zu bytes)\n",
           loadid_scalar_is_float() ? "float" : "double", sizeof(loadid_real_t));
    printf("  kernel     RTLS's Jacobi on %s (LOADID_JACOBI_KERNEL=portable forces portable)\n",
           loadid_jacobi_kernel());
    printf("  machine    %ld CPUs online (%ld configured)", ncpu_onln, ncpu_conf);
    if (have_uname) printf(", %s %s %s", u.sysname, u.release, u.machine);
    printf("\n");
    if (model[0]) printf("  cpu        %s\n", model);
    if (load[0]) printf("  loadavg    %s (other processes share the CPUs: figures vary)\n", load);
    printf("  workload   load o1, default synthetic trajectory (seed %llu), %d samples at 1 kHz,\n",
           (unsigned long long)kSeed, samples);
    printf(
        "             %d parameters with zeroing (eqs. 7-9); noise f %.3g N, tau %.3g Nm, a-g %.3g "
        "m/s^2,\n",
        NPAR, kNoise.sigma_f, kNoise.sigma_tau, kNoise.sigma_spec);
    printf(
        "             alpha %.3g rad/s^2, w %.3g rad/s; weights from the noise (omega_typ %.3g "
        "rad/s)\n",
        kNoise.sigma_alpha, kNoise.sigma_omega, kOmegaTyp);
    printf("  timing     CLOCK_MONOTONIC around each call");
    if (have_res)
        printf(" (resolution %ld ns)", (long)res.tv_nsec + (long)res.tv_sec * 1000000000L);
    printf(";\n             clock-pair overhead median %.3f us, included below", tov->median);
    if (tov_cpu) printf(" (thread CPU clock: %.3f us)", tov_cpu->median);
    printf("\n");
    loadid_est_config_t def;
    loadid_est_config_default(LOADID_METHOD_RTLS, NPAR, &def);
    printf(
        "  config     defaults (max_condition %.3g), weights from the noise, batch capacity = "
        "samples,\n"
        "             noise-ratio gate off (max_noise_ratio 1; default %.3g) so that estimate() "
        "does its work\n",
        (double)def.max_condition, (double)def.max_noise_ratio);
    printf("  recursive  %d timed repetitions of the %d samples after 1 warm-up, reset between\n\n",
           reps, samples);
}

static void usage(FILE *f) {
    fprintf(f,
            "usage: %s [--reps N] [--samples N] [--help]\n"
            "  Times the loadid core's estimators per call on the paper's load o1 (synthetic\n"
            "  trajectory, noisy states and wrench, 10 parameters with zeroing) and prints\n"
            "  median, 99.9th percentile and max in microseconds, the batch TLS recomputation\n"
            "  cost, and whether the real-time targets are met. Always exits 0 once set up.\n"
            "  --reps N     timed repetitions of the workload per recursive method, 1..1000 "
            "(default 20)\n"
            "  --samples N  samples at 1 kHz, 10..100000 (default 1500: the paper's 1.5 s)\n"
            "  --help       this text\n",
            prog);
}

static int parse_int(const char *opt, const char *arg, long lo, long hi, int *out) {
    char *end = NULL;
    errno = 0;
    const long v = strtol(arg, &end, 10);
    if (errno || !end || end == arg || *end || v < lo || v > hi) {
        fprintf(stderr, "%s: %s must be an integer in %ld..%ld, not '%s'\n", prog, opt, lo, hi,
                arg);
        return -1;
    }
    *out = (int)v;
    return 0;
}

static const char *met(int ok) {
    return ok ? "met" : "NOT met";
}

int main(int argc, char **argv) {
    if (argc > 0 && argv[0] && argv[0][0]) {
        const char *slash = strrchr(argv[0], '/');
        prog = slash ? slash + 1 : argv[0];
    }
    int reps = 20, samples = 1500;
    static const struct option opts[] = {
        {"help", no_argument, NULL, 'h'},
        {"reps", required_argument, NULL, 'r'},
        {"samples", required_argument, NULL, 'n'},
        {NULL, 0, NULL, 0},
    };
    int c;
    opterr = 0; /* one-line errors of our own */
    while ((c = getopt_long(argc, argv, ":hr:n:", opts, NULL)) != -1) {
        switch (c) {
            case 'h':
                usage(stdout);
                return 0;
            case 'r':
                if (parse_int("--reps", optarg, 1, 1000, &reps)) return 2;
                break;
            case 'n':
                if (parse_int("--samples", optarg, 10, 100000, &samples)) return 2;
                break;
            case ':':
                fprintf(stderr, "%s: option '%s' needs a value (see --help)\n", prog,
                        argv[optind - 1]);
                return 2;
            default:
                fprintf(stderr, "%s: unknown option '%s' (see --help)\n", prog, argv[optind - 1]);
                return 2;
        }
    }
    if (optind != argc) {
        fprintf(stderr, "%s: unexpected argument '%s' (see --help)\n", prog, argv[optind]);
        return 2;
    }
    if ((long)reps * samples > MAX_CALLS) {
        fprintf(stderr, "%s: --reps x --samples must be at most %ld, not %ld\n", prog, MAX_CALLS,
                (long)reps * samples);
        return 2;
    }

    workload_t w;
    if (workload_make(samples, &w) != 0) {
        fprintf(stderr, "%s: cannot build the workload (out of memory?)\n", prog);
        return 1;
    }
    long nbuf = (long)reps * samples;
    if (nbuf < 2 * BATCH_REPS) nbuf = 2 * BATCH_REPS;
    if (nbuf < 100000) nbuf = 100000;
    int64_t *buf = malloc((size_t)nbuf * sizeof *buf);
    if (!buf) {
        fprintf(stderr, "%s: out of memory for %ld timings\n", prog, nbuf);
        workload_free(&w);
        return 1;
    }

    const stats_t tov = timer_overhead(CLOCK_MONOTONIC, buf, 100000);
#ifdef CLOCK_THREAD_CPUTIME_ID
    /* The CPU time of this thread does not advance while it is preempted:
     * timing the RTLS update on it too separates the core's own tail from
     * the scheduler's (the targets are judged on CLOCK_MONOTONIC). */
    struct timespec cpu_res;
    const int have_cpu_clock = clock_getres(CLOCK_THREAD_CPUTIME_ID, &cpu_res) == 0;
#else
    const int have_cpu_clock = 0;
#endif
    stats_t tov_cpu = {0, 0, 0, 0, 0, 0};
#ifdef CLOCK_THREAD_CPUTIME_ID
    if (have_cpu_clock) tov_cpu = timer_overhead(CLOCK_THREAD_CPUTIME_ID, buf, 100000);
#endif
    print_machine(reps, samples, &tov, have_cpu_clock ? &tov_cpu : NULL);

    run_result_t rtls, rtls_est, rtls_est_only, rtls_exact, rls, riv, rtls_cpu, shortcut;
    memset(&shortcut, 0, sizeof shortcut);
    batch_result_t batch;
    memset(&rtls_cpu, 0, sizeof rtls_cpu);
    if (run_recursive(LOADID_METHOD_RTLS, 0, CLOCK_MONOTONIC, &w, reps, buf, &rtls) ||
        run_recursive(LOADID_METHOD_RTLS, 1, CLOCK_MONOTONIC, &w, reps, buf, &rtls_est) ||
        run_recursive(LOADID_METHOD_RTLS, 2, CLOCK_MONOTONIC, &w, reps, buf, &rtls_est_only) ||
        run_recursive(LOADID_METHOD_RTLS, 3, CLOCK_MONOTONIC, &w, reps, buf, &rtls_exact) ||
        run_recursive(LOADID_METHOD_RLS, 0, CLOCK_MONOTONIC, &w, reps, buf, &rls) ||
        run_recursive(LOADID_METHOD_RIV, 0, CLOCK_MONOTONIC, &w, reps, buf, &riv) ||
#ifdef LOADID_BENCH_SHORTCUT
        run_shortcut(&w, reps, buf, &shortcut) ||
#endif
        run_batch(&w, have_cpu_clock, buf, &batch)) {
        free(buf);
        workload_free(&w);
        return 1;
    }
#ifdef CLOCK_THREAD_CPUTIME_ID
    if (have_cpu_clock &&
        run_recursive(LOADID_METHOD_RTLS, 0, CLOCK_THREAD_CPUTIME_ID, &w, reps, buf, &rtls_cpu)) {
        free(buf);
        workload_free(&w);
        return 1;
    }
#endif

    printf("  %-32s %9s %11s %11s %11s %11s\n", "figure [us per call]", "calls", "mean", "median",
           "p99.9", "max");
    print_row("RTLS update", &rtls.st, NULL);
    print_row("RTLS update+estimate", &rtls_est.st, NULL);
    print_row("RTLS estimate, nothing waiting", &rtls_est_only.st, NULL);
    print_row("RTLS upd+est, exact columns", &rtls_exact.st, NULL);
#ifdef LOADID_BENCH_SHORTCUT
    print_row("Gram eigen shortcut upd+est", &shortcut.st, NULL);
#endif
    print_row("RLS update", &rls.st, NULL);
    print_row("RIV update", &riv.st, NULL);
    for (int p = 0; p < batch.npoints; ++p) {
        char name[64], note[96];
        snprintf(name, sizeof name, "TLS_BATCH estimate @ k=%d", batch.k[p]);
        snprintf(note, sizeof note, "%.4f us/sample%s%s", batch.st[p].median / batch.k[p],
                 batch.rc[p] ? "; returned " : "", batch.rc[p] ? loadid_strerror(batch.rc[p]) : "");
        print_row(name, &batch.st[p], note);
    }
    const stats_t *bN = &batch.st[batch.npoints - 1];
    const double ratio = rtls_est.st.median > 0 ? bN->median / rtls_est.st.median : INFINITY;
    printf(
        "  %-32s %9s %11.1fx   (TLS_BATCH estimate @ k=%d %.3f us / RTLS update+estimate %.3f "
        "us)\n",
        "ratio batch / RTLS (medians)", "", ratio, samples, bN->median, rtls_est.st.median);
#ifdef LOADID_BENCH_SHORTCUT
    const double sc_ratio =
        rtls_est.st.median > 0 ? shortcut.st.median / rtls_est.st.median : INFINITY;
    printf("  %-32s %9s %11.2fx   (Gram eigen shortcut %.3f us / RTLS update+estimate %.3f us)\n",
           "ratio shortcut / RTLS (medians)", "", sc_ratio, shortcut.st.median, rtls_est.st.median);
#endif
    if (have_cpu_clock) {
        /* The same on the thread's CPU clock, which stops while another
         * process runs: what the core costs when it has the CPU. */
        printf("\n  on the thread CPU clock (preemption by other processes excluded):\n");
        print_row("RTLS update [CPU]", &rtls_cpu.st, NULL);
        if (batch.have_cpu) {
            char name[64];
            snprintf(name, sizeof name, "TLS_BATCH estimate @ k=%d [CPU]", samples);
            print_row(name, &batch.cpu, NULL);
            printf("  %-32s %9s %11.1fx   (TLS_BATCH median / RTLS update mean)\n",
                   "ratio batch / RTLS [CPU]", "",
                   rtls_cpu.st.mean > 0 ? batch.cpu.median / rtls_cpu.st.mean : INFINITY);
        }
    }

    /* The estimates after the whole workload: the benchmark did real work. */
    const double m_true = loadid_synth_phi_o1[0];
    printf("\n  estimates after %d samples (true mass %.4g kg):\n", samples, m_true);
    const struct {
        const char *name;
        int rc;
        const loadid_real_t *phi;
        const loadid_est_info_t *info;
        long errors;
        int last_error;
    } res[] = {
        {"RTLS", rtls.estimate_rc, rtls.phi, &rtls.info,
         rtls.update_errors + rtls_est.update_errors,
         rtls.update_errors ? rtls.last_update_rc : rtls_est.last_update_rc},
        {"RLS", rls.estimate_rc, rls.phi, &rls.info, rls.update_errors, rls.last_update_rc},
        {"RIV", riv.estimate_rc, riv.phi, &riv.info, riv.update_errors, riv.last_update_rc},
        {"TLS_BATCH", batch.rc[batch.npoints - 1], batch.phi, &batch.info, batch.update_errors,
         batch.last_update_rc},
#ifdef LOADID_BENCH_SHORTCUT
        {"shortcut", shortcut.estimate_rc, shortcut.phi, &shortcut.info, 0, 0},
#endif
    };
    for (size_t i = 0; i < sizeof res / sizeof res[0]; ++i) {
        if (res[i].rc != 0) {
            printf("    %-9s no estimate: %s (kappa %.3g)\n", res[i].name,
                   loadid_strerror(res[i].rc), (double)res[i].info->condition_number);
        } else {
            const double m = (double)res[i].phi[0];
            printf(
                "    %-9s mass %.5f kg (error %.2f %%), m*c [%.5f %.5f %.5f] kg m, "
                "condition_number %.3g, noise ratio %.3f",
                res[i].name, m, 100.0 * fabs(m - m_true) / m_true, (double)res[i].phi[1],
                (double)res[i].phi[2], (double)res[i].phi[3], (double)res[i].info->condition_number,
                (double)res[i].info->noise_ratio);
            if (res[i].info->sigma_min > 0)
                printf(", sigma_min %.4g", (double)res[i].info->sigma_min);
            printf("\n");
        }
        if (res[i].errors)
            printf("    %-9s WARNING: %ld updates failed (%s)\n", res[i].name, res[i].errors,
                   loadid_strerror(res[i].last_error));
    }
#ifdef LOADID_BENCH_SHORTCUT
    if (shortcut.estimate_rc == 0 && batch.rc[batch.npoints - 1] == 0) {
        double worst = 0;
        for (int j = 0; j < NPAR; ++j) {
            const double b = (double)batch.phi[j],
                         d = fabs((double)shortcut.phi[j] - b) / fmax(fabs(b), 1e-3);
            worst = d > worst ? d : worst;
        }
        printf(
            "    shortcut  vs TLS_BATCH: max rel diff of phi %.2e (the Gram matrix squares the "
            "condition number)\n",
            worst);
    }
#endif
    printf("    RTLS      U re-orthogonalised %d times, ||U^T U - I|| %.3g\n",
           rtls.info.reorthogonalisations, (double)rtls.info.orthogonality_error);
    if (rtls.estimate_rc == 0)
        printf(
            "    (noise-ratio gate off for the benchmark; with the default max_noise_ratio %.3g "
            "the RTLS\n"
            "     estimate would be %s)\n",
            default_max_noise_ratio,
            (double)rtls.info.noise_ratio > default_max_noise_ratio ? "rejected as not excited"
                                                                    : "accepted");

    printf("\n  targets (%s core):\n", loadid_scalar_is_float() ? "float" : "double");
    char label[64];
    snprintf(label, sizeof label, "RTLS update mean <= %.0f us", kTargetMedianUs);
    printf("    %-40s : %10.3f us  %s\n", label, rtls.st.mean,
           met(rtls.st.mean <= kTargetMedianUs));
    snprintf(label, sizeof label, "RTLS update p99.9 <= %.0f us", kTargetP999Us);
    printf("    %-40s : %10.3f us  %s\n", label, rtls.st.p999, met(rtls.st.p999 <= kTargetP999Us));
    snprintf(label, sizeof label, "batch TLS / RTLS @ k=%d >= %.0fx", samples, kTargetRatio);
    printf("    %-40s : %10.1f x   %s\n", label, ratio, met(ratio >= kTargetRatio));
    snprintf(label, sizeof label, "RTLS update+estimate median <= %.0f us", kTargetLiveUs);
    printf("    %-40s : %10.3f us  %s   (the live loop at 1 kHz; p99.9 %.3f us)\n", label,
           rtls_est.st.median, met(rtls_est.st.median <= kTargetLiveUs), rtls_est.st.p999);
    snprintf(label, sizeof label, "  the same, exact columns <= %.0f us", kTargetLiveUs);
    printf("    %-40s : %10.3f us  %s   (loadidd's weights for joint-filter columns)\n", label,
           rtls_exact.st.median, met(rtls_exact.st.median <= kTargetLiveUs));
#ifdef LOADID_BENCH_SHORTCUT
    snprintf(label, sizeof label, "Gram shortcut / RTLS >= %.2fx", kTargetShortcutRatio);
    printf("    %-40s : %10.2f x   %s\n", label, sc_ratio, met(sc_ratio >= kTargetShortcutRatio));
#endif
    if (have_cpu_clock)
        printf("    (thread CPU clock, for reference: RTLS update mean %.3f us, p99.9 %.3f us)\n",
               rtls_cpu.st.mean, rtls_cpu.st.p999);

    free(buf);
    workload_free(&w);
    return 0;
}
