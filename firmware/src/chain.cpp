// loadid_chain_check (loadid/chain.h): is a chain description usable?
#include "loadid/chain.h"

#include <cerrno>
#include <cmath>
#include <cstring>

#include "enum_value.hpp"

namespace {

constexpr double kTol = 1e-9;

bool finite(const double *v, int n) {
    for (int i = 0; i < n; ++i)
        if (!std::isfinite(v[i])) return false;
    return true;
}

// Orthonormal within kTol and det +1: a rotation, not a reflection.
bool proper_rotation(const double r[9]) {
    if (!finite(r, 9)) return false;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            double dot = 0; // (R^T R)_ij: column i . column j
            for (int k = 0; k < 3; ++k) dot += r[3 * k + i] * r[3 * k + j];
            if (std::fabs(dot - (i == j ? 1.0 : 0.0)) > kTol) return false;
        }
    }
    double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                 r[2] * (r[3] * r[7] - r[4] * r[6]);
    return std::fabs(det - 1.0) <= kTol;
}

bool named(const char *name) {
    return std::memchr(name, '\0', LOADID_NAME_MAX) != nullptr;
}

bool valid_joint(const loadid_joint_desc_t &j) {
    if (!named(j.name)) return false;
    const int type = loadid::enum_value(j.type);
    if (type != LOADID_JOINT_REVOLUTE && type != LOADID_JOINT_PRISMATIC) return false;
    if (!finite(j.origin_xyz, 3) || !proper_rotation(j.origin_rot) || !finite(j.axis, 3))
        return false;
    double n2 = j.axis[0] * j.axis[0] + j.axis[1] * j.axis[1] + j.axis[2] * j.axis[2];
    if (std::fabs(std::sqrt(n2) - 1.0) > kTol) return false;
    if (std::isnan(j.lower) || std::isnan(j.upper) || !(j.lower <= j.upper)) return false;
    return j.velocity > 0; // +inf when the URDF gives none; NaN fails
}

} // namespace

extern "C" int loadid_chain_check(const loadid_chain_t *chain) {
    if (!chain) return -EINVAL;
    if (chain->num_joints < 1 || chain->num_joints > LOADID_MAX_JOINTS) return -EINVAL;
    if (!named(chain->base_link) || !named(chain->sensor_link)) return -EINVAL;
    for (int i = 0; i < chain->num_joints; ++i)
        if (!valid_joint(chain->joints[i])) return -EINVAL;
    if (!finite(chain->tip_xyz, 3) || !proper_rotation(chain->tip_rot)) return -EINVAL;
    return 0;
}
