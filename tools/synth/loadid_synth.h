/*
 * Synthetic rigid-body motion of the sensor frame S and the wrench a load
 * exerts on it, for the demo, the tests and the benchmarks (double only).
 *
 * The motion: orientation R(t) = Rz(psi) Ry(theta) Rx(phi) and position p(t)
 * of S in the base frame, each of the six coordinates a finite Fourier
 * series as in eqs. (10)-(11) of the paper, with exact derivatives. From
 * them: w and alpha in S, and a - g = R^T (p'' - g_base).
 *
 * The wrench is computed from eqs. (1)-(2) with explicit cross products and
 * the inertia tensor, independently of the core's regressor, so tests can
 * compare the two.
 */
#ifndef LOADID_SYNTH_H
#define LOADID_SYNTH_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* xoshiro256** pseudo-random numbers: the same sequence on every machine. */
typedef struct {
    uint64_t s[4];
    int has_spare;
    double spare;
} loadid_rng_t;

void loadid_rng_seed(loadid_rng_t *rng, uint64_t seed);
double loadid_rng_uniform(loadid_rng_t *rng); /* [0, 1) */
double loadid_rng_normal(loadid_rng_t *rng);  /* N(0, 1), Box-Muller */

#define LOADID_SYNTH_MAX_HARMONICS 8

/* Six coordinates: 0-2 Euler angles psi (z), theta (y), phi (x) [rad];
 * 3-5 position of the origin of S in the base frame [m]. */
typedef struct {
    double base_freq;                               /* f of eq. (10) [Hz] */
    int harmonics;                                  /* N of eq. (10) */
    double offset[6];                               /* q_0 of eq. (11) */
    double sin_coef[6][LOADID_SYNTH_MAX_HARMONICS]; /* rho_{i,k} */
    double cos_coef[6][LOADID_SYNTH_MAX_HARMONICS]; /* delta_{i,k} */
    double gravity[3];                              /* in the base frame [m/s^2] */
} loadid_synth_traj_t;

/* The true kinematic state of S at one instant, all in S. */
typedef struct {
    double spec[3];  /* a - g [m/s^2] */
    double omega[3]; /* [rad/s] */
    double alpha[3]; /* [rad/s^2] */
    double g[3];     /* gravity in S [m/s^2] */
} loadid_motion_t;

/* A well-exciting default trajectory: base 0.4 Hz, 5 harmonics (highest
 * 2 Hz, the paper's limit), random coefficients from seed, scaled so the
 * angular acceleration stays within about +-40 rad/s^2 and the linear
 * acceleration within about +-10 m/s^2. Gravity [0 0 -9.81]. */
void loadid_synth_traj_default(loadid_synth_traj_t *traj, uint64_t seed);

/* The state of S at time t [s]. still != 0 evaluates the pose q_0 at rest
 * (the zeroing pose). Returns 0, or -EINVAL for NULL pointers. */
int loadid_synth_motion(const loadid_synth_traj_t *traj, double t, int still, loadid_motion_t *out);

/* Eqs. (1)-(2): the wrench [f; tau] that a load with phi (eq. 5) exerts on
 * the sensor in the state m. */
void loadid_synth_wrench(const double phi[10], const loadid_motion_t *m, double wrench[6]);

/* Noise of one synthetic measurement (standard deviations, white Gaussian)
 * and the sensor's constant offset. */
typedef struct {
    double sigma_f;     /* force [N] */
    double sigma_tau;   /* torque [Nm] */
    double sigma_spec;  /* a - g [m/s^2] */
    double sigma_alpha; /* angular acceleration [rad/s^2] */
    double sigma_omega; /* angular velocity [rad/s] */
    double offset[6];   /* F/T offset [N, Nm] added to every wrench */
} loadid_synth_noise_t;

typedef struct {
    loadid_motion_t truth; /* exact state */
    loadid_motion_t meas;  /* state with noise (g: exact) */
    double wrench_true[6]; /* eqs. (1)-(2) of the exact state, no offset */
    double wrench_meas[6]; /* plus offset and noise */
} loadid_synth_sample_t;

/* One measurement at time t of a load phi on trajectory traj. noise may be
 * NULL (exact data). Draws from rng in a fixed order. Returns 0 or -EINVAL. */
int loadid_synth_sample(const loadid_synth_traj_t *traj, const double phi[10], double t, int still,
                        const loadid_synth_noise_t *noise, loadid_rng_t *rng,
                        loadid_synth_sample_t *out);

/* The paper's load o1 (section V.A), eq. (5) units. */
extern const double loadid_synth_phi_o1[10];

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SYNTH_H */
