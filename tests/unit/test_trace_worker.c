/*
 * The trace writer (host/src/daemon/trace_worker.h), which writes
 * results.trace off loadidd's loop:
 *  - sessions come out in order, each renamed to the saved result's name
 *    with .trace.csv ("traced PATH (N rows)"), or START's utime without a
 *    final estimate; the rows are trace_csv.h's;
 *  - a stalled disk (the thread held in open() of a FIFO, which waits for
 *    a reader) does not hold up the loop's calls: rows are dropped once
 *    the ring is full, counted, the first one said (-ENOBUFS), the
 *    session's end still fits; once the disk moves on, what was queued is
 *    written and the drops are in the message.
 * The loop's side making no allocation in a real session is
 * tests/python/test_live_replay.py's.
 */
#define _DEFAULT_SOURCE /* mkdtemp, mkfifo */
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "loadid/estimator.h"
#include "trace_worker.h"
#include "scratch_dir.h"

static char g_dir[64];

static int make_dir(void **state) {
    (void)state;
    return scratch_dir_make(g_dir, sizeof g_dir, "trace");
}

static int remove_dir(void **state) {
    (void)state;
    return scratch_dir_remove(g_dir);
}

static void row_of(int64_t utime, const char *name, loadid_pipeline_estimate_t *e) {
    memset(e, 0, sizeof *e);
    e->utime = utime;
    e->samples = 7;
    e->method = LOADID_METHOD_RTLS;
    e->valid = 1;
    snprintf(e->load_name, sizeof e->load_name, "%s", name);
    for (int i = 0; i < 10; ++i) e->phi[i] = 0.5 * i;
}

/* The messages until stop's, in order, joined by '|'. */
static void messages(loadid_trace_worker_t *w, char *out, size_t len) {
    char msg[4608];
    out[0] = 0;
    while (loadid_trace_worker_collect(w, msg, sizeof msg))
        snprintf(out + strlen(out), len - strlen(out), "%s|", msg);
}

static int count_lines(const char *path, char *first, size_t len) {
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char line[4096];
    int n = 0;
    while (fgets(line, sizeof line, f))
        if (n++ == 1) snprintf(first, len, "%s", line);
    fclose(f);
    return n;
}

static void sessions_named_as_saved_results(void **state) {
    (void)state;
    loadid_trace_worker_t *w;
    assert_int_equal(loadid_trace_worker_start(g_dir, &w), 0);
    loadid_pipeline_estimate_t e;
    row_of(1, "x", &e);
    assert_int_equal(loadid_trace_worker_row(w, &e), 0); /* before any session: nothing */
    assert_int_equal(loadid_trace_worker_begin(w, 1000), 0);
    assert_true(loadid_trace_worker_open(w));
    for (int k = 1; k <= 3; ++k) {
        row_of(1000 + 1000 * k, "a/b", &e);
        assert_int_equal(loadid_trace_worker_row(w, &e), 0);
    }
    row_of(5000, "a/b", &e);
    assert_int_equal(loadid_trace_worker_end(w, &e), 0);
    assert_false(loadid_trace_worker_open(w));
    assert_int_equal(loadid_trace_worker_begin(w, 7000), 0);
    row_of(7000, "c", &e);
    assert_int_equal(loadid_trace_worker_row(w, &e), 0);
    assert_int_equal(loadid_trace_worker_begin(w, 9000), 0); /* ends the one open */
    assert_int_equal(loadid_trace_worker_end(w, NULL), 0);   /* no row: load-9000 */
    loadid_trace_worker_stop(w);
    char got[16384], want[16384], first[4096];
    messages(w, got, sizeof got);
    snprintf(want, sizeof want,
             "traced %s/a_b-5000.trace.csv (3 rows)|traced %s/c-7000.trace.csv (1 rows)|"
             "traced %s/load-9000.trace.csv (0 rows)|",
             g_dir, g_dir, g_dir);
    assert_string_equal(got, want);
    char path[256];
    snprintf(path, sizeof path, "%s/a_b-5000.trace.csv", g_dir);
    assert_int_equal(count_lines(path, first, sizeof first), 4);
    assert_memory_equal(first, "0.001,RTLS,1,7,0,0,0,0,", 23); /* t_s from START */
    snprintf(path, sizeof path, "%s/.trace-1000.csv.tmp", g_dir);
    assert_int_not_equal(access(path, F_OK), 0);
    loadid_trace_worker_destroy(w);
}

static void *drain(void *arg) {
    const int fd = open(arg, O_RDONLY);
    char buf[65536];
    long lines = 0;
    ssize_t n;
    while (fd >= 0 && (n = read(fd, buf, sizeof buf)) > 0)
        for (ssize_t i = 0; i < n; ++i) lines += buf[i] == '\n';
    if (fd >= 0) close(fd);
    return (void *)lines;
}

static void stalled_disk_drops_rows_and_never_waits(void **state) {
    (void)state;
    char fifo[128];
    snprintf(fifo, sizeof fifo, "%s/.trace-1000.csv.tmp", g_dir);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    loadid_trace_worker_t *w;
    assert_int_equal(loadid_trace_worker_start(g_dir, &w), 0);
    assert_int_equal(loadid_trace_worker_begin(w, 1000), 0);
    loadid_pipeline_estimate_t e;
    int said = 0;
    for (int k = 0; k < 5000; ++k) {
        row_of(1000 + k, "", &e);
        said += loadid_trace_worker_row(w, &e) == -ENOBUFS;
    }
    assert_int_equal(said, 1);
    row_of(9, "o", &e);
    assert_int_equal(loadid_trace_worker_end(w, &e), 0); /* its entry was kept free */
    /* The disk moves on: BEGIN's entry and 4093 rows were queued (two entries kept free). */
    pthread_t reader;
    assert_int_equal(pthread_create(&reader, NULL, drain, fifo), 0);
    loadid_trace_worker_stop(w);
    void *lines;
    pthread_join(reader, &lines);
    assert_int_equal((long)lines, 1 + 4093);
    char got[16384], want[16384];
    messages(w, got, sizeof got);
    snprintf(want, sizeof want,
             "traced %s/o-9.trace.csv (4093 rows; 907 more dropped: the writer fell behind)|",
             g_dir);
    assert_string_equal(got, want);
    loadid_trace_worker_destroy(w);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(sessions_named_as_saved_results, make_dir, remove_dir),
        cmocka_unit_test_setup_teardown(stalled_disk_drops_rows_and_never_waits, make_dir,
                                        remove_dir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
