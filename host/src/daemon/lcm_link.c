/* The daemon's LCM transport (lcm_link.h). */
#include "lcm_link.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "log.h"
#include "loadid/lcm_wire.h"

static uint8_t rx_buf[65536]; /* one datagram: any UDP datagram fits */

/* Other providers: liblcm's raw subscription. */
static void on_lcm_raw(const lcm_recv_buf_t *rbuf, const char *channel, void *ctx) {
    loadid_lcm_link_t *l = ctx;
    (void)l->on_message(l->ctx, channel, rbuf->data, rbuf->data_size, 0);
}

int loadid_lcm_link_open(loadid_lcm_link_t *l, const loadid_config_t *cfg,
                         const char *const *channels, int num_channels,
                         loadid_lcm_link_fn on_message, void *ctx, char *err, size_t errlen) {
    memset(l, 0, sizeof *l);
    l->rx_fd = -1;
    l->tx.fd = -1;
    l->on_message = on_message;
    l->ctx = ctx;
    /* An empty lcm.url is liblcm's: LCM_DEFAULT_URL, else its default. */
    const char *url = cfg->lcm_url[0] ? cfg->lcm_url : getenv("LCM_DEFAULT_URL");
    loadid_lcm_udpm_url_t udpm;
    const int udpm_rc = loadid_lcm_udpm_parse_url(url, &udpm);
    if (udpm_rc == -EINVAL) {
        snprintf(err, errlen, "cannot open LCM at %s: malformed udpm URL", url);
        return -EINVAL;
    }
    l->udpm = udpm_rc == 0;
    if (l->udpm) {
        char why[512];
        l->rx_fd = loadid_lcm_udpm_open(&udpm, why, sizeof why);
        int rc = l->rx_fd < 0 ? l->rx_fd : loadid_lcm_udpm_open_tx(&udpm, &l->tx, why, sizeof why);
        if (rc != 0) {
            snprintf(err, errlen, "cannot open LCM at %s: %s", url ? url : "", why);
            loadid_lcm_link_close(l);
            return rc < 0 ? rc : -EIO;
        }
        return 0;
    }
    if (cfg->lcm_num_command_sources > 0) {
        /* liblcm's providers do not say who sent a message. */
        snprintf(err, errlen, "lcm.command_sources needs a udpm:// lcm.url, not %s",
                 url ? url : "");
        return -EINVAL;
    }
    if (!(l->lcm = lcm_create(cfg->lcm_url))) {
        snprintf(err, errlen, "cannot open LCM at %s", cfg->lcm_url);
        return -EIO;
    }
    for (int i = 0; i < num_channels; ++i) lcm_subscribe(l->lcm, channels[i], on_lcm_raw, l);
    return 0;
}

int loadid_lcm_link_fd(const loadid_lcm_link_t *l) {
    return l->udpm ? l->rx_fd : lcm_get_fileno(l->lcm);
}

/* udpm://: what else arrives (above all the daemon's own output, which
 * liblcm's receive thread dropped before the loop saw it) is not an input. */
int loadid_lcm_link_drain(loadid_lcm_link_t *l, int max) {
    int handled = 0;
    if (!l->udpm) {
        for (int n = 0; n < max && lcm_handle_timeout(l->lcm, 0) > 0; ++n) handled++;
        return handled;
    }
    for (int n = 0; n < max; ++n) {
        uint32_t source = 0;
        const int len = loadid_lcm_udpm_read_from(l->rx_fd, rx_buf, sizeof rx_buf, &source);
        if (len == 0) break; /* nothing queued */
        const char *channel;
        const uint8_t *data;
        size_t size;
        if (len > 0 && loadid_lcm_udpm_parse(rx_buf, (size_t)len, &channel, &data, &size) == 0)
            handled += l->on_message(l->ctx, channel, data, size, source) != 0;
    }
    return handled;
}

void loadid_lcm_link_publish(loadid_lcm_link_t *l, const char *channel, const uint8_t *buf, int n) {
    if (n <= 0)
        loadidd_log("%s: cannot encode: %s", channel, loadid_lcm_strerror(n));
    else if (l->udpm)
        loadid_lcm_udpm_send(&l->tx, channel, buf, (size_t)n);
    else
        lcm_publish(l->lcm, channel, buf, (unsigned)n);
}

void loadid_lcm_link_close(loadid_lcm_link_t *l) {
    if (l->rx_fd >= 0) close(l->rx_fd);
    l->rx_fd = -1;
    loadid_lcm_udpm_close_tx(&l->tx);
    if (l->lcm) lcm_destroy(l->lcm);
    l->lcm = NULL;
}
