/* Random numbers and rotations for the tests (random_util.h). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "random_util.h"

double uniform_in(loadid_rng_t *rng, double lo, double hi) {
    return lo + (hi - lo) * loadid_rng_uniform(rng);
}

void uniform_vec3(loadid_rng_t *rng, double lim, double v[3]) {
    for (int i = 0; i < 3; ++i) v[i] = uniform_in(rng, -lim, lim);
}

void random_rotation(loadid_rng_t *rng, double R[3][3]) {
    double q[4], n2;
    do {
        n2 = 0.0;
        for (int i = 0; i < 4; ++i) {
            q[i] = loadid_rng_normal(rng);
            n2 += q[i] * q[i];
        }
    } while (n2 < 1e-6);
    const double n = sqrt(n2);
    const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    R[0][0] = 1 - 2 * (y * y + z * z);
    R[0][1] = 2 * (x * y - w * z);
    R[0][2] = 2 * (x * z + w * y);
    R[1][0] = 2 * (x * y + w * z);
    R[1][1] = 1 - 2 * (x * x + z * z);
    R[1][2] = 2 * (y * z - w * x);
    R[2][0] = 2 * (x * z - w * y);
    R[2][1] = 2 * (y * z + w * x);
    R[2][2] = 1 - 2 * (x * x + y * y);
}

void random_principal_moments(loadid_rng_t *rng, double m, double p[3]) {
    double s[3];
    for (int i = 0; i < 3; ++i) {
        const double r = uniform_in(rng, 0.02, 0.15);
        s[i] = m * r * r;
    }
    p[0] = s[1] + s[2];
    p[1] = s[0] + s[2];
    p[2] = s[0] + s[1];
}
