/* LCM event-log reader that trusts no byte of the file (lcm_eventlog.h). */
#define _POSIX_C_SOURCE 200809L
#include "loadid/lcm_eventlog.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#define SCAN_CHUNK 4096 /* bytes searched per read while looking for a sync word */

struct loadid_eventlog {
    FILE *f;
    int64_t start; /* f's position at open: where the log begins */
    int64_t pos;   /* f's position as far as this reader knows */
    /* The last read when it was of 4 bytes or fewer (the next event's sync
     * word, read to check an event's length), while f is still just past
     * it: reading the next header from there needs no seek back. */
    int64_t held_off;
    int held_len;
    uint8_t held[4];
    int64_t next; /* where the next event should begin */
    size_t data_max;
    int error; /* sticky: LOADID_EVENTLOG_E_NOT_LOG or -EIO */
    int ended;
    char error_text[LOADID_EVENTLOG_PROBLEM_MAX + 64];
    loadid_eventlog_stats_t st;
    char channel[LOADID_EVENTLOG_CHANNEL_MAX + 1]; /* the event's */
    char probe[LOADID_EVENTLOG_CHANNEL_MAX + 1];   /* a candidate's, while searching */
    uint8_t scan[SCAN_CHUNK];
    uint8_t data[]; /* data_max bytes */
};

typedef struct {
    int64_t eventnum, timestamp;
    int32_t channel_len, data_len;
} header_t;

/* What header_at found. */
enum {
    H_OK,          /* a plausible header, its channel read */
    H_SHORT,       /* the file ends inside the header or the channel; what
                        is there is plausible */
    H_SYNC,        /* no sync word */
    H_CHANNEL_LEN, /* channel length outside 1..LOADID_EVENTLOG_CHANNEL_MAX */
    H_DATA_LEN,    /* negative data length */
    H_CHANNEL,     /* a channel byte that is not printable ASCII */
    H_IO           /* read error */
};

static uint32_t be32(const uint8_t *b) {
    return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | (uint32_t)b[3];
}

static int64_t be64(const uint8_t *b) {
    return (int64_t)((uint64_t)be32(b) << 32 | (uint64_t)be32(b + 4));
}

/* Reads up to n bytes at off; returns how many (fewer at the end of the
 * file), or -1 on a read or seek error. Bytes still held from the last
 * read are taken from there: a seek costs a system call (lseek) even
 * within stdio's buffer, one per event, which was most of --offline's
 * reading time. */
static long read_at(loadid_eventlog_t *r, int64_t off, void *dst, size_t n) {
    size_t done = 0;
    if (r->pos != off) {
        if (r->held_len > 0 && r->pos == r->held_off + r->held_len && off >= r->held_off &&
            off < r->pos) {
            done = (size_t)(r->pos - off) < n ? (size_t)(r->pos - off) : n;
            memcpy(dst, r->held + (off - r->held_off), done);
            if (done == n) return (long)n;
        } else {
            if (fseeko(r->f, (off_t)off, SEEK_SET) != 0) return -1;
            r->pos = off;
        }
    }
    const size_t got = fread((uint8_t *)dst + done, 1, n - done, r->f);
    r->pos += (int64_t)got;
    if (got < n - done && ferror(r->f)) return -1;
    r->held_len = 0;
    if (done == 0 && got <= sizeof r->held) {
        memcpy(r->held, dst, got);
        r->held_off = off;
        r->held_len = (int)got;
    }
    return (long)(done + got);
}

/* Classifies the bytes at off as an event header; on H_OK fills *h and
 * channel (room for LOADID_EVENTLOG_CHANNEL_MAX + 1, NUL-terminated).
 * *detail: the offending value for the problem's text. */
static int header_at(loadid_eventlog_t *r, int64_t off, header_t *h, char *channel,
                     uint32_t *detail) {
    uint8_t b[LOADID_EVENTLOG_HEADER];
    const long got = read_at(r, off, b, sizeof b);
    if (got < 0) return H_IO;
    static const uint8_t sync[4] = {0xED, 0xA1, 0xDA, 0x01};
    const long cmp = got < 4 ? got : 4;
    if (memcmp(b, sync, (size_t)cmp) != 0) {
        uint8_t w[4] = {0, 0, 0, 0};
        memcpy(w, b, (size_t)cmp);
        *detail = be32(w);
        return H_SYNC;
    }
    if (got < LOADID_EVENTLOG_HEADER) return H_SHORT;
    h->eventnum = be64(b + 4);
    h->timestamp = be64(b + 12);
    h->channel_len = (int32_t)be32(b + 20);
    h->data_len = (int32_t)be32(b + 24);
    if (h->channel_len < 1 || h->channel_len > LOADID_EVENTLOG_CHANNEL_MAX) {
        *detail = (uint32_t)h->channel_len;
        return H_CHANNEL_LEN;
    }
    if (h->data_len < 0) {
        *detail = (uint32_t)h->data_len;
        return H_DATA_LEN;
    }
    const long n = read_at(r, off + LOADID_EVENTLOG_HEADER, channel, (size_t)h->channel_len);
    if (n < 0) return H_IO;
    for (long i = 0; i < n; ++i) {
        const unsigned char c = (unsigned char)channel[i];
        if (c < 0x20 || c > 0x7e) {
            *detail = c;
            return H_CHANNEL;
        }
    }
    if (n < h->channel_len) return H_SHORT;
    channel[h->channel_len] = 0;
    return H_OK;
}

/* The first offset in [from, to) where a plausible header begins, or one
 * the file ends inside (H_SHORT: a truncated last event); -1 when none;
 * -2 on a read error. */
static int64_t find_event(loadid_eventlog_t *r, int64_t from, int64_t to) {
    if (to > r->st.size) to = r->st.size;
    int64_t off = from;
    while (off < to) {
        const int64_t want = to - off + 3 < SCAN_CHUNK ? to - off + 3 : SCAN_CHUNK;
        const long got = read_at(r, off, r->scan, (size_t)want);
        if (got < 0) return -2;
        if (got < 4) return -1;
        const long positions = got - 3 < to - off ? got - 3 : (long)(to - off);
        for (long i = 0; i < positions; ++i) {
            if (r->scan[i] != 0xED || be32(r->scan + i) != LOADID_EVENTLOG_SYNC) continue;
            header_t h;
            uint32_t detail;
            const int hs = header_at(r, off + i, &h, r->probe, &detail);
            if (hs == H_IO) return -2;
            if (hs == H_OK || hs == H_SHORT) return off + i;
        }
        off += positions;
    }
    return -1;
}

static void problem(loadid_eventlog_t *r, const char *fmt, ...) {
    if (r->st.first_problem[0]) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->st.first_problem, sizeof r->st.first_problem, fmt, ap);
    va_end(ap);
}

static int fail_io(loadid_eventlog_t *r, int64_t off) {
    r->error = -EIO;
    snprintf(r->error_text, sizeof r->error_text, "read error near byte %lld: %s", (long long)off,
             strerror(errno ? errno : EIO));
    return r->error;
}

/* What was wrong at off, in words. */
static void describe(int hs, uint32_t detail, char *out, size_t len) {
    switch (hs) {
        case H_SYNC:
            snprintf(out, len, "0x%08X where the sync word 0xEDA1DA01 should be", (unsigned)detail);
            return;
        case H_CHANNEL_LEN:
            snprintf(out, len, "channel length %d in an event header (1..%d)", (int)(int32_t)detail,
                     LOADID_EVENTLOG_CHANNEL_MAX);
            return;
        case H_DATA_LEN:
            snprintf(out, len, "negative data length %d in an event header", (int)(int32_t)detail);
            return;
        default:
            snprintf(out, len, "byte 0x%02X in an event's channel name", (unsigned)detail);
            return;
    }
}

/* The bytes at off are not an event (what: why; no_sync: not even the
 * sync word): search on for the next one. Returns 1 when there is one
 * (r->next is it), 0 when none follows, or an error code. */
static int resync(loadid_eventlog_t *r, int64_t off, const char *what, int no_sync) {
    const int64_t at = find_event(r, off + 1, r->st.size);
    if (at == -2) return fail_io(r, off + 1);
    r->st.damaged++;
    if (at >= 0) {
        r->st.skipped_bytes += at - off;
        problem(r, "byte %lld: %s; %lld bytes skipped to the next event at byte %lld",
                (long long)off, what, (long long)(at - off), (long long)at);
        r->next = at;
        return 1;
    }
    r->st.skipped_bytes += r->st.size - off;
    r->ended = 1;
    if (no_sync && off == r->start && r->st.events == 0 && r->st.oversized == 0) {
        r->error = LOADID_EVENTLOG_E_NOT_LOG;
        snprintf(r->error_text, sizeof r->error_text,
                 "not an LCM log: byte %lld holds %s, and no event follows in its %lld bytes",
                 (long long)off, what, (long long)(r->st.size - r->start));
        return r->error;
    }
    problem(r, "byte %lld: %s; no event follows (%lld bytes to the end skipped)", (long long)off,
            what, (long long)(r->st.size - off));
    return 0;
}

static void truncated(loadid_eventlog_t *r, int64_t off, int64_t need) {
    r->st.truncated = 1;
    r->st.truncated_at = off;
    r->ended = 1;
    if (need > 0)
        problem(r, "byte %lld: the file ends inside the last event (%lld of its %lld bytes)",
                (long long)off, (long long)(r->st.size - off), (long long)need);
    else
        problem(r, "byte %lld: the file ends inside the last event's header (%lld bytes)",
                (long long)off, (long long)(r->st.size - off));
}

int loadid_eventlog_open(FILE *f, size_t data_max, loadid_eventlog_t **out) {
    if (!f || !out) return -EINVAL;
    if (data_max == 0) data_max = LOADID_EVENTLOG_DATA_MAX;
    if (data_max > INT32_MAX) return -EINVAL;
    const off_t start = ftello(f);
    if (start < 0 || fseeko(f, 0, SEEK_END) != 0) return LOADID_EVENTLOG_E_SEEK;
    const off_t end = ftello(f);
    if (end < 0 || fseeko(f, start, SEEK_SET) != 0) return LOADID_EVENTLOG_E_SEEK;
    loadid_eventlog_t *r = calloc(1, sizeof *r + data_max);
    if (!r) return -ENOMEM;
    r->f = f;
    r->start = r->pos = r->next = (int64_t)start;
    r->data_max = data_max;
    r->st.size = (int64_t)end;
    r->st.truncated_at = -1;
    *out = r;
    return 0;
}

void loadid_eventlog_close(loadid_eventlog_t *r) {
    free(r);
}

int loadid_eventlog_next(loadid_eventlog_t *r, loadid_eventlog_event_t *ev) {
    if (r->error) return r->error;
    for (;;) {
        const int64_t off = r->next;
        if (r->ended || off >= r->st.size) {
            r->ended = 1;
            return 0;
        }
        header_t h;
        uint32_t detail = 0;
        const int hs = header_at(r, off, &h, r->channel, &detail);
        if (hs == H_IO) return fail_io(r, off);
        if (hs == H_SHORT) {
            truncated(r, off, 0);
            return 0;
        }
        if (hs != H_OK) {
            char what[120];
            describe(hs, detail, what, sizeof what);
            const int rc = resync(r, off, what, hs == H_SYNC);
            if (rc == 1) continue;
            return rc;
        }
        const int64_t end = off + LOADID_EVENTLOG_HEADER + h.channel_len + (int64_t)h.data_len;
        /* The data first, so the reads go forward: header, data, the next
         * sync word, the next header. */
        const int fits = (size_t)h.data_len <= r->data_max && end <= r->st.size;
        if (fits) {
            const long got = read_at(r, off + LOADID_EVENTLOG_HEADER + h.channel_len, r->data,
                                     (size_t)h.data_len);
            if (got < 0) return fail_io(r, off);
            if (got < h.data_len) { /* the file shrank under us */
                truncated(r, off, end - off);
                return 0;
            }
        }
        int follows = end == r->st.size;
        if (end < r->st.size) {
            uint8_t w[4];
            const long got = read_at(r, end, w, 4);
            if (got < 0) return fail_io(r, end);
            follows = got == 4 && be32(w) == LOADID_EVENTLOG_SYNC;
        }
        if (!follows) {
            /* The length does not lead to the next event. If an event
             * begins inside this one, the length is damaged; if none does,
             * the next event's sync word is, and this one stands. */
            const int64_t inside = find_event(r, off + 1, end);
            if (inside == -2) return fail_io(r, off + 1);
            if (inside >= 0) {
                r->st.damaged++;
                r->st.skipped_bytes += inside - off;
                problem(r,
                        "byte %lld: data length %d in the event header runs %s; %lld bytes "
                        "skipped to the next event at byte %lld",
                        (long long)off, (int)h.data_len,
                        end > r->st.size ? "past the end of the file" : "over the next event",
                        (long long)(inside - off), (long long)inside);
                r->next = inside;
                continue;
            }
            if (end > r->st.size) {
                truncated(r, off, end - off);
                return 0;
            }
        }
        r->next = end;
        if (!fits) { /* end <= size here: more data than data_max */
            r->st.oversized++;
            continue;
        }
        ev->eventnum = h.eventnum;
        ev->timestamp = h.timestamp;
        ev->channel = r->channel;
        ev->channel_len = h.channel_len;
        ev->data = r->data;
        ev->data_len = h.data_len;
        ev->offset = off;
        r->st.events++;
        return 1;
    }
}

void loadid_eventlog_stats(const loadid_eventlog_t *r, loadid_eventlog_stats_t *st) {
    *st = r->st;
}

const char *loadid_eventlog_error(const loadid_eventlog_t *r) {
    return r->error ? r->error_text : "";
}

const char *loadid_eventlog_strerror(int code) {
    switch (code) {
        case 0:
            return "success";
        case LOADID_EVENTLOG_E_NOT_LOG:
            return "not an LCM log";
        case LOADID_EVENTLOG_E_SEEK:
            return "the LCM log is not seekable";
        default:
            return code < 0 && code > -4096 ? strerror(-code) : "unknown error";
    }
}
