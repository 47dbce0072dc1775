/* Why a final estimate's group is not identified, in words (pipeline.h). */
#include "loadid/pipeline.h"

#include "loadid/load_model.h"

#include <math.h>
#include <stdio.h>

int loadid_pipeline_why_not(const loadid_pipeline_estimate_t *e, int group, char *out, size_t len) {
    if (!out || len == 0) return 0;
    out[0] = '\0';
    if (!e || group < 0 || group > 2) return 0;
    if (!e->valid) {
        snprintf(out, len, "no estimate");
        return 1;
    }
    if (!e->has_model || (e->identified & (1 << group))) return 0;
    static const char *const needs[3] = {"", "needs the mass", "needs the com"};
    const double over = e->ident_over[group];
    switch (e->ident_why[group]) {
        case LOADID_WHY_NO_MASS:
            snprintf(out, len, "no positive mass");
            break;
        case LOADID_WHY_STD:
            if (isnan(over))
                snprintf(out, len, "phi_std not a number: its covariance failed");
            else if (isinf(over))
                snprintf(out, len, "phi_std infinite: the data do not bound it");
            else
                snprintf(out, len, "phi_std %.3g times its bound", over);
            break;
        case LOADID_WHY_NEEDS:
            snprintf(out, len, "%s", needs[group]);
            break;
        case LOADID_WHY_GYRATION:
            snprintf(out, len, "radius of gyration %.3g times its bound", over);
            break;
        case LOADID_WHY_SNR:
            if (!isfinite(over)) {
                snprintf(out, len, "its torque does not stand out of the noise at all");
                break;
            }
            snprintf(out, len,
                     "its torque stands out of the noise %.3g times less than the bound, "
                     "as on slow or mostly translational motion",
                     over);
            break;
        case LOADID_WHY_JOINT_NOISE:
            snprintf(out, len,
                     "the joint positions are %.3g times noisier than kalman.meas_sigma: "
                     "phi_std does not count what the joint filters passed on",
                     over);
            break;
        case LOADID_WHY_JOINT_STAMPS:
            snprintf(out, len,
                     "the joint stamps lost the stream's rate %.0f times in the window: phi_std "
                     "does not count the joint states taken at wrong times",
                     over);
            break;
        default: /* not kept: a result restored from its saved YAML */
            snprintf(out, len, "not identified (no reason kept)");
            break;
    }
    return 1;
}
