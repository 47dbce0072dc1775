// Steady-state error of the joint filter and of its RTS smoother
// (loadid_jf_steady_sigma in loadid/joint_filter.h): the Riccati recursions
// of joint_filter.cpp's model at a constant step, iterated in double to a
// fixed point. Start-up only: Eigen 3x3, no heap.
#include <cerrno>
#include <cmath>

#include <Eigen/Dense>

#include "joint_filter_steady.hpp"
#include "loadid/joint_filter.h"

namespace {

using M3 = Eigen::Matrix3d;

bool converged(const M3 &a, const M3 &b) {
    return ((a - b).cwiseAbs().array() <= 1e-12 * b.cwiseAbs().array() + 1e-300).all();
}

// The steady filter: P- and P (predicted and corrected covariances).
void steady_filter(const loadid_jf_config_t &cfg, double dt, M3 &F, M3 &P, M3 &Pp, double &r) {
    const double q = cfg.jerk_psd;
    r = double(cfg.meas_sigma) * double(cfg.meas_sigma);
    const double h = dt * dt / 2, d2 = dt * dt, d3 = d2 * dt;
    M3 Q;
    F << 1, dt, h, 0, 1, dt, 0, 0, 1;
    Q << d3 * d2 / 20, d2 * d2 / 8, d3 / 6, d2 * d2 / 8, d3 / 3, d2 / 2, d3 / 6, d2 / 2, dt;
    Q *= q;
    P = M3::Zero();
    P.diagonal() << r, 1, 100; // the filter's initial state (joint_filter.cpp)
    for (int it = 0; it < 200000; ++it) {
        Pp = F * P * F.transpose() + Q;
        const Eigen::Vector3d K = Pp.col(0) / (Pp(0, 0) + r);
        M3 A = M3::Identity();
        A.col(0) -= K;
        const M3 next = A * Pp * A.transpose() + r * K * K.transpose(); // Joseph form
        const bool done = converged(next, P);
        P = next;
        if (done) break;
    }
    Pp = F * P * F.transpose() + Q;
}

} // namespace

namespace loadid {

void fixed_lag_gains(const loadid_jf_config_t &cfg, double dt, int lag, double gain[][3]) {
    M3 F, P, Pp;
    double r;
    steady_filter(cfg, dt, F, P, Pp, r);
    const double s = Pp(0, 0) + r;
    const Eigen::Vector3d K = Pp.col(0) / s;
    M3 IKH = M3::Identity();
    IKH.col(0) -= K;
    const M3 Fc_t = (F * IKH).transpose();
    Eigen::Vector3d u(1, 0, 0); // [(F (I - K H))^T]^i H^T
    for (int i = 0; i <= lag; ++i) {
        const Eigen::Vector3d b = Pp * u / s;
        for (int c = 0; c < 3; ++c) gain[i][c] = b(c);
        u = Fc_t * u;
    }
}

int settle_steps(const loadid_jf_config_t &cfg, double dt) {
    M3 F, P, Pp;
    double r;
    steady_filter(cfg, dt, F, P, Pp, r);
    const M3 steady = Pp;
    const double d2 = dt * dt, d3 = d2 * dt;
    M3 Q;
    Q << d3 * d2 / 20, d2 * d2 / 8, d3 / 6, d2 * d2 / 8, d3 / 3, d2 / 2, d3 / 6, d2 / 2, dt;
    Q *= double(cfg.jerk_psd);
    P = M3::Zero(); // after the first measurement (joint_filter.cpp, initialise)
    P.diagonal() << r, double(cfg.init_sigma_vel) * double(cfg.init_sigma_vel),
        double(cfg.init_sigma_acc) * double(cfg.init_sigma_acc);
    for (int k = 1; k < kMaxSettle; ++k) {
        Pp = F * P * F.transpose() + Q;
        if ((Pp.diagonal().array() <= kSettleFactor * steady.diagonal().array()).all()) return k;
        const Eigen::Vector3d K = Pp.col(0) / (Pp(0, 0) + r);
        M3 A = M3::Identity();
        A.col(0) -= K;
        P = A * Pp * A.transpose() + r * K * K.transpose();
    }
    return kMaxSettle;
}

} // namespace loadid

extern "C" int loadid_jf_noise_sigma(const loadid_jf_config_t *cfg, double dt, double sigma[3]) {
    if (!cfg || !sigma || !(std::isfinite(dt) && dt > 0)) return -EINVAL;
    if (!(cfg->jerk_psd > 0 && cfg->meas_sigma > 0) || cfg->lag_steps < 0 ||
        cfg->lag_steps > LOADID_JF_MAX_LAG)
        return -EINVAL;
    M3 F, P, Pp;
    double r;
    steady_filter(*cfg, dt, F, P, Pp, r);
    const int lag = cfg->lag_steps;
    double gain[LOADID_JF_MAX_LAG + 1][3];
    if (lag > 0) loadid::fixed_lag_gains(*cfg, dt, lag, gain);
    const Eigen::Vector3d K = Pp.col(0) / (Pp(0, 0) + r);
    // A unit measurement at step lag through the steady filter; the
    // estimate of step j responds to it as g(j - lag). The last lag + 1
    // innovations and predictions are kept in rings.
    constexpr int kSpan = 4000; // the filter forgets within about 20 ms
    constexpr int kRing = LOADID_JF_MAX_LAG + 1;
    double nu[kRing], xp[kRing][3];
    const int steps = kSpan + 2 * lag + 1;
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    double sum[3] = {0, 0, 0};
    for (int k = 0; k < steps; ++k) {
        const Eigen::Vector3d pred = F * x;
        const double z = k == lag ? 1.0 : 0.0;
        const int slot = k % kRing;
        nu[slot] = z - pred(0);
        for (int c = 0; c < 3; ++c) xp[slot][c] = pred(c);
        x = pred + K * nu[slot];
        const int j = k - lag; // its estimate is complete now
        if (j < 0) continue;
        const int js = j % kRing;
        double e[3] = {xp[js][0], xp[js][1], xp[js][2]};
        if (lag > 0) {
            for (int i = 0; i <= lag; ++i)
                for (int c = 0; c < 3; ++c) e[c] += gain[i][c] * nu[(j + i) % kRing];
        } else {
            for (int c = 0; c < 3; ++c) e[c] += K(c) * nu[js];
        }
        for (int c = 0; c < 3; ++c) sum[c] += e[c] * e[c];
    }
    for (int c = 0; c < 3; ++c) sigma[c] = std::sqrt(r * sum[c]);
    return 0;
}

extern "C" int loadid_jf_steady_sigma(const loadid_jf_config_t *cfg, double dt, int smoothed,
                                      double sigma[3]) {
    if (!cfg || !sigma || !(std::isfinite(dt) && dt > 0)) return -EINVAL;
    const double q = cfg->jerk_psd, r0 = double(cfg->meas_sigma) * double(cfg->meas_sigma);
    if (!(std::isfinite(q) && q > 0 && std::isfinite(r0) && r0 > 0)) return -EINVAL;
    M3 F, P, Pp;
    double r;
    steady_filter(*cfg, dt, F, P, Pp, r);
    M3 out = P;
    if (smoothed) {
        const M3 G = P * F.transpose() * Pp.inverse();
        M3 Ps = P;
        for (int it = 0; it < 200000; ++it) {
            const M3 next = P + G * (Ps - Pp) * G.transpose();
            const bool done = converged(next, Ps);
            Ps = next;
            if (done) break;
        }
        out = Ps;
    }
    for (int i = 0; i < 3; ++i) sigma[i] = std::sqrt(std::max(out(i, i), 0.0));
    return 0;
}
