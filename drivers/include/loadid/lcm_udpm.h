/*
 * Receiving LCM over UDP multicast (the udpm provider's wire protocol)
 * without liblcm's receive side, so that the loop of loadidd allocates
 * nothing: liblcm 1.3.1 receives on a thread of its own and, on the first
 * message of every channel name it sees (the daemon's own estimate_t,
 * wrench_t and status_t come back to it over the multicast loopback, and
 * any stranger's channel on the group counts too), allocates a handler
 * list and matches every subscription's regular expression against the
 * name (glib and PCRE2 allocate); its lcm_publish allocates the mutex of
 * its send path on the first message (a GStaticMutex made lazily). So
 * loadidd speaks the udpm protocol itself, on two sockets of its own: a
 * non-blocking receiving one in its epoll set (datagrams into the caller's
 * buffer, the channel compared by the caller) and a sending one (the
 * header, the channel and the payload gathered by sendmsg).
 *
 * LCM's short message, one datagram (lcm_udpm.c, "LC02"):
 *   uint32 magic 0x4c433032, uint32 sequence number (big-endian),
 *   the channel name and its NUL (at most 63 characters), the payload.
 * Messages longer than LCM's short-message limit (1400 bytes) come as
 * fragments ("LC03"); loadidd's inputs (joint_state_t: at most 276 bytes,
 * command_t: at most 149) never do, so fragments are skipped.
 */
#ifndef LOADID_LCM_UDPM_H
#define LOADID_LCM_UDPM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_LCM_CHANNEL_MAX 63 /* LCM_MAX_CHANNEL_NAME_LENGTH */

typedef struct {
    uint8_t group[4];  /* IPv4 multicast group, network order */
    uint16_t port;     /* UDP port */
    int recv_buf_size; /* [bytes] SO_RCVBUF from ?recv_buf_size=, 0: the default */
    int ttl;           /* IP_MULTICAST_TTL from ?ttl=, 0..255; default 0 (as liblcm):
                             * packets stay on this host */
} loadid_lcm_udpm_url_t;

/* The sending side: the socket, the group, LCM's message counter. */
typedef struct {
    int fd;
    uint8_t group[4];
    uint16_t port;
    uint32_t seqno; /* sequence number of the next message */
} loadid_lcm_udpm_tx_t;

/* LCM's largest short message: channel, NUL and payload [bytes]. */
#define LOADID_LCM_SHORT_MAX 1400

/* Parses "udpm://GROUP:PORT?opt=v&...": an empty url is LCM's default
 * udpm://239.255.76.67:7667; options other than recv_buf_size and ttl are
 * ignored. Returns 0, -EPROTONOSUPPORT (another provider) or -EINVAL
 * (malformed, not a multicast group, ttl out of range). */
int loadid_lcm_udpm_parse_url(const char *url, loadid_lcm_udpm_url_t *out);

/* The pure part: one datagram of n bytes. On an LCM short message returns
 * 0 with *channel (NUL-terminated, inside dgram) and the payload; returns
 * 1 for a fragment of a long message (skipped), -EBADMSG for anything else
 * (wrong magic, no NUL within the channel's 63 characters). */
int loadid_lcm_udpm_parse(const uint8_t *dgram, size_t n, const char **channel,
                          const uint8_t **payload, size_t *len);

/* A non-blocking socket receiving the group (SO_REUSEADDR, as every LCM
 * peer on the port binds it). Returns the fd, or -errno with a reason in
 * err. */
int loadid_lcm_udpm_open(const loadid_lcm_udpm_url_t *url, char *err, size_t errlen);

/* Reads one datagram into buf (cap bytes; 65536 holds any). Returns its
 * length, 0 when none is waiting, or -errno. */
int loadid_lcm_udpm_read(int fd, uint8_t *buf, size_t cap);

/* The same, and the sender's IPv4 address (host byte order) in *source
 * (may be NULL): the address the datagram came from, as the kernel saw it.
 * UDP has no authentication: this says which host (and, on a host, which
 * local address) sent it, not who. */
int loadid_lcm_udpm_read_from(int fd, uint8_t *buf, size_t cap, uint32_t *source);

/* A sending socket for the group (IP_MULTICAST_TTL ttl, IP_MULTICAST_LOOP
 * on, as liblcm's: peers on this host receive). Returns 0, or -errno with
 * a reason in err. */
int loadid_lcm_udpm_open_tx(const loadid_lcm_udpm_url_t *url, loadid_lcm_udpm_tx_t *tx, char *err,
                            size_t errlen);

/* Sends one message as a short LCM message (one datagram: the same bytes
 * as liblcm's lcm_publish, whose sequence numbers also count from 0).
 * Returns 0, -EINVAL (channel empty or longer than 63), -EMSGSIZE (longer
 * than LOADID_LCM_SHORT_MAX: liblcm would fragment it; no loadid type
 * comes near) or -errno of sendmsg. */
int loadid_lcm_udpm_send(loadid_lcm_udpm_tx_t *tx, const char *channel, const uint8_t *data,
                         size_t len);

void loadid_lcm_udpm_close_tx(loadid_lcm_udpm_tx_t *tx);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_LCM_UDPM_H */
