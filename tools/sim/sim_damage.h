/*
 * Deliberate damage for fault tests (loadid-sim --damage KIND=VALUE):
 *   drop-frames=P    each data frame (base+0..3) is lost with probability P
 *                    (an incomplete sample)
 *   skip-samples=P   all four frames of a sample are lost (a sequence gap)
 *   bit-errors=P     one random bit of a frame's 8 data bytes flips
 *   saturate=P       a sample's force X is driven to 3 full scales (the
 *                    encoder clamps it and sets the saturation bit)
 *   fault=P          a sample carries the sensor-fault bit in every group
 *   bad-frames=P     after a sample, an extra frame with a wrong DLC or an
 *                    unknown identifier (base+7)
 *   nan-joints=P     a joint state whose first position is NaN
 *   stall-joints=T0:T1  no joint states in [T0, T1) s of simulation time
 * Decisions come from a random stream of their own, so the frames and
 * messages left alone are exactly those of the clean recording with the
 * same seed. Each kind's count is reported in truth.yaml.
 */
#ifndef LOADID_SIM_DAMAGE_H
#define LOADID_SIM_DAMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "loadid_synth.h"

#ifdef __cplusplus
extern "C" {
#endif

enum {
    LOADID_DAMAGE_DROP_FRAMES,
    LOADID_DAMAGE_SKIP_SAMPLES,
    LOADID_DAMAGE_BIT_ERRORS,
    LOADID_DAMAGE_SATURATE,
    LOADID_DAMAGE_FAULT,
    LOADID_DAMAGE_BAD_FRAMES,
    LOADID_DAMAGE_NAN_JOINTS,
    LOADID_DAMAGE_KINDS
};

typedef struct {
    double p[LOADID_DAMAGE_KINDS];      /* probabilities, 0 = off */
    double stall_from, stall_to;        /* [s]; stall_to <= stall_from: off */
    int64_t count[LOADID_DAMAGE_KINDS]; /* what was done */
    int64_t stalled_joint_msgs;
    loadid_rng_t rng;
} loadid_damage_t;

void loadid_damage_init(loadid_damage_t *d, uint64_t seed);

/* Parses one KIND=VALUE. Returns 0 or -EINVAL with a message in err. */
int loadid_damage_parse(loadid_damage_t *d, const char *spec, char *err, size_t errlen);

/* Draws whether damage of this kind happens now (and counts it). */
int loadid_damage_now(loadid_damage_t *d, int kind);

/* A uniform integer in [0, n). */
unsigned loadid_damage_pick(loadid_damage_t *d, unsigned n);

const char *loadid_damage_name(int kind);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SIM_DAMAGE_H */
