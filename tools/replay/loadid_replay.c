/*
 * loadid-replay: puts a recording (can.log, lcm.log) back on a CAN
 * interface and on LCM together, both streams keeping their recorded
 * relative timing (times a speed factor), the LCM messages' utime
 * rewritten to their scheduled time now (CAN frames get the kernel's
 * receive time anyway).
 * --loop repeats it. When the interface goes away (deleted, down), the
 * replay keeps its schedule, as a sensor on the bus would: the frames due
 * meanwhile are lost, counted, and the interface is reopened at the next
 * frame due once it is back. Recording a live session into the same format is
 * `candump -l -s 0 <if>` (can-utils) beside `lcm-logger` (lcm): see the
 * README.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <getopt.h>
#include <lcm/lcm.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "loadid/lcm_wire.h"
#include "loadid/recording.h"
#include "loadid/socketcan.h"

static const char *prog = "loadid-replay";

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s --interface IF [--lcm-url URL] [--speed X] [--loop] RECORDING_DIR\n"
            "Replays can.log onto the CAN interface IF and lcm.log onto LCM (default\n"
            "udpm://239.255.76.67:7667?ttl=0) with their recorded relative timing scaled by\n"
            "1/X (default 1), utime fields rewritten to now. --loop repeats until killed.\n",
            prog);
}

static int64_t wall_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static void sleep_until(int64_t t_us) {
    for (;;) {
        int64_t left = t_us - wall_us();
        if (left <= 0) return;
        struct timespec ts = {left / 1000000, (left % 1000000) * 1000};
        nanosleep(&ts, NULL);
    }
}

/* Whether channel is name, after any lcm.channel_prefix. */
static int is_channel(const char *channel, const char *name) {
    const size_t c = strlen(channel), n = strlen(name);
    return c >= n && strcmp(channel + c - n, name) == 0;
}

/* Re-publishes an LCM event with its utime moved to now's time base, on
 * the channel it was recorded on; joint states and commands go through the
 * service's decoder (lcm_wire.h), and one it refuses is not sent. Returns
 * 1 when it was refused. */
static int republish(lcm_t *lcm, const loadid_rec_event_t *ev, int64_t shift) {
    uint8_t buf[LOADID_LCM_JOINT_STATE_MAX > LOADID_LCM_COMMAND_MAX ? LOADID_LCM_JOINT_STATE_MAX
                                                                    : LOADID_LCM_COMMAND_MAX];
    const size_t len = (size_t)ev->datalen;
    int n;
    if (is_channel(ev->channel, "LOADID_JOINTS")) {
        loadid_lcm_joint_state_t m;
        if (loadid_lcm_decode_joint_state(ev->data, len, &m) < 0) return 1;
        m.utime += shift;
        n = loadid_lcm_encode_joint_state(&m, buf, sizeof buf);
    } else if (is_channel(ev->channel, "LOADID_COMMAND")) {
        loadid_lcm_command_t m;
        if (loadid_lcm_decode_command(ev->data, len, &m) < 0) return 1;
        m.utime += shift;
        n = loadid_lcm_encode_command(&m, buf, sizeof buf);
    } else {
        lcm_publish(lcm, ev->channel, ev->data, (unsigned)ev->datalen); /* as recorded */
        return 0;
    }
    if (n > 0) lcm_publish(lcm, ev->channel, buf, (unsigned)n);
    return n <= 0;
}

/* What the CAN side did: frames lost while the interface was gone, and how
 * often it went. */
typedef struct {
    const char *ifname;
    int fd; /* -1 while the interface is gone */
    int64_t lost, gone;
} can_out_t;

/* One frame due now. Returns 0 (sent, or lost with the interface gone) or
 * -errno (another failure). */
static int send_frame(can_out_t *can, const loadid_can_frame_t *frame) {
    char err[512];
    if (can->fd < 0 && (can->fd = loadid_socketcan_open_tx(can->ifname, err, sizeof err)) >= 0)
        fprintf(stderr, "%s: CAN %s back\n", prog, can->ifname);
    if (can->fd < 0) {
        can->lost++;
        return 0;
    }
    int w;
    while ((w = loadid_socketcan_write(can->fd, frame)) == -EAGAIN || w == -ENOBUFS) {
        struct timespec ts = {0, 20000};
        nanosleep(&ts, NULL);
    }
    if (w == -ENXIO || w == -ENODEV || w == -ENETDOWN) { /* gone: deleted or down */
        fprintf(stderr, "%s: CAN %s: %s; frames lost until it is back\n", prog, can->ifname,
                strerror(-w));
        close(can->fd);
        can->fd = -1;
        can->lost++;
        can->gone++;
        return 0;
    }
    return w;
}

static int play(const char *dir, can_out_t *can, lcm_t *lcm, double speed, int64_t *sent) {
    char err[4400];
    loadid_recording_reader_t *rec = NULL;
    if (loadid_recording_reader_open(dir, &rec, err, sizeof err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    loadid_rec_event_t ev;
    int rc, have_t0 = 0;
    int64_t t0 = 0, start = 0, bad = 0;
    while ((rc = loadid_recording_reader_next(rec, &ev)) == 1) {
        if (ev.kind == LOADID_REC_BAD_LINE) continue;
        if (!have_t0) t0 = ev.t_us, start = wall_us() + 100000, have_t0 = 1;
        const int64_t due = start + (int64_t)llround((double)(ev.t_us - t0) / speed);
        sleep_until(due);
        if (ev.kind == LOADID_REC_CAN) {
            const int w = send_frame(can, &ev.can);
            if (w != 0) {
                fprintf(stderr, "%s: CAN write: %s\n", prog, strerror(-w));
                loadid_recording_reader_close(rec);
                return 1;
            }
        } else {
            /* The scheduled time, not the moment it goes out: a joint
             * state's utime is when the joints were sampled, and the
             * filters differentiate by it (send-time jitter there cost the
             * VM test 67 % of the mass). */
            bad += republish(lcm, &ev, due - ev.t_us);
        }
        (*sent)++;
    }
    /* What could not be read or decoded, said once a pass. */
    loadid_eventlog_stats_t ls;
    loadid_recording_lcm_stats(rec, &ls);
    if (rc < 0 && *loadid_recording_lcm_error(rec))
        fprintf(stderr, "%s: %s/lcm.log: %s\n", prog, dir, loadid_recording_lcm_error(rec));
    else if (rc < 0)
        fprintf(stderr, "%s: %s/can.log: read error\n", prog, dir);
    if (ls.damaged || ls.truncated)
        fprintf(stderr, "%s: warning: %s/lcm.log: %s\n", prog, dir, ls.first_problem);
    if (bad)
        fprintf(stderr, "%s: warning: %s/lcm.log: %lld messages could not be decoded, not sent\n",
                prog, dir, (long long)bad);
    loadid_recording_reader_close(rec);
    return rc < 0 ? 1 : 0;
}

int main(int argc, char **argv) {
    const char *ifname = NULL, *url = "udpm://239.255.76.67:7667?ttl=0";
    double speed = 1;
    int loop = 0;
    static const struct option opts[] = {{"interface", required_argument, NULL, 'i'},
                                         {"lcm-url", required_argument, NULL, 'u'},
                                         {"speed", required_argument, NULL, 's'},
                                         {"loop", no_argument, NULL, 'l'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "i:u:s:lh", opts, NULL)) != -1) {
        switch (c) {
            case 'i':
                ifname = optarg;
                break;
            case 'u':
                url = optarg;
                break;
            case 's': {
                char *end;
                speed = strtod(optarg, &end);
                if (*end || end == optarg || !(speed > 0) || !isfinite(speed)) {
                    fprintf(stderr, "%s: --speed: a factor > 0, not %s\n", prog, optarg);
                    return 2;
                }
                break;
            }
            case 'l':
                loop = 1;
                break;
            case 'h':
                usage(stdout);
                return 0;
            default:
                usage(stderr);
                return 2;
        }
    }
    if (optind + 1 != argc || !ifname) {
        usage(stderr);
        return 2;
    }
    char err[512];
    can_out_t can = {.ifname = ifname, .fd = loadid_socketcan_open_tx(ifname, err, sizeof err)};
    if (can.fd < 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 1;
    }
    lcm_t *lcm = lcm_create(url);
    if (!lcm) {
        fprintf(stderr, "%s: cannot open LCM at %s\n", prog, url);
        return 1;
    }
    int64_t sent = 0;
    int rc;
    do {
        rc = play(argv[optind], &can, lcm, speed, &sent);
    } while (loop && rc == 0);
    fprintf(stderr, "%s: %lld frames and messages replayed\n", prog, (long long)sent - can.lost);
    if (can.lost)
        fprintf(stderr, "%s: %lld CAN frames lost: %s was gone %lld times\n", prog,
                (long long)can.lost, ifname, (long long)can.gone);
    if (can.fd >= 0) close(can.fd);
    lcm_destroy(lcm);
    return rc;
}
