/*
 * From the parameter vector phi (eq. 5) to physical quantities, the checks
 * that tell whether phi can belong to a real rigid body, the subtraction of
 * the distal sensor part, and the relative error of eq. (37).
 */
#ifndef LOADID_INERTIA_H
#define LOADID_INERTIA_H

#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bits of loadid_physical_t.violations. */
enum {
    LOADID_PHYS_MASS_NOT_POSITIVE = 1 << 0,    /* m <= 0 */
    LOADID_PHYS_INERTIA_NOT_PD = 1 << 1,       /* I about the COM not positive definite */
    LOADID_PHYS_TRIANGLE = 1 << 2,             /* principal moments break I1 + I2 >= I3 */
    LOADID_PHYS_PSEUDO_INERTIA_NOT_PD = 1 << 3 /* 4x4 pseudo-inertia not positive definite */
};

typedef struct {
    loadid_real_t mass;           /* [kg] */
    loadid_real_t com[3];         /* [m] in S; 0 when mass <= 0 */
    loadid_real_t inertia_com[6]; /* [Ixx Ixy Ixz Iyy Iyz Izz] about the COM, axes of S [kg m^2] */
    loadid_real_t principal[3];   /* eigenvalues of the inertia about the COM, ascending [kg m^2] */
    int violations;               /* LOADID_PHYS_* bits; 0 = physically consistent */
} loadid_physical_t;

/* Mass, COM, inertia about the COM by the parallel-axis theorem
 * I_C = I_S - m (c.c E - c c^T), principal moments, and the consistency
 * checks: positive mass, positive-definite inertia about the COM, triangle
 * inequalities of the principal moments, positive-definite pseudo-inertia
 * J = [0.5 tr(I_S) E - I_S, m c; (m c)^T, m] (tested through its Schur
 * complement 0.5 tr(I_C) E - I_C, in kg m^2). Each test has a relative
 * tolerance of 1e-9 (double) or 1e-5 (float) of the largest principal
 * moment.
 * Returns 0 (also when phi is inconsistent: see violations), -EINVAL, or
 * LOADID_E_NONFINITE. */
int loadid_phi_to_physical(const loadid_real_t phi[10], loadid_physical_t *out);

/* The inverse: phi from mass, COM and inertia about the COM. Returns 0 or
 * -EINVAL. */
int loadid_phi_from_physical(loadid_real_t mass, const loadid_real_t com[3],
                             const loadid_real_t inertia_com[6], loadid_real_t phi[10]);

/* Distal sensor part compensation: load = measured - distal (phi is linear
 * in mass distribution, so rigidly joined bodies add). out may alias
 * measured. Returns 0 or -EINVAL. */
int loadid_phi_subtract(const loadid_real_t measured[10], const loadid_real_t distal[10],
                        loadid_real_t out[10]);

/* Eq. (37): e_rel = |(est - truth) / truth| * 100 [%], per element.
 * Where truth is 0 the ratio is undefined: out is then 0 if est is 0 too,
 * else +Inf. Returns 0 or -EINVAL. */
int loadid_relative_error(const loadid_real_t *est, const loadid_real_t *truth, int n,
                          loadid_real_t *out);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_INERTIA_H */
