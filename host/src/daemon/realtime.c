/* Real-time setup and systemd notifications (realtime.h). */
#define _GNU_SOURCE
#include "realtime.h"

#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <systemd/sd-daemon.h>

int loadid_realtime_setup(const loadid_config_t *cfg, char *err, size_t errlen) {
    if (cfg->rt_cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(cfg->rt_cpu, &set);
        if (sched_setaffinity(0, sizeof set, &set) != 0) {
            int e = errno;
            snprintf(err, errlen, "realtime.cpu %d: %s", cfg->rt_cpu, strerror(e));
            return -e;
        }
    }
    if (cfg->rt_lock_memory && mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
        int e = errno;
        snprintf(err, errlen, "realtime.lock_memory: mlockall: %s (LimitMEMLOCK?)", strerror(e));
        return -e;
    }
    if (cfg->rt_priority > 0) {
        struct sched_param sp = {.sched_priority = cfg->rt_priority};
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            int e = errno;
            snprintf(err, errlen, "realtime.priority %d: SCHED_FIFO: %s (LimitRTPRIO? root?)",
                     cfg->rt_priority, strerror(e));
            return -e;
        }
    }
    return 0;
}

static uint64_t watchdog_period_us; /* 0: no watchdog */
static int64_t watchdog_next_us;

void loadid_notify_ready(const char *status) {
    uint64_t usec = 0;
    if (sd_watchdog_enabled(0, &usec) > 0) watchdog_period_us = usec;
    sd_notifyf(0, "READY=1\nSTATUS=%s", status);
}

void loadid_notify_watchdog(int64_t now_us) {
    if (!watchdog_period_us || now_us < watchdog_next_us) return;
    sd_notify(0, "WATCHDOG=1");
    watchdog_next_us = now_us + (int64_t)(watchdog_period_us / 2);
}

void loadid_notify_stopping(void) {
    sd_notify(0, "STOPPING=1");
}
