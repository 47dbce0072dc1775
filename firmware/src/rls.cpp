// RLS and RIV instantiated for 10 and 16 parameters.
#include <new>

#include "estimator_factory.hpp"
#include "rls.hpp"

namespace loadid {

template <int N>
loadid_est *make_recursive_ls(const loadid_est_config_t &c) {
    return new (std::nothrow) RecursiveLs<N>(c);
}

template loadid_est *make_recursive_ls<LOADID_NPHI>(const loadid_est_config_t &);
template loadid_est *make_recursive_ls<LOADID_NPHI_OFFSET>(const loadid_est_config_t &);

} // namespace loadid
