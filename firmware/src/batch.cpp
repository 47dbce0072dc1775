// Batch LS and TLS instantiated for 10 and 16 parameters.
#include <new>

#include "batch.hpp"
#include "estimator_factory.hpp"

namespace loadid {

template <int N>
loadid_est *make_batch(const loadid_est_config_t &c) {
    auto *b = new (std::nothrow) Batch<N>(c);
    if (b && !b->allocate()) {
        delete b;
        return nullptr;
    }
    return b;
}

template loadid_est *make_batch<LOADID_NPHI>(const loadid_est_config_t &);
template loadid_est *make_batch<LOADID_NPHI_OFFSET>(const loadid_est_config_t &);

} // namespace loadid
