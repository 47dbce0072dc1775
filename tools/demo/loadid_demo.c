/*
 * loadid-demo: the paper's experiment on synthetic data. The load o1
 * (section V.A) on a 1.5 s multi-sine trajectory sampled at 1 kHz, with
 * noise in the wrench and in the accelerations and angular velocity, a
 * sensor offset removed by zeroing (eqs. 7-9) or estimated (16 parameters),
 * and a distal sensor part subtracted. Every method estimates on-line; the
 * demo prints each estimate, the truth and the eq. (37) error.
 */
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/core.h"
#include "loadid_synth.h"

#define NMETHODS 5

static const double kServoLag = 0.008; /* [s] actual motion behind the setpoint */

static const char *const kParamNames[10] = {"m", "m*cx", "m*cy", "m*cz", "Ixx",
                                            "Ixy", "Ixz", "Iyy", "Iyz", "Izz"};

/* A distal sensor part: 0.2 kg disc, 8 mm thick, r = 40 mm, centred 4 mm
 * along z of S. */
static void distal_phi(double phi[10]) {
    const double m = 0.2, r = 0.04, h = 0.008;
    const double ixx = m * (3 * r * r + h * h) / 12.0, izz = m * r * r / 2.0;
    const double c[3] = {0, 0, 0.004};
    const double icom[6] = {ixx, 0, 0, ixx, 0, izz};
    loadid_real_t p[10], cc[3] = {c[0], c[1], c[2]}, ic[6];
    for (int i = 0; i < 6; ++i) ic[i] = (loadid_real_t)icom[i];
    loadid_phi_from_physical((loadid_real_t)m, cc, ic, p);
    for (int i = 0; i < 10; ++i) phi[i] = p[i];
}

static void usage(FILE *f) {
    fprintf(f,
            "usage: loadid-demo [--seed N] [--samples N] [--offset-model zeroing|estimate]\n"
            "  Simulates the paper's load o1 on an optimised-style multi-sine trajectory and\n"
            "  estimates it on-line with RLS, RIV, RTLS (and batch LS, TLS as references).\n"
            "  --seed N          noise and trajectory seed (default 1)\n"
            "  --samples N       samples at 1 kHz (default 1500: the paper's 1.5 s)\n"
            "  --offset-model M  zeroing (eqs. 7-9, default) or estimate (16 parameters)\n");
}

int main(int argc, char **argv) {
    unsigned long long seed = 1;
    long samples = 1500;
    int n_params = LOADID_NPHI;
    static const struct option opts[] = {
        {"help", no_argument, NULL, 'h'},
        {"offset-model", required_argument, NULL, 'o'},
        {"samples", required_argument, NULL, 'n'},
        {"seed", required_argument, NULL, 's'},
        {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "hn:o:s:", opts, NULL)) != -1) {
        char *end = NULL;
        switch (c) {
            case 'h': usage(stdout); return 0;
            case 'n':
                errno = 0;
                samples = strtol(optarg, &end, 10);
                if (errno || !end || *end || samples < 10 || samples > 100000) {
                    fprintf(stderr, "loadid-demo: --samples must be 10..100000, not '%s'\n", optarg);
                    return 2;
                }
                break;
            case 'o':
                if (!strcmp(optarg, "zeroing")) n_params = LOADID_NPHI;
                else if (!strcmp(optarg, "estimate")) n_params = LOADID_NPHI_OFFSET;
                else {
                    fprintf(stderr, "loadid-demo: --offset-model is zeroing or estimate, not '%s'\n", optarg);
                    return 2;
                }
                break;
            case 's':
                errno = 0;
                seed = strtoull(optarg, &end, 10);
                if (errno || !end || *end) {
                    fprintf(stderr, "loadid-demo: --seed must be an unsigned integer, not '%s'\n", optarg);
                    return 2;
                }
                break;
            default: usage(stderr); return 2;
        }
    }
    if (optind != argc) {
        fprintf(stderr, "loadid-demo: unexpected argument '%s'\n", argv[optind]);
        return 2;
    }

    loadid_synth_traj_t traj;
    loadid_synth_traj_default(&traj, seed);
    double phi_load[10], phi_distal[10], phi_total[10];
    memcpy(phi_load, loadid_synth_phi_o1, sizeof phi_load);
    distal_phi(phi_distal);
    for (int i = 0; i < 10; ++i) phi_total[i] = phi_load[i] + phi_distal[i];
    /* JR3-like force-torque noise; accelerometer and filter signals much
     * noisier relative to their range (paper sections I, IV.A). */
    const loadid_synth_noise_t noise = {
        .sigma_f = 0.1, .sigma_tau = 0.005, .sigma_spec = 0.5, .sigma_alpha = 5.0, .sigma_omega = 0.02,
        .offset = {2.0, -1.5, 3.0, 0.08, -0.05, 0.03},
    };
    loadid_rng_t rng;
    loadid_rng_seed(&rng, seed * 7919u + 17u);

    const loadid_method_t methods[NMETHODS] = {LOADID_METHOD_RLS, LOADID_METHOD_RIV, LOADID_METHOD_RTLS,
                                               LOADID_METHOD_LS_BATCH, LOADID_METHOD_TLS_BATCH};
    loadid_est_t *est[NMETHODS] = {0};
    for (int k = 0; k < NMETHODS; ++k) {
        loadid_est_config_t cfg;
        loadid_est_config_default(methods[k], n_params, &cfg);
        loadid_est_weights_from_noise(&cfg, noise.sigma_f, noise.sigma_tau, noise.sigma_spec,
                                      noise.sigma_alpha, noise.sigma_omega, 2.0);
        cfg.batch_capacity = (int)samples;
        int rc = loadid_est_create(&cfg, &est[k]);
        if (rc) {
            fprintf(stderr, "loadid-demo: cannot create %s: %s\n", loadid_method_name(methods[k]), loadid_strerror(rc));
            return 1;
        }
    }

    /* Zeroing (n = 10): average the wrench 0.2 s in the still start pose;
     * g_init is gravity in S there (eq. 7). */
    double zero[6] = {0};
    loadid_real_t g_init[3];
    loadid_synth_sample_t s;
    const int zero_n = 200;
    for (int k = 0; k < zero_n; ++k) {
        loadid_synth_sample(&traj, phi_total, 0.0, 1, &noise, &rng, &s);
        for (int i = 0; i < 6; ++i) zero[i] += s.wrench_meas[i] / zero_n;
    }
    for (int i = 0; i < 3; ++i) g_init[i] = (loadid_real_t)s.truth.g[i];

    long skipped = 0;
    for (long k = 0; k < samples; ++k) {
        loadid_synth_sample(&traj, phi_total, (double)k * 1e-3, 0, &noise, &rng, &s);
        /* RIV instruments: setpoint kinematics, noise-free but leading the
         * actual motion by the servo lag (paper IV.A: setpoints deviate). */
        loadid_motion_t setpoint;
        loadid_synth_motion(&traj, (double)k * 1e-3 + kServoLag, 0, &setpoint);
        loadid_real_t spec[3], w[3], al[3], ts[3], tw[3], ta[3], y[6];
        for (int i = 0; i < 3; ++i) {
            spec[i] = (loadid_real_t)s.meas.spec[i];
            w[i] = (loadid_real_t)s.meas.omega[i];
            al[i] = (loadid_real_t)s.meas.alpha[i];
            ts[i] = (loadid_real_t)setpoint.spec[i];
            tw[i] = (loadid_real_t)setpoint.omega[i];
            ta[i] = (loadid_real_t)setpoint.alpha[i];
        }
        loadid_real_t A10[60], C10[60], A[96], C[96];
        loadid_regressor(spec, w, al, A10);
        loadid_regressor(ts, tw, ta, C10);
        if (n_params == LOADID_NPHI) {
            loadid_regressor_add_zeroing(g_init, A10);
            loadid_regressor_add_zeroing(g_init, C10);
            memcpy(A, A10, sizeof A10);
            memcpy(C, C10, sizeof C10);
            for (int i = 0; i < 6; ++i) y[i] = (loadid_real_t)(s.wrench_meas[i] - zero[i]);
        } else {
            loadid_regressor_with_offset(A10, A);
            loadid_regressor_with_offset(C10, C);
            for (int i = 0; i < 6; ++i) y[i] = (loadid_real_t)s.wrench_meas[i];
        }
        for (int m = 0; m < NMETHODS; ++m)
            if (loadid_est_update(est[m], A, C, y) != 0) ++skipped;
    }

    printf("loadid demo: load o1 (paper V.A) + distal sensor part, %ld samples at 1 kHz, seed %llu, %s, core in %s\n",
           samples, seed, n_params == LOADID_NPHI ? "zeroing (eqs. 7-9)" : "offset estimated (16 parameters)",
           loadid_scalar_is_float() ? "float" : "double");
    printf("noise: f %.3g N, tau %.3g Nm, a-g %.3g m/s^2, alpha %.3g rad/s^2, w %.3g rad/s\n\n", noise.sigma_f,
           noise.sigma_tau, noise.sigma_spec, noise.sigma_alpha, noise.sigma_omega);
    double est_phi[NMETHODS][10];
    double mean_err[NMETHODS] = {0};
    int ok[NMETHODS] = {0};
    for (int m = 0; m < NMETHODS; ++m) {
        loadid_real_t phi[LOADID_MAX_PARAMS], load[10], distal[10], err[10], truth[10];
        loadid_est_info_t info;
        int rc = loadid_est_estimate(est[m], phi, &info);
        if (rc) {
            printf("%-9s no estimate: %s\n", loadid_method_name(methods[m]), loadid_strerror(rc));
            continue;
        }
        for (int i = 0; i < 10; ++i) {
            distal[i] = (loadid_real_t)phi_distal[i];
            truth[i] = (loadid_real_t)phi_load[i];
        }
        loadid_phi_subtract(phi, distal, load); /* distal part compensation */
        loadid_relative_error(load, truth, 10, err);
        loadid_physical_t phys;
        loadid_phi_to_physical(load, &phys);
        ok[m] = 1;
        for (int i = 0; i < 10; ++i) {
            est_phi[m][i] = load[i];
            mean_err[m] += err[i] / 10.0;
        }
        printf("%-9s kappa %.3g  noise ratio %.3f  sigma_min %.3g  physically consistent: %s\n", loadid_method_name(methods[m]),
               info.condition_number, info.noise_ratio, info.sigma_min, phys.violations ? "no" : "yes");
        if (n_params == LOADID_NPHI_OFFSET)
            printf("          offset estimate [%.3f %.3f %.3f N, %.4f %.4f %.4f Nm] (true %.3f %.3f %.3f, %.4f %.4f %.4f)\n",
                   phi[10], phi[11], phi[12], phi[13], phi[14], phi[15], noise.offset[0], noise.offset[1],
                   noise.offset[2], noise.offset[3], noise.offset[4], noise.offset[5]);
    }
    printf("\n%-6s %12s", "param", "truth");
    for (int m = 0; m < NMETHODS; ++m)
        if (ok[m]) printf(" %11s %6s", loadid_method_name(methods[m]), "e[%]");
    printf("\n");
    for (int i = 0; i < 10; ++i) {
        printf("%-6s %12.5g", kParamNames[i], phi_load[i]);
        for (int m = 0; m < NMETHODS; ++m) {
            if (!ok[m]) continue;
            const double e = phi_load[i] != 0 ? 100.0 * (est_phi[m][i] - phi_load[i]) / phi_load[i] : 0.0;
            printf(" %11.5g %6.1f", est_phi[m][i], e < 0 ? -e : e);
        }
        printf("\n");
    }
    printf("%-6s %12s", "mean", "");
    for (int m = 0; m < NMETHODS; ++m)
        if (ok[m]) printf(" %11s %6.1f", "", mean_err[m]);
    printf("\n");
    if (skipped) printf("\n%ld updates rejected\n", skipped);
    for (int m = 0; m < NMETHODS; ++m) loadid_est_destroy(est[m]);
    return 0;
}
