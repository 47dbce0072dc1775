/*
 * loadid-kappa: condition numbers of recordings, the structure of the
 * paper's Table I: kappa_set from the commanded joint positions and
 * kappa_sens from the measured signals (the JR3's a - g and alpha, omega
 * from the encoders' Kalman filter), plus kappa_kf (everything from the
 * encoders), over the estimation window (START to START + duration_s).
 * Each kappa is that of the data matrix A as eq. (12) has it (kappa of
 * Upsilon = A^T A is its square), or with --weighted of D A T with the
 * estimator's weights (the daemon's condition_number), with the zeroing
 * term of eqs. (7)-(9) at the ZERO pose or the offset columns, as
 * estimation.offset_model says. Why both: the weights equalise the noise of
 * every column, so noise adds to every singular value alike and lowers the
 * weighted kappa; the paper's effect (noisy accelerometers raise kappa_sens
 * above kappa_set) shows in the plain A, whose columns carry the noise
 * unequally.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/config.h"
#include "loadid/core.h"
#include "loadid/jr3.h"
#include "loadid/lcm_wire.h"
#include "loadid/pipeline.h"
#include "loadid/recording.h"
#include "loadid/setup.h"

static const char *prog = "loadid-kappa";

/* A warning of the configuration (another program's section). */
static void warn_line(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "%s: warning: %s\n", prog, msg);
}
static int weighted; /* --weighted: the estimator's D and T, else D = I, T = I */

enum { KAPPA_SET, KAPPA_SENS, KAPPA_KF, KAPPAS };

typedef struct {
    const loadid_config_t *cfg;
    loadid_signals_t *sig;
    loadid_jr3_decoder_t *jr3;
    loadid_est_t *est[KAPPAS];
    int n_params;
    int have_zero, in_window;
    loadid_real_t g_init[3];
    int64_t zero_us, start_us, end_us;
    int64_t samples, refused;
    int64_t bad_messages; /* joint states and commands not decodable */
    char load_name[128];
} kappa_run_t;

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s [--config FILE] [--weighted] RECORDING_DIR...\n"
            "Prints, per recording, the condition numbers of the estimator's weighted data\n"
            "matrix over the estimation window (START to START + estimation.duration_s):\n"
            "kappa_set from the setpoints, kappa_sens from the JR3's accelerations (omega\n"
            "from the joint Kalman filter), kappa_kf from the encoders alone; the layout\n"
            "of Table I of Kubus et al. (2008): kappa of the plain data matrix A (eq. 12's\n"
            "Upsilon = A^T A has kappa^2). --weighted gives kappa of D A T with the\n"
            "weights the JR3's noise levels give (noise.*), named kappa_*_w; kappa_set_w is\n"
            "loadid-traj's kappa_design (its setpoints at 1 kHz).\n",
            prog);
}

static int data_matrix(const kappa_run_t *k, const loadid_real_t spec[3],
                       const loadid_real_t omega[3], const loadid_real_t alpha[3],
                       loadid_real_t A[6 * 16]) {
    return loadid_regressor_model(spec, omega, alpha, k->n_params, k->g_init, A);
}

/* Joint states and commands through the service's decoder (lcm_wire.h),
 * which bounds num_joints and the strings; what it refuses is counted. */
static void on_joints(kappa_run_t *k, const loadid_rec_event_t *ev) {
    loadid_lcm_joint_state_t msg;
    if (loadid_lcm_decode_joint_state(ev->data, (size_t)ev->datalen, &msg) < 0) {
        k->bad_messages++;
        return;
    }
    loadid_real_t pos[LOADID_MAX_JOINTS], set[LOADID_MAX_JOINTS];
    const int n = msg.num_joints;
    if (n >= 1 && n <= LOADID_MAX_JOINTS) {
        for (int i = 0; i < n; ++i)
            pos[i] = (loadid_real_t)msg.position[i], set[i] = (loadid_real_t)msg.setpoint[i];
        loadid_signals_push_joints(k->sig, msg.utime, n, pos, set); /* bad ones are counted there */
    }
}

static void on_command(kappa_run_t *k, const loadid_rec_event_t *ev) {
    loadid_lcm_command_t msg;
    if (loadid_lcm_decode_command(ev->data, (size_t)ev->datalen, &msg) < 0) {
        k->bad_messages++;
        return;
    }
    if (msg.action == LOADID_CMD_ZERO) {
        loadid_kin_state_t st;
        if (loadid_signals_kinematics_at(k->sig, ev->t_us, &st) == 0) {
            memcpy(k->g_init, st.gravity, sizeof k->g_init);
            k->have_zero = 1;
            k->zero_us = ev->t_us;
        }
    } else if (msg.action == LOADID_CMD_START && k->start_us == INT64_MIN) {
        k->start_us = ev->t_us;
        k->end_us = ev->t_us + (int64_t)llround(k->cfg->duration_s * 1e6);
        snprintf(k->load_name, sizeof k->load_name, "%s", msg.load_name);
    }
}

static void on_sample(kappa_run_t *k, const loadid_jr3_sample_t *smp) {
    if (k->start_us == INT64_MIN || smp->t_us < k->start_us || smp->t_us >= k->end_us) return;
    if (k->n_params == LOADID_NPHI && !k->have_zero) return;
    loadid_real_t lin[3], ang[3];
    for (int i = 0; i < 3; ++i) {
        lin[i] = (loadid_real_t)smp->value[LOADID_JR3_LINEAR][i];
        ang[i] = (loadid_real_t)smp->value[LOADID_JR3_ANGULAR][i];
    }
    loadid_regressor_input_t kf, set;
    if (loadid_signals_at(k->sig, smp->t_us, lin, ang, NULL, &kf, &set) != 0) {
        k->refused++;
        return;
    }
    const loadid_real_t y[6] = {0, 0, 0, 0, 0, 0};
    loadid_real_t A[6 * 16];
    if (data_matrix(k, set.spec, set.omega, set.alpha, A) == 0)
        loadid_est_update(k->est[KAPPA_SET], A, NULL, y);
    if (data_matrix(k, lin, kf.omega, ang, A) == 0)
        loadid_est_update(k->est[KAPPA_SENS], A, NULL, y);
    if (data_matrix(k, kf.spec, kf.omega, kf.alpha, A) == 0)
        loadid_est_update(k->est[KAPPA_KF], A, NULL, y);
    k->samples++;
}

static int run(const loadid_config_t *cfg, const loadid_chain_t *chain, const char *dir,
               double kappa[KAPPAS], kappa_run_t *k) {
    char err[4400];
    memset(k, 0, sizeof *k);
    k->cfg = cfg;
    k->start_us = INT64_MIN;
    k->n_params = cfg->offset_model_estimate ? LOADID_NPHI_OFFSET : LOADID_NPHI;
    loadid_signals_config_t scfg;
    loadid_setup_signals(cfg, LOADID_SIGNALS_KF, &scfg);
    /* Table I's kappa_sens and kappa_kf are of the causal filter, as the
     * paper has them; this reader serves each sample as it comes, which the
     * fixed-lag smoother (kalman.lag_s) could not. */
    scfg.measured.lag_steps = scfg.setpoint.lag_steps = 0;
    scfg.lag_us = 0; /* also once the joint period is measured */
    loadid_jr3_config_t jcfg;
    loadid_setup_jr3(cfg, &jcfg);
    loadid_est_config_t ecfg;
    loadid_est_config_default(LOADID_METHOD_RLS, k->n_params, &ecfg);
    if (weighted) loadid_setup_weights(cfg, LOADID_SIGNALS_SENSOR, &ecfg);
    ecfg.max_noise_ratio = 1;
    int rc = loadid_signals_create(chain, cfg->robot_gravity, &scfg, &k->sig);
    if (rc == 0) rc = loadid_jr3_decoder_create(&jcfg, &k->jr3);
    for (int i = 0; i < KAPPAS && rc == 0; ++i) rc = loadid_est_create(&ecfg, &k->est[i]);
    loadid_recording_reader_t *rec = NULL;
    if (rc != 0) {
        fprintf(stderr, "%s: %s: cannot set up: %s\n", prog, dir, loadid_strerror(rc));
    } else if ((rc = loadid_recording_reader_open(dir, &rec, err, sizeof err)) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
    } else {
        loadid_rec_event_t ev;
        while ((rc = loadid_recording_reader_next(rec, &ev)) == 1) {
            if (ev.kind == LOADID_REC_LCM && strcmp(ev.channel, "LOADID_JOINTS") == 0) {
                on_joints(k, &ev);
            } else if (ev.kind == LOADID_REC_LCM && strcmp(ev.channel, "LOADID_COMMAND") == 0) {
                on_command(k, &ev);
            } else if (ev.kind == LOADID_REC_CAN) {
                loadid_jr3_output_t out;
                if (loadid_jr3_decoder_feed(k->jr3, &ev.can, &out) == LOADID_JR3_SAMPLE)
                    on_sample(k, &out.sample);
            }
        }
        if (rc < 0 && *loadid_recording_lcm_error(rec))
            fprintf(stderr, "%s: %s/lcm.log: %s\n", prog, dir, loadid_recording_lcm_error(rec));
        else if (rc < 0)
            fprintf(stderr, "%s: %s/can.log: read error\n", prog, dir);
        loadid_eventlog_stats_t ls;
        loadid_recording_lcm_stats(rec, &ls);
        if (ls.damaged || ls.truncated)
            fprintf(stderr, "%s: warning: %s/lcm.log: %s\n", prog, dir, ls.first_problem);
        if (k->bad_messages)
            fprintf(stderr, "%s: warning: %s/lcm.log: %lld messages could not be decoded\n", prog,
                    dir, (long long)k->bad_messages);
    }
    for (int i = 0; i < KAPPAS; ++i) {
        loadid_real_t phi[16];
        loadid_est_info_t info = {0};
        kappa[i] = NAN;
        if (k->est[i] && loadid_est_estimate(k->est[i], phi, &info) != -EINVAL)
            kappa[i] = info.samples > 0 ? (double)info.condition_number : NAN;
        loadid_est_destroy(k->est[i]);
    }
    loadid_recording_reader_close(rec);
    loadid_jr3_decoder_destroy(k->jr3);
    loadid_signals_destroy(k->sig);
    if (rc < 0) return rc;
    if (k->start_us == INT64_MIN) {
        fprintf(stderr, "%s: %s: no START command in lcm.log\n", prog, dir);
        return -EINVAL;
    }
    if (k->samples == 0) {
        fprintf(stderr, "%s: %s: no usable sample in the estimation window%s\n", prog, dir,
                k->n_params == LOADID_NPHI && !k->have_zero ? " (no ZERO before START)" : "");
        return -EINVAL;
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *config_path = NULL;
    static const struct option opts[] = {{"config", required_argument, NULL, 'c'},
                                         {"weighted", no_argument, NULL, 'w'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "c:h", opts, NULL)) != -1) {
        if (c == 'c')
            config_path = optarg;
        else if (c == 'w')
            weighted = 1;
        else if (c == 'h') {
            usage(stdout);
            return 0;
        } else {
            usage(stderr);
            return 2;
        }
    }
    if (optind == argc) {
        usage(stderr);
        return 2;
    }
    static loadid_config_t cfg;
    loadid_chain_t chain;
    char setup_err[1200];
    if (loadid_setup_load(config_path, &cfg, &chain, warn_line, NULL, setup_err,
                          sizeof setup_err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, setup_err);
        return 1;
    }
    printf("%-28s %-10s %8s %10s %10s %10s\n", "recording", "load", "samples",
           weighted ? "kappa_set_w" : "kappa_set", weighted ? "kappa_sens_w" : "kappa_sens",
           weighted ? "kappa_kf_w" : "kappa_kf");
    int failed = 0;
    for (int i = optind; i < argc; ++i) {
        double kappa[KAPPAS];
        kappa_run_t k;
        if (run(&cfg, &chain, argv[i], kappa, &k) != 0) {
            failed = 1;
            continue;
        }
        printf("%-28s %-10s %8lld %10.4g %10.4g %10.4g\n", argv[i], k.load_name,
               (long long)k.samples, kappa[KAPPA_SET], kappa[KAPPA_SENS], kappa[KAPPA_KF]);
    }
    return failed;
}
