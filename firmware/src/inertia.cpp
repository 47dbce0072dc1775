// phi <-> mass, COM, inertia about the COM; physical consistency; distal
// part subtraction; eq. (37) (loadid/inertia.h).
#include "loadid/inertia.h"

#include <cerrno>
#include <cmath>
#include <limits>

#include "eigen_types.hpp"
#include "finite.hpp"

using namespace loadid;

namespace {

Mat3 sym3(const Real v[6]) { // [xx xy xz yy yz zz]
    Mat3 I;
    I << v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5];
    return I;
}

// c.c E - c c^T: the parallel-axis term per unit mass.
Mat3 parallel_axis(const Vec3 &c) {
    return c.squaredNorm() * Mat3::Identity() - c * c.transpose();
}

} // namespace

extern "C" int loadid_phi_to_physical(const loadid_real_t phi[10], loadid_physical_t *out) {
    if (!phi || !out) return -EINVAL;
    if (!all_finite(phi, LOADID_NPHI)) return LOADID_E_NONFINITE;
    *out = loadid_physical_t{};
    const Real m = phi[0];
    const Vec3 h(phi[1], phi[2], phi[3]); // m c
    const Mat3 Is = sym3(phi + 4);
    const Real rel = sizeof(Real) == sizeof(float) ? Real(1e-5) : Real(1e-9);
    out->mass = m;
    Mat3 Ic = Is;
    if (m > 0) {
        const Vec3 c = h / m;
        for (int i = 0; i < 3; ++i) out->com[i] = c(i);
        Ic = Is - m * parallel_axis(c); // I_C = I_S - m (c.c E - c c^T)
    } else {
        out->violations |= LOADID_PHYS_MASS_NOT_POSITIVE;
    }
    const Real v[6] = {Ic(0, 0), Ic(0, 1), Ic(0, 2), Ic(1, 1), Ic(1, 2), Ic(2, 2)};
    for (int i = 0; i < 6; ++i) out->inertia_com[i] = v[i];

    const Eigen::SelfAdjointEigenSolver<Mat3> es(Ic, Eigen::EigenvaluesOnly);
    const Vec3 p = es.eigenvalues(); // ascending
    for (int i = 0; i < 3; ++i) out->principal[i] = p(i);
    const Real scale = std::max(std::abs(p(2)), std::numeric_limits<Real>::min());
    if (!(p(0) > rel * scale)) out->violations |= LOADID_PHYS_INERTIA_NOT_PD;
    if (p(0) + p(1) < p(2) - rel * scale) out->violations |= LOADID_PHYS_TRIANGLE;

    // Pseudo-inertia J = [Sigma h; h^T m], Sigma = 0.5 tr(I_S) E - I_S, is
    // positive definite exactly when phi belongs to a body with positive
    // density (Wensing, Kim, Slotine 2017). J mixes kg and kg m^2, so its
    // eigenvalues have no common scale; for m > 0, J is positive definite
    // exactly when its Schur complement Sigma - h h^T / m = 0.5 tr(I_C) E - I_C
    // (the second moment of mass about the COM, in kg m^2) is, which is
    // tested against the principal moments' scale.
    if (m > 0) {
        const Mat3 Sc = Real(0.5) * Ic.trace() * Mat3::Identity() - Ic;
        const Eigen::SelfAdjointEigenSolver<Mat3> es2(Sc, Eigen::EigenvaluesOnly);
        if (!(es2.eigenvalues()(0) > rel * scale))
            out->violations |= LOADID_PHYS_PSEUDO_INERTIA_NOT_PD;
    } else {
        out->violations |= LOADID_PHYS_PSEUDO_INERTIA_NOT_PD;
    }
    return 0;
}

extern "C" int loadid_phi_from_physical(loadid_real_t mass, const loadid_real_t com[3],
                                        const loadid_real_t inertia_com[6], loadid_real_t phi[10]) {
    if (!com || !inertia_com || !phi) return -EINVAL;
    const Vec3 c(com[0], com[1], com[2]);
    const Mat3 Is = sym3(inertia_com) + mass * parallel_axis(c);
    phi[0] = mass;
    for (int i = 0; i < 3; ++i) phi[1 + i] = mass * c(i);
    const Real v[6] = {Is(0, 0), Is(0, 1), Is(0, 2), Is(1, 1), Is(1, 2), Is(2, 2)};
    for (int i = 0; i < 6; ++i) phi[4 + i] = v[i];
    return 0;
}

extern "C" int loadid_phi_subtract(const loadid_real_t measured[10], const loadid_real_t distal[10],
                                   loadid_real_t out[10]) {
    if (!measured || !distal || !out) return -EINVAL;
    for (int i = 0; i < LOADID_NPHI; ++i) out[i] = measured[i] - distal[i];
    return 0;
}

extern "C" int loadid_relative_error(const loadid_real_t *est, const loadid_real_t *truth, int n,
                                     loadid_real_t *out) {
    if (!est || !truth || !out || n < 0) return -EINVAL;
    for (int i = 0; i < n; ++i) {
        if (truth[i] != 0)
            out[i] = std::abs((est[i] - truth[i]) / truth[i]) * Real(100);
        else
            out[i] = est[i] == 0 ? Real(0) : std::numeric_limits<Real>::infinity();
    }
    return 0;
}
