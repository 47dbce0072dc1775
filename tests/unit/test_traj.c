/*
 * Unit tests of the excitation trajectories (tools/traj): the Fourier
 * series with polynomial fades of eqs. (10)-(15), and the designer.
 *
 * References, independent of the code under test:
 *  - derivatives by central finite differences of the position alone;
 *  - the fade conditions of eq. (15) and rest at both ends, checked at the
 *    boundary times;
 *  - the jerk bound, numerically (differences of q'') against the bound
 *    that follows from the coefficients and the fade polynomial;
 *  - the limits of a designed trajectory, re-checked here at 10 kHz with
 *    this file's own loop over the URDF's limits and the kinematics'
 *    position of S.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/core.h"
#include "loadid/urdf.h"
#include "random_util.h"
#include "traj_design.h"
#include "traj_file.h"

static const double kTwoPi = 6.28318530717958647692;

static void random_traj(loadid_rng_t *rng, int n, loadid_fourier_traj_t *tr) {
    memset(tr, 0, sizeof *tr);
    tr->num_joints = n;
    tr->harmonics = 4;
    tr->base_frequency = 0.5;
    tr->active_s = 1.5;
    tr->fade_s = 0.5;
    for (int i = 0; i < n; ++i) {
        tr->q0[i] = uniform_in(rng, -1, 1);
        for (int k = 0; k < tr->harmonics; ++k) {
            tr->rho[i][k] = uniform_in(rng, -0.3, 0.3) / (k + 1);
            tr->delta[i][k] = uniform_in(rng, -0.3, 0.3) / (k + 1);
        }
    }
}

/* Derivatives agree with central differences of the position (and of the
 * velocity, acceleration) everywhere, fades included. */
static void derivatives_match_finite_differences(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 3);
    loadid_fourier_traj_t tr;
    random_traj(&rng, 6, &tr);
    const double h = 1e-4, T = loadid_traj_duration(&tr);
    for (double t = 0.013; t < T; t += 0.0371) {
        double q[6], qd[6], qdd[6], j[6], qp[6], qm[6], dp[6], dm[6], ap[6], am[6];
        loadid_traj_eval(&tr, t, q, qd, qdd, j);
        loadid_traj_eval(&tr, t + h, qp, dp, ap, NULL);
        loadid_traj_eval(&tr, t - h, qm, dm, am, NULL);
        for (int i = 0; i < 6; ++i) {
            /* central differences err by h^2/6 times the next derivative */
            ASSERT_CLOSE((qp[i] - qm[i]) / (2 * h), qd[i], 1e-6 * (1 + fabs(qd[i])), "qd vs dq/dt");
            ASSERT_CLOSE((dp[i] - dm[i]) / (2 * h), qdd[i], 1e-5 * (1 + fabs(qdd[i])),
                         "qdd vs dqd/dt");
            ASSERT_CLOSE((ap[i] - am[i]) / (2 * h), j[i], 1e-4 * (1 + fabs(j[i])),
                         "jerk vs dqdd/dt");
        }
    }
}

/* Eq. (15): the fade-in starts at rest at q0 and meets the series with the
 * same position, velocity and acceleration at t1 (and jerk: one order
 * above the paper's); the fade-out mirrors it; outside [0, t3] the robot
 * rests at q0. */
static void fades_start_and_end_at_rest_and_join_the_series(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 4);
    loadid_fourier_traj_t tr;
    random_traj(&rng, 7, &tr);
    const double t1 = tr.fade_s, t2 = t1 + tr.active_s, t3 = loadid_traj_duration(&tr);
    const double ends[] = {-1.0, 0.0, t3, t3 + 2};
    for (int e = 0; e < 4; ++e) {
        double q[7], qd[7], qdd[7], j[7];
        loadid_traj_eval(&tr, ends[e], q, qd, qdd, j);
        for (int i = 0; i < 7; ++i) {
            ASSERT_CLOSE(q[i], tr.q0[i], 1e-15, "at rest: q0");
            ASSERT_CLOSE(qd[i], 0, 1e-15, "at rest: qd");
            ASSERT_CLOSE(qdd[i], 0, 1e-15, "at rest: qdd");
            ASSERT_CLOSE(j[i], 0, 1e-12, "at rest: jerk (f''' = 0 at rest)");
        }
    }
    /* The series written out here, at the joins, from both sides. */
    const double joins[] = {t1, t2};
    for (int e = 0; e < 2; ++e) {
        for (int side = -1; side <= 1; side += 2) {
            double t = joins[e] + side * 1e-9, q[7], qd[7], qdd[7], j[7];
            loadid_traj_eval(&tr, t, q, qd, qdd, j);
            for (int i = 0; i < 7; ++i) {
                double s = 0, sd = 0, sdd = 0, sddd = 0, ts = t - t1;
                for (int k = 1; k <= tr.harmonics; ++k) {
                    double w = kTwoPi * k * tr.base_frequency;
                    s += tr.rho[i][k - 1] * sin(w * ts) + tr.delta[i][k - 1] * cos(w * ts);
                    sd += w * (tr.rho[i][k - 1] * cos(w * ts) - tr.delta[i][k - 1] * sin(w * ts));
                    sdd -=
                        w * w * (tr.rho[i][k - 1] * sin(w * ts) + tr.delta[i][k - 1] * cos(w * ts));
                    sddd -= w * w * w *
                            (tr.rho[i][k - 1] * cos(w * ts) - tr.delta[i][k - 1] * sin(w * ts));
                }
                ASSERT_CLOSE(q[i], tr.q0[i] + s, 1e-7, "join: q");
                ASSERT_CLOSE(qd[i], sd, 1e-6, "join: qd");
                ASSERT_CLOSE(qdd[i], sdd, 1e-5, "join: qdd");
                /* No jerk step where the estimation window starts and ends. */
                ASSERT_CLOSE(j[i], sddd, 1e-4 * (1 + fabs(sddd)), "join: jerk");
            }
        }
    }
}

/* The jerk, measured as differences of q'' at 10 kHz over the whole
 * trajectory, stays below the bound from the coefficients:
 * |(f s)'''| <= sum_j C(3,j) max|f^(j)| / T^j max|s^(3-j)|, with
 * max|s^(m)| <= sum_k (|rho| + |delta|) w_k^m and the fade polynomial's
 * maxima on [0, 1]. With p = tau (1 - tau): f' = 140 p^3, at most 140 / 64 =
 * 2.1875 at tau 0.5; f'' = 420 p^2 (1 - 2 tau), at most 420 0.2^2 sqrt(0.2)
 * = 7.513 where p = 0.2 (tau 0.276); f''' = 840 (p - 5 p^2), at most 52.5
 * in magnitude at p = 1/4 (tau 0.5), 42 at p = 0.1. */
static void jerk_is_bounded_everywhere(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 5);
    loadid_fourier_traj_t tr;
    random_traj(&rng, 6, &tr);
    const double fmax_j[4] = {1, 2.1875, 7.514, 52.5};
    const double dt = 1e-4, T = loadid_traj_duration(&tr);
    for (int i = 0; i < 6; ++i) {
        double smax[4] = {0, 0, 0, 0};
        for (int k = 1; k <= tr.harmonics; ++k) {
            double w = kTwoPi * k * tr.base_frequency,
                   c = fabs(tr.rho[i][k - 1]) + fabs(tr.delta[i][k - 1]);
            for (int m = 0; m < 4; ++m) smax[m] += c * pow(w, m);
        }
        const double binom[4] = {1, 3, 3, 1};
        double bound = 0;
        for (int j = 0; j < 4; ++j) bound += binom[j] * fmax_j[j] / pow(tr.fade_s, j) * smax[3 - j];
        double prev[6], worst = 0;
        loadid_traj_eval(&tr, -dt, NULL, NULL, prev, NULL);
        for (double t = 0; t <= T + dt; t += dt) {
            double qdd[6];
            loadid_traj_eval(&tr, t, NULL, NULL, qdd, NULL);
            worst = fmax(worst, fabs(qdd[i] - prev[i]) / dt);
            memcpy(prev, qdd, sizeof prev);
        }
        print_message("joint %d: max |jerk| %.3g rad/s^3, bound %.3g\n", i, worst, bound);
        assert_true(isfinite(worst) && worst <= bound);
    }
}

/* ------------------------------------------------------------ designer */

typedef struct {
    loadid_chain_t chain;
    loadid_kin_t *kin;
    loadid_traj_problem_t p;
} robot_t;

static void rx60_problem(robot_t *r) {
    char err[256];
    assert_int_equal(loadid_urdf_load_file(LOADID_SOURCE_DIR "/host/config/robots/rx60.urdf",
                                           "base_link", "ft_sensor", &r->chain, err, sizeof err),
                     0);
    const double g[3] = {0, 0, -9.81};
    assert_int_equal(loadid_kin_create(&r->chain, g, &r->kin), 0);
    memset(&r->p, 0, sizeof r->p);
    loadid_traj_problem_defaults(&r->p);
    r->p.kin = r->kin;
    loadid_traj_limits_t *L = &r->p.limits;
    L->num_joints = r->chain.num_joints;
    for (int i = 0; i < L->num_joints; ++i) {
        L->lower[i] = r->chain.joints[i].lower;
        L->upper[i] = r->chain.joints[i].upper;
        L->velocity[i] = r->chain.joints[i].velocity;
        L->acceleration[i] = 15;
    }
    for (int a = 0; a < 3; ++a) L->ws_min[a] = -0.7, L->ws_max[a] = 0.7;
    L->ws_min[2] = 0, L->ws_max[2] = 1.2;
    L->floor_z = 0.25;
    assert_int_equal(loadid_est_config_default(LOADID_METHOD_RLS, 10, &r->p.est), 0);
    assert_int_equal(loadid_est_weights_from_noise(&r->p.est, 0.1, 0.005, 0.5, 5, 0.02, 2), 0);
    r->p.zeroing = 1;
}

static void template_of(const robot_t *r, loadid_fourier_traj_t *tr) {
    memset(tr, 0, sizeof *tr);
    tr->num_joints = r->chain.num_joints;
    tr->harmonics = 4;
    tr->base_frequency = 0.5;
    tr->active_s = 1.5;
    tr->fade_s = 0.5;
}

/* This file's own check of every limit at 10 kHz: joint position,
 * velocity and acceleration, the box and the floor for S's origin. */
static void assert_within_limits(const robot_t *r, const loadid_fourier_traj_t *tr) {
    const loadid_traj_limits_t *L = &r->p.limits;
    const double T = loadid_traj_duration(tr);
    for (long k = 0; k <= (long)(T * 1e4); ++k) {
        double q[16], qd[16], qdd[16];
        loadid_traj_eval(tr, k * 1e-4, q, qd, qdd, NULL);
        loadid_real_t rq[16];
        for (int i = 0; i < L->num_joints; ++i) {
            assert_true(q[i] >= r->chain.joints[i].lower && q[i] <= r->chain.joints[i].upper);
            assert_true(fabs(qd[i]) <= r->chain.joints[i].velocity);
            assert_true(fabs(qdd[i]) <= L->acceleration[i]);
            rq[i] = (loadid_real_t)q[i];
        }
        loadid_kin_state_t st;
        assert_int_equal(loadid_kin_eval(r->kin, rq, NULL, NULL, &st), 0);
        for (int a = 0; a < 3; ++a)
            assert_true(st.position[a] >= L->ws_min[a] && st.position[a] <= L->ws_max[a]);
        assert_true(st.position[2] >= L->floor_z);
    }
}

static void designer_lowers_kappa_within_the_limits(void **state) {
    (void)state;
    robot_t r;
    rx60_problem(&r);
#if defined(LOADID_SANITIZED)
    /* The sanitizers make the search ~30x slower: one smaller
     * search (2 harmonics, 24 coefficients). */
    const uint64_t seeds = 1;
    const int mc = 30, evals = 150, harmonics = 2;
#else
    const uint64_t seeds = 3;
    const int mc = 150, evals = 400, harmonics = 4;
#endif
    for (uint64_t seed = 1; seed <= seeds; ++seed) {
        loadid_fourier_traj_t tr;
        template_of(&r, &tr);
        tr.harmonics = harmonics;
        tr.q0[1] = 0.3, tr.q0[2] = 1.2, tr.q0[4] = 0.8; /* arm bent, sensor forward */
        loadid_traj_search_t s = {.monte_carlo = mc,
                                  .candidates = 2,
                                  .max_evals = evals,
                                  .seed = seed,
                                  .optimise_home = seed == 3};
        loadid_traj_search_result_t res;
        assert_int_equal(loadid_traj_design(&r.p, &s, &tr, &res), 0);
        print_message(
            "seed %llu: kappa Monte Carlo %.4g -> optimised %.4g (%d feasible, %d evals)\n",
            (unsigned long long)seed, res.kappa_monte_carlo, res.kappa_optimised,
            res.feasible_candidates, res.evaluations);
        assert_true(res.kappa_optimised < 0.9 * res.kappa_monte_carlo);
        assert_true(fabs(loadid_traj_kappa(&r.p, &tr, r.p.objective_hz) - res.kappa_optimised) <=
                    1e-9 * res.kappa_optimised);
        assert_within_limits(&r, &tr);
    }
    loadid_kin_destroy(r.kin);
}

/* A workspace the sensor cannot stay in from the home pose: no result. */
static void impossible_limits_give_no_trajectory(void **state) {
    (void)state;
    robot_t r;
    rx60_problem(&r);
    r.p.limits.floor_z = 5.0; /* the floor above the robot's reach */
    loadid_fourier_traj_t tr, before;
    template_of(&r, &tr);
    memcpy(&before, &tr, sizeof tr);
    loadid_traj_search_t s = {.monte_carlo = 20, .candidates = 1, .max_evals = 50, .seed = 1};
    loadid_traj_search_result_t res;
    assert_int_equal(loadid_traj_design(&r.p, &s, &tr, &res), -ERANGE);
    assert_memory_equal(&tr, &before, sizeof tr);
    s.monte_carlo = 0;
    assert_int_equal(loadid_traj_design(&r.p, &s, &tr, &res), -EINVAL);
    tr.harmonics = 0;
    s.monte_carlo = 1;
    assert_int_equal(loadid_traj_design(&r.p, &s, &tr, &res), -EINVAL);
    loadid_kin_destroy(r.kin);
}

/* The file keeps every coefficient to the bit (%.17g), and a file with a
 * key missing or a row too short is refused with the key's line. */
static void trajectory_file_round_trips_and_refuses_damage(void **state) {
    (void)state;
    robot_t r;
    rx60_problem(&r);
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 8);
    loadid_fourier_traj_t tr, back;
    random_traj(&rng, 6, &tr);
    char path[] = "/tmp/loadid_traj_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "w");
    loadid_traj_file_info_t info = {"robot.urdf", "base_link", "ft_sensor", &r.chain,
                                    2.5,          7.5,         9.5,         3};
    assert_int_equal(loadid_traj_file_write(f, &tr, &r.p.limits, &info), 0);
    fclose(f);
    char names[LOADID_MAX_JOINTS][LOADID_NAME_MAX], err[512];
    double kappa = 0;
    assert_int_equal(loadid_traj_file_read(path, &back, names, &kappa, err, sizeof err), 0);
    assert_int_equal(back.num_joints, 6);
    assert_int_equal(back.harmonics, tr.harmonics);
    assert_memory_equal(back.q0, tr.q0, 6 * sizeof(double));
    for (int i = 0; i < 6; ++i) {
        assert_memory_equal(back.rho[i], tr.rho[i], 4 * sizeof(double));
        assert_memory_equal(back.delta[i], tr.delta[i], 4 * sizeof(double));
        assert_string_equal(names[i], r.chain.joints[i].name);
    }
    assert_true(back.base_frequency == tr.base_frequency && back.fade_s == tr.fade_s);
    assert_true(kappa == 2.5);

    /* Damage: the second rho row loses a number. */
    f = fopen(path, "r");
    char text[16384];
    size_t len = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[len] = 0;
    char *row = strstr(strstr(text, "rho:"), "\n  - [");
    row = strstr(row + 1, "\n  - [");
    char *comma = strchr(row, ',');
    memmove(row + 7, comma + 2, strlen(comma + 2) + 1);
    f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
    assert_int_not_equal(loadid_traj_file_read(path, &back, NULL, NULL, err, sizeof err), 0);
    print_message("damaged file: %s\n", err);
    assert_non_null(strstr(err, "rho[1]: expected 4 numbers, got 3"));

    /* A file designed with another fade (this one's limits were checked on
     * a different motion) is refused, not moved on. */
    f = fopen(path, "w");
    assert_int_equal(loadid_traj_file_write(f, &tr, &r.p.limits, &info), 0);
    fclose(f);
    f = fopen(path, "r");
    len = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[len] = 0;
    char *fade = strstr(text, "fade_polynomial: \"");
    assert_non_null(fade);
    char *rest = strchr(fade, '\n');
    f = fopen(path, "w");
    fprintf(f, "%.*sfade_polynomial: \"15 tau^4 - 24 tau^5 + 10 tau^6\"%s", (int)(fade - text),
            text, rest);
    fclose(f);
    assert_int_equal(loadid_traj_file_read(path, &back, NULL, NULL, err, sizeof err), -EINVAL);
    print_message("other fade: %s\n", err);
    assert_non_null(strstr(err, "fade_polynomial: '15 tau^4 - 24 tau^5 + 10 tau^6' is not"));
    remove(path);
    assert_int_equal(loadid_traj_file_read(path, &back, NULL, NULL, err, sizeof err), -ENOENT);
    loadid_kin_destroy(r.kin);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(derivatives_match_finite_differences),
        cmocka_unit_test(fades_start_and_end_at_rest_and_join_the_series),
        cmocka_unit_test(jerk_is_bounded_everywhere),
        cmocka_unit_test(designer_lowers_kappa_within_the_limits),
        cmocka_unit_test(impossible_limits_give_no_trajectory),
        cmocka_unit_test(trajectory_file_round_trips_and_refuses_damage),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
