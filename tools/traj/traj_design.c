/* Excitation trajectory design: objective, limits, Monte Carlo search and
 * NLopt refinement (traj_design.h; paper sec. III). */
#include "traj_design.h"

#include <errno.h>
#include <math.h>
#include <nlopt.h>
#include <stdlib.h>
#include <string.h>

#include "loadid_synth.h"

static const double kTwoPi = 6.28318530717958647692;

void loadid_traj_problem_defaults(loadid_traj_problem_t *p) {
    p->objective_hz = 100;
    p->constraint_hz = 200;
    p->margin = 0.02;
}

/* ------------------------------------------------------------ objective */

typedef struct {
    const loadid_traj_problem_t *p;
    loadid_est_t *est;
} evaluator_t;

static int evaluator_open(evaluator_t *ev, const loadid_traj_problem_t *p) {
    ev->p = p;
    loadid_est_config_t cfg = p->est;
    cfg.method = LOADID_METHOD_RLS; /* kappa is the same for every method */
    cfg.max_noise_ratio = 1;
    return loadid_est_create(&cfg, &ev->est);
}

static void evaluator_close(evaluator_t *ev) {
    loadid_est_destroy(ev->est);
}

static void to_real(const double *in, loadid_real_t *out, int n) {
    for (int i = 0; i < n; ++i) out[i] = (loadid_real_t)in[i];
}

/* The estimator's data matrix at one setpoint state: eq. (6), plus the
 * zeroing term (eqs. 7-9) or the offset columns [A E6]. */
static int data_matrix(const loadid_traj_problem_t *p, const loadid_real_t g_init[3],
                       const double *q, const double *qd, const double *qdd,
                       loadid_real_t A[6 * 16]) {
    const int n = p->limits.num_joints;
    loadid_real_t rq[LOADID_MAX_JOINTS], rqd[LOADID_MAX_JOINTS], rqdd[LOADID_MAX_JOINTS];
    to_real(q, rq, n), to_real(qd, rqd, n), to_real(qdd, rqdd, n);
    loadid_kin_state_t st;
    int rc = loadid_kin_eval(p->kin, rq, rqd, rqdd, &st);
    if (rc != 0) return rc;
    return loadid_regressor_model(st.spec, st.omega, st.alpha, p->est.n_params,
                                  p->zeroing ? g_init : NULL, A);
}

static double kappa_with(evaluator_t *ev, const loadid_fourier_traj_t *tr, double rate_hz) {
    const loadid_traj_problem_t *p = ev->p;
    loadid_est_reset(ev->est);
    loadid_real_t q0[LOADID_MAX_JOINTS];
    to_real(tr->q0, q0, tr->num_joints);
    loadid_kin_state_t rest;
    if (loadid_kin_eval(p->kin, q0, NULL, NULL, &rest) != 0) return NAN;
    const double t1 = loadid_traj_active_start(tr);
    const int samples = (int)floor(tr->active_s * rate_hz + 0.5);
    const loadid_real_t y[6] = {0, 0, 0, 0, 0, 0};
    for (int k = 0; k < samples; ++k) {
        double q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
        loadid_traj_eval(tr, t1 + k / rate_hz, q, qd, qdd, NULL);
        loadid_real_t A[6 * 16];
        if (data_matrix(p, rest.gravity, q, qd, qdd, A) != 0) return NAN;
        if (loadid_est_update(ev->est, A, NULL, y) != 0) return NAN;
    }
    loadid_real_t phi[16];
    loadid_est_info_t info;
    int rc = loadid_est_estimate(ev->est, phi, &info);
    if (rc != 0 && rc != LOADID_E_NOT_EXCITED) return NAN;
    return info.condition_number;
}

double loadid_traj_kappa(const loadid_traj_problem_t *p, const loadid_fourier_traj_t *tr,
                         double rate_hz) {
    evaluator_t ev;
    if (evaluator_open(&ev, p) != 0) return NAN;
    double k = kappa_with(&ev, tr, rate_hz);
    evaluator_close(&ev);
    return k;
}

/* ---------------------------------------------------------------- limits */

static void worse(loadid_traj_violation_t *w, double excess, const char *what, int joint,
                  double t) {
    if (excess > w->excess) *w = (loadid_traj_violation_t){excess, what, joint, t};
}

int loadid_traj_check(const loadid_traj_problem_t *p, const loadid_fourier_traj_t *tr,
                      double rate_hz, double shrink, loadid_traj_violation_t *worst) {
    const loadid_traj_limits_t *L = &p->limits;
    const int n = tr->num_joints;
    loadid_traj_violation_t w = {-INFINITY, "none", -1, 0};
    const double ws_margin = shrink * 0.5; /* metres */
    const int samples = (int)ceil(loadid_traj_duration(tr) * rate_hz);
    for (int k = 0; k <= samples; ++k) {
        const double t = k / rate_hz;
        double q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
        loadid_traj_eval(tr, t, q, qd, qdd, NULL);
        for (int i = 0; i < n; ++i) {
            const double range = L->upper[i] - L->lower[i];
            if (isfinite(range)) {
                const double lo = L->lower[i] + shrink * range / 2;
                const double hi = L->upper[i] - shrink * range / 2;
                worse(&w, fmax(lo - q[i], q[i] - hi) / range, "position", i, t);
            }
            const double vmax = L->velocity[i] * (1 - shrink);
            const double amax = L->acceleration[i] * (1 - shrink);
            worse(&w, (fabs(qd[i]) - vmax) / L->velocity[i], "velocity", i, t);
            worse(&w, (fabs(qdd[i]) - amax) / L->acceleration[i], "acceleration", i, t);
        }
        loadid_real_t rq[LOADID_MAX_JOINTS];
        to_real(q, rq, n);
        loadid_kin_state_t st;
        if (loadid_kin_eval(p->kin, rq, NULL, NULL, &st) != 0) {
            worse(&w, INFINITY, "position", -1, t);
            continue;
        }
        for (int a = 0; a < 3; ++a) {
            worse(&w,
                  fmax(L->ws_min[a] + ws_margin - st.position[a],
                       st.position[a] - (L->ws_max[a] - ws_margin)),
                  "workspace", a, t);
        }
        worse(&w, L->floor_z + ws_margin - st.position[2], "floor", 2, t);
    }
    if (worst) *worst = w;
    return w.excess <= 0;
}

/* ---------------------------------------------------------------- search */

/* The optimisation variables: [q0 (if optimised)] then, per joint and
 * harmonic, rho and delta. */
typedef struct {
    const loadid_traj_problem_t *p;
    const loadid_traj_search_t *s;
    loadid_fourier_traj_t base; /* template: sizes, times, q0 */
    int nx;
    double *lb, *ub;
    evaluator_t ev;
    int evaluations;
    /* the best point within the limits seen while optimising */
    double best_kappa;
    double *best_x;
    /* NLopt's progress: evaluations of the candidates done before this
     * one, and of this one so far (a report every PROGRESS_EVALS). */
    int opt_done, opt_evals, opt_total;
} search_t;

/* NLopt reports progress this often: a candidate's 2000 evaluations take
 * seconds, which without it pass in silence. */
#define PROGRESS_EVALS 100

static void unpack(const search_t *S, const double *x, loadid_fourier_traj_t *tr) {
    *tr = S->base;
    const int n = S->base.num_joints, h = S->base.harmonics;
    int j = 0;
    if (S->s->optimise_home)
        for (int i = 0; i < n; ++i) tr->q0[i] = x[j++];
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < h; ++k) {
            tr->rho[i][k] = x[j++];
            tr->delta[i][k] = x[j++];
        }
}

static void pack(const search_t *S, const loadid_fourier_traj_t *tr, double *x) {
    const int n = tr->num_joints, h = tr->harmonics;
    int j = 0;
    if (S->s->optimise_home)
        for (int i = 0; i < n; ++i) x[j++] = tr->q0[i];
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < h; ++k) {
            x[j++] = tr->rho[i][k];
            x[j++] = tr->delta[i][k];
        }
}

/* Bounds: q0 inside the middle 80 % of its range; a harmonic's coefficient
 * no larger than what alone would reach a position, velocity or
 * acceleration limit. */
static void bounds(search_t *S) {
    const loadid_traj_limits_t *L = &S->p->limits;
    const int n = S->base.num_joints, h = S->base.harmonics;
    int j = 0;
    if (S->s->optimise_home)
        for (int i = 0; i < n; ++i, ++j) {
            const double range = L->upper[i] - L->lower[i];
            S->lb[j] = isfinite(range) ? L->lower[i] + 0.1 * range : -3.14159265358979;
            S->ub[j] = isfinite(range) ? L->upper[i] - 0.1 * range : 3.14159265358979;
        }
    for (int i = 0; i < n; ++i) {
        const double range = L->upper[i] - L->lower[i];
        for (int k = 1; k <= h; ++k) {
            const double w = kTwoPi * k * S->base.base_frequency;
            double a = fmin(L->velocity[i] / w, L->acceleration[i] / (w * w));
            if (isfinite(range)) a = fmin(a, range / 2);
            for (int c = 0; c < 2; ++c, ++j) S->lb[j] = -a, S->ub[j] = a;
        }
    }
}

/* Excess of the worst limit while optimising (limits shrunk by margin). */
static double excess(search_t *S, const loadid_fourier_traj_t *tr) {
    loadid_traj_violation_t w;
    loadid_traj_check(S->p, tr, S->p->constraint_hz, S->p->margin, &w);
    return w.excess;
}

static double objective(search_t *S, const double *x, int *feasible) {
    loadid_fourier_traj_t tr;
    unpack(S, x, &tr);
    S->evaluations++;
    *feasible = excess(S, &tr) <= 0;
    double k = kappa_with(&S->ev, &tr, S->p->objective_hz);
    if (!isfinite(k)) k = 1e12;
    if (*feasible && k < S->best_kappa) {
        S->best_kappa = k;
        memcpy(S->best_x, x, (size_t)S->nx * sizeof *x);
    }
    return k;
}

static double nlopt_objective(unsigned nx, const double *x, double *grad, void *data) {
    (void)nx, (void)grad; /* COBYLA is derivative-free */
    search_t *S = data;
    int feasible;
    const double k = objective(S, x, &feasible);
    /* (a candidate's last evaluation: reported at its end, below) */
    if (S->s->progress && ++S->opt_evals % PROGRESS_EVALS == 0 && S->opt_evals < S->s->max_evals)
        S->s->progress(S->s->progress_ctx, "optimise", S->opt_done + S->opt_evals, S->opt_total,
                       S->best_kappa);
    return log(k);
}

static double nlopt_constraint(unsigned nx, const double *x, double *grad, void *data) {
    (void)nx, (void)grad;
    search_t *S = data;
    loadid_fourier_traj_t tr;
    unpack(S, x, &tr);
    return excess(S, &tr);
}

/* Largest factor c <= 1 by which the series part can be scaled so that the
 * joint position, velocity and acceleration limits (shrunk) hold; all three
 * are linear in c. */
static double joint_scale(const search_t *S, const loadid_fourier_traj_t *tr) {
    const loadid_traj_limits_t *L = &S->p->limits;
    const double m = S->p->margin, rate = S->p->constraint_hz;
    double c = 1;
    const int samples = (int)ceil(loadid_traj_duration(tr) * rate);
    for (int k = 0; k <= samples; ++k) {
        double q[LOADID_MAX_JOINTS], qd[LOADID_MAX_JOINTS], qdd[LOADID_MAX_JOINTS];
        loadid_traj_eval(tr, k / rate, q, qd, qdd, NULL);
        for (int i = 0; i < tr->num_joints; ++i) {
            const double dev = q[i] - tr->q0[i], range = L->upper[i] - L->lower[i];
            if (isfinite(range) && dev != 0) {
                const double room = dev > 0 ? L->upper[i] - m * range / 2 - tr->q0[i]
                                            : L->lower[i] + m * range / 2 - tr->q0[i];
                c = fmin(c, fmax(room / dev, 0));
            }
            if (qd[i] != 0) c = fmin(c, L->velocity[i] * (1 - m) / fabs(qd[i]));
            if (qdd[i] != 0) c = fmin(c, L->acceleration[i] * (1 - m) / fabs(qdd[i]));
        }
    }
    return c;
}

static void scale_series(loadid_fourier_traj_t *tr, double c) {
    for (int i = 0; i < tr->num_joints; ++i)
        for (int k = 0; k < tr->harmonics; ++k) tr->rho[i][k] *= c, tr->delta[i][k] *= c;
}

typedef struct {
    double kappa;
    double *x;
} candidate_t;

/* Keeps the `count` smallest kappas, sorted ascending. */
static void keep_best(candidate_t *best, int count, int nx, double kappa, const double *x) {
    if (!(kappa < best[count - 1].kappa)) return;
    int i = count - 1;
    double *spare = best[i].x;
    while (i > 0 && kappa < best[i - 1].kappa) {
        best[i] = best[i - 1];
        --i;
    }
    best[i].kappa = kappa;
    best[i].x = spare;
    memcpy(spare, x, (size_t)nx * sizeof *x);
}

static int valid_template(const loadid_traj_problem_t *p, const loadid_fourier_traj_t *tr) {
    if (tr->num_joints != p->limits.num_joints || tr->num_joints < 1) return 0;
    if (tr->harmonics < 1 || tr->harmonics > LOADID_TRAJ_MAX_HARMONICS) return 0;
    if (!(tr->base_frequency > 0) || !(tr->active_s > 0) || !(tr->fade_s > 0)) return 0;
    for (int i = 0; i < tr->num_joints; ++i)
        if (!(p->limits.velocity[i] > 0) || !(p->limits.acceleration[i] > 0)) return 0;
    return 1;
}

int loadid_traj_design(const loadid_traj_problem_t *p, const loadid_traj_search_t *s,
                       loadid_fourier_traj_t *tr, loadid_traj_search_result_t *result) {
    if (!p || !s || !tr || !result || !valid_template(p, tr)) return -EINVAL;
    if (s->monte_carlo < 1 || s->candidates < 1 || s->max_evals < 0) return -EINVAL;
    search_t S = {.p = p, .s = s, .base = *tr, .best_kappa = INFINITY};
    S.nx = (s->optimise_home ? tr->num_joints : 0) + 2 * tr->num_joints * tr->harmonics;
    const int ncand = s->candidates;
    double *mem = calloc((size_t)S.nx * (4 + ncand), sizeof *mem);
    candidate_t *best = calloc((size_t)ncand, sizeof *best);
    if (!mem || !best || evaluator_open(&S.ev, p) != 0) {
        free(mem), free(best);
        return -ENOMEM;
    }
    S.lb = mem, S.ub = mem + S.nx, S.best_x = mem + 2 * S.nx;
    double *x = mem + 3 * S.nx;
    for (int c = 0; c < ncand; ++c) best[c] = (candidate_t){INFINITY, mem + (4 + c) * S.nx};
    bounds(&S);
    memset(result, 0, sizeof *result);

    /* Monte Carlo: random coefficients inside the bounds, scaled to 85 % of
     * what the joint limits allow (a candidate on a limit leaves COBYLA no
     * room: seen stuck within 1 % of its start), shrunk further while the
     * workspace is broken. */
    loadid_rng_t rng;
    loadid_rng_seed(&rng, s->seed);
    for (int m = 0; m < s->monte_carlo; ++m) {
        for (int j = 0; j < S.nx; ++j)
            x[j] = S.lb[j] + (S.ub[j] - S.lb[j]) * loadid_rng_uniform(&rng);
        loadid_fourier_traj_t cand;
        unpack(&S, x, &cand);
        scale_series(&cand, 0.85 * joint_scale(&S, &cand));
        double e = excess(&S, &cand);
        for (int shrink = 0; shrink < 6 && e > 0; ++shrink) {
            scale_series(&cand, 0.7);
            e = excess(&S, &cand);
        }
        S.evaluations++;
        if (e <= 0) {
            const double k = kappa_with(&S.ev, &cand, p->objective_hz);
            result->feasible_candidates++;
            pack(&S, &cand, x);
            if (isfinite(k)) keep_best(best, ncand, S.nx, k, x);
        }
        if (s->progress && ((m + 1) % 100 == 0 || m + 1 == s->monte_carlo))
            s->progress(s->progress_ctx, "monte-carlo", m + 1, s->monte_carlo, best[0].kappa);
    }
    result->kappa_monte_carlo = best[0].kappa;
    if (!isfinite(best[0].kappa)) {
        evaluator_close(&S.ev);
        free(mem), free(best);
        return -ERANGE;
    }
    S.best_kappa = best[0].kappa;
    memcpy(S.best_x, best[0].x, (size_t)S.nx * sizeof *x);

    /* Local refinement of each candidate under the limits (COBYLA: no
     * gradients, inequality constraints); the best point within the limits
     * seen in any evaluation wins. */
    S.opt_total = ncand * s->max_evals;
    for (int c = 0; c < ncand && isfinite(best[c].kappa) && s->max_evals > 0; ++c) {
        S.opt_done = c * s->max_evals, S.opt_evals = 0;
        nlopt_opt opt = nlopt_create(NLOPT_LN_COBYLA, (unsigned)S.nx);
        if (!opt) break;
        double *step = x; /* scratch */
        for (int j = 0; j < S.nx; ++j) step[j] = 0.1 * (S.ub[j] - S.lb[j]);
        nlopt_set_lower_bounds(opt, S.lb);
        nlopt_set_upper_bounds(opt, S.ub);
        nlopt_set_initial_step(opt, step);
        nlopt_set_min_objective(opt, nlopt_objective, &S);
        nlopt_add_inequality_constraint(opt, nlopt_constraint, &S, 0);
        nlopt_set_maxeval(opt, s->max_evals);
        nlopt_set_xtol_rel(opt, 1e-6);
        double f;
        nlopt_optimize(opt, best[c].x, &f); /* any outcome: best_x keeps the best */
        nlopt_destroy(opt);
        /* A candidate that converged early counts as its whole budget. */
        if (s->progress)
            s->progress(s->progress_ctx, "optimise", (c + 1) * s->max_evals, S.opt_total,
                        S.best_kappa);
    }

    /* The result must hold every limit itself (not shrunk) at 10 kHz. */
    loadid_fourier_traj_t out;
    unpack(&S, S.best_x, &out);
    int rc = 0;
    if (!loadid_traj_check(p, &out, 10000, 0, NULL)) {
        rc = -ERANGE;
    } else {
        *tr = out;
        result->kappa_optimised = kappa_with(&S.ev, &out, p->objective_hz);
    }
    result->evaluations = S.evaluations;
    evaluator_close(&S.ev);
    free(mem), free(best);
    return rc;
}
