/*
 * The per-sample path of the core (update and estimate of every method,
 * both parameter counts, including RTLS's initial SVD and its rank-growing
 * branch; joint states into the Kalman filters, their retuning to a measured
 * encoder noise, the signal sources with
 * forward kinematics, and their refusals; the offline smoother on a
 * caller's work space) performs no heap allocation, takes no lock and makes
 * no system call:
 *  - malloc, calloc, realloc, free and the aligned allocators are
 *    interposed and counted (C++ operator new ends in malloc too), and so
 *    are the pthread mutex and rwlock lock calls (no lock either);
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
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <linux/seccomp.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "dataset.h"
#include "loadid/core.h"

/* ---- allocation counting: alloc_counter.c ---- */
#include "alloc_counter.h"

/* ---- the workload ---- */
static const loadid_method_t kAll[] = {LOADID_METHOD_RLS, LOADID_METHOD_RIV, LOADID_METHOD_RTLS,
                                       LOADID_METHOD_LS_BATCH, LOADID_METHOD_TLS_BATCH};
enum { NEST = 10, NSAMPLES = 300 };

enum { NJ = 7 };

typedef struct {
    dataset_t d[2];
    loadid_est_t *est[NEST];
    loadid_signals_t *sig;
    loadid_signals_t *sig_lag; /* with the fixed-lag smoother */
    int settle;                /* the filters' settling count (joint_filter.h) */
    int64_t t_us[NSAMPLES];
    loadid_real_t q[NSAMPLES][NJ];
    loadid_real_t *smooth_work;
    loadid_real_t q1[NSAMPLES], smoothed[3][NSAMPLES];
} workload_t;

/* A 7-joint arm (axes alternating z, y, x; one prismatic joint), and a
 * sampled smooth motion of it. */
static void signals_make(workload_t *w) {
    loadid_chain_t c;
    memset(&c, 0, sizeof c);
    strcpy(c.base_link, "base");
    strcpy(c.sensor_link, "sensor");
    c.num_joints = NJ;
    const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < NJ; ++i) {
        loadid_joint_desc_t *j = &c.joints[i];
        j->name[0] = (char)('a' + i);
        j->type = i == 3 ? LOADID_JOINT_PRISMATIC : LOADID_JOINT_REVOLUTE;
        j->origin_xyz[0] = 0.05 * i, j->origin_xyz[2] = 0.1;
        memcpy(j->origin_rot, id, sizeof id);
        j->axis[2 - i % 3] = 1;
        j->lower = -1e9, j->upper = 1e9, j->velocity = 1e9;
    }
    memcpy(c.tip_rot, id, sizeof id);
    const double g[3] = {0, 0, -9.81};
    loadid_signals_config_t cfg;
    loadid_signals_config_default(&cfg);
    assert_int_equal(loadid_signals_create(&c, g, &cfg, &w->sig), 0);
    loadid_jf_t *jf = NULL;
    assert_int_equal(loadid_jf_create(NJ, &cfg.measured, &jf), 0);
    w->settle = loadid_jf_settle_steps(jf);
    loadid_jf_destroy(jf);
    assert_true(w->settle > 0 && w->settle < NSAMPLES / 4);
    cfg.measured.lag_steps = cfg.setpoint.lag_steps = 20;
    assert_int_equal(loadid_signals_create(&c, g, &cfg, &w->sig_lag), 0);
    for (int k = 0; k < NSAMPLES; ++k) {
        w->t_us[k] = 1700000000000000LL + 1000LL * k;
        for (int i = 0; i < NJ; ++i) w->q[k][i] = (loadid_real_t)(0.3 * sin(0.01 * k * (i + 1)));
        w->q1[k] = w->q[k][1];
    }
    w->smooth_work = calloc(loadid_jf_smooth_work_size(NSAMPLES), sizeof *w->smooth_work);
    assert_non_null(w->smooth_work);
}

/* Every sample: a joint state, then the sensor sample 0.3 ms later; a bad
 * joint message and a stale sample in the middle; then the smoother over
 * one joint. Returns the number of unexpected return codes. */
static int signals_run(workload_t *w) {
    int bad = 0;
    const loadid_real_t spec[3] = {0, 0, 9.81}, alpha[3] = {0, 0, 0};
    for (int k = 0; k < NSAMPLES; ++k) {
        if (loadid_signals_push_joints(w->sig, w->t_us[k], NJ, w->q[k], w->q[k]) != 0) ++bad;
        loadid_regressor_input_t m, instr;
        /* (refused while the filters settle: joint_filter.h) */
        if (loadid_signals_at(w->sig, w->t_us[k] + 300, spec, alpha, NULL, &m, &instr) !=
            (k < w->settle ? LOADID_E_STALE : 0))
            ++bad;
        /* The fixed-lag smoother serves a sample 20 joint states later. */
        if (loadid_signals_push_joints(w->sig_lag, w->t_us[k], NJ, w->q[k], w->q[k]) != 0) ++bad;
        if (k >= 21 && loadid_signals_last_joint_time(w->sig_lag) != w->t_us[k - 19] - 1) ++bad;
        if (k >= 21 && loadid_signals_at(w->sig_lag, w->t_us[k - 20] + 300, spec, alpha, NULL, &m,
                                         &instr) != (k - 20 < w->settle ? LOADID_E_STALE : 0))
            ++bad;
        if (k == NSAMPLES / 2) {
            if (loadid_signals_push_joints(w->sig, w->t_us[k], NJ, w->q[k], NULL) !=
                LOADID_E_TIME_ORDER)
                ++bad;
            if (loadid_signals_at(w->sig, w->t_us[k] + 60000, spec, alpha, NULL, &m, &instr) !=
                LOADID_E_STALE)
                ++bad;
            loadid_kin_state_t st;
            if (loadid_signals_kinematics_at(w->sig, w->t_us[k], &st) != 0) ++bad;
            /* The pipeline's retune (coarser encoders): their noise, and the
             * filters' and the smoother's gains derived again in place. */
            if (loadid_signals_position_noise_count(w->sig) <= 0 ||
                !(loadid_signals_position_noise(w->sig) >= 0))
                ++bad;
            if (loadid_signals_retune(w->sig, 1e-4, 0) <= 0) ++bad;
            if (loadid_signals_retune(w->sig_lag, 1e-4, 20000) <= 0) ++bad;
        }
    }
    /* The stamp clock's look-ahead: two lost states (held until four
     * stamps after them confirm it), then a far stamp the stream's stall
     * releases. */
    int64_t t = w->t_us[NSAMPLES - 1] + 3000;
    loadid_real_t q[NJ];
    for (int k = 0; k < 4; ++k, t += 1000) {
        if (loadid_signals_push_joints(w->sig_lag, t, NJ, w->q[NSAMPLES - 1], NULL) != 0) ++bad;
        if (loadid_signals_fed_count(w->sig_lag) != (k < 3 ? 0 : 4)) ++bad;
    }
    if (llabs(loadid_signals_fed_state(w->sig_lag, 3, q) - (t - 1000)) > 2) ++bad;
    if (loadid_signals_push_joints(w->sig_lag, t + 5000, NJ, w->q[NSAMPLES - 1], NULL) != 0 ||
        loadid_signals_fed_count(w->sig_lag) != 0)
        ++bad;
    if (loadid_signals_end_piece(w->sig_lag) != 0 || loadid_signals_fed_count(w->sig_lag) != 1)
        ++bad;
    loadid_jf_config_t jcfg;
    loadid_jf_config_default(&jcfg);
    if (loadid_jf_smooth(&jcfg, NSAMPLES, w->t_us, w->q1, w->smooth_work, w->smoothed[0],
                         w->smoothed[1], w->smoothed[2]) != 0)
        ++bad;
    if (loadid_signals_reset(w->sig) != 0) ++bad;
    if (loadid_signals_reset(w->sig_lag) != 0) ++bad;
    return bad;
}

static void workload_make(workload_t *w) {
    const loadid_synth_noise_t noise = {
        .sigma_f = 0.1,
        .sigma_tau = 0.005,
        .sigma_spec = 0.5,
        .sigma_alpha = 5.0,
        .sigma_omega = 0.02,
    };
    for (int i = 0; i < 2; ++i) {
        dataset_spec_t spec = {
            .seed = 9, .n_samples = NSAMPLES, .n_params = i ? 16 : 10, .noise = noise};
        assert_int_equal(dataset_make(&spec, &w->d[i]), 0);
        for (int m = 0; m < 5; ++m) {
            loadid_est_config_t cfg;
            dataset_config(&spec, kAll[m], &cfg);
            cfg.rtls_ortho_tol = 1e-15; /* also exercise re-orthogonalisation */
            assert_int_equal(loadid_est_create(&cfg, &w->est[i * 5 + m]), 0);
        }
    }
    signals_make(w);
}

static void workload_free(workload_t *w) {
    for (int i = 0; i < NEST; ++i) loadid_est_destroy(w->est[i]);
    loadid_signals_destroy(w->sig);
    loadid_signals_destroy(w->sig_lag);
    free(w->smooth_work);
    dataset_free(&w->d[0]);
    dataset_free(&w->d[1]);
}

/* Every sample an update; an estimate after most, 1 to 5 samples apart
 * (the daemon publishes every sample or every publish_every-th: RTLS's
 * blocks of 1, 2, 3 and 4 samples, rtls.hpp); a NaN sample in the middle
 * (the rejection path); at the end what the daemon does at DONE (the
 * uncertainty and the load model) and at START (new weights), then a
 * reset. Returns the number of unexpected return codes. */
static int workload_run(workload_t *w) {
    int bad = 0;
    for (int i = 0; i < NEST; ++i) {
        const dataset_t *d = &w->d[i / 5];
        for (int k = 0; k < NSAMPLES; ++k) {
            if (loadid_est_update(w->est[i], dataset_A(d, k), dataset_C(d, k), dataset_y(d, k)) !=
                0)
                ++bad;
            const int r = k % 15; /* gaps of 1, 2, 3, 4 and 5 samples */
            if (k <= 20 || r == 0 || r == 2 || r == 5 || r == 9 || r == 14) {
                loadid_real_t phi[16];
                loadid_est_info_t info;
                const int rc = loadid_est_estimate(w->est[i], phi, &info);
                if (rc != 0 && rc != LOADID_E_NOT_EXCITED) ++bad;
            }
            if (k == NSAMPLES / 2) {
                loadid_real_t y[6];
                memcpy(y, dataset_y(d, k), sizeof y);
                y[2] = (loadid_real_t)__builtin_nan("");
                if (loadid_est_update(w->est[i], dataset_A(d, k), dataset_C(d, k), y) !=
                    LOADID_E_NONFINITE)
                    ++bad;
            }
        }
        loadid_real_t phi[16], std[16], scale;
        const int rc_e = loadid_est_estimate(w->est[i], phi, NULL);
        const int rc_u = loadid_est_uncertainty(w->est[i], phi, std, &scale);
        if ((rc_e != 0 && rc_e != LOADID_E_NOT_EXCITED) || rc_u != 0) ++bad;
        loadid_model_config_t mc;
        loadid_model_config_default(&mc);
        loadid_load_model_t model;
        loadid_real_t snr[3];
        if (loadid_est_signal_to_noise(w->est[i], phi, snr) != 0) ++bad;
        if (loadid_load_model(phi, std, snr, &mc, &model) != 0) ++bad;
        /* estimation.rescale_s: residual scales and the re-weighting. */
        loadid_real_t sc[2];
        if (loadid_est_residual_scales(w->est[i], NULL, sc) != 0) ++bad;
        const loadid_method_t m = loadid_est_config(w->est[i])->method;
        const int rc_s = loadid_est_rescale(w->est[i], 2, 3, 2);
        if (m == LOADID_METHOD_RLS || m == LOADID_METHOD_RIV ? rc_s != -ENOTSUP : rc_s != 0) ++bad;
        const loadid_est_config_t *c = loadid_est_config(w->est[i]);
        loadid_real_t rows[6], cols[LOADID_MAX_PARAMS + 1];
        memcpy(rows, c->row_sigma, sizeof rows);
        memcpy(cols, c->col_weight, sizeof cols);
        if (loadid_est_set_weights(w->est[i], rows, cols) != 0) ++bad;
        if (loadid_est_reset(w->est[i]) != 0) ++bad;
    }
    return bad + signals_run(w);
}

static void test_update_and_estimate_do_not_allocate(void **state) {
    (void)state;
    static workload_t w;
    workload_make(&w);
    /* The counter works: a plain malloc is seen. */
    alloc_counting = 1;
    void *volatile p = malloc(16); /* volatile: not elided as a malloc/free pair */
    alloc_counting = 0;
    free(p);
    assert_int_equal(alloc_count, 1);
    /* So is a lock. */
    static pthread_mutex_t mutex = PTHREAD_MUTEX_INITIALIZER;
    alloc_counting = 1;
    pthread_mutex_lock(&mutex);
    alloc_counting = 0;
    pthread_mutex_unlock(&mutex);
    assert_int_equal(lock_count, 1);
    alloc_count = lock_count = 0;
    alloc_counting = 1;
    const int bad = workload_run(&w);
    alloc_counting = 0;
    print_message("allocations during %d updates+estimates of %d estimators: %ld; locks: %ld\n",
                  NSAMPLES, NEST, alloc_count, lock_count);
    assert_int_equal(bad, 0);
    assert_int_equal(alloc_count, 0);
    assert_int_equal(lock_count, 0);
    workload_free(&w);
}

static void test_update_and_estimate_make_no_system_call(void **state) {
    (void)state;
    static workload_t w;
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
        print_message("child killed by signal %d: a system call in the per-sample path\n",
                      WTERMSIG(status));
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
