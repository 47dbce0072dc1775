// The abstract estimator behind the opaque C handle loadid_est_t. Each
// method is a class template on the parameter count N (10 or 16), so every
// matrix is fixed-size; create() is the only allocation.
#pragma once

#include "eigen_types.hpp"
#include "loadid/estimator.h"
#include "uncertainty.hpp"

struct loadid_est {
    explicit loadid_est(const loadid_est_config_t &config) : cfg(config) {}
    virtual ~loadid_est() = default;
    loadid_est(const loadid_est &) = delete;
    loadid_est &operator=(const loadid_est &) = delete;

    virtual void reset() = 0;
    // cfg's row_sigma and col_weight changed: derive the weights again and
    // reset (loadid_est_set_weights).
    virtual void reweight() = 0;
    // The force rows' noise level times force, the torque rows' times
    // torque, the regressor columns' weights times columns, for the samples
    // already taken as well (loadid_est_rescale; cfg already updated). 0,
    // -ENOTSUP (the method cannot weigh its past again) or
    // LOADID_E_NOT_EXCITED.
    virtual int rescale(loadid_real_t force, loadid_real_t torque, loadid_real_t columns) = 0;
    // Inputs are checked (non-NULL, finite) by the C API before this call;
    // an implementation returns 0 or LOADID_E_FULL without changing state.
    virtual int update(const loadid_real_t *A, const loadid_real_t *C, const loadid_real_t *y) = 0;
    // ratio_gate false: without the noise-ratio test (the C API's
    // loadid_est_estimate_unique decides when).
    virtual int estimate(loadid_real_t *phi, loadid_est_info_t *info, bool ratio_gate) const = 0;
    // The information matrix the excitation gate keeps, and this method's
    // kind of covariance, for phi (may be NULL): uncertainty.hpp computes
    // phi_std, the groups' signal-to-noise and the weakest direction from
    // it (loadid_est_uncertainty and its neighbours in estimator.cpp).
    virtual loadid::CovInput information(const loadid_real_t *phi) const = 0;

    loadid_est_config_t cfg; // changed only by loadid_est_set_weights
};
