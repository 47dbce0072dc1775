// The abstract estimator behind the opaque C handle loadid_est_t. Each
// method is a class template on the parameter count N (10 or 16), so every
// matrix is fixed-size; create() is the only allocation.
#pragma once

#include "eigen_types.hpp"
#include "loadid/estimator.h"

struct loadid_est {
    explicit loadid_est(const loadid_est_config_t &config) : cfg(config) {}
    virtual ~loadid_est() = default;
    loadid_est(const loadid_est &) = delete;
    loadid_est &operator=(const loadid_est &) = delete;

    virtual void reset() = 0;
    // cfg's row_sigma and col_weight changed: derive the weights again and
    // reset (loadid_est_set_weights).
    virtual void reweight() = 0;
    // Inputs are checked (non-NULL, finite) by the C API before this call;
    // an implementation returns 0 or LOADID_E_FULL without changing state.
    virtual int update(const loadid_real_t *A, const loadid_real_t *C, const loadid_real_t *y) = 0;
    virtual int estimate(loadid_real_t *phi, loadid_est_info_t *info) const = 0;
    // One standard deviation of each element of phi (this method's estimate)
    // and the a-posteriori noise scale (uncertainty.hpp).
    virtual int uncertainty(const loadid_real_t *phi, loadid_real_t *std, loadid_real_t *scale) const = 0;
    // loadid_est_signal_to_noise (uncertainty.hpp's group_snr).
    virtual int signal_to_noise(const loadid_real_t *phi, loadid_real_t snr[3]) const = 0;
    // loadid_est_weakest_direction (uncertainty.hpp's weakest_direction).
    virtual int weakest(loadid_real_t *dir, loadid_real_t *ratio) const = 0;

    loadid_est_config_t cfg;  // changed only by loadid_est_set_weights
};
