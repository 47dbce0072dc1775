// C API of the regressor (loadid/regressor.h).
#include "loadid/regressor.h"

#include <cerrno>
#include <cstring>

#include "finite.hpp"
#include "regressor.hpp"

using namespace loadid;

extern "C" int loadid_regressor(const loadid_real_t spec[3], const loadid_real_t omega[3],
                                const loadid_real_t alpha[3], loadid_real_t A[6 * 10]) {
    if (!spec || !omega || !alpha || !A) return -EINVAL;
    if (!all_finite(spec, 3) || !all_finite(omega, 3) || !all_finite(alpha, 3))
        return LOADID_E_NONFINITE;
    Eigen::Map<Regressor<10>> out(A);
    out = regressor(Vec3(spec[0], spec[1], spec[2]), Vec3(omega[0], omega[1], omega[2]),
                    Vec3(alpha[0], alpha[1], alpha[2]));
    return 0;
}

extern "C" int loadid_regressor_add_zeroing(const loadid_real_t g_init[3],
                                            loadid_real_t A[6 * 10]) {
    if (!g_init || !A) return -EINVAL;
    if (!all_finite(g_init, 3)) return LOADID_E_NONFINITE;
    Eigen::Map<Regressor<10>> out(A);
    out += zeroing_term(Vec3(g_init[0], g_init[1], g_init[2]));
    return 0;
}

extern "C" int loadid_regressor_subtract_zeroing(const loadid_real_t A0[6 * 10],
                                                 loadid_real_t A[6 * 10]) {
    if (!A0 || !A) return -EINVAL;
    if (!all_finite(A0, LOADID_NROWS * LOADID_NPHI)) return LOADID_E_NONFINITE;
    Eigen::Map<Regressor<10>>(A) -= ConstRegressorMap<10>(A0);
    return 0;
}

extern "C" int loadid_regressor_with_offset(const loadid_real_t A[6 * 10],
                                            loadid_real_t A16[6 * 16]) {
    if (!A || !A16) return -EINVAL;
    Eigen::Map<Regressor<16>> out(A16);
    out.leftCols<10>() = ConstRegressorMap<10>(A);
    out.rightCols<6>().setIdentity(); // [A E6]: y = A phi + o
    return 0;
}

extern "C" int loadid_regressor_model(const loadid_real_t spec[3], const loadid_real_t omega[3],
                                      const loadid_real_t alpha[3], int n_params,
                                      const loadid_real_t g_init[3], loadid_real_t *A) {
    if (!A || (n_params != LOADID_NPHI && n_params != LOADID_NPHI_OFFSET)) return -EINVAL;
    loadid_real_t A10[LOADID_NROWS * LOADID_NPHI];
    int rc = loadid_regressor(spec, omega, alpha, A10);
    if (rc == 0 && n_params == LOADID_NPHI && g_init)
        rc = loadid_regressor_add_zeroing(g_init, A10);
    if (rc != 0) return rc;
    if (n_params == LOADID_NPHI_OFFSET) return loadid_regressor_with_offset(A10, A);
    std::memcpy(A, A10, sizeof A10);
    return 0;
}

extern "C" int loadid_regressor_model_zeroed(const loadid_real_t spec[3],
                                             const loadid_real_t omega[3],
                                             const loadid_real_t alpha[3], int n_params,
                                             const loadid_real_t zero_a[6 * 10], loadid_real_t *A) {
    if (n_params == LOADID_NPHI_OFFSET)
        return loadid_regressor_model(spec, omega, alpha, n_params, nullptr, A);
    if (!A || !zero_a || n_params != LOADID_NPHI) return -EINVAL;
    loadid_real_t A10[LOADID_NROWS * LOADID_NPHI];
    int rc = loadid_regressor(spec, omega, alpha, A10);
    if (rc == 0) rc = loadid_regressor_subtract_zeroing(zero_a, A10);
    if (rc == 0) std::memcpy(A, A10, sizeof A10);
    return rc;
}

extern "C" int loadid_regressor_apply(const loadid_real_t *A, int n_params,
                                      const loadid_real_t *phi, loadid_real_t y[6]) {
    if (!A || !phi || !y) return -EINVAL;
    Eigen::Map<Vec6> out(y);
    if (n_params == LOADID_NPHI)
        out = ConstRegressorMap<10>(A) * Eigen::Map<const Vec<10>>(phi);
    else if (n_params == LOADID_NPHI_OFFSET)
        out = ConstRegressorMap<16>(A) * Eigen::Map<const Vec<16>>(phi);
    else
        return -EINVAL;
    return 0;
}
