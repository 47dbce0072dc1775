/* The daemon's two clocks: the wall clock (CLOCK_REALTIME, the utime of
 * docs/INTERFACE.md, which SocketCAN's time stamps and LCM senders use) and
 * a monotonic one for intervals and pacing. */
#ifndef LOADID_DAEMON_CLOCK_H
#define LOADID_DAEMON_CLOCK_H

#include <stdint.h>
#include <time.h>

/* Wall time [us since the epoch]. */
static inline int64_t loadid_wall_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

/* Monotonic time [us]. */
static inline double loadid_mono_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e6 + ts.tv_nsec * 1e-3;
}

#endif /* LOADID_DAEMON_CLOCK_H */
