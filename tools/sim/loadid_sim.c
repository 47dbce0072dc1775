/*
 * loadid-sim: simulates a recording (DESIGN.md "A recording is a folder")
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
 * Timeline: rest at q_0 for simulation.still_s (ZERO at 0.05 s), the
 * trajectory (START when its active part begins), 0.3 s of rest. CAN
 * samples (base+0..3) at 1 kHz, 370 us after each 1 kHz joint state;
 * base+4 full-scale frames of all four groups once a second.
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
#include "loadid/core.h"
#include "loadid/jr3.h"
#include "tool_setup.h"
#include "loadid_synth.h"
#include "recording_writer.h"
#include "servo.h"
#include "sim_damage.h"
#include "traj_file.h"

static const char *prog = "loadid-sim";
static const double kTwoPi = 6.28318530717958647692;

#define ZERO_AT_S 0.05      /* ZERO command, into the still phase [s] */
#define TAIL_S 0.3          /* rest after the trajectory [s] */
#define CAN_PHASE_US 370    /* CAN sample after the joint state [us] */
#define FRAME_GAP_US 115    /* between the frames of one sample (1 Mbit/s) */
#define PRISMATIC_STEP 1e-6 /* encoder resolution of a prismatic joint [m] */

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s --trajectory TRAJ.yaml --out DIR [--config FILE] [--seed N]\n"
            "                  [--load-name NAME] [--start-utime US] [--damage KIND=VALUE]...\n"
            "                  [--values FILE.csv] [--load-phi m,mcx,mcy,mcz,Ixx,Ixy,Ixz,Iyy,Iyz,Izz]\n"
            "Simulates a recording (can.log, lcm.log, truth.yaml in DIR) of the configured\n"
            "robot (robot.*) following the trajectory of loadid-traj with the load\n"
            "simulation.load_phi (default the paper's o1) and the distal part distal.phi,\n"
            "offsets simulation.offset, noise noise.*, servo, backlash, vibration and\n"
            "encoder of simulation.*, JR3 full scales jr3.*, CAN can.*.\n"
            "--damage writes a deliberately damaged recording; KIND is one of\n"
            "  drop-frames=P skip-samples=P bit-errors=P saturate=P fault=P bad-frames=P\n"
            "  nan-joints=P stall-joints=T0:T1 (seconds); may be repeated.\n"
            "--load-phi overrides simulation.load_phi (eq. 5, inertia about the origin of S).\n"
            "--values writes what each CAN sample encodes, in SI (t_us, sequence, f, tau,\n"
            "a - g, alpha), before rounding to counts.\n",
            prog);
}

typedef struct {
    loadid_config_t cfg;
    loadid_chain_t chain;
    loadid_kin_t *kin;
    loadid_fourier_traj_t traj;
    double kappa_set;
    loadid_jr3_config_t jr3;
    loadid_servo_t servo;
    loadid_rng_t rng;
    loadid_damage_t damage;
    loadid_recording_writer_t *rec;
    FILE *values;                 /* --values: what each sample encodes, in SI */
    double vib_phase[2][3];
    /* counts */
    int64_t samples, saturated_samples;
} sim_t;

static double quantise(const sim_t *s, int joint, double q) {
    const double step = s->chain.joints[joint].type == LOADID_JOINT_PRISMATIC
                            ? PRISMATIC_STEP
                            : kTwoPi / s->cfg.sim_encoder_counts;
    return round(q / step) * step;
}

/* The true motion of S (link side) at simulation time t. */
static int motion_at(sim_t *s, double t, loadid_servo_state_t *st, loadid_motion_t *m) {
    loadid_servo_advance(&s->servo, t, st);
    loadid_real_t q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
    for (int i = 0; i < s->chain.num_joints; ++i) {
        q[i] = (loadid_real_t)st->link[i];
        qd[i] = (loadid_real_t)st->link_d[i];
        qdd[i] = (loadid_real_t)st->link_dd[i];
    }
    loadid_kin_state_t k;
    int rc = loadid_kin_eval(s->kin, q, qd, qdd, &k);
    if (rc != 0) return rc;
    for (int i = 0; i < 3; ++i) {
        m->spec[i] = k.spec[i];
        m->omega[i] = k.omega[i];
        m->alpha[i] = k.alpha[i];
        m->g[i] = k.gravity[i];
    }
    return 0;
}

/* One JR3 sample at simulation time t: what the sensor measures, in SI. */
static void measure(sim_t *s, double t, const loadid_motion_t *m, double value[4][3]) {
    double load[6], distal[6];
    loadid_synth_wrench(s->cfg.sim_load_phi, m, load);
    loadid_synth_wrench(s->cfg.distal_phi, m, distal);
    for (int i = 0; i < 3; ++i) {
        value[LOADID_JR3_FORCE][i] = load[i] + distal[i] + s->cfg.sim_offset[i] +
                                     s->cfg.noise_force * loadid_rng_normal(&s->rng);
        value[LOADID_JR3_MOMENT][i] = load[3 + i] + distal[3 + i] + s->cfg.sim_offset[3 + i] +
                                      s->cfg.noise_torque * loadid_rng_normal(&s->rng);
    }
    const double wt = kTwoPi * s->cfg.sim_vibration_hz * t;
    for (int i = 0; i < 3; ++i) {
        value[LOADID_JR3_LINEAR][i] = m->spec[i] + s->cfg.noise_linear * loadid_rng_normal(&s->rng) +
                                      s->cfg.sim_vibration_linear * sin(wt + s->vib_phase[0][i]);
        value[LOADID_JR3_ANGULAR][i] = m->alpha[i] +
                                       s->cfg.noise_angular * loadid_rng_normal(&s->rng) +
                                       s->cfg.sim_vibration_angular * sin(wt + s->vib_phase[1][i]);
    }
}

static int write_can(sim_t *s, loadid_can_frame_t *f) {
    if (loadid_damage_now(&s->damage, LOADID_DAMAGE_BIT_ERRORS)) {
        unsigned bit = loadid_damage_pick(&s->damage, 64);
        f->data[bit / 8] ^= (uint8_t)(1u << (bit % 8));
    }
    return loadid_recording_can(s->rec, f);
}

/* The four frames of CAN sample k at utime t, with any damage asked for. */
static int can_sample(sim_t *s, int64_t k, int64_t t, double sim_t_s) {
    loadid_servo_state_t st;
    loadid_motion_t m;
    int rc = motion_at(s, sim_t_s, &st, &m);
    if (rc != 0) return rc;
    double value[4][3];
    measure(s, sim_t_s, &m, value);
    const int saturate = loadid_damage_now(&s->damage, LOADID_DAMAGE_SATURATE);
    if (saturate) value[LOADID_JR3_FORCE][0] = 3 * s->jr3.full_scale[LOADID_JR3_FORCE][0];
    const unsigned fault = loadid_damage_now(&s->damage, LOADID_DAMAGE_FAULT) ? LOADID_JR3_ALL_GROUPS : 0;
    loadid_can_frame_t frames[4];
    int sat = loadid_jr3_encode(&s->jr3, (const double(*)[3])value, (uint8_t)(k & 0xFF), fault, t, frames);
    if (sat < 0) return sat;
    if (s->values) {
        fprintf(s->values, "%lld,%u", (long long)t, (unsigned)(k & 0xFF));
        for (int g = 0; g < 4; ++g)
            for (int i = 0; i < 3; ++i) fprintf(s->values, ",%.17g", value[g][i]);
        fputc('\n', s->values);
    }
    s->samples++;
    if (sat) s->saturated_samples++;
    if (loadid_damage_now(&s->damage, LOADID_DAMAGE_SKIP_SAMPLES)) return 0;
    for (int g = 0; g < 4; ++g) {
        frames[g].t_us = t + g * FRAME_GAP_US;
        if (loadid_damage_now(&s->damage, LOADID_DAMAGE_DROP_FRAMES)) continue;
        if ((rc = write_can(s, &frames[g])) != 0) return rc;
    }
    if (loadid_damage_now(&s->damage, LOADID_DAMAGE_BAD_FRAMES)) {
        loadid_can_frame_t bad = frames[0];
        bad.t_us = t + 4 * FRAME_GAP_US;
        if (loadid_damage_pick(&s->damage, 2))
            bad.dlc = 6;
        else
            bad.id = s->jr3.base_id + 7;
        if ((rc = loadid_recording_can(s->rec, &bad)) != 0) return rc;
    }
    return 0;
}

static int full_scale_frames(sim_t *s, int64_t t) {
    for (int g = 0; g < 4; ++g) {
        loadid_can_frame_t f;
        int rc = loadid_jr3_encode_full_scale(s->jr3.base_id, g, s->jr3.full_scale[g],
                                              t + g * FRAME_GAP_US, &f, NULL);
        if (rc == 0) rc = write_can(s, &f);
        if (rc != 0) return rc;
    }
    return 0;
}

static int joint_state(sim_t *s, int64_t t, double sim_t_s) {
    loadid_servo_state_t st;
    loadid_servo_advance(&s->servo, sim_t_s, &st);
    if (s->damage.stall_to > s->damage.stall_from && sim_t_s >= s->damage.stall_from &&
        sim_t_s < s->damage.stall_to) {
        s->damage.stalled_joint_msgs++;
        return 0;
    }
    double pos[LOADID_MAX_JOINTS];
    for (int i = 0; i < s->chain.num_joints; ++i) pos[i] = quantise(s, i, st.motor[i]);
    if (loadid_damage_now(&s->damage, LOADID_DAMAGE_NAN_JOINTS)) pos[0] = NAN;
    return loadid_recording_joints(s->rec, t, s->chain.num_joints, pos, st.setpoint);
}

static void list(FILE *f, const double *v, int n) {
    fputc('[', f);
    for (int i = 0; i < n; ++i) fprintf(f, "%s%.17g", i ? ", " : "", v[i]);
    fputc(']', f);
}

static int write_truth(const sim_t *s, const char *dir, const char *traj_path,
                       const char *load_name, uint64_t seed, int64_t t0, int64_t zero_us,
                       int64_t start_us, int64_t traj_us, int64_t active_end_us, int64_t end_us) {
    char path[4200];
    snprintf(path, sizeof path, "%s/truth.yaml", dir);
    FILE *f = fopen(path, "w");
    if (!f) return -errno;
    const loadid_config_t *c = &s->cfg;
    fprintf(f, "# What loadid-sim simulated (DESIGN.md recording format).\n");
    fprintf(f, "format: loadid-truth-1\nseed: %llu\nload_name: \"%s\"\n", (unsigned long long)seed,
            load_name);
    loadid_real_t phi[10];
    for (int i = 0; i < 10; ++i) phi[i] = (loadid_real_t)c->sim_load_phi[i];
    loadid_physical_t p;
    loadid_phi_to_physical(phi, &p);
    fprintf(f, "load:\n  phi: ");
    list(f, c->sim_load_phi, 10);
    fprintf(f, "\n  mass: %.17g\n  com: [%.17g, %.17g, %.17g]\n  inertia_com: [", (double)p.mass,
            (double)p.com[0], (double)p.com[1], (double)p.com[2]);
    for (int i = 0; i < 6; ++i) fprintf(f, "%s%.17g", i ? ", " : "", (double)p.inertia_com[i]);
    fprintf(f, "]\n  physically_consistent: %s\n", p.violations ? "false" : "true");
    fprintf(f, "distal_phi: ");
    list(f, c->distal_phi, 10);
    fprintf(f, "\noffset: ");
    list(f, c->sim_offset, 6);
    fprintf(f, "\nnoise:\n  force: %.17g\n  torque: %.17g\n  linear: %.17g\n  angular: %.17g\n",
            c->noise_force, c->noise_torque, c->noise_linear, c->noise_angular);
    fprintf(f, "vibration:\n  hz: %.17g\n  linear: %.17g\n  angular: %.17g\n", c->sim_vibration_hz,
            c->sim_vibration_linear, c->sim_vibration_angular);
    fprintf(f, "servo:\n  bandwidth_hz: %.17g\n  damping: %.17g\n  backlash: %.17g\n",
            c->sim_servo_bandwidth_hz, c->sim_servo_damping, c->sim_backlash);
    fprintf(f, "encoder_counts: %.17g\n", c->sim_encoder_counts);
    fprintf(f, "robot:\n  urdf: \"%s\"\n  base_link: \"%s\"\n  sensor_link: \"%s\"\n", c->robot_urdf,
            c->robot_base_link, c->robot_sensor_link);
    fprintf(f, "trajectory:\n  file: \"%s\"\n  kappa_set: %.17g\n", traj_path, s->kappa_set);
    fprintf(f, "can:\n  interface: \"%s\"\n  base_id: 0x%X\n", c->can_interface, (unsigned)c->can_base_id);
    fprintf(f, "jr3_full_scale:\n");
    const char *g[4] = {"force", "moment", "linear", "angular"};
    for (int i = 0; i < 4; ++i) {
        fprintf(f, "  %s: ", g[i]);
        list(f, s->jr3.full_scale[i], 3);
        fputc('\n', f);
    }
    fprintf(f, "times:                 # utime [us]\n  begin: %lld\n  zero: %lld\n  start: %lld\n"
               "  trajectory: %lld\n  active_end: %lld\n  end: %lld\n",
            (long long)t0, (long long)zero_us, (long long)start_us, (long long)traj_us,
            (long long)active_end_us, (long long)end_us);
    loadid_recording_counts_t rc;
    loadid_recording_counts(s->rec, &rc);
    fprintf(f, "counts:\n  samples: %lld\n  saturated_samples: %lld\n  can_frames: %lld\n"
               "  joint_msgs: %lld\n  commands: %lld\n",
            (long long)s->samples, (long long)s->saturated_samples, (long long)rc.can_frames,
            (long long)rc.joint_msgs, (long long)rc.commands);
    fprintf(f, "damage:\n");
    for (int k = 0; k < LOADID_DAMAGE_KINDS; ++k)
        fprintf(f, "  %s: {probability: %.17g, count: %lld}\n", loadid_damage_name(k), s->damage.p[k],
                (long long)s->damage.count[k]);
    fprintf(f, "  stall-joints: {from_s: %.17g, to_s: %.17g, count: %lld}\n", s->damage.stall_from,
            s->damage.stall_to, (long long)s->damage.stalled_joint_msgs);
    int e = ferror(f) ? EIO : 0;
    if (fclose(f) != 0 && !e) e = errno;
    return -e;
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
    long long seed = -1, t0 = 1700000000000000LL;
    static sim_t s;
    loadid_damage_init(&s.damage, 0);
    char err[1024];
    static const struct option opts[] = {
        {"config", required_argument, NULL, 'c'},    {"trajectory", required_argument, NULL, 't'},
        {"out", required_argument, NULL, 'o'},       {"seed", required_argument, NULL, 'S'},
        {"load-name", required_argument, NULL, 'l'}, {"start-utime", required_argument, NULL, 'u'},
        {"damage", required_argument, NULL, 'd'},    {"values", required_argument, NULL, 'v'},
        {"load-phi", required_argument, NULL, 'p'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "c:t:o:h", opts, NULL)) != -1) {
        char *end;
        switch (c) {
            case 'c': config_path = optarg; break;
            case 't': traj_path = optarg; break;
            case 'o': out_dir = optarg; break;
            case 'l': load_name = optarg; break;
            case 'v': values_path = optarg; break;
            case 'p': load_phi = optarg; break;
            case 'S':
            case 'u': {
                errno = 0;
                long long v = strtoll(optarg, &end, 10);
                if (errno || *end || end == optarg || v < 0) {
                    fprintf(stderr, "%s: --%s: not a non-negative integer: %s\n", prog,
                            c == 'S' ? "seed" : "start-utime", optarg);
                    return 2;
                }
                if (c == 'S') seed = v; else t0 = v;
                break;
            }
            case 'd':
                if (loadid_damage_parse(&s.damage, optarg, err, sizeof err) != 0) {
                    fprintf(stderr, "%s: %s\n", prog, err);
                    return 2;
                }
                break;
            case 'h': usage(stdout); return 0;
            default: usage(stderr); return 2;
        }
    }
    if (optind != argc || !traj_path || !out_dir) {
        usage(stderr);
        return 2;
    }
    if (loadid_tool_setup(prog, config_path, &s.cfg, &s.chain) != 0) return 1;
    if (load_phi && parse_phi(load_phi, s.cfg.sim_load_phi) != 0) {
        fprintf(stderr, "%s: --load-phi: expected 10 comma-separated numbers: %s\n", prog, load_phi);
        return 2;
    }
    const uint64_t the_seed = seed >= 0 ? (uint64_t)seed : s.cfg.sim_seed;
    char names[LOADID_MAX_JOINTS][LOADID_NAME_MAX];
    if (loadid_traj_file_read(traj_path, &s.traj, names, &s.kappa_set, err, sizeof err) != 0) {
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
    if (s.cfg.sim_still_s < ZERO_AT_S + s.cfg.zeroing_window_s)
        fprintf(stderr, "%s: warning: simulation.still_s %.3g s leaves less than zeroing.window_s "
                        "after ZERO at %.2f s\n", prog, s.cfg.sim_still_s, ZERO_AT_S);
    if (loadid_kin_create(&s.chain, s.cfg.robot_gravity, &s.kin) != 0) {
        fprintf(stderr, "%s: cannot build the kinematics\n", prog);
        return 1;
    }
    loadid_tool_jr3_config(&s.cfg, &s.jr3);
    if (loadid_jr3_config_check(&s.jr3) != 0) {
        fprintf(stderr, "%s: invalid JR3 configuration\n", prog);
        return 1;
    }
    loadid_rng_seed(&s.rng, the_seed);
    loadid_damage_t parsed = s.damage;
    loadid_damage_init(&s.damage, the_seed);
    memcpy(s.damage.p, parsed.p, sizeof s.damage.p);
    s.damage.stall_from = parsed.stall_from, s.damage.stall_to = parsed.stall_to;
    for (int a = 0; a < 2; ++a)
        for (int i = 0; i < 3; ++i) s.vib_phase[a][i] = kTwoPi * loadid_rng_uniform(&s.rng);

    const double traj_start = s.cfg.sim_still_s;
    const double active_start = traj_start + loadid_traj_active_start(&s.traj);
    const double total = traj_start + loadid_traj_duration(&s.traj) + TAIL_S;
    loadid_servo_config_t servo = {.bandwidth_hz = s.cfg.sim_servo_bandwidth_hz,
                                   .damping = s.cfg.sim_servo_damping,
                                   .backlash = s.cfg.sim_backlash};
    loadid_servo_init(&s.servo, &servo, &s.traj, traj_start);
    if (loadid_recording_open(out_dir, s.cfg.can_interface, &s.rec, err, sizeof err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    if (values_path) {
        s.values = fopen(values_path, "w");
        if (!s.values) {
            fprintf(stderr, "%s: %s: cannot write: %s\n", prog, values_path, strerror(errno));
            return 1;
        }
        fprintf(s.values, "t_us,sequence,fx,fy,fz,tx,ty,tz,ax,ay,az,alx,aly,alz\n");
    }
    const int64_t zero_us = t0 + (int64_t)llround(ZERO_AT_S * 1e6);
    const int64_t start_us = t0 + (int64_t)llround(active_start * 1e6);
    const long ticks = lround(total * 1000);
    int rc = 0;
    for (long k = 0; k < ticks && rc == 0; ++k) {
        const int64_t tj = t0 + (int64_t)k * 1000;
        if (tj == zero_us) rc = loadid_recording_command(s.rec, tj, 1, load_name);
        if (rc == 0 && tj == start_us) rc = loadid_recording_command(s.rec, tj, 2, load_name);
        if (rc == 0) rc = joint_state(&s, tj, k * 1e-3);
        const int64_t tc = tj + CAN_PHASE_US;
        if (rc == 0) rc = can_sample(&s, k, tc, (tc - t0) * 1e-6);
        if (rc == 0 && k % 1000 == 500) rc = full_scale_frames(&s, tc + 4 * FRAME_GAP_US);
    }
    if (rc == 0)
        rc = write_truth(&s, out_dir, traj_path, load_name, the_seed, t0, zero_us, start_us,
                         t0 + (int64_t)llround(traj_start * 1e6),
                         start_us + (int64_t)llround(s.traj.active_s * 1e6), t0 + ticks * 1000);
    int crc = loadid_recording_close(s.rec);
    if (s.values && fclose(s.values) != 0 && rc == 0) rc = -errno;
    if (rc == 0) rc = crc;
    loadid_kin_destroy(s.kin);
    if (rc != 0) {
        fprintf(stderr, "%s: writing %s failed: %s\n", prog, out_dir,
                rc > -1000 ? strerror(-rc) : loadid_strerror(rc));
        return 1;
    }
    fprintf(stderr, "%s: %s: %lld samples, %.2f s, ZERO at %.2f s, START at %.2f s\n", prog,
            out_dir, (long long)s.samples, total, ZERO_AT_S, active_start);
    return 0;
}
