/*
 * Fuzz target candump: the candump log reader (drivers/src/candump.c).
 * Input: the text of a can.log. Every line goes through
 * loadid_candump_parse; a line it takes must survive the round trip
 * format -> parse unchanged. The whole text then goes through the reader
 * (loadid_candump_read over fmemopen), which must agree line by line with
 * the parser: a line with a NUL byte or longer than the reader's limit is
 * LOADID_CANDUMP_E_LONG_LINE, a blank line is skipped, any other line
 * gives what loadid_candump_parse gives, with the right line number.
 */
#define _POSIX_C_SOURCE 200809L /* fmemopen */
#include <errno.h>
#include <stdbool.h>
#include <string.h>

#include "fuzz_check.h"
#include "loadid/candump.h"

static bool known_code(int rc) {
    return rc == LOADID_CANDUMP_E_SYNTAX || rc == LOADID_CANDUMP_E_TIMESTAMP ||
           rc == LOADID_CANDUMP_E_IFNAME || rc == LOADID_CANDUMP_E_ID ||
           rc == LOADID_CANDUMP_E_DATA || rc == LOADID_CANDUMP_E_FD ||
           rc == LOADID_CANDUMP_E_REMOTE;
}

static bool same_frame(const loadid_can_frame_t *a, const loadid_can_frame_t *b) {
    return a->id == b->id && a->dlc == b->dlc && a->extended == b->extended && a->t_us == b->t_us &&
           memcmp(a->data, b->data, a->dlc) == 0;
}

/* Parses one line (NUL-terminated); checks the round trip when it parses. */
static int parse_line(const char *line, loadid_can_frame_t *f,
                      char ifname[LOADID_CANDUMP_IFNAME_MAX]) {
    const int rc = loadid_candump_parse(line, f, ifname);
    if (rc != 0) {
        FUZZ_CHECK(known_code(rc));
        return rc;
    }
    FUZZ_CHECK(f->dlc <= LOADID_CAN_MAX_DLEN && f->t_us >= 0);
    FUZZ_CHECK(f->id <= (f->extended ? LOADID_CAN_EFF_MASK : LOADID_CAN_SFF_MASK));
    const size_t n = strlen(ifname);
    FUZZ_CHECK(n > 0 && n < LOADID_CANDUMP_IFNAME_MAX);
    char text[LOADID_CANDUMP_LINE_MAX];
    const int len = loadid_candump_format(f, ifname, text, sizeof text);
    FUZZ_CHECK(len > 0 && (size_t)len == strlen(text) && text[len - 1] == '\n');
    loadid_can_frame_t again;
    char ifname_again[LOADID_CANDUMP_IFNAME_MAX];
    FUZZ_CHECK(loadid_candump_parse(text, &again, ifname_again) == 0);
    FUZZ_CHECK(same_frame(f, &again));
    FUZZ_CHECK(strcmp(ifname, ifname_again) == 0);
    return 0;
}

/* Line k (from 1) of the input: [start, end) without its '\n'. */
typedef struct {
    size_t start, end;
} span_t;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size > 64 * 1024) {
        return 0; /* nothing new past a few lines; keeps runs fast */
    }
    const char *text = (const char *)data;
    size_t nlines = 0;
    for (size_t i = 0; i < size; ++i) {
        nlines += text[i] == '\n';
    }
    nlines += size > 0 && text[size - 1] != '\n';
    span_t *lines = malloc((nlines + 1) * sizeof *lines);
    char *buf = malloc(size + 1);
    FUZZ_CHECK(lines && buf);
    size_t k = 0, start = 0;
    for (size_t i = 0; i <= size; ++i) {
        if (i == size ? i > start : text[i] == '\n') {
            lines[k].start = start;
            lines[k].end = i;
            ++k;
            start = i + 1;
        }
    }
    FUZZ_CHECK(k == nlines);

    /* The parser, line by line (with its '\n', as a log line has it). */
    for (size_t j = 0; j < nlines; ++j) {
        const size_t n = lines[j].end - lines[j].start;
        memcpy(buf, text + lines[j].start, n);
        buf[n] = '\n';
        buf[n + (lines[j].end < size)] = '\0';
        loadid_can_frame_t f;
        char ifname[LOADID_CANDUMP_IFNAME_MAX];
        (void)parse_line(buf, &f, ifname);
    }

    /* The reader over the same text. */
    FILE *fp = size > 0 ? fmemopen((void *)data, size, "r") : NULL;
    if (fp) {
        loadid_candump_reader_t *r = NULL;
        FUZZ_CHECK(loadid_candump_reader_open(fp, &r) == 0);
        long last = 0;
        for (;;) {
            loadid_can_frame_t f;
            char ifname[LOADID_CANDUMP_IFNAME_MAX];
            const int rc = loadid_candump_read(r, &f, ifname);
            const long line = loadid_candump_reader_line(r);
            if (rc == 0) {
                /* The end: every line read (the blank ones after the
                 * last result are checked below). */
                FUZZ_CHECK((size_t)line == nlines);
                break;
            }
            FUZZ_CHECK(line > last && (size_t)line <= nlines);
            for (long skipped = last + 1; skipped < line; ++skipped) {
                const span_t *s = &lines[skipped - 1];
                for (size_t i = s->start; i < s->end; ++i) {
                    FUZZ_CHECK(text[i] == ' ' || text[i] == '\t' || text[i] == '\r');
                }
            }
            last = line;
            const span_t *s = &lines[line - 1];
            const size_t n = s->end - s->start;
            const bool nul = memchr(text + s->start, '\0', n) != NULL;
            if (nul || n > LOADID_CANDUMP_LINE_MAX - 1) {
                FUZZ_CHECK(rc == LOADID_CANDUMP_E_LONG_LINE);
                continue;
            }
            FUZZ_CHECK(rc != LOADID_CANDUMP_E_LONG_LINE);
            memcpy(buf, text + s->start, n);
            buf[n] = '\0';
            loadid_can_frame_t expect;
            char expect_ifname[LOADID_CANDUMP_IFNAME_MAX];
            const int want = parse_line(buf, &expect, expect_ifname);
            FUZZ_CHECK(rc == (want == 0 ? 1 : want));
            if (rc == 1) {
                FUZZ_CHECK(same_frame(&f, &expect));
                FUZZ_CHECK(strcmp(ifname, expect_ifname) == 0);
            }
        }
        /* Lines after the last one returned are blank. */
        for (size_t j = (size_t)last; j < nlines; ++j) {
            for (size_t i = lines[j].start; i < lines[j].end; ++i) {
                FUZZ_CHECK(text[i] == ' ' || text[i] == '\t' || text[i] == '\r');
            }
        }
        loadid_candump_reader_close(r);
        fclose(fp);
    }
    free(buf);
    free(lines);
    return 0;
}
