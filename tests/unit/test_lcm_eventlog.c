/*
 * Unit tests of loadid/lcm_eventlog.h, the LCM event-log reader.
 *
 * References: a log written by liblcm's own lcm_eventlog_write_event (the
 * writer of lcm-logger), and logs built here byte by byte from the format
 * (sync word 0xEDA1DA01, int64 event number, int64 time, int32 channel
 * length, int32 data length, channel, data; big-endian), read through
 * fmemopen as a fuzz harness would. Damage is made at known offsets and
 * the expected events, skipped bytes and offsets are computed from the
 * builder's own bookkeeping.
 */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <lcm/eventlog.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "loadid/lcm_eventlog.h"

/* ---- a log built by hand ---- */

enum { MAX_EVENTS = 64, LOG_CAP = 1 << 16 };

typedef struct {
    uint8_t bytes[LOG_CAP];
    size_t len;
    int n;
    size_t off[MAX_EVENTS], size[MAX_EVENTS]; /* each event's offset and length */
    int64_t eventnum[MAX_EVENTS], t[MAX_EVENTS];
    char channel[MAX_EVENTS][LOADID_EVENTLOG_CHANNEL_MAX + 2];
    int32_t data_len[MAX_EVENTS];
} log_t;

static void put32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24), p[1] = (uint8_t)(v >> 16), p[2] = (uint8_t)(v >> 8),
    p[3] = (uint8_t)v;
}

static void put64(uint8_t *p, uint64_t v) {
    put32(p, (uint32_t)(v >> 32));
    put32(p + 4, (uint32_t)v);
}

/* The data of event i: bytes a reader cannot mistake for another's. */
static uint8_t data_byte(int i, int32_t k) {
    return (uint8_t)(i * 37 + k * 11 + 5);
}

static void add(log_t *l, int64_t eventnum, int64_t t, const char *channel, int32_t data_len) {
    const int i = l->n++;
    assert_true(i < MAX_EVENTS);
    const size_t cl = strlen(channel);
    uint8_t *p = l->bytes + l->len;
    assert_true(l->len + 28 + cl + (size_t)data_len <= LOG_CAP);
    put32(p, LOADID_EVENTLOG_SYNC);
    put64(p + 4, (uint64_t)eventnum);
    put64(p + 12, (uint64_t)t);
    put32(p + 20, (uint32_t)cl);
    put32(p + 24, (uint32_t)data_len);
    memcpy(p + 28, channel, cl);
    for (int32_t k = 0; k < data_len; ++k) p[28 + cl + (size_t)k] = data_byte(i, k);
    l->off[i] = l->len;
    l->size[i] = 28 + cl + (size_t)data_len;
    l->eventnum[i] = eventnum;
    l->t[i] = t;
    snprintf(l->channel[i], sizeof l->channel[i], "%s", channel);
    l->data_len[i] = data_len;
    l->len += l->size[i];
}

/* n events of varied channels and lengths (0 .. 200 bytes of data). */
static void build(log_t *l, int n) {
    memset(l, 0, sizeof *l);
    static const char *const channels[] = {"LOADID_JOINTS", "LOADID_COMMAND", "R2_LOADID_JOINTS",
                                           "x", "A channel/with.odd-chars_1"};
    for (int i = 0; i < n; ++i)
        add(l, i, 1700000000000000 + 1000 * (int64_t)i, channels[i % 5], (int32_t)((i * 53) % 201));
}

typedef struct {
    FILE *f;
    loadid_eventlog_t *r;
    char vbuf[512];
} reader_t;

static void open_bytes(reader_t *rd, const void *bytes, size_t len, size_t data_max) {
    /* fmemopen of 0 bytes is EINVAL in older glibc: give it one byte and
     * an end at 0 instead. */
    static const uint8_t empty[1] = {0};
    rd->f = fmemopen((void *)(len ? bytes : empty), len ? len : 1, "rb");
    assert_non_null(rd->f);
    setvbuf(rd->f, rd->vbuf, _IOFBF, sizeof rd->vbuf);
    if (!len) fseek(rd->f, 1, SEEK_SET); /* start at the end: an empty log */
    assert_int_equal(loadid_eventlog_open(rd->f, data_max, &rd->r), 0);
}

static void close_reader(reader_t *rd) {
    loadid_eventlog_close(rd->r);
    fclose(rd->f);
}

/* Reads event i of l and checks every field against the builder's. */
static void expect_event(reader_t *rd, const log_t *l, int i, size_t base) {
    loadid_eventlog_event_t ev;
    assert_int_equal(loadid_eventlog_next(rd->r, &ev), 1);
    assert_int_equal(ev.offset, (int64_t)(l->off[i] + base));
    assert_int_equal(ev.eventnum, l->eventnum[i]);
    assert_int_equal(ev.timestamp, l->t[i]);
    assert_string_equal(ev.channel, l->channel[i]);
    assert_int_equal(ev.channel_len, (int32_t)strlen(l->channel[i]));
    assert_int_equal(ev.data_len, l->data_len[i]);
    for (int32_t k = 0; k < ev.data_len; ++k) assert_int_equal(ev.data[k], data_byte(i, k));
}

static void expect_end(reader_t *rd) {
    loadid_eventlog_event_t ev;
    assert_int_equal(loadid_eventlog_next(rd->r, &ev), 0);
    assert_int_equal(loadid_eventlog_next(rd->r, &ev), 0); /* and stays there */
}

static loadid_eventlog_stats_t stats(const reader_t *rd) {
    loadid_eventlog_stats_t st;
    loadid_eventlog_stats(rd->r, &st);
    return st;
}

/* "byte N" in the problem's text. */
static void expect_problem_at(const loadid_eventlog_stats_t *st, size_t off) {
    char want[48];
    snprintf(want, sizeof want, "byte %zu:", off);
    assert_non_null(strstr(st->first_problem, want));
}

/* ---- tests ---- */

static void test_reads_what_liblcm_wrote(void **state) {
    (void)state;
    char path[] = "/tmp/loadid_eventlog_XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    lcm_eventlog_t *w = lcm_eventlog_create(path, "w");
    assert_non_null(w);
    enum { N = 300 };
    static uint8_t data[2000];
    for (int i = 0; i < N; ++i) {
        char channel[64];
        snprintf(channel, sizeof channel, "CH_%d", i % 7);
        for (int k = 0; k < (int)sizeof data; ++k) data[k] = data_byte(i, k);
        lcm_eventlog_event_t ev = {.eventnum = i,
                                   .timestamp = 1700000000000000 + 997 * (int64_t)i,
                                   .channellen = (int32_t)strlen(channel),
                                   .datalen = (i * 131) % 2000,
                                   .channel = channel,
                                   .data = data};
        assert_int_equal(lcm_eventlog_write_event(w, &ev), 0);
    }
    lcm_eventlog_destroy(w);

    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    loadid_eventlog_t *r;
    assert_int_equal(loadid_eventlog_open(f, 0, &r), 0);
    loadid_eventlog_event_t ev;
    int64_t off = 0;
    for (int i = 0; i < N; ++i) {
        assert_int_equal(loadid_eventlog_next(r, &ev), 1);
        char channel[64];
        snprintf(channel, sizeof channel, "CH_%d", i % 7);
        assert_int_equal(ev.eventnum, i);
        assert_int_equal(ev.timestamp, 1700000000000000 + 997 * (int64_t)i);
        assert_string_equal(ev.channel, channel);
        assert_int_equal(ev.data_len, (i * 131) % 2000);
        assert_int_equal(ev.offset, off);
        for (int k = 0; k < ev.data_len; ++k) assert_int_equal(ev.data[k], data_byte(i, k));
        off += 28 + (int64_t)strlen(channel) + ev.data_len;
    }
    assert_int_equal(loadid_eventlog_next(r, &ev), 0);
    loadid_eventlog_stats_t st;
    loadid_eventlog_stats(r, &st);
    assert_int_equal(st.events, N);
    assert_int_equal(st.size, off);
    assert_int_equal(st.damaged + st.skipped_bytes + st.oversized + st.truncated, 0);
    assert_int_equal(st.truncated_at, -1);
    assert_string_equal(st.first_problem, "");
    assert_string_equal(loadid_eventlog_error(r), "");
    loadid_eventlog_close(r);
    fclose(f);
    unlink(path);
}

static void test_hand_built_log_big_endian(void **state) {
    (void)state;
    static log_t l;
    memset(&l, 0, sizeof l);
    /* Values whose bytes all differ: a swapped or shifted field shows. */
    add(&l, 0x0102030405060708, 0x1112131415161718, "LOADID_JOINTS", 3);
    add(&l, -1, INT64_MIN, "C", 0);
    add(&l, INT64_MAX, -5, "LOADID_COMMAND", 17);
    reader_t rd;
    open_bytes(&rd, l.bytes, l.len, 0);
    for (int i = 0; i < l.n; ++i) expect_event(&rd, &l, i, 0);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.events, 3);
    assert_int_equal(st.damaged + st.truncated + st.oversized, 0);
    close_reader(&rd);
}

static void test_empty_log_has_no_events_and_no_problem(void **state) {
    (void)state;
    reader_t rd;
    open_bytes(&rd, "", 0, 0);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.events + st.damaged + st.truncated, 0);
    assert_string_equal(st.first_problem, "");
    close_reader(&rd);
}

/* Every cut inside the last event: the others read, then "truncated" at
 * the last one's offset, nothing counted as damage. */
static void test_truncated_last_event(void **state) {
    (void)state;
    static log_t l;
    build(&l, 6);
    const size_t last = l.off[5];
    for (size_t cut = last + 1; cut < l.len; ++cut) {
        reader_t rd;
        open_bytes(&rd, l.bytes, cut, 0);
        for (int i = 0; i < 5; ++i) expect_event(&rd, &l, i, 0);
        expect_end(&rd);
        loadid_eventlog_stats_t st = stats(&rd);
        assert_int_equal(st.events, 5);
        assert_int_equal(st.truncated, 1);
        assert_int_equal(st.truncated_at, (int64_t)last);
        assert_int_equal(st.damaged, 0);
        assert_int_equal(st.skipped_bytes, 0);
        expect_problem_at(&st, last);
        assert_non_null(strstr(st.first_problem, "ends inside"));
        close_reader(&rd);
    }
}

/* A data length of 0x7fffffff (liblcm would allocate 2 GiB): that event is
 * passed over, counted, the next read whole, the problem at its offset. */
static void test_huge_data_length_resyncs(void **state) {
    (void)state;
    static log_t l;
    build(&l, 8);
    const int bad = 3;
    put32(l.bytes + l.off[bad] + 24, 0x7fffffff);
    reader_t rd;
    open_bytes(&rd, l.bytes, l.len, 0);
    for (int i = 0; i < l.n; ++i)
        if (i != bad) expect_event(&rd, &l, i, 0);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.events, l.n - 1);
    assert_int_equal(st.damaged, 1);
    assert_int_equal(st.skipped_bytes, (int64_t)l.size[bad]);
    assert_int_equal(st.truncated, 0);
    expect_problem_at(&st, l.off[bad]);
    assert_non_null(strstr(st.first_problem, "2147483647"));
    close_reader(&rd);

    /* The same in the last event: nothing follows, so it is a cut-short end. */
    build(&l, 8);
    put32(l.bytes + l.off[7] + 24, 0x7fffffff);
    open_bytes(&rd, l.bytes, l.len, 0);
    for (int i = 0; i < 7; ++i) expect_event(&rd, &l, i, 0);
    expect_end(&rd);
    st = stats(&rd);
    assert_int_equal(st.truncated, 1);
    assert_int_equal(st.truncated_at, (int64_t)l.off[7]);
    close_reader(&rd);
}

/* A length that still fits in the file but runs over the next event (a
 * flipped high bit): the next event's sync word inside it gives it away. */
static void test_length_over_the_next_event(void **state) {
    (void)state;
    static log_t l;
    build(&l, 8);
    const int bad = 2;
    put32(l.bytes + l.off[bad] + 24, (uint32_t)l.data_len[bad] + 0x100);
    reader_t rd;
    open_bytes(&rd, l.bytes, l.len, 0);
    for (int i = 0; i < l.n; ++i)
        if (i != bad) expect_event(&rd, &l, i, 0);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.damaged, 1);
    assert_int_equal(st.skipped_bytes, (int64_t)l.size[bad]);
    expect_problem_at(&st, l.off[bad]);
    close_reader(&rd);
}

/* A length too short: the event is handed out as it claims (its decoder
 * will refuse it), then the rest of it is searched past to the next. */
static void test_length_too_short(void **state) {
    (void)state;
    static log_t l;
    build(&l, 8);
    const int bad = 4; /* 212 % 201 = 11 bytes of data */
    assert_true(l.data_len[bad] > 5);
    put32(l.bytes + l.off[bad] + 24, (uint32_t)l.data_len[bad] - 5);
    reader_t rd;
    open_bytes(&rd, l.bytes, l.len, 0);
    for (int i = 0; i < bad; ++i) expect_event(&rd, &l, i, 0);
    loadid_eventlog_event_t ev;
    assert_int_equal(loadid_eventlog_next(rd.r, &ev), 1);
    assert_int_equal(ev.offset, (int64_t)l.off[bad]);
    assert_int_equal(ev.data_len, l.data_len[bad] - 5);
    for (int i = bad + 1; i < l.n; ++i) expect_event(&rd, &l, i, 0);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.damaged, 1);
    assert_int_equal(st.skipped_bytes, 5);
    expect_problem_at(&st, l.off[bad] + l.size[bad] - 5);
    close_reader(&rd);
}

/* A corrupted sync word: that event is lost, the one before it still
 * stands (its length is confirmed by no event inside it), every later one
 * reads, and the skipped bytes are exactly the lost event. Also for the
 * first event of the log (not "not an LCM log": events follow). */
static void test_corrupt_sync_word_resyncs_and_counts(void **state) {
    (void)state;
    static log_t l;
    for (int bad = 0; bad < 8; ++bad) {
        build(&l, 8);
        l.bytes[l.off[bad] + 1] ^= 0x40;
        reader_t rd;
        open_bytes(&rd, l.bytes, l.len, 0);
        for (int i = 0; i < l.n; ++i)
            if (i != bad) expect_event(&rd, &l, i, 0);
        expect_end(&rd);
        loadid_eventlog_stats_t st = stats(&rd);
        assert_int_equal(st.events, l.n - 1);
        assert_int_equal(st.damaged, 1);
        assert_int_equal(st.skipped_bytes, (int64_t)l.size[bad]);
        assert_int_equal(st.truncated, 0);
        expect_problem_at(&st, l.off[bad]);
        assert_string_equal(loadid_eventlog_error(rd.r), "");
        close_reader(&rd);
    }
}

/* An event whose data hold a sync word and a header that is not
 * plausible (a control character in its channel), before a damaged sync
 * word: the search inside it finds nothing, and the event is handed out
 * with its own channel and data, untouched by the search. */
static void test_search_inside_an_event_leaves_it_whole(void **state) {
    (void)state;
    static log_t l;
    memset(&l, 0, sizeof l);
    add(&l, 0, 10, "GOOD", 60);
    add(&l, 1, 11, "LOST", 8);
    add(&l, 2, 12, "NEXT", 8);
    uint8_t *d = l.bytes + l.off[0] + 28 + 4;
    put32(d + 10, LOADID_EVENTLOG_SYNC);
    put32(d + 10 + 20, 4); /* channel length */
    put32(d + 10 + 24, 0); /* data length */
    memcpy(d + 10 + 28, "\x01\x02\x03\x04", 4);
    uint8_t want[60];
    memcpy(want, d, sizeof want);
    l.bytes[l.off[1] + 3] ^= 0xFF; /* LOST's sync word */
    reader_t rd;
    open_bytes(&rd, l.bytes, l.len, 0);
    loadid_eventlog_event_t ev;
    assert_int_equal(loadid_eventlog_next(rd.r, &ev), 1);
    assert_string_equal(ev.channel, "GOOD");
    assert_int_equal(ev.data_len, 60);
    assert_memory_equal(ev.data, want, sizeof want);
    expect_event(&rd, &l, 2, 0);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.damaged, 1);
    assert_int_equal(st.skipped_bytes, (int64_t)l.size[1]);
    close_reader(&rd);
}

/* Junk before the log, and junk between events. */
static void test_junk_is_skipped_and_counted(void **state) {
    (void)state;
    static log_t l;
    build(&l, 6);
    static uint8_t buf[LOG_CAP + 64];
    memset(buf, 0xA5, 13);
    memcpy(buf + 13, l.bytes, l.off[3]);
    memset(buf + 13 + l.off[3], 0xED, 7); /* sync-like bytes, no sync word */
    memcpy(buf + 13 + l.off[3] + 7, l.bytes + l.off[3], l.len - l.off[3]);
    reader_t rd;
    open_bytes(&rd, buf, l.len + 20, 0);
    for (int i = 0; i < l.n; ++i) expect_event(&rd, &l, i, i < 3 ? 13 : 20);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.events, l.n);
    assert_int_equal(st.damaged, 2);
    assert_int_equal(st.skipped_bytes, 20);
    expect_problem_at(&st, 0);
    close_reader(&rd);
}

static void test_random_bytes_are_not_an_lcm_log(void **state) {
    (void)state;
    static uint8_t junk[100000];
    uint64_t x = 0x9E3779B97F4A7C15ull;
    for (size_t i = 0; i < sizeof junk; ++i) {
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        junk[i] = (uint8_t)x;
    }
    junk[0] = 0x7F; /* not the sync word, whatever the generator gives */
    reader_t rd;
    open_bytes(&rd, junk, sizeof junk, 0);
    loadid_eventlog_event_t ev;
    assert_int_equal(loadid_eventlog_next(rd.r, &ev), LOADID_EVENTLOG_E_NOT_LOG);
    assert_int_equal(loadid_eventlog_next(rd.r, &ev), LOADID_EVENTLOG_E_NOT_LOG); /* sticky */
    const char *e = loadid_eventlog_error(rd.r);
    assert_non_null(strstr(e, "not an LCM log"));
    assert_non_null(strstr(e, "byte 0"));
    assert_non_null(strstr(e, "100000 bytes"));
    assert_string_equal(loadid_eventlog_strerror(LOADID_EVENTLOG_E_NOT_LOG), "not an LCM log");
    close_reader(&rd);
    /* A text file too, and a file of three bytes. */
    const char *text = "(1700000000.000000) vcan0 1A0#0102030405060708\n";
    open_bytes(&rd, text, strlen(text), 0);
    assert_int_equal(loadid_eventlog_next(rd.r, &ev), LOADID_EVENTLOG_E_NOT_LOG);
    close_reader(&rd);
    open_bytes(&rd, "abc", 3, 0);
    assert_int_equal(loadid_eventlog_next(rd.r, &ev), LOADID_EVENTLOG_E_NOT_LOG);
    close_reader(&rd);
}

/* The bounds: a channel of 256 bytes reads, 257 is damage; data of
 * data_max bytes reads, one more is passed over as oversized. */
static void test_size_bounds(void **state) {
    (void)state;
    static log_t l;
    char ch256[LOADID_EVENTLOG_CHANNEL_MAX + 2];
    memset(ch256, 'c', LOADID_EVENTLOG_CHANNEL_MAX);
    ch256[LOADID_EVENTLOG_CHANNEL_MAX] = 0;
    memset(&l, 0, sizeof l);
    add(&l, 0, 10, "A", 4);
    add(&l, 1, 11, ch256, 64); /* the longest channel, data_max bytes */
    add(&l, 2, 12, "B", 65);   /* one byte over data_max */
    add(&l, 3, 13, "C", 0);
    reader_t rd;
    open_bytes(&rd, l.bytes, l.len, 64);
    expect_event(&rd, &l, 0, 0);
    expect_event(&rd, &l, 1, 0);
    expect_event(&rd, &l, 3, 0);
    expect_end(&rd);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.events, 3);
    assert_int_equal(st.oversized, 1);
    assert_int_equal(st.damaged, 0);
    close_reader(&rd);

    ch256[LOADID_EVENTLOG_CHANNEL_MAX] = 'c';
    ch256[LOADID_EVENTLOG_CHANNEL_MAX + 1] = 0;
    memset(&l, 0, sizeof l);
    add(&l, 0, 10, "A", 4);
    add(&l, 1, 11, ch256, 8); /* 257 bytes of channel */
    add(&l, 2, 12, "B", 4);
    open_bytes(&rd, l.bytes, l.len, 64);
    expect_event(&rd, &l, 0, 0);
    expect_event(&rd, &l, 2, 0);
    expect_end(&rd);
    st = stats(&rd);
    assert_int_equal(st.damaged, 1);
    assert_int_equal(st.skipped_bytes, (int64_t)l.size[1]);
    assert_non_null(strstr(st.first_problem, "channel length 257"));
    close_reader(&rd);

    /* A control character in the channel, a negative data length. */
    memset(&l, 0, sizeof l);
    add(&l, 0, 10, "A", 4);
    add(&l, 1, 11, "BAD\tNAME", 4);
    add(&l, 2, 12, "NEG", 4);
    add(&l, 3, 13, "D", 4);
    put32(l.bytes + l.off[2] + 24, 0xFFFFFFF0u);
    open_bytes(&rd, l.bytes, l.len, 64);
    expect_event(&rd, &l, 0, 0);
    expect_event(&rd, &l, 3, 0);
    expect_end(&rd);
    st = stats(&rd);
    /* One damaged stretch: the search passes the implausible header too. */
    assert_int_equal(st.damaged, 1);
    assert_int_equal(st.skipped_bytes, (int64_t)(l.size[1] + l.size[2]));
    assert_non_null(strstr(st.first_problem, "byte 0x09 in an event's channel name"));
    close_reader(&rd);

    /* data_max beyond int32 is refused; 0 means the default. */
    FILE *f = fmemopen(l.bytes, l.len, "rb");
    loadid_eventlog_t *r = NULL;
    assert_int_equal(loadid_eventlog_open(f, (size_t)INT32_MAX + 1, &r), -EINVAL);
    assert_int_equal(loadid_eventlog_open(NULL, 0, &r), -EINVAL);
    fclose(f);
}

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;
static uint64_t rng(void) { /* xorshift64 */
    rng_state ^= rng_state << 13, rng_state ^= rng_state >> 7, rng_state ^= rng_state << 17;
    return rng_state;
}

/* Every single-byte change anywhere in a log: each event but the changed
 * one still comes out whole, at its offset; whatever comes out lies in the
 * file, in order, within the bounds. */
static void test_any_one_byte_changed_costs_at_most_its_event(void **state) {
    (void)state;
    static log_t l;
    build(&l, 12);
    static uint8_t m[LOG_CAP];
    for (int trial = 0; trial < 4000; ++trial) {
        memcpy(m, l.bytes, l.len);
        const size_t at = (size_t)(rng() % l.len);
        const uint8_t was = m[at];
        do m[at] = (uint8_t)rng();
        while (m[at] == was);
        int hit = 0;
        while (!(l.off[hit] <= at && at < l.off[hit] + l.size[hit])) ++hit;
        reader_t rd;
        open_bytes(&rd, m, l.len, 0);
        loadid_eventlog_event_t ev;
        int next = 0, rc;
        int64_t prev = -1;
        while ((rc = loadid_eventlog_next(rd.r, &ev)) == 1) {
            assert_true(ev.offset > prev);
            prev = ev.offset;
            assert_true(ev.offset + 28 + ev.channel_len + ev.data_len <= (int64_t)l.len);
            assert_int_equal((int32_t)strlen(ev.channel), ev.channel_len);
            while (next < l.n && (int64_t)l.off[next] < ev.offset) {
                assert_int_equal(next, hit); /* only the changed event may be missing */
                ++next;
            }
            if (next == hit && (int64_t)l.off[hit] == ev.offset) {
                ++next; /* the changed one, as changed */
                continue;
            }
            assert_true(next < l.n);
            assert_int_equal(ev.offset, (int64_t)l.off[next]);
            assert_int_equal(ev.eventnum, l.eventnum[next]);
            assert_string_equal(ev.channel, l.channel[next]);
            assert_int_equal(ev.data_len, l.data_len[next]);
            for (int32_t k = 0; k < ev.data_len; ++k)
                assert_int_equal(ev.data[k], data_byte(next, k));
            ++next;
        }
        assert_int_equal(rc, 0);
        assert_true(next >= l.n - 1);
        close_reader(&rd);
    }
}

/* Many bytes changed, cut short, junk appended: no crash, and everything
 * handed out lies in the file within the bounds. (ASan and UBSan watch the
 * reads in the asan build.) */
static void test_heavy_damage_stays_in_bounds(void **state) {
    (void)state;
    static log_t l;
    build(&l, 20);
    static uint8_t m[LOG_CAP];
    for (int trial = 0; trial < 2000; ++trial) {
        memcpy(m, l.bytes, l.len);
        size_t len = l.len;
        const int changes = 1 + (int)(rng() % 40);
        for (int c = 0; c < changes; ++c) m[rng() % len] = (uint8_t)rng();
        if (rng() % 2) len = 1 + (size_t)(rng() % len);
        const size_t junk = rng() % 3 ? 0 : (size_t)(rng() % 300);
        for (size_t k = 0; k < junk && len < LOG_CAP; ++k) m[len++] = (uint8_t)rng();
        reader_t rd;
        open_bytes(&rd, m, len, 1 + (size_t)(rng() % 300));
        loadid_eventlog_event_t ev;
        int rc, n = 0;
        int64_t prev = -1;
        while ((rc = loadid_eventlog_next(rd.r, &ev)) == 1) {
            assert_true(ev.offset > prev && ++n <= 2 * l.n + 300);
            prev = ev.offset;
            assert_true(ev.offset + 28 + ev.channel_len + ev.data_len <= (int64_t)len);
            assert_true(ev.channel_len >= 1 && ev.channel_len <= LOADID_EVENTLOG_CHANNEL_MAX);
            volatile uint8_t sum = 0;
            for (int32_t k = 0; k < ev.data_len; ++k) sum ^= ev.data[k];
            (void)sum;
        }
        assert_true(rc == 0 || rc == LOADID_EVENTLOG_E_NOT_LOG);
        loadid_eventlog_stats_t st = stats(&rd);
        assert_true(st.skipped_bytes <= (int64_t)len);
        close_reader(&rd);
    }
}

/* A pipe cannot be read: the reader looks ahead and back. */
static void test_unseekable_input_is_refused(void **state) {
    (void)state;
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    FILE *f = fdopen(fds[0], "rb");
    loadid_eventlog_t *r = NULL;
    assert_int_equal(loadid_eventlog_open(f, 0, &r), LOADID_EVENTLOG_E_SEEK);
    fclose(f);
    close(fds[1]);
}

#ifndef LOADID_SANITIZED
/* ---- no allocation per event (alloc_counter.c; not under ASan) ---- */
#include "alloc_counter.h"

static void test_reading_allocates_nothing(void **state) {
    (void)state;
    static log_t l;
    build(&l, 40);
    put32(l.bytes + l.off[10] + 24, 0x7fffffff); /* damage and a search too */
    l.bytes[l.off[20]] = 0;
    reader_t rd;
    open_bytes(&rd, l.bytes, l.len - 3, 0);
    alloc_count = 0;
    alloc_counting = 1;
    loadid_eventlog_event_t ev;
    int n = 0;
    while (loadid_eventlog_next(rd.r, &ev) == 1) ++n;
    alloc_counting = 0;
    assert_int_equal(n, 37);
    assert_int_equal(alloc_count, 0);
    loadid_eventlog_stats_t st = stats(&rd);
    assert_int_equal(st.damaged, 2);
    assert_int_equal(st.truncated, 1);
    close_reader(&rd);
}
#endif

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reads_what_liblcm_wrote),
        cmocka_unit_test(test_hand_built_log_big_endian),
        cmocka_unit_test(test_empty_log_has_no_events_and_no_problem),
        cmocka_unit_test(test_truncated_last_event),
        cmocka_unit_test(test_huge_data_length_resyncs),
        cmocka_unit_test(test_length_over_the_next_event),
        cmocka_unit_test(test_length_too_short),
        cmocka_unit_test(test_corrupt_sync_word_resyncs_and_counts),
        cmocka_unit_test(test_search_inside_an_event_leaves_it_whole),
        cmocka_unit_test(test_junk_is_skipped_and_counted),
        cmocka_unit_test(test_random_bytes_are_not_an_lcm_log),
        cmocka_unit_test(test_size_bounds),
        cmocka_unit_test(test_any_one_byte_changed_costs_at_most_its_event),
        cmocka_unit_test(test_heavy_damage_stays_in_bounds),
        cmocka_unit_test(test_unseekable_input_is_refused),
#ifndef LOADID_SANITIZED
        cmocka_unit_test(test_reading_allocates_nothing),
#endif
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
