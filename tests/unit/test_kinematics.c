/*
 * Unit tests of the forward kinematics of S (loadid/kinematics.h) and of
 * loadid_chain_check, built against the double and the float core.
 *
 * References, independent of the recursion in kinematics.cpp:
 *  - a planar two-link arm whose S pose, velocity and acceleration are
 *    written out in closed form here (the textbook trigonometric result);
 *  - (double only) central finite differences, with Richardson
 *    extrapolation, of the pose alone along a smooth joint trajectory on a
 *    random 7-joint chain with revolute and prismatic joints: omega from
 *    dR/dt, alpha from d(omega)/dt, the acceleration from d^2 p/dt^2.
 * The comparison with Pinocchio on real URDFs is in
 * tests/python/test_kinematics_pinocchio.py.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "loadid/core.h"
#include "random_util.h"

#define HALF_PI 1.57079632679489661923
#define IS_FLOAT (sizeof(loadid_real_t) == sizeof(float))
/* Closed-form comparisons: round-off of a handful of operations. */
#define TOL (IS_FLOAT ? 2e-4 : 1e-12)

static const double kGravity[3] = {0.0, -9.81, 0.0};

static void identity(double r[9]) {
    static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(r, id, sizeof id);
}

/* r = Rz(a) as row-major 3x3. */
static void rot_z(double a, double r[9]) {
    identity(r);
    r[0] = cos(a), r[1] = -sin(a), r[3] = sin(a), r[4] = cos(a);
}

static void rot_x(double a, double r[9]) {
    identity(r);
    r[4] = cos(a), r[5] = -sin(a), r[7] = sin(a), r[8] = cos(a);
}

static void matmul(const double a[9], const double b[9], double out[9]) {
    double t[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            t[3 * i + j] = 0;
            for (int k = 0; k < 3; ++k) t[3 * i + j] += a[3 * i + k] * b[3 * k + j];
        }
    memcpy(out, t, sizeof t);
}

/* out = R^T v */
static void rt_mul(const double r[9], const double v[3], double out[3]) {
    for (int i = 0; i < 3; ++i) out[i] = r[i] * v[0] + r[3 + i] * v[1] + r[6 + i] * v[2];
}

static void add_joint(loadid_chain_t *c, loadid_joint_type_t type, const double xyz[3],
                      const double rot[9], const double axis[3]) {
    loadid_joint_desc_t *j = &c->joints[c->num_joints];
    snprintf(j->name, sizeof j->name, "j%d", c->num_joints + 1);
    j->type = type;
    memcpy(j->origin_xyz, xyz, sizeof j->origin_xyz);
    memcpy(j->origin_rot, rot, sizeof j->origin_rot);
    memcpy(j->axis, axis, sizeof j->axis);
    j->lower = -INFINITY;
    j->upper = INFINITY;
    j->velocity = INFINITY;
    c->num_joints++;
}

static void begin_chain(loadid_chain_t *c) {
    memset(c, 0, sizeof *c);
    strcpy(c->base_link, "base");
    strcpy(c->sensor_link, "sensor");
    identity(c->tip_rot);
}

/* Planar arm in the base x-y plane: two revolute z joints, links L1, L2,
 * and S turned by +90 deg about x at the tip (so S's axes differ from the
 * last link's). */
#define L1 0.4
#define L2 0.3
static void planar_chain(loadid_chain_t *c) {
    static const double z[3] = {0, 0, 1}, at0[3] = {0, 0, 0}, at1[3] = {L1, 0, 0};
    double id[9];
    identity(id);
    begin_chain(c);
    add_joint(c, LOADID_JOINT_REVOLUTE, at0, id, z);
    add_joint(c, LOADID_JOINT_REVOLUTE, at1, id, z);
    c->tip_xyz[0] = L2;
    rot_x(HALF_PI, c->tip_rot);
}

static void assert_vec(const loadid_real_t *got, const double *want, double tol, const char *what) {
    for (int i = 0; i < 3; ++i) ASSERT_CLOSE(got[i], want[i], tol, what);
}

static void planar_arm_matches_closed_form(void **state) {
    (void)state;
    loadid_chain_t chain;
    planar_chain(&chain);
    loadid_kin_t *kin = NULL;
    assert_int_equal(loadid_kin_create(&chain, kGravity, &kin), 0);
    assert_int_equal(loadid_kin_num_joints(kin), 2);
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 7);
    for (int trial = 0; trial < 200; ++trial) {
        double q1 = uniform_in(&rng, -3, 3), q2 = uniform_in(&rng, -3, 3);
        double v1 = uniform_in(&rng, -3, 3), v2 = uniform_in(&rng, -3, 3);
        double a1 = uniform_in(&rng, -20, 20), a2 = uniform_in(&rng, -20, 20);
        loadid_real_t q[2] = {q1, q2}, qd[2] = {v1, v2}, qdd[2] = {a1, a2};
        loadid_kin_state_t st;
        assert_int_equal(loadid_kin_eval(kin, q, qd, qdd, &st), 0);

        double th = q1 + q2, thd = v1 + v2, thdd = a1 + a2;
        double c1 = cos(q1), s1 = sin(q1), c12 = cos(th), s12 = sin(th);
        double pos[3] = {L1 * c1 + L2 * c12, L1 * s1 + L2 * s12, 0};
        double acc_base[3] = {-L1 * (s1 * a1 + c1 * v1 * v1) - L2 * (s12 * thdd + c12 * thd * thd),
                              L1 * (c1 * a1 - s1 * v1 * v1) + L2 * (c12 * thdd - s12 * thd * thd),
                              0};
        double rz[9], rx[9], r[9];
        rot_z(th, rz);
        rot_x(HALF_PI, rx);
        matmul(rz, rx, r); /* S -> base */
        double w_base[3] = {0, 0, thd}, dw_base[3] = {0, 0, thdd};
        double w[3], dw[3], acc[3], g[3], spec[3];
        rt_mul(r, w_base, w);
        rt_mul(r, dw_base, dw);
        rt_mul(r, acc_base, acc);
        rt_mul(r, kGravity, g);
        for (int i = 0; i < 3; ++i) spec[i] = acc[i] - g[i];
        for (int i = 0; i < 9; ++i) ASSERT_CLOSE(st.rotation[i], r[i], TOL, "rotation");
        assert_vec(st.position, pos, TOL, "position");
        assert_vec(st.omega, w, TOL, "omega");
        assert_vec(st.alpha, dw, 10 * TOL, "alpha");
        assert_vec(st.accel, acc, 10 * TOL, "accel");
        assert_vec(st.gravity, g, 10 * TOL, "gravity");
        assert_vec(st.spec, spec, 10 * TOL, "spec");
    }
    /* qd, qdd NULL mean zero: at rest S reads only gravity. */
    loadid_real_t q[2] = {0.3, -1.1};
    loadid_kin_state_t st;
    assert_int_equal(loadid_kin_eval(kin, q, NULL, NULL, &st), 0);
    double zero[3] = {0, 0, 0};
    assert_vec(st.omega, zero, 0, "omega at rest");
    assert_vec(st.accel, zero, TOL, "accel at rest");
    loadid_kin_destroy(kin);
}

static void bad_input_is_rejected(void **state) {
    (void)state;
    loadid_chain_t chain;
    planar_chain(&chain);
    loadid_kin_t *kin = NULL;
    assert_int_equal(loadid_kin_create(NULL, kGravity, &kin), -EINVAL);
    double nan_g[3] = {0, NAN, 0};
    assert_int_equal(loadid_kin_create(&chain, nan_g, &kin), -EINVAL);
    assert_int_equal(loadid_kin_create(&chain, kGravity, &kin), 0);

    loadid_real_t q[2] = {0.1, 0.2}, bad[2] = {0.1, NAN};
    loadid_kin_state_t st, before;
    memset(&st, 0x5a, sizeof st);
    memcpy(&before, &st, sizeof st);
    assert_int_equal(loadid_kin_eval(kin, bad, NULL, NULL, &st), LOADID_E_NONFINITE);
    assert_int_equal(loadid_kin_eval(kin, q, bad, NULL, &st), LOADID_E_NONFINITE);
    assert_int_equal(loadid_kin_eval(kin, q, NULL, bad, &st), LOADID_E_NONFINITE);
    assert_memory_equal(&st, &before, sizeof st);
    assert_int_equal(loadid_kin_eval(kin, NULL, NULL, NULL, &st), -EINVAL);
    assert_int_equal(loadid_kin_eval(kin, q, NULL, NULL, NULL), -EINVAL);
    loadid_kin_destroy(kin);
    loadid_kin_destroy(NULL);
}

static void chain_check_refuses_broken_chains(void **state) {
    (void)state;
    loadid_chain_t good, c;
    planar_chain(&good);
    assert_int_equal(loadid_chain_check(&good), 0);
    assert_int_equal(loadid_chain_check(NULL), -EINVAL);

    c = good;
    c.num_joints = 0;
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.num_joints = LOADID_MAX_JOINTS + 1;
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.joints[1].axis[2] = 0.9; /* not a unit axis */
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.joints[0].type = (loadid_joint_type_t)7;
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.joints[0].origin_rot[8] = -1; /* a reflection, det -1 */
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.joints[1].origin_rot[1] = 1e-6; /* not orthonormal */
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.tip_xyz[0] = INFINITY;
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.joints[0].lower = 1, c.joints[0].upper = 0;
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    c.joints[0].velocity = 0;
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    c = good;
    memset(c.joints[0].name, 'x', sizeof c.joints[0].name); /* no NUL */
    assert_int_equal(loadid_chain_check(&c), -EINVAL);
    loadid_kin_t *kin = NULL;
    assert_int_equal(loadid_kin_create(&c, kGravity, &kin), -EINVAL);
    assert_null(kin);
}

#if !LOADID_SCALAR_FLOAT
/* ------------------------------------------------ finite differences */

#define NJ 7

/* A random chain: joints 1, 4, 6 prismatic, the others revolute, every
 * origin and axis random, and a random tip. */
static void random_chain(loadid_rng_t *rng, loadid_chain_t *c) {
    begin_chain(c);
    for (int i = 0; i < NJ; ++i) {
        double xyz[3], axis[3], r[3][3], rot[9];
        uniform_vec3(rng, 0.3, xyz);
        uniform_vec3(rng, 1.0, axis);
        double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        for (int k = 0; k < 3; ++k) axis[k] /= n;
        random_rotation(rng, r);
        memcpy(rot, r, sizeof rot);
        int prismatic = i == 0 || i == 3 || i == 5;
        add_joint(c, prismatic ? LOADID_JOINT_PRISMATIC : LOADID_JOINT_REVOLUTE, xyz, rot, axis);
    }
    double r[3][3];
    uniform_vec3(rng, 0.2, c->tip_xyz);
    random_rotation(rng, r);
    memcpy(c->tip_rot, r, sizeof c->tip_rot);
}

typedef struct {
    double q0[NJ], v[NJ], a[NJ], j[NJ]; /* q(t) = q0 + v t + a t^2/2 + j t^3/6 */
} poly_traj_t;

static void traj_at(const poly_traj_t *p, double t, loadid_real_t q[NJ], loadid_real_t qd[NJ]) {
    for (int i = 0; i < NJ; ++i) {
        q[i] = p->q0[i] + p->v[i] * t + p->a[i] * t * t / 2 + p->j[i] * t * t * t / 6;
        qd[i] = p->v[i] + p->a[i] * t + p->j[i] * t * t / 2;
    }
}

/* Pose, and omega in the base frame, of S at time t. */
static void pose_at(const loadid_kin_t *kin, const poly_traj_t *p, double t, double r[9],
                    double pos[3], double w_base[3]) {
    loadid_real_t q[NJ], qd[NJ];
    traj_at(p, t, q, qd);
    loadid_kin_state_t st;
    assert_int_equal(loadid_kin_eval(kin, q, qd, NULL, &st), 0);
    for (int i = 0; i < 9; ++i) r[i] = st.rotation[i];
    for (int i = 0; i < 3; ++i) {
        pos[i] = st.position[i];
        w_base[i] =
            r[3 * i] * st.omega[0] + r[3 * i + 1] * st.omega[1] + r[3 * i + 2] * st.omega[2];
    }
}

/* Central differences at step h of: omega_base from dR/dt R^T (pose only),
 * alpha_base from omega_base, and the acceleration from the position. */
static void differences(const loadid_kin_t *kin, const poly_traj_t *p, double h, double w[3],
                        double dw[3], double acc[3]) {
    double rp[9], rm[9], r0[9], pp[3], pm[3], p0[3], wp[3], wm[3], w0[3];
    pose_at(kin, p, h, rp, pp, wp);
    pose_at(kin, p, -h, rm, pm, wm);
    pose_at(kin, p, 0, r0, p0, w0);
    double rdot[9], skew[9], r0t[9];
    for (int i = 0; i < 9; ++i) rdot[i] = (rp[i] - rm[i]) / (2 * h);
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) r0t[3 * i + k] = r0[3 * k + i];
    matmul(rdot, r0t, skew); /* [omega_base]x */
    w[0] = (skew[7] - skew[5]) / 2, w[1] = (skew[2] - skew[6]) / 2, w[2] = (skew[3] - skew[1]) / 2;
    for (int i = 0; i < 3; ++i) {
        dw[i] = (wp[i] - wm[i]) / (2 * h);
        acc[i] = (pp[i] - 2 * p0[i] + pm[i]) / (h * h);
    }
}

static void random_chain_matches_finite_differences(void **state) {
    (void)state;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 2024);
    for (int trial = 0; trial < 50; ++trial) {
        loadid_chain_t chain;
        random_chain(&rng, &chain);
        loadid_kin_t *kin = NULL;
        assert_int_equal(loadid_kin_create(&chain, kGravity, &kin), 0);
        poly_traj_t p;
        for (int i = 0; i < NJ; ++i) {
            p.q0[i] = uniform_in(&rng, -2, 2);
            p.v[i] = uniform_in(&rng, -2, 2);
            p.a[i] = uniform_in(&rng, -15, 15);
            p.j[i] = uniform_in(&rng, -100, 100);
        }
        /* Richardson: (4 D(h/2) - D(h)) / 3 cancels the h^2 error term. */
        const double h = 2e-3;
        double w1[3], dw1[3], a1[3], w2[3], dw2[3], a2[3];
        differences(kin, &p, h, w1, dw1, a1);
        differences(kin, &p, h / 2, w2, dw2, a2);
        double w_b[3], dw_b[3], acc_b[3];
        for (int i = 0; i < 3; ++i) {
            w_b[i] = (4 * w2[i] - w1[i]) / 3;
            dw_b[i] = (4 * dw2[i] - dw1[i]) / 3;
            acc_b[i] = (4 * a2[i] - a1[i]) / 3;
        }
        loadid_real_t q[NJ], qd[NJ], qdd[NJ];
        traj_at(&p, 0, q, qd);
        for (int i = 0; i < NJ; ++i) qdd[i] = p.a[i];
        loadid_kin_state_t st;
        assert_int_equal(loadid_kin_eval(kin, q, qd, qdd, &st), 0);
        double r[9], w[3], dw[3], acc[3], g[3];
        for (int i = 0; i < 9; ++i) r[i] = st.rotation[i];
        rt_mul(r, w_b, w);
        rt_mul(r, dw_b, dw);
        rt_mul(r, acc_b, acc);
        rt_mul(r, kGravity, g);
        /* Truncation O(h^4) and round-off eps |p| / h^2 are both ~1e-9. */
        assert_vec(st.omega, w, 1e-7, "omega vs dR/dt");
        assert_vec(st.alpha, dw, 1e-6, "alpha vs d(omega)/dt");
        assert_vec(st.accel, acc, 1e-5, "accel vs d2p/dt2");
        assert_vec(st.gravity, g, 1e-12, "gravity");
        double spec[3] = {st.accel[0] - g[0], st.accel[1] - g[1], st.accel[2] - g[2]};
        assert_vec(st.spec, spec, 1e-12, "spec");
        loadid_kin_destroy(kin);
    }
}
#endif

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(planar_arm_matches_closed_form),
        cmocka_unit_test(bad_input_is_rejected),
        cmocka_unit_test(chain_check_refuses_broken_chains),
#if !LOADID_SCALAR_FLOAT
        cmocka_unit_test(random_chain_matches_finite_differences),
#endif
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
