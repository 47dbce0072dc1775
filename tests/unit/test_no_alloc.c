/*
 * The per-sample path of the core (update and estimate of every method,
 * both parameter counts, including RTLS's initial SVD and its rank-growing
 * branch) performs no heap allocation and no system call:
 *  - malloc, calloc, realloc, free and the aligned allocators are
 *    interposed and counted (C++ operator new ends in malloc too);
 *  - the same loop runs in a child under SECCOMP_MODE_STRICT, where any
 *    system call but read, write, _exit and sigreturn kills the process.
 * Not built with the sanitizers, whose allocator and runtime conflict with
 * both techniques.
 */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <linux/seccomp.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "dataset.h"

/* ---- allocation counting by interposition ---- */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);

static volatile int counting;
static volatile long allocations;

void *malloc(size_t n) {
    if (counting) ++allocations;
    return __libc_malloc(n);
}
void *calloc(size_t n, size_t s) {
    if (counting) ++allocations;
    return __libc_calloc(n, s);
}
void *realloc(void *p, size_t n) {
    if (counting) ++allocations;
    return __libc_realloc(p, n);
}
void free(void *p) {
    if (counting && p) ++allocations;
    __libc_free(p);
}
void *aligned_alloc(size_t a, size_t n) {
    if (counting) ++allocations;
    return __libc_memalign(a, n);
}
void *memalign(size_t a, size_t n) {
    if (counting) ++allocations;
    return __libc_memalign(a, n);
}
int posix_memalign(void **out, size_t a, size_t n) {
    if (counting) ++allocations;
    *out = __libc_memalign(a, n);
    return *out ? 0 : 12 /* ENOMEM */;
}

/* ---- the workload ---- */
static const loadid_method_t kAll[] = {LOADID_METHOD_RLS, LOADID_METHOD_RIV, LOADID_METHOD_RTLS,
                                       LOADID_METHOD_LS_BATCH, LOADID_METHOD_TLS_BATCH};
enum { NEST = 10, NSAMPLES = 300 };

typedef struct {
    dataset_t d[2];
    loadid_est_t *est[NEST];
} workload_t;

static void workload_make(workload_t *w) {
    const loadid_synth_noise_t noise = {
        .sigma_f = 0.1, .sigma_tau = 0.005, .sigma_spec = 0.5, .sigma_alpha = 5.0, .sigma_omega = 0.02,
    };
    for (int i = 0; i < 2; ++i) {
        dataset_spec_t spec = {.seed = 9, .n_samples = NSAMPLES, .n_params = i ? 16 : 10, .noise = noise};
        assert_int_equal(dataset_make(&spec, &w->d[i]), 0);
        for (int m = 0; m < 5; ++m) {
            loadid_est_config_t cfg;
            dataset_config(&spec, kAll[m], &cfg);
            cfg.rtls_ortho_tol = 1e-15; /* also exercise re-orthogonalisation */
            assert_int_equal(loadid_est_create(&cfg, &w->est[i * 5 + m]), 0);
        }
    }
}

static void workload_free(workload_t *w) {
    for (int i = 0; i < NEST; ++i) loadid_est_destroy(w->est[i]);
    dataset_free(&w->d[0]);
    dataset_free(&w->d[1]);
}

/* Every sample: update, then estimate (as the daemon publishes every
 * sample); a NaN sample in the middle (the rejection path); a reset at the
 * end. Returns the number of unexpected return codes. */
static int workload_run(workload_t *w) {
    int bad = 0;
    for (int i = 0; i < NEST; ++i) {
        const dataset_t *d = &w->d[i / 5];
        for (int k = 0; k < NSAMPLES; ++k) {
            if (loadid_est_update(w->est[i], dataset_A(d, k), dataset_C(d, k), dataset_y(d, k)) != 0) ++bad;
            loadid_real_t phi[16];
            loadid_est_info_t info;
            const int rc = loadid_est_estimate(w->est[i], phi, &info);
            if (rc != 0 && rc != LOADID_E_NOT_EXCITED) ++bad;
            if (k == NSAMPLES / 2) {
                loadid_real_t y[6];
                memcpy(y, dataset_y(d, k), sizeof y);
                y[2] = (loadid_real_t)__builtin_nan("");
                if (loadid_est_update(w->est[i], dataset_A(d, k), dataset_C(d, k), y) != LOADID_E_NONFINITE) ++bad;
            }
        }
        if (loadid_est_reset(w->est[i]) != 0) ++bad;
    }
    return bad;
}

static void test_update_and_estimate_do_not_allocate(void **state) {
    (void)state;
    workload_t w;
    workload_make(&w);
    /* The counter works: a plain malloc is seen. */
    counting = 1;
    void *p = malloc(16);
    counting = 0;
    free(p);
    assert_int_equal(allocations, 1);
    allocations = 0;
    counting = 1;
    const int bad = workload_run(&w);
    counting = 0;
    print_message("allocations during %d updates+estimates of %d estimators: %ld\n", NSAMPLES, NEST, allocations);
    assert_int_equal(bad, 0);
    assert_int_equal(allocations, 0);
    workload_free(&w);
}

static void test_update_and_estimate_make_no_system_call(void **state) {
    (void)state;
    workload_t w;
    workload_make(&w);
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(fd[0]);
        if (prctl(PR_SET_SECCOMP, SECCOMP_MODE_STRICT) != 0) syscall(SYS_exit, 3);
        const unsigned char bad = (unsigned char)workload_run(&w);
        if (write(fd[1], &bad, 1) != 1) syscall(SYS_exit, 4);
        syscall(SYS_exit, 0); /* exit_group is not allowed in strict mode */
    }
    close(fd[1]);
    unsigned char bad = 255;
    const ssize_t n = read(fd[0], &bad, 1);
    close(fd[0]);
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    if (WIFSIGNALED(status))
        print_message("child killed by signal %d: a system call in the per-sample path\n", WTERMSIG(status));
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
    assert_int_equal(n, 1);
    assert_int_equal(bad, 0);
    workload_free(&w);
}

/* The check can fail: a system call in the same setting kills the child. */
static void test_strict_seccomp_catches_a_system_call(void **state) {
    (void)state;
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        if (prctl(PR_SET_SECCOMP, SECCOMP_MODE_STRICT) != 0) syscall(SYS_exit, 3);
        (void)getppid();
        syscall(SYS_exit, 0);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFSIGNALED(status));
    assert_int_equal(WTERMSIG(status), SIGKILL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_update_and_estimate_do_not_allocate),
        cmocka_unit_test(test_update_and_estimate_make_no_system_call),
        cmocka_unit_test(test_strict_seccomp_catches_a_system_call),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
