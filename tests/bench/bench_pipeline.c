/*
 * bench_pipeline: throughput of the service's whole per-sample path over a
 * recording, as loadidd --offline runs it (JR3 decoding, joint filters,
 * kinematics, signal source, regressor, every configured estimator), and
 * the process's peak resident memory. A benchmark: prints its figures and
 * exits 0; non-zero only when it cannot set up.
 *
 *   bench_pipeline CONFIG RECORDING_DIR [REPETITIONS]
 *
 * Each repetition builds a fresh pipeline (not timed) and runs the whole
 * recording through it (timed, wall clock, reading and parsing the files
 * included). estimation.duration_s is raised so that every sample after
 * START is estimated, and the throughput is charged to those samples only:
 * estimated samples / run time, a lower bound (the zeroing and rest before
 * START cost time too). Reported: its median over the repetitions, the
 * time a 1.5 s estimation at 1 kHz takes at that rate, and the peak
 * resident memory. Target: at least 100 000 samples per second here (1.5 s
 * of data in under 15 ms), under 20 MB.
 */
#define _POSIX_C_SOURCE 200809L

#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>

#include "loadid/config.h"
#include "loadid/offline.h"
#include "loadid/pipeline.h"
#include "loadid/urdf.h"

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: bench_pipeline CONFIG RECORDING_DIR [REPETITIONS]\n");
        return 2;
    }
    const int reps = argc > 3 ? atoi(argv[3]) : 20;
    static loadid_config_t cfg;
    loadid_chain_t chain;
    char err[1024];
    loadid_config_default(&cfg);
    if (loadid_config_load(argv[1], &cfg, err, sizeof err, NULL, NULL) != 0 ||
        loadid_urdf_load_file(cfg.robot_urdf, cfg.robot_base_link, cfg.robot_sensor_link, &chain,
                              err, sizeof err) != 0) {
        fprintf(stderr, "bench_pipeline: %s\n", err);
        return 1;
    }
    cfg.duration_s = 1e6; /* everything after START is estimated */
    double *rate = calloc((size_t)(reps > 0 ? reps : 1), sizeof *rate);
    long long samples = 0, used = 0;
    for (int r = 0; r < reps; ++r) {
        loadid_pipeline_t *p = NULL;
        if (loadid_pipeline_create(&cfg, &chain, NULL, 0, &p, err, sizeof err) != 0) {
            fprintf(stderr, "bench_pipeline: %s\n", err);
            return 1;
        }
        const double t0 = now_s();
        if (loadid_offline_run(p, argv[2], NULL, err, sizeof err) != 0) {
            fprintf(stderr, "bench_pipeline: %s\n", err);
            return 1;
        }
        const double dt = now_s() - t0;
        loadid_pipeline_status_t st;
        loadid_pipeline_status(p, &st);
        samples = st.samples_ok, used = st.samples_used;
        rate[r] = (double)st.samples_used / dt;
        loadid_pipeline_destroy(p);
    }
    qsort(rate, (size_t)reps, sizeof *rate, cmp);
    const double med = rate[reps / 2];
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("bench_pipeline: %s, %d methods, signals %d, %d repetitions\n", argv[2],
           cfg.num_methods, cfg.signals, reps);
    printf("  samples per run          %lld (%lld estimated)\n", samples, used);
    printf("  throughput median        %.0f estimated samples/s (min %.0f, max %.0f)\n", med,
           rate[0], rate[reps - 1]);
    printf("  1.5 s estimation at 1 kHz %.2f ms (target < 15 ms, >= 100000 samples/s: %s)\n",
           1500 / med * 1e3, med >= 100000 ? "met" : "NOT met");
    printf("  peak resident memory     %.1f MB (target < 20 MB)\n", ru.ru_maxrss / 1024.0);
    free(rate);
    return 0;
}
