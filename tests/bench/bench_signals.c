/*
 * bench_signals: per-sample cost of the joint side of the pipeline, for
 * each robot given (URDF files whose chain runs base_link -> ft_sensor;
 * default the shipped 6-joint RX60 and the 7-joint test robot), printed as
 * a table (a benchmark: exits 0 whatever the figures, non-zero only when it
 * cannot set up).
 *
 * One step, as the daemon runs it at 1 kHz: a joint state (measured and
 * commanded positions) into both Kalman filter banks, then the sensor
 * sample 0.3 ms later: both filter banks evaluated at its time, forward
 * kinematics of the measured and of the commanded joints, the MIXED
 * source's regressor input and RIV's instruments. Also timed alone: the
 * forward kinematics (one evaluation), and one filter bank update.
 * The joints follow multi-sine trajectories (highest harmonic 2 Hz),
 * quantised to 2^20 counts per revolution; everything is prepared before
 * the clock runs. Each call is timed with CLOCK_MONOTONIC; median, 99th
 * percentile and max over all calls. Target: step median <= 5 us.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "loadid/core.h"
#include "loadid/urdf.h"

#define SAMPLES 3000 /* 3 s at 1 kHz */
#define REPS 20
static const double kTargetStepUs = 5.0;
static const double kGravity[3] = {0, 0, -9.81};
static const double kPi = 3.14159265358979323846;

static double now_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e6 + ts.tv_nsec * 1e-3;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void report(const char *robot, const char *what, double *t, size_t n) {
    qsort(t, n, sizeof *t, cmp_double);
    printf("%-10s %-34s %8.3f %8.3f %8.2f\n", robot, what, t[n / 2], t[(size_t)(0.99 * n)],
           t[n - 1]);
}

/* Joint j at time t [s]: a sum of three sines up to 2 Hz, quantised. */
static double joint_pos(int j, double t, int quantise) {
    const double f[3] = {0.5, 1.2, 2.0}, amp[3] = {0.4, 0.15, 0.05};
    double q = 0.1 * j;
    for (int k = 0; k < 3; ++k) q += amp[k] * sin(2 * kPi * f[k] * t + 0.7 * j + k);
    if (!quantise) return q;
    const double step = 2 * kPi / (1 << 20);
    return round(q / step) * step;
}

static int bench_robot(const char *path) {
    loadid_chain_t chain;
    char err[256];
    int rc = loadid_urdf_load_file(path, "base_link", "ft_sensor", &chain, err, sizeof err);
    if (rc != 0) {
        fprintf(stderr, "bench_signals: %s\n", err);
        return 1;
    }
    const int n = chain.num_joints;
    const char *slash = strrchr(path, '/');
    char robot[32];
    const char *base = slash ? slash + 1 : path, *dot = strchr(base, '.');
    snprintf(robot, sizeof robot, "%.*s/%dj", dot ? (int)(dot - base) : 20, base, n);

    loadid_signals_config_t cfg;
    loadid_signals_config_default(&cfg);
    loadid_signals_t *s = NULL;
    loadid_kin_t *kin = NULL;
    loadid_jf_t *jf = NULL;
    if (loadid_signals_create(&chain, kGravity, &cfg, &s) != 0 ||
        loadid_kin_create(&chain, kGravity, &kin) != 0 ||
        loadid_jf_create(n, &cfg.measured, &jf) != 0) {
        fprintf(stderr, "bench_signals: cannot create the pipeline for %s\n", path);
        return 1;
    }
    static loadid_real_t pos[SAMPLES][LOADID_MAX_JOINTS], set[SAMPLES][LOADID_MAX_JOINTS];
    for (int k = 0; k < SAMPLES; ++k)
        for (int j = 0; j < n; ++j) {
            pos[k][j] = joint_pos(j, k * 1e-3, 1);
            set[k][j] = joint_pos(j, k * 1e-3 + 0.002, 0); /* servo lag of 2 ms */
        }
    const size_t calls = (size_t)SAMPLES * REPS;
    double *t_step = malloc(calls * sizeof *t_step), *t_fk = malloc(calls * sizeof *t_fk),
           *t_jf = malloc(calls * sizeof *t_jf);
    if (!t_step || !t_fk || !t_jf) return 1;
    const loadid_real_t jr3_spec[3] = {0.1, 0.2, 9.8};
    loadid_regressor_input_t m, instr;
    double sink = 0;
    /* After a reset the filters serve no sample until settled (the daemon
     * refuses those samples as stale): not timed, and no failure. */
    const int settle = loadid_jf_settle_steps(jf);
    size_t i = 0;
    for (int r = 0; r < REPS; ++r) {
        loadid_signals_reset(s);
        loadid_jf_reset(jf);
        for (int k = 0; k < SAMPLES; ++k) {
            int64_t t = (int64_t)r * 10000000 + (int64_t)k * 1000;
            double t0 = now_us();
            int e1 = loadid_signals_push_joints(s, t, n, pos[k], set[k]);
            int e2 = loadid_signals_at(s, t + 300, jr3_spec, NULL, NULL, &m, &instr);
            double t1 = now_us();
            if (e1 == 0 && e2 == LOADID_E_STALE && k <= settle) {
                loadid_jf_update(jf, t, pos[k]);
                continue;
            }
            if (e1 != 0 || e2 != 0) {
                fprintf(stderr, "bench_signals: step failed: %s\n", loadid_strerror(e1 ? e1 : e2));
                return 1;
            }
            loadid_kin_state_t st;
            double t2 = now_us();
            loadid_kin_eval(kin, pos[k], set[k], set[k], &st);
            double t3 = now_us();
            loadid_jf_update(jf, t, pos[k]);
            double t4 = now_us();
            t_step[i] = t1 - t0, t_fk[i] = t3 - t2, t_jf[i] = t4 - t3;
            ++i;
            sink += m.alpha[0] + instr.spec[2] + st.spec[0];
        }
    }
    const size_t served = i;
    if (served == 0) {
        fprintf(stderr, "bench_signals: no sample served\n");
        return 1;
    }
    report(robot, "step: 2 filter banks + 2 FK + select", t_step, served);
    report(robot, "forward kinematics alone", t_fk, served);
    report(robot, "one filter bank update alone", t_jf, served);
    qsort(t_step, served, sizeof *t_step, cmp_double);
    printf(
        "%-10s target step median <= %.0f us: %s (%zu of %zu steps served, the first %d after "
        "each reset settling; checksum %.3g)\n",
        robot, kTargetStepUs, t_step[served / 2] <= kTargetStepUs ? "met" : "NOT met", served,
        calls, settle, sink);
    free(t_step), free(t_fk), free(t_jf);
    loadid_signals_destroy(s);
    loadid_kin_destroy(kin);
    loadid_jf_destroy(jf);
    return 0;
}

int main(int argc, char **argv) {
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printf(
            "usage: bench_signals [URDF...]\n"
            "Times the joint side of the pipeline per sample (Kalman filter banks, forward\n"
            "kinematics, the signal sources) for each robot given (chains base_link ->\n"
            "ft_sensor; default the RX60 and the 7-joint test robot) and prints a table.\n");
        return 0;
    }
    for (int i = 1; i < argc; ++i)
        if (argv[i][0] == '-') {
            fprintf(stderr, "usage: bench_signals [URDF...] (see --help)\n");
            return 2;
        }
    const char *defaults[] = {LOADID_SOURCE_DIR "/host/config/robots/rx60.urdf",
                              LOADID_SOURCE_DIR "/tests/data/urdf/track7.urdf"};
    const char **robots = argc > 1 ? (const char **)argv + 1 : defaults;
    int count = argc > 1 ? argc - 1 : 2;
    printf("bench_signals: %d samples x %d repetitions per robot, scalar %s\n", SAMPLES, REPS,
           loadid_scalar_is_float() ? "float" : "double");
    printf("%-10s %-34s %8s %8s %8s\n", "robot", "per call [us]", "median", "p99", "max");
    for (int i = 0; i < count; ++i)
        if (bench_robot(robots[i]) != 0) return 1;
    return 0;
}
