/*
 * Design of an excitation trajectory (paper sec. III) for one robot: the
 * objective is the condition number of the weighted data matrix the
 * estimator will see, computed from setpoint kinematics; the search is a
 * Monte Carlo stage over random Fourier coefficients followed by a local
 * constrained optimisation (NLopt's COBYLA) of the best candidates. Every
 * iterate is checked against the joint position, velocity and acceleration
 * limits and the workspace (a box and a floor plane for the origin of S),
 * and the result is verified at 10 kHz over the whole trajectory, fades
 * included, before it is returned.
 *
 * kappa here is kappa(D A_Xi T): the estimator's condition_number
 * (loadid_est_info_t), with the estimator's row and column weights and its
 * data matrix (eq. 6 with the zeroing term of eqs. 7-9, or [A E6]).
 * kappa(Upsilon) of eq. (12) is its square; both have the same minimiser.
 */
#ifndef LOADID_TRAJ_DESIGN_H
#define LOADID_TRAJ_DESIGN_H

#include <stdint.h>

#include "fourier_traj.h"
#include "loadid/core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int num_joints;
    double lower[LOADID_MAX_JOINTS], upper[LOADID_MAX_JOINTS]; /* position */
    double velocity[LOADID_MAX_JOINTS];                        /* |qd| max */
    double acceleration[LOADID_MAX_JOINTS];                    /* |qdd| max */
    double ws_min[3], ws_max[3]; /* box for the origin of S, base frame [m] */
    double floor_z;              /* origin of S must keep z >= floor_z [m]
                                     (clearance included) */
} loadid_traj_limits_t;

/* Which limit is broken the most, and where. */
typedef struct {
    double excess;    /* > 0: by how much, relative to the limit
                                     (workspace: in metres); <= 0: all met */
    const char *what; /* "position", "velocity", "acceleration",
                                     "workspace", "floor" */
    int joint;        /* joint index, or axis for workspace */
    double t;         /* time [s] */
} loadid_traj_violation_t;

typedef struct {
    const loadid_kin_t *kin; /* the robot (not owned) */
    loadid_traj_limits_t limits;
    loadid_est_config_t est; /* weights and n_params of the estimator
                                     (method is ignored: RLS is used) */
    int zeroing;             /* 1: eqs. 7-9 with g_init at q_0 (n_params 10) */
    double objective_hz;     /* sampling of the objective, default 100 */
    double constraint_hz;    /* sampling of the constraints, default 200 */
    double margin;           /* limits shrunk by this fraction while
                                     optimising, default 0.02 */
} loadid_traj_problem_t;

/* Sets the sampling rates and margin to their defaults. */
void loadid_traj_problem_defaults(loadid_traj_problem_t *p);

/* kappa of the setpoint data over the active part, sampled at rate_hz.
 * Returns kappa (+inf when rank-deficient), or NAN on a core error. */
double loadid_traj_kappa(const loadid_traj_problem_t *p, const loadid_fourier_traj_t *tr,
                         double rate_hz);

/* Checks every limit over [0, t_3] at rate_hz with the limits shrunk by
 * `shrink` (0 = the limits themselves). Returns 1 when all hold, else 0;
 * worst (may be NULL) gets the largest excess. */
int loadid_traj_check(const loadid_traj_problem_t *p, const loadid_fourier_traj_t *tr,
                      double rate_hz, double shrink, loadid_traj_violation_t *worst);

typedef struct {
    int monte_carlo; /* random candidates */
    int candidates;  /* best ones refined by NLopt */
    int max_evals;   /* NLopt evaluations per candidate */
    uint64_t seed;
    int optimise_home; /* 0: keep tr->q0 as given; 1: optimise q0 too */
    /* Progress (may be NULL): stage "monte-carlo" (candidates, every 100)
     * or "optimise" (NLopt's evaluations over all candidates, every 100,
     * and at each candidate's end: done = its whole budget), done/total. */
    void (*progress)(void *ctx, const char *stage, int done, int total, double best_kappa);
    void *progress_ctx;
} loadid_traj_search_t;

typedef struct {
    double kappa_monte_carlo; /* best feasible kappa of the Monte Carlo stage */
    double kappa_optimised;   /* the result's kappa at objective_hz */
    int evaluations;          /* objective evaluations in total */
    int feasible_candidates;  /* Monte Carlo candidates within the limits */
} loadid_traj_search_result_t;

/* Designs a trajectory: tr holds the template on entry (num_joints,
 * harmonics, base_frequency, active_s, fade_s, q0 as the home pose or the
 * starting point) and the result on success. Returns 0, -EINVAL (bad
 * template or problem), -ENOMEM, or -ERANGE when no candidate within the
 * limits was found (tr unchanged). */
int loadid_traj_design(const loadid_traj_problem_t *p, const loadid_traj_search_t *search,
                       loadid_fourier_traj_t *tr, loadid_traj_search_result_t *result);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_TRAJ_DESIGN_H */
