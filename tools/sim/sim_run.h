/*
 * The simulator of loadid-sim as a library: the robot following an
 * excitation trajectory with a load on its wrist sensor, written as a
 * recording folder (docs/INTERFACE.md):
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
#ifndef LOADID_SIM_RUN_H
#define LOADID_SIM_RUN_H

#include <stddef.h>
#include <stdint.h>

#include "fourier_traj.h"
#include "loadid/chain.h"
#include "loadid/config.h"
#include "sim_damage.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const loadid_config_t *cfg;        /* robot, noise, simulation.*, jr3.*, can.*, distal */
    const loadid_chain_t *chain;       /* the robot's chain (from cfg's URDF) */
    const loadid_fourier_traj_t *traj; /* its joints in the chain's order */
    double kappa_design;               /* the trajectory file's, for truth.yaml */
    const char *traj_path;             /* for truth.yaml */
    const char *out_dir;               /* created if missing */
    const char *values_path;           /* NULL, or the --values CSV */
    const char *load_name;             /* in the commands and truth.yaml */
    uint64_t seed;
    int64_t start_utime;                      /* time of the first joint state [us] */
    loadid_damage_t damage;                   /* probabilities and stall window */
    void (*warn)(void *ctx, const char *msg); /* a one-line warning; may be NULL */
    void *warn_ctx;
} loadid_sim_options_t;

typedef struct {
    int64_t samples;                    /* CAN samples simulated */
    double duration_s, zero_s, start_s; /* length; ZERO (-1: none, simulation.zero
                                           false) and START after the start */
    int64_t jitter_clipped;             /* jittered stamps clipped to keep order */
} loadid_sim_summary_t;

/* Simulates and writes out_dir/can.log, lcm.log, truth.yaml (its times.zero
 * is -1 without a ZERO command). Returns 0, or
 * a negative code with a one-line reason in err. sum may be NULL. */
int loadid_sim_run(const loadid_sim_options_t *o, loadid_sim_summary_t *sum, char *err,
                   size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SIM_RUN_H */
