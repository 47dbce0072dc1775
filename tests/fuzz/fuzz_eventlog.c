/*
 * Fuzz target eventlog: the LCM event-log reader (drivers/src/lcm_eventlog.c)
 * over fmemopen. Input: the bytes of an lcm.log. Checks what the header
 * promises: every event handed out lies inside the file, after the last
 * one, with a channel of 1..256 printable bytes and data within data_max
 * (a small data_max here, so that oversized events happen); only the
 * documented return codes, an error repeated by the next call and said in
 * one line; the statistics add up (events, and the bytes skipped never
 * more than the file).
 */
#define _POSIX_C_SOURCE 200809L /* fmemopen */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_check.h"
#include "loadid/lcm_eventlog.h"

#define DATA_MAX 512

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size == 0) return 0; /* fmemopen wants a non-empty buffer */
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f) return 0;
    loadid_eventlog_t *r = NULL;
    const int rc = loadid_eventlog_open(f, DATA_MAX, &r);
    FUZZ_CHECK(rc == 0 && r);
    loadid_eventlog_event_t ev;
    int64_t events = 0, end = 0;
    int got;
    while ((got = loadid_eventlog_next(r, &ev)) == 1) {
        ++events;
        FUZZ_CHECK(ev.offset >= end);
        FUZZ_CHECK(ev.channel_len >= 1 && ev.channel_len <= LOADID_EVENTLOG_CHANNEL_MAX);
        FUZZ_CHECK((size_t)ev.channel_len == strlen(ev.channel));
        for (int i = 0; i < ev.channel_len; ++i)
            FUZZ_CHECK(ev.channel[i] >= 0x20 && ev.channel[i] < 0x7f);
        FUZZ_CHECK(ev.data_len >= 0 && ev.data_len <= DATA_MAX);
        end = ev.offset + LOADID_EVENTLOG_HEADER + ev.channel_len + ev.data_len;
        FUZZ_CHECK(end <= (int64_t)size);
        /* The data are the file's bytes at their place. */
        FUZZ_CHECK(memcmp(ev.data, data + ev.offset + LOADID_EVENTLOG_HEADER + ev.channel_len,
                          (size_t)ev.data_len) == 0);
    }
    FUZZ_CHECK(got == 0 || got == LOADID_EVENTLOG_E_NOT_LOG || got == -EIO);
    if (got < 0) {
        FUZZ_CHECK(events == 0 || got == -EIO);
        FUZZ_CHECK(loadid_eventlog_next(r, &ev) == got); /* repeated */
        const char *why = loadid_eventlog_error(r);
        FUZZ_CHECK(why[0] != '\0' && strchr(why, '\n') == NULL);
    } else {
        FUZZ_CHECK(loadid_eventlog_next(r, &ev) == 0);
    }
    loadid_eventlog_stats_t st;
    loadid_eventlog_stats(r, &st);
    FUZZ_CHECK(st.events == events && st.size == (int64_t)size);
    FUZZ_CHECK(st.skipped_bytes >= 0 && st.skipped_bytes <= (int64_t)size);
    FUZZ_CHECK(st.damaged >= 0 && st.oversized >= 0);
    FUZZ_CHECK(strchr(st.first_problem, '\n') == NULL);
    loadid_eventlog_close(r);
    fclose(f);
    return 0;
}
