/*
 * loadid-traj: designs an excitation trajectory for the configured robot
 * (paper sec. III): Fourier series (eqs. 10-11) with polynomial fades
 * (eqs. 14-15), minimising the condition number of the estimator's
 * weighted data matrix from setpoint kinematics, within the joint limits
 * and the workspace. Writes the trajectory file (YAML) and the 1 kHz
 * setpoint samples (CSV), and reports kappa_design.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "loadid/config.h"
#include "loadid/core.h"
#include "loadid/setup.h"
#include "traj_design.h"
#include "traj_file.h"

static const char *prog = "loadid-traj";

/* A warning of the configuration (another program's section). */
static void warn_line(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "%s: warning: %s\n", prog, msg);
}

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s [--config FILE] [--out TRAJ.yaml] [--setpoints FILE.csv]\n"
            "                   [--seed N] [--monte-carlo N] [--candidates N] [--max-evals N]\n"
            "                   [--quiet]\n"
            "Designs an excitation trajectory (Kubus et al. 2008, sec. III) for the robot\n"
            "of the configuration (robot.*, trajectory.*, noise.*, estimation.offset_model;\n"
            "defaults without --config: the shipped RX60). Writes the trajectory as YAML\n"
            "(--out, default stdout) and the 1 kHz setpoints as CSV (--setpoints), and\n"
            "prints kappa_design, the condition number of the estimator's data matrix\n"
            "from the setpoints over the active part, weighted with noise.* (D A T), on\n"
            "stderr. Options override trajectory.*.\n",
            prog);
}

/* Progress on stderr: one line rewritten in place on a terminal, else a
 * line per quarter of each stage (logs stay short). */
static void progress(void *ctx, const char *stage, int done, int total, double best) {
    if (*(int *)ctx) return;
    static int tty = -1;
    if (tty < 0) tty = isatty(STDERR_FILENO);
    if (tty) {
        fprintf(stderr, "\r%s: %-11s %5d/%-5d best kappa %.4g   ", prog, stage, done, total, best);
        if (done == total) fputc('\n', stderr);
    } else if (done == total || done % ((total + 3) / 4) == 0) {
        fprintf(stderr, "%s: %s %d/%d, best kappa %.4g\n", prog, stage, done, total, best);
    }
}

/* Limits of the problem: the URDF's position and velocity limits (scaled),
 * the configured accelerations and workspace. */
static void make_limits(const loadid_config_t *cfg, const loadid_chain_t *chain,
                        loadid_traj_limits_t *L) {
    memset(L, 0, sizeof *L);
    L->num_joints = chain->num_joints;
    for (int i = 0; i < chain->num_joints; ++i) {
        L->lower[i] = chain->joints[i].lower;
        L->upper[i] = chain->joints[i].upper;
        L->velocity[i] = chain->joints[i].velocity * cfg->traj_vel_scale;
        L->acceleration[i] =
            cfg->traj_num_acc_limits ? cfg->traj_acc_limit[i] : cfg->traj_acc_limit[0];
    }
    memcpy(L->ws_min, cfg->traj_workspace_min, sizeof L->ws_min);
    memcpy(L->ws_max, cfg->traj_workspace_max, sizeof L->ws_max);
    L->floor_z = cfg->traj_floor_z + cfg->traj_floor_clearance;
}

static int parse_count(const char *s, long lo, long hi, long *out) {
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || *end || end == s || v < lo || v > hi) return -1;
    *out = v;
    return 0;
}

int main(int argc, char **argv) {
    const char *config_path = NULL, *out_path = NULL, *setpoints_path = NULL;
    long seed = -1, mc = -1, cand = -1, evals = -1;
    int quiet = 0;
    static const struct option opts[] = {{"config", required_argument, NULL, 'c'},
                                         {"out", required_argument, NULL, 'o'},
                                         {"setpoints", required_argument, NULL, 's'},
                                         {"seed", required_argument, NULL, 'S'},
                                         {"monte-carlo", required_argument, NULL, 'm'},
                                         {"candidates", required_argument, NULL, 'n'},
                                         {"max-evals", required_argument, NULL, 'e'},
                                         {"quiet", no_argument, NULL, 'q'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    int c, which = 0;
    while ((c = getopt_long(argc, argv, "c:o:s:qh", opts, &which)) != -1) {
        int bad = 0;
        switch (c) {
            case 'c':
                config_path = optarg;
                break;
            case 'o':
                out_path = optarg;
                break;
            case 's':
                setpoints_path = optarg;
                break;
            case 'S':
                bad = parse_count(optarg, 0, 2147483647L, &seed);
                break;
            case 'm':
                bad = parse_count(optarg, 1, 10000000L, &mc);
                break;
            case 'n':
                bad = parse_count(optarg, 1, 1000, &cand);
                break;
            case 'e':
                bad = parse_count(optarg, 0, 10000000L, &evals);
                break;
            case 'q':
                quiet = 1;
                break;
            case 'h':
                usage(stdout);
                return 0;
            default:
                usage(stderr);
                return 2;
        }
        if (bad) {
            fprintf(stderr, "%s: --%s: not a valid count: %s\n", prog, opts[which].name, optarg);
            return 2;
        }
    }
    if (optind != argc) {
        usage(stderr);
        return 2;
    }

    loadid_config_t cfg;
    loadid_chain_t chain;
    char setup_err[1200];
    if (loadid_setup_load(config_path, &cfg, &chain, warn_line, NULL, setup_err,
                          sizeof setup_err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, setup_err);
        return 1;
    }
    if (seed >= 0) cfg.traj_seed = (uint64_t)seed;
    if (mc > 0) cfg.traj_monte_carlo = (int)mc;
    if (cand > 0) cfg.traj_candidates = (int)cand;
    if (evals >= 0) cfg.traj_max_evals = (int)evals;
    const int n = chain.num_joints;
    if (cfg.traj_num_acc_limits && cfg.traj_num_acc_limits != n) {
        fprintf(stderr, "%s: trajectory.acc_limit has %d values, the robot %d joints\n", prog,
                cfg.traj_num_acc_limits, n);
        return 1;
    }

    loadid_kin_t *kin = NULL;
    if (loadid_kin_create(&chain, cfg.robot_gravity, &kin) != 0) {
        fprintf(stderr, "%s: cannot build the kinematics of %s\n", prog, cfg.robot_urdf);
        return 1;
    }
    loadid_traj_problem_t p;
    memset(&p, 0, sizeof p);
    loadid_traj_problem_defaults(&p);
    p.kin = kin;
    make_limits(&cfg, &chain, &p.limits);
    const int n_params = cfg.offset_model_estimate ? LOADID_NPHI_OFFSET : LOADID_NPHI;
    loadid_est_config_default(LOADID_METHOD_RLS, n_params, &p.est);
    /* Column scaling by the JR3's noise levels (the sensor source's), as
     * loadid-kappa --weighted reports it. */
    if (loadid_setup_weights(&cfg, LOADID_SIGNALS_SENSOR, &p.est) != 0) {
        fprintf(stderr, "%s: noise levels must be finite and > 0\n", prog);
        return 1;
    }
    p.zeroing = !cfg.offset_model_estimate;

    loadid_fourier_traj_t tr;
    memset(&tr, 0, sizeof tr);
    tr.num_joints = n;
    tr.harmonics = cfg.traj_harmonics;
    tr.base_frequency = cfg.traj_base_frequency;
    tr.active_s = cfg.traj_active_s;
    tr.fade_s = cfg.traj_fade_s;
    for (int i = 0; i < n; ++i) {
        const double lo = chain.joints[i].lower, hi = chain.joints[i].upper;
        tr.q0[i] = cfg.traj_has_home ? cfg.traj_home[i] : (isfinite(hi - lo) ? (lo + hi) / 2 : 0);
    }
    loadid_traj_search_t search = {
        .monte_carlo = cfg.traj_monte_carlo,
        .candidates = cfg.traj_candidates,
        .max_evals = cfg.traj_max_evals,
        .seed = cfg.traj_seed,
        .optimise_home = !cfg.traj_has_home,
        .progress = progress,
        .progress_ctx = &quiet,
    };
    loadid_traj_search_result_t res;
    int rc = loadid_traj_design(&p, &search, &tr, &res);
    if (rc == -ERANGE) {
        fprintf(stderr,
                "%s: no trajectory within the limits found (%d Monte Carlo candidates); "
                "check trajectory.home, the workspace and the limits\n",
                prog, cfg.traj_monte_carlo);
        return 1;
    }
    if (rc != 0) {
        fprintf(stderr, "%s: design failed: %s\n", prog, loadid_strerror(rc));
        return 1;
    }
    const double kappa_design = loadid_traj_kappa(&p, &tr, 1000);
    loadid_traj_problem_t plain = p; /* the same data matrix without weights */
    loadid_est_config_default(LOADID_METHOD_RLS, n_params, &plain.est);
    loadid_traj_file_info_t info = {cfg.robot_urdf,
                                    cfg.robot_base_link,
                                    cfg.robot_sensor_link,
                                    &chain,
                                    kappa_design,
                                    res.kappa_monte_carlo,
                                    loadid_traj_kappa(&plain, &tr, 1000),
                                    cfg.traj_seed};
    FILE *out = out_path ? fopen(out_path, "w") : stdout;
    if (!out || loadid_traj_file_write(out, &tr, &p.limits, &info) != 0 ||
        (out_path && fclose(out) != 0)) {
        fprintf(stderr, "%s: cannot write %s: %s\n", prog, out_path ? out_path : "stdout",
                strerror(errno));
        return 1;
    }
    if (setpoints_path) {
        FILE *sp = fopen(setpoints_path, "w");
        if (!sp || loadid_traj_setpoints_write(sp, &tr, 1000) != 0 || fclose(sp) != 0) {
            fprintf(stderr, "%s: cannot write %s: %s\n", prog, setpoints_path, strerror(errno));
            return 1;
        }
    }
    fprintf(stderr,
            "%s: kappa_design %.4g (Monte Carlo start %.4g, %d of %d candidates within the limits, "
            "%d evaluations)\n",
            prog, kappa_design, res.kappa_monte_carlo, res.feasible_candidates,
            cfg.traj_monte_carlo, res.evaluations);
    loadid_kin_destroy(kin);
    return 0;
}
