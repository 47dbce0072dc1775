/*
 * loadid-record: records a live session into a recording folder of the
 * docs/INTERFACE.md format, the input of `loadidd --offline` and `loadid-replay`:
 *
 *   can.log  the JR3's frames (base..base+4, standard identifiers) from a
 *            SocketCAN interface, one candump line each, with the kernel's
 *            receive time to the microsecond (drivers/candump.h writes what
 *            `candump -l` writes);
 *   lcm.log  an LCM event log (liblcm's lcm_eventlog_*, as lcm-logger
 *            writes it) of LOADID_JOINTS and LOADID_COMMAND, or of every
 *            channel with --all-channels; each event's time is LCM's
 *            receive time.
 *
 * Both times are wall-clock microseconds (SO_TIMESTAMP and LCM's
 * recv_utime), the one clock of docs/INTERFACE.md. Stops on SIGINT or SIGTERM, or
 * after --duration seconds, and prints what it recorded, with the frames
 * the kernel dropped when the recorder fell behind (SO_RXQ_OVFL). An
 * interface that vanishes is reported and reopened once a second, as the
 * daemon does.
 */
#define _GNU_SOURCE

#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <lcm/eventlog.h>
#include <lcm/lcm.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "loadid/candump.h"
#include "loadid/config.h"
#include "loadid/socketcan.h"

static const char *prog = "loadid-record";

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig) {
    (void)sig;
    stop_requested = 1; /* only a flag */
}

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s [--config FILE] [--interface IF] [--lcm-url URL] [--all-channels]\n"
            "       [--duration SECONDS] [--quiet] --out DIR\n"
            "Records the JR3's CAN frames (can.base_id .. base+4) into DIR/can.log and\n"
            "LOADID_JOINTS and LOADID_COMMAND (every channel with --all-channels) into\n"
            "DIR/lcm.log, until SIGINT/SIGTERM or --duration. The interface, base id and LCM\n"
            "URL come from --config (can.interface, can.base_id, lcm.url), the options\n"
            "override them. DIR is created; existing recordings there are not overwritten.\n",
            prog);
}

static double mono_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

typedef struct {
    lcm_eventlog_t *log;
    int64_t events, write_errors;
} lcm_sink_t;

static void on_lcm(const lcm_recv_buf_t *rbuf, const char *channel, void *ctx) {
    lcm_sink_t *s = ctx;
    lcm_eventlog_event_t ev = {.eventnum = s->events,
                               .timestamp = rbuf->recv_utime,
                               .channellen = (int32_t)strlen(channel),
                               .datalen = (int32_t)rbuf->data_size,
                               .channel = (char *)channel,
                               .data = rbuf->data};
    if (lcm_eventlog_write_event(s->log, &ev) != 0)
        s->write_errors++;
    else
        s->events++;
}

/* Creates dir/name, refusing to overwrite one that exists. Returns the
 * stream, or NULL with a reason in err. */
static FILE *create_new(const char *dir, const char *name, char *path, size_t pathlen, char *err,
                        size_t errlen) {
    snprintf(path, pathlen, "%s/%s", dir, name);
    const int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!f) {
        snprintf(err, errlen, "%s: cannot create: %s", path, strerror(errno));
        if (fd >= 0) close(fd);
    }
    return f;
}

int main(int argc, char **argv) {
    const char *config_path = NULL, *ifname_opt = NULL, *url_opt = NULL, *out_dir = NULL;
    double duration = 0; /* 0: until a signal */
    int all_channels = 0, quiet = 0;
    static const struct option opts[] = {{"all-channels", no_argument, NULL, 'a'},
                                         {"config", required_argument, NULL, 'c'},
                                         {"duration", required_argument, NULL, 'd'},
                                         {"help", no_argument, NULL, 'h'},
                                         {"interface", required_argument, NULL, 'i'},
                                         {"lcm-url", required_argument, NULL, 'u'},
                                         {"out", required_argument, NULL, 'o'},
                                         {"quiet", no_argument, NULL, 'q'},
                                         {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "ac:d:hi:o:qu:", opts, NULL)) != -1) {
        switch (c) {
            case 'a':
                all_channels = 1;
                break;
            case 'c':
                config_path = optarg;
                break;
            case 'd': {
                char *end;
                duration = strtod(optarg, &end);
                if (*end || end == optarg || !(duration > 0) || !isfinite(duration)) {
                    fprintf(stderr, "%s: --duration: seconds > 0, not %s\n", prog, optarg);
                    return 2;
                }
                break;
            }
            case 'h':
                usage(stdout);
                return 0;
            case 'i':
                ifname_opt = optarg;
                break;
            case 'o':
                out_dir = optarg;
                break;
            case 'q':
                quiet = 1;
                break;
            case 'u':
                url_opt = optarg;
                break;
            default:
                usage(stderr);
                return 2;
        }
    }
    if (optind != argc || !out_dir) {
        usage(stderr);
        return 2;
    }
    static loadid_config_t cfg;
    loadid_config_default(&cfg);
    char err[4600];
    if (config_path && loadid_config_load(config_path, &cfg, err, sizeof err, NULL, NULL) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    const char *ifname = ifname_opt ? ifname_opt : cfg.can_interface;
    const char *url = url_opt ? url_opt : cfg.lcm_url;

    int can_fd = loadid_socketcan_open(ifname, cfg.can_base_id, err, sizeof err);
    if (can_fd < 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    lcm_t *lcm = lcm_create(url);
    if (!lcm) {
        fprintf(stderr, "%s: cannot open LCM at %s\n", prog, url);
        close(can_fd);
        return 1;
    }
    if (mkdir(out_dir, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "%s: %s: cannot create: %s\n", prog, out_dir, strerror(errno));
        lcm_destroy(lcm), close(can_fd);
        return 1;
    }
    char can_path[4200], lcm_path[4200];
    FILE *can_log = create_new(out_dir, "can.log", can_path, sizeof can_path, err, sizeof err);
    FILE *lcm_probe =
        can_log ? create_new(out_dir, "lcm.log", lcm_path, sizeof lcm_path, err, sizeof err) : NULL;
    lcm_sink_t sink = {0};
    if (lcm_probe) {
        fclose(lcm_probe); /* exists now, empty: the event log takes it over */
        sink.log = lcm_eventlog_create(lcm_path, "w");
        if (!sink.log)
            snprintf(err, sizeof err, "%s: cannot create: %s", lcm_path, strerror(errno));
    }
    if (!sink.log) {
        fprintf(stderr, "%s: %s\n", prog, err);
        if (can_log) fclose(can_log);
        lcm_destroy(lcm), close(can_fd);
        return 1;
    }
    /* LCM queues 30 messages per subscription and drops the rest; a
     * recorder held up (a slow disk, an emulated CPU) must not lose joint
     * states: room for 100 s of them at 1 kHz. */
    char joints[128], command[128]; /* with lcm.channel_prefix */
    loadid_config_channel(&cfg, "LOADID_JOINTS", joints, sizeof joints);
    loadid_config_channel(&cfg, "LOADID_COMMAND", command, sizeof command);
    lcm_subscription_t *subs[2] = {
        lcm_subscribe(lcm, all_channels ? ".*" : joints, on_lcm, &sink),
        all_channels ? NULL : lcm_subscribe(lcm, command, on_lcm, &sink)};
    for (int i = 0; i < 2; ++i)
        if (subs[i]) lcm_subscription_set_queue_capacity(subs[i], 100000);

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    int64_t frames = 0, error_frames = 0, format_errors = 0, can_losses = 0, reopens = 0;
    int64_t drops = 0;       /* frames the kernel dropped, its receive buffer full */
    uint32_t drops_seen = 0; /* the open socket's cumulative count (SO_RXQ_OVFL) */
    int rc = 0;
    const double t_end = duration > 0 ? mono_s() + duration : INFINITY;
    double next_reopen = 0;
    if (!quiet)
        fprintf(stderr, "%s: recording %s (0x%X..0x%X) and LCM %s%s into %s\n", prog, ifname,
                (unsigned)cfg.can_base_id, (unsigned)cfg.can_base_id + 4, url,
                all_channels ? " (all channels)" : "", out_dir);
    while (!stop_requested && rc == 0) {
        const double now = mono_s();
        if (now >= t_end) break;
        if (can_fd < 0 && now >= next_reopen) {
            can_fd = loadid_socketcan_open(ifname, cfg.can_base_id, err, sizeof err);
            next_reopen = now + 1;
            if (can_fd >= 0) {
                reopens++;
                fprintf(stderr, "%s: CAN %s reopened\n", prog, ifname);
            }
        }
        struct pollfd pfd[2] = {{.fd = lcm_get_fileno(lcm), .events = POLLIN},
                                {.fd = can_fd, .events = POLLIN}};
        const double wait_s = fmin(0.1, t_end - now);
        const int n = poll(pfd, can_fd >= 0 ? 2 : 1, (int)ceil(wait_s * 1000));
        if (n < 0) {
            if (errno == EINTR) continue;
            fprintf(stderr, "%s: poll: %s\n", prog, strerror(errno));
            rc = 1;
            break;
        }
        if (pfd[0].revents & POLLIN) lcm_handle_timeout(lcm, 0); /* all that wait */
        if (can_fd >= 0 && pfd[1].revents) {
            loadid_can_frame_t f;
            int r;
            uint32_t d = drops_seen;
            while ((r = loadid_socketcan_read(can_fd, &f, &d)) > 0) {
                drops += (uint32_t)(d - drops_seen), drops_seen = d;
                if (r == 2) { /* a bus error: not a frame of the recording */
                    error_frames++;
                    continue;
                }
                char line[LOADID_CANDUMP_LINE_MAX];
                const int len = loadid_candump_format(&f, ifname, line, sizeof line);
                if (len < 0)
                    format_errors++;
                else if (fwrite(line, 1, (size_t)len, can_log) != (size_t)len)
                    rc = 1;
                else
                    frames++;
            }
            if (r < 0) {
                fprintf(stderr, "%s: CAN %s: %s; reopening\n", prog, ifname, strerror(-r));
                close(can_fd);
                can_fd = -1;
                can_losses++;
                drops_seen = 0;
                next_reopen = mono_s() + 1;
            }
        }
    }
    if (fflush(can_log) != 0 || ferror(can_log)) rc = 1;
    if (rc) fprintf(stderr, "%s: %s: write error: %s\n", prog, can_path, strerror(errno));
    fclose(can_log);
    lcm_eventlog_destroy(sink.log);
    if (sink.write_errors) {
        fprintf(stderr, "%s: %s: %lld events not written\n", prog, lcm_path,
                (long long)sink.write_errors);
        rc = 1;
    }
    if (!quiet)
        fprintf(stderr,
                "%s: %lld CAN frames, %lld LCM events; %lld error frames, %lld unwritable "
                "frames, interface lost %lld times, reopened %lld, %lld frames dropped by "
                "the kernel\n",
                prog, (long long)frames, (long long)sink.events, (long long)error_frames,
                (long long)format_errors, (long long)can_losses, (long long)reopens,
                (long long)drops);
    if (can_fd >= 0) close(can_fd);
    lcm_destroy(lcm);
    return rc;
}
