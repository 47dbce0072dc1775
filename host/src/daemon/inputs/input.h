/*
 * A sensor input of the daemon's loop: one small interface, one backend a
 * file, in the manner of libmodbus' context (a struct of the backend's
 * functions, a context that carries them and the backend's own state):
 *
 *   jr3_socketcan.c   JR3 frames from SocketCAN (can.interface)
 *   jr3_candump.c     JR3 frames from a candump log in real time (--can-file)
 *   modbus_rtu.c      the Modbus RTU F/T sensor (sensor.type modbus), polled
 *                     by its own thread (modbus_input.h)
 *   replay.c          a whole recording in real time (--replay): its JR3
 *                     frames, joint states and commands
 *
 * The loop waits on the input's file descriptor and calls read when it is
 * readable; the input hands what it has to the pipeline (frames, samples,
 * and for a replay joint states and commands too). Each backend owns its
 * counters and gives them in one form (loadid_input_counters_t), which
 * status.c maps into status_t with the pipeline's. Samples handled more
 * than 1 ms after their arrival are counted here, for every backend that
 * knows when its samples arrived.
 *
 * After open nothing here allocates (the loop's no-allocation rule).
 */
#ifndef LOADID_INPUT_H
#define LOADID_INPUT_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/config.h"
#include "loadid/pipeline.h"

/* What an input counts, in one form for status_t and the log. */
typedef struct {
    int64_t frames_bad;         /* status_t.frames_bad, besides the pipeline's: bad
                                    frames the pipeline never saw (CAN error frames;
                                    the Modbus sensor's bad answers, exceptions,
                                    malformed blocks) */
    int64_t samples_incomplete; /* status_t.samples_incomplete, besides the
                                    pipeline's: reads without an answer */
    int64_t errors;             /* the input failed and is reopened ("CAN errors") */
    int64_t drops;              /* frames the kernel dropped ("CAN drops") */
    int64_t error_frames;       /* CAN error frames ("error frames"; in frames_bad) */
    int late_measured;          /* the backend knows its samples' arrival */
    int64_t samples_late;       /* handled more than LOADID_INPUT_LATE_US after arrival */
    double late_max_us;         /* the worst lateness of any sample */
} loadid_input_counters_t;

#define LOADID_INPUT_LATE_US 1000.0 /* a sample's deadline after its arrival */

/* What a backend is told besides the configuration. */
typedef struct {
    const char *path;  /* jr3_candump: the log; replay: the folder */
    int64_t epoch_us;  /* jr3_candump: the wall time of the first frame;
                                    replay: of the first event; 0: now */
    int with_commands; /* replay: its command_t events act too */
} loadid_input_options_t;

typedef struct loadid_input loadid_input_t;

typedef struct {
    const char *name;
    /* Opens the device or file, allocating what it needs; may hand what is
     * already due to the pipeline. Returns 0, or a negative code with a
     * one-line reason in err. */
    int (*open)(loadid_input_t *in, const loadid_input_options_t *opt, char *err, size_t errlen);
    /* The descriptor the loop waits on; -1 while there is none (a CAN
     * interface gone, to be reopened by second). */
    int (*fd)(const loadid_input_t *in);
    /* The descriptor is readable: hands what is due to the pipeline. */
    void (*read)(loadid_input_t *in);
    /* May be NULL. Before the clock's tick: hands what is due by now, so
     * the clock never judges the pipeline ahead of an input it paces
     * itself (a replay whose timer waits behind the tick). */
    void (*catch_up)(loadid_input_t *in);
    /* May be NULL. Once a second: reopen what was lost, log what grew. */
    void (*second)(loadid_input_t *in);
    /* May be NULL. At the stop, before the summary: what happened since
     * the last second. */
    void (*finish)(loadid_input_t *in);
    /* Its counters (the lateness fields are kept by input.c). */
    void (*counters)(const loadid_input_t *in, loadid_input_counters_t *c);
    /* May be NULL. --verbose at exit: its own counters, logged. */
    void (*summary)(const loadid_input_t *in);
    /* Frees everything; called after a failed open too. */
    void (*close)(loadid_input_t *in);
} loadid_input_backend_t;

/* The context: the backend, where its samples go, and its state. */
struct loadid_input {
    const loadid_input_backend_t *backend;
    const loadid_config_t *cfg;
    loadid_pipeline_t *pipe;
    void *state; /* the backend's own */
    /* lateness (input.c) */
    int late_measured;
    int64_t samples_late, late_logged;
    double late_max_us, late_warned_us;
};

/* The four backends. */
extern const loadid_input_backend_t loadid_input_jr3_socketcan;
extern const loadid_input_backend_t loadid_input_jr3_candump;
extern const loadid_input_backend_t loadid_input_modbus_rtu;
extern const loadid_input_backend_t loadid_input_replay;

/* Creates and opens in (the context is static: one input per daemon).
 * Returns 0, or a negative code with a one-line reason in err (and in is
 * closed). */
int loadid_input_open(loadid_input_t *in, const loadid_input_backend_t *backend,
                      const loadid_config_t *cfg, loadid_pipeline_t *pipe,
                      const loadid_input_options_t *opt, char *err, size_t errlen);
int loadid_input_fd(const loadid_input_t *in);
void loadid_input_read(loadid_input_t *in);
void loadid_input_catch_up(loadid_input_t *in);
void loadid_input_second(loadid_input_t *in);
void loadid_input_finish(loadid_input_t *in);
void loadid_input_counters(const loadid_input_t *in, loadid_input_counters_t *c);
void loadid_input_summary(const loadid_input_t *in);
void loadid_input_close(loadid_input_t *in);

/* For the backends: a sample was handed to the pipeline late_us after it
 * arrived. More than LOADID_INPUT_LATE_US is a missed deadline: counted,
 * logged at most once a second while the count grows. */
void loadid_input_late(loadid_input_t *in, double late_us);

#endif /* LOADID_INPUT_H */
