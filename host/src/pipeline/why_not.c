/* Why a final estimate's group is not identified, in words (pipeline.h). */
#include "loadid/pipeline.h"

#include "loadid/load_model.h"

#include <math.h>
#include <stdio.h>

/* R as "%.3g", with more digits where that would round a ratio just past
 * its bound to "1" (the bound is exceeded by definition here). */
static void ratio(char *buf, size_t len, double over) {
    int digits = 3;
    const double off = fabs(over - 1);
    while (digits < 9 && off > 0 && off < 5 * pow(10, -digits)) ++digits;
    snprintf(buf, len, "%.*g", digits, over);
}

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
    char r[24];
    ratio(r, sizeof r, over);
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
                snprintf(out, len, "phi_std %s times its bound", r);
            break;
        case LOADID_WHY_NEEDS:
            snprintf(out, len, "%s", needs[group]);
            break;
        case LOADID_WHY_GYRATION:
            snprintf(out, len, "radius of gyration %s times its bound", r);
            break;
        case LOADID_WHY_SNR:
            if (!isfinite(over)) {
                snprintf(out, len, "its torque does not stand out of the noise at all");
                break;
            }
            snprintf(out, len,
                     "its torque stands out of the noise %s times less than the bound, "
                     "as on slow or mostly translational motion",
                     r);
            break;
        case LOADID_WHY_JOINT_NOISE:
            snprintf(out, len,
                     "the joint positions are %s times noisier than kalman.meas_sigma: "
                     "phi_std does not count what the joint filters passed on",
                     r);
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
