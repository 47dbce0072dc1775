/* SocketCAN input (socketcan.h). */
#define _DEFAULT_SOURCE
#include "loadid/socketcan.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

/* A CAN_RAW socket (flags: SOCK_NONBLOCK or 0) bound to ifname after
 * configure(fd, ctx) set its options. Returns the fd or -errno with a
 * reason in err. */
static int open_bound(const char *ifname, int flags,
                      int (*configure)(int fd, const void *ctx, const char **what), const void *ctx,
                      char *err, size_t errlen) {
    if (!ifname || strlen(ifname) >= IFNAMSIZ) {
        snprintf(err, errlen, "invalid CAN interface name");
        return -EINVAL;
    }
    int fd = socket(PF_CAN, SOCK_RAW | flags | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        int e = errno;
        /* EAFNOSUPPORT (or EPROTONOSUPPORT): the kernel has SocketCAN as
         * modules (can, can-raw, vcan) not loaded yet, or has none at all. */
        snprintf(err, errlen, "%s: no CAN socket: %s%s", ifname, strerror(e),
                 e == EAFNOSUPPORT || e == EPROTONOSUPPORT
                     ? " (no SocketCAN in the running kernel: load it with 'modprobe can_raw', "
                       "and 'modprobe vcan' for a virtual bus)"
                     : "");
        return -e;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    memcpy(ifr.ifr_name, ifname, strlen(ifname));
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    const char *what = NULL;
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0)
        what = "no such interface";
    else if (configure(fd, ctx, &what) < 0)
        (void)0;
    else if ((addr.can_ifindex = ifr.ifr_ifindex),
             bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0)
        what = "bind";
    if (what) {
        int e = errno;
        if (e == ENODEV && !strcmp(what, "no such interface"))
            snprintf(err, errlen,
                     "%s: %s: %s (a virtual bus: 'ip link add dev %s type vcan && "
                     "ip link set up dev %s'; a real one: 'ip link set up dev %s "
                     "type can bitrate <bit/s>')",
                     ifname, what, strerror(e), ifname, ifname, ifname);
        else
            snprintf(err, errlen, "%s: %s: %s", ifname, what, strerror(e));
        close(fd);
        return -e;
    }
    return fd;
}

/* Receiving: the JR3's five identifiers only (standard data frames), error
 * frames, the kernel's receive time stamps and its drop count. */
static int configure_rx(int fd, const void *ctx, const char **what) {
    const uint32_t base_id = *(const uint32_t *)ctx;
    struct can_filter filter[5];
    for (int i = 0; i < 5; ++i) {
        filter[i].can_id = base_id + (uint32_t)i;
        filter[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
    }
    const can_err_mask_t err_mask = CAN_ERR_MASK;
    const int one = 1;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filter, sizeof filter) < 0)
        *what = "filter";
    else if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) < 0)
        *what = "error filter";
    else if (setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one) < 0)
        *what = "time stamps";
    else if (setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) < 0)
        *what = "drop count";
    if (*what) return -1;
    /* Room for bursts: a loop held up reads them late instead of the kernel
     * dropping them. The kernel doubles the 1 MiB asked and charges each
     * frame its sk_buff's 768 bytes: 2731 frames, 0.68 s of the JR3's 4 kHz
     * frames (measured by the vcan VM test). Beyond rmem_max only with
     * CAP_NET_ADMIN; the default otherwise, not an error. What overflows is
     * counted (SO_RXQ_OVFL). */
    const int bytes = 1 << 20;
    if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof bytes) < 0)
        (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
    return 0;
}

/* Sending: receive nothing. */
static int configure_tx(int fd, const void *ctx, const char **what) {
    (void)ctx;
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, NULL, 0) < 0) *what = "filter";
    return *what ? -1 : 0;
}

int loadid_socketcan_open(const char *ifname, uint32_t base_id, char *err, size_t errlen) {
    if (base_id > 0x7FB) {
        snprintf(err, errlen, "invalid CAN base id 0x%X", (unsigned)base_id);
        return -EINVAL;
    }
    return open_bound(ifname, SOCK_NONBLOCK, configure_rx, &base_id, err, errlen);
}

int loadid_socketcan_read(int fd, loadid_can_frame_t *frame, uint32_t *drops) {
    struct can_frame cf;
    /* Aligned for the cmsghdr: the time stamp and the drop count. */
    union {
        char buf[CMSG_SPACE(sizeof(struct timeval)) + CMSG_SPACE(sizeof(uint32_t))];
        struct cmsghdr align;
    } control;
    struct iovec iov = {.iov_base = &cf, .iov_len = sizeof cf};
    struct msghdr msg = {.msg_iov = &iov,
                         .msg_iovlen = 1,
                         .msg_control = control.buf,
                         .msg_controllen = sizeof control.buf};
    ssize_t n = recvmsg(fd, &msg, 0);
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR ? 0 : -errno;
    if ((size_t)n < sizeof cf) return -EIO;
    memset(frame, 0, sizeof *frame);
    frame->t_us = -1;
    for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
            struct timeval tv;
            memcpy(&tv, CMSG_DATA(c), sizeof tv);
            frame->t_us = (int64_t)tv.tv_sec * 1000000 + tv.tv_usec;
        } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL && drops) {
            memcpy(drops, CMSG_DATA(c), sizeof *drops);
        }
    }
    if (frame->t_us < 0) { /* no kernel stamp: the time of reading */
        struct timeval tv;
        gettimeofday(&tv, NULL);
        frame->t_us = (int64_t)tv.tv_sec * 1000000 + tv.tv_usec;
    }
    frame->extended = (cf.can_id & CAN_EFF_FLAG) != 0;
    frame->id = cf.can_id & (frame->extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    frame->dlc = cf.can_dlc;
    memcpy(frame->data, cf.data, sizeof frame->data);
    return (cf.can_id & CAN_ERR_FLAG) ? 2 : 1;
}

int loadid_socketcan_open_tx(const char *ifname, char *err, size_t errlen) {
    return open_bound(ifname, 0, configure_tx, NULL, err, errlen);
}

int loadid_socketcan_write(int fd, const loadid_can_frame_t *frame) {
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = frame->id | (frame->extended ? CAN_EFF_FLAG : 0);
    cf.can_dlc = frame->dlc > 8 ? 8 : frame->dlc;
    memcpy(cf.data, frame->data, cf.can_dlc);
    ssize_t n = write(fd, &cf, sizeof cf);
    if (n == (ssize_t)sizeof cf) return 0;
    return n < 0 ? -errno : -EIO;
}
