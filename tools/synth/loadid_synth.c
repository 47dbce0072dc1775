/* Synthetic motion of S and the load's wrench (loadid_synth.h). */
#include "loadid_synth.h"

#define LOADID_PI 3.14159265358979323846

#include <errno.h>
#include <math.h>
#include <string.h>

/* Section V.A of the paper: o1, [kg, kg m, kg m^2]. */
const double loadid_synth_phi_o1[10] = {
    1.00, -43.5e-3, 28.5e-3, 22.5e-3, 2.21e-3, 1.22e-3, 0.96e-3, 3.74e-3, -0.63e-3, 4.95e-3,
};

static uint64_t rotl(uint64_t x, int k) {
    return (x << k) | (x >> (64 - k));
}

static uint64_t splitmix64(uint64_t *x) {
    uint64_t z = (*x += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

void loadid_rng_seed(loadid_rng_t *rng, uint64_t seed) {
    for (int i = 0; i < 4; ++i) rng->s[i] = splitmix64(&seed);
    rng->has_spare = 0;
    rng->spare = 0;
}

static uint64_t next_u64(loadid_rng_t *rng) {
    uint64_t *s = rng->s;
    const uint64_t result = rotl(s[1] * 5, 7) * 9;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

double loadid_rng_uniform(loadid_rng_t *rng) {
    return (double)(next_u64(rng) >> 11) * 0x1.0p-53;
}

double loadid_rng_normal(loadid_rng_t *rng) {
    if (rng->has_spare) {
        rng->has_spare = 0;
        return rng->spare;
    }
    double u1;
    do {
        u1 = loadid_rng_uniform(rng);
    } while (u1 <= 0.0);
    const double u2 = loadid_rng_uniform(rng);
    const double r = sqrt(-2.0 * log(u1));
    rng->spare = r * sin(2.0 * LOADID_PI * u2);
    rng->has_spare = 1;
    return r * cos(2.0 * LOADID_PI * u2);
}

void loadid_synth_traj_default(loadid_synth_traj_t *traj, uint64_t seed) {
    loadid_rng_t rng;
    loadid_rng_seed(&rng, seed);
    memset(traj, 0, sizeof *traj);
    traj->base_freq = 0.4;
    traj->harmonics = 5;
    traj->gravity[2] = -9.81;
    /* A tilted start so gravity is not along one axis of S. */
    traj->offset[0] = 0.3;
    traj->offset[1] = 0.5;
    traj->offset[2] = -0.4;
    traj->offset[5] = 0.6;
    for (int i = 0; i < 6; ++i) {
        /* Harmonic k adds an acceleration of amplitude a_k (2 pi k f)^2:
         * each gets up to 12 rad/s^2 (angles) or 3 m/s^2 (positions), with
         * its amplitude capped at 0.3 rad or 0.1 m. */
        const double acc = i < 3 ? 12.0 : 3.0, cap = i < 3 ? 0.3 : 0.1;
        for (int k = 1; k <= traj->harmonics; ++k) {
            const double wk = 2.0 * LOADID_PI * k * traj->base_freq;
            double amp = acc / (wk * wk);
            if (amp > cap) amp = cap;
            traj->sin_coef[i][k - 1] = amp * (2.0 * loadid_rng_uniform(&rng) - 1.0);
            traj->cos_coef[i][k - 1] = amp * (2.0 * loadid_rng_uniform(&rng) - 1.0);
        }
    }
}

/* One coordinate of eq. (11) and its first two time derivatives. */
static void coordinate(const loadid_synth_traj_t *tr, int i, double t, int still, double q[3]) {
    q[0] = tr->offset[i];
    q[1] = q[2] = 0.0;
    if (still) return;
    for (int k = 1; k <= tr->harmonics; ++k) {
        const double w = 2.0 * LOADID_PI * k * tr->base_freq;
        const double s = sin(w * t), c = cos(w * t);
        const double a = tr->sin_coef[i][k - 1], b = tr->cos_coef[i][k - 1];
        q[0] += a * s + b * c;
        q[1] += w * (a * c - b * s);
        q[2] += -w * w * (a * s + b * c);
    }
}

typedef double mat3[3][3];

static void mat_mul(const mat3 a, const mat3 b, mat3 out) {
    mat3 r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            r[i][j] = 0.0;
            for (int k = 0; k < 3; ++k) r[i][j] += a[i][k] * b[k][j];
        }
    memcpy(out, r, sizeof r);
}

static void mat3_mul3(const mat3 a, const mat3 b, const mat3 c, mat3 out) {
    mat3 ab;
    mat_mul(a, b, ab);
    mat_mul(ab, c, out);
}

/* acc += w * a b c */
static void add_product(const mat3 a, const mat3 b, const mat3 c, double w, mat3 acc) {
    mat3 t;
    mat3_mul3(a, b, c, t);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) acc[i][j] += w * t[i][j];
}

/* Elementary rotation about axis ax by angle q[0], with its first and second
 * time derivatives given q' = q[1], q'' = q[2]. */
static void elementary(int ax, const double q[3], mat3 R, mat3 Rd, mat3 Rdd) {
    const double c = cos(q[0]), s = sin(q[0]);
    const int i = (ax + 1) % 3, j = (ax + 2) % 3;
    memset(R, 0, sizeof(mat3));
    memset(Rd, 0, sizeof(mat3));
    memset(Rdd, 0, sizeof(mat3));
    R[ax][ax] = 1.0;
    R[i][i] = c;
    R[i][j] = -s;
    R[j][i] = s;
    R[j][j] = c;
    /* dR/dq = [-s -c; c -s] on (i, j); d2R/dq2 = [-c s; -s -c]. */
    const double d1[2][2] = {{-s, -c}, {c, -s}}, d2[2][2] = {{-c, s}, {-s, -c}};
    const int idx[2] = {i, j};
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) {
            Rd[idx[a]][idx[b]] = d1[a][b] * q[1];
            Rdd[idx[a]][idx[b]] = d2[a][b] * q[1] * q[1] + d1[a][b] * q[2];
        }
}

int loadid_synth_motion(const loadid_synth_traj_t *traj, double t, int still,
                        loadid_motion_t *out) {
    if (!traj || !out) return -EINVAL;
    double q[6][3];
    for (int i = 0; i < 6; ++i) coordinate(traj, i, t, still, q[i]);
    mat3 A, Ad, Add, B, Bd, Bdd, C, Cd, Cdd;
    elementary(2, q[0], A, Ad, Add); /* Rz(psi) */
    elementary(1, q[1], B, Bd, Bdd); /* Ry(theta) */
    elementary(0, q[2], C, Cd, Cdd); /* Rx(phi) */
    mat3 R, Rd, Rdd;
    mat3_mul3(A, B, C, R);
    memset(Rd, 0, sizeof Rd);
    memset(Rdd, 0, sizeof Rdd);
    /* (ABC)' = A'BC + AB'C + ABC' */
    add_product(Ad, B, C, 1.0, Rd);
    add_product(A, Bd, C, 1.0, Rd);
    add_product(A, B, Cd, 1.0, Rd);
    /* (ABC)'' = A''BC + AB''C + ABC'' + 2 (A'B'C + A'BC' + AB'C') */
    add_product(Add, B, C, 1.0, Rdd);
    add_product(A, Bdd, C, 1.0, Rdd);
    add_product(A, B, Cdd, 1.0, Rdd);
    add_product(Ad, Bd, C, 2.0, Rdd);
    add_product(Ad, B, Cd, 2.0, Rdd);
    add_product(A, Bd, Cd, 2.0, Rdd);
    /* R^T R' = [w]x and R^T R'' = [alpha]x + [w]x^2 (body frame S). */
    mat3 Rt, W, Q;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Rt[i][j] = R[j][i];
    mat_mul(Rt, Rd, W);
    mat_mul(Rt, Rdd, Q);
    const double w[3] = {0.5 * (W[2][1] - W[1][2]), 0.5 * (W[0][2] - W[2][0]),
                         0.5 * (W[1][0] - W[0][1])};
    mat3 W2;
    const mat3 Wx = {{0, -w[2], w[1]}, {w[2], 0, -w[0]}, {-w[1], w[0], 0}};
    mat_mul(Wx, Wx, W2);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Q[i][j] -= W2[i][j];
    const double al[3] = {0.5 * (Q[2][1] - Q[1][2]), 0.5 * (Q[0][2] - Q[2][0]),
                          0.5 * (Q[1][0] - Q[0][1])};
    double pdd_minus_g[3];
    for (int i = 0; i < 3; ++i) pdd_minus_g[i] = q[3 + i][2] - traj->gravity[i];
    for (int i = 0; i < 3; ++i) {
        out->omega[i] = w[i];
        out->alpha[i] = al[i];
        out->spec[i] = 0.0;
        out->g[i] = 0.0;
        for (int j = 0; j < 3; ++j) {
            out->spec[i] += Rt[i][j] * pdd_minus_g[j];
            out->g[i] += Rt[i][j] * traj->gravity[j];
        }
    }
    return 0;
}

static void cross(const double a[3], const double b[3], double out[3]) {
    const double r[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                         a[0] * b[1] - a[1] * b[0]};
    memcpy(out, r, sizeof r);
}

void loadid_synth_wrench(const double phi[10], const loadid_motion_t *m, double wrench[6]) {
    const double mass = phi[0];
    const double h[3] = {phi[1], phi[2], phi[3]}; /* m c */
    const double I[3][3] = {
        {phi[4], phi[5], phi[6]}, {phi[5], phi[7], phi[8]}, {phi[6], phi[8], phi[9]}};
    double t1[3], t2[3], Iw[3], Ia[3];
    /* Eq. (1): f = m (a - g) + alpha x (m c) + w x (w x (m c)). */
    cross(m->alpha, h, t1);
    cross(m->omega, h, t2);
    cross(m->omega, t2, t2);
    for (int i = 0; i < 3; ++i) wrench[i] = mass * m->spec[i] + t1[i] + t2[i];
    /* Eq. (2): tau = I alpha + w x (I w) + (m c) x (a - g). */
    for (int i = 0; i < 3; ++i) {
        Iw[i] = I[i][0] * m->omega[0] + I[i][1] * m->omega[1] + I[i][2] * m->omega[2];
        Ia[i] = I[i][0] * m->alpha[0] + I[i][1] * m->alpha[1] + I[i][2] * m->alpha[2];
    }
    cross(m->omega, Iw, t1);
    cross(h, m->spec, t2);
    for (int i = 0; i < 3; ++i) wrench[3 + i] = Ia[i] + t1[i] + t2[i];
}

int loadid_synth_sample(const loadid_synth_traj_t *traj, const double phi[10], double t, int still,
                        const loadid_synth_noise_t *noise, loadid_rng_t *rng,
                        loadid_synth_sample_t *out) {
    if (!traj || !phi || !out || (noise && !rng)) return -EINVAL;
    loadid_synth_motion(traj, t, still, &out->truth);
    loadid_synth_wrench(phi, &out->truth, out->wrench_true);
    out->meas = out->truth;
    memcpy(out->wrench_meas, out->wrench_true, sizeof out->wrench_meas);
    if (!noise) return 0;
    for (int i = 0; i < 3; ++i) {
        out->meas.spec[i] += noise->sigma_spec * loadid_rng_normal(rng);
        out->meas.alpha[i] += noise->sigma_alpha * loadid_rng_normal(rng);
        out->meas.omega[i] += noise->sigma_omega * loadid_rng_normal(rng);
    }
    for (int i = 0; i < 6; ++i)
        out->wrench_meas[i] +=
            noise->offset[i] + (i < 3 ? noise->sigma_f : noise->sigma_tau) * loadid_rng_normal(rng);
    return 0;
}
