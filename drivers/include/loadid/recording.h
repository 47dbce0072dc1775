/*
 * Reads a recording folder (docs/INTERFACE.md): can.log (candump format) and
 * lcm.log (an LCM event log) merged into one stream of events in time
 * order, as they would have arrived live. Used by the offline pipeline and
 * the analysis tools. Allocates at open; reading is sequential.
 *
 * A bad can.log line is handed on as an event of kind LOADID_REC_BAD_LINE
 * (with its line number and the candump error) so the caller can count it
 * as a bad frame and go on. lcm.log is read by the project's own event-log
 * reader (lcm_eventlog.h): damage is passed over to the next event and
 * counted, a truncated last event ends the LCM stream, and both are in
 * loadid_recording_lcm_stats() with their byte offsets.
 */
#ifndef LOADID_RECORDING_H
#define LOADID_RECORDING_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/can_frame.h"
#include "loadid/lcm_eventlog.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    LOADID_REC_CAN = 1,     /* a frame of can.log */
    LOADID_REC_LCM = 2,     /* an event of lcm.log */
    LOADID_REC_BAD_LINE = 3 /* a can.log line that is not a frame */
} loadid_rec_kind_t;

typedef struct {
    loadid_rec_kind_t kind;
    int64_t t_us;           /* CAN: receive time; LCM: the event's time */
    loadid_can_frame_t can; /* LOADID_REC_CAN */
    const char *channel;    /* LOADID_REC_LCM: valid until the next call */
    const uint8_t *data;    /* LOADID_REC_LCM: the encoded message */
    int datalen;
    int64_t offset; /* LOADID_REC_LCM: the event's byte offset in lcm.log */
    long line;      /* LOADID_REC_CAN, _BAD_LINE: line in can.log */
    int error;      /* LOADID_REC_BAD_LINE: the candump error code */
} loadid_rec_event_t;

typedef struct loadid_recording_reader loadid_recording_reader_t; /* opaque */

/* Opens dir/can.log and dir/lcm.log (both must exist) and reads the first
 * event of each. Returns 0, or -errno with "DIR/FILE: cannot read: reason"
 * in err; -EBADMSG with "DIR/lcm.log: not an LCM log: byte 0 holds ..."
 * when lcm.log holds no LCM event at all. */
int loadid_recording_reader_open(const char *dir, loadid_recording_reader_t **out, char *err,
                                 size_t errlen);

void loadid_recording_reader_close(loadid_recording_reader_t *r);

/* The next event in time order (an LCM event before a CAN frame of the
 * same time). Returns 1 with *ev filled (channel and data valid until the
 * next call), 0 at the end of both files, -EIO on a read error (of lcm.log
 * when loadid_recording_lcm_error says so, else of can.log). */
int loadid_recording_reader_next(loadid_recording_reader_t *r, loadid_rec_event_t *ev);

/* What reading lcm.log has found so far: events, damage passed over,
 * bytes skipped, a truncated last event, the first problem with its byte
 * offset. */
void loadid_recording_lcm_stats(const loadid_recording_reader_t *r, loadid_eventlog_stats_t *st);

/* After a read error of lcm.log: the reason with its byte offset; else "". */
const char *loadid_recording_lcm_error(const loadid_recording_reader_t *r);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_RECORDING_H */
