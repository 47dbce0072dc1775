// Identified groups and the nearest physically consistent phi
// (loadid/load_model.h).
#include "loadid/load_model.h"

#include <cerrno>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "eigen_types.hpp"
#include "finite.hpp"

using namespace loadid;

namespace {

bool positive_finite(Real v) {
    return std::isfinite(v) && v > 0;
}

Mat3 sym3(const Real v[6]) { // [xx xy xz yy yz zz]
    Mat3 I;
    I << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
    return I;
}

// Principal moment of a uniform sphere of mass m and density rho.
Real sphere_moment(Real m, Real rho) {
    const Real r = std::cbrt(Real(3) * m / (Real(4) * Real(M_PI) * rho));
    return Real(0.4) * m * r * r;
}

// Sigma_C = tr(I_C)/2 E - I_C clipped to the positive semidefinite cone,
// back to I_C = tr(Sigma_C) E - Sigma_C. The floor is a millionth of the
// largest eigenvalue rather than 0, so the model is strictly consistent (a
// thin plate, not a plane) and passes loadid_phi_to_physical's checks.
Mat3 consistent_inertia(const Mat3 &Ic) {
    const Mat3 sigma = Real(0.5) * Ic.trace() * Mat3::Identity() - Ic;
    const Eigen::SelfAdjointEigenSolver<Mat3> es(sigma);
    const Real floor = Real(1e-6) * std::max(es.eigenvalues()(2), Real(0));
    const Vec3 l = es.eigenvalues().cwiseMax(floor);
    const Mat3 s = es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
    return s.trace() * Mat3::Identity() - s;
}

} // namespace

extern "C" void loadid_model_config_default(loadid_model_config_t *cfg) {
    if (!cfg) return;
    cfg->mass_rel_std = Real(0.025);
    cfg->com_std = Real(0.005);
    cfg->inertia_rel_std = Real(0.15);
    cfg->max_gyration = Real(0.5);
    cfg->min_snr = Real(1);
    cfg->fallback_density = Real(2700);
}

extern "C" int loadid_load_model(const loadid_real_t estimate[10], const loadid_real_t std[10],
                                 const loadid_real_t *snr, const loadid_model_config_t *cfg,
                                 loadid_load_model_t *out) {
    if (!estimate || !std || !cfg || !out) return -EINVAL;
    if (!positive_finite(cfg->mass_rel_std) || !positive_finite(cfg->com_std) ||
        !positive_finite(cfg->inertia_rel_std) || !positive_finite(cfg->max_gyration) ||
        !positive_finite(cfg->fallback_density) || !std::isfinite(cfg->min_snr) || cfg->min_snr < 0)
        return -EINVAL;
    if (!all_finite(estimate, LOADID_NPHI)) return LOADID_E_NONFINITE;
    *out = loadid_load_model_t{};
    const Real m = estimate[0];
    if (!(m > 0)) {
        // No positive mass: no body has this phi. The model is no load.
        out->projected = 1;
        for (int g = 0; g < 3; ++g) out->why[g] = LOADID_WHY_NO_MASS;
        loadid_phi_to_physical(out->phi, &out->physical);
        return 0;
    }
    // NaN std (a failed covariance) compares false: not identified.
    const auto within = [](Real s, Real bound) { return s <= bound; };
    // A group that fails: why, and by how much.
    const auto fail = [out](int group, int why, Real over) {
        out->why[group] = why;
        out->over[group] = over;
    };
    const Vec3 c = Vec3(estimate[1], estimate[2], estimate[3]) / m;
    int id = 0;
    if (within(std[0], cfg->mass_rel_std * m))
        id |= LOADID_IDENT_MASS;
    else
        fail(0, LOADID_WHY_STD, std[0] / (cfg->mass_rel_std * m));
    if (id & LOADID_IDENT_MASS) {
        Real worst = 0;
        for (int i = 0; i < 3; ++i) {
            const Real sc = std::sqrt(std[1 + i] * std[1 + i] + c(i) * c(i) * std[0] * std[0]) / m;
            worst = std::isnan(sc) ? sc : std::max(worst, sc);
        }
        if (within(worst, cfg->com_std))
            id |= LOADID_IDENT_COM;
        else
            fail(1, LOADID_WHY_STD, worst / cfg->com_std);
    } else {
        fail(1, LOADID_WHY_NEEDS, 0);
    }

    const Mat3 Is = sym3(estimate + 4);
    const Mat3 pa = c.squaredNorm() * Mat3::Identity() - c * c.transpose();
    const Mat3 Ic_est = Is - m * pa; // parallel-axis theorem
    const Mat3 Ic_cons = consistent_inertia(Ic_est);
    if (id & LOADID_IDENT_COM) {
        Real smax = 0;
        for (int i = 4; i < LOADID_NPHI; ++i)
            smax = std::isnan(std[i]) ? std[i] : std::max(smax, std[i]);
        const Real scale =
            std::max(Ic_cons.trace() / Real(3), sphere_moment(m, cfg->fallback_density));
        const Real gyration = std::sqrt(std::max(Ic_cons.trace(), Real(0)) / (Real(2) * m));
        if (!within(smax, cfg->inertia_rel_std * scale))
            fail(2, LOADID_WHY_STD, smax / (cfg->inertia_rel_std * scale));
        else if (!(gyration <= cfg->max_gyration))
            fail(2, LOADID_WHY_GYRATION, gyration / cfg->max_gyration);
        else if (snr && !(snr[2] >= cfg->min_snr))
            fail(2, LOADID_WHY_SNR, cfg->min_snr / snr[2]);
        else
            id |= LOADID_IDENT_INERTIA;
    } else {
        fail(2, LOADID_WHY_NEEDS, 0);
    }
    out->identified = id;

    const Mat3 Ic = (id & LOADID_IDENT_INERTIA)
                        ? Ic_cons
                        : Mat3(sphere_moment(m, cfg->fallback_density) * Mat3::Identity());
    const Mat3 Im = Ic + m * pa;
    const Real v[6] = {Im(0, 0), Im(0, 1), Im(0, 2), Im(1, 1), Im(1, 2), Im(2, 2)};
    for (int i = 0; i < 4; ++i) out->phi[i] = estimate[i];
    for (int i = 0; i < 6; ++i) out->phi[4 + i] = v[i];
    // Projected: the inertia moved by more than rounding of its scale.
    const Real tol = (sizeof(Real) == sizeof(float) ? Real(1e-5) : Real(1e-10)) *
                     std::max(Is.cwiseAbs().maxCoeff(), Im.cwiseAbs().maxCoeff());
    for (int i = 4; i < LOADID_NPHI; ++i)
        if (std::abs(out->phi[i] - estimate[i]) > tol) out->projected = 1;
    // Not projected: the estimate itself, to the bit.
    if (!out->projected)
        for (int i = 4; i < LOADID_NPHI; ++i) out->phi[i] = estimate[i];
    loadid_phi_to_physical(out->phi, &out->physical);
    return 0;
}

extern "C" const char *loadid_ident_name(int bit) {
    switch (bit) {
        case LOADID_IDENT_MASS:
            return "mass";
        case LOADID_IDENT_COM:
            return "com";
        case LOADID_IDENT_INERTIA:
            return "inertia";
        default:
            return "?";
    }
}
