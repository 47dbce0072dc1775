/*
 * loadid: the command line of the service. Sends command_t on
 * LOADID_COMMAND (zero, start, stop, reset) or waits for the daemon's next
 * status_t on LOADID_STATUS and prints it (status), over the LCM URL of the
 * configuration (lcm.url) or --lcm-url.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <getopt.h>
#include <lcm/lcm.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "lcmtypes/loadid_command_t.h"
#include "lcmtypes/loadid_status_t.h"
#include "loadid/config.h"

static const char *prog = "loadid";

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s [--config FILE | --lcm-url URL] zero|start|stop|reset [--load-name NAME]\n"
            "       %s [--config FILE | --lcm-url URL] status [--timeout SECONDS]\n"
            "Commands loadidd over LCM: zero (average the wrench in the still pose), start\n"
            "(estimate for estimation.duration_s), stop, reset; status waits for the next\n"
            "status_t (once a second) and prints it; exit 1 when none comes in time.\n",
            prog, prog);
}

static int64_t now_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static const char *state_name(int s) {
    static const char *names[] = {"IDLE", "ZEROING", "ESTIMATING", "DONE", "FAILED"};
    return s >= 0 && s <= 4 ? names[s] : "?";
}

static int got_status;

static void on_status(const lcm_recv_buf_t *rbuf, const char *channel, const loadid_status_t *m,
                      void *ctx) {
    (void)rbuf, (void)channel, (void)ctx;
    printf("state %s\nsamples_ok %lld\nframes_bad %lld\nsamples_incomplete %lld\n"
           "samples_saturated %lld\nsequence_gaps %lld\njoint_msgs_bad %lld\n"
           "loop_us p50 %.1f p99 %.1f max %.1f\n",
           state_name(m->state), (long long)m->samples_ok, (long long)m->frames_bad,
           (long long)m->samples_incomplete, (long long)m->samples_saturated,
           (long long)m->sequence_gaps, (long long)m->joint_msgs_bad, m->loop_us_p50,
           m->loop_us_p99, m->loop_us_max);
    got_status = 1;
}

int main(int argc, char **argv) {
    const char *config_path = NULL, *url = NULL, *load_name = "";
    double timeout = 3;
    static const struct option opts[] = {
        {"config", required_argument, NULL, 'c'}, {"lcm-url", required_argument, NULL, 'u'},
        {"load-name", required_argument, NULL, 'n'}, {"timeout", required_argument, NULL, 't'},
        {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "c:u:n:t:h", opts, NULL)) != -1) {
        switch (c) {
            case 'c': config_path = optarg; break;
            case 'u': url = optarg; break;
            case 'n': load_name = optarg; break;
            case 't': {
                char *end;
                timeout = strtod(optarg, &end);
                if (*end || end == optarg || !(timeout > 0)) {
                    fprintf(stderr, "%s: --timeout: seconds > 0, not %s\n", prog, optarg);
                    return 2;
                }
                break;
            }
            case 'h': usage(stdout); return 0;
            default: usage(stderr); return 2;
        }
    }
    if (optind + 1 != argc) {
        usage(stderr);
        return 2;
    }
    const char *verb = argv[optind];
    static const char *const verbs[] = {NULL, "zero", "start", "stop", "reset"};
    int action = 0;
    for (int i = 1; i <= 4; ++i)
        if (strcmp(verb, verbs[i]) == 0) action = i;
    if (!action && strcmp(verb, "status") != 0) {
        fprintf(stderr, "%s: unknown command '%s' (zero, start, stop, reset, status)\n", prog, verb);
        return 2;
    }
    static loadid_config_t cfg;
    loadid_config_default(&cfg);
    char err[1024];
    if (config_path && loadid_config_load(config_path, &cfg, err, sizeof err, NULL, NULL) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    lcm_t *lcm = lcm_create(url ? url : cfg.lcm_url);
    if (!lcm) {
        fprintf(stderr, "%s: cannot open LCM at %s\n", prog, url ? url : cfg.lcm_url);
        return 1;
    }
    char command[128], status[128];
    loadid_config_channel(&cfg, "LOADID_COMMAND", command, sizeof command);
    loadid_config_channel(&cfg, "LOADID_STATUS", status, sizeof status);
    int rc = 0;
    if (action) {
        loadid_command_t m = {.utime = now_us(), .action = (int8_t)action,
                              .load_name = (char *)load_name};
        if (loadid_command_t_publish(lcm, command, &m) != 0) {
            fprintf(stderr, "%s: cannot publish on %s\n", prog, command);
            rc = 1;
        }
    } else {
        loadid_status_t_subscribe(lcm, status, on_status, NULL);
        const int64_t end = now_us() + (int64_t)(timeout * 1e6);
        while (!got_status && now_us() < end) {
            struct pollfd pfd = {.fd = lcm_get_fileno(lcm), .events = POLLIN};
            if (poll(&pfd, 1, 100) > 0) lcm_handle(lcm);
        }
        if (!got_status) {
            fprintf(stderr, "%s: no status_t on %s within %.3g s: is loadidd running?\n", prog,
                    status, timeout);
            rc = 1;
        }
    }
    lcm_destroy(lcm);
    return rc;
}
