// Steady-state error of the joint filter and of its RTS smoother
// (loadid_jf_steady_sigma in loadid/joint_filter.h): the Riccati recursions
// of joint_filter.cpp's model at a constant step, iterated in double to a
// fixed point. Start-up only: Eigen 3x3, no heap.
#include <cerrno>
#include <cmath>

#include <Eigen/Dense>

#include "loadid/joint_filter.h"

namespace {

using M3 = Eigen::Matrix3d;

bool converged(const M3 &a, const M3 &b) {
    return ((a - b).cwiseAbs().array() <= 1e-12 * b.cwiseAbs().array() + 1e-300).all();
}

}  // namespace

extern "C" int loadid_jf_steady_sigma(const loadid_jf_config_t *cfg, double dt, int smoothed,
                                      double sigma[3]) {
    if (!cfg || !sigma || !(std::isfinite(dt) && dt > 0)) return -EINVAL;
    const double q = cfg->jerk_psd, r = double(cfg->meas_sigma) * double(cfg->meas_sigma);
    if (!(std::isfinite(q) && q > 0 && std::isfinite(r) && r > 0)) return -EINVAL;
    const double h = dt * dt / 2, d2 = dt * dt, d3 = d2 * dt;
    M3 F, Q;
    F << 1, dt, h, 0, 1, dt, 0, 0, 1;
    Q << d3 * d2 / 20, d2 * d2 / 8, d3 / 6, d2 * d2 / 8, d3 / 3, d2 / 2, d3 / 6, d2 / 2, dt;
    Q *= q;
    M3 P = M3::Zero(), Pp = M3::Zero();
    P.diagonal() << r, 1, 100;  // the filter's initial state (joint_filter.cpp)
    for (int it = 0; it < 200000; ++it) {
        Pp = F * P * F.transpose() + Q;
        const Eigen::Vector3d K = Pp.col(0) / (Pp(0, 0) + r);
        M3 A = M3::Identity();
        A.col(0) -= K;
        const M3 next = A * Pp * A.transpose() + r * K * K.transpose();  // Joseph form
        const bool done = converged(next, P);
        P = next;
        if (done) break;
    }
    Pp = F * P * F.transpose() + Q;
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
