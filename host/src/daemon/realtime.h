/* Real-time setup of the live service (realtime.priority, lock_memory,
 * cpu) and its systemd notifications (Type=notify, WatchdogSec). */
#ifndef LOADID_REALTIME_H
#define LOADID_REALTIME_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/config.h"

/* Applies SCHED_FIFO, mlockall and CPU affinity as configured. Returns 0,
 * or -errno with a one-line reason in err. */
int loadid_realtime_setup(const loadid_config_t *cfg, char *err, size_t errlen);

/* systemd: READY=1 (with a status line), then WATCHDOG=1 at half the
 * watchdog period while running, and STOPPING=1. Without NOTIFY_SOCKET
 * (not under systemd) these do nothing. */
void loadid_notify_ready(const char *status);
/* Call often (every loop tick); pings the watchdog when due. now_us: a
 * monotonic time. */
void loadid_notify_watchdog(int64_t now_us);
void loadid_notify_stopping(void);

#endif /* LOADID_REALTIME_H */
