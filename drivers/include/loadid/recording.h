/*
 * Reads a recording folder (DESIGN.md): can.log (candump format) and
 * lcm.log (an LCM event log) merged into one stream of events in time
 * order, as they would have arrived live. Used by the offline pipeline and
 * the analysis tools. Allocates at open; reading is sequential.
 *
 * A bad can.log line is handed on as an event of kind LOADID_REC_BAD_LINE
 * (with its line number and the candump error) so the caller can count it
 * as a bad frame and go on; a truncated or corrupt lcm.log ends the LCM
 * stream early, which loadid_recording_lcm_truncated() reports.
 */
#ifndef LOADID_RECORDING_H
#define LOADID_RECORDING_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/can_frame.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    LOADID_REC_CAN = 1,       /* a frame of can.log */
    LOADID_REC_LCM = 2,       /* an event of lcm.log */
    LOADID_REC_BAD_LINE = 3   /* a can.log line that is not a frame */
} loadid_rec_kind_t;

typedef struct {
    loadid_rec_kind_t kind;
    int64_t t_us;             /* CAN: receive time; LCM: the event's time */
    loadid_can_frame_t can;   /* LOADID_REC_CAN */
    const char *channel;      /* LOADID_REC_LCM: valid until the next call */
    const uint8_t *data;      /* LOADID_REC_LCM: the encoded message */
    int datalen;
    long line;                /* LOADID_REC_CAN, _BAD_LINE: line in can.log */
    int error;                /* LOADID_REC_BAD_LINE: the candump error code */
} loadid_rec_event_t;

typedef struct loadid_recording_reader loadid_recording_reader_t; /* opaque */

/* Opens dir/can.log and dir/lcm.log (both must exist). Returns 0, or
 * -errno with "DIR/FILE: cannot read: reason" in err. */
int loadid_recording_reader_open(const char *dir, loadid_recording_reader_t **out, char *err,
                                 size_t errlen);

void loadid_recording_reader_close(loadid_recording_reader_t *r);

/* The next event in time order (an LCM event before a CAN frame of the
 * same time). Returns 1 with *ev filled, 0 at the end of both files,
 * -EIO on a read error of can.log. */
int loadid_recording_reader_next(loadid_recording_reader_t *r, loadid_rec_event_t *ev);

/* 1 when lcm.log ended in a partial or corrupt event (the stream stopped
 * there), else 0. */
int loadid_recording_lcm_truncated(const loadid_recording_reader_t *r);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_RECORDING_H */
