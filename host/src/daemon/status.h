/*
 * What the daemon reports of itself: status_t (docs/INTERFACE.md), whose
 * counters come from the pipeline and the sensor input through one
 * mapping here, with the loop's time per input event over the last
 * second; and --verbose's summary of every counter at exit.
 */
#ifndef LOADID_STATUS_H
#define LOADID_STATUS_H

#include <stdint.h>

#include "inputs/input.h"
#include "loadid/lcm_wire.h"
#include "loadid/pipeline.h"

#define LOADID_LOOP_TIME_BINS 20001 /* 0.5 us bins up to 10 ms; the last holds the rest */

/* The loop's time per input event (a CAN read, an LCM message, which is
 * where waiting samples are estimated, or a tick), as a histogram. */
typedef struct {
    uint32_t hist[LOADID_LOOP_TIME_BINS];
    double max_us;
} loadid_loop_times_t;

void loadid_loop_times_add(loadid_loop_times_t *t, double us);

/* status_t: state and utime as given, the counters of the pipeline and the
 * input, the loop times' p50, p99 and max since they were last cleared
 * (clear: cleared now, at the end of a 1 Hz status's second). */
void loadid_status_make(const loadid_pipeline_status_t *st, const loadid_input_counters_t *in,
                        loadid_loop_times_t *times, int clear, int64_t utime, int state,
                        loadid_lcm_status_t *m);

/* --verbose at exit: the pipeline's and the input's counters and the
 * commands refused (lcm.command_sources), then the deadline's count where
 * the input measures it. */
void loadid_status_summary(const loadid_pipeline_status_t *st, const loadid_input_counters_t *in,
                           int64_t commands_refused);

#endif /* LOADID_STATUS_H */
