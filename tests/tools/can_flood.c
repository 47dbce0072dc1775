/*
 * can_flood: other devices' traffic on the JR3's bus, for the vcan VM
 * test: classic 8-byte frames that the daemon's kernel filter must keep
 * away (drivers/socketcan.h: standard data frames base..base+4 only), at a
 * fixed rate on absolute 1 ms deadlines (late ticks catch up, so the
 * average holds), for a given time. The frames cycle through every
 * standard identifier but the JR3's five, with every 8th an extended frame
 * of a JR3 identifier's number and every 8th (offset by 4) a remote frame
 * of one. Prints one line:
 *
 *   LOADID-FLOOD sent N frames in T s (R frames/s), refused K, extended E, remote Q
 *
 * refused: writes the interface refused (ENOBUFS: its queue full), not
 * retried; a vcan interface has no queue.
 *
 * usage: can_flood IF RATE SECONDS [BASE_ID]
 */
#define _GNU_SOURCE

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <math.h>
#include <net/if.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static void usage(FILE *out) {
    fprintf(out,
            "usage: can_flood IF RATE SECONDS [BASE_ID]\n"
            "Sends classic 8-byte CAN frames that a JR3 reader's kernel filter keeps away\n"
            "(standard identifiers other than BASE_ID..BASE_ID+4, default 0x1A0, and\n"
            "extended and remote frames of those) onto IF at RATE frames/s for SECONDS,\n"
            "and prints 'LOADID-FLOOD sent N frames in T s (R frames/s), refused K, ...'.\n");
}

static double mono_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(int argc, char **argv) {
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        usage(stdout);
        return 0;
    }
    if (argc < 4 || argc > 5) {
        usage(stderr);
        return 2;
    }
    char *end;
    const double rate = strtod(argv[2], &end);
    const int rate_ok = !*end && rate > 0 && rate <= 1e6;
    const double seconds = strtod(argv[3], &end);
    const int seconds_ok = !*end && seconds > 0 && seconds <= 3600;
    const unsigned long base = argc == 5 ? strtoul(argv[4], &end, 0) : 0x1A0;
    if (!rate_ok || !seconds_ok || (argc == 5 && *end) || base > 0x7FB ||
        strlen(argv[1]) >= IFNAMSIZ) {
        usage(stderr);
        return 2;
    }
    const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    memcpy(ifr.ifr_name, argv[1], strlen(argv[1]));
    struct sockaddr_can addr = {.can_family = AF_CAN};
    if (fd < 0 || ioctl(fd, SIOCGIFINDEX, &ifr) < 0 ||
        (addr.can_ifindex = ifr.ifr_ifindex, bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0) ||
        setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, NULL, 0) < 0) {
        fprintf(stderr, "can_flood: %s: %s\n", argv[1], strerror(errno));
        return 1;
    }
    const int64_t total = (int64_t)llround(rate * seconds);
    int64_t sent = 0, refused = 0, extended = 0, remote = 0;
    uint32_t next_id = 0;
    const double t0 = mono_s();
    double first = -1, last = t0;
    struct timespec tick;
    clock_gettime(CLOCK_MONOTONIC, &tick);
    while (sent + refused < total) {
        /* Every frame due by now (a late tick catches up). */
        const int64_t due = (int64_t)floor((mono_s() - t0) * rate) + 1;
        while (sent + refused < due && sent + refused < total) {
            const int64_t k = sent + refused;
            struct can_frame cf;
            memset(&cf, 0, sizeof cf);
            cf.can_dlc = 8;
            if (k % 8 == 7) { /* extended: the filter's EFF bit keeps it away */
                cf.can_id = (canid_t)(base + (uint64_t)(k / 8) % 5) | CAN_EFF_FLAG;
                extended++;
            } else if (k % 8 == 3) { /* remote: so does its RTR bit */
                cf.can_id = (canid_t)(base + (uint64_t)(k / 8) % 5) | CAN_RTR_FLAG;
                remote++;
            } else {
                if (next_id >= base && next_id <= base + 4) next_id = (uint32_t)base + 5;
                cf.can_id = next_id;
                next_id = (next_id + 1) & CAN_SFF_MASK;
            }
            memcpy(cf.data, &k, sizeof k);
            if (write(fd, &cf, sizeof cf) == (ssize_t)sizeof cf) {
                sent++;
                last = mono_s();
                if (first < 0) first = last;
            } else if (errno == ENOBUFS || errno == EAGAIN) {
                refused++;
            } else {
                fprintf(stderr, "can_flood: %s: write: %s\n", argv[1], strerror(errno));
                return 1;
            }
        }
        tick.tv_nsec += 1000000;
        if (tick.tv_nsec >= 1000000000) tick.tv_sec++, tick.tv_nsec -= 1000000000;
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &tick, NULL);
    }
    /* The rate over the frames' span: N - 1 intervals. */
    const double span = first >= 0 ? last - first : 0;
    printf(
        "LOADID-FLOOD sent %lld frames in %.3f s (%.0f frames/s), refused %lld, extended "
        "%lld, remote %lld\n",
        (long long)sent, span, span > 0 ? (double)(sent - 1) / span : 0.0, (long long)refused,
        (long long)extended, (long long)remote);
    close(fd);
    return 0;
}
