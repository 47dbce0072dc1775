/*
 * loadidd: the load identification service (docs/INTERFACE.md, "Command
 * line" and "Configuration").
 *
 *   loadidd --config FILE --offline RECORDING_DIR [--result OUT.json]
 *           [--trace TRACE.csv [--publish-every N]]
 *       runs the pipeline (pipeline.h) over a recording as fast as the
 *       machine allows, with no sockets: can.log and lcm.log merged in time
 *       order, commands acting at their utime; writes the final estimate of
 *       every configured method as a JSON array (OUT.json, else stdout).
 *       Exit 0, or non-zero with a one-line reason on stderr; a recording
 *       that ends before the window, lacks ZERO or START, or lacks joint
 *       data for part of the window is written with "complete": false and
 *       exits 3 unless --allow-incomplete. --trace also writes every
 *       method's estimate every N-th sample (default 10) and the final ones
 *       as CSV (trace_csv.h); without it nothing is published before DONE.
 *   loadidd --config FILE [--can-file CAN.LOG] [--publish-every N]
 *       the live service (live.c): joint states and commands from LCM, JR3
 *       frames from SocketCAN (can.interface) or, with --can-file, from a
 *       candump log replayed in real time; estimate_t (every N-th sample
 *       while estimating, and the final one), wrench_t once DONE, status_t
 *       at 1 Hz on LCM. SIGTERM or SIGINT stop it cleanly.
 *   loadidd --config FILE --replay RECORDING_DIR [--replay-without-commands]
 *       live, with a recording's JR3 frames, joint states and commands
 *       replayed in real time in the daemon itself (inputs/replay.c): no
 *       CAN, the normal LCM output, commands over LCM as well.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/arg_number.h"
#include "loadid/config.h"
#include "loadid/core.h"
#include "loadid/lcm_wire.h"
#include "loadid/offline.h"
#include "loadid/pipeline.h"
#include "loadid/setup.h"
#include "live.h"
#include "result_json.h"
#include "saved_result.h"
#include "trace_csv.h"

static const char *prog = "loadidd";

/* A warning of the configuration (another program's section). */
static void warn_line(void *ctx, const char *msg) {
    (void)ctx;
    fprintf(stderr, "%s: warning: %s\n", prog, msg);
}

static void usage(FILE *out) {
    fprintf(out,
            "usage: %s --config FILE --offline RECORDING_DIR [--result OUT.json]\n"
            "                [--trace TRACE.csv [--publish-every N]] [--allow-incomplete]\n"
            "                [--verbose]\n"
            "       %s --config FILE [--can-file CAN.LOG [--can-file-epoch US]]\n"
            "                [--publish-every N] [--verbose]\n"
            "       %s --config FILE --replay RECORDING_DIR [--replay-without-commands]\n"
            "                [--publish-every N] [--verbose]\n"
            "Estimates the inertial parameters of the load on the robot's wrist sensor\n"
            "(Kubus, Kroeger, Wahl 2008). --offline runs the pipeline over a recording\n"
            "(can.log, lcm.log) and writes the final estimate of every configured method\n"
            "as a JSON array to OUT.json (default stdout); an incomplete recording exits 3\n"
            "(\"complete\": false) unless --allow-incomplete; --trace writes every method's\n"
            "estimate every N-th sample (--publish-every, default 10) and the final ones as\n"
            "CSV (t_s since START, method, valid, samples, mass, com, inertia about the COM,\n"
            "phi, phi_std, offset, the newest sample's wrench and motion, and the residual\n"
            "wrench the estimate leaves on it). Without --offline it runs live:\n"
            "LCM in and out, JR3 frames from SocketCAN or a candump log (--can-file),\n"
            "or a Modbus F/T sensor (sensor.type modbus). --publish-every overrides\n"
            "estimation.publish_every. --replay runs live on a recording instead, without\n"
            "CAN: its JR3 frames, joint states and commands (unless\n"
            "--replay-without-commands) replayed in real time in the daemon, the times\n"
            "shifted to now; LCM joint states are then not read; LCM output and LCM\n"
            "commands as live.\n",
            prog, prog, prog);
}

static int verbose;

static void log_line(void *ctx, const char *msg) {
    (void)ctx;
    if (verbose || strncmp(msg, "warning: ", 9) == 0) fprintf(stderr, "%s: %s\n", prog, msg);
}

/* The sinks' context offline. */
typedef struct {
    loadid_trace_csv_t *trace;          /* NULL without --trace */
    const loadid_offline_report_t *rep; /* its t_first_us: the recording's start */
} offline_ctx_t;

/* A state change with its time in seconds since the recording's first
 * event (the trace counts its own from START). A failure's reason is in
 * the final message; here with --verbose only. */
static void state_line(void *ctx, int64_t utime, int state, const char *reason) {
    const offline_ctx_t *c = ctx;
    if (c->trace && state == LOADID_STATE_ESTIMATING) loadid_trace_csv_start(c->trace, utime);
    const int64_t t0 = c->rep->t_first_us == INT64_MIN ? utime : c->rep->t_first_us;
    if (verbose)
        fprintf(stderr, "%s: %.6f s: %s%s%s\n", prog, (double)(utime - t0) / 1e6,
                loadid_lcm_state_name(state), *reason ? ": " : "", reason);
}

static void trace_row(void *ctx, const loadid_pipeline_estimate_t *e) {
    loadid_trace_csv_row(((const offline_ctx_t *)ctx)->trace, e);
}

/* What reading lcm.log found: damage passed over, a truncated end,
 * messages that could not be decoded. One warning line each. */
static void lcm_warnings(const char *dir, const loadid_offline_report_t *r) {
    const loadid_eventlog_stats_t *l = &r->lcm;
    if (l->damaged)
        fprintf(stderr,
                "%s: warning: %s/lcm.log: damaged in %lld place%s, %lld bytes skipped; "
                "the first: %s\n",
                prog, dir, (long long)l->damaged, l->damaged == 1 ? "" : "s",
                (long long)l->skipped_bytes, l->first_problem);
    if (l->truncated)
        fprintf(stderr,
                "%s: warning: %s/lcm.log: cut short: the file ends inside its last event "
                "(at byte %lld of %lld)\n",
                prog, dir, (long long)l->truncated_at, (long long)l->size);
    if (l->oversized)
        fprintf(stderr, "%s: warning: %s/lcm.log: %lld events of more than %u bytes passed over\n",
                prog, dir, (long long)l->oversized, (unsigned)LOADID_EVENTLOG_DATA_MAX);
    const int64_t bad = r->joint_states_bad + r->commands_bad;
    if (bad)
        fprintf(stderr,
                "%s: warning: %s/lcm.log: %lld of %lld joint states and %lld of %lld "
                "commands could not be decoded; the first: %s\n",
                prog, dir, (long long)r->joint_states_bad, (long long)r->joint_states,
                (long long)r->commands_bad, (long long)r->commands, r->first_bad);
}

/* Why no estimation ran (START never started one), in one line. */
static void why_not_started(const loadid_config_t *cfg, const loadid_offline_report_t *r,
                            const loadid_pipeline_status_t *st, char *out, size_t len) {
    if (st->state == LOADID_STATE_FAILED) {
        snprintf(out, len, "%s", st->reason);
        return;
    }
    char channel[128];
    loadid_config_channel(cfg, "LOADID_COMMAND", channel, sizeof channel);
    int n = r->starts ? snprintf(out, len, "START came, but no estimation ran")
                      : snprintf(out, len, "no START command on %s in lcm.log", channel);
    if (r->commands_bad && n > 0 && (size_t)n < len)
        n += snprintf(out + n, len - (size_t)n, "; %lld command%s could not be decoded",
                      (long long)r->commands_bad, r->commands_bad == 1 ? "" : "s");
    if (r->lcm.truncated && n > 0 && (size_t)n < len)
        n += snprintf(out + n, len - (size_t)n, "; lcm.log is cut short at byte %lld",
                      (long long)r->lcm.truncated_at);
    if (r->lcm.damaged && n > 0 && (size_t)n < len)
        snprintf(out + n, len - (size_t)n, "; lcm.log is damaged (%lld bytes skipped)",
                 (long long)r->lcm.skipped_bytes);
}

/* trace_path NULL: no trace, and nothing published before DONE (the
 * result as it always was); else estimates every publish_every-th sample. */
static int run_offline(const loadid_config_t *cfg, const loadid_chain_t *chain, const char *dir,
                       const char *result_path, const char *trace_path, int publish_every,
                       int allow_incomplete) {
    char err[4400];
    loadid_trace_csv_t trace;
    if (trace_path && loadid_trace_csv_open(&trace, trace_path, err, sizeof err) != 0) {
        fprintf(stderr, "%s: --trace: %s\n", prog, err);
        return 1;
    }
    loadid_offline_report_t rep;
    memset(&rep, 0, sizeof rep);
    rep.t_first_us = INT64_MIN;
    offline_ctx_t ctx = {.trace = trace_path ? &trace : NULL, .rep = &rep};
    loadid_pipeline_sink_t sink = {.ctx = &ctx, .log = log_line, .state = state_line};
    if (trace_path) sink.estimate = trace_row;
    loadid_pipeline_t *p = NULL;
    int rc = loadid_pipeline_create(cfg, chain, &sink, trace_path ? publish_every : 0, &p, err,
                                    sizeof err);
    /* The trace shows each estimate with its standard deviations and the
     * residual wrench it leaves on the newest sample. */
    if (rc == 0 && trace_path) {
        loadid_pipeline_std_always(p, 1);
        loadid_pipeline_trace_rows(p, 1);
    }
    if (rc == 0) rc = loadid_offline_run(p, dir, &rep, err, sizeof err);
    if (rc != 0) {
        fprintf(stderr, "%s: %s\n", prog, err);
        loadid_pipeline_destroy(p);
        if (trace_path) loadid_trace_csv_close(&trace, err, sizeof err);
        return 1;
    }
    lcm_warnings(dir, &rep);
    loadid_pipeline_status_t st;
    loadid_pipeline_status(p, &st);
    if (verbose)
        fprintf(stderr,
                "%s: samples ok %lld, used %lld, frames bad %lld, incomplete %lld, saturated %lld, "
                "faulty %lld, gaps %lld, joint msgs bad %lld, stale %lld, joint stamp restarts "
                "%lld\n",
                prog, (long long)st.samples_ok, (long long)st.samples_used,
                (long long)st.frames_bad, (long long)st.samples_incomplete,
                (long long)st.samples_saturated, (long long)st.samples_faulty,
                (long long)st.sequence_gaps, (long long)st.joint_msgs_bad,
                (long long)st.samples_stale, (long long)st.joint_stamp_restarts);
    if (verbose)
        fprintf(stderr,
                "%s: lcm.log: %lld events (joint states %lld, commands %lld, other %lld), "
                "damaged %lld (%lld bytes skipped), %s\n",
                prog, (long long)rep.lcm.events, (long long)rep.joint_states,
                (long long)rep.commands, (long long)rep.other_events, (long long)rep.lcm.damaged,
                (long long)rep.lcm.skipped_bytes, rep.lcm.truncated ? "cut short" : "complete");
    const loadid_noise_levels_t *l = &st.noise;
    const int started = loadid_pipeline_started(p);
    if (verbose && started)
        fprintf(stderr,
                "%s: noise levels (channels from %s): f %.3g N, tau %.3g N m, a - g %.3g m/s^2, "
                "alpha %.3g rad/s^2, omega %.3g rad/s\n",
                prog, loadid_noise_source_name(l->channel_source), l->force, l->torque, l->spec,
                l->alpha, l->omega);
    /* Incomplete (docs/INTERFACE.md): no START or ZERO, the window cut short or
     * without data; FAILED is always one of these. */
    char why[320] = "";
    if (!started)
        why_not_started(cfg, &rep, &st, why, sizeof why);
    else if (!st.complete)
        snprintf(why, sizeof why, "%s", st.incomplete_reason[0] ? st.incomplete_reason : st.reason);
    loadid_pipeline_estimate_t fin;
    loadid_pipeline_compensation_t comp;
    char path[4400];
    if (started && st.complete && cfg->results_directory[0] &&
        loadid_pipeline_final(p, &fin, &comp) == 0) {
        if (loadid_saved_result_write(cfg->results_directory, &fin, &comp, path, sizeof path, err,
                                      sizeof err) != 0)
            fprintf(stderr, "%s: %s\n", prog, err);
        else if (verbose)
            fprintf(stderr, "%s: saved %s\n", prog, path);
    }
    loadid_pipeline_estimate_t est[LOADID_MAX_METHODS];
    const int n = loadid_pipeline_estimates(p, est, LOADID_MAX_METHODS);
    for (int i = 0; i < n && !started; ++i)
        snprintf(est[i].why, sizeof est[i].why, "no estimation ran");
    st.complete = started && st.complete;
    loadid_refined_report_t ref;
    const int have_ref = loadid_pipeline_refined_report(p, &ref) == 0;
    int status = 0;
    FILE *out = result_path ? fopen(result_path, "w") : stdout;
    if (!out || loadid_result_json_write(out, est, n, &st, have_ref ? &ref : NULL) != 0 ||
        (result_path && fclose(out) != 0)) {
        fprintf(stderr, "%s: cannot write %s: %s\n", prog, result_path ? result_path : "stdout",
                strerror(errno));
        status = 1;
    } else if (!st.complete) {
        fprintf(stderr, "%s: %s: incomplete recording: %s%s\n", prog, dir, why,
                allow_incomplete ? " (allowed)" : "");
        if (!allow_incomplete) status = 3;
    }
    loadid_pipeline_destroy(p);
    if (trace_path && loadid_trace_csv_close(&trace, err, sizeof err) != 0) {
        fprintf(stderr, "%s: --trace: %s\n", prog, err);
        if (status == 0 || status == 3) status = 1;
    }
    return status;
}

int main(int argc, char **argv) {
    const char *config_path = NULL, *offline = NULL, *result = NULL, *can_file = NULL;
    const char *trace = NULL, *replay = NULL;
    int replay_commands = 1;
    int publish_every = 0; /* 0: estimation.publish_every (live), 10 (--trace) */
    int allow_incomplete = 0;
    long long epoch = 0;
    static const struct option opts[] = {{"config", required_argument, NULL, 'c'},
                                         {"offline", required_argument, NULL, 'o'},
                                         {"result", required_argument, NULL, 'r'},
                                         {"verbose", no_argument, NULL, 'v'},
                                         {"can-file", required_argument, NULL, 'f'},
                                         {"publish-every", required_argument, NULL, 'p'},
                                         {"can-file-epoch", required_argument, NULL, 'e'},
                                         {"allow-incomplete", no_argument, NULL, 'a'},
                                         {"trace", required_argument, NULL, 't'},
                                         {"replay", required_argument, NULL, 'R'},
                                         {"replay-without-commands", no_argument, NULL, 'W'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "c:o:r:vh", opts, NULL)) != -1) {
        switch (c) {
            case 'c':
                config_path = optarg;
                break;
            case 'o':
                offline = optarg;
                break;
            case 'r':
                result = optarg;
                break;
            case 'v':
                verbose = 1;
                break;
            case 'f':
                can_file = optarg;
                break;
            case 'e':
                if (loadid_arg_integer(optarg, 0, LLONG_MAX, &epoch) != 0) {
                    fprintf(stderr,
                            "%s: --can-file-epoch: wall time in microseconds since 1970 "
                            "(0: now), not %s\n",
                            prog, optarg);
                    return 2;
                }
                break;
            case 'a':
                allow_incomplete = 1;
                break;
            case 't':
                trace = optarg;
                break;
            case 'R':
                replay = optarg;
                break;
            case 'W':
                replay_commands = 0;
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
            case 'h':
                usage(stdout);
                return 0;
            default:
                usage(stderr);
                return 2;
        }
    }
    if (optind != argc) {
        /* A recording named without --offline, most likely. */
        fprintf(stderr, "%s: unexpected argument %s%s\n", prog, argv[optind],
                offline ? "" : " (a recording is read with --offline DIR)");
        return 2;
    }
    if (!config_path) {
        fprintf(stderr, "%s: --config FILE is required\n", prog);
        usage(stderr);
        return 2;
    }
    if (allow_incomplete && !offline) {
        fprintf(stderr, "%s: --allow-incomplete needs --offline\n", prog);
        return 2;
    }
    if (result && !offline) {
        fprintf(stderr, "%s: --result needs --offline\n", prog);
        return 2;
    }
    if (trace && !offline) {
        fprintf(stderr, "%s: --trace needs --offline\n", prog);
        return 2;
    }
    if (replay && (offline || can_file)) {
        fprintf(stderr, "%s: --replay runs live on a recording: not with %s\n", prog,
                offline ? "--offline" : "--can-file");
        return 2;
    }
    if (!replay_commands && !replay) {
        fprintf(stderr, "%s: --replay-without-commands needs --replay\n", prog);
        return 2;
    }
    static loadid_config_t cfg;
    loadid_chain_t chain;
    char setup_err[1200];
    if (loadid_setup_load(config_path, &cfg, &chain, warn_line, NULL, setup_err,
                          sizeof setup_err) != 0) {
        fprintf(stderr, "%s: %s\n", prog, setup_err);
        return 1;
    }
    if (!offline) {
        loadid_live_options_t live = {
            .can_file = can_file,
            .can_file_epoch = epoch,
            .replay = replay,
            .replay_commands = replay_commands,
            .publish_every = publish_every ? publish_every : cfg.publish_every,
            .verbose = verbose};
        return loadid_live_run(&cfg, &chain, &live);
    }
    return run_offline(&cfg, &chain, offline, result, trace, publish_every ? publish_every : 10,
                       allow_incomplete);
}
