/*
 * The data matrix A of eq. (6): the wrench a rigid load exerts on the sensor
 * is linear in its ten inertial parameters, [f; tau] = A(a-g, w, alpha) phi.
 *
 * Conventions (docs/INTERFACE.md): all vectors in the sensor frame S;
 *   spec = a - g, the specific force of the origin of S (what an
 *          accelerometer at that point reads; [0 0 +9.81] at rest, z up);
 *   phi  = [m, m cx, m cy, m cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz], the inertia
 *          tensor about the origin of S.
 * Matrices are row-major: A[r * ncols + c].
 */
#ifndef LOADID_REGRESSOR_H
#define LOADID_REGRESSOR_H

#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fills A (6x10, row-major) with eq. (6).
 * spec: a - g [m/s^2]; omega: angular velocity [rad/s];
 * alpha: angular acceleration [rad/s^2].
 * Returns 0, -EINVAL for a NULL pointer, LOADID_E_NONFINITE for NaN/Inf
 * input (A is then left untouched). */
int loadid_regressor(const loadid_real_t spec[3], const loadid_real_t omega[3],
                     const loadid_real_t alpha[3], loadid_real_t A[6 * 10]);

/* Adds the zeroing term of eqs. (7)-(9) to A (6x10, in place):
 * A_offs = A + [A~(g_init) 0_6x6]. g_init is the gravity vector in S at the
 * pose where the wrench was zeroed [m/s^2] (e.g. [0 0 -9.81] with z up).
 * Use it when y is the measured wrench minus the wrench read at zeroing.
 * Returns 0, -EINVAL, or LOADID_E_NONFINITE (A untouched). */
int loadid_regressor_add_zeroing(const loadid_real_t g_init[3], loadid_real_t A[6 * 10]);

/* Eqs. (7)-(9) for a load that may move while it is zeroed: A - A0, A0
 * the mean of eq. (6) over the zeroing window, where the mean wrench is
 * A0 phi plus the offset. At rest A0 = A(-g_init, 0, 0), and this is
 * loadid_regressor_add_zeroing; a load turning while it was zeroed (no
 * still phase) has a mean acceleration, alpha and omega^2 there that
 * A(-g_init, 0, 0) lacks. A, A0: 6x10 row-major; A in place.
 * Returns 0, -EINVAL, or LOADID_E_NONFINITE (A untouched). */
int loadid_regressor_subtract_zeroing(const loadid_real_t A0[6 * 10], loadid_real_t A[6 * 10]);

/* Widens a 6x10 regressor into the 16-parameter model [A E6] (6x16,
 * row-major) whose last six parameters are the sensor offset [o_f; o_tau],
 * so no zeroing is needed. A and A16 must not overlap.
 * Returns 0 or -EINVAL. */
int loadid_regressor_with_offset(const loadid_real_t A[6 * 10], loadid_real_t A16[6 * 16]);

/* The data matrix of an estimation model in one call: n_params 10 gives
 * eq. (6), plus the zeroing term of eqs. (7)-(9) when g_init is not NULL;
 * n_params 16 gives [A E6] (g_init ignored). A holds 6 x n_params.
 * Returns 0, -EINVAL (NULL pointer, n_params not 10 or 16) or
 * LOADID_E_NONFINITE (A untouched). */
int loadid_regressor_model(const loadid_real_t spec[3], const loadid_real_t omega[3],
                           const loadid_real_t alpha[3], int n_params,
                           const loadid_real_t g_init[3], loadid_real_t *A);

/* The same with the zeroing term of a load that may have moved while it
 * was zeroed: n_params 10 gives eq. (6) less zero_a, eq. (6) averaged over
 * the zeroing window (loadid_regressor_subtract_zeroing; not NULL);
 * n_params 16 gives [A E6] (zero_a ignored). Same returns. */
int loadid_regressor_model_zeroed(const loadid_real_t spec[3], const loadid_real_t omega[3],
                                  const loadid_real_t alpha[3], int n_params,
                                  const loadid_real_t zero_a[6 * 10], loadid_real_t *A);

/* The wrench the model predicts: y = A phi for an A of n_params columns
 * (10 or 16). Returns 0 or -EINVAL. */
int loadid_regressor_apply(const loadid_real_t *A, int n_params, const loadid_real_t *phi,
                           loadid_real_t y[6]);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_REGRESSOR_H */
