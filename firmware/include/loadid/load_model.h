/*
 * The load a controller should use, made from one method's estimate: which
 * groups of phi the data determine (identified), and the nearest
 * physically consistent phi (load_model_t of proto/).
 *
 * Identified, from the estimate's own standard deviations (phi_std):
 *   MASS     m > 0 and std(m) <= mass_rel_std * m
 *   COM      MASS, and every axis of c = m c / m within com_std
 *            (std(c_i) ~ sqrt(std(m c_i)^2 + c_i^2 std(m)^2) / m)
 *   INERTIA  COM, the largest std of the six I_S elements within
 *            inertia_rel_std of the inertia's scale (the mean principal
 *            moment about the COM, at least that of a sphere of the
 *            fallback density), a radius of gyration sqrt(tr(I_C) / 2m)
 *            within max_gyration, and the torque the inertia explains at
 *            least min_snr times the torque rows' noise (snr[2], from
 *            loadid_est_signal_to_noise): a slow, mostly translational
 *            motion gives the inertia too little torque to stand out of a
 *            drift or a model error of the noise's size, whatever its
 *            statistical std says.
 *
 * The model phi:
 *   - mass and COM as estimated (an unidentified one is kept, and flagged;
 *     m <= 0 gives phi = 0, no load);
 *   - inertia about the COM made physically consistent: the second moment
 *     of the mass distribution Sigma_C = tr(I_C)/2 E - I_C must be positive
 *     semidefinite (the pseudo-inertia J >= 0 with m > 0; Wensing, Kim &
 *     Slotine 2017). Its eigenvalues below a millionth of the largest are
 *     raised to that, which is the nearest such Sigma_C in the Frobenius
 *     norm (the principal axes are kept; Higham 1988), and
 *     I_C = tr(Sigma_C) E - Sigma_C;
 *   - an unidentified inertia is replaced by the fallback: a uniform solid
 *     sphere of fallback_density at the COM, I_C = 2/5 m r^2 E,
 *     r = (3 m / (4 pi rho))^(1/3), which is consistent, small and never
 *     the wild value of a badly excited estimate.
 * projected is set when the model phi differs from the estimate by more
 * than rounding. For each group not identified, why (the first test it
 * failed, in the order above) and by how much (over: the tested value
 * over its bound, or the bound over snr[2]; 0 for a missing prerequisite
 * or no positive mass; NaN for a std that is not a number).
 */
#ifndef LOADID_LOAD_MODEL_H
#define LOADID_LOAD_MODEL_H

#include "loadid/inertia.h"
#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bits of identified: load_model_t's constants. */
enum { LOADID_IDENT_MASS = 1, LOADID_IDENT_COM = 2, LOADID_IDENT_INERTIA = 4 };

/* Why a group is not identified (why[] of loadid_load_model_t). */
typedef enum {
    LOADID_WHY_IDENTIFIED = 0,
    LOADID_WHY_NO_MASS,     /* m <= 0: no load */
    LOADID_WHY_STD,         /* its std over the bound (over: std / bound) */
    LOADID_WHY_NEEDS,       /* COM without the mass, inertia without the COM */
    LOADID_WHY_GYRATION,    /* radius of gyration over max_gyration (over: r / max) */
    LOADID_WHY_SNR,         /* its torque under min_snr times the noise (over: min_snr / snr) */
    LOADID_WHY_JOINT_NOISE, /* the joints noisier than the filters assume (over: that factor) */
    LOADID_WHY_JOINT_STAMPS /* the joint stamps lost their rate (over: how often in the window) */
} loadid_ident_why_t;

typedef struct {
    loadid_real_t mass_rel_std;     /* [-], default 0.025 */
    loadid_real_t com_std;          /* [m], default 0.005 */
    loadid_real_t inertia_rel_std;  /* [-], default 0.15 */
    loadid_real_t max_gyration;     /* [m], default 0.5 */
    loadid_real_t min_snr;          /* [-], default 1 */
    loadid_real_t fallback_density; /* [kg/m^3], default 2700 (aluminium) */
} loadid_model_config_t;

typedef struct {
    int identified;             /* LOADID_IDENT_* bits */
    int projected;              /* phi differs from the estimate */
    int why[3];                 /* mass, COM, inertia: loadid_ident_why_t */
    loadid_real_t over[3];      /* how far the failed test is over its bound */
    loadid_real_t phi[10];      /* physically consistent (eq. 5) */
    loadid_physical_t physical; /* mass, COM, inertia about the COM of phi */
} loadid_load_model_t;

void loadid_model_config_default(loadid_model_config_t *cfg);

/* estimate: a method's phi (load only); std: its standard deviations
 * (+Inf allowed: that group is then not identified); snr: the groups'
 * signal-to-noise ratios (loadid_est_signal_to_noise), or NULL to skip
 * that test. Returns 0, -EINVAL (NULL, or a config value not finite and
 * > 0) or LOADID_E_NONFINITE (estimate not finite). No allocation, no
 * system call. */
int loadid_load_model(const loadid_real_t estimate[10], const loadid_real_t std[10],
                      const loadid_real_t *snr, const loadid_model_config_t *cfg,
                      loadid_load_model_t *out);

/* The names of the identified bits, "mass", "com", "inertia". */
const char *loadid_ident_name(int bit);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_LOAD_MODEL_H */
