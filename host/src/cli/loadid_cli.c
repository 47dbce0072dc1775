/*
 * loadid: the command line of the service. Sends command_t on
 * LOADID_COMMAND (zero, start, stop, reset) and waits until loadidd's
 * status_t on LOADID_STATUS shows its effect, or waits for the daemon's
 * next status_t and prints it (status), over the LCM URL of the
 * configuration (lcm.url) or --lcm-url.
 *
 * The acknowledgement is status_t itself (its type is fixed): besides once
 * a second, loadidd publishes one at every state change with the time of
 * the change as its utime, which for a change a command made is the
 * command's own utime. So the answer to this command is the status_t with
 * the utime sent, and its effect the state it shows (zero: ZEROING, start:
 * ESTIMATING, stop: DONE, reset: IDLE). No status_t at all within
 * --timeout means no daemon on this URL and channel prefix; status_t but
 * no answer, a daemon that did not act on the command (STOP while idle,
 * START while estimating); both exit 1 with the reason, as does a start
 * that ends in FAILED.
 *
 * `loadid plot PATH` draws how an estimate came about (cli_plot.h); it
 * needs no daemon.
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
#include "lcmtypes/loadid_estimate_t.h" /* the states status_t carries */
#include "lcmtypes/loadid_status_t.h"
#include "cli_plot.h"
#include "loadid/arg_number.h"
#include "loadid/config.h"
#include "loadid/lcm_wire.h" /* the states' names */

static const char *prog = "loadid";

static void warn(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "%s: warning: %s\n", prog, msg);
}

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s [--config FILE | --lcm-url URL] [--timeout SECONDS] zero|start|stop|reset\n"
            "              [--load-name NAME]\n"
            "       %s [--config FILE | --lcm-url URL] [--timeout SECONDS] status\n"
            "       %s plot [--config FILE] [--out DIR] [--publish-every N] RECORDING|TRACE|DIR\n"
            "Commands loadidd over LCM: zero (average the wrench in the still pose), start\n"
            "(estimate for estimation.duration_s), stop, reset. Each waits until loadidd's\n"
            "status_t shows the command's effect (zero: ZEROING, start: ESTIMATING,\n"
            "stop: DONE, reset: IDLE) and prints that state; exit 1 with the reason when\n"
            "no status_t comes within --timeout (default 3 s: no daemon on this lcm.url\n"
            "and lcm.channel_prefix) or none shows the effect (the daemon did not act on\n"
            "it). status waits for the next status_t (once a second) and prints it; exit 1\n"
            "when none comes in time. Exit 2 for a usage error.\n"
            "plot draws PNG figures of how an estimate came about: every method's estimate\n"
            "over the window and the residual wrench (measured minus A(t) phi_hat). A\n"
            "RECORDING (can.log, lcm.log) is estimated first by loadidd --offline --trace\n"
            "with --config FILE (into --out DIR, default RECORDING/plots); a TRACE CSV of\n"
            "loadidd --trace, or a DIR holding some (and loadid-demo's runs.csv), is drawn\n"
            "as it is (into --out DIR, default beside it). It prints the residual's RMS.\n",
            prog, prog, prog);
}

static double mono_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int64_t now_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

/* What the wait has seen. */
typedef struct {
    int action;   /* 0: status (any status_t will do) */
    int64_t sent; /* the command's utime */
    int statuses; /* status_t received */
    int state;    /* the last one's state */
    int done;     /* the wait is over: the expected state, or FAILED */
    loadid_status_t last;
} wait_t;

enum {
    ZERO = LOADID_COMMAND_T_ZERO,
    START = LOADID_COMMAND_T_START,
    STOP = LOADID_COMMAND_T_STOP,
    RESET = LOADID_COMMAND_T_RESET
};
enum {
    IDLE = LOADID_ESTIMATE_T_IDLE,
    ZEROING = LOADID_ESTIMATE_T_ZEROING,
    ESTIMATING = LOADID_ESTIMATE_T_ESTIMATING,
    DONE = LOADID_ESTIMATE_T_DONE,
    FAILED = LOADID_ESTIMATE_T_FAILED
};

/* The state a command's effect shows as. */
static int expected_state(int action) {
    switch (action) {
        case ZERO:
            return ZEROING;
        case START:
            return ESTIMATING;
        case STOP:
            return DONE;
        case RESET:
            return IDLE;
        default:
            return -1;
    }
}

static void on_status(const lcm_recv_buf_t *rbuf, const char *channel, const loadid_status_t *m,
                      void *ctx) {
    (void)rbuf, (void)channel;
    wait_t *w = ctx;
    if (w->done) return;
    w->statuses++;
    w->state = m->state;
    w->last = *m;
    if (!w->action) w->done = 1;
    /* The command's own state change, or its failure (START before a
     * completed ZERO); a change to another state (START while zeroing
     * ends the zeroing first) is followed by more at the same utime. */
    else if (m->utime == w->sent && (m->state == expected_state(w->action) || m->state == FAILED))
        w->done = 1;
    /* START in FAILED is not acted on: no need to wait for the timeout. */
    else if (w->action == START && m->state == FAILED)
        w->done = 1;
}

static void print_status(const loadid_status_t *m) {
    printf(
        "state %s\nsamples_ok %lld\nframes_bad %lld\nsamples_incomplete %lld\n"
        "samples_saturated %lld\nsequence_gaps %lld\njoint_msgs_bad %lld\n"
        "loop_us p50 %.1f p99 %.1f max %.1f\n",
        loadid_lcm_state_name(m->state), (long long)m->samples_ok, (long long)m->frames_bad,
        (long long)m->samples_incomplete, (long long)m->samples_saturated,
        (long long)m->sequence_gaps, (long long)m->joint_msgs_bad, m->loop_us_p50, m->loop_us_p99,
        m->loop_us_max);
}

/* Why a command did not show its effect, given the state loadidd is in
 * (the pipeline's rules, host/src/pipeline/pipeline.c run_command). */
static const char *no_effect_hint(int action, int state) {
    if (state == FAILED) return ": 'loadid reset' clears FAILED (loadidd's log says why it failed)";
    if (action == ZERO && state == ESTIMATING) return ": ZERO is ignored while estimating";
    if (action == START && state == ESTIMATING) return ": it is estimating already";
    if (action == STOP) return ": STOP acts only while estimating";
    return "";
}

int main(int argc, char **argv) {
    const char *config_path = NULL, *url = NULL, *load_name = "", *out = NULL;
    double timeout = 3;
    int publish_every = 0;
    static const struct option opts[] = {{"config", required_argument, NULL, 'c'},
                                         {"lcm-url", required_argument, NULL, 'u'},
                                         {"load-name", required_argument, NULL, 'n'},
                                         {"timeout", required_argument, NULL, 't'},
                                         {"out", required_argument, NULL, 'o'},
                                         {"publish-every", required_argument, NULL, 'p'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "c:u:n:t:h", opts, NULL)) != -1) {
        switch (c) {
            case 'c':
                config_path = optarg;
                break;
            case 'o':
                out = optarg;
                break;
            case 'p': {
                long long v;
                if (loadid_arg_integer(optarg, 1, 1000000, &v) != 0) {
                    fprintf(stderr, "%s: --publish-every: a count in 1..1000000, not %s\n", prog,
                            optarg);
                    return 2;
                }
                publish_every = (int)v;
                break;
            }
            case 'u':
                url = optarg;
                break;
            case 'n':
                load_name = optarg;
                break;
            case 't': {
                char *end;
                timeout = strtod(optarg, &end);
                if (*end || end == optarg || !(timeout > 0) || timeout > 3600) {
                    fprintf(stderr, "%s: --timeout: seconds in (0, 3600], not %s\n", prog, optarg);
                    return 2;
                }
                break;
            }
            case 'h':
                usage(stdout);
                return 0;
            default:
                usage(stderr);
                return 2;
        }
    }
    if (optind < argc && strcmp(argv[optind], "plot") == 0) {
        if (optind + 2 != argc) {
            fprintf(stderr, "%s: plot needs one RECORDING, TRACE or DIR\n", prog);
            usage(stderr);
            return 2;
        }
        return loadid_cli_plot(prog, config_path, argv[optind + 1], out, publish_every);
    }
    if (optind + 1 != argc) {
        usage(stderr);
        return 2;
    }
    if (out || publish_every) {
        fprintf(stderr, "%s: --out and --publish-every are for plot\n", prog);
        return 2;
    }
    const char *verb = argv[optind];
    static const char *const verbs[] = {
        [ZERO] = "zero", [START] = "start", [STOP] = "stop", [RESET] = "reset"};
    int action = 0;
    for (int i = ZERO; i <= RESET; ++i)
        if (strcmp(verb, verbs[i]) == 0) action = i;
    if (!action && strcmp(verb, "status") != 0) {
        fprintf(stderr, "%s: unknown command '%s' (zero, start, stop, reset, status, plot)\n", prog,
                verb);
        return 2;
    }
    static loadid_config_t cfg;
    loadid_config_default(&cfg);
    char err[1024];
    if (config_path && loadid_config_load(config_path, &cfg, err, sizeof err, warn, NULL) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    const char *lcm_url = url ? url : cfg.lcm_url;
    lcm_t *lcm = lcm_create(lcm_url);
    if (!lcm) {
        fprintf(stderr, "%s: cannot open LCM at %s\n", prog, lcm_url);
        return 1;
    }
    char command[128], status[128];
    loadid_config_channel(&cfg, "LOADID_COMMAND", command, sizeof command);
    loadid_config_channel(&cfg, "LOADID_STATUS", status, sizeof status);
    /* Subscribed (and liblcm's receive socket open) before the command goes
     * out, so that no answer can come before we listen. */
    wait_t w = {.action = action, .sent = now_us(), .state = -1};
    loadid_status_t_subscription_t *sub = loadid_status_t_subscribe(lcm, status, on_status, &w);
    const int fd = lcm_get_fileno(lcm);
    int rc = 0;
    if (action) {
        loadid_command_t m = {
            .utime = w.sent, .action = (int8_t)action, .load_name = (char *)load_name};
        if (loadid_command_t_publish(lcm, command, &m) != 0) {
            fprintf(stderr, "%s: cannot publish on %s at %s\n", prog, command, lcm_url);
            loadid_status_t_unsubscribe(lcm, sub);
            lcm_destroy(lcm);
            return 1;
        }
    }
    const double end = mono_s() + timeout;
    for (double left = timeout; !w.done && left > 0; left = end - mono_s()) {
        struct pollfd pfd = {.fd = fd, .events = POLLIN};
        const int ms = left > 0.1 ? 100 : (int)(left * 1000) + 1;
        if (poll(&pfd, 1, ms) > 0) lcm_handle(lcm);
    }
    if (!w.statuses) {
        fprintf(stderr,
                "%s: %s: no answer: no status_t on %s at %s within %.3g s (is loadidd "
                "running, with the same lcm.url and lcm.channel_prefix?)\n",
                prog, verb, status, lcm_url, timeout);
        rc = 1;
    } else if (!action) {
        print_status(&w.last);
    } else if (w.done && w.state == expected_state(action)) {
        printf("state %s\n", loadid_lcm_state_name(w.state));
    } else if (w.done) { /* FAILED */
        fprintf(stderr, "%s: %s: loadidd is in state FAILED%s\n", prog, verb,
                no_effect_hint(action, w.state));
        rc = 1;
    } else {
        fprintf(stderr,
                "%s: %s: loadidd is running (state %s) but did not act on it within "
                "%.3g s%s\n",
                prog, verb, loadid_lcm_state_name(w.state), timeout,
                no_effect_hint(action, w.state));
        rc = 1;
    }
    loadid_status_t_unsubscribe(lcm, sub);
    lcm_destroy(lcm);
    return rc;
}
