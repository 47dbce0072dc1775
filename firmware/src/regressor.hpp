// Eq. (6) and the zeroing term of eqs. (7)-(8) as Eigen expressions, shared
// by the C API and the estimators' tests of the inner code.
#pragma once

#include "eigen_types.hpp"

namespace loadid {

// Eq. (6): [f; tau] = A phi with phi of eq. (5). spec = a - g in S.
inline Regressor<10> regressor(const Vec3 &spec, const Vec3 &w, const Vec3 &al) {
    const Real ax = spec.x(), ay = spec.y(), az = spec.z();
    const Real wx = w.x(), wy = w.y(), wz = w.z();
    const Real bx = al.x(), by = al.y(), bz = al.z();
    Regressor<10> A;
    // Force rows: f = m (a - g) + alpha x (m c) + w x (w x (m c)), eq. (1).
    A.row(0) << ax, -wy * wy - wz * wz, wx * wy - bz, wx * wz + by, 0, 0, 0, 0, 0, 0;
    A.row(1) << ay, wx * wy + bz, -wx * wx - wz * wz, wy * wz - bx, 0, 0, 0, 0, 0, 0;
    A.row(2) << az, wx * wz - by, wy * wz + bx, -wy * wy - wx * wx, 0, 0, 0, 0, 0, 0;
    // Torque rows: tau = I alpha + w x (I w) + (m c) x (a - g), eq. (2).
    A.row(3) << 0, 0, az, -ay, bx, by - wx * wz, bz + wx * wy, -wy * wz, wy * wy - wz * wz, wy * wz;
    A.row(4) << 0, -az, 0, ax, wx * wz, bx + wy * wz, wz * wz - wx * wx, by, bz - wx * wy, -wx * wz;
    A.row(5) << 0, ay, -ax, 0, -wx * wy, wx * wx - wy * wy, bx - wy * wz, wx * wy, by + wx * wz, bz;
    return A;
}

// Eq. (7): the gravitational wrench removed by zeroing at a pose with
// gravity g_init in S. Zeroing subtracts the reading m(-g_init) + o_f,
// (m c) x (-g_init) + o_tau, so the zeroed wrench gains m g_init and
// (m c) x g_init: these columns act on m and m c only (eq. 8).
inline Regressor<10> zeroing_term(const Vec3 &g) {
    Regressor<10> Z = Regressor<10>::Zero();
    Z(0, 0) = g.x();
    Z(1, 0) = g.y();
    Z(2, 0) = g.z();
    Z(3, 2) = g.z();
    Z(3, 3) = -g.y();
    Z(4, 1) = -g.z();
    Z(4, 3) = g.x();
    Z(5, 1) = g.y();
    Z(5, 2) = -g.x();
    return Z;
}

} // namespace loadid
