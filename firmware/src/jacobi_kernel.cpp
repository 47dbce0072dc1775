// Which column kernel brand_jacobi runs on (brand_jacobi.hpp), chosen once
// at start-up, and its name for the C API.
#include <cstdlib>
#include <cstring>
#include <type_traits>

#include "brand_jacobi.hpp"
#include "loadid/estimator.h"

namespace loadid {

#ifdef LOADID_JACOBI_AVX2
namespace {
bool choose_avx2() {
    if (!std::is_same<Real, double>::value) return false;
    // For tests and for comparing the two on one machine.
    const char *forced = std::getenv("LOADID_JACOBI_KERNEL");
    if (forced && std::strcmp(forced, "portable") == 0) return false;
    __builtin_cpu_init(); // may run before libgcc's own initialiser
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}
} // namespace

const bool kJacobiAvx2 = choose_avx2();
#endif

} // namespace loadid

extern "C" const char *loadid_jacobi_kernel(void) {
#ifdef LOADID_JACOBI_AVX2
    if (loadid::kJacobiAvx2) return "avx2+fma";
#endif
    return "portable";
}
