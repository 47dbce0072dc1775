/*
 * Forward kinematics of the sensor frame S (paper sec. IV.A): from joint
 * positions, velocities and accelerations to what the regressor of eq. (6)
 * needs, all expressed in S:
 *   omega, alpha        angular velocity and acceleration of S
 *   accel               linear (classical) acceleration of the origin of S
 *   gravity             the gravity vector in S
 *   spec = accel - gravity, the specific force (a - g) of the origin of S
 * plus the pose of S in the base frame. One recursive pass over the chain
 * (Newton-Euler's forward recursion), no allocation after create.
 */
#ifndef LOADID_KINEMATICS_H
#define LOADID_KINEMATICS_H

#include "loadid/chain.h"
#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    loadid_real_t rotation[9]; /* R from S to base, row-major: its columns
                                     are S's axes in the base frame */
    loadid_real_t position[3]; /* origin of S in the base frame [m] */
    loadid_real_t omega[3];    /* [rad/s], in S */
    loadid_real_t alpha[3];    /* [rad/s^2], in S */
    loadid_real_t accel[3];    /* [m/s^2], in S */
    loadid_real_t gravity[3];  /* [m/s^2], in S */
    loadid_real_t spec[3];     /* accel - gravity [m/s^2], in S */
} loadid_kin_state_t;

typedef struct loadid_kin loadid_kin_t; /* opaque */

/* Builds the kinematics of a chain (copied; loadid_chain_check must pass)
 * with gravity given in the base frame [m/s^2] (docs/INTERFACE.md default
 * [0 0 -9.81]). The only allocation. Returns 0, -EINVAL (NULL pointer, a
 * chain that fails the check, gravity not finite) or -ENOMEM. */
int loadid_kin_create(const loadid_chain_t *chain, const double gravity[3], loadid_kin_t **out);

void loadid_kin_destroy(loadid_kin_t *kin);

/* Number of movable joints (the length of q, qd, qdd). */
int loadid_kin_num_joints(const loadid_kin_t *kin);

/* Evaluates S at joint positions q, velocities qd and accelerations qdd
 * (num_joints values each; qd and qdd may be NULL for zero).
 * Returns 0, -EINVAL (NULL kin, q or out) or LOADID_E_NONFINITE (an input
 * not finite; out untouched). */
int loadid_kin_eval(const loadid_kin_t *kin, const loadid_real_t *q, const loadid_real_t *qd,
                    const loadid_real_t *qdd, loadid_kin_state_t *out);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_KINEMATICS_H */
