// RTLS instantiated for 10 and 16 parameters.
#include <new>

#include "estimator_factory.hpp"
#include "rtls.hpp"

namespace loadid {

template <int N>
loadid_est *make_rtls(const loadid_est_config_t &c) {
    return new (std::nothrow) Rtls<N>(c);
}

template loadid_est *make_rtls<LOADID_NPHI>(const loadid_est_config_t &);
template loadid_est *make_rtls<LOADID_NPHI_OFFSET>(const loadid_est_config_t &);

} // namespace loadid
