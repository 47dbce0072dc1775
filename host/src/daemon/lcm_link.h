/*
 * The daemon's LCM transport, both ways: on udpm:// (the provider in use)
 * its own two sockets (drivers/lcm_udpm.h), because liblcm 1.3.1's receive
 * thread allocates on the first message of every channel name it sees
 * (the daemon's own output channels among them, mid-session) and its
 * lcm_publish on its first message (a lazily made mutex); other providers
 * (memq://, file://) through liblcm (lcm_subscribe with raw handlers,
 * lcm_handle, lcm_publish), not proven allocation-free. Messages are
 * handed over encoded; lcm_out.c and status.c make them, lcm_inputs.c
 * takes them apart.
 */
#ifndef LOADID_LCM_LINK_H
#define LOADID_LCM_LINK_H

#include <lcm/lcm.h>
#include <stddef.h>
#include <stdint.h>

#include "loadid/config.h"
#include "loadid/lcm_udpm.h"

/* One message received: its channel, its bytes, and the sender's IPv4
 * address (host order; 0 on liblcm's providers, which do not say).
 * Returns 1 when it was an input (a channel the daemon reads). */
typedef int (*loadid_lcm_link_fn)(void *ctx, const char *channel, const uint8_t *data, size_t len,
                                  uint32_t source);

typedef struct {
    int udpm;                /* udpm://: the daemon's own sockets; else liblcm */
    loadid_lcm_udpm_tx_t tx; /* udpm://: sending */
    int rx_fd;               /* udpm://: receiving, or -1 */
    lcm_t *lcm;              /* other providers, else NULL */
    loadid_lcm_link_fn on_message;
    void *ctx;
} loadid_lcm_link_t;

/* Opens lcm.url (empty: liblcm's LCM_DEFAULT_URL, else its default) and,
 * on liblcm, subscribes the channels listed (udpm:// receives every
 * channel and on_message picks). A sender's address is needed for
 * lcm.command_sources, so that is refused on other providers. Returns 0,
 * or -EINVAL / -errno with a one-line reason in err. */
int loadid_lcm_link_open(loadid_lcm_link_t *l, const loadid_config_t *cfg,
                         const char *const *channels, int num_channels,
                         loadid_lcm_link_fn on_message, void *ctx, char *err, size_t errlen);

/* The descriptor that is readable when a message waits. */
int loadid_lcm_link_fd(const loadid_lcm_link_t *l);

/* Handles every message already queued, at most max (datagrams on
 * udpm://), without waiting: the loop reads LCM so before anything else of
 * an epoll round. Returns how many were inputs (on_message's say; on
 * liblcm, which does not say, every one). */
int loadid_lcm_link_drain(loadid_lcm_link_t *l, int max);

/* Sends n encoded bytes (what an encoder returned; n <= 0 is an encoder's
 * failure, a bug: logged). */
void loadid_lcm_link_publish(loadid_lcm_link_t *l, const char *channel, const uint8_t *buf, int n);

void loadid_lcm_link_close(loadid_lcm_link_t *l);

#endif /* LOADID_LCM_LINK_H */
