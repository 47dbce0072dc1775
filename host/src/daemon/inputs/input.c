/* The sensor inputs' shared part (input.h): dispatch to the backend, and
 * the deadline count every backend that knows its samples' arrival uses. */
#include "input.h"

#include <string.h>

#include "../clock.h"
#include "../log.h"

int loadid_input_open(loadid_input_t *in, const loadid_input_backend_t *backend,
                      const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                      const loadid_input_options_t *opt, char *err, size_t errlen) {
    memset(in, 0, sizeof *in);
    in->backend = backend;
    in->cfg = cfg;
    in->pipe = pipe;
    const int rc = backend->open(in, opt, err, errlen);
    if (rc != 0) loadid_input_close(in);
    return rc;
}

int loadid_input_fd(const loadid_input_t *in) {
    return in->backend ? in->backend->fd(in) : -1;
}

void loadid_input_read(loadid_input_t *in) {
    if (in->backend) in->backend->read(in);
}

void loadid_input_catch_up(loadid_input_t *in) {
    if (in->backend && in->backend->catch_up) in->backend->catch_up(in);
}

void loadid_input_second(loadid_input_t *in) {
    if (in->backend && in->backend->second) in->backend->second(in);
}

void loadid_input_finish(loadid_input_t *in) {
    if (in->backend && in->backend->finish) in->backend->finish(in);
}

void loadid_input_counters(const loadid_input_t *in, loadid_input_counters_t *c) {
    memset(c, 0, sizeof *c);
    if (in->backend) in->backend->counters(in, c);
    c->late_measured = in->late_measured;
    c->samples_late = in->samples_late;
    c->late_max_us = in->late_max_us;
}

void loadid_input_summary(const loadid_input_t *in) {
    if (in->backend && in->backend->summary) in->backend->summary(in);
}

void loadid_input_close(loadid_input_t *in) {
    if (in->backend) in->backend->close(in);
    in->backend = NULL;
}

/* Deadlines: late_us is how long after its arrival a sample was handled
 * (taken in by the pipeline: decoded, counted, queued for the joint data
 * the fixed-lag smoother waits for, which is by design and not lateness). */
void loadid_input_late(loadid_input_t *in, double late_us) {
    if (late_us > in->late_max_us) in->late_max_us = late_us;
    if (late_us <= LOADID_INPUT_LATE_US) return;
    in->samples_late++;
    const double now = loadid_mono_us();
    if (now - in->late_warned_us >= 1e6) {
        loadidd_log(
            "%lld samples handled more than %.0f ms after arrival so far "
            "(%lld new, worst %.0f us)",
            (long long)in->samples_late, LOADID_INPUT_LATE_US / 1e3,
            (long long)(in->samples_late - in->late_logged), in->late_max_us);
        in->late_logged = in->samples_late;
        in->late_warned_us = now;
    }
}
