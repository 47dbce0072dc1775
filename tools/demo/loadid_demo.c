/*
 * loadid-demo: the paper's experiment end to end on the simulated robot.
 *   1. loadid-traj's designer: an excitation trajectory for the default
 *      robot (the RX60 of host/config/robots), Monte Carlo then NLopt,
 *      within its joint limits (paper sec. III);
 *   2. loadid-sim's simulator: the robot following it through a servo with
 *      backlash, carrying the paper's load o1 (sec. V.A) on a JR3 with a
 *      distal part, JR3 frames and joint states as a recording;
 *   3. loadidd's pipeline over the recording, exactly as --offline runs it:
 *      zeroing (eqs. 7-9) or the offset model, the configured signal
 *      source, every method on-line (RLS, RIV, RTLS; batch LS and TLS as
 *      references), the distal part subtracted;
 * and prints each method's estimate, the truth and the eq. (37) errors.
 */
#define _XOPEN_SOURCE 700

#include <errno.h>
#include <ftw.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/core.h"
#include "loadid/offline.h"
#include "loadid/pipeline.h"
#include "recording_writer.h"
#include "sim_run.h"
#include "loadid/setup.h"
#include "traj_design.h"

static const char *prog = "loadid-demo";

/* A warning of the configuration (another program's section). */
static void warn_line(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "%s: warning: %s\n", prog, msg);
}

static const char *const kParamNames[10] = {"m", "m*cx", "m*cy", "m*cz", "Ixx",
                                            "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};

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
            "usage: loadid-demo [--seed N] [--offset-model zeroing|estimate]\n"
            "                   [--signals sensor|kf|setpoint|mixed] [--keep DIR [--force]]\n"
            "  Designs an excitation trajectory for the RX60, simulates the paper's load o1\n"
            "  on it (JR3 frames, joint states, servo, backlash, noise, vibration), runs\n"
            "  loadidd's pipeline over the recording and prints every method's estimate\n"
            "  with its eq. (37) error.\n"
            "  --seed N          simulation and search seed (default 1)\n"
            "  --offset-model M  zeroing (eqs. 7-9, default) or estimate (16 parameters)\n"
            "  --signals S       signal source (default kf, as the service)\n"
            "  --keep DIR        write the recording (can.log, lcm.log, truth.yaml) to DIR\n"
            "                    and keep it (default: a temporary folder, removed); DIR\n"
            "                    must not exist or be empty\n"
            "  --force           write into a --keep DIR that holds files (the recording's\n"
            "                    three are overwritten)\n");
}

static void progress(void *ctx, const char *stage, int done, int total, double best) {
    (void)ctx;
    if (done == total) printf("  %-11s %5d candidates, best kappa_design %.4g\n", stage, total, best);
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
    (void)st, (void)flag, (void)ftw;
    return remove(path);
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
    loadid_traj_search_t s = {.monte_carlo = 600, .candidates = 2, .max_evals = 2000,
                              .seed = seed, .optimise_home = 1, .progress = progress};
    loadid_traj_search_result_t res;
    int rc = loadid_traj_design(&p, &s, tr, &res);
    if (rc == 0) *kappa = loadid_traj_kappa(&p, tr, 1000);
    loadid_kin_destroy(kin);
    return rc;
}

static void print_results(const loadid_config_t *cfg, const loadid_pipeline_estimate_t *est,
                          int n) {
    loadid_real_t truth[10];
    for (int i = 0; i < 10; ++i) truth[i] = (loadid_real_t)cfg->sim_load_phi[i];
    int ok[LOADID_MAX_METHODS] = {0};
    double err[LOADID_MAX_METHODS][10], mean[LOADID_MAX_METHODS] = {0};
    for (int m = 0; m < n; ++m) {
        const char *name = loadid_method_name((loadid_method_t)est[m].method);
        if (!est[m].valid) {
            printf("%-9s no estimate: %s\n", name, loadid_strerror(est[m].error));
            continue;
        }
        ok[m] = 1;
        loadid_real_t phi[10], e[10];
        for (int i = 0; i < 10; ++i) phi[i] = (loadid_real_t)est[m].phi[i];
        loadid_relative_error(phi, truth, 10, e); /* eq. (37) */
        for (int i = 0; i < 10; ++i) err[m][i] = (double)e[i], mean[m] += (double)e[i] / 10;
        printf("%-9s %lld samples, condition_number %.3g, sigma_min %.3g, physically consistent: %s\n", name,
               (long long)est[m].samples, est[m].condition_number, est[m].sigma_min,
               est[m].physically_consistent ? "yes" : "no");
        if (cfg->offset_model_estimate)
            printf("          offset [%.3f %.3f %.3f N, %.4f %.4f %.4f Nm] (true %.3f %.3f %.3f, "
                   "%.4f %.4f %.4f)\n",
                   est[m].offset[0], est[m].offset[1], est[m].offset[2], est[m].offset[3],
                   est[m].offset[4], est[m].offset[5], cfg->sim_offset[0], cfg->sim_offset[1],
                   cfg->sim_offset[2], cfg->sim_offset[3], cfg->sim_offset[4], cfg->sim_offset[5]);
    }
    printf("\n%-6s %12s", "param", "truth");
    for (int m = 0; m < n; ++m)
        if (ok[m]) printf(" %11s %6s", loadid_method_name((loadid_method_t)est[m].method), "e[%]");
    printf("\n");
    for (int i = 0; i < 10; ++i) {
        printf("%-6s %12.5g", kParamNames[i], cfg->sim_load_phi[i]);
        for (int m = 0; m < n; ++m)
            if (ok[m]) printf(" %11.5g %6.1f", est[m].phi[i], err[m][i]);
        printf("\n");
    }
    printf("%-6s %12s", "mean", "");
    for (int m = 0; m < n; ++m)
        if (ok[m]) printf(" %11s %6.1f", "", mean[m]);
    printf("\n");
}

int main(int argc, char **argv) {
    unsigned long long seed = 1;
    const char *keep = NULL, *offset_model = "zeroing", *signals = "kf";
    int force = 0;
    static const struct option opts[] = {
        {"help", no_argument, NULL, 'h'},       {"offset-model", required_argument, NULL, 'o'},
        {"seed", required_argument, NULL, 's'}, {"signals", required_argument, NULL, 'g'},
        {"keep", required_argument, NULL, 'k'}, {"force", no_argument, NULL, 'f'},
        {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "ho:s:g:k:", opts, NULL)) != -1) {
        char *end = NULL;
        switch (c) {
            case 'h': usage(stdout); return 0;
            case 'o': offset_model = optarg; break;
            case 'g': signals = optarg; break;
            case 'k': keep = optarg; break;
            case 'f': force = 1; break;
            case 's':
                errno = 0;
                seed = strtoull(optarg, &end, 10);
                if (errno || !end || *end) {
                    fprintf(stderr, "%s: --seed must be an unsigned integer, not '%s'\n", prog, optarg);
                    return 2;
                }
                break;
            default: usage(stderr); return 2;
        }
    }
    if (optind != argc) {
        fprintf(stderr, "%s: unexpected argument '%s'\n", prog, argv[optind]);
        return 2;
    }
    char err[1024];
    if (force && !keep) {
        fprintf(stderr, "%s: --force needs --keep DIR\n", prog);
        return 2;
    }
    if (keep && loadid_recording_dir_check(keep, force, "--force", err, sizeof err) != 0) {
        fprintf(stderr, "%s: --keep %s\n", prog, err);
        return 1;
    }
    static loadid_config_t cfg;
    loadid_chain_t chain;
    char setup_err[1200];
    if (loadid_setup_load(NULL, &cfg, &chain, warn_line, NULL, setup_err,
                          sizeof setup_err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, setup_err);
        return 1;
    }
    loadid_signal_source_t src;
    if (loadid_signal_source_parse(signals, &src) != 0 ||
        (strcmp(offset_model, "zeroing") && strcmp(offset_model, "estimate"))) {
        fprintf(stderr, "%s: --signals is sensor|kf|setpoint|mixed, --offset-model zeroing|estimate\n",
                prog);
        return 2;
    }
    cfg.signals = src;
    cfg.offset_model_estimate = strcmp(offset_model, "estimate") == 0;
    const int methods[] = {LOADID_METHOD_RLS, LOADID_METHOD_RIV, LOADID_METHOD_RTLS,
                           LOADID_METHOD_LS_BATCH, LOADID_METHOD_TLS_BATCH};
    cfg.num_methods = 5;
    memcpy(cfg.methods, methods, sizeof methods);
    distal_phi(cfg.distal_phi);

    printf("loadid demo: the paper's load o1 (sec. V.A) and a distal sensor part on a simulated "
           "RX60, core in %s\n\n1. excitation trajectory (sec. III): %d harmonics of %.2g Hz, "
           "%.2g s active\n",
           loadid_scalar_is_float() ? "float" : "double", cfg.traj_harmonics,
           cfg.traj_base_frequency, cfg.traj_active_s);
    loadid_fourier_traj_t tr;
    double kappa = NAN;
    if (design(&cfg, &chain, seed, &tr, &kappa) != 0) {
        fprintf(stderr, "%s: no trajectory within the limits was found\n", prog);
        return 1;
    }
    printf("  kappa_design %.4g (the weighted data matrix D A T of the setpoints at 1 kHz)\n", kappa);

    char tmp[] = "/tmp/loadid-demo-XXXXXX";
    const char *dir = keep ? keep : mkdtemp(tmp);
    if (!dir) {
        fprintf(stderr, "%s: cannot make a temporary folder: %s\n", prog, strerror(errno));
        return 1;
    }
    loadid_sim_options_t opt = {.cfg = &cfg, .chain = &chain, .traj = &tr, .kappa_design = kappa,
                                .traj_path = "(designed by loadid-demo)", .out_dir = dir,
                                .load_name = "o1", .seed = seed,
                                .start_utime = 1700000000000000LL, .warn = warn_line};
    loadid_damage_init(&opt.damage, seed);
    loadid_sim_summary_t sum;
    int rc = loadid_sim_run(&opt, &sum, err, sizeof err);
    if (rc == 0) {
        printf("\n2. simulated recording%s%s: %lld JR3 samples and joint states at 1 kHz, "
               "%.2f s; noise f %.3g N, tau %.3g Nm, a-g %.3g m/s^2, alpha %.3g rad/s^2; servo "
               "%.3g Hz, backlash %.3g rad, 2^20-count encoders\n",
               keep ? " in " : "", keep ? keep : "", (long long)sum.samples, sum.duration_s,
               cfg.sim_noise_force, cfg.sim_noise_torque, cfg.sim_noise_linear, cfg.sim_noise_angular,
               cfg.sim_servo_bandwidth_hz, cfg.sim_backlash);
        loadid_pipeline_t *p = NULL;
        rc = loadid_pipeline_create(&cfg, &chain, NULL, 0, &p, err, sizeof err);
        if (rc == 0) rc = loadid_offline_run(p, dir, NULL, err, sizeof err);
        if (rc == 0) {
            loadid_pipeline_status_t st;
            loadid_pipeline_status(p, &st);
            printf("\n3. on-line estimation (signals %s, %s): %lld samples after START\n\n",
                   signals, cfg.offset_model_estimate ? "offset estimated, 16 parameters"
                                                      : "zeroing, eqs. 7-9",
                   (long long)st.samples_used);
            if (st.state == LOADID_STATE_FAILED) {
                fprintf(stderr, "%s: estimation failed: %s\n", prog, st.reason);
                rc = -1;
            } else {
                loadid_pipeline_estimate_t est[LOADID_MAX_METHODS];
                print_results(&cfg, est, loadid_pipeline_estimates(p, est, LOADID_MAX_METHODS));
            }
        }
        loadid_pipeline_destroy(p);
    }
    if (rc != 0 && err[0]) fprintf(stderr, "%s: %s\n", prog, err);
    if (!keep) nftw(dir, remove_entry, 8, FTW_DEPTH | FTW_PHYS);
    return rc == 0 ? 0 : 1;
}
