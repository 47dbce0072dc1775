/*
 * The candump log format of can-utils (see loadid/candump.h). Hand-written
 * parsing rather than sscanf: sscanf's %llu accepts signs, skips blanks and
 * overflows silently, and a time must reach microseconds exactly.
 */

#include "loadid/candump.h"

#include <errno.h>
#include <inttypes.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#define USEC_PER_SEC 1000000

struct loadid_candump_reader {
    FILE *fp;
    long line;
    char buf[LOADID_CANDUMP_LINE_MAX + 3]; /* fgets's LINE_MAX + 1, and two '\n' after */
};

static bool is_blank(char c) {
    return c == ' ' || c == '\t';
}

static bool is_digit(char c) {
    return c >= '0' && c <= '9';
}

/* A hex digit's value plus 1, 0 for any other byte: a table, as the
 * three ranges' comparisons were most of a frame's parsing. */
static const unsigned char hex_plus_1[256] = {
    ['0'] = 1,  ['1'] = 2,  ['2'] = 3,  ['3'] = 4,  ['4'] = 5,  ['5'] = 6,  ['6'] = 7,  ['7'] = 8,
    ['8'] = 9,  ['9'] = 10, ['A'] = 11, ['B'] = 12, ['C'] = 13, ['D'] = 14, ['E'] = 15, ['F'] = 16,
    ['a'] = 11, ['b'] = 12, ['c'] = 13, ['d'] = 14, ['e'] = 15, ['f'] = 16,
};

static int hex_value(char c) {
    return (int)hex_plus_1[(unsigned char)c] - 1;
}

/* An interface name: 1..15 printable characters other than blanks. */
static bool ifname_ok(const char *s, size_t n) {
    if (n == 0 || n >= LOADID_CANDUMP_IFNAME_MAX) {
        return false;
    }
    for (size_t i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)s[i];
        if (c <= ' ' || c >= 0x7F) {
            return false;
        }
    }
    return true;
}

int loadid_candump_format(const loadid_can_frame_t *frame, const char *ifname, char *buf,
                          size_t size) {
    if (buf && size > 0) {
        buf[0] = '\0';
    }
    if (!frame || !ifname || !buf || frame->dlc > LOADID_CAN_MAX_DLEN || frame->t_us < 0 ||
        frame->id > (frame->extended ? LOADID_CAN_EFF_MASK : LOADID_CAN_SFF_MASK) ||
        !ifname_ok(ifname, strlen(ifname))) {
        return -EINVAL;
    }
    char data[2 * LOADID_CAN_MAX_DLEN + 1];
    static const char hex[] = "0123456789ABCDEF";
    for (int i = 0; i < frame->dlc; ++i) {
        data[2 * i] = hex[frame->data[i] >> 4];
        data[2 * i + 1] = hex[frame->data[i] & 0xF];
    }
    data[2 * frame->dlc] = '\0';
    /* candump -l: "(%010lu.%06lu) " then the interface, then the frame. */
    int n = snprintf(buf, size, "(%010" PRId64 ".%06" PRId64 ") %s %0*" PRIX32 "#%s\n",
                     frame->t_us / USEC_PER_SEC, frame->t_us % USEC_PER_SEC, ifname,
                     frame->extended ? 8 : 3, frame->id, data);
    if (n < 0) {
        return -EINVAL;
    }
    if ((size_t)n >= size) {
        if (size > 0) {
            buf[0] = '\0';
        }
        return -ENOSPC;
    }
    return n;
}

/* "(digits.dddddd)" at *pp; advances *pp past ')'. */
static int parse_time(const char **pp, int64_t *t_us) {
    const char *p = *pp;
    if (*p != '(') {
        return LOADID_CANDUMP_E_SYNTAX;
    }
    ++p;
    if (!is_digit(*p)) {
        return LOADID_CANDUMP_E_TIMESTAMP;
    }
    /* Seconds, at most INT64_MAX / 10^6; the exact limit once the
     * microseconds are known. */
    const int64_t max_sec = INT64_MAX / USEC_PER_SEC;
    int64_t sec = 0;
    for (; is_digit(*p); ++p) {
        int d = *p - '0';
        if (sec > (max_sec - d) / 10) {
            return LOADID_CANDUMP_E_TIMESTAMP;
        }
        sec = sec * 10 + d;
    }
    if (*p != '.') {
        return LOADID_CANDUMP_E_TIMESTAMP;
    }
    ++p;
    int64_t usec = 0;
    for (int i = 0; i < 6; ++i, ++p) {
        if (!is_digit(*p)) {
            return LOADID_CANDUMP_E_TIMESTAMP;
        }
        usec = usec * 10 + (*p - '0');
    }
    if (*p != ')') {
        /* More than 6 fraction digits, or anything else. */
        return LOADID_CANDUMP_E_TIMESTAMP;
    }
    if (sec > (INT64_MAX - usec) / USEC_PER_SEC) {
        return LOADID_CANDUMP_E_TIMESTAMP;
    }
    *pp = p + 1;
    *t_us = sec * USEC_PER_SEC + usec;
    return 0;
}

/* The frame token [s, e): "<id>#<data>". */
static int parse_frame(const char *s, const char *e, loadid_can_frame_t *f) {
    const char *hash = memchr(s, '#', (size_t)(e - s));
    if (!hash) {
        return LOADID_CANDUMP_E_SYNTAX;
    }
    size_t idlen = (size_t)(hash - s);
    if (idlen != 3 && idlen != 8) {
        return LOADID_CANDUMP_E_ID;
    }
    uint32_t id = 0;
    for (const char *p = s; p < hash; ++p) {
        int v = hex_value(*p);
        if (v < 0) {
            return LOADID_CANDUMP_E_ID;
        }
        id = (id << 4) | (uint32_t)v;
    }
    f->extended = idlen == 8;
    /* An 8-digit id above 29 bits carries can-utils' flag bits (error
     * frames: CAN_ERR_FLAG 0x20000000); 3 digits reach 0xFFF. */
    if (id > (f->extended ? LOADID_CAN_EFF_MASK : LOADID_CAN_SFF_MASK)) {
        return LOADID_CANDUMP_E_ID;
    }
    f->id = id;

    const char *p = hash + 1;
    if (p < e && *p == '#') {
        return LOADID_CANDUMP_E_FD;
    }
    if (p < e && (*p == 'R' || *p == 'r')) {
        return LOADID_CANDUMP_E_REMOTE;
    }
    /* Hex pairs, each after the first optionally preceded by one '.'. */
    int n = 0;
    while (p < e) {
        if (*p == '.') {
            if (n == 0 || p + 1 >= e || p[1] == '.') {
                return LOADID_CANDUMP_E_DATA;
            }
            ++p;
        }
        if (n == LOADID_CAN_MAX_DLEN || e - p < 2) {
            return LOADID_CANDUMP_E_DATA;
        }
        int hi = hex_value(p[0]);
        int lo = hex_value(p[1]);
        if (hi < 0 || lo < 0) {
            return LOADID_CANDUMP_E_DATA;
        }
        f->data[n++] = (uint8_t)(hi << 4 | lo);
        p += 2;
    }
    f->dlc = (uint8_t)n;
    return 0;
}

int loadid_candump_parse(const char *line, loadid_can_frame_t *frame,
                         char ifname[LOADID_CANDUMP_IFNAME_MAX]) {
    if (!line || !frame) {
        return -EINVAL;
    }
    memset(frame, 0, sizeof *frame);
    const char *p = line;
    int rc = parse_time(&p, &frame->t_us);
    if (rc != 0) {
        return rc;
    }
    if (!is_blank(*p)) {
        return LOADID_CANDUMP_E_SYNTAX;
    }
    while (is_blank(*p)) {
        ++p; /* candump right-aligns the names of several interfaces */
    }
    const char *name = p;
    while (*p && !is_blank(*p) && *p != '\n' && *p != '\r') {
        ++p;
    }
    if (!*p || !is_blank(*p)) {
        return LOADID_CANDUMP_E_SYNTAX; /* no frame after the name */
    }
    size_t name_len = (size_t)(p - name);
    if (!ifname_ok(name, name_len)) {
        return LOADID_CANDUMP_E_IFNAME;
    }
    while (is_blank(*p)) {
        ++p;
    }
    const char *tok = p;
    while (*p && !is_blank(*p) && *p != '\n' && *p != '\r') {
        ++p;
    }
    const char *tok_end = p;
    if (tok == tok_end) {
        return LOADID_CANDUMP_E_SYNTAX;
    }
    /* Only blanks and one line ending may follow. */
    while (is_blank(*p)) {
        ++p;
    }
    if (*p == '\r') {
        ++p;
    }
    if (*p == '\n') {
        ++p;
    }
    if (*p) {
        return LOADID_CANDUMP_E_SYNTAX;
    }
    rc = parse_frame(tok, tok_end, frame);
    if (rc != 0) {
        return rc;
    }
    if (ifname) {
        memcpy(ifname, name, name_len);
        ifname[name_len] = '\0';
    }
    return 0;
}

const char *loadid_candump_strerror(int code) {
    switch (code) {
        case 0:
            return "success";
        case LOADID_CANDUMP_E_SYNTAX:
            return "candump line: not \"(time) interface id#data\"";
        case LOADID_CANDUMP_E_TIMESTAMP:
            return "candump line: time is not (seconds.microseconds) with 6 digits, or out of "
                   "range";
        case LOADID_CANDUMP_E_IFNAME:
            return "candump line: bad interface name";
        case LOADID_CANDUMP_E_ID:
            return "candump line: identifier is not 3 or 8 hex digits of a standard or extended id";
        case LOADID_CANDUMP_E_DATA:
            return "candump line: data is not 0 to 8 bytes of hex pairs";
        case LOADID_CANDUMP_E_FD:
            return "candump line: a CAN FD frame (##), not classic CAN";
        case LOADID_CANDUMP_E_REMOTE:
            return "candump line: a remote frame (#R), not a data frame";
        case LOADID_CANDUMP_E_LONG_LINE:
            return "candump line: too long, or holds a NUL byte";
        case -EINVAL:
            return "invalid argument";
        case -ENOSPC:
            return "buffer too small";
        case -ENOMEM:
            return "out of memory";
        case -EIO:
            return "read error";
        default:
            return "unknown error";
    }
}

/* ---- Reader ------------------------------------------------------------ */

int loadid_candump_reader_open(FILE *fp, loadid_candump_reader_t **out) {
    if (!out) {
        return -EINVAL;
    }
    *out = NULL;
    if (!fp) {
        return -EINVAL;
    }
    loadid_candump_reader_t *r = calloc(1, sizeof *r);
    if (!r) {
        return -ENOMEM;
    }
    r->fp = fp;
    *out = r;
    return 0;
}

void loadid_candump_reader_close(loadid_candump_reader_t *r) {
    free(r);
}

long loadid_candump_reader_line(const loadid_candump_reader_t *r) {
    return r ? r->line : 0;
}

/* Reads one line into r->buf (without its '\n'). Returns 1 for a line,
 * 0 at the end of the file, -EIO, or LOADID_CANDUMP_E_LONG_LINE (the rest
 * of the line is consumed). fgets reads up to the '\n' (a memchr in
 * stdio's buffer, where getc per character cost as much as parsing the
 * line), but a NUL byte must not silently cut a line short: the buffer
 * is filled with '\n' first, so fgets's own NUL is the one followed by
 * two of them (after the line's data, only its last byte can be a '\n');
 * any NUL before it was in the line. */
static int read_line(loadid_candump_reader_t *r) {
    bool too_long = false, nul = false, any = false, newline = false;
    for (;;) {
        memset(r->buf, '\n', sizeof r->buf);
        if (!fgets(r->buf, LOADID_CANDUMP_LINE_MAX + 1, r->fp)) {
            break; /* the end of the file (or an error) before any byte */
        }
        any = true;
        size_t len = strlen(r->buf);
        if (r->buf[len + 1] != '\n' || r->buf[len + 2] != '\n') {
            nul = true; /* a NUL in the line: fgets's is the last NUL */
            len = LOADID_CANDUMP_LINE_MAX;
            while (r->buf[len] != '\0') {
                --len;
            }
        }
        newline = r->buf[len - 1] == '\n';
        if (!too_long && !newline && len == LOADID_CANDUMP_LINE_MAX) {
            too_long = true; /* more than LINE_MAX - 1 bytes before the '\n' */
        }
        if (!too_long && !nul) {
            r->buf[len - newline] = '\0';
        }
        if (newline || len < LOADID_CANDUMP_LINE_MAX) {
            break; /* the line's end, or the file's (a short read) */
        }
    }
    if (!newline && ferror(r->fp)) {
        return -EIO;
    }
    if (!any) {
        return 0;
    }
    ++r->line;
    return too_long || nul ? LOADID_CANDUMP_E_LONG_LINE : 1;
}

int loadid_candump_read(loadid_candump_reader_t *r, loadid_can_frame_t *frame,
                        char ifname[LOADID_CANDUMP_IFNAME_MAX]) {
    if (!r || !frame) {
        return -EINVAL;
    }
    for (;;) {
        int rc = read_line(r);
        if (rc <= 0) {
            return rc; /* end, -EIO, or LOADID_CANDUMP_E_LONG_LINE */
        }
        const char *p = r->buf;
        while (is_blank(*p) || *p == '\r') {
            ++p;
        }
        if (*p == '\0') {
            continue; /* an empty line */
        }
        rc = loadid_candump_parse(r->buf, frame, ifname);
        return rc == 0 ? 1 : rc;
    }
}
