/*
 * The save worker (host/src/daemon/save_worker.h), which writes loadidd's
 * finished estimates off its loop:
 *  - saves come out in order, each "saved PATH", and the files read back
 *    (saved_result.h) as the estimates submitted;
 *  - a save that fails comes back as the reason;
 *  - a stalled disk (the worker held in open() of a FIFO, which waits for
 *    a reader) does not hold up submit: it returns at once, until the
 *    ring is full, which it says (-EBUSY) instead of waiting; once the
 *    disk moves on, what waited is saved.
 * A load model's groups not identified are said why in comments, and the
 * file reads back.
 * The loop's side making no file-system call in a real session is
 * tests/python/test_systemd_unit.py's.
 */
#define _DEFAULT_SOURCE /* mkdtemp, mkfifo */
#include <errno.h>
#include <fcntl.h>
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
#include "loadid/load_model.h"
#include "loadid/regressor.h"
#include "save_worker.h"
#include "saved_result.h"
#include "scratch_dir.h"

static char g_dir[64];

static int make_dir(void **state) {
    (void)state;
    return scratch_dir_make(g_dir, sizeof g_dir, "save");
}

static int remove_dir(void **state) {
    (void)state;
    return scratch_dir_remove(g_dir);
}

/* An estimate of its own for each k. */
static void estimate(int k, loadid_pipeline_estimate_t *e, loadid_pipeline_compensation_t *c) {
    memset(e, 0, sizeof *e);
    memset(c, 0, sizeof *c);
    e->utime = 1700000000000000 + k;
    e->samples = 1500;
    e->method = LOADID_METHOD_RTLS;
    e->state = 3;
    e->valid = 1;
    snprintf(e->load_name, sizeof e->load_name, "o%d", k);
    for (int i = 0; i < 10; ++i) e->phi[i] = k + 0.1 * i;
    e->mass = e->phi[0];
    c->n_params = 10;
    for (int i = 0; i < 10; ++i) c->phi_total[i] = e->phi[i] + 1;
    c->zeroed = 1;
    c->g_init[2] = 9.81;
    for (int i = 0; i < 60; ++i) c->zero_a[i] = k - 0.01 * i;
}

static void check_saved(const char *msg, int k) {
    char want[256];
    snprintf(want, sizeof want, "saved %s/o%d-%lld.yaml", g_dir, k, 1700000000000000LL + k);
    assert_string_equal(msg, want);
    loadid_pipeline_estimate_t e, back;
    loadid_pipeline_compensation_t c, cback;
    estimate(k, &e, &c);
    char err[4600];
    assert_int_equal(loadid_saved_result_read(msg + 6, &back, &cback, err, sizeof err), 0);
    assert_string_equal(back.load_name, e.load_name);
    assert_true(back.utime == e.utime);
    assert_memory_equal(back.phi, e.phi, sizeof e.phi);
    assert_memory_equal(cback.phi_total, c.phi_total, sizeof c.phi_total);
    assert_memory_equal(cback.zero_a, c.zero_a, sizeof c.zero_a);
}

/* A saved result without zero_regressor (written before it was saved)
 * was zeroed at rest: eq. (6) there, A(-g_init, 0, 0), comes back. */
static void zeroing_regressor_defaults_to_rest(void **state) {
    (void)state;
    loadid_pipeline_estimate_t e, back;
    loadid_pipeline_compensation_t c, cback;
    estimate(5, &e, &c);
    c.g_init[0] = 1.0, c.g_init[1] = -2.0, c.g_init[2] = -9.5;
    char path[256], old[160], err[512];
    snprintf(old, sizeof old, "%s/without.yaml", g_dir);
    assert_int_equal(loadid_saved_result_write(g_dir, &e, &c, path, sizeof path, err, sizeof err),
                     0);
    FILE *in = fopen(path, "r"), *out = fopen(old, "w");
    assert_non_null(in);
    assert_non_null(out);
    char line[4096];
    int dropped = 0;
    while (fgets(line, sizeof line, in))
        if (strstr(line, "zero_regressor:"))
            dropped++;
        else
            fputs(line, out);
    fclose(in);
    fclose(out);
    assert_int_equal(dropped, 1);
    assert_int_equal(loadid_saved_result_read(path, &back, &cback, err, sizeof err), 0);
    assert_memory_equal(cback.zero_a, c.zero_a, sizeof c.zero_a);
    assert_int_equal(loadid_saved_result_read(old, &back, &cback, err, sizeof err), 0);
    const loadid_real_t spec[3] = {-1.0, 2.0, 9.5}, zero[3] = {0, 0, 0};
    loadid_real_t a[60];
    assert_int_equal(loadid_regressor(spec, zero, zero, a), 0);
    for (int i = 0; i < 60; ++i) assert_true(cback.zero_a[i] == (double)a[i]);
}

/* A load model's groups not identified are said why in comments, for
 * people; the file reads back with the groups it identified. */
static void unidentified_groups_are_commented(void **state) {
    (void)state;
    loadid_pipeline_estimate_t e, back;
    loadid_pipeline_compensation_t c, cback;
    estimate(6, &e, &c);
    e.has_model = 1;
    e.identified = LOADID_IDENT_MASS;
    e.ident_why[1] = LOADID_WHY_STD, e.ident_over[1] = 1.2;
    e.ident_why[2] = LOADID_WHY_NEEDS;
    for (int i = 0; i < 10; ++i) e.model_phi[i] = e.phi[i];
    char path[256], err[512], text[8192];
    assert_int_equal(loadid_saved_result_write(g_dir, &e, &c, path, sizeof path, err, sizeof err),
                     0);
    FILE *in = fopen(path, "r");
    assert_non_null(in);
    const size_t n = fread(text, 1, sizeof text - 1, in);
    fclose(in);
    text[n] = '\0';
    assert_non_null(strstr(text,
                           "  identified: [mass]\n"
                           "  # com not identified: phi_std 1.2 times its bound\n"
                           "  # inertia not identified: needs the com\n"));
    assert_null(strstr(text, "# mass not identified"));
    assert_int_equal(loadid_saved_result_read(path, &back, &cback, err, sizeof err), 0);
    assert_int_equal(back.identified, LOADID_IDENT_MASS);
}

static void saves_in_order(void **state) {
    (void)state;
    loadid_save_worker_t *w = NULL;
    assert_int_equal(loadid_save_worker_start(g_dir, &w), 0);
    for (int k = 1; k <= 3; ++k) {
        loadid_pipeline_estimate_t e;
        loadid_pipeline_compensation_t c;
        estimate(k, &e, &c);
        assert_int_equal(loadid_save_worker_submit(w, &e, &c), 0);
    }
    loadid_save_worker_stop(w); /* the three end first */
    char msg[4608];
    for (int k = 1; k <= 3; ++k) {
        assert_int_equal(loadid_save_worker_collect(w, msg, sizeof msg), 1);
        check_saved(msg, k);
    }
    assert_int_equal(loadid_save_worker_collect(w, msg, sizeof msg), 0);
    loadid_save_worker_destroy(w);
    /* latest.yaml is the last one's */
    char latest[128];
    snprintf(latest, sizeof latest, "%s/latest.yaml", g_dir);
    loadid_pipeline_estimate_t back;
    loadid_pipeline_compensation_t cback;
    assert_int_equal(loadid_saved_result_read(latest, &back, &cback, msg, sizeof msg), 0);
    assert_string_equal(back.load_name, "o3");
}

static void failure_comes_back_as_the_reason(void **state) {
    (void)state;
    char file[128], dir[160];
    snprintf(file, sizeof file, "%s/plain", g_dir);
    const int fd = open(file, O_WRONLY | O_CREAT, 0644);
    assert_true(fd >= 0);
    close(fd);
    snprintf(dir, sizeof dir, "%s/results", file); /* under a regular file */
    loadid_save_worker_t *w = NULL;
    assert_int_equal(loadid_save_worker_start(dir, &w), 0);
    loadid_pipeline_estimate_t e;
    loadid_pipeline_compensation_t c;
    estimate(1, &e, &c);
    assert_int_equal(loadid_save_worker_submit(w, &e, &c), 0);
    loadid_save_worker_stop(w);
    char msg[4608], want[256];
    assert_int_equal(loadid_save_worker_collect(w, msg, sizeof msg), -1);
    snprintf(want, sizeof want, "%s: cannot create: Not a directory", dir);
    assert_string_equal(msg, want);
    loadid_save_worker_destroy(w);
}

static void stalled_disk_does_not_hold_up_submit(void **state) {
    (void)state;
    /* The first save's temporary file is a FIFO: the worker's open() waits
     * for a reader, as a write would wait for a stalled disk. */
    char fifo[160];
    snprintf(fifo, sizeof fifo, "%s/o1-%lld.yaml.tmp", g_dir, 1700000000000001LL);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    loadid_save_worker_t *w = NULL;
    assert_int_equal(loadid_save_worker_start(g_dir, &w), 0);
    loadid_pipeline_estimate_t e;
    loadid_pipeline_compensation_t c;
    for (int k = 1; k <= LOADID_SAVE_WORKER_SLOTS; ++k) {
        estimate(k, &e, &c);
        assert_int_equal(loadid_save_worker_submit(w, &e, &c), 0);
    }
    estimate(99, &e, &c);
    assert_int_equal(loadid_save_worker_submit(w, &e, &c), -EBUSY); /* full: not waiting */
    char msg[4608];
    assert_int_equal(loadid_save_worker_collect(w, msg, sizeof msg), 0); /* none ended */
    /* The disk moves on: a reader takes the document; fsync of a FIFO
     * fails (EINVAL), so that one save fails, and the others go through. */
    const int rd = open(fifo, O_RDONLY);
    assert_true(rd >= 0);
    char buf[8192];
    size_t got = 0;
    ssize_t r;
    while ((r = read(rd, buf + got, sizeof buf - got)) > 0) got += (size_t)r;
    close(rd);
    assert_true(got > 500 && !memcmp(buf, "# A load estimated by loadidd", 29));
    loadid_save_worker_stop(w);
    assert_int_equal(loadid_save_worker_collect(w, msg, sizeof msg), -1);
    assert_non_null(strstr(msg, "o1-1700000000000001.yaml: cannot write: Invalid argument"));
    for (int k = 2; k <= LOADID_SAVE_WORKER_SLOTS; ++k) {
        assert_int_equal(loadid_save_worker_collect(w, msg, sizeof msg), 1);
        check_saved(msg, k);
    }
    assert_int_equal(loadid_save_worker_collect(w, msg, sizeof msg), 0);
    loadid_save_worker_destroy(w);
    assert_int_equal(access(fifo, F_OK), -1); /* the failed save's .tmp removed */
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(saves_in_order, make_dir, remove_dir),
        cmocka_unit_test_setup_teardown(failure_comes_back_as_the_reason, make_dir, remove_dir),
        cmocka_unit_test_setup_teardown(stalled_disk_does_not_hold_up_submit, make_dir, remove_dir),
        cmocka_unit_test_setup_teardown(zeroing_regressor_defaults_to_rest, make_dir, remove_dir),
        cmocka_unit_test_setup_teardown(unidentified_groups_are_commented, make_dir, remove_dir),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
