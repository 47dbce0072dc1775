/* Receiving LCM over UDP multicast (lcm_udpm.h). */
#define _DEFAULT_SOURCE /* IN_MULTICAST, strnlen */
#include "loadid/lcm_udpm.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <unistd.h>

#define MAGIC_SHORT 0x4c433032u /* "LC02" */
#define MAGIC_LONG 0x4c433033u  /* "LC03" */

int loadid_lcm_udpm_parse_url(const char *url, loadid_lcm_udpm_url_t *out) {
    static const char prefix[] = "udpm://";
    memset(out, 0, sizeof *out);
    if (!url || !*url) url = "udpm://239.255.76.67:7667";
    if (strncmp(url, prefix, sizeof prefix - 1) != 0)
        return strstr(url, "://") ? -EPROTONOSUPPORT : -EINVAL;
    const char *host = url + sizeof prefix - 1;
    const char *end = host + strcspn(host, ":?");
    char addr[16];
    if (end == host || (size_t)(end - host) >= sizeof addr) return -EINVAL;
    memcpy(addr, host, (size_t)(end - host));
    addr[end - host] = 0;
    struct in_addr in;
    if (inet_pton(AF_INET, addr, &in) != 1 || !IN_MULTICAST(ntohl(in.s_addr))) return -EINVAL;
    memcpy(out->group, &in.s_addr, 4);
    out->port = 7667;
    if (*end == ':') {
        char *e;
        const long port = strtol(end + 1, &e, 10);
        if (e == end + 1 || port < 1 || port > 65535 || (*e && *e != '?')) return -EINVAL;
        out->port = (uint16_t)port;
        end = e;
    }
    if (*end == '?') {
        for (const char *o = end + 1; *o; o += strcspn(o, "&"), o += *o == '&') {
            if (strncmp(o, "recv_buf_size=", 14) == 0) {
                char *e;
                const long v = strtol(o + 14, &e, 10);
                if (e == o + 14 || v < 0 || v > (1L << 30) || (*e && *e != '&')) return -EINVAL;
                out->recv_buf_size = (int)v;
            } else if (strncmp(o, "ttl=", 4) == 0) {
                char *e;
                const long v = strtol(o + 4, &e, 10);
                if (e == o + 4 || v < 0 || v > 255 || (*e && *e != '&')) return -EINVAL;
                out->ttl = (int)v;
            }
        }
    }
    return 0;
}

int loadid_lcm_udpm_parse(const uint8_t *dgram, size_t n, const char **channel,
                          const uint8_t **payload, size_t *len) {
    if (n < 4) return -EBADMSG;
    const uint32_t magic =
        (uint32_t)dgram[0] << 24 | (uint32_t)dgram[1] << 16 | (uint32_t)dgram[2] << 8 | dgram[3];
    if (magic == MAGIC_LONG) return 1;
    if (magic != MAGIC_SHORT || n < 9) return -EBADMSG; /* header and at least a NUL */
    const uint8_t *name = dgram + 8;
    size_t room = n - 8 < LOADID_LCM_CHANNEL_MAX + 1 ? n - 8 : LOADID_LCM_CHANNEL_MAX + 1;
    const uint8_t *nul = memchr(name, 0, room);
    if (!nul) return -EBADMSG;
    *channel = (const char *)name;
    *payload = nul + 1;
    *len = n - (size_t)(nul + 1 - dgram);
    return 0;
}

int loadid_lcm_udpm_open(const loadid_lcm_udpm_url_t *url, char *err, size_t errlen) {
    const char *what = "socket";
    int fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd >= 0) {
        const int one = 1;
        struct sockaddr_in sa;
        memset(&sa, 0, sizeof sa);
        sa.sin_family = AF_INET;
        sa.sin_addr.s_addr = htonl(INADDR_ANY);
        sa.sin_port = htons(url->port);
        struct ip_mreq mreq;
        memcpy(&mreq.imr_multiaddr.s_addr, url->group, 4);
        mreq.imr_interface.s_addr = htonl(INADDR_ANY);
        /* Without recv_buf_size, room for bursts as liblcm's 1 MB ring
         * buffer gave (its thread emptied the socket at once; here the loop
         * does, between events): beyond rmem_max only with CAP_NET_ADMIN,
         * else the default, not an error. */
        const int burst = 1 << 20;
        if (url->recv_buf_size <= 0 &&
            setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &burst, sizeof burst) < 0)
            (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &burst, sizeof burst);
        if ((what = "SO_REUSEADDR", setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one)) <
                0 ||
            (what = "bind", bind(fd, (struct sockaddr *)&sa, sizeof sa)) < 0 ||
            (what = "IP_ADD_MEMBERSHIP (a multicast route?)",
             setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq)) < 0 ||
            (what = "SO_RCVBUF",
             url->recv_buf_size > 0 && setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &url->recv_buf_size,
                                                  sizeof url->recv_buf_size) < 0)) {
            const int e = errno;
            close(fd);
            fd = -1;
            errno = e;
        }
    }
    if (fd < 0) {
        const int e = errno;
        char group[16];
        inet_ntop(AF_INET, url->group, group, sizeof group);
        snprintf(err, errlen, "LCM udpm://%s:%u: %s: %s", group, (unsigned)url->port, what,
                 strerror(e));
        return -e;
    }
    return fd;
}

int loadid_lcm_udpm_read_from(int fd, uint8_t *buf, size_t cap, uint32_t *source) {
    struct sockaddr_in from;
    socklen_t fromlen = sizeof from;
    memset(&from, 0, sizeof from);
    const ssize_t n =
        recvfrom(fd, buf, cap, MSG_DONTWAIT | MSG_TRUNC, (struct sockaddr *)&from, &fromlen);
    if (n < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR ? 0 : -errno;
    if ((size_t)n > cap) return -EMSGSIZE; /* truncated: dropped */
    if (source) *source = from.sin_family == AF_INET ? ntohl(from.sin_addr.s_addr) : 0;
    return (int)n;
}

int loadid_lcm_udpm_read(int fd, uint8_t *buf, size_t cap) {
    return loadid_lcm_udpm_read_from(fd, buf, cap, NULL);
}

int loadid_lcm_udpm_open_tx(const loadid_lcm_udpm_url_t *url, loadid_lcm_udpm_tx_t *tx, char *err,
                            size_t errlen) {
    memset(tx, 0, sizeof *tx);
    memcpy(tx->group, url->group, 4);
    tx->port = url->port;
    const char *what = "socket";
    tx->fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (tx->fd >= 0) {
        const unsigned char ttl = (unsigned char)url->ttl, loop = 1;
        if ((what = "IP_MULTICAST_TTL",
             setsockopt(tx->fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl)) < 0 ||
            (what = "IP_MULTICAST_LOOP",
             setsockopt(tx->fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop)) < 0) {
            const int e = errno;
            close(tx->fd);
            tx->fd = -1;
            errno = e;
        }
    }
    if (tx->fd < 0) {
        const int e = errno;
        snprintf(err, errlen, "LCM: sending socket: %s: %s", what, strerror(e));
        return -e;
    }
    return 0;
}

int loadid_lcm_udpm_send(loadid_lcm_udpm_tx_t *tx, const char *channel, const uint8_t *data,
                         size_t len) {
    const size_t nch = strnlen(channel, LOADID_LCM_CHANNEL_MAX + 1);
    if (nch == 0 || nch > LOADID_LCM_CHANNEL_MAX) return -EINVAL;
    if (nch + 1 + len > LOADID_LCM_SHORT_MAX) return -EMSGSIZE;
    const uint32_t seq = tx->seqno++;
    const uint8_t hdr[8] = {0x4c,
                            0x43,
                            0x30,
                            0x32, /* "LC02" */
                            (uint8_t)(seq >> 24),
                            (uint8_t)(seq >> 16),
                            (uint8_t)(seq >> 8),
                            (uint8_t)seq};
    struct iovec iov[3] = {
        {(void *)hdr, sizeof hdr}, {(void *)channel, nch + 1}, {(void *)data, len}};
    struct sockaddr_in sa;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    memcpy(&sa.sin_addr.s_addr, tx->group, 4);
    sa.sin_port = htons(tx->port);
    struct msghdr msg;
    memset(&msg, 0, sizeof msg);
    msg.msg_name = &sa;
    msg.msg_namelen = sizeof sa;
    msg.msg_iov = iov;
    msg.msg_iovlen = 3;
    return sendmsg(tx->fd, &msg, 0) < 0 ? -errno : 0;
}

void loadid_lcm_udpm_close_tx(loadid_lcm_udpm_tx_t *tx) {
    if (tx->fd >= 0) close(tx->fd);
    tx->fd = -1;
}
