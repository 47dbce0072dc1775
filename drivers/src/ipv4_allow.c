/* An allowlist of IPv4 source addresses (ipv4_allow.h). */
#define _DEFAULT_SOURCE
#include "loadid/ipv4_allow.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>

static uint32_t prefix_mask(unsigned bits) {
    return bits == 0 ? 0 : 0xFFFFFFFFu << (32 - bits);
}

int loadid_ipv4_net_parse(const char *text, loadid_ipv4_net_t *out) {
    char addr[16];
    unsigned bits = 32;
    if (!text || !out) return -EINVAL;
    const char *slash = strchr(text, '/');
    const size_t len = slash ? (size_t)(slash - text) : strlen(text);
    if (len == 0 || len >= sizeof addr) return -EINVAL;
    memcpy(addr, text, len);
    addr[len] = 0;
    if (slash) {
        /* One or two decimal digits, nothing else (no sign, no space). */
        const char *d = slash + 1;
        if (d[0] < '0' || d[0] > '9') return -EINVAL;
        bits = (unsigned)(d[0] - '0');
        if (d[1]) {
            if (d[1] < '0' || d[1] > '9' || d[2]) return -EINVAL;
            bits = bits * 10 + (unsigned)(d[1] - '0');
        }
        if (bits > 32) return -EINVAL;
    }
    struct in_addr in;
    if (inet_pton(AF_INET, addr, &in) != 1) return -EINVAL; /* also refuses trailing text */
    const uint32_t a = ntohl(in.s_addr), mask = prefix_mask(bits);
    out->net = a & mask;
    out->mask = mask;
    return a == out->net ? 0 : -ERANGE;
}

const char *loadid_ipv4_net_format(const loadid_ipv4_net_t *net, char *buf, unsigned size) {
    const uint32_t a = net->net;
    unsigned bits = 0;
    while (bits < 32 && (net->mask & (0x80000000u >> bits))) ++bits;
    if (bits == 32)
        snprintf(buf, size, "%u.%u.%u.%u", a >> 24, (a >> 16) & 255, (a >> 8) & 255, a & 255);
    else
        snprintf(buf, size, "%u.%u.%u.%u/%u", a >> 24, (a >> 16) & 255, (a >> 8) & 255, a & 255,
                 bits);
    return buf;
}

int loadid_ipv4_allow_match(const loadid_ipv4_net_t *nets, int n, uint32_t addr) {
    if (n <= 0) return 1;
    for (int i = 0; i < n; ++i)
        if ((addr & nets[i].mask) == nets[i].net) return 1;
    return 0;
}
