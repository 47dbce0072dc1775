/*
 * An allowlist of IPv4 source addresses (lcm.command_sources): addresses
 * and CIDR blocks, parsed from text and matched against the sender of a
 * datagram. Pure (no I/O), so that the configuration checks the text and
 * the daemon's loop matches without allocating; unit-tested in
 * tests/unit/test_ipv4_allow.c.
 */
#ifndef LOADID_IPV4_ALLOW_H
#define LOADID_IPV4_ALLOW_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* At most this many entries in one list. */
#define LOADID_IPV4_ALLOW_MAX 16

/* One block: an address matches when (address & mask) == net. Host byte
 * order; a single address has mask 0xFFFFFFFF, "0.0.0.0/0" mask 0. */
typedef struct {
    uint32_t net;
    uint32_t mask;
} loadid_ipv4_net_t;

/* Parses "a.b.c.d" (one address) or "a.b.c.d/n" (n 0..32, decimal) in
 * dotted-quad form as inet_pton(AF_INET) takes it. Returns 0, -EINVAL
 * (not an address, a prefix length outside 0..32, anything trailing) or
 * -ERANGE (a block with bits set after its prefix, such as 10.0.0.5/24:
 * refused rather than guessed, the way ip route and Python's ipaddress
 * refuse it; *out then holds the block the prefix means, for the message). */
int loadid_ipv4_net_parse(const char *text, loadid_ipv4_net_t *out);

/* Writes the block as text ("a.b.c.d" or "a.b.c.d/n") into buf (18 bytes
 * hold any). Returns buf. */
const char *loadid_ipv4_net_format(const loadid_ipv4_net_t *net, char *buf, unsigned size);

/* Whether addr (host byte order) is in one of the n blocks; with n == 0
 * (no list) every address is. Returns 1 (allowed) or 0. */
int loadid_ipv4_allow_match(const loadid_ipv4_net_t *nets, int n, uint32_t addr);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_IPV4_ALLOW_H */
