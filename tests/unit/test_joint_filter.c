/*
 * Unit tests of loadid/joint_filter.h: the joint-space Kalman filter and
 * the Rauch-Tung-Striebel smoother. Built against the double and the float
 * core (the exact comparison with the textbook filter is double only).
 *
 * Every expected value is computed here, independently of the library:
 * the multi-sine joint trajectory and its derivatives analytically, the
 * encoder by rounding to the nearest of 2^20 counts per revolution, the
 * textbook Kalman filter by plain 3x3 matrix products in double, and the
 * quadratic of a constant acceleration in closed form.
 *
 * Figures of the default configuration on the multi-sine (3 s at 1 kHz,
 * 2^20 counts, double; float within 1 %), errors after 50 ms of settling:
 *   filter   qdd RMS 1.06 rad/s^2 (of 36.9 RMS), lag 2.0 ms, qd RMS 1.6e-3 rad/s
 *   smoother qdd RMS 0.26 rad/s^2, lag 0.0 ms, qd RMS 3.8e-4 rad/s
 *   jittered sampling (+-200 us): filter qdd RMS 1.06, lag 2.0 ms.
 * The bounds asserted are below.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <string.h>

#include "loadid/joint_filter.h"
#include "random_util.h"

#define IS_FLOAT (sizeof(loadid_real_t) == sizeof(float))

#define PI 3.14159265358979323846
#define T0 1700000000000000LL      /* epoch-like time stamps [us] */
#define N_SAMPLES 3000             /* 3 s at 1 kHz */
#define SETTLE 50                  /* samples (50 ms) left out of the error figures */
#define COUNT (2 * PI / 1048576.0) /* one encoder count [rad]: 2^20 per revolution */

/* Bounds on the multi-sine (figures measured: see the top). */
#define QDD_RMS_MAX 1.5       /* filter qdd RMS error [rad/s^2] */
#define QD_RMS_MAX 2.5e-3     /* filter qd RMS error [rad/s] */
#define LAG_MAX_MS 3.0        /* filter qdd lag [ms], searched over 0..30 ms */
#define SMOOTH_FACTOR 3.0     /* filter qdd RMS / smoother qdd RMS at least this */
#define SMOOTH_LAG_MAX_MS 0.2 /* |smoother qdd lag| [ms], searched over -30..30 ms */

/* ------------------------------------------------------------ trajectory */

/* q(t) = 0.4 + sum a_i sin(2 pi f_i t + phi_i): a robot joint, 0.5-2 Hz. */
static const double kAmp[3] = {0.8, 0.5, 0.3};   /* [rad] */
static const double kFreq[3] = {0.5, 1.1, 2.0};  /* [Hz] */
static const double kPhase[3] = {0.3, 1.2, 2.5}; /* [rad] */

/* The order-th time derivative of q at t [s] (order 0..3), exactly. */
static double traj(double t, int order) {
    double s = order == 0 ? 0.4 : 0;
    for (int i = 0; i < 3; ++i) {
        const double w = 2 * PI * kFreq[i];
        s += kAmp[i] * pow(w, order) * sin(w * t + kPhase[i] + order * PI / 2);
    }
    return s;
}

static double seconds_of(int64_t t_us) {
    return (double)(t_us - T0) * 1e-6;
}

static double quantise(double q) {
    return round(q / COUNT) * COUNT;
}

typedef struct {
    int n;
    int64_t t[N_SAMPLES];
    loadid_real_t z[N_SAMPLES]; /* encoder positions */
} series_t;

/* 1 kHz from T0, each stamp moved by a uniform integer in [-jitter, jitter]
 * us; positions at the true stamped times, quantised. */
static void make_series(series_t *s, int jitter_us, uint64_t seed) {
    loadid_rng_t rng;
    loadid_rng_seed(&rng, seed);
    s->n = N_SAMPLES;
    for (int k = 0; k < N_SAMPLES; ++k) {
        const int64_t j =
            jitter_us ? (int64_t)floor(uniform_in(&rng, -jitter_us, jitter_us + 1)) : 0;
        s->t[k] = T0 + 1000LL * k + j;
        s->z[k] = (loadid_real_t)quantise(traj(seconds_of(s->t[k]), 0));
    }
}

typedef struct {
    loadid_real_t x[3][N_SAMPLES]; /* q, qd, qdd per sample */
} estimate_t;

/* The on-line filter, read at each sample's time just after its update. */
static void run_filter(const loadid_jf_config_t *cfg, const series_t *s, estimate_t *e) {
    loadid_jf_t *jf = NULL;
    assert_int_equal(loadid_jf_create(1, cfg, &jf), 0);
    for (int k = 0; k < s->n; ++k) {
        assert_int_equal(loadid_jf_update(jf, s->t[k], &s->z[k]), 0);
        assert_int_equal(loadid_jf_state_at(jf, s->t[k], &e->x[0][k], &e->x[1][k], &e->x[2][k]), 0);
    }
    loadid_jf_destroy(jf);
}

static loadid_real_t g_work[18 * N_SAMPLES];

static void run_smoother(const loadid_jf_config_t *cfg, const series_t *s, estimate_t *e) {
    assert_true(loadid_jf_smooth_work_size((size_t)s->n) <= sizeof g_work / sizeof *g_work);
    assert_int_equal(
        loadid_jf_smooth(cfg, (size_t)s->n, s->t, s->z, g_work, e->x[0], e->x[1], e->x[2]), 0);
}

/* RMS over samples [k0, k1) of est_k - q^(order)(t_k - delay). */
static double rms_error(const series_t *s, const loadid_real_t *est, int order, double delay_s,
                        int k0, int k1) {
    double sum = 0;
    for (int k = k0; k < k1; ++k) {
        const double e = est[k] - traj(seconds_of(s->t[k]) - delay_s, order);
        sum += e * e;
    }
    return sqrt(sum / (k1 - k0));
}

/* RMS over samples [k0, k1) of q^(order)(t_k) itself. */
static double true_rms(const series_t *s, int order, int k0, int k1) {
    double sum = 0;
    for (int k = k0; k < k1; ++k) sum += pow(traj(seconds_of(s->t[k]), order), 2);
    return sqrt(sum / (k1 - k0));
}

/* The delay [ms] in [lo_ms, hi_ms], on a 0.1 ms grid, that minimises that RMS. */
static double lag_ms(const series_t *s, const loadid_real_t *est, int order, int k0, int k1,
                     int lo_ms, int hi_ms) {
    double best = INFINITY, lag = NAN;
    for (int d = 10 * lo_ms; d <= 10 * hi_ms; ++d) {
        const double r = rms_error(s, est, order, d * 1e-4, k0, k1);
        if (r < best) best = r, lag = d * 0.1;
    }
    return lag;
}

static loadid_jf_config_t default_config(void) {
    loadid_jf_config_t c;
    assert_int_equal(loadid_jf_config_default(&c), 0);
    return c;
}

static series_t g_series;
static estimate_t g_filt, g_smooth;

/* ---------------------------------------------------------------- tests */

static void test_config_default(void **state) {
    (void)state;
    const loadid_jf_config_t c = default_config();
    ASSERT_CLOSE(c.meas_sigma, 2 * PI / 1048576.0 / sqrt(12.0), 1e-6 * c.meas_sigma, "meas_sigma");
    assert_true(c.jerk_psd > 0 && c.init_sigma_vel > 0 && c.init_sigma_acc > 0);
    assert_true(c.max_step_us == 100000);
    assert_int_equal(loadid_jf_config_default(NULL), -EINVAL);
}

/* Filter on the quantised multi-sine: qdd and qd RMS, qdd lag. */
static void check_filter_figures(const series_t *s, const char *what) {
    const loadid_jf_config_t c = default_config();
    run_filter(&c, s, &g_filt);
    const double qdd = rms_error(s, g_filt.x[2], 2, 0, SETTLE, s->n);
    const double qd = rms_error(s, g_filt.x[1], 1, 0, SETTLE, s->n);
    const double q = rms_error(s, g_filt.x[0], 0, 0, SETTLE, s->n);
    const double lag = lag_ms(s, g_filt.x[2], 2, SETTLE, s->n, 0, 30);
    print_message(
        "%s filter: qdd RMS %.3f rad/s^2 (true %.1f), lag %.1f ms, "
        "qd RMS %.2e rad/s, q RMS %.2e rad\n",
        what, qdd, true_rms(s, 2, SETTLE, s->n), lag, qd, q);
    assert_true(qdd < QDD_RMS_MAX);
    assert_true(qd < QD_RMS_MAX);
    assert_true(lag < LAG_MAX_MS);
    assert_true(q < 3 * COUNT / sqrt(12.0)); /* not worse than a few quantisation steps */
}

static void test_filter_multisine(void **state) {
    (void)state;
    make_series(&g_series, 0, 1);
    check_filter_figures(&g_series, "1 kHz");
}

/* Irregular sampling: the model takes dt from the stamps. */
static void test_filter_jittered(void **state) {
    (void)state;
    make_series(&g_series, 200, 7);
    check_filter_figures(&g_series, "1 kHz +-200 us");
}

/* The smoother over the same data: less error and no lag; its last sample
 * is the filter's (nothing after it to smooth with, RTS theory). */
static void check_smoother(const series_t *s) {
    const loadid_jf_config_t c = default_config();
    run_filter(&c, s, &g_filt);
    run_smoother(&c, s, &g_smooth);
    const double f_qdd = rms_error(s, g_filt.x[2], 2, 0, SETTLE, s->n);
    const double f_qd = rms_error(s, g_filt.x[1], 1, 0, SETTLE, s->n);
    const double s_qdd = rms_error(s, g_smooth.x[2], 2, 0, SETTLE, s->n - SETTLE);
    const double s_qd = rms_error(s, g_smooth.x[1], 1, 0, SETTLE, s->n - SETTLE);
    const double lag = lag_ms(s, g_smooth.x[2], 2, SETTLE, s->n - SETTLE, -30, 30);
    print_message(
        "smoother: qdd RMS %.3f rad/s^2 (filter %.3f), lag %.1f ms, "
        "qd RMS %.2e rad/s (filter %.2e)\n",
        s_qdd, f_qdd, lag, s_qd, f_qd);
    assert_true(s_qdd * SMOOTH_FACTOR < f_qdd);
    assert_true(s_qd < f_qd);
    assert_true(fabs(lag) <= SMOOTH_LAG_MAX_MS);
    const int last = s->n - 1;
    for (int i = 0; i < 3; ++i)
        ASSERT_CLOSE(g_smooth.x[i][last], g_filt.x[i][last], 1e-12 * (1 + fabs(g_filt.x[i][last])),
                     "smoother = filter at the last sample");
}

static void test_smoother_multisine(void **state) {
    (void)state;
    make_series(&g_series, 0, 1);
    check_smoother(&g_series);
    make_series(&g_series, 200, 7);
    check_smoother(&g_series);
}

/* A gap over max_step_us splits the series: the smoother over the whole is
 * the smoother over each piece, to the bit. */
static void test_smoother_gap(void **state) {
    (void)state;
    static series_t a, b;
    static estimate_t whole, pa, pb;
    make_series(&a, 0, 1);
    const int cut = 1200;
    memcpy(&b, &a, sizeof a);
    for (int k = cut; k < a.n; ++k) a.t[k] += 150000; /* a 151 ms step between cut-1 and cut */
    const loadid_jf_config_t c = default_config();
    run_smoother(&c, &a, &whole);
    series_t *piece = &b;
    piece->n = cut;
    run_smoother(&c, piece, &pa);
    for (int k = cut; k < a.n; ++k) piece->t[k - cut] = a.t[k], piece->z[k - cut] = a.z[k];
    piece->n = a.n - cut;
    run_smoother(&c, piece, &pb);
    for (int i = 0; i < 3; ++i) {
        assert_memory_equal(whole.x[i], pa.x[i], cut * sizeof(loadid_real_t));
        assert_memory_equal(whole.x[i] + cut, pb.x[i], (size_t)(a.n - cut) * sizeof(loadid_real_t));
    }
}

#if !LOADID_SCALAR_FLOAT
/* The textbook Kalman filter, written plainly with 3x3 products in double:
 * x = F x, P = F P F^T + Q; K = P H^T (H P H^T + R)^-1; x += K (z - H x);
 * P = (I - K H) P. */
typedef double m3_t[3][3];

static void m3_mul(const m3_t a, const m3_t b, m3_t c) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            c[i][j] = 0;
            for (int k = 0; k < 3; ++k) c[i][j] += a[i][k] * b[k][j];
        }
}

static void m3_transpose(const m3_t a, m3_t t) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) t[i][j] = a[j][i];
}

static void transition(double dt, m3_t F) {
    const m3_t f = {{1, dt, dt * dt / 2}, {0, 1, dt}, {0, 0, 1}};
    memcpy(F, f, sizeof f);
}

typedef struct {
    double x[3];
    m3_t P;
} ref_kf_t;

static void ref_init(ref_kf_t *r, double z, const loadid_jf_config_t *c) {
    memset(r, 0, sizeof *r);
    r->x[0] = z;
    r->P[0][0] = c->meas_sigma * c->meas_sigma;
    r->P[1][1] = c->init_sigma_vel * c->init_sigma_vel;
    r->P[2][2] = c->init_sigma_acc * c->init_sigma_acc;
}

static void ref_step(ref_kf_t *r, double dt, double z, const loadid_jf_config_t *c) {
    m3_t F, Ft, FP, Q;
    transition(dt, F);
    m3_transpose(F, Ft);
    const double x0[3] = {r->x[0], r->x[1], r->x[2]};
    for (int i = 0; i < 3; ++i) r->x[i] = F[i][0] * x0[0] + F[i][1] * x0[1] + F[i][2] * x0[2];
    const m3_t q = {{pow(dt, 5) / 20, pow(dt, 4) / 8, pow(dt, 3) / 6},
                    {pow(dt, 4) / 8, pow(dt, 3) / 3, pow(dt, 2) / 2},
                    {pow(dt, 3) / 6, pow(dt, 2) / 2, dt}};
    m3_mul(F, r->P, FP);
    m3_mul(FP, Ft, r->P);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Q[i][j] = c->jerk_psd * q[i][j], r->P[i][j] += Q[i][j];
    const double S = r->P[0][0] + c->meas_sigma * c->meas_sigma; /* H P H^T + R */
    double K[3];
    for (int i = 0; i < 3; ++i) K[i] = r->P[i][0] / S; /* P H^T S^-1 */
    const double innov = z - r->x[0];
    for (int i = 0; i < 3; ++i) r->x[i] += K[i] * innov;
    m3_t IKH, P;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) IKH[i][j] = (i == j) - (j == 0 ? K[i] : 0);
    m3_mul(IKH, r->P, P);
    memcpy(r->P, P, sizeof P);
}

static void assert_state(const loadid_jf_t *jf, int64_t t, const ref_kf_t *r, int n_ref,
                         int64_t t_ref) {
    loadid_real_t q[2], qd[2], qdd[2];
    assert_int_equal(loadid_jf_state_at(jf, t, q, qd, qdd), 0);
    m3_t F;
    transition((double)(t - t_ref) / 1e6, F);
    for (int j = 0; j < n_ref; ++j) {
        const loadid_real_t *got[3] = {q, qd, qdd};
        for (int i = 0; i < 3; ++i) {
            const double want = F[i][0] * r[j].x[0] + F[i][1] * r[j].x[1] + F[i][2] * r[j].x[2];
            ASSERT_CLOSE(got[i][j], want, 1e-9 * (1 + fabs(want)), "state vs textbook KF");
        }
    }
}

/* Irregular steps (1 us to 0.1 s = max_step_us, and one gap over it that
 * restarts), two joints with different signals and a non-default config. */
static void test_matches_textbook_kf(void **state) {
    (void)state;
    const loadid_jf_config_t c = {.jerk_psd = 2e4,
                                  .meas_sigma = 3e-6,
                                  .init_sigma_vel = 2,
                                  .init_sigma_acc = 40,
                                  .max_step_us = 100000};
    static const int64_t steps[] = {1000,  250,  3170,   999,  17,     40000, 1,    1000, 500,
                                    12345, 2000, 100000, 1000, 150000, 800,   1200, 1000, 1000};
    loadid_jf_t *jf = NULL;
    assert_int_equal(loadid_jf_create(2, &c, &jf), 0);
    ref_kf_t ref[2];
    int64_t t = T0 + 123;
    for (int k = 0; k < 400; ++k) {
        if (k > 0) t += steps[k % (int)(sizeof steps / sizeof *steps)];
        const double ts = seconds_of(t);
        const double z[2] = {quantise(traj(ts, 0)),
                             quantise(-0.5 * traj(ts, 0) + 0.1 * sin(37 * ts))};
        const loadid_real_t zr[2] = {z[0], z[1]};
        const int64_t prev = loadid_jf_last_time(jf);
        assert_int_equal(loadid_jf_update(jf, t, zr), 0);
        assert_true(loadid_jf_last_time(jf) == t);
        for (int j = 0; j < 2; ++j) {
            if (k == 0 || t - prev > c.max_step_us)
                ref_init(&ref[j], z[j], &c);
            else
                ref_step(&ref[j], (double)(t - prev) / 1e6, z[j], &c);
        }
        assert_state(jf, t, ref, 2, t);
        assert_state(jf, t + 333, ref, 2, t); /* the model's prediction, forwards */
        assert_state(jf, t - 777, ref, 2, t); /* and backwards */
    }
    loadid_jf_destroy(jf);
}
#endif

/* q = q0 + v0 t + a t^2 / 2 without noise: the model holds exactly, so the
 * filter converges to the exact state and state_at is the exact quadratic
 * at any time, before or after the last update. */
static void test_constant_acceleration(void **state) {
    (void)state;
    const double q0 = 0.3, v0 = 1.2, a = -5.0;
    const double tol = IS_FLOAT ? 0.1 : 1e-10; /* on qdd [rad/s^2]; qd and q tighter below */
    loadid_jf_config_t c = default_config();
    loadid_jf_t *jf = NULL, *twin = NULL;
    assert_int_equal(loadid_jf_create(1, &c, &jf), 0);
    assert_int_equal(loadid_jf_create(1, &c, &twin), 0);
    int64_t t = T0;
    for (int k = 0; k <= 1000; ++k, t += 1000) {
        const double ts = seconds_of(t);
        const loadid_real_t z = (loadid_real_t)(q0 + v0 * ts + a * ts * ts / 2);
        assert_int_equal(loadid_jf_update(jf, t, &z), 0);
        assert_int_equal(loadid_jf_update(twin, t, &z), 0);
        /* state_at far off in both directions must not change the filter */
        loadid_real_t v[3];
        const int64_t far = t + 5000000 * (k % 2 ? 1 : -1);
        assert_int_equal(loadid_jf_state_at(twin, far, &v[0], &v[1], &v[2]), 0);
    }
    const int64_t last = t - 1000;
    const int64_t probes[] = {last,          last + 20000,   last + 1000000,
                              last - 500000, last - 2000000, T0 - 300000};
    for (size_t p = 0; p < sizeof probes / sizeof *probes; ++p) {
        const double ts = seconds_of(probes[p]);
        loadid_real_t q, qd, qdd;
        assert_int_equal(loadid_jf_state_at(jf, probes[p], &q, &qd, &qdd), 0);
        const double dt = fabs((double)(probes[p] - last)) * 1e-6;
        ASSERT_CLOSE(qdd, a, tol, "qdd");
        ASSERT_CLOSE(qd, v0 + a * ts, (IS_FLOAT ? 1e-3 : 1e-10) + tol * dt, "qd");
        ASSERT_CLOSE(q, q0 + v0 * ts + a * ts * ts / 2,
                     (IS_FLOAT ? 1e-5 : 1e-12) + (IS_FLOAT ? 1e-3 : 1e-10) * dt + tol * dt * dt / 2,
                     "q");
        loadid_real_t tq[3];
        assert_int_equal(loadid_jf_state_at(twin, probes[p], &tq[0], &tq[1], &tq[2]), 0);
        assert_memory_equal(&q, &tq[0], sizeof q);
        assert_memory_equal(&qd, &tq[1], sizeof qd);
        assert_memory_equal(&qdd, &tq[2], sizeof qdd);
    }
    loadid_jf_destroy(jf);
    loadid_jf_destroy(twin);
}

/* Bit-identical outputs of state_at at a few times. */
typedef struct {
    loadid_real_t v[3][3][3]; /* probe, quantity, joint */
} snapshot_t;

static void snapshot(const loadid_jf_t *jf, int64_t last, snapshot_t *s) {
    const int64_t probes[3] = {last, last + 1500, last - 2500};
    for (int p = 0; p < 3; ++p)
        assert_int_equal(loadid_jf_state_at(jf, probes[p], s->v[p][0], s->v[p][1], s->v[p][2]), 0);
}

static void test_errors(void **state) {
    (void)state;
    loadid_jf_config_t c = default_config();
    loadid_jf_t *jf = (loadid_jf_t *)&c; /* create must clear it on failure */

    /* bad arguments and configurations */
    assert_int_equal(loadid_jf_create(3, &c, NULL), -EINVAL);
    assert_int_equal(loadid_jf_create(3, NULL, &jf), -EINVAL);
    assert_null(jf);
    assert_int_equal(loadid_jf_create(0, &c, &jf), -EINVAL);
    assert_int_equal(loadid_jf_create(17, &c, &jf), -EINVAL);
    const loadid_real_t bad[] = {0, -1, NAN, INFINITY};
    for (int field = 0; field < 4; ++field)
        for (size_t b = 0; b < sizeof bad / sizeof *bad; ++b) {
            loadid_jf_config_t x = default_config();
            loadid_real_t *f[4] = {&x.jerk_psd, &x.meas_sigma, &x.init_sigma_vel,
                                   &x.init_sigma_acc};
            *f[field] = bad[b];
            assert_int_equal(loadid_jf_create(2, &x, &jf), -EINVAL);
            assert_null(jf);
            const int64_t t1 = T0;
            const loadid_real_t z1 = 0;
            assert_int_equal(loadid_jf_smooth(&x, 1, &t1, &z1, g_work, NULL, NULL, NULL), -EINVAL);
        }
    for (int64_t step = -5; step <= 0; step += 5) {
        loadid_jf_config_t x = default_config();
        x.max_step_us = step;
        assert_int_equal(loadid_jf_create(2, &x, &jf), -EINVAL);
    }
    assert_int_equal(loadid_jf_create(16, &c, &jf), 0);
    loadid_jf_destroy(jf);
    loadid_jf_destroy(NULL);
    assert_int_equal(loadid_jf_reset(NULL), -EINVAL);
    assert_true(loadid_jf_last_time(NULL) == INT64_MIN);

    /* before the first update */
    assert_int_equal(loadid_jf_create(3, &c, &jf), 0);
    loadid_real_t q[3], qd[3], qdd[3];
    assert_true(loadid_jf_last_time(jf) == INT64_MIN);
    assert_int_equal(loadid_jf_state_at(jf, T0, q, qd, qdd), LOADID_E_NO_DATA);
    assert_int_equal(loadid_jf_state_at(NULL, T0, q, qd, qdd), -EINVAL);
    assert_int_equal(loadid_jf_update(jf, T0, NULL), -EINVAL);
    assert_int_equal(loadid_jf_update(NULL, T0, q), -EINVAL);

    /* some motion, then rejected updates change nothing */
    int64_t t = T0;
    for (int k = 0; k < 100; ++k, t += 1000) {
        const double ts = seconds_of(t);
        const loadid_real_t z[3] = {traj(ts, 0), -traj(ts, 0), 0.5 * traj(ts, 0)};
        assert_int_equal(loadid_jf_update(jf, t, z), 0);
    }
    const int64_t last = t - 1000;
    assert_true(loadid_jf_last_time(jf) == last);
    snapshot_t before, after;
    snapshot(jf, last, &before);
    const loadid_real_t nonfinite[2] = {NAN, INFINITY};
    for (int b = 0; b < 2; ++b) {
        const loadid_real_t z[3] = {0.1, nonfinite[b], 0.2};
        assert_int_equal(loadid_jf_update(jf, t, z), LOADID_E_NONFINITE);
    }
    const loadid_real_t z_ok[3] = {0.1, 0.2, 0.3};
    assert_int_equal(loadid_jf_update(jf, last, z_ok), LOADID_E_TIME_ORDER);
    assert_int_equal(loadid_jf_update(jf, last - 1, z_ok), LOADID_E_TIME_ORDER);
    assert_int_equal(loadid_jf_update(jf, INT64_MIN + 1, z_ok), LOADID_E_TIME_ORDER);
    assert_true(loadid_jf_last_time(jf) == last);
    snapshot(jf, last, &after);
    assert_memory_equal(&before, &after, sizeof before);

    /* any output may be NULL */
    assert_int_equal(loadid_jf_state_at(jf, last, NULL, NULL, NULL), 0);
    assert_int_equal(loadid_jf_state_at(jf, last, NULL, NULL, qdd), 0);
    assert_memory_equal(qdd, before.v[0][2], sizeof qdd);

    /* reset forgets, and time order starts again */
    assert_int_equal(loadid_jf_reset(jf), 0);
    assert_true(loadid_jf_last_time(jf) == INT64_MIN);
    assert_int_equal(loadid_jf_state_at(jf, last, q, qd, qdd), LOADID_E_NO_DATA);
    assert_int_equal(loadid_jf_update(jf, T0 - 5, z_ok), 0);
    assert_int_equal(loadid_jf_state_at(jf, T0 + 1000, q, qd, qdd), 0);
    for (int i = 0; i < 3; ++i) {
        assert_true(q[i] == z_ok[i] && qd[i] == 0 && qdd[i] == 0);
    }
    loadid_jf_destroy(jf);

    /* the smoother's checks */
    const int64_t ts_ok[3] = {T0, T0 + 1000, T0 + 2000}, ts_eq[3] = {T0, T0 + 1000, T0 + 1000},
                  ts_back[3] = {T0, T0 + 1000, T0 + 500};
    const loadid_real_t zs[3] = {0.1, 0.2, 0.3}, zs_nan[3] = {0.1, NAN, 0.3};
    assert_int_equal(loadid_jf_smooth(&c, 3, ts_ok, zs, g_work, q, qd, qdd), 0);
    assert_int_equal(loadid_jf_smooth(&c, 3, ts_eq, zs, g_work, q, qd, qdd), LOADID_E_TIME_ORDER);
    assert_int_equal(loadid_jf_smooth(&c, 3, ts_back, zs, g_work, q, qd, qdd), LOADID_E_TIME_ORDER);
    assert_int_equal(loadid_jf_smooth(&c, 3, ts_ok, zs_nan, g_work, q, qd, qdd),
                     LOADID_E_NONFINITE);
    assert_int_equal(loadid_jf_smooth(&c, 0, ts_ok, zs, g_work, q, qd, qdd), -EINVAL);
    assert_int_equal(loadid_jf_smooth(NULL, 3, ts_ok, zs, g_work, q, qd, qdd), -EINVAL);
    assert_int_equal(loadid_jf_smooth(&c, 3, NULL, zs, g_work, q, qd, qdd), -EINVAL);
    assert_int_equal(loadid_jf_smooth(&c, 3, ts_ok, NULL, g_work, q, qd, qdd), -EINVAL);
    assert_int_equal(loadid_jf_smooth(&c, 3, ts_ok, zs, NULL, q, qd, qdd), -EINVAL);
    assert_int_equal(loadid_jf_smooth(&c, 3, ts_ok, zs, g_work, NULL, NULL, NULL), 0);
    assert_true(loadid_jf_smooth_work_size(3) >= 3);
}

/* A step over max_step_us restarts from the new measurement (q = z, qd =
 * qdd = 0); a step of exactly max_step_us is bridged by the model. */
static void test_gap_reinitialises(void **state) {
    (void)state;
    const loadid_jf_config_t c = default_config();
    for (int over = 0; over <= 1; ++over) {
        loadid_jf_t *jf = NULL;
        assert_int_equal(loadid_jf_create(1, &c, &jf), 0);
        int64_t t = T0;
        for (int k = 0; k < 200; ++k, t += 1000) {
            const loadid_real_t z = (loadid_real_t)traj(seconds_of(t), 0);
            assert_int_equal(loadid_jf_update(jf, t, &z), 0);
        }
        t += c.max_step_us - 1000 + over;
        const loadid_real_t z = (loadid_real_t)traj(seconds_of(t), 0);
        assert_int_equal(loadid_jf_update(jf, t, &z), 0);
        loadid_real_t q, qd, qdd;
        assert_int_equal(loadid_jf_state_at(jf, t, &q, &qd, &qdd), 0);
        if (over) {
            assert_true(q == z && qd == 0 && qdd == 0);
        } else {
            /* bridged: the filter keeps a velocity close to the truth */
            ASSERT_CLOSE(qd, traj(seconds_of(t), 1), 0.5, "qd after a step of max_step_us");
        }
        loadid_jf_destroy(jf);
    }
}

/* loadid_jf_steady_sigma against a Monte Carlo of the model itself: truths
 * driven by white jerk of the configured PSD (x_k+1 = F x_k + w, w drawn
 * from Q by its Cholesky factor, computed here), measured with white noise
 * of meas_sigma; the RMS errors of the filter (after settling) and of the
 * smoother (the middle of each run) over 200 runs of 0.3 s. */
#define MC_RUNS 200
#define MC_STEPS 300
static void test_steady_sigma_is_the_models_error(void **state) {
    (void)state;
    loadid_jf_config_t cfg;
    loadid_jf_config_default(&cfg);
    double sf[3], ss[3];
    assert_int_equal(loadid_jf_steady_sigma(&cfg, 1e-3, 0, sf), 0);
    assert_int_equal(loadid_jf_steady_sigma(&cfg, 1e-3, 1, ss), 0);
    const double dt = 1e-3, q = (double)cfg.jerk_psd, r = (double)cfg.meas_sigma;
    const double d2 = dt * dt, d3 = d2 * dt;
    const double Q[3][3] = {{q * d3 * d2 / 20, q * d2 * d2 / 8, q * d3 / 6},
                            {q * d2 * d2 / 8, q * d3 / 3, q * d2 / 2},
                            {q * d3 / 6, q * d2 / 2, q * dt}};
    double L[3][3] = {{0}}; /* Cholesky of Q */
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j <= i; ++j) {
            double s = Q[i][j];
            for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
            L[i][j] = i == j ? sqrt(s) : s / L[j][j];
        }
    /* The fixed-lag smoother (50 steps) on the same runs: against the RTS
     * smoother of the whole run, and against the truth. */
    loadid_jf_config_t lcfg = cfg;
    lcfg.lag_steps = 50;
    loadid_jf_t *lagged;
    assert_int_equal(loadid_jf_create(1, &lcfg, &lagged), 0);
    static loadid_real_t lq[MC_STEPS], lqd[MC_STEPS], lqdd[MC_STEPS];
    double dl = 0, el = 0;
    long nl = 0;
    static int64_t t[MC_STEPS];
    static loadid_real_t z[MC_STEPS], work[18 * MC_STEPS], sq[MC_STEPS], sqd[MC_STEPS],
        sqdd[MC_STEPS];
    static double truth[MC_STEPS][3];
    double ef[3] = {0}, es[3] = {0};
    long nf = 0, ns = 0;
    loadid_rng_t rng;
    loadid_rng_seed(&rng, 2024);
    loadid_jf_t *jf;
    assert_int_equal(loadid_jf_create(1, &cfg, &jf), 0);
    for (int run = 0; run < MC_RUNS; ++run) {
        double x[3] = {0.3, 0.5 * loadid_rng_normal(&rng), 5 * loadid_rng_normal(&rng)};
        loadid_jf_reset(jf);
        loadid_jf_reset(lagged);
        for (int k = 0; k < MC_STEPS; ++k) {
            t[k] = T0 + k * 1000;
            memcpy(truth[k], x, sizeof x);
            z[k] = (loadid_real_t)(x[0] + r * loadid_rng_normal(&rng));
            assert_int_equal(loadid_jf_update(jf, t[k], &z[k]), 0);
            assert_int_equal(loadid_jf_update(lagged, t[k], &z[k]), 0);
            if (k >= 50) { /* update k - 50 has its 50 after it */
                assert_int_equal(loadid_jf_lagged_time(lagged), t[k - 49] - 1);
                /* (the first few while the filter settles: refused) */
                assert_int_equal(loadid_jf_lagged_state_at(lagged, t[k - 50], 5000, &lq[k - 50],
                                                           &lqd[k - 50], &lqdd[k - 50]),
                                 k - 50 < loadid_jf_settle_steps(lagged) ? LOADID_E_STALE : 0);
                assert_int_equal(
                    loadid_jf_lagged_state_at(lagged, t[k - 49], 5000, NULL, NULL, NULL),
                    k - 49 < loadid_jf_settle_steps(lagged) ? LOADID_E_STALE : LOADID_E_NO_DATA);
            } else {
                assert_int_equal(loadid_jf_lagged_time(lagged), INT64_MIN);
            }
            loadid_real_t fq, fqd, fqdd;
            loadid_jf_state_at(jf, t[k], &fq, &fqd, &fqdd);
            if (k >= 150) {
                const double e[3] = {fq - x[0], fqd - x[1], fqdd - x[2]};
                for (int i = 0; i < 3; ++i) ef[i] += e[i] * e[i];
                nf++;
            }
            const double w[3] = {loadid_rng_normal(&rng), loadid_rng_normal(&rng),
                                 loadid_rng_normal(&rng)};
            const double nx[3] = {x[0] + dt * x[1] + d2 / 2 * x[2], x[1] + dt * x[2], x[2]};
            for (int i = 0; i < 3; ++i)
                x[i] = nx[i] + L[i][0] * w[0] + L[i][1] * w[1] + L[i][2] * w[2];
        }
        assert_true(loadid_jf_smooth_work_size(MC_STEPS) <= sizeof work / sizeof *work);
        assert_int_equal(loadid_jf_smooth(&cfg, MC_STEPS, t, z, work, sq, sqd, sqdd), 0);
        for (int k = 100; k < 200; ++k) {
            const double e[3] = {sq[k] - truth[k][0], sqd[k] - truth[k][1], sqdd[k] - truth[k][2]};
            for (int i = 0; i < 3; ++i) es[i] += e[i] * e[i];
            ns++;
            dl += (lqdd[k] - sqdd[k]) * (lqdd[k] - sqdd[k]);
            el += (lqdd[k] - truth[k][2]) * (lqdd[k] - truth[k][2]);
            nl++;
        }
    }
    loadid_jf_destroy(jf);
    loadid_jf_destroy(lagged);
    dl = sqrt(dl / nl), el = sqrt(el / nl);
    for (int i = 0; i < 3; ++i) ef[i] = sqrt(ef[i] / nf), es[i] = sqrt(es[i] / ns);
    print_message(
        "steady sigma q, qd, qdd: filter %.3g %.3g %.3g (Monte Carlo %.3g %.3g %.3g), "
        "smoother %.3g %.3g %.3g (Monte Carlo %.3g %.3g %.3g)\n",
        sf[0], sf[1], sf[2], ef[0], ef[1], ef[2], ss[0], ss[1], ss[2], es[0], es[1], es[2]);
    /* 30000 filter and 20000 smoother errors, correlated over a few ms:
     * their RMS is known to about 2 %. Float rounds q to 6e-8 of 1.7e-6. */
    const double tol = IS_FLOAT ? 0.2 : 0.1;
    for (int i = 1; i < 3; ++i) {
        assert_true(fabs(ef[i] / sf[i] - 1) < tol);
        assert_true(fabs(es[i] / ss[i] - 1) < tol);
    }
    assert_true(ss[2] < 0.5 * sf[2]); /* the smoother's point */
    print_message(
        "fixed-lag smoother (50 steps): qdd %.3g from the truth, %.3g from the RTS "
        "smoother of the whole run\n",
        el, dl);
    /* 50 steps are many times the smoother's memory: the same as RTS, to
     * a few % of its error (seen 1 %); its error is the smoother's. */
    assert_true(dl < 0.05 * ss[2]);
    assert_true(fabs(el / ss[2] - 1) < tol);
    assert_int_equal(loadid_jf_steady_sigma(&cfg, 0, 0, sf), -EINVAL);
    assert_int_equal(loadid_jf_steady_sigma(NULL, 1e-3, 0, sf), -EINVAL);
}

/* loadid_jf_noise_sigma: the measurement noise's share of the errors, for
 * the filter and the fixed-lag smoother, against a Monte Carlo with no
 * process noise at all (a constant acceleration, which the model follows
 * without bias): what is left is the noise's response. */
static void test_noise_sigma_is_the_noise_response(void **state) {
    (void)state;
    for (int lag = 0; lag <= 50; lag += 50) {
        loadid_jf_config_t cfg;
        loadid_jf_config_default(&cfg);
        cfg.lag_steps = lag;
        double ns[3];
        assert_int_equal(loadid_jf_noise_sigma(&cfg, 1e-3, ns), 0);
        loadid_jf_t *jf;
        assert_int_equal(loadid_jf_create(1, &cfg, &jf), 0);
        loadid_rng_t rng;
        loadid_rng_seed(&rng, 77 + lag);
        double e[3] = {0, 0, 0};
        long n = 0;
        const double r = (double)cfg.meas_sigma, a = 3.0;
        for (int k = 0; k < 20000; ++k) {
            const int64_t tk = T0 + (int64_t)k * 1000;
            const double ts = k * 1e-3;
            const loadid_real_t z =
                (loadid_real_t)(0.2 + 0.5 * ts + a * ts * ts / 2 + r * loadid_rng_normal(&rng));
            assert_int_equal(loadid_jf_update(jf, tk, &z), 0);
            if (k < 500 + lag) continue;
            const int j = lag ? k - lag : k;
            const double tj = j * 1e-3;
            loadid_real_t q, qd, qdd;
            if (lag)
                assert_int_equal(
                    loadid_jf_lagged_state_at(jf, T0 + (int64_t)j * 1000, 5000, &q, &qd, &qdd), 0);
            else
                assert_int_equal(loadid_jf_state_at(jf, tk, &q, &qd, &qdd), 0);
            const double d[3] = {q - (0.2 + 0.5 * tj + a * tj * tj / 2), qd - (0.5 + a * tj),
                                 qdd - a};
            for (int c = 0; c < 3; ++c) e[c] += d[c] * d[c];
            n++;
        }
        loadid_jf_destroy(jf);
        for (int c = 0; c < 3; ++c) e[c] = sqrt(e[c] / n);
        print_message("%s: noise share of qd, qdd %.3g %.3g (Monte Carlo %.3g %.3g)\n",
                      lag ? "fixed-lag smoother" : "filter", ns[1], ns[2], e[1], e[2]);
        /* q grows to 600 rad: float's rounding of it swamps the noise. */
        if (IS_FLOAT) continue;
        for (int c = 1; c < 3; ++c) assert_true(fabs(e[c] / ns[c] - 1) < 0.1);
    }
    loadid_jf_config_t bad;
    loadid_jf_config_default(&bad);
    double ns[3];
    bad.lag_steps = LOADID_JF_MAX_LAG + 1;
    assert_int_equal(loadid_jf_noise_sigma(&bad, 1e-3, ns), -EINVAL);
}

/* The fixed-lag smoother read between updates, where the sensor samples
 * are (0.37 ms after each joint state, as loadid-sim and the JR3 on CAN
 * are), with the pipeline's settings (jerk_psd 1, 50 steps of lag): qdd
 * within the RTS smoother's own error at the updates (0.038 rad/s^2 on
 * this multi-sine), and qd and q close. Holding qdd constant from the
 * update before, as the model's mean does, gave 0.16 rad/s^2; longer lags
 * then did worse than 10 steps. Checked against the analytic derivatives
 * at the sample times. */
static void test_lagged_between_updates(void **state) {
    (void)state;
    loadid_jf_config_t c = default_config();
    c.jerk_psd = 1;
    series_t *s = &g_series;
    make_series(s, 0, 1);
    run_smoother(&c, s, &g_smooth);
    const double rts = rms_error(s, g_smooth.x[2], 2, 0, SETTLE, s->n - SETTLE);
    const int offsets[3] = {0, 370, 900};
    for (int lag = 10; lag <= 50; lag += 40) {
        c.lag_steps = lag;
        for (int o = 0; o < 3; ++o) {
            loadid_jf_t *jf = NULL;
            assert_int_equal(loadid_jf_create(1, &c, &jf), 0);
            double e2[3] = {0, 0, 0};
            int n = 0;
            for (int k = 0; k < s->n; ++k) {
                assert_int_equal(loadid_jf_update(jf, s->t[k], &s->z[k]), 0);
                const int j = k - lag;
                if (j < SETTLE || j >= s->n - SETTLE) continue;
                const int64_t t = s->t[j] + offsets[o];
                loadid_real_t x[3];
                assert_int_equal(loadid_jf_lagged_state_at(jf, t, 5000, &x[0], &x[1], &x[2]), 0);
                for (int d = 0; d < 3; ++d) e2[d] += pow(x[d] - traj(seconds_of(t), d), 2);
                ++n;
            }
            loadid_jf_destroy(jf);
            const double q = sqrt(e2[0] / n), qd = sqrt(e2[1] / n), qdd = sqrt(e2[2] / n);
            print_message(
                "lag %d, %3d us after the update: qdd RMS %.4f rad/s^2 (RTS %.4f), qd "
                "%.2e rad/s, q %.2e rad\n",
                lag, offsets[o], qdd, rts, qd, q);
            /* 50 steps: the RTS figure (measured 1.00x at every offset); 10
             * steps are not enough for jerk_psd 1 (measured 2.1-6.2x, qd 1.3e-3). */
            if (lag == 50) assert_true(qdd < 1.3 * rts + (IS_FLOAT ? 0.02 : 0));
            if (lag == 50) assert_true(qd < 1e-3 && q < 2e-5);
        }
    }
}

/* The settling count by the covariance recursion alone, written here in
 * plain doubles: from the prior after the first measurement (q: r, qd:
 * init_sigma_vel^2, qdd: init_sigma_acc^2) to the first prediction whose
 * variances of q, qd and qdd are all within 1.5 of the steady state's. */
static int settle_reference(const loadid_jf_config_t *c, double dt) {
    const double q = (double)c->jerk_psd, r = (double)c->meas_sigma * (double)c->meas_sigma;
    const double F[3][3] = {{1, dt, dt * dt / 2}, {0, 1, dt}, {0, 0, 1}};
    const double d2 = dt * dt, d3 = d2 * dt;
    const double Q[3][3] = {{q * d3 * d2 / 20, q * d2 * d2 / 8, q * d3 / 6},
                            {q * d2 * d2 / 8, q * d3 / 3, q * d2 / 2},
                            {q * d3 / 6, q * d2 / 2, q * dt}};
    double steady[3] = {0, 0, 0}, first[3][3] = {{r, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    first[1][1] = (double)c->init_sigma_vel * (double)c->init_sigma_vel;
    first[2][2] = (double)c->init_sigma_acc * (double)c->init_sigma_acc;
    for (int pass = 0; pass < 2; ++pass) {
        double P[3][3];
        memcpy(P, first, sizeof P);
        for (int k = 1; k < 100000; ++k) {
            double FP[3][3], Pp[3][3];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    FP[i][j] = F[i][0] * P[0][j] + F[i][1] * P[1][j] + F[i][2] * P[2][j];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    Pp[i][j] =
                        FP[i][0] * F[j][0] + FP[i][1] * F[j][1] + FP[i][2] * F[j][2] + Q[i][j];
            if (pass == 1 && Pp[0][0] <= 1.5 * steady[0] && Pp[1][1] <= 1.5 * steady[1] &&
                Pp[2][2] <= 1.5 * steady[2])
                return k;
            if (pass == 0) steady[0] = Pp[0][0], steady[1] = Pp[1][1], steady[2] = Pp[2][2];
            /* P = (I - K H) Pp with K = Pp H^T / (Pp00 + r) */
            const double s = Pp[0][0] + r;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) P[i][j] = Pp[i][j] - Pp[i][0] * Pp[0][j] / s;
        }
    }
    return -1;
}

/* A stalled stream (0.3 s without joint states, over max_step_us: the
 * filter restarts) with the daemon's settings (jerk_psd 1, 50 steps of
 * lag, max_step_us = max_joint_age 5 ms): a sample more than 5 ms from the
 * joint states before the stall, or served by one of the first settle
 * updates after it, is refused (LOADID_E_STALE); every other is served
 * within the smoother's error. Served, the unsettled updates had qdd off
 * by up to 320 rad/s^2 (the steady gains on the restarted filter's
 * innovations); a 0.3 s stall then cost RTLS 55 % of the mass offline. */
static void test_restart_settles_before_serving(void **state) {
    (void)state;
    loadid_jf_config_t c = default_config();
    c.jerk_psd = 1;
    c.lag_steps = 50;
    c.max_step_us = 5000;
    loadid_jf_t *jf = NULL;
    assert_int_equal(loadid_jf_create(1, &c, &jf), 0);
    const int settle = loadid_jf_settle_steps(jf);
    print_message("settle: %d updates (reference %d)\n", settle, settle_reference(&c, 1e-3));
    assert_int_equal(settle, settle_reference(&c, 1e-3));
    assert_int_equal(loadid_jf_settle_steps(NULL), -EINVAL);
    assert_int_equal(loadid_jf_settled(NULL), 0);
    assert_int_equal(loadid_jf_settled(jf), 0);
    series_t *s = &g_series;
    make_series(s, 0, 1);
    const int cut0 = 1500, cut1 = 1800; /* updates [cut0, cut1) never come */
    int64_t refused = 0, expected = 0;
    double worst_before = 0, worst_after = 0;
    int j = 1400; /* the next sample: 0.37 ms after millisecond j */
    for (int k = 0; k < s->n && j < 2000; ++k) {
        if (k >= cut0 && k < cut1) continue;
        assert_int_equal(loadid_jf_update(jf, s->t[k], &s->z[k]), 0);
        assert_int_equal(loadid_jf_settled(jf), k < cut1 ? k >= settle : k >= cut1 + settle);
        /* The samples the smoother covers now. */
        for (; j < 2000 && T0 + 1000LL * j + 370 <= loadid_jf_lagged_time(jf); ++j) {
            const int64_t t = T0 + 1000LL * j + 370;
            loadid_real_t x[3];
            const int rc = loadid_jf_lagged_state_at(jf, t, 5000, &x[0], &x[1], &x[2]);
            const int served = t <= s->t[cut0 - 1] + 5000 || t >= s->t[cut1] + 1000LL * settle;
            expected += !served;
            if (!served) {
                assert_int_equal(rc, LOADID_E_STALE);
                ++refused;
                continue;
            }
            assert_int_equal(rc, 0);
            const double e = fabs(x[2] - traj(seconds_of(t), 2));
            double *w = j < cut0 + 5 ? &worst_before : &worst_after;
            if (e > *w) *w = e;
        }
    }
    assert_int_equal(j, 2000);
    loadid_jf_destroy(jf);
    print_message(
        "0.3 s stall: %lld samples refused (expected %lld); served qdd at most %.3g "
        "rad/s^2 off before it, %.3g after\n",
        (long long)refused, (long long)expected, worst_before, worst_after);
    assert_int_equal(expected, 300 - 4 + settle);
    /* Before: the last updates smoothed with the few after them, then
     * propagated up to 5 ms (seen 3.4 rad/s^2 at the end, on 37 RMS).
     * After: the smoother's own error once settled (seen 0.38; 0.04 RTS). */
    assert_true(worst_before < 6.0);
    assert_true(worst_after < 0.8);
}

/* loadid_jf_retune: encoders of 2^14 counts (step / sqrt(12) = 1.1e-4
 * rad) under a filter and fixed-lag smoother (20 steps) set for 2^20;
 * switched after 1 s to the coarse encoder's noise and a 60-step lag, the
 * filter runs again over the updates it kept (the last 2 MAX_LAG + 1):
 * from there on it is one created so and first updated at the oldest of
 * them (filter and smoother alike; seen 0 apart in double and float, the
 * measurements rebuilt exactly), while the unswitched one is far off (max
 * qdd difference seen 130 rad/s^2 for the filter, 56 for the smoother).
 * With its state kept, it took 0.3 s of the new, slower gains to forget
 * the old ones' errors, and on-line RTLS had 1.5 times the reference's
 * inertia error on the RX60 at 2^14 counts (1.1 run again). */
static void test_retune(void **state) {
    (void)state;
    const double coarse = 2 * PI / 16384.0;
    loadid_jf_config_t fine = default_config(), big = fine;
    fine.lag_steps = 20;
    big.lag_steps = 60;
    big.meas_sigma = (loadid_real_t)(coarse / sqrt(12.0));
    loadid_jf_t *sw = NULL, *ref = NULL, *old = NULL;
    assert_int_equal(loadid_jf_create(1, &fine, &sw), 0);
    assert_int_equal(loadid_jf_create(1, &big, &ref), 0);
    assert_int_equal(loadid_jf_create(1, &fine, &old), 0);
    const int n = N_SAMPLES, cut = 1000, kept = 2 * LOADID_JF_MAX_LAG + 1;
    const int from = cut - kept; /* ref's first update */
    int compared[2] = {0, 0};
    double diff[2] = {0, 0}, diff_old[2] = {0, 0}; /* max |qdd - ref's|: filter, smoother */
    for (int k = 0; k < n; ++k) {
        const int64_t t = T0 + 1000LL * k;
        const loadid_real_t z = (loadid_real_t)(round(traj(seconds_of(t), 0) / coarse) * coarse);
        if (k == cut) {
            const int64_t tp = t - 1000;
            loadid_real_t x[2][3];
            const loadid_real_t bad[4] = {0, -1, (loadid_real_t)NAN, (loadid_real_t)INFINITY};
            for (int b = 0; b < 4; ++b) assert_int_equal(loadid_jf_retune(sw, bad[b], 60), -EINVAL);
            assert_int_equal(loadid_jf_retune(sw, big.meas_sigma, -1), -EINVAL);
            assert_int_equal(loadid_jf_retune(sw, big.meas_sigma, LOADID_JF_MAX_LAG + 1), -EINVAL);
            assert_int_equal(loadid_jf_retune(NULL, big.meas_sigma, 60), -EINVAL);
            assert_int_equal(loadid_jf_settle_steps(sw), loadid_jf_settle_steps(old));
            assert_int_equal(loadid_jf_lagged_time(sw), t - 1000LL * 20 - 1);
            assert_int_equal(loadid_jf_retune(sw, big.meas_sigma, 60), 0);
            assert_int_equal(loadid_jf_settle_steps(sw), loadid_jf_settle_steps(ref));
            assert_int_equal(loadid_jf_lagged_time(sw), t - 1000LL * 60 - 1);
            assert_int_equal(loadid_jf_lagged_time(sw), loadid_jf_lagged_time(ref));
            assert_true(loadid_jf_settled(sw) && loadid_jf_settled(ref));
            assert_int_equal(loadid_jf_state_at(sw, tp, &x[0][0], &x[0][1], &x[0][2]), 0);
            assert_int_equal(loadid_jf_state_at(ref, tp, &x[1][0], &x[1][1], &x[1][2]), 0);
            for (int c = 0; c < 3; ++c) diff[0] = fmax(diff[0], fabs(x[0][c] - x[1][c]));
        }
        loadid_jf_t *jf[3] = {sw, ref, old};
        loadid_real_t qdd[3], lagged[3];
        int rc[3];
        for (int f = 0; f < 3; ++f) {
            if (f == 1 && k < from) continue;
            assert_int_equal(loadid_jf_update(jf[f], t, &z), 0);
            assert_int_equal(loadid_jf_state_at(jf[f], t, NULL, NULL, &qdd[f]), 0);
        }
        if (k < cut) continue;
        ++compared[0];
        diff[0] = fmax(diff[0], fabs(qdd[0] - qdd[1]));
        diff_old[0] = fmax(diff_old[0], fabs(qdd[2] - qdd[1]));
        /* From 60 steps before the switch: served from the updates run again. */
        const int64_t tl = t - 1000LL * 2 * big.lag_steps;
        for (int f = 0; f < 3; ++f)
            rc[f] = loadid_jf_lagged_state_at(jf[f], tl, 5000, NULL, NULL, &lagged[f]);
        assert_int_equal(rc[0], 0);
        assert_int_equal(rc[1], 0);
        assert_int_equal(rc[2], 0);
        ++compared[1];
        diff[1] = fmax(diff[1], fabs(lagged[0] - lagged[1]));
        diff_old[1] = fmax(diff_old[1], fabs(lagged[2] - lagged[1]));
    }
    print_message(
        "after the switch (%d filter states, %d smoothed), max |qdd - the coarse-tuned one's| "
        "[rad/s^2]: filter %.3g (unswitched %.3g), smoother %.3g (unswitched %.3g)\n",
        compared[0], compared[1], diff[0], diff_old[0], diff[1], diff_old[1]);
    assert_int_equal(compared[0], n - cut);
    for (int i = 0; i < 2; ++i) {
        assert_true(diff_old[i] > 1.0);
        assert_true(diff[i] < 1e-6 * diff_old[i]);
    }
    loadid_jf_destroy(sw);
    loadid_jf_destroy(ref);
    loadid_jf_destroy(old);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_restart_settles_before_serving),
        cmocka_unit_test(test_retune),
        cmocka_unit_test(test_steady_sigma_is_the_models_error),
        cmocka_unit_test(test_noise_sigma_is_the_noise_response),
        cmocka_unit_test(test_config_default),
        cmocka_unit_test(test_lagged_between_updates),
        cmocka_unit_test(test_filter_multisine),
        cmocka_unit_test(test_filter_jittered),
        cmocka_unit_test(test_smoother_multisine),
        cmocka_unit_test(test_smoother_gap),
#if !LOADID_SCALAR_FLOAT
        cmocka_unit_test(test_matches_textbook_kf),
#endif
        cmocka_unit_test(test_constant_acceleration),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_gap_reinitialises),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
