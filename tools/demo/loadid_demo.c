/*
 * loadid-demo: the paper's experiment end to end on the simulated robot,
 * short enough to watch (about 10 s of CPU):
 *   1. loadid-traj's designer: an excitation trajectory for the default
 *      robot (the RX60 of host/config/robots), Monte Carlo then NLopt,
 *      within its joint limits (paper sec. III), with its progress;
 *   2. loadid-sim's simulator, once per seed: the robot following it
 *      through a servo with backlash, carrying the paper's load o1
 *      (sec. V.A) on a JR3 with a distal part, JR3 frames and joint states
 *      as a recording;
 *   3. loadidd's pipeline over each recording, exactly as --offline runs
 *      it, once per signal source (by default the paper's Fig. 6 setting,
 *      the JR3's accelerations, and the service's default, the encoders):
 *      zeroing (eqs. 7-9) or the offset model, RLS, RIV and RTLS on line,
 *      batch LS and TLS and REFINED at the end, the distal part subtracted;
 * and prints how long the estimation took, the eq. (37) errors (median
 * over the seeds) and a verdict per method against the truth and the
 * paper (demo_report.h). With --out it writes runs.csv, the first seed's
 * estimate traces, its recording and configurations, and draws the plots
 * with `loadid plot`.
 */
#define _XOPEN_SOURCE 700

#include <errno.h>
#include <ftw.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "demo_report.h"
#include "loadid/core.h"
#include "loadid/offline.h"
#include "loadid/pipeline.h"
#include "loadid/setup.h"
#include "recording_writer.h"
#include "sim_run.h"
#include "trace_csv.h"
#include "traj_design.h"

static const char *prog = "loadid-demo";

/* A warning of the configuration (another program's section). */
static void warn_line(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "%s: warning: %s\n", prog, msg);
}

/* Every method, in the order of the paper's comparison first. */
static const int kMethods[DEMO_METHODS] = {LOADID_METHOD_RLS,       LOADID_METHOD_RIV,
                                           LOADID_METHOD_RTLS,      LOADID_METHOD_LS_BATCH,
                                           LOADID_METHOD_TLS_BATCH, LOADID_METHOD_REFINED};

/* A distal sensor part: a 0.2 kg disc, 8 mm thick, r = 40 mm, centred
 * 4 mm along z of S. */
static void distal_phi(double phi[10]) {
    const double m = 0.2, r = 0.04, h = 0.008;
    const double ixx = m * (3 * r * r + h * h) / 12.0, izz = m * r * r / 2.0;
    loadid_real_t p[10], c[3] = {0, 0, 0.004}, ic[6] = {(loadid_real_t)ixx, 0, 0,
                                                        (loadid_real_t)ixx, 0, (loadid_real_t)izz};
    loadid_phi_from_physical((loadid_real_t)m, c, ic, p);
    for (int i = 0; i < 10; ++i) phi[i] = (double)p[i];
}

static void usage(FILE *f) {
    fprintf(f,
            "usage: loadid-demo [--seed N] [--seeds N] [--signals S[,S...]]\n"
            "                   [--offset-model zeroing|estimate] [--out DIR [--no-plots]]\n"
            "                   [--keep DIR [--force]]\n"
            "  Designs an excitation trajectory for the RX60, simulates the paper's load o1\n"
            "  on it (JR3 frames, joint states, servo, backlash, noise, vibration) once per\n"
            "  seed, runs loadidd's pipeline over each recording with every method and\n"
            "  signal source, and prints the time it took, the eq. (37) errors (median over\n"
            "  the seeds) and a verdict per method against the truth and the paper.\n"
            "  --seed N          the trajectory search's seed and the first simulation's\n"
            "                    (default 1)\n"
            "  --seeds N         simulations with seeds N, N+1, ... (default 5, at most %d)\n"
            "  --signals S,...   signal sources, each run on every recording (default\n"
            "                    sensor,kf: the paper's Fig. 6 and the service's default)\n"
            "  --offset-model M  zeroing (eqs. 7-9, default) or estimate (16 parameters)\n"
            "  --out DIR         write DIR/runs.csv (every run's estimate and errors), the\n"
            "                    first seed's estimate traces DIR/trace-SOURCE.csv, its\n"
            "                    recording DIR/recording, DIR/truth.yaml, the configuration\n"
            "                    of each source DIR/loadid-SOURCE.yaml, and the plots\n"
            "                    (loadid plot DIR); files there are replaced\n"
            "  --no-plots        with --out: no plots\n"
            "  --keep DIR        keep the first seed's recording (can.log, lcm.log,\n"
            "                    truth.yaml) in DIR, which must not exist or be empty\n"
            "  --force           write into a --keep DIR that holds files (the recording's\n"
            "                    three are overwritten)\n",
            DEMO_MAX_SEEDS);
}

static double now_s(clockid_t clock) {
    struct timespec ts;
    clock_gettime(clock, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* The designer's progress: one line rewritten in place on a terminal,
 * else a line at each quarter of a stage (a log stays short). */
static void progress(void *ctx, const char *stage, int done, int total, double best) {
    (void)ctx;
    static int tty = -1;
    if (tty < 0) tty = isatty(STDOUT_FILENO);
    const int mc = strcmp(stage, "monte-carlo") == 0;
    const char *what = mc ? "random candidates" : "NLopt COBYLA evaluations";
    if (tty) {
        printf("\r   %-11s %5d/%-5d %s, best kappa_design %.4g   ", stage, done, total, what, best);
        if (done == total) putchar('\n');
    } else if (done == total || done % ((total + 3) / 4) == 0) {
        printf("   %-11s %5d/%-5d %s, best kappa_design %.4g\n", stage, done, total, what, best);
    }
    fflush(stdout);
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
    (void)st, (void)flag, (void)ftw;
    return remove(path);
}

static int mkdir_p(const char *dir) {
    char buf[PATH_MAX];
    if (snprintf(buf, sizeof buf, "%s", dir) >= (int)sizeof buf) return -ENAMETOOLONG;
    for (char *p = buf + 1; *p; ++p)
        if (*p == '/') {
            *p = 0;
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -errno;
            *p = '/';
        }
    if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -errno;
    return 0;
}

static int design(const loadid_config_t *cfg, const loadid_chain_t *chain, uint64_t seed,
                  loadid_fourier_traj_t *tr, double *kappa) {
    loadid_kin_t *kin = NULL;
    if (loadid_kin_create(chain, cfg->robot_gravity, &kin) != 0) return -1;
    loadid_traj_problem_t p;
    memset(&p, 0, sizeof p);
    loadid_traj_problem_defaults(&p);
    p.kin = kin;
    p.limits.num_joints = chain->num_joints;
    for (int i = 0; i < chain->num_joints; ++i) {
        p.limits.lower[i] = chain->joints[i].lower;
        p.limits.upper[i] = chain->joints[i].upper;
        p.limits.velocity[i] = chain->joints[i].velocity;
        p.limits.acceleration[i] = cfg->traj_acc_limit[0];
    }
    for (int a = 0; a < 3; ++a) p.limits.ws_min[a] = -1e9, p.limits.ws_max[a] = 1e9;
    p.limits.floor_z = 0.1; /* the sensor stays 10 cm above the robot's base plane */
    const int n_params = cfg->offset_model_estimate ? LOADID_NPHI_OFFSET : LOADID_NPHI;
    loadid_est_config_default(LOADID_METHOD_RLS, n_params, &p.est);
    loadid_setup_weights(cfg, (loadid_signal_source_t)cfg->signals, &p.est);
    p.zeroing = !cfg->offset_model_estimate;
    memset(tr, 0, sizeof *tr);
    tr->num_joints = chain->num_joints;
    tr->harmonics = cfg->traj_harmonics;
    tr->base_frequency = cfg->traj_base_frequency;
    tr->active_s = cfg->traj_active_s;
    tr->fade_s = cfg->traj_fade_s;
    for (int i = 0; i < chain->num_joints; ++i) {
        const double lo = chain->joints[i].lower, hi = chain->joints[i].upper;
        tr->q0[i] = isfinite(hi - lo) ? (lo + hi) / 2 : 0;
    }
    loadid_traj_search_t s = {.monte_carlo = 600,
                              .candidates = 2,
                              .max_evals = 2000,
                              .seed = seed,
                              .optimise_home = 1,
                              .progress = progress};
    loadid_traj_search_result_t res;
    int rc = loadid_traj_design(&p, &s, tr, &res);
    if (rc == 0) *kappa = loadid_traj_kappa(&p, tr, 1000);
    loadid_kin_destroy(kin);
    return rc;
}

/* One estimation run's sinks: the window's times, and the trace. */
typedef struct {
    loadid_trace_csv_t *trace; /* NULL: none */
    double wall0, cpu0, wall, cpu;
} run_ctx_t;

static void on_state(void *ctx, int64_t utime, int state, const char *reason) {
    (void)reason;
    run_ctx_t *c = ctx;
    if (state == LOADID_STATE_ESTIMATING) {
        if (c->trace) loadid_trace_csv_start(c->trace, utime);
        c->wall0 = now_s(CLOCK_MONOTONIC), c->cpu0 = now_s(CLOCK_PROCESS_CPUTIME_ID);
    } else if (state == LOADID_STATE_DONE) {
        c->wall = now_s(CLOCK_MONOTONIC) - c->wall0;
        c->cpu = now_s(CLOCK_PROCESS_CPUTIME_ID) - c->cpu0;
    }
}

static void on_estimate(void *ctx, const loadid_pipeline_estimate_t *e) {
    loadid_trace_csv_row(((run_ctx_t *)ctx)->trace, e);
}

/* Estimates recording dir with cfg (its signal source), into seed j of s;
 * trace_path: the trace's file, or NULL. */
static int estimate(const loadid_config_t *cfg, const loadid_chain_t *chain, const char *dir,
                    const double truth[10], demo_source_t *s, int j, const char *trace_path,
                    char *err, size_t errlen) {
    loadid_trace_csv_t trace;
    run_ctx_t ctx = {.trace = NULL};
    if (trace_path) {
        if (loadid_trace_csv_open(&trace, trace_path, err, errlen) != 0) return -1;
        ctx.trace = &trace;
    }
    loadid_pipeline_sink_t sink = {
        .ctx = &ctx, .state = on_state, .estimate = trace_path ? on_estimate : NULL};
    loadid_pipeline_t *p = NULL;
    loadid_offline_report_t rep;
    const double t0 = now_s(CLOCK_MONOTONIC);
    int rc = loadid_pipeline_create(cfg, chain, &sink, trace_path ? 10 : 0, &p, err, errlen);
    if (rc == 0 && trace_path) {
        loadid_pipeline_std_always(p, 1);
        loadid_pipeline_trace_rows(p, 1);
    }
    if (rc == 0) rc = loadid_offline_run(p, dir, &rep, err, errlen);
    s->run_wall_s[j] = now_s(CLOCK_MONOTONIC) - t0;
    if (rc == 0) {
        loadid_pipeline_status_t st;
        loadid_pipeline_status(p, &st);
        if (st.state == LOADID_STATE_FAILED) {
            snprintf(err, errlen, "estimation failed: %s", st.reason);
            rc = -1;
        } else {
            s->window_wall_s[j] = ctx.wall, s->window_cpu_s[j] = ctx.cpu;
            s->window_samples[j] = st.samples_used;
            s->run_samples[j] = st.samples_ok;
            loadid_pipeline_estimate_t est[LOADID_MAX_METHODS];
            const int n = loadid_pipeline_estimates(p, est, LOADID_MAX_METHODS);
            for (int m = 0; m < n && m < DEMO_METHODS; ++m)
                demo_est_fill(&s->est[j][m], &est[m], truth);
        }
    }
    loadid_pipeline_destroy(p);
    char terr[512];
    if (trace_path && loadid_trace_csv_close(&trace, terr, sizeof terr) != 0 && rc == 0) {
        snprintf(err, errlen, "%s", terr);
        rc = -1;
    }
    return rc;
}

/* dir/loadid-SOURCE.yaml: the configuration the demo estimated with
 * (what it sets; the rest at its defaults), for loadidd --offline and
 * loadid plot on the kept recording. */
static int write_config(const char *dir, const loadid_config_t *cfg, const char *source) {
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/loadid-%s.yaml", dir, source);
    FILE *f = fopen(path, "w");
    if (!f) return -errno;
    fprintf(f,
            "# loadid-demo's configuration for signals %s: the keys below, the rest at their\n"
            "# defaults (host/config/loadid.yaml).\nestimation:\n  methods: [",
            source);
    for (int m = 0; m < DEMO_METHODS; ++m)
        fprintf(f, "%s%s", m ? ", " : "", loadid_method_name((loadid_method_t)kMethods[m]));
    fprintf(f, "]\n  signals: %s\n  offset_model: %s\ndistal:\n  phi: [", source,
            cfg->offset_model_estimate ? "estimate" : "zeroing");
    for (int i = 0; i < 10; ++i) fprintf(f, "%s%.17g", i ? ", " : "", cfg->distal_phi[i]);
    fprintf(f, "]   # the demo's 0.2 kg disc\n");
    return fclose(f) == 0 ? 0 : -errno;
}

static int copy_file(const char *from, const char *to) {
    FILE *in = fopen(from, "rb"), *out = in ? fopen(to, "wb") : NULL;
    char buf[8192];
    size_t n;
    int rc = in && out ? 0 : -errno;
    while (rc == 0 && (n = fread(buf, 1, sizeof buf, in)) > 0)
        if (fwrite(buf, 1, n, out) != n) rc = -EIO;
    if (in) fclose(in);
    if (out && fclose(out) != 0 && rc == 0) rc = -EIO;
    return rc;
}

/* `loadid plot DIR`: the CLI beside this program (the build tree's
 * host/, or the same bin/ when installed). Returns its exit status, or -1
 * when it cannot be found or run. */
static int draw_plots(const char *dir) {
    char self[PATH_MAX], exe[PATH_MAX + 32];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) return -1;
    self[n] = 0;
    char *slash = strrchr(self, '/');
    if (!slash) return -1;
    *slash = 0;
    snprintf(exe, sizeof exe, "%s/../host/loadid", self);
    if (access(exe, X_OK) != 0) snprintf(exe, sizeof exe, "%s/loadid", self);
    if (access(exe, X_OK) != 0) return -1;
    fflush(stdout);
    const pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        execl(exe, exe, "plot", dir, (char *)NULL);
        _exit(127);
    }
    int status;
    if (waitpid(pid, &status, 0) != pid) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static int parse_sources(const char *list, demo_results_t *r) {
    char buf[128];
    snprintf(buf, sizeof buf, "%s", list);
    r->num_sources = 0;
    for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        loadid_signal_source_t src;
        if (loadid_signal_source_parse(t, &src) != 0 || r->num_sources == DEMO_MAX_SOURCES)
            return -1;
        for (int k = 0; k < r->num_sources; ++k)
            if (r->src[k].source == (int)src) return -1;
        r->src[r->num_sources].source = src;
        r->src[r->num_sources++].name = loadid_signal_source_name(src);
    }
    return r->num_sources ? 0 : -1;
}

static const char *source_story(int src) {
    switch (src) {
        case LOADID_SIGNALS_SENSOR:
            return "the paper's Fig. 6: a - g and alpha from the JR3's accelerometer";
        case LOADID_SIGNALS_MIXED:
            return "the paper's Fig. 7: a - g from the JR3, alpha from the joints";
        case LOADID_SIGNALS_KF:
            return "the service's default: a - g, omega, alpha from the joint encoders";
        case LOADID_SIGNALS_SETPOINT:
            return "from the commanded joint setpoints";
        default:
            return "";
    }
}

int main(int argc, char **argv) {
    unsigned long long seed = 1;
    long seeds = 5;
    const char *keep = NULL, *offset_model = "zeroing", *signals = "sensor,kf", *out = NULL;
    int force = 0, plots = 1;
    static const struct option opts[] = {
        {"help", no_argument, NULL, 'h'},        {"offset-model", required_argument, NULL, 'o'},
        {"seed", required_argument, NULL, 's'},  {"signals", required_argument, NULL, 'g'},
        {"keep", required_argument, NULL, 'k'},  {"force", no_argument, NULL, 'f'},
        {"seeds", required_argument, NULL, 'n'}, {"out", required_argument, NULL, 'O'},
        {"no-plots", no_argument, NULL, 'P'},    {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "ho:s:g:k:", opts, NULL)) != -1) {
        char *end = NULL;
        switch (c) {
            case 'h':
                usage(stdout);
                return 0;
            case 'o':
                offset_model = optarg;
                break;
            case 'g':
                signals = optarg;
                break;
            case 'k':
                keep = optarg;
                break;
            case 'f':
                force = 1;
                break;
            case 'O':
                out = optarg;
                break;
            case 'P':
                plots = 0;
                break;
            case 's':
                errno = 0;
                seed = strtoull(optarg, &end, 10);
                if (errno || !end || *end) {
                    fprintf(stderr, "%s: --seed must be an unsigned integer, not '%s'\n", prog,
                            optarg);
                    return 2;
                }
                break;
            case 'n':
                errno = 0;
                seeds = strtol(optarg, &end, 10);
                if (errno || !end || *end || seeds < 1 || seeds > DEMO_MAX_SEEDS) {
                    fprintf(stderr, "%s: --seeds must be 1 to %d, not '%s'\n", prog, DEMO_MAX_SEEDS,
                            optarg);
                    return 2;
                }
                break;
            default:
                usage(stderr);
                return 2;
        }
    }
    if (optind != argc) {
        fprintf(stderr, "%s: unexpected argument '%s'\n", prog, argv[optind]);
        return 2;
    }
    char err[4400];
    if (force && !keep) {
        fprintf(stderr, "%s: --force needs --keep DIR\n", prog);
        return 2;
    }
    if (!plots && !out) {
        fprintf(stderr, "%s: --no-plots needs --out DIR\n", prog);
        return 2;
    }
    if (keep && loadid_recording_dir_check(keep, force, "--force", err, sizeof err) != 0) {
        fprintf(stderr, "%s: --keep %s\n", prog, err);
        return 1;
    }
    static demo_results_t res;
    if (parse_sources(signals, &res) != 0 ||
        (strcmp(offset_model, "zeroing") && strcmp(offset_model, "estimate"))) {
        fprintf(stderr,
                "%s: --signals is a list of sensor, kf, setpoint, mixed (each once), "
                "--offset-model zeroing|estimate\n",
                prog);
        return 2;
    }
    char rec_keep[PATH_MAX] = "";
    if (out) {
        const int rc = mkdir_p(out);
        if (rc != 0) {
            fprintf(stderr, "%s: --out %s: %s\n", prog, out, strerror(-rc));
            return 1;
        }
        snprintf(rec_keep, sizeof rec_keep, "%s/recording", out);
    }
    if (keep) snprintf(rec_keep, sizeof rec_keep, "%s", keep);
    static loadid_config_t cfg;
    loadid_chain_t chain;
    char setup_err[1200];
    if (loadid_setup_load(NULL, &cfg, &chain, warn_line, NULL, setup_err, sizeof setup_err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, setup_err);
        return 1;
    }
    cfg.offset_model_estimate = strcmp(offset_model, "estimate") == 0;
    cfg.num_methods = DEMO_METHODS;
    memcpy(cfg.methods, kMethods, sizeof kMethods);
    memcpy(res.methods, kMethods, sizeof kMethods);
    distal_phi(cfg.distal_phi);
    for (int i = 0; i < 10; ++i) res.truth[i] = cfg.sim_load_phi[i];
    res.first_seed = seed;
    res.seeds = (int)seeds;

    loadid_real_t truth_r[10];
    for (int i = 0; i < 10; ++i) truth_r[i] = (loadid_real_t)res.truth[i];
    loadid_physical_t tp;
    loadid_phi_to_physical(truth_r, &tp);
    printf(
        "loadid demo: Kubus, Kroeger & Wahl (IROS 2008) sec. V in simulation: the paper's load "
        "o1 (%.3g kg, COM [%.1f %.1f %.1f] mm) with a 0.2 kg distal sensor part, on a simulated "
        "Staeubli RX60; core in %s\n\n"
        "1. Excitation trajectory (paper sec. III): %d harmonics of %.2g Hz, %.2g s active, "
        "search seed %llu\n",
        (double)tp.mass, 1e3 * tp.com[0], 1e3 * tp.com[1], 1e3 * tp.com[2],
        loadid_scalar_is_float() ? "float" : "double", cfg.traj_harmonics, cfg.traj_base_frequency,
        cfg.traj_active_s, seed);
    fflush(stdout);
    const double began = now_s(CLOCK_MONOTONIC);
    loadid_fourier_traj_t tr;
    double kappa = NAN;
    if (design(&cfg, &chain, seed, &tr, &kappa) != 0) {
        fprintf(stderr, "%s: no trajectory within the limits was found\n", prog);
        return 1;
    }
    printf(
        "   kappa_design %.4g (dimensionless: the condition number of the noise-weighted data "
        "matrix D A T of the setpoints at 1 kHz; 1 is ideal), in %.1f s\n",
        kappa, now_s(CLOCK_MONOTONIC) - began);

    /* 2 and 3: simulate each seed, estimate it with every source. */
    const double sim0 = now_s(CLOCK_MONOTONIC);
    double sim_s = 0;
    loadid_sim_summary_t sum;
    memset(&sum, 0, sizeof sum);
    int rc = 0;
    for (int j = 0; j < res.seeds && rc == 0; ++j) {
        const uint64_t sd = seed + (uint64_t)j;
        char tmp[] = "/tmp/loadid-demo-XXXXXX";
        const int kept = j == 0 && rec_keep[0];
        const char *dir = kept ? rec_keep : mkdtemp(tmp);
        if (!dir) {
            fprintf(stderr, "%s: cannot make a temporary folder: %s\n", prog, strerror(errno));
            return 1;
        }
        loadid_sim_options_t opt = {.cfg = &cfg,
                                    .chain = &chain,
                                    .traj = &tr,
                                    .kappa_design = kappa,
                                    .traj_path = "(designed by loadid-demo)",
                                    .out_dir = dir,
                                    .load_name = "o1",
                                    .seed = sd,
                                    .start_utime = 1700000000000000LL,
                                    .warn = warn_line};
        loadid_damage_init(&opt.damage, sd);
        const double s0 = now_s(CLOCK_MONOTONIC);
        rc = loadid_sim_run(&opt, &sum, err, sizeof err);
        sim_s += now_s(CLOCK_MONOTONIC) - s0;
        for (int k = 0; k < res.num_sources && rc == 0; ++k) {
            loadid_config_t run = cfg;
            run.signals = res.src[k].source;
            char trace[PATH_MAX] = "";
            if (out && j == 0)
                snprintf(trace, sizeof trace, "%s/trace-%s.csv", out, res.src[k].name);
            res.src[k].traced[j] = trace[0] != 0;
            rc = estimate(&run, &chain, dir, res.truth, &res.src[k], j, trace[0] ? trace : NULL,
                          err, sizeof err);
        }
        if (rc == 0 && out && j == 0) {
            char from[PATH_MAX + 16], to[PATH_MAX + 16];
            snprintf(from, sizeof from, "%s/truth.yaml", dir);
            snprintf(to, sizeof to, "%s/truth.yaml", out);
            rc = copy_file(from, to);
            if (rc != 0) snprintf(err, sizeof err, "cannot write %s: %s", to, strerror(-rc));
        }
        if (!kept) nftw(dir, remove_entry, 8, FTW_DEPTH | FTW_PHYS);
    }
    if (rc != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    const double est_s = now_s(CLOCK_MONOTONIC) - sim0 - sim_s;
    printf(
        "\n2. Simulated recordings, seeds %llu to %llu (the same trajectory; the noise, "
        "vibration and backlash draws differ), in %.1f s: each %lld JR3 samples and joint "
        "states at 1 kHz over %.2f s (still, ZERO, START, the 1.5 s window, still); noise "
        "(1 sigma) f %.3g N, tau %.3g N m, a - g %.3g m/s^2, alpha %.3g rad/s^2; servo %.3g "
        "Hz, backlash %.3g mrad, 2^20-count encoders%s%s\n",
        seed, seed + (unsigned long long)res.seeds - 1, sim_s, (long long)sum.samples,
        sum.duration_s, cfg.sim_noise_force, cfg.sim_noise_torque, cfg.sim_noise_linear,
        cfg.sim_noise_angular, cfg.sim_servo_bandwidth_hz, 1e3 * cfg.sim_backlash,
        rec_keep[0] ? "; the first kept in " : "", rec_keep);
    printf(
        "\n3. Estimation by the service's pipeline (as loadidd --offline; %s): RLS, RIV and "
        "RTLS on line, LS_BATCH, TLS_BATCH and REFINED at the window's end; %d runs in %.2f s "
        "wall\n",
        cfg.offset_model_estimate ? "the offset estimated, 16 parameters" : "zeroing, eqs. 7-9",
        res.seeds * res.num_sources, est_s);
    demo_print_timing(stdout, &res);
    const demo_est_t *rt = &res.src[0].est[0][2];
    if (rt->valid)
        printf(
            "   %s, seed %llu, RTLS: condition_number %.3g (dimensionless, of the weighted data "
            "D A T), sigma_min %.4g (dimensionless: the noise-weighted misfit; %.2f times "
            "sqrt(6 x %lld), what the noise levels explain)\n",
            res.src[0].name, seed, rt->condition_number, rt->sigma_min,
            rt->sigma_min / sqrt(6.0 * (double)rt->samples), (long long)rt->samples);

    for (int k = 0; k < res.num_sources; ++k) {
        printf(
            "\n%d. Signals %s (%s): eq. (37) error |estimate - truth| / |truth| [%%], median "
            "over the %d seeds\n",
            4 + k, res.src[k].name, source_story(res.src[k].source), res.seeds);
        demo_print_table(stdout, &res, k);
        printf(
            "   Verdicts against the truth (medians over the seeds; usable: within 1 %% of the "
            "mass, 2 mm of the COM and 15 %% of the inertia about the COM) and against the paper "
            "(\"better on p/10 parameters (q/N runs)\": a lower median error on p parameters, a "
            "lower mean of the ten in q runs):\n");
        demo_print_verdicts(stdout, &res, k);
        printf(
            "   What each method claimed (identified in its load model, runs with an estimate) "
            "and why not:\n");
        demo_print_claims(stdout, &res, k);
    }
    if (!out) {
        printf("\nNo plots without --out DIR (bash tools/setup.sh demo writes build/demo).\n");
        return 0;
    }
    for (int k = 0; k < res.num_sources && rc == 0; ++k)
        rc = write_config(out, &cfg, res.src[k].name);
    if (rc == 0) rc = demo_write_runs(out, &res);
    if (rc != 0) {
        fprintf(stderr, "%s: cannot write into %s: %s\n", prog, out, strerror(-rc));
        return 1;
    }
    printf(
        "\nWritten to %s: runs.csv (every run's estimate and errors), trace-SOURCE.csv (seed "
        "%llu's estimates over the window), recording/ with truth.yaml, loadid-SOURCE.yaml (the "
        "configuration of each source: loadid plot --config %s/loadid-%s.yaml %s)\n",
        out, seed, out, res.src[0].name, rec_keep);
    if (!plots) return 0;
    printf("\nPlots (loadid plot %s):\n", out);
    const int prc = draw_plots(out);
    if (prc != 0)
        printf(
            "   not drawn: loadid plot %s (its message above; it needs Python with "
            "matplotlib: bash tools/setup.sh deps)\n",
            prc < 0 ? "was not found beside loadid-demo" : "failed");
    return 0;
}
