// Joint-space Kalman filter and Rauch-Tung-Striebel smoother
// (loadid/joint_filter.h): per joint a triple integrator driven by white
// jerk, measured in position only.
//
// References for the equations below:
//  [BLK] Bar-Shalom, Li & Kirubarajan, "Estimation with Applications to
//        Tracking and Navigation", Wiley 2001: sec. 6.2.3 (continuous
//        Wiener-process acceleration model: F(dt) and Q(dt) of the header),
//        sec. 5.2 (the discrete Kalman filter; Joseph form of the
//        covariance update).
//  [S]   Saerkkae, "Bayesian Filtering and Smoothing", CUP 2013, sec. 8.2
//        (Rauch-Tung-Striebel smoother, Theorem 8.2).
// The 3x3 covariances are plain arrays: no Eigen, nothing on the heap
// after loadid_jf_create.
#include "loadid/joint_filter.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <new>
#include <utility>

#include "finite.hpp"
#include "joint_filter_steady.hpp"

using Real = loadid_real_t;

namespace {

constexpr int kMaxJoints = 16;
constexpr int kRing = 2 * LOADID_JF_MAX_LAG + 1; // fixed-lag history, updates
// Smoother: per sample the filtered x (3) and upper triangle of P (6), then
// the prediction into it from the sample before (the same 9), which the
// backward pass reuses instead of computing it again.
constexpr size_t kWorkPerSample = 18;
constexpr size_t kPredicted = 9;

// Mean and covariance of one joint's x = [q, qd, qdd].
struct Gauss {
    Real x[3];
    Real P[3][3]; // symmetric: both triangles are kept equal
};

bool positive_finite(Real v) {
    return std::isfinite(v) && v > 0;
}

bool valid_config(const loadid_jf_config_t *c) {
    return c && positive_finite(c->jerk_psd) && positive_finite(c->meas_sigma) &&
           positive_finite(c->init_sigma_vel) && positive_finite(c->init_sigma_acc) &&
           c->max_step_us > 0 && c->lag_steps >= 0 && c->lag_steps <= LOADID_JF_MAX_LAG &&
           (c->lag_steps == 0 || c->nominal_step_us > 0);
}

// |t1 - t0| in unsigned arithmetic: exact for any two int64 stamps.
uint64_t distance_us(int64_t t0, int64_t t1) {
    return t1 >= t0 ? uint64_t(t1) - uint64_t(t0) : uint64_t(t0) - uint64_t(t1);
}

// t1 - t0 in seconds (either sign), rounded once from the exact difference.
Real seconds(int64_t t0, int64_t t1) {
    const Real s = Real(double(distance_us(t0, t1)) / 1e6);
    return t1 >= t0 ? s : -s;
}

// Does the step t0 -> t1 (t1 > t0) break the series (restart the filter)?
bool is_gap(int64_t t0, int64_t t1, const loadid_jf_config_t &c) {
    return distance_us(t0, t1) > uint64_t(c.max_step_us);
}

// The first measurement: q from it (variance meas_sigma^2), qd and qdd 0.
void initialise(Gauss &g, Real z, const loadid_jf_config_t &c) {
    g = Gauss{{z, 0, 0}, {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}};
    g.P[0][0] = c.meas_sigma * c.meas_sigma;
    g.P[1][1] = c.init_sigma_vel * c.init_sigma_vel;
    g.P[2][2] = c.init_sigma_acc * c.init_sigma_acc;
}

// The model over a step dt > 0 ([BLK] 6.2.3): F(dt) and jerk_psd Q(dt),
// the same for every joint of an update.
struct Step {
    Real dt, h;   // F(dt) = [1 dt h; 0 1 dt; 0 0 1], h = dt^2 / 2
    Real Q[3][3]; // jerk_psd Q(dt)
};

Step step_of(Real dt, Real jerk_psd) {
    const Real h = dt * dt / 2;
    const Real dt2 = dt * dt, dt3 = dt2 * dt;
    const Real Q[3][3] = {{dt3 * dt2 / 20, dt2 * dt2 / 8, dt3 / 6},
                          {dt2 * dt2 / 8, dt3 / 3, dt2 / 2},
                          {dt3 / 6, dt2 / 2, dt}};
    Step m{dt, h, {}};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) m.Q[i][j] = jerk_psd * Q[i][j];
    return m;
}

// Time update ([BLK] 6.2.3, 5.2): x <- F x, P <- F P F^T + Q.
void predict(Gauss &g, const Step &m) {
    const Real dt = m.dt, h = m.h;
    const Real F[3][3] = {{1, dt, h}, {0, 1, dt}, {0, 0, 1}};
    g.x[0] += dt * g.x[1] + h * g.x[2];
    g.x[1] += dt * g.x[2];
    Real FP[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            FP[i][j] = F[i][0] * g.P[0][j] + F[i][1] * g.P[1][j] + F[i][2] * g.P[2][j];
    for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) // upper triangle of F P F^T + Q, mirrored
            g.P[i][j] = g.P[j][i] =
                FP[i][0] * F[j][0] + FP[i][1] * F[j][1] + FP[i][2] * F[j][2] + m.Q[i][j];
}

void predict(Gauss &g, Real dt, Real jerk_psd) {
    predict(g, step_of(dt, jerk_psd));
}

// Measurement update with z = q + v, var(v) = r, H = [1 0 0] ([BLK] 5.2):
// K = P H^T / s, s = H P H^T + r; x <- x + K (z - H x); and P in Joseph
// form, P <- (I - K H) P (I - K H)^T + r K K^T, which stays symmetric
// positive definite under rounding (the float build) where the short form
// (I - K H) P need not.
void correct(Gauss &g, Real z, Real r) {
    const Real s = g.P[0][0] + r;
    const Real K[3] = {g.P[0][0] / s, g.P[1][0] / s, g.P[2][0] / s};
    const Real e = z - g.x[0];
    for (int i = 0; i < 3; ++i) g.x[i] += K[i] * e;
    // A = I - K H: only its first column differs from I; A[0][0] = 1 - K[0]
    // is taken as r / s, without the cancellation.
    const Real a0[3] = {r / s, -K[1], -K[2]};
    Real AP[3][3]; // A P: row i is P[i] + a0[i] P[0] (i > 0), a0[0] P[0] (i = 0)
    for (int j = 0; j < 3; ++j) {
        AP[0][j] = a0[0] * g.P[0][j];
        AP[1][j] = g.P[1][j] + a0[1] * g.P[0][j];
        AP[2][j] = g.P[2][j] + a0[2] * g.P[0][j];
    }
    for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) {
            // (A P A^T)[i][j] = sum_k AP[i][k] A[j][k] = AP[i][j] + AP[i][0] a0[j] (j > 0)
            const Real apa = j == 0 ? AP[i][0] * a0[0] : AP[i][j] + AP[i][0] * a0[j];
            g.P[i][j] = g.P[j][i] = apa + r * K[i] * K[j];
        }
}

// Solves S y = b for a symmetric positive definite 3x3 S by S = L D L^T
// (accurate for badly scaled S, as P of q, qd, qdd is). False when a pivot
// is not positive (S not numerically positive definite).
bool ldlt_solve(const Real S[3][3], const Real b[3], Real y[3]) {
    const Real d0 = S[0][0];
    if (!(d0 > 0)) return false;
    const Real l10 = S[1][0] / d0, l20 = S[2][0] / d0;
    const Real d1 = S[1][1] - l10 * l10 * d0;
    if (!(d1 > 0)) return false;
    const Real l21 = (S[2][1] - l20 * l10 * d0) / d1;
    const Real d2 = S[2][2] - l20 * l20 * d0 - l21 * l21 * d1;
    if (!(d2 > 0)) return false;
    const Real z0 = b[0], z1 = b[1] - l10 * z0, z2 = b[2] - l20 * z0 - l21 * z1;
    y[2] = z2 / d2;
    y[1] = z1 / d1 - l21 * y[2];
    y[0] = z0 / d0 - l10 * y[1] - l20 * y[2];
    return true;
}

void store(const Gauss &g, Real *w) {
    w[0] = g.x[0], w[1] = g.x[1], w[2] = g.x[2];
    w[3] = g.P[0][0], w[4] = g.P[0][1], w[5] = g.P[0][2];
    w[6] = g.P[1][1], w[7] = g.P[1][2], w[8] = g.P[2][2];
}

Gauss load(const Real *w) {
    return Gauss{{w[0], w[1], w[2]}, {{w[3], w[4], w[5]}, {w[4], w[6], w[7]}, {w[5], w[7], w[8]}}};
}

// The on-line filters of all joints, joint index last (x[c][i], P[r][c][i],
// both triangles of P): an update is predict and correct above, written
// out element by element with the same operations in the same order (the
// same bits), in loops over the joints that the compiler vectorises, two
// joints at a time (the filters of one joint were a chain of divisions
// waiting on each other).
struct Bank {
    Real x[3][kMaxJoints];
    Real P[3][3][kMaxJoints];

    void set(int i, const Gauss &g) {
        for (int r = 0; r < 3; ++r) {
            x[r][i] = g.x[r];
            for (int c = 0; c < 3; ++c) P[r][c][i] = g.P[r][c];
        }
    }

    // predict(g, m) for each joint.
    void predict_all(int n, const Step &m) {
        const Real dt = m.dt, h = m.h;
        const Real F[3][3] = {{1, dt, h}, {0, 1, dt}, {0, 0, 1}};
        for (int i = 0; i < n; ++i) {
            x[0][i] += dt * x[1][i] + h * x[2][i];
            x[1][i] += dt * x[2][i];
            const Real p00 = P[0][0][i], p01 = P[0][1][i], p02 = P[0][2][i];
            const Real p10 = P[1][0][i], p11 = P[1][1][i], p12 = P[1][2][i];
            const Real p20 = P[2][0][i], p21 = P[2][1][i], p22 = P[2][2][i];
            // FP[a][b] = F[a][0] P[0][b] + F[a][1] P[1][b] + F[a][2] P[2][b]
            const Real fp00 = F[0][0] * p00 + F[0][1] * p10 + F[0][2] * p20;
            const Real fp01 = F[0][0] * p01 + F[0][1] * p11 + F[0][2] * p21;
            const Real fp02 = F[0][0] * p02 + F[0][1] * p12 + F[0][2] * p22;
            const Real fp10 = F[1][0] * p00 + F[1][1] * p10 + F[1][2] * p20;
            const Real fp11 = F[1][0] * p01 + F[1][1] * p11 + F[1][2] * p21;
            const Real fp12 = F[1][0] * p02 + F[1][1] * p12 + F[1][2] * p22;
            const Real fp20 = F[2][0] * p00 + F[2][1] * p10 + F[2][2] * p20;
            const Real fp21 = F[2][0] * p01 + F[2][1] * p11 + F[2][2] * p21;
            const Real fp22 = F[2][0] * p02 + F[2][1] * p12 + F[2][2] * p22;
            // P[a][b] = FP[a][0] F[b][0] + FP[a][1] F[b][1] + FP[a][2] F[b][2] + Q[a][b], b >= a
            const Real q00 = fp00 * F[0][0] + fp01 * F[0][1] + fp02 * F[0][2] + m.Q[0][0];
            const Real q01 = fp00 * F[1][0] + fp01 * F[1][1] + fp02 * F[1][2] + m.Q[0][1];
            const Real q02 = fp00 * F[2][0] + fp01 * F[2][1] + fp02 * F[2][2] + m.Q[0][2];
            const Real q11 = fp10 * F[1][0] + fp11 * F[1][1] + fp12 * F[1][2] + m.Q[1][1];
            const Real q12 = fp10 * F[2][0] + fp11 * F[2][1] + fp12 * F[2][2] + m.Q[1][2];
            const Real q22 = fp20 * F[2][0] + fp21 * F[2][1] + fp22 * F[2][2] + m.Q[2][2];
            P[0][0][i] = q00, P[0][1][i] = P[1][0][i] = q01, P[0][2][i] = P[2][0][i] = q02;
            P[1][1][i] = q11, P[1][2][i] = P[2][1][i] = q12, P[2][2][i] = q22;
        }
    }

    // correct(g, z[i], r) for each joint.
    void correct_all(int n, const Real *z, Real r) {
        for (int i = 0; i < n; ++i) {
            const Real p00 = P[0][0][i], p01 = P[0][1][i], p02 = P[0][2][i];
            const Real p10 = P[1][0][i], p11 = P[1][1][i], p12 = P[1][2][i];
            const Real p20 = P[2][0][i], p22 = P[2][2][i]; // P[2][1] is not read
            const Real s = p00 + r;
            const Real k0 = p00 / s, k1 = p10 / s, k2 = p20 / s;
            const Real e = z[i] - x[0][i];
            x[0][i] += k0 * e;
            x[1][i] += k1 * e;
            x[2][i] += k2 * e;
            const Real a0 = r / s, a1 = -k1, a2 = -k2;
            // AP: row 0 a0 P[0], row c P[c] + a_c P[0]
            const Real ap00 = a0 * p00, ap01 = a0 * p01, ap02 = a0 * p02;
            const Real ap10 = p10 + a1 * p00, ap11 = p11 + a1 * p01, ap12 = p12 + a1 * p02;
            const Real ap20 = p20 + a2 * p00, ap22 = p22 + a2 * p02; // AP[2][1] is not needed
            // P[a][b] = (b == 0 ? AP[a][0] a0 : AP[a][b] + AP[a][0] a_b) + r K[a] K[b]
            const Real q00 = ap00 * a0 + r * k0 * k0;
            const Real q01 = ap01 + ap00 * a1 + r * k0 * k1;
            const Real q02 = ap02 + ap00 * a2 + r * k0 * k2;
            const Real q11 = ap11 + ap10 * a1 + r * k1 * k1;
            const Real q12 = ap12 + ap10 * a2 + r * k1 * k2;
            const Real q22 = ap22 + ap20 * a2 + r * k2 * k2;
            P[0][0][i] = q00, P[0][1][i] = P[1][0][i] = q01, P[0][2][i] = P[2][0][i] = q02;
            P[1][1][i] = q11, P[1][2][i] = P[2][1][i] = q12, P[2][2][i] = q22;
        }
    }
};

} // namespace

// The fixed-lag smoother's history: per update its time, the piece of the
// series it belongs to (a restart after a gap begins a new one), each
// joint's predicted state x(k|k-1) and innovation nu(k), in a ring of the
// last kRing updates (kept without a lag too): lag + 1 are needed, the
// rest serves sensor samples that arrive late (a CAN bus behind the joint
// stream), and loadid_jf_retune filters them again.
struct LagEntry {
    int64_t t;
    int piece;
    int seq; // updates before it since the filter's (re)start (capped): settled from settle on
    Real xpred[3][kMaxJoints]; // x(j|j-1): xpred[c][i], component c of joint i
    // Its smoothed state so far, x(j|j-1) + sum_{k < terms} B_k nu(j+k)
    // (terms -1: not begun): a sample extends the sum with the updates
    // that came since the last, the same additions in the same order.
    int terms;
    Real xs[3][kMaxJoints];
};

struct loadid_jf {
    loadid_jf_config_t cfg;
    int n;
    int64_t last; // INT64_MIN: no measurement since create or reset
    Bank joints;
    // Fixed-lag smoothing (cfg.lag_steps > 0): gains B_i, i = 0..lag, and
    // the ring of the last kRing updates, their innovations apart (a
    // smoothed state walks lag of them: a cache line each).
    Real gain[LOADID_JF_MAX_LAG + 1][3];
    LagEntry ring[kRing];
    Real nu[kRing][kMaxJoints];
    int ring_head, ring_count; // the oldest entry, and how many
    int piece;                 // the current piece of the series
    int piece_entries;         // its entries, at the ring's end
    int64_t piece_start;       // the time of its first update (no entry)
    int since_start;           // updates since the filter's (re)start (capped)
    int settle;                // loadid_jf_settle_steps
};

extern "C" int loadid_jf_config_default(loadid_jf_config_t *cfg) {
    if (!cfg) return -EINVAL;
    // Tuned on multi-sine joint motion up to 2 Hz, 1 kHz, 2^20 counts per
    // revolution: see the figures in joint_filter.h.
    cfg->jerk_psd = Real(1e3);
    cfg->meas_sigma =
        Real(6.283185307179586 / 1048576.0 / 3.4641016151377546); // 2 pi / 2^20 / sqrt(12)
    cfg->init_sigma_vel = 1;
    cfg->init_sigma_acc = 10;
    cfg->max_step_us = 100000;
    cfg->lag_steps = 0;
    cfg->nominal_step_us = 1000;
    return 0;
}

extern "C" int loadid_jf_create(int num_joints, const loadid_jf_config_t *cfg, loadid_jf_t **out) {
    if (!out) return -EINVAL;
    *out = nullptr;
    if (num_joints < 1 || num_joints > kMaxJoints || !valid_config(cfg)) return -EINVAL;
    loadid_jf *jf = new (std::nothrow) loadid_jf;
    if (!jf) return -ENOMEM;
    jf->n = num_joints;
    loadid_jf_configure(jf, cfg);
    *out = jf;
    return 0;
}

// The settle count and the fixed-lag smoother's steady gains of cfg.
static void derive(loadid_jf_t *jf, const loadid_jf_config_t *cfg) {
    jf->cfg = *cfg;
    jf->settle = loadid::settle_steps(
        *cfg, double(cfg->nominal_step_us > 0 ? cfg->nominal_step_us : 1000) * 1e-6);
    if (cfg->lag_steps > 0) {
        double g[LOADID_JF_MAX_LAG + 1][3];
        loadid::fixed_lag_gains(*cfg, double(cfg->nominal_step_us) * 1e-6, cfg->lag_steps, g);
        for (int i = 0; i <= cfg->lag_steps; ++i)
            for (int c = 0; c < 3; ++c) jf->gain[i][c] = Real(g[i][c]);
    }
}

extern "C" int loadid_jf_configure(loadid_jf_t *jf, const loadid_jf_config_t *cfg) {
    if (!jf || !valid_config(cfg)) return -EINVAL;
    derive(jf, cfg);
    return loadid_jf_reset(jf);
}

extern "C" void loadid_jf_destroy(loadid_jf_t *jf) {
    delete jf;
}

extern "C" int loadid_jf_reset(loadid_jf_t *jf) {
    if (!jf) return -EINVAL;
    jf->last = INT64_MIN;
    jf->ring_head = jf->ring_count = 0;
    jf->piece = jf->piece_entries = jf->since_start = 0;
    return 0;
}

// A new entry of the current piece at the ring's end (the ring keeps the
// last kRing updates); returns its slot.
static int push_entry(loadid_jf_t *jf, int64_t t_us, int seq) {
    if (jf->ring_count == kRing)
        jf->ring_head = (jf->ring_head + 1) % kRing;
    else
        ++jf->ring_count;
    const int slot = (jf->ring_head + jf->ring_count - 1) % kRing;
    LagEntry *e = &jf->ring[slot];
    e->t = t_us;
    e->piece = jf->piece;
    e->seq = seq;
    e->terms = -1;
    jf->piece_entries = std::min(jf->piece_entries + 1, jf->ring_count);
    return slot;
}

// One update of every joint with the measurements z, kept in ring slot
// slot: the first of a (re)start initialises from z, another predicts over
// dt [s] and corrects; the entry keeps x(k|k-1) and the innovations
// z - x(k|k-1) (0 for a first update).
static void filter_into(loadid_jf_t *jf, int slot, bool first, Real dt, const Real *z) {
    if (first) {
        for (int i = 0; i < jf->n; ++i) {
            Gauss g;
            initialise(g, z[i], jf->cfg);
            jf->joints.set(i, g);
        }
    } else {
        jf->joints.predict_all(jf->n, step_of(dt, jf->cfg.jerk_psd));
    }
    LagEntry &e = jf->ring[slot];
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < jf->n; ++i) e.xpred[c][i] = jf->joints.x[c][i];
    for (int i = 0; i < jf->n; ++i) jf->nu[slot][i] = first ? Real(0) : z[i] - jf->joints.x[0][i];
    if (!first) jf->joints.correct_all(jf->n, z, jf->cfg.meas_sigma * jf->cfg.meas_sigma);
}

// The current piece's kept updates filtered again with jf's gains, from
// the prior at the oldest of them as at a restart (its entries, state and
// settle count). A measurement is its entry's x(k|k-1) + nu(k): z itself
// where z - x(k|k-1) was exact (Sterbenz: within a factor 2 of each
// other), else within an ulp of it. With none kept since the piece began
// (loadid_jf_end_piece just before), the state stays, counted as not
// settled.
static void refilter(loadid_jf_t *jf) {
    const int count = jf->piece_entries, first = jf->ring_count - count;
    Real z[kMaxJoints];
    int64_t prev = 0;
    for (int k = 0; k < count; ++k) {
        const int slot = (jf->ring_head + first + k) % kRing;
        LagEntry &e = jf->ring[slot];
        for (int i = 0; i < jf->n; ++i) z[i] = e.xpred[0][i] + jf->nu[slot][i];
        filter_into(jf, slot, k == 0, k == 0 ? Real(0) : seconds(prev, e.t), z);
        e.seq = k;
        prev = e.t;
    }
    jf->since_start = count;
}

extern "C" int loadid_jf_retune(loadid_jf_t *jf, loadid_real_t meas_sigma, int lag_steps) {
    if (!jf) return -EINVAL;
    loadid_jf_config_t c = jf->cfg;
    c.meas_sigma = meas_sigma;
    c.lag_steps = lag_steps;
    if (!valid_config(&c)) return -EINVAL;
    derive(jf, &c);
    for (LagEntry &e : jf->ring) e.terms = -1; // sums of the old gains
    // A kept state would carry the old gains' errors, far beyond its
    // covariance, for many settle counts of the new ones (joint_filter.h).
    if (jf->last != INT64_MIN) refilter(jf);
    return 0;
}

extern "C" int loadid_jf_update(loadid_jf_t *jf, int64_t t_us, const loadid_real_t *q) {
    if (!jf || !q) return -EINVAL;
    if (!loadid::all_finite(q, jf->n)) return LOADID_E_NONFINITE;
    const bool first = jf->last == INT64_MIN;
    if (!first && t_us <= jf->last) return LOADID_E_TIME_ORDER;
    const bool restart = first || is_gap(jf->last, t_us, jf->cfg);
    if (restart) {
        // The smoother restarts with the filter; the last piece's updates
        // stay (smoothed with what came after them in it) until pushed out.
        // The first update is an entry too (its state, no innovation), so
        // a sample just after it is served from it, as the filter would.
        ++jf->piece;
        jf->piece_entries = 0;
        jf->piece_start = t_us;
        jf->since_start = 0;
    }
    const int slot = push_entry(jf, t_us, jf->since_start);
    filter_into(jf, slot, restart, restart ? Real(0) : seconds(jf->last, t_us), q);
    jf->last = t_us;
    if (jf->since_start < INT32_MAX) ++jf->since_start;
    return 0;
}

extern "C" int loadid_jf_state_at(const loadid_jf_t *jf, int64_t t_us, loadid_real_t *q,
                                  loadid_real_t *qd, loadid_real_t *qdd) {
    if (!jf) return -EINVAL;
    if (jf->last == INT64_MIN) return LOADID_E_NO_DATA;
    // x(t) = F(dt) x: the model's mean, forwards or backwards.
    const Real dt = seconds(jf->last, t_us), h = dt * dt / 2;
    for (int i = 0; i < jf->n; ++i) {
        const Real x[3] = {jf->joints.x[0][i], jf->joints.x[1][i], jf->joints.x[2][i]};
        if (q) q[i] = x[0] + dt * x[1] + h * x[2];
        if (qd) qd[i] = x[1] + dt * x[2];
        if (qdd) qdd[i] = x[2];
    }
    return 0;
}

extern "C" int64_t loadid_jf_last_time(const loadid_jf_t *jf) {
    return jf ? jf->last : INT64_MIN;
}

// The entry that is index k of the ring, oldest first.
static const LagEntry &ring_at(const loadid_jf_t *jf, int k) {
    return jf->ring[(jf->ring_head + k) % kRing];
}

extern "C" int loadid_jf_end_piece(loadid_jf_t *jf) {
    if (!jf) return -EINVAL;
    if (jf->last == INT64_MIN) return 0;
    ++jf->piece;
    jf->piece_entries = 0;
    jf->piece_start = jf->last + 1; // what came before is served now
    return 0;                       // the filter goes on: no settling
}

extern "C" int loadid_jf_settle_steps(const loadid_jf_t *jf) {
    return jf ? jf->settle : -EINVAL;
}

extern "C" int loadid_jf_settled(const loadid_jf_t *jf) {
    return jf && jf->last != INT64_MIN && jf->since_start > jf->settle;
}

// Entries of the current piece at the ring's end (kept as they come: the
// walk back over the ring cost as much as the smoothing itself).
static int current_entries(const loadid_jf_t *jf) {
    return jf->piece_entries;
}

extern "C" int64_t loadid_jf_lagged_time(const loadid_jf_t *jf) {
    if (!jf || jf->cfg.lag_steps <= 0 || jf->last == INT64_MIN) return INT64_MIN;
    const int lag = jf->cfg.lag_steps, cur = current_entries(jf);
    // The current piece: up to the first update without lag_steps after it.
    if (cur > lag) return ring_at(jf, jf->ring_count - lag).t - 1;
    // Else what an earlier piece left: up to its newest update (a sample
    // after that waits for this piece's first update to be smoothed).
    if (cur < jf->ring_count) return ring_at(jf, jf->ring_count - cur - 1).t;
    return INT64_MIN;
}

// Updates after ring entry j in its piece, at most lag. A piece's entries
// are contiguous in the ring: the current piece runs to the ring's end,
// and an older one has lag after j when entry j + lag is still in it.
static int updates_after(const loadid_jf_t *jf, int j, int lag) {
    const int piece = ring_at(jf, j).piece;
    if (piece == jf->piece) return std::min(lag, jf->ring_count - 1 - j);
    if (j + lag < jf->ring_count && ring_at(jf, j + lag).piece == piece) return lag;
    int after = 0;
    while (j + after + 1 < jf->ring_count && after < lag &&
           ring_at(jf, j + after + 1).piece == piece)
        ++after;
    return after;
}

// Adds the terms k0..k1 of the smoothed sums of entry j to xs (below),
// for N joints: a step is three multiply-adds over the joints, held in
// registers, so the 3 N sums run side by side instead of one after another.
template <int N>
void add_terms(const loadid_jf_t *jf, int j, int k0, int k1, Real (&xs)[3][kMaxJoints]) {
    Real acc[3][N];
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < N; ++i) acc[c][i] = xs[c][i];
    int slot = (jf->ring_head + j + k0) % kRing;
    for (int k = k0; k <= k1; ++k, slot = slot + 1 == kRing ? 0 : slot + 1) {
        const Real *nu = jf->nu[slot];
        const Real b0 = jf->gain[k][0], b1 = jf->gain[k][1], b2 = jf->gain[k][2];
        for (int i = 0; i < N; ++i) {
            acc[0][i] += b0 * nu[i];
            acc[1][i] += b1 * nu[i];
            acc[2][i] += b2 * nu[i];
        }
    }
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < N; ++i) xs[c][i] = acc[c][i];
}

using AddTerms = void (*)(const loadid_jf_t *, int, int, int, Real (&)[3][kMaxJoints]);

template <int... N>
constexpr std::array<AddTerms, sizeof...(N)> add_terms_table(std::integer_sequence<int, N...>) {
    return {{add_terms<N + 1>...}};
}

// add_terms for 1..kMaxJoints joints.
constexpr std::array<AddTerms, kMaxJoints> kAddTerms =
    add_terms_table(std::make_integer_sequence<int, kMaxJoints>{});

// Every joint's state at ring entry j smoothed with the after updates that
// follow it: x(j|j-1) + sum_k B_k nu(j+k), k = 0..after in that order
// (xs[c][i]: component c of joint i). The entry keeps the sum: a later call
// adds only the terms it lacks (the same additions in the same order as
// the whole sum, so the same bits), and one asking for fewer terms than
// it holds starts it again. The filter's const is the data's: the sums are
// a cache (not for two threads).
static const Real (&smoothed(const loadid_jf_t *jf, int j, int after))[3][kMaxJoints] {
    LagEntry &e = const_cast<LagEntry &>(ring_at(jf, j));
    if (e.terms < 0 || e.terms > after + 1) {
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < jf->n; ++i) e.xs[c][i] = e.xpred[c][i];
        e.terms = 0;
    }
    if (e.terms <= after) kAddTerms[jf->n - 1](jf, j, e.terms, after, e.xs);
    e.terms = after + 1;
    return e.xs;
}

// The newest kept update at or before t serves it: with lag_steps updates
// after it in its piece, or, in a piece that has ended, with those it had.
extern "C" int loadid_jf_lagged_state_at(const loadid_jf_t *jf, int64_t t_us, int64_t max_age_us,
                                         loadid_real_t *q, loadid_real_t *qd, loadid_real_t *qdd) {
    if (!jf || jf->cfg.lag_steps <= 0) return -EINVAL;
    const int lag = jf->cfg.lag_steps;
    if (jf->ring_count == 0) return LOADID_E_NO_DATA;
    // Before every kept update: served from the first, when close to it.
    if (ring_at(jf, 0).t > t_us && distance_us(t_us, ring_at(jf, 0).t) > uint64_t(max_age_us))
        return LOADID_E_STALE;
    int lo = 0, hi = jf->ring_count - 1; // the newest update at or before t: binary search
    while (lo < hi) {
        const int mid = (lo + hi + 1) / 2;
        if (ring_at(jf, mid).t <= t_us)
            lo = mid;
        else
            hi = mid - 1;
    }
    int j = lo;
    // Too far after it, but the next update (a piece that began after a
    // gap) is close: that one serves it, back in time, as the filter would.
    if (distance_us(ring_at(jf, j).t, t_us) > uint64_t(max_age_us) && j + 1 < jf->ring_count &&
        distance_us(t_us, ring_at(jf, j + 1).t) <= uint64_t(max_age_us))
        ++j;
    const LagEntry &e0 = ring_at(jf, j);
    // The filter had not settled there: never served (joint_filter.h).
    if (e0.seq < jf->settle) return LOADID_E_STALE;
    const int after = updates_after(jf, j, lag);
    if (e0.piece == jf->piece && after < lag) return LOADID_E_NO_DATA; // not smoothed yet
    if (distance_us(e0.t, t_us) > uint64_t(max_age_us)) return LOADID_E_STALE;
    // Between two updates of a piece, qdd is interpolated between both
    // smoothed states (the next one with the updates it has, lag - 1 for
    // the newest served): held constant from the first, as the model's
    // mean does, it lags by up to a step, 0.4 ms of jerk (0.16 rad/s^2 RMS
    // on a 2 Hz multi-sine, four times the smoother's own error).
    const bool next = j + 1 < jf->ring_count && ring_at(jf, j + 1).piece == e0.piece &&
                      ring_at(jf, j + 1).t > t_us && t_us >= e0.t;
    const Real dt = seconds(e0.t, t_us), h = dt * dt / 2;
    const Real step = next ? seconds(e0.t, ring_at(jf, j + 1).t) : Real(0);
    const Real w = next ? dt / step : Real(0);
    const int after1 = next ? updates_after(jf, j + 1, lag) : 0;
    const Real(&xs)[3][kMaxJoints] = smoothed(jf, j, after);
    const Real *qdd1 = next ? smoothed(jf, j + 1, after1)[2] : nullptr; // only its qdd is used
    for (int i = 0; i < jf->n; ++i) {
        const Real x[3] = {xs[0][i], xs[1][i], xs[2][i]};
        Real a = x[2], jerk = 0;
        if (next) {
            a = (1 - w) * x[2] + w * qdd1[i];
            jerk = (qdd1[i] - x[2]) / step;
        }
        // q and qd: the model's propagation with the interpolated jerk.
        if (q) q[i] = x[0] + dt * x[1] + h * x[2] + dt * h / 3 * jerk;
        if (qd) qd[i] = x[1] + dt * x[2] + h * jerk;
        if (qdd) qdd[i] = a;
    }
    return 0;
}

extern "C" size_t loadid_jf_smooth_work_size(size_t count) {
    return count > SIZE_MAX / kWorkPerSample ? SIZE_MAX : count * kWorkPerSample;
}

// Forward: the filter of loadid_jf_update, x_k and P_k stored per sample.
// Backward ([S] Theorem 8.2), k = count-2 .. 0, with the forward pass's
// prediction x-_{k+1} = F x_k, P-_{k+1} = F P_k F^T + Q:
//   x^s_k = x_k + G_k (x^s_{k+1} - x-_{k+1}),  G_k = P_k F^T (P-_{k+1})^-1,
// evaluated as x_k + P_k F^T y with P-_{k+1} y = x^s_{k+1} - x-_{k+1} (no
// inverse). A gap over max_step_us splits the series into independent
// pieces, as it restarts the on-line filter: each piece is smoothed alone.
extern "C" int loadid_jf_smooth(const loadid_jf_config_t *cfg, size_t count, const int64_t *t_us,
                                const loadid_real_t *q, loadid_real_t *work, loadid_real_t *q_out,
                                loadid_real_t *qd_out, loadid_real_t *qdd_out) {
    if (!valid_config(cfg) || count == 0 || !t_us || !q || !work) return -EINVAL;
    if (count > SIZE_MAX / kWorkPerSample) return -EINVAL;
    for (size_t k = 0; k < count; ++k) {
        if (!std::isfinite(q[k])) return LOADID_E_NONFINITE;
        if (k > 0 && t_us[k] <= t_us[k - 1]) return LOADID_E_TIME_ORDER;
    }
    const Real r = cfg->meas_sigma * cfg->meas_sigma;
    Gauss g;
    for (size_t k = 0; k < count; ++k) {
        if (k == 0 || is_gap(t_us[k - 1], t_us[k], *cfg)) {
            initialise(g, q[k], *cfg);
        } else {
            predict(g, seconds(t_us[k - 1], t_us[k]), cfg->jerk_psd);
            store(g, work + kWorkPerSample * k + kPredicted);
            correct(g, q[k], r);
        }
        store(g, work + kWorkPerSample * k);
    }
    for (size_t k = count - 1; k-- > 0;) {
        if (is_gap(t_us[k], t_us[k + 1], *cfg)) continue; // end of a piece: x^s_k = x_k
        Real *xk = work + kWorkPerSample * k;
        const Real *xs_next = xk + kWorkPerSample; // already smoothed
        const Gauss f = load(xk);
        const Gauss p = load(xs_next + kPredicted); // x-_{k+1}, P-_{k+1}
        const Real dt = seconds(t_us[k], t_us[k + 1]), h = dt * dt / 2;
        const Real d[3] = {xs_next[0] - p.x[0], xs_next[1] - p.x[1], xs_next[2] - p.x[2]};
        Real y[3];
        // P- is positive definite by construction (Q(dt) is for dt > 0); the
        // guard only keeps rounding from ever writing a non-finite value.
        if (!ldlt_solve(p.P, d, y)) continue;
        const Real u[3] = {y[0], dt * y[0] + y[1], h * y[0] + dt * y[1] + y[2]}; // F^T y
        for (int i = 0; i < 3; ++i) xk[i] += f.P[i][0] * u[0] + f.P[i][1] * u[1] + f.P[i][2] * u[2];
    }
    for (size_t k = 0; k < count; ++k) {
        const Real *x = work + kWorkPerSample * k;
        if (q_out) q_out[k] = x[0];
        if (qd_out) qd_out[k] = x[1];
        if (qdd_out) qdd_out[k] = x[2];
    }
    return 0;
}
