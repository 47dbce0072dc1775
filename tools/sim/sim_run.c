/* The simulation of loadid-sim (sim_run.h). */
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
#include "loadid/setup.h"
#include "loadid_synth.h"
#include "recording_writer.h"
#include "sim_run.h"
#include "servo.h"
#include "sim_damage.h"
#include "traj_file.h"

static const double kTwoPi = 6.28318530717958647692;

#define ZERO_AT_S 0.05      /* ZERO command, into the still phase [s] */
#define TAIL_S 0.3          /* rest after the trajectory [s] */
#define CAN_PHASE_US 370    /* CAN sample after the joint state [us] */
#define FRAME_GAP_US 115    /* between the frames of one sample (1 Mbit/s) */
#define PRISMATIC_STEP 1e-6 /* encoder resolution of a prismatic joint [m] */

/* The --values file's last column: what was done to a CAN sample, so tests
 * can count usable samples from the simulator's own record. */
enum {
    SAMPLE_SKIPPED = 1,       /* no frame sent (a sequence gap) */
    SAMPLE_FRAME_DROPPED = 2, /* one or more of its frames not sent (incomplete) */
    SAMPLE_BIT_FLIPPED = 4,   /* a data bit of one of its frames flipped */
    SAMPLE_SATURATED = 8,     /* a count clamped at full scale (saturation bit) */
    SAMPLE_FAULT = 16,        /* the sensor-fault bit set */
};

typedef struct {
    loadid_config_t cfg;
    loadid_chain_t chain;
    loadid_kin_t *kin;
    loadid_fourier_traj_t traj;
    double kappa_design;
    loadid_jr3_config_t jr3;
    loadid_servo_t servo;
    loadid_rng_t rng;
    loadid_damage_t damage;
    loadid_recording_writer_t *rec;
    FILE *values;           /* --values: what each sample encodes, in SI */
    unsigned sample_damage; /* SAMPLE_* of the CAN sample being written */
    double vib_phase[2][3];
    double ft_state[6]; /* the F/T noise's AR(1) state (ft_noise) */
    int ft_started;
    loadid_rng_t jitter_rng; /* simulation.jitter_us: a stream of its own */
    int64_t last_joint_us;   /* stamp of the last joint state written */
    int64_t last_can_us;     /* time of the last CAN frame written */
    /* counts */
    int64_t samples, saturated_samples, jitter_clipped;
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

/* Unit-variance noise of F/T channel i: white, or with
 * simulation.noise.ft_correlation r an AR(1) process x_k = r x_k-1 +
 * sqrt(1 - r^2) e_k (a first-order low-pass filter sampled at 1 kHz),
 * started in its stationary law. r 0 leaves the draws as they were. */
static double ft_noise(sim_t *s, int i) {
    const double e = loadid_rng_normal(&s->rng), r = s->cfg.sim_noise_ft_correlation;
    if (r == 0) return e;
    s->ft_state[i] = s->ft_started ? r * s->ft_state[i] + sqrt(1 - r * r) * e : e;
    if (i == 5) s->ft_started = 1;
    return s->ft_state[i];
}

/* One JR3 sample at simulation time t: what the sensor measures, in SI. */
static void measure(sim_t *s, double t, const loadid_motion_t *m, double value[4][3]) {
    double load[6], distal[6];
    loadid_synth_wrench(s->cfg.sim_load_phi, m, load);
    loadid_synth_wrench(s->cfg.distal_phi, m, distal);
    /* The offset, drifting linearly from the recording's start (t = 0). */
    double offset[6];
    for (int i = 0; i < 6; ++i) offset[i] = s->cfg.sim_offset[i] + s->cfg.sim_drift[i] * t;
    for (int i = 0; i < 3; ++i) {
        value[LOADID_JR3_FORCE][i] =
            load[i] + distal[i] + offset[i] + s->cfg.sim_noise_force * ft_noise(s, i);
        value[LOADID_JR3_MOMENT][i] = load[3 + i] + distal[3 + i] + offset[3 + i] +
                                      s->cfg.sim_noise_torque * ft_noise(s, 3 + i);
    }
    const double wt = kTwoPi * s->cfg.sim_vibration_hz * t;
    const double on = t >= s->cfg.sim_vibration_start_s ? 1.0 : 0.0;
    for (int i = 0; i < 3; ++i) {
        value[LOADID_JR3_LINEAR][i] =
            m->spec[i] + s->cfg.sim_noise_linear * loadid_rng_normal(&s->rng) +
            on * s->cfg.sim_vibration_linear * sin(wt + s->vib_phase[0][i]);
        value[LOADID_JR3_ANGULAR][i] =
            m->alpha[i] + s->cfg.sim_noise_angular * loadid_rng_normal(&s->rng) +
            on * s->cfg.sim_vibration_angular * sin(wt + s->vib_phase[1][i]);
    }
    /* Accelerometer biases (added only when set: a zero bias leaves the
     * values bit for bit as without it). */
    for (int i = 0; i < 3; ++i) {
        if (s->cfg.sim_accel_bias[i] != 0) value[LOADID_JR3_LINEAR][i] += s->cfg.sim_accel_bias[i];
        if (s->cfg.sim_alpha_bias[i] != 0) value[LOADID_JR3_ANGULAR][i] += s->cfg.sim_alpha_bias[i];
    }
}

static int write_can(sim_t *s, loadid_can_frame_t *f) {
    if (loadid_damage_now(&s->damage, LOADID_DAMAGE_BIT_ERRORS)) {
        unsigned bit = loadid_damage_pick(&s->damage, 64);
        f->data[bit / 8] ^= (uint8_t)(1u << (bit % 8));
        s->sample_damage |= SAMPLE_BIT_FLIPPED;
    }
    s->last_can_us = f->t_us;
    return loadid_recording_can(s->rec, f);
}

/* The four frames of CAN sample k stamped utime t (its motion at simulation
 * time sim_t_s), with any damage asked for. */
static int can_sample(sim_t *s, int64_t k, int64_t t, double sim_t_s) {
    loadid_servo_state_t st;
    loadid_motion_t m;
    int rc = motion_at(s, sim_t_s, &st, &m);
    if (rc != 0) return rc;
    double value[4][3];
    measure(s, sim_t_s, &m, value);
    const int saturate = loadid_damage_now(&s->damage, LOADID_DAMAGE_SATURATE);
    if (saturate) value[LOADID_JR3_FORCE][0] = 3 * s->jr3.full_scale[LOADID_JR3_FORCE][0];
    const unsigned fault =
        loadid_damage_now(&s->damage, LOADID_DAMAGE_FAULT) ? LOADID_JR3_ALL_GROUPS : 0;
    loadid_can_frame_t frames[4];
    int sat = loadid_jr3_encode(&s->jr3, (const double(*)[3])value, (uint8_t)(k & 0xFF), fault, t,
                                frames);
    if (sat < 0) return sat;
    s->samples++;
    if (sat) s->saturated_samples++;
    s->sample_damage = (sat ? SAMPLE_SATURATED : 0) | (fault ? SAMPLE_FAULT : 0);
    if (loadid_damage_now(&s->damage, LOADID_DAMAGE_SKIP_SAMPLES)) {
        s->sample_damage |= SAMPLE_SKIPPED;
    } else {
        for (int g = 0; g < 4; ++g) {
            frames[g].t_us = t + g * FRAME_GAP_US;
            if (loadid_damage_now(&s->damage, LOADID_DAMAGE_DROP_FRAMES)) {
                s->sample_damage |= SAMPLE_FRAME_DROPPED;
                continue;
            }
            if ((rc = write_can(s, &frames[g])) != 0) return rc;
        }
    }
    if (s->values) {
        fprintf(s->values, "%lld,%u", (long long)t, (unsigned)(k & 0xFF));
        for (int g = 0; g < 4; ++g)
            for (int i = 0; i < 3; ++i) fprintf(s->values, ",%.17g", value[g][i]);
        fprintf(s->values, ",%u\n", s->sample_damage);
    }
    if (s->sample_damage & SAMPLE_SKIPPED) return 0;
    if (loadid_damage_now(&s->damage, LOADID_DAMAGE_BAD_FRAMES)) {
        loadid_can_frame_t bad = frames[0];
        bad.t_us = t + 4 * FRAME_GAP_US;
        if (loadid_damage_pick(&s->damage, 2))
            bad.dlc = 6;
        else
            bad.id = s->jr3.base_id + 7;
        s->last_can_us = bad.t_us;
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

/* The joint state of simulation time sim_t_s, stamped utime t. */
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
    s->last_joint_us = t;
    return loadid_recording_joints(s->rec, t, s->chain.num_joints, pos, st.setpoint);
}

/* The stamp of an event due at utime t: t plus uniform integer jitter in
 * [-N, N] us, clipped to 1 us after last (its stream's previous stamp).
 * Without jitter, t untouched and nothing drawn. */
static int64_t jittered(sim_t *s, int64_t t, int64_t last) {
    const int n = s->cfg.sim_jitter_us;
    if (n <= 0) return t;
    int64_t j = (int64_t)floor(loadid_rng_uniform(&s->jitter_rng) * (2 * n + 1)) - n;
    if (j > n) j = n; /* uniform() < 1, but stay safe */
    if (t + j <= last) {
        s->jitter_clipped++;
        return last + 1;
    }
    return t + j;
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
    fprintf(f, "# What loadid-sim simulated (docs/INTERFACE.md recording format).\n");
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
    fprintf(f,
            "\nnoise:\n  force: %.17g\n  torque: %.17g\n  linear: %.17g\n  angular: %.17g\n"
            "  ft_correlation: %.17g\n",
            c->sim_noise_force, c->sim_noise_torque, c->sim_noise_linear, c->sim_noise_angular,
            c->sim_noise_ft_correlation);
    fprintf(f, "vibration:\n  hz: %.17g\n  linear: %.17g\n  angular: %.17g\n  start_s: %.17g\n",
            c->sim_vibration_hz, c->sim_vibration_linear, c->sim_vibration_angular,
            c->sim_vibration_start_s);
    fprintf(f, "servo:\n  bandwidth_hz: %.17g\n  damping: %.17g\n  backlash: %.17g\n",
            c->sim_servo_bandwidth_hz, c->sim_servo_damping, c->sim_backlash);
    fprintf(f, "encoder_counts: %.17g\n", c->sim_encoder_counts);
    fprintf(f, "robot:\n  urdf: \"%s\"\n  base_link: \"%s\"\n  sensor_link: \"%s\"\n",
            c->robot_urdf, c->robot_base_link, c->robot_sensor_link);
    fprintf(f, "trajectory:\n  file: \"%s\"\n  kappa_design: %.17g\n", traj_path, s->kappa_design);
    fprintf(f, "can:\n  interface: \"%s\"\n  base_id: 0x%X\n", c->can_interface,
            (unsigned)c->can_base_id);
    fprintf(f, "jr3_full_scale:\n");
    const char *g[4] = {"force", "moment", "linear", "angular"};
    for (int i = 0; i < 4; ++i) {
        fprintf(f, "  %s: ", g[i]);
        list(f, s->jr3.full_scale[i], 3);
        fputc('\n', f);
    }
    fprintf(f,
            "times:                 # utime [us]\n  begin: %lld\n  zero: %lld\n  start: %lld\n"
            "  trajectory: %lld\n  active_end: %lld\n  end: %lld\n",
            (long long)t0, (long long)zero_us, (long long)start_us, (long long)traj_us,
            (long long)active_end_us, (long long)end_us);
    loadid_recording_counts_t rc;
    loadid_recording_counts(s->rec, &rc);
    fprintf(f,
            "counts:\n  samples: %lld\n  saturated_samples: %lld\n  can_frames: %lld\n"
            "  joint_msgs: %lld\n  commands: %lld\n",
            (long long)s->samples, (long long)s->saturated_samples, (long long)rc.can_frames,
            (long long)rc.joint_msgs, (long long)rc.commands);
    fprintf(f, "damage:\n");
    for (int k = 0; k < LOADID_DAMAGE_KINDS; ++k)
        fprintf(f, "  %s: {probability: %.17g, count: %lld}\n", loadid_damage_name(k),
                s->damage.p[k], (long long)s->damage.count[k]);
    fprintf(f, "  stall-joints: {from_s: %.17g, to_s: %.17g, count: %lld}\n", s->damage.stall_from,
            s->damage.stall_to, (long long)s->damage.stalled_joint_msgs);
    fprintf(f,
            "simulation:            # imitating real hardware data (loadid.yaml simulation.*)\n"
            "  zero: %s\n  still_s: %.17g\n  drift: ",
            c->sim_zero ? "true" : "false", c->sim_still_s);
    list(f, c->sim_drift, 6);
    fprintf(f, "\n  accel_bias: ");
    list(f, c->sim_accel_bias, 3);
    fprintf(f, "\n  alpha_bias: ");
    list(f, c->sim_alpha_bias, 3);
    fprintf(f, "\n  jitter_us: %d\n  jitter_clipped: %lld\n  trajectory_scale: %.17g\n",
            c->sim_jitter_us, (long long)s->jitter_clipped, c->sim_trajectory_scale);
    int e = ferror(f) ? EIO : 0;
    if (fclose(f) != 0 && !e) e = errno;
    return -e;
}

/* Frees s and reports why in err; returns rc. */
static int fail(sim_t *s, char *err, size_t errlen, int rc, const char *what) {
    if (err && errlen)
        snprintf(err, errlen, "%s: %s", what, rc > -1000 ? strerror(-rc) : loadid_strerror(rc));
    loadid_kin_destroy(s->kin);
    free(s);
    return rc;
}

int loadid_sim_run(const loadid_sim_options_t *o, loadid_sim_summary_t *sum, char *err,
                   size_t errlen) {
    sim_t *s = calloc(1, sizeof *s);
    if (!s) return -ENOMEM;
    s->cfg = *o->cfg;
    s->chain = *o->chain;
    s->traj = *o->traj;
    s->kappa_design = o->kappa_design;
    /* simulation.trajectory_scale: s_i(t) of eqs. (10)-(11) is linear in
     * the coefficients, so scaling them scales it (q_0 stays). */
    const double scale = s->cfg.sim_trajectory_scale;
    if (scale != 1.0)
        for (int i = 0; i < s->traj.num_joints; ++i)
            for (int k = 0; k < LOADID_TRAJ_MAX_HARMONICS; ++k) {
                s->traj.rho[i][k] *= scale;
                s->traj.delta[i][k] *= scale;
            }
    if (o->warn && s->cfg.sim_zero && s->cfg.sim_still_s < ZERO_AT_S + s->cfg.zeroing_window_s) {
        char msg[160];
        snprintf(msg, sizeof msg,
                 "simulation.still_s %.3g s leaves less than zeroing.window_s "
                 "after ZERO at %.2f s",
                 s->cfg.sim_still_s, ZERO_AT_S);
        o->warn(o->warn_ctx, msg);
    }
    int rc = loadid_kin_create(&s->chain, s->cfg.robot_gravity, &s->kin);
    if (rc != 0) return fail(s, err, errlen, rc, "cannot build the kinematics");
    loadid_setup_jr3(&s->cfg, &s->jr3);
    if (loadid_jr3_config_check(&s->jr3) != 0)
        return fail(s, err, errlen, -EINVAL, "invalid JR3 configuration (can.base_id, jr3.*)");
    loadid_rng_seed(&s->rng, o->seed);
    loadid_damage_init(&s->damage, o->seed);
    loadid_rng_seed(&s->jitter_rng, o->seed ^ 0xD1B54A32D192ED03ull); /* apart from both */
    s->last_joint_us = s->last_can_us = INT64_MIN;
    memcpy(s->damage.p, o->damage.p, sizeof s->damage.p);
    s->damage.stall_from = o->damage.stall_from, s->damage.stall_to = o->damage.stall_to;
    for (int a = 0; a < 2; ++a)
        for (int i = 0; i < 3; ++i) s->vib_phase[a][i] = kTwoPi * loadid_rng_uniform(&s->rng);

    const double traj_start = s->cfg.sim_still_s;
    const double active_start = traj_start + loadid_traj_active_start(&s->traj);
    const double total = traj_start + loadid_traj_duration(&s->traj) + TAIL_S;
    loadid_servo_config_t servo = {.bandwidth_hz = s->cfg.sim_servo_bandwidth_hz,
                                   .damping = s->cfg.sim_servo_damping,
                                   .backlash = s->cfg.sim_backlash};
    loadid_servo_init(&s->servo, &servo, &s->traj, traj_start);
    if ((rc = loadid_recording_open(o->out_dir, s->cfg.can_interface, &s->rec, err, errlen)) != 0) {
        loadid_kin_destroy(s->kin);
        free(s);
        return rc;
    }
    if (o->values_path) {
        s->values = fopen(o->values_path, "w");
        if (!s->values) {
            rc = -errno;
            loadid_recording_close(s->rec);
            return fail(s, err, errlen, rc, "cannot write the --values file");
        }
        fprintf(s->values, "t_us,sequence,fx,fy,fz,tx,ty,tz,ax,ay,az,alx,aly,alz,damage\n");
    }
    const int64_t t0 = o->start_utime;
    const int64_t zero_us = t0 + (int64_t)llround(ZERO_AT_S * 1e6);
    const int64_t start_us = t0 + (int64_t)llround(active_start * 1e6);
    const long ticks = lround(total * 1000);
    for (long k = 0; k < ticks && rc == 0; ++k) {
        const int64_t tj = t0 + (int64_t)k * 1000;
        /* The joint state's stamp, jittered; lcm.log stays in time order
         * when it falls before this tick's commands (at tj). */
        const int64_t sj = jittered(s, tj, s->last_joint_us);
        const int early = sj < tj;
        if (early) rc = joint_state(s, sj, k * 1e-3);
        if (rc == 0 && s->cfg.sim_zero && tj == zero_us)
            rc = loadid_recording_command(s->rec, tj, 1, o->load_name);
        if (rc == 0 && tj == start_us) rc = loadid_recording_command(s->rec, tj, 2, o->load_name);
        if (rc == 0 && !early) rc = joint_state(s, sj, k * 1e-3);
        const int64_t tc = tj + CAN_PHASE_US;
        const int64_t sc = jittered(s, tc, s->last_can_us); /* the sample's stamp */
        if (rc == 0) rc = can_sample(s, k, sc, (tc - t0) * 1e-6);
        if (rc == 0 && k % 1000 == 500) rc = full_scale_frames(s, sc + 4 * FRAME_GAP_US);
    }
    if (rc == 0)
        rc = write_truth(s, o->out_dir, o->traj_path, o->load_name, o->seed, t0,
                         s->cfg.sim_zero ? zero_us : -1, start_us,
                         t0 + (int64_t)llround(traj_start * 1e6),
                         start_us + (int64_t)llround(s->traj.active_s * 1e6), t0 + ticks * 1000);
    int crc = loadid_recording_close(s->rec);
    if (s->values && fclose(s->values) != 0 && rc == 0) rc = -errno;
    if (rc == 0) rc = crc;
    if (rc != 0) return fail(s, err, errlen, rc, "writing the recording failed");
    if (sum) {
        sum->samples = s->samples;
        sum->duration_s = total;
        sum->zero_s = s->cfg.sim_zero ? ZERO_AT_S : -1;
        sum->jitter_clipped = s->jitter_clipped;
        sum->start_s = active_start;
    }
    loadid_kin_destroy(s->kin);
    free(s);
    return 0;
}
