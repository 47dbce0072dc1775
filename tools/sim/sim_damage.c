/* Damage for fault tests (sim_damage.h). */
#include "sim_damage.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const kNames[LOADID_DAMAGE_KINDS] = {
    "drop-frames", "skip-samples", "bit-errors", "saturate", "fault", "bad-frames", "nan-joints",
};

const char *loadid_damage_name(int kind) {
    return kind >= 0 && kind < LOADID_DAMAGE_KINDS ? kNames[kind] : "?";
}

void loadid_damage_init(loadid_damage_t *d, uint64_t seed) {
    memset(d, 0, sizeof *d);
    /* A stream apart from the simulation's (golden-ratio offset). */
    loadid_rng_seed(&d->rng, seed ^ 0x9E3779B97F4A7C15ull);
}

static int parse_number(const char *s, double *out) {
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end || !isfinite(v)) return -1;
    *out = v;
    return 0;
}

int loadid_damage_parse(loadid_damage_t *d, const char *spec, char *err, size_t errlen) {
    const char *eq = strchr(spec, '=');
    if (!eq) {
        snprintf(err, errlen, "--damage %s: expected KIND=VALUE", spec);
        return -EINVAL;
    }
    const size_t klen = (size_t)(eq - spec);
    const char *value = eq + 1;
    if (klen == strlen("stall-joints") && strncmp(spec, "stall-joints", klen) == 0) {
        char buf[64];
        snprintf(buf, sizeof buf, "%s", value);
        char *colon = strchr(buf, ':');
        if (!colon) {
            snprintf(err, errlen, "--damage stall-joints=%s: expected T0:T1 in seconds", value);
            return -EINVAL;
        }
        *colon = 0;
        if (parse_number(buf, &d->stall_from) || parse_number(colon + 1, &d->stall_to) ||
            !(d->stall_to > d->stall_from)) {
            snprintf(err, errlen, "--damage stall-joints=%s: expected T0:T1 with T0 < T1", value);
            return -EINVAL;
        }
        return 0;
    }
    for (int k = 0; k < LOADID_DAMAGE_KINDS; ++k) {
        if (klen == strlen(kNames[k]) && strncmp(spec, kNames[k], klen) == 0) {
            double p;
            if (parse_number(value, &p) || p < 0 || p > 1) {
                snprintf(err, errlen, "--damage %s: expected a probability in [0, 1]", spec);
                return -EINVAL;
            }
            d->p[k] = p;
            return 0;
        }
    }
    snprintf(err, errlen,
             "--damage %.*s: unknown kind (drop-frames, skip-samples, bit-errors, saturate, "
             "fault, bad-frames, nan-joints, stall-joints)",
             (int)klen, spec);
    return -EINVAL;
}

int loadid_damage_now(loadid_damage_t *d, int kind) {
    if (!(d->p[kind] > 0)) return 0;
    if (loadid_rng_uniform(&d->rng) >= d->p[kind]) return 0;
    d->count[kind]++;
    return 1;
}

unsigned loadid_damage_pick(loadid_damage_t *d, unsigned n) {
    unsigned v = (unsigned)(loadid_rng_uniform(&d->rng) * n);
    return v < n ? v : n - 1;
}
