/* The live service of loadidd: one epoll loop over LCM, the sensor input,
 * two timers and the termination signals, driving the pipeline (live.c). */
#ifndef LOADID_LIVE_H
#define LOADID_LIVE_H

#include "loadid/chain.h"
#include "loadid/config.h"

typedef struct {
    const char *can_file;   /* NULL: SocketCAN on can.interface; else a
                              candump log replayed in real time */
    int64_t can_file_epoch; /* wall time [us] of the file's first frame;
                               0: now */
    const char *replay;     /* a recording replayed in real time: its JR3
                              frames, joint states and commands (NULL: none) */
    int replay_commands;    /* with replay: its commands act too */
    int publish_every;      /* estimate_t after every n-th sample (>= 1) */
    int verbose;
} loadid_live_options_t;

/* Runs until SIGTERM or SIGINT (a replayed can_file or recording just
 * falls silent at its end). Returns the exit status: 0, or 1 after
 * printing why on stderr. */
int loadid_live_run(const loadid_config_t *cfg, const loadid_chain_t *chain,
                    const loadid_live_options_t *opt);

#endif /* LOADID_LIVE_H */
