/*
 * estimate_watch: prints every estimate_t on LOADID_ESTIMATE whose state is
 * DONE or FAILED (the final estimates), one line each, until SIGTERM or
 * SIGINT. The vcan VM test runs it beside loadidd to read how many samples
 * reached each estimator and what each estimated (phi to the last bit, for
 * the comparison with `loadidd --offline`):
 *
 *   LOADID-ESTIMATE method 3 state 3 samples 61 phi 0.998 -0.0434 ... (10)
 *
 * usage: estimate_watch [LCM_URL]
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <lcm/lcm.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "lcmtypes/loadid_estimate_t.h"

static volatile sig_atomic_t stop;

static void usage(FILE *out) {
    fprintf(out,
            "usage: estimate_watch [LCM_URL]\n"
            "Prints every final estimate_t (DONE or FAILED) on LOADID_ESTIMATE as\n"
            "'LOADID-ESTIMATE method M state S samples N phi P0 ... P9' until SIGTERM or\n"
            "SIGINT; LCM_URL "
            "defaults to udpm://239.255.76.67:7667?ttl=0.\n");
}

static void on_signal(int sig) {
    (void)sig;
    stop = 1;
}

static void on_estimate(const lcm_recv_buf_t *rbuf, const char *channel, const loadid_estimate_t *m,
                        void *ctx) {
    (void)rbuf, (void)channel, (void)ctx;
    if (m->state != LOADID_ESTIMATE_T_DONE && m->state != LOADID_ESTIMATE_T_FAILED) return;
    printf("LOADID-ESTIMATE method %d state %d samples %lld phi", m->method, m->state,
           (long long)m->samples);
    for (int i = 0; i < 10; ++i) printf(" %.17g", m->phi[i]);
    printf("\n");
    fflush(stdout);
}

int main(int argc, char **argv) {
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        usage(stdout);
        return 0;
    }
    if (argc > 2 || (argc == 2 && argv[1][0] == '-')) {
        usage(stderr);
        return 2;
    }
    const char *url = argc > 1 ? argv[1] : "udpm://239.255.76.67:7667?ttl=0";
    lcm_t *lcm = lcm_create(url);
    if (!lcm) {
        fprintf(stderr, "estimate_watch: cannot open LCM at %s\n", url);
        return 1;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    loadid_estimate_t_subscribe(lcm, "LOADID_ESTIMATE", on_estimate, NULL);
    while (!stop) {
        struct pollfd pfd = {.fd = lcm_get_fileno(lcm), .events = POLLIN};
        const int n = poll(&pfd, 1, 100);
        if (n > 0)
            lcm_handle(lcm);
        else if (n < 0 && errno != EINTR)
            break;
    }
    lcm_destroy(lcm);
    return 0;
}
