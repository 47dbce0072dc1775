/*
 * loadid-sim: simulates a recording (docs/INTERFACE.md "Recordings")
 * of the configured robot following an excitation trajectory from
 * loadid-traj with a load on its wrist sensor:
 *   - the joints follow the setpoints through a second-order servo with
 *     backlash (servo.h), so encoder positions differ from setpoints and the
 *     load's real motion from both;
 *   - the true wrench by eqs. (1)-(2) of the load plus the distal sensor
 *     part (tools/synth, an evaluation independent of the core's regressor)
 *     plus the sensor offset and white noise;
 *   - the JR3 accelerometer's a - g and alpha of the real motion, plus white
 *     noise and a structural vibration;
 *   - encoder quantisation, JR3 counts with saturation and status bytes.
 * Timeline: rest at q_0 for simulation.still_s (ZERO at 0.05 s unless
 * simulation.zero is false), the trajectory (START when its active part
 * begins), 0.3 s of rest. CAN samples (base+0..3) at 1 kHz, 370 us after
 * each 1 kHz joint state; base+4 full-scale frames of all four groups once
 * a second.
 * Imitating real hardware data (simulation.*, all off by default): the
 * trajectory's s_i(t) about q_0 scaled by trajectory_scale (slower, gentler
 * motion); the F/T offset drifting linearly from the recording's start
 * (drift); constant accelerometer biases (accel_bias on a - g, alpha_bias
 * on alpha); time stamps of CAN samples and joint states jittered by
 * uniform integers in [-jitter_us, jitter_us] from a random stream of their
 * own (the physics stays at the nominal times; a stamp that would not
 * follow its stream's previous one is clipped to 1 us after it).
 * Output: DIR/can.log, DIR/lcm.log, DIR/truth.yaml; byte-identical for the
 * same inputs and seed.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/config.h"
#include "recording_writer.h"
#include "sim_damage.h"
#include "sim_run.h"
#include "loadid/setup.h"
#include "traj_file.h"

static const char *prog = "loadid-sim";

/* A warning of the configuration (another program's section). */
static void warn_line(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "%s: warning: %s\n", prog, msg);
}

/* What main keeps: the inputs it reads before the simulation runs. */
static struct {
    loadid_config_t cfg;
    loadid_chain_t chain;
    loadid_fourier_traj_t traj;
    double kappa_design;
    loadid_damage_t damage;
} s;

static void usage(FILE *out) {
    fprintf(
        out,
        "usage: %s --trajectory TRAJ.yaml --out DIR [--force] [--config FILE] [--seed N]\n"
        "                  [--load-name NAME] [--start-utime US] [--damage KIND=VALUE]...\n"
        "                  [--values FILE.csv] [--load-phi m,mcx,mcy,mcz,Ixx,Ixy,Ixz,Iyy,Iyz,Izz]\n"
        "Simulates a recording (can.log, lcm.log, truth.yaml in DIR) of the configured\n"
        "robot (robot.*) following the trajectory of loadid-traj with the load\n"
        "simulation.load_phi (default the paper's o1) and the distal part distal.phi,\n"
        "offsets simulation.offset, noise noise.*, servo, backlash, vibration and\n"
        "encoder of simulation.*, JR3 full scales jr3.*, CAN can.*; like real\n"
        "hardware data with simulation.zero false (no ZERO command), drift (of\n"
        "the offset), accel_bias, alpha_bias, jitter_us (of the time stamps) and\n"
        "trajectory_scale < 1 (slower motion).\n"
        "--damage writes a deliberately damaged recording; KIND is one of\n"
        "  drop-frames=P skip-samples=P bit-errors=P saturate=P fault=P bad-frames=P\n"
        "  nan-joints=P stall-joints=T0:T1 (seconds); may be repeated.\n"
        "DIR must not exist or be empty; --force writes into a folder that holds files\n"
        "(can.log, lcm.log and truth.yaml are overwritten, other files stay).\n"
        "--load-phi overrides simulation.load_phi (eq. 5, inertia about the origin of S).\n"
        "--values writes what each CAN sample encodes, in SI (t_us, sequence, f, tau,\n"
        "a - g, alpha), before rounding to counts, and the damage done to it (bits:\n"
        "1 skipped, 2 a frame dropped, 4 a bit flipped, 8 saturated, 16 fault).\n",
        prog);
}

/* Ten comma-separated finite numbers. */
static int parse_phi(const char *text, double phi[10]) {
    const char *p = text;
    for (int i = 0; i < 10; ++i) {
        char *end;
        errno = 0;
        phi[i] = strtod(p, &end);
        if (errno || end == p || !isfinite(phi[i])) return -1;
        if (i < 9 && *end != ',') return -1;
        p = end + (i < 9);
        if (i == 9 && *end) return -1;
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *config_path = NULL, *traj_path = NULL, *out_dir = NULL, *load_name = "o1";
    const char *values_path = NULL, *load_phi = NULL;
    int force = 0;
    long long seed = -1, t0 = 1700000000000000LL;
    loadid_damage_init(&s.damage, 0);
    char err[1024];
    static const struct option opts[] = {{"config", required_argument, NULL, 'c'},
                                         {"trajectory", required_argument, NULL, 't'},
                                         {"out", required_argument, NULL, 'o'},
                                         {"seed", required_argument, NULL, 'S'},
                                         {"load-name", required_argument, NULL, 'l'},
                                         {"start-utime", required_argument, NULL, 'u'},
                                         {"damage", required_argument, NULL, 'd'},
                                         {"values", required_argument, NULL, 'v'},
                                         {"load-phi", required_argument, NULL, 'p'},
                                         {"force", no_argument, NULL, 'f'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "c:t:o:h", opts, NULL)) != -1) {
        char *end;
        switch (c) {
            case 'c':
                config_path = optarg;
                break;
            case 't':
                traj_path = optarg;
                break;
            case 'o':
                out_dir = optarg;
                break;
            case 'l':
                load_name = optarg;
                break;
            case 'v':
                values_path = optarg;
                break;
            case 'p':
                load_phi = optarg;
                break;
            case 'f':
                force = 1;
                break;
            case 'S':
            case 'u': {
                errno = 0;
                long long v = strtoll(optarg, &end, 10);
                if (errno || *end || end == optarg || v < 0) {
                    fprintf(stderr, "%s: --%s: not a non-negative integer: %s\n", prog,
                            c == 'S' ? "seed" : "start-utime", optarg);
                    return 2;
                }
                if (c == 'S')
                    seed = v;
                else
                    t0 = v;
                break;
            }
            case 'd':
                if (loadid_damage_parse(&s.damage, optarg, err, sizeof err) != 0) {
                    fprintf(stderr, "%s: %s\n", prog, err);
                    return 2;
                }
                break;
            case 'h':
                usage(stdout);
                return 0;
            default:
                usage(stderr);
                return 2;
        }
    }
    if (optind != argc || !traj_path || !out_dir) {
        usage(stderr);
        return 2;
    }
    if (loadid_recording_dir_check(out_dir, force, "--force", err, sizeof err) != 0) {
        fprintf(stderr, "%s: --out %s\n", prog, err);
        return 1;
    }
    char setup_err[1200];
    if (loadid_setup_load(config_path, &s.cfg, &s.chain, warn_line, NULL, setup_err,
                          sizeof setup_err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, setup_err);
        return 1;
    }
    if (load_phi && parse_phi(load_phi, s.cfg.sim_load_phi) != 0) {
        fprintf(stderr, "%s: --load-phi: expected 10 comma-separated numbers: %s\n", prog,
                load_phi);
        return 2;
    }
    const uint64_t the_seed = seed >= 0 ? (uint64_t)seed : s.cfg.sim_seed;
    char names[LOADID_MAX_JOINTS][LOADID_NAME_MAX];
    if (loadid_traj_file_read(traj_path, &s.traj, names, &s.kappa_design, err, sizeof err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    if (s.traj.num_joints != s.chain.num_joints) {
        fprintf(stderr, "%s: %s has %d joints, the robot %s %d\n", prog, traj_path,
                s.traj.num_joints, s.cfg.robot_urdf, s.chain.num_joints);
        return 1;
    }
    for (int i = 0; i < s.chain.num_joints; ++i)
        if (strcmp(names[i], s.chain.joints[i].name) != 0) {
            fprintf(stderr, "%s: %s: joint %d is '%s', the robot's is '%s'\n", prog, traj_path,
                    i + 1, names[i], s.chain.joints[i].name);
            return 1;
        }
    loadid_sim_options_t opt = {
        .cfg = &s.cfg,
        .chain = &s.chain,
        .traj = &s.traj,
        .kappa_design = s.kappa_design,
        .traj_path = traj_path,
        .out_dir = out_dir,
        .values_path = values_path,
        .load_name = load_name,
        .seed = the_seed,
        .start_utime = t0,
        .damage = s.damage,
        .warn = warn_line,
    };
    loadid_sim_summary_t sum;
    if (loadid_sim_run(&opt, &sum, err, sizeof err) != 0) {
        fprintf(stderr, "%s: %s: %s\n", prog, out_dir, err);
        return 1;
    }
    char zero[32] = "no ZERO";
    if (sum.zero_s >= 0) snprintf(zero, sizeof zero, "ZERO at %.2f s", sum.zero_s);
    fprintf(stderr, "%s: %s: %lld samples, %.2f s, %s, START at %.2f s\n", prog, out_dir,
            (long long)sum.samples, sum.duration_s, zero, sum.start_s);
    if (sum.jitter_clipped > 0)
        fprintf(stderr,
                "%s: %s: %lld jittered time stamps clipped to keep their stream in "
                "order\n",
                prog, out_dir, (long long)sum.jitter_clipped);
    return 0;
}
