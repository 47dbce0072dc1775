/* status_t and the counters' summary (status.h). */
#include "status.h"

#include <string.h>

#include "log.h"

void loadid_loop_times_add(loadid_loop_times_t *t, double us) {
    const int bin = (int)(us * 2);
    t->hist[bin < LOADID_LOOP_TIME_BINS ? bin : LOADID_LOOP_TIME_BINS - 1]++;
    if (us > t->max_us) t->max_us = us;
}

static void percentiles(const loadid_loop_times_t *t, double *p50, double *p99, double *max) {
    uint64_t n = 0;
    for (int i = 0; i < LOADID_LOOP_TIME_BINS; ++i) n += t->hist[i];
    *p50 = *p99 = 0;
    *max = t->max_us;
    if (!n) return;
    uint64_t acc = 0, k50 = (n + 1) / 2, k99 = (n * 99 + 99) / 100;
    int got50 = 0;
    for (int i = 0; i < LOADID_LOOP_TIME_BINS; ++i) {
        acc += t->hist[i];
        if (!got50 && acc >= k50) *p50 = (i + 0.5) * 0.5, got50 = 1;
        if (acc >= k99) {
            *p99 = (i + 0.5) * 0.5;
            return;
        }
    }
}

void loadid_status_make(const loadid_pipeline_status_t *st, const loadid_input_counters_t *in,
                        loadid_loop_times_t *times, int clear, int64_t utime, int state,
                        loadid_lcm_status_t *m) {
    memset(m, 0, sizeof *m);
    m->utime = utime;
    m->state = (int8_t)state;
    m->samples_ok = st->samples_ok;
    /* Bad frames the pipeline never saw: CAN error frames, the serial
     * sensor's bad answers and exceptions (inputs/input.h). */
    m->frames_bad = st->frames_bad + in->frames_bad;
    /* The serial sensor's transactions without an answer. */
    m->samples_incomplete = st->samples_incomplete + in->samples_incomplete;
    /* status_t has no field for faults: a sample saturated or faulty (or
     * both, counted once) never reaches an estimator (docs/INTERFACE.md). */
    m->samples_saturated = st->samples_rejected;
    m->sequence_gaps = st->sequence_gaps;
    m->joint_msgs_bad = st->joint_msgs_bad;
    percentiles(times, &m->loop_us_p50, &m->loop_us_p99, &m->loop_us_max);
    if (clear) memset(times, 0, sizeof *times);
}

void loadid_status_summary(const loadid_pipeline_status_t *st, const loadid_input_counters_t *in,
                           int64_t commands_refused) {
    loadidd_log(
        "samples ok %lld, used %lld, frames bad %lld, incomplete %lld, saturated %lld, "
        "faulty %lld, gaps %lld, joint msgs bad %lld, stale %lld, CAN errors %lld, "
        "CAN drops %lld, error frames %lld, joint stamp restarts %lld, commands refused %lld",
        (long long)st->samples_ok, (long long)st->samples_used, (long long)st->frames_bad,
        (long long)st->samples_incomplete, (long long)st->samples_saturated,
        (long long)st->samples_faulty, (long long)st->sequence_gaps, (long long)st->joint_msgs_bad,
        (long long)st->samples_stale, (long long)in->errors, (long long)in->drops,
        (long long)in->error_frames, (long long)st->joint_stamp_restarts,
        (long long)commands_refused);
    if (in->late_measured) /* every backend measures it */
        loadidd_log(
            "samples late %lld (handled more than %.0f ms after arrival), worst "
            "lateness %.0f us",
            (long long)in->samples_late, LOADID_INPUT_LATE_US / 1e3, in->late_max_us);
}
