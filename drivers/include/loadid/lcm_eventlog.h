/*
 * loadid drivers: a reader of LCM event logs (lcm-logger's format, the
 * lcm.log of a recording) that trusts no byte of the file. Every event is
 *
 *   uint32 sync word 0xEDA1DA01, int64 event number, int64 time stamp [us],
 *   int32 channel length, int32 data length, the channel (no NUL), the data
 *
 * big-endian, back to back. liblcm's own reader allocates what a length
 * field says (a flipped bit asks for 2 GiB) and prints unprefixed lines on
 * stderr; this one allocates one buffer at open and nothing per event, and
 * says what it found, with the byte offset, in its statistics.
 *
 * A header is plausible when the sync word is there, 1 <= channel length
 * <= LOADID_EVENTLOG_CHANNEL_MAX, data length >= 0 and the channel is
 * printable ASCII. A plausible event is taken when the next event's sync
 * word (or the end of the file) follows it, or when no plausible header
 * starts inside it; otherwise its length is taken for damage. Where the
 * bytes are not an event (a wrong sync word, an implausible or damaged
 * header) the reader searches the following bytes for the next plausible
 * header, and counts the bytes it passed over. Events with more than
 * data_max bytes of data are passed over and counted (oversized). A last
 * event the file ends inside is reported as truncated.
 *
 * The file must be seekable (a regular file, or fmemopen() for a fuzz
 * harness or a test): the reader looks ahead and goes back.
 *
 * Return convention (loadid/error_text.h): 0 or a count on success, a negated errno
 * or a LOADID_EVENTLOG_E_* code otherwise; loadid_eventlog_strerror()
 * names each.
 */
#ifndef LOADID_LCM_EVENTLOG_H
#define LOADID_LCM_EVENTLOG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_EVENTLOG_SYNC 0xEDA1DA01u
#define LOADID_EVENTLOG_HEADER 28       /* bytes before the channel */
#define LOADID_EVENTLOG_CHANNEL_MAX 256 /* longest channel name [bytes] */
/* The default data_max [bytes]: far above loadid's largest message
 * (LOADID_LCM_ESTIMATE_MAX, under 400 bytes), so that a log recorded with
 * other channels (loadid-record --all-channels) reads too. */
#define LOADID_EVENTLOG_DATA_MAX (1u << 20)
#define LOADID_EVENTLOG_PROBLEM_MAX 200 /* room of a problem's text */

enum loadid_eventlog_error {
    LOADID_EVENTLOG_E_NOT_LOG = -1301, /* not an LCM log: byte 0 is not the
                                              sync word, and no plausible event
                                              is anywhere in the file */
    LOADID_EVENTLOG_E_SEEK = -1302     /* open: the file is not seekable */
};

typedef struct {
    int64_t eventnum;    /* as lcm-logger numbered it (not checked) */
    int64_t timestamp;   /* [us] the time lcm-logger received it */
    const char *channel; /* NUL-terminated; valid until the next call */
    int32_t channel_len; /* 1 .. LOADID_EVENTLOG_CHANNEL_MAX */
    const uint8_t *data; /* valid until the next call */
    int32_t data_len;    /* 0 .. data_max */
    int64_t offset;      /* byte offset of its sync word in the file */
} loadid_eventlog_event_t;

typedef struct {
    int64_t size;          /* the file's size [bytes] */
    int64_t events;        /* events handed out */
    int64_t oversized;     /* plausible events with more than data_max
                                 bytes of data, passed over */
    int64_t damaged;       /* places where the bytes were not an event
                                 (a wrong sync word, an implausible or
                                 damaged header), each searched past */
    int64_t skipped_bytes; /* bytes passed over in those searches */
    int truncated;         /* 1: the file ends inside its last event */
    int64_t truncated_at;  /* that event's offset, else -1 */
    char first_problem[LOADID_EVENTLOG_PROBLEM_MAX];
    /* The first damage, truncation or failed search, e.g. "byte 1234: data
     * length 2147483647 in the event header runs past the end of the file;
     * 456 bytes skipped to the next event at byte 1690"; "" when none. */
} loadid_eventlog_stats_t;

typedef struct loadid_eventlog loadid_eventlog_t; /* opaque */

/* A reader of the event log in f from its current position (offsets count
 * from the start of f). It does not take f: the caller closes f after
 * loadid_eventlog_close. data_max: the longest data it hands out [bytes],
 * 0 for LOADID_EVENTLOG_DATA_MAX; its buffer (data_max plus the header and
 * channel) is the only allocation. Returns 0, -EINVAL (NULL argument,
 * data_max above INT32_MAX), -ENOMEM, LOADID_EVENTLOG_E_SEEK, or -errno. */
int loadid_eventlog_open(FILE *f, size_t data_max, loadid_eventlog_t **out);

void loadid_eventlog_close(loadid_eventlog_t *r);

/* The next event. Returns 1 with *ev filled (its pointers valid until the
 * next call), 0 at the end of the log (also after a truncated last event
 * or damage that runs to the end), LOADID_EVENTLOG_E_NOT_LOG (the first
 * call only; the reason with its offset in loadid_eventlog_error), or -EIO
 * on a read error. An error is repeated by every later call. */
int loadid_eventlog_next(loadid_eventlog_t *r, loadid_eventlog_event_t *ev);

/* What the reader has found so far. */
void loadid_eventlog_stats(const loadid_eventlog_t *r, loadid_eventlog_stats_t *st);

/* After LOADID_EVENTLOG_E_NOT_LOG or -EIO: the reason in one line with its
 * byte offset, e.g. "not an LCM log: byte 0 holds 0x7f454c46, not the sync
 * word 0xEDA1DA01, and no event follows in its 14328 bytes"; else "". */
const char *loadid_eventlog_error(const loadid_eventlog_t *r);

/* A static text for any return code of this module (or a negated errno).
 * Never NULL. */
const char *loadid_eventlog_strerror(int code);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_LCM_EVENTLOG_H */
