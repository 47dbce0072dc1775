/* Random numbers and rotations for the tests, and a close-to assertion
 * that prints the numbers. Include after <cmocka.h>. */
#ifndef LOADID_TEST_RANDOM_UTIL_H
#define LOADID_TEST_RANDOM_UTIL_H

#include <math.h>

#include "loadid_synth.h"

/* Fails with the numbers when |actual - expected| > tol (NaN fails too). */
#define ASSERT_CLOSE(actual, expected, tol, what)                                                 \
    do {                                                                                          \
        const double got_ = (actual), want_ = (expected), tol_ = (tol);                           \
        if (!(fabs(got_ - want_) <= tol_)) {                                                      \
            print_error("%s: got %.17g, expected %.17g (|diff| %.3g > tol %.3g)\n", (what), got_, \
                        want_, fabs(got_ - want_), tol_);                                         \
            fail();                                                                               \
        }                                                                                         \
    } while (0)

/* Uniform in [lo, hi). */
double uniform_in(loadid_rng_t *rng, double lo, double hi);
/* Each component uniform in [-lim, lim). */
void uniform_vec3(loadid_rng_t *rng, double lim, double v[3]);
/* Principal moments of a real mass distribution of mass m [kg]: second
 * moments s_i = m r_i^2 with r_i uniform in [0.02, 0.15] m, p_1 = s_2 + s_3
 * and so on, so the triangle inequality holds strictly. */
void random_principal_moments(loadid_rng_t *rng, double m, double p[3]);
/* A uniformly distributed rotation, from a random unit quaternion. */
void random_rotation(loadid_rng_t *rng, double R[3][3]);

#endif /* LOADID_TEST_RANDOM_UTIL_H */
