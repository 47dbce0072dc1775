// loadid_strerror and the build's scalar (loadid/types.h).
#include <cstring>

#include "loadid/types.h"

extern "C" const char *loadid_strerror(int code) {
    switch (code) {
        case 0:
            return "success";
        case LOADID_E_NONFINITE:
            return "input holds NaN or Inf (rejected, state unchanged)";
        case LOADID_E_NOT_EXCITED:
            return "not excited: the data do not determine every parameter";
        case LOADID_E_NO_SOLUTION:
            return "no TLS solution: last component of the TLS vector is zero";
        case LOADID_E_FULL:
            return "batch estimator full: raise batch_capacity";
        case LOADID_E_STALE:
            return "joint data stale: no joint state close enough to the sample time";
        case LOADID_E_NO_DATA:
            return "no joint state received yet";
        case LOADID_E_TIME_ORDER:
            return "time stamp not after the previous one (rejected)";
        case LOADID_E_MODEL:
            return "robot model is not a usable kinematic chain";
        default:
            break;
    }
    if (code < 0 && code > -1000) return std::strerror(-code);
    return "unknown error";
}

extern "C" int loadid_scalar_is_float(void) {
    return sizeof(loadid_real_t) == sizeof(float) ? 1 : 0;
}
