// Forward kinematics of the sensor frame S (loadid/kinematics.h): the
// forward recursion of Newton-Euler (Luh, Walker, Paul 1980; Craig,
// "Introduction to Robotics", eqs. 6.45-6.47 for revolute and 6.48-6.50 for
// prismatic joints), in URDF's frame convention, each quantity kept in the
// coordinates of the current frame so that the last one is already in S.
#include "loadid/kinematics.h"

#include <cerrno>
#include <cmath>
#include <new>

#include "eigen_types.hpp"
#include "finite.hpp"

using namespace loadid;

namespace {

// A fixed transform: x_parent = rot * x_child + xyz. Most of a URDF's are
// a translation alone, or nothing (all of the RX60's): apply_fixed skips
// the rotation by the identity and the move by 0, which change no value
// but the sign of a zero (x * 1 and x + 0 are exact; products and sums
// are all there is, so no other value can differ either).
struct Fixed {
    Mat3 rot;
    Vec3 xyz;
    bool rotates; // rot is not the identity
    bool moves;   // xyz is not 0
};

struct Joint {
    Fixed origin;
    Vec3 axis;
    bool revolute;
};

Fixed fixed_from(const double xyz[3], const double rot[9]) {
    Fixed f;
    for (int r = 0; r < 3; ++r) {
        f.xyz(r) = Real(xyz[r]);
        for (int c = 0; c < 3; ++c) f.rot(r, c) = Real(rot[3 * r + c]);
    }
    f.rotates = f.rot != Mat3::Identity();
    f.moves = f.xyz != Vec3::Zero();
    return f;
}

// The moving frame of the recursion; vectors in its own coordinates.
struct Frame {
    Mat3 rot;   // frame -> base
    Vec3 pos;   // origin in base
    Vec3 omega; // angular velocity
    Vec3 alpha; // angular acceleration
    Vec3 accel; // classical linear acceleration of the origin
};

// Moves to a child frame rigidly attached at xyz (rot: child -> this).
void apply_fixed(Frame &f, const Fixed &t) {
    if (!t.rotates) {
        if (t.moves) {
            const Vec3 a = f.accel + f.alpha.cross(t.xyz) + f.omega.cross(f.omega.cross(t.xyz));
            f.accel = a;
            f.pos += f.rot * t.xyz;
        }
        return;
    }
    Vec3 a = f.accel + f.alpha.cross(t.xyz) + f.omega.cross(f.omega.cross(t.xyz));
    f.pos += f.rot * t.xyz;
    f.rot = f.rot * t.rot;
    f.accel.noalias() = t.rot.transpose() * a;
    f.omega = t.rot.transpose() * f.omega;
    f.alpha = t.rot.transpose() * f.alpha;
}

// Rodrigues: rotation by angle q about the unit axis k.
Mat3 axis_angle(const Vec3 &k, Real q) {
    Real c = std::cos(q), s = std::sin(q);
    Mat3 kx;
    kx << 0, -k(2), k(1), k(2), 0, -k(0), -k(1), k(0), 0;
    return Mat3::Identity() * c + kx * s + (1 - c) * k * k.transpose();
}

// The joint's own motion, in the joint frame (after its fixed origin).
void apply_revolute(Frame &f, const Vec3 &k, Real q, Real qd, Real qdd) {
    Mat3 m = axis_angle(k, q); // moved frame -> joint frame
    Vec3 w = f.omega + k * qd;
    Vec3 dw = f.alpha + k * qdd + f.omega.cross(k * qd);
    f.rot = f.rot * m;
    f.omega.noalias() = m.transpose() * w;
    f.alpha.noalias() = m.transpose() * dw;
    f.accel = m.transpose() * f.accel; // the origin does not move
}

void apply_prismatic(Frame &f, const Vec3 &k, Real q, Real qd, Real qdd) {
    Vec3 d = k * q;
    f.accel += f.alpha.cross(d) + f.omega.cross(f.omega.cross(d)) +
               Real(2) * f.omega.cross(k * qd) + k * qdd;
    f.pos += f.rot * d;
}

void store(const Vec3 &v, loadid_real_t out[3]) {
    for (int i = 0; i < 3; ++i) out[i] = v(i);
}

} // namespace

struct loadid_kin {
    int n;
    Joint joints[LOADID_MAX_JOINTS];
    Fixed tip;
    Vec3 gravity; // in the base frame
};

extern "C" int loadid_kin_create(const loadid_chain_t *chain, const double gravity[3],
                                 loadid_kin_t **out) {
    if (!chain || !gravity || !out) return -EINVAL;
    if (loadid_chain_check(chain) != 0) return -EINVAL;
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(gravity[i])) return -EINVAL;
    auto *kin = new (std::nothrow) loadid_kin;
    if (!kin) return -ENOMEM;
    kin->n = chain->num_joints;
    for (int i = 0; i < kin->n; ++i) {
        const loadid_joint_desc_t &d = chain->joints[i];
        kin->joints[i].origin = fixed_from(d.origin_xyz, d.origin_rot);
        for (int r = 0; r < 3; ++r) kin->joints[i].axis(r) = Real(d.axis[r]);
        kin->joints[i].revolute = d.type == LOADID_JOINT_REVOLUTE;
    }
    kin->tip = fixed_from(chain->tip_xyz, chain->tip_rot);
    for (int r = 0; r < 3; ++r) kin->gravity(r) = Real(gravity[r]);
    *out = kin;
    return 0;
}

extern "C" void loadid_kin_destroy(loadid_kin_t *kin) {
    delete kin;
}

extern "C" int loadid_kin_num_joints(const loadid_kin_t *kin) {
    return kin ? kin->n : -EINVAL;
}

extern "C" int loadid_kin_eval(const loadid_kin_t *kin, const loadid_real_t *q,
                               const loadid_real_t *qd, const loadid_real_t *qdd,
                               loadid_kin_state_t *out) {
    if (!kin || !q || !out) return -EINVAL;
    const int n = kin->n;
    if (!all_finite(q, n) || (qd && !all_finite(qd, n)) || (qdd && !all_finite(qdd, n)))
        return LOADID_E_NONFINITE;
    // The base is fixed: it neither moves nor accelerates; gravity enters
    // at the end as a - g (the paper's regressor needs only the difference).
    Frame f{Mat3::Identity(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    for (int i = 0; i < n; ++i) {
        const Joint &j = kin->joints[i];
        Real v = qd ? qd[i] : Real(0), a = qdd ? qdd[i] : Real(0);
        apply_fixed(f, j.origin);
        if (j.revolute)
            apply_revolute(f, j.axis, q[i], v, a);
        else
            apply_prismatic(f, j.axis, q[i], v, a);
    }
    apply_fixed(f, kin->tip);
    Vec3 g = f.rot.transpose() * kin->gravity;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) out->rotation[3 * r + c] = f.rot(r, c);
    store(f.pos, out->position);
    store(f.omega, out->omega);
    store(f.alpha, out->alpha);
    store(f.accel, out->accel);
    store(g, out->gravity);
    store(f.accel - g, out->spec);
    return 0;
}
