/*
 * loadid-modbus-sim: a serial force-torque sensor (proto/modbus_ft.md) on a
 * pseudo-terminal it creates, for the daemon's end-to-end tests and for
 * trying `sensor.type: modbus` without hardware. It prints the slave side's
 * path ("pty /dev/pts/N", and "link PATH" with --link) on stdout and serves
 * Modbus RTU with the same server as tests/unit/test_modbus_ft.c
 * (loadid/modbus_ft_server.h) until SIGINT/SIGTERM, --duration, or the end
 * of the recording.
 *
 * The wrench is a constant (--wrench) or a recording's JR3 force and
 * moment (--recording DIR: DIR/can.log decoded with drivers/jr3.h, full
 * scales and base id from --config's jr3.* and can.* keys). The sensor
 * "measures" with the recording's own timing mapped onto now: a request
 * gets the newest sample whose relative time has passed, and the counter
 * register is that sample's index + 1, so a client that polls faster than
 * the recording sees stale reads, and one that polls slower sees gaps.
 * Saturated or faulty JR3 samples keep their status bits. A constant
 * wrench is measured anew for every read (the counter counts the reads).
 * --silent T0:T1 and --bad-crc T0:T1 (seconds on that timeline) leave the
 * sample reads in [T0, T1) unanswered or answer them with a wrong CRC, as
 * a sensor that hangs or a noisy line would. At exit it tallies on stderr
 * what the client got: reads unanswered and with a bad CRC, the counters
 * it was answered with (first..last, how many different) and the wall
 * time of the first sample read, so a test can check a client's counts
 * against the sensor's own.
 */
#define _DEFAULT_SOURCE /* cfmakeraw, openpty */

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pty.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "loadid/candump.h"
#include "loadid/config.h"
#include "loadid/jr3.h"
#include "loadid/modbus_ft.h"
#include "loadid/modbus_ft_server.h"

static volatile sig_atomic_t g_stop;
static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

typedef struct {
    int64_t t_us; /* relative to the first sample */
    double force[3], torque[3];
    bool saturated, faulty;
} rec_sample_t;

typedef struct {
    rec_sample_t *s;
    size_t n;
    double fs_force[3], fs_moment[3];
    int64_t start_ns; /* CLOCK_MONOTONIC at the first sample */
    bool loop;
    bool constant;      /* --wrench: one sample, measured again per read */
    bool start_on_read; /* --start-on-read: the timeline starts at the first read */
    bool started;
    bool ended;
    int64_t served;
    double silent[2], bad_crc[2]; /* fault windows [s] on the timeline; empty: off */
    /* what the client was answered with (normal answers only) */
    int64_t first_number, last_number, numbers; /* counters first..last, how many different */
    int64_t first_read_us;                      /* wall time of the first sample read */
} sim_t;

static int64_t wall_us(void) {
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static bool within(const double w[2], double t) {
    return w[1] > w[0] && t >= w[0] && t < w[1];
}

static int64_t mono_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static int load_recording(const char *dir, const loadid_config_t *cfg, sim_t *sim) {
    char path[LOADID_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/can.log", dir);
    FILE *fp = fopen(path, "r");
    if (!fp) {
        fprintf(stderr, "loadid-modbus-sim: %s: %s\n", path, strerror(errno));
        return -1;
    }
    loadid_jr3_config_t jc;
    loadid_jr3_config_default(&jc);
    jc.base_id = cfg->can_base_id;
    for (int i = 0; i < 3; ++i) {
        jc.full_scale[LOADID_JR3_FORCE][i] = cfg->jr3_fs_force[i];
        jc.full_scale[LOADID_JR3_MOMENT][i] = cfg->jr3_fs_moment[i];
        jc.full_scale[LOADID_JR3_LINEAR][i] = cfg->jr3_fs_linear[i];
        jc.full_scale[LOADID_JR3_ANGULAR][i] = cfg->jr3_fs_angular[i];
    }
    loadid_jr3_decoder_t *dec = NULL;
    loadid_candump_reader_t *rd = NULL;
    if (loadid_jr3_decoder_create(&jc, &dec) != 0 || loadid_candump_reader_open(fp, &rd) != 0) {
        fprintf(stderr, "loadid-modbus-sim: out of memory\n");
        fclose(fp);
        loadid_jr3_decoder_destroy(dec);
        return -1;
    }
    size_t cap = 0;
    int64_t t0 = 0;
    loadid_can_frame_t f;
    int rc;
    while ((rc = loadid_candump_read(rd, &f, NULL)) != 0) {
        if (rc < 0 && rc != -EIO) continue; /* a bad line: skipped */
        if (rc < 0) break;
        loadid_jr3_output_t out;
        const int d = loadid_jr3_decoder_feed(dec, &f, &out);
        if (d != LOADID_JR3_SAMPLE && d != LOADID_JR3_E_SATURATED && d != LOADID_JR3_E_FAULT)
            continue;
        if (sim->n == cap) {
            cap = cap ? 2 * cap : 4096;
            rec_sample_t *g = realloc(sim->s, cap * sizeof *g);
            if (!g) break;
            sim->s = g;
        }
        if (sim->n == 0) t0 = out.sample.t_us;
        rec_sample_t *s = &sim->s[sim->n++];
        s->t_us = out.sample.t_us - t0;
        for (int i = 0; i < 3; ++i) {
            s->force[i] = out.sample.value[LOADID_JR3_FORCE][i];
            s->torque[i] = out.sample.value[LOADID_JR3_MOMENT][i];
        }
        s->saturated = out.sample.saturated;
        s->faulty = out.sample.faulty;
    }
    loadid_candump_reader_close(rd);
    loadid_jr3_decoder_destroy(dec);
    fclose(fp);
    if (sim->n == 0) {
        fprintf(stderr, "loadid-modbus-sim: %s: no complete JR3 sample\n", path);
        return -1;
    }
    return 0;
}

/* Before each input read: the newest sample whose time has come. */
static void hook(void *ctx, loadid_modbus_ft_server_t *srv) {
    sim_t *sim = ctx;
    if (sim->start_on_read && !sim->started) {
        sim->start_ns = mono_ns();
        sim->started = true;
    }
    const int64_t dt_us = (mono_ns() - sim->start_ns) / 1000;
    if (!sim->first_read_us) sim->first_read_us = wall_us();
    const int mode = within(sim->silent, (double)dt_us * 1e-6)    ? LOADID_MODBUS_FT_SERVER_SILENT
                     : within(sim->bad_crc, (double)dt_us * 1e-6) ? LOADID_MODBUS_FT_SERVER_BAD_CRC
                                                                  : LOADID_MODBUS_FT_SERVER_NORMAL;
    loadid_modbus_ft_server_set_mode(srv, mode);
    const int64_t span = sim->s[sim->n - 1].t_us + 1;
    int64_t rel = dt_us, lap = 0;
    if (sim->constant) {
        rel = 0; /* measuring all the time: every read a new measurement */
    } else if (sim->loop) {
        lap = dt_us / span;
        rel = dt_us % span;
    } else if (dt_us >= span) {
        sim->ended = true;
    }
    /* binary search: the last sample with t_us <= rel */
    size_t lo = 0, hi = sim->n;
    while (hi - lo > 1) {
        const size_t mid = (lo + hi) / 2;
        if (sim->s[mid].t_us <= rel)
            lo = mid;
        else
            hi = mid;
    }
    const rec_sample_t *s = &sim->s[lo];
    uint16_t regs[LOADID_MODBUS_FT_INPUT_COUNT];
    const int64_t number =
        sim->constant ? sim->served + 1 : lap * (int64_t)sim->n + (int64_t)lo + 1;
    const uint16_t counter = (uint16_t)((uint64_t)number & 0xFFFFu);
    loadid_modbus_ft_encode(sim->fs_force, sim->fs_moment, s->force, s->torque, s->faulty, counter,
                            regs);
    if (s->saturated) regs[LOADID_MODBUS_FT_REG_STATUS] |= LOADID_MODBUS_FT_STATUS_SATURATED;
    loadid_modbus_ft_server_set_input(srv, regs);
    ++sim->served;
    if (mode == LOADID_MODBUS_FT_SERVER_NORMAL) {
        if (!sim->numbers) sim->first_number = number;
        if (!sim->numbers || number != sim->last_number) ++sim->numbers;
        sim->last_number = number;
    }
}

/* --silent / --bad-crc T0:T1 [s], T0 < T1. */
static int parse_window(const char *arg, double w[2]) {
    char *end;
    w[0] = strtod(arg, &end);
    if (end == arg || *end != ':') return -1;
    arg = end + 1;
    w[1] = strtod(arg, &end);
    return end == arg || *end || !isfinite(w[0]) || !isfinite(w[1]) || !(w[1] > w[0]) ? -1 : 0;
}

static int parse_list(const char *arg, double *v, int n) {
    char *end;
    for (int i = 0; i < n; ++i) {
        v[i] = strtod(arg, &end);
        if (end == arg || !isfinite(v[i])) return -1;
        arg = end;
        if (i < n - 1) {
            if (*arg != ',') return -1;
            ++arg;
        }
    }
    return *arg ? -1 : 0;
}

static void usage(FILE *f) {
    fprintf(
        f,
        "usage: loadid-modbus-sim [--wrench FX,FY,FZ,TX,TY,TZ | --recording DIR] [--config FILE]\n"
        "                         [--link PATH] [--slave ID] [--full-scale FN,TNM] [--loop]\n"
        "                         [--duration S] [--start-on-read | --epoch UTIME]\n"
        "                         [--silent T0:T1] [--bad-crc T0:T1]\n"
        "Serves the Modbus F/T register map (proto/modbus_ft.md) on a new pty and prints\n"
        "its slave path. --wrench default 0,0,9.81,0,0,0 [N, N m]; --full-scale default\n"
        "modbus.full_scale of --config (200 N, 12 N m). The recording's timeline starts\n"
        "now, or with --start-on-read at the first sample read, or at --epoch (the wall\n"
        "time in microseconds since the epoch of its first sample, so that a test can time\n"
        "its joint states to it); --loop repeats it. --silent and --bad-crc leave the sample\n"
        "reads in [T0, T1) s of that timeline unanswered or answer them with a wrong CRC.\n"
        "At exit stderr says what was answered (counters, the first sample read's time).\n");
}

int main(int argc, char **argv) {
    static const struct option opts[] = {
        {"config", required_argument, NULL, 'c'},     {"duration", required_argument, NULL, 'd'},
        {"full-scale", required_argument, NULL, 'f'}, {"help", no_argument, NULL, 'h'},
        {"link", required_argument, NULL, 'k'},       {"loop", no_argument, NULL, 'l'},
        {"recording", required_argument, NULL, 'r'},  {"slave", required_argument, NULL, 's'},
        {"start-on-read", no_argument, NULL, 'S'},    {"epoch", required_argument, NULL, 'e'},
        {"wrench", required_argument, NULL, 'w'},     {"silent", required_argument, NULL, 'q'},
        {"bad-crc", required_argument, NULL, 'b'},    {NULL, 0, NULL, 0},
    };
    const char *config = NULL, *recording = NULL, *link_path = NULL;
    double wrench[6] = {0, 0, 9.81, 0, 0, 0}, fs[2] = {0, 0}, duration = 0;
    bool have_wrench = false, have_fs = false, loop = false, start_on_read = false;
    int slave = 1, c;
    long long epoch_us = 0;
    double silent[2] = {0, 0}, bad_crc[2] = {0, 0};
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        switch (c) {
            case 'c':
                config = optarg;
                break;
            case 'd':
                duration = strtod(optarg, NULL);
                break;
            case 'e': {
                char *end;
                epoch_us = strtoll(optarg, &end, 10);
                if (*end || epoch_us <= 0) {
                    fprintf(stderr,
                            "loadid-modbus-sim: --epoch: microseconds since the epoch, not %s\n",
                            optarg);
                    return 2;
                }
                break;
            }
            case 'f':
                if (parse_list(optarg, fs, 2) || !(fs[0] > 0) || !(fs[1] > 0)) {
                    fprintf(stderr, "loadid-modbus-sim: --full-scale: expected FN,TNM > 0\n");
                    return 2;
                }
                have_fs = true;
                break;
            case 'h':
                usage(stdout);
                return 0;
            case 'q':
            case 'b':
                if (parse_window(optarg, c == 'q' ? silent : bad_crc) != 0) {
                    fprintf(stderr, "loadid-modbus-sim: --%s: expected T0:T1 in seconds, T0 < T1\n",
                            c == 'q' ? "silent" : "bad-crc");
                    return 2;
                }
                break;
            case 'k':
                link_path = optarg;
                break;
            case 'l':
                loop = true;
                break;
            case 'r':
                recording = optarg;
                break;
            case 's':
                slave = atoi(optarg);
                break;
            case 'S':
                start_on_read = true;
                break;
            case 'w':
                if (parse_list(optarg, wrench, 6)) {
                    fprintf(
                        stderr,
                        "loadid-modbus-sim: --wrench: expected six numbers FX,FY,FZ,TX,TY,TZ\n");
                    return 2;
                }
                have_wrench = true;
                break;
            default:
                usage(stderr);
                return 2;
        }
    }
    if (optind < argc || (have_wrench && recording) || slave < 1 || slave > 247 || duration < 0) {
        fprintf(stderr, "loadid-modbus-sim: %s\n",
                optind < argc              ? "unexpected argument"
                : have_wrench && recording ? "--wrench and --recording exclude each other"
                : duration < 0             ? "--duration must be >= 0"
                                           : "--slave must be 1..247");
        return 2;
    }
    loadid_config_t cfg;
    loadid_config_default(&cfg);
    if (config) {
        char err[512];
        if (loadid_config_load(config, &cfg, err, sizeof err, NULL, NULL) != 0) {
            fprintf(stderr, "loadid-modbus-sim: %s\n", err);
            return 2;
        }
    }
    sim_t sim = {0};
    for (int i = 0; i < 3; ++i) {
        sim.fs_force[i] = have_fs ? fs[0] : cfg.modbus_fs_force[i];
        sim.fs_moment[i] = have_fs ? fs[1] : cfg.modbus_fs_moment[i];
    }
    uint16_t holding[LOADID_MODBUS_FT_HOLDING_COUNT];
    if (loadid_modbus_ft_encode_full_scale(sim.fs_force, sim.fs_moment, holding) != 0) {
        fprintf(stderr,
                "loadid-modbus-sim: a full scale outside 0.1..6553.5 N or 0.01..655.35 N m\n");
        return 2;
    }
    /* The sensor serves the full scales its registers carry. */
    for (int i = 0; i < 3; ++i) {
        sim.fs_force[i] = holding[i] * LOADID_MODBUS_FT_FORCE_UNIT;
        sim.fs_moment[i] = holding[3 + i] * LOADID_MODBUS_FT_MOMENT_UNIT;
    }
    if (recording) {
        if (load_recording(recording, &cfg, &sim) != 0) return 1;
    } else {
        sim.s = calloc(1, sizeof *sim.s);
        if (!sim.s) return 1;
        sim.n = 1;
        memcpy(sim.s[0].force, wrench, sizeof sim.s[0].force);
        memcpy(sim.s[0].torque, wrench + 3, sizeof sim.s[0].torque);
    }
    sim.loop = loop;
    memcpy(sim.silent, silent, sizeof silent);
    memcpy(sim.bad_crc, bad_crc, sizeof bad_crc);
    sim.start_on_read = start_on_read;
    sim.constant = !recording;

    int master = -1, slave_fd = -1;
    char pts[128];
    struct termios tio;
    memset(&tio, 0, sizeof tio);
    cfmakeraw(&tio);
    if (openpty(&master, &slave_fd, pts, &tio, NULL) != 0) {
        fprintf(stderr, "loadid-modbus-sim: openpty: %s\n", strerror(errno));
        return 1;
    }
    if (link_path) {
        unlink(link_path);
        if (symlink(pts, link_path) != 0) {
            fprintf(stderr, "loadid-modbus-sim: --link %s: %s\n", link_path, strerror(errno));
            return 1;
        }
    }
    loadid_modbus_ft_server_t *srv = NULL;
    if (loadid_modbus_ft_server_create(master, slave, LOADID_MODBUS_FT_INPUT_COUNT,
                                       LOADID_MODBUS_FT_HOLDING_COUNT, &srv) != 0) {
        fprintf(stderr, "loadid-modbus-sim: cannot create the server\n");
        return 1;
    }
    loadid_modbus_ft_server_set_holding(srv, holding);
    loadid_modbus_ft_server_set_hook(srv, hook, &sim);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    printf("pty %s\n", pts);
    if (link_path) printf("link %s\n", link_path);
    printf("samples %zu\n", sim.n);
    fflush(stdout);
    sim.start_ns = mono_ns();
    const int64_t end_ns0 = sim.start_ns;
    if (epoch_us > 0 && !start_on_read) {
        struct timespec wall;
        clock_gettime(CLOCK_REALTIME, &wall);
        const int64_t wall_us = (int64_t)wall.tv_sec * 1000000 + wall.tv_nsec / 1000;
        sim.start_ns += ((int64_t)epoch_us - wall_us) * 1000;
    }
    const int64_t end_ns = duration > 0 ? end_ns0 + (int64_t)(duration * 1e9) : INT64_MAX;
    while (!g_stop && !sim.ended && mono_ns() < end_ns) {
        /* A malformed request is dropped, as a sensor would; -EIO (nobody
         * holds the slave open) cannot last, this process holds it. */
        if (loadid_modbus_ft_server_poll(srv, 50) == -EIO) usleep(10000);
    }
    loadid_modbus_ft_server_stats_t st;
    loadid_modbus_ft_server_stats(srv, &st);
    fprintf(stderr,
            "loadid-modbus-sim: %lld requests, %lld sample reads, %lld full-scale reads, "
            "%lld unanswered, %lld bad CRC; counters %lld..%lld, %lld different; first sample "
            "read at %lld us\n",
            (long long)st.requests, (long long)st.input_reads, (long long)st.holding_reads,
            (long long)st.silent, (long long)st.bad_crc, (long long)sim.first_number,
            (long long)sim.last_number, (long long)sim.numbers, (long long)sim.first_read_us);
    loadid_modbus_ft_server_destroy(srv);
    close(master);
    close(slave_fd);
    if (link_path) unlink(link_path);
    free(sim.s);
    return 0;
}
