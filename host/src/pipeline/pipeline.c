/* The estimation pipeline of loadidd (pipeline.h). */
#include "loadid/pipeline.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/core.h"
#include "loadid/jr3.h"
#include "loadid/setup.h"
#include "drift_check.h"
#include "notch.h"
#include "spectrum_rows.h"
#include "worker.h"

#define MIN_ZEROING_SAMPLES 10
#define PENDING_MAX 512 /* samples waiting for joint data (and the fixed lag): 0.5 s at 1 kHz */
#define NOISE_MAX_GAP_US 20000 /* third differences need consecutive samples */
#define COMMANDS_MAX 16        /* commands waiting for the fixed lag (50 ms: a few at most) */
/* A pause between F/T samples longer than this is time without F/T data
 * (completeness): 20 samples of the JR3 at 1 kHz; for the Modbus sensor
 * at least 4 of its poll periods. */
#define FT_GAP_US 20000

#define DRIFT_P 1e-4

struct loadid_pipeline {
    loadid_config_t cfg;
    loadid_pipeline_sink_t sink;
    int publish_every;
    int std_always; /* phi_std in every published estimate */
    int n_params;   /* 10 (zeroing) or 16 ([A E6]) */
    int num_methods;
    int has_riv; /* RIV configured: instruments needed */
    loadid_est_t *est[LOADID_MAX_METHODS];
    loadid_signals_t *sig;
    loadid_jr3_decoder_t *jr3;
    loadid_real_t distal[10];
    loadid_model_config_t model_cfg;
    /* the measured noise model (noise_model.h) */
    loadid_noise_acc_t noise;
    loadid_noise_levels_t levels; /* the on-line estimators' */
    loadid_kin_t *kin;            /* the joint levels at the pose */
    int period_noted;             /* the joint period said (once) */
    double filter_sigma[3];       /* the joint filter's (or fixed-lag smoother's)
                                         noise share of its q, qd, qdd errors */
    int64_t filter_period_us;     /* the joint period filter_sigma is for */
    loadid_real_t last_q[LOADID_MAX_JOINTS];
    int have_q;
    int has_accel; /* the configured sensor has an accelerometer (JR3) */
    /* REFINED (refined.h) */
    int refined_m; /* its method index, -1 when not configured */
    loadid_refined_t *refined;
    loadid_refined_report_t refined_rep;
    int refined_ran;
    /* Live: REFINED on a worker thread (loadid_pipeline_refined_async);
     * the job's inputs and result. */
    loadid_worker_t *worker;
    double job_channel[LOADID_NOISE_CHANNELS];
    int job_src, job_rc;
    loadid_pipeline_estimate_t job_est; /* REFINED's final estimate, made by the job */
    /* completeness of the last run */
    int zero_seen;
    int complete;
    char incomplete_reason[256];
    int64_t stale_at_start;
    int64_t ft_gap_us;                 /* FT_GAP_US, or the Modbus sensor's */
    int64_t cover_prev_us;             /* the window's last F/T sample so far (START at first) */
    int64_t missing_us;                /* time of the window without F/T samples */
    int64_t win_samples;               /* the window's F/T samples, usable or refused */
    int64_t win_saturated, win_faulty; /* of which refused, saturated or faulty */
    int64_t incomplete_at_start;       /* the decoder's samples_incomplete at START */
    int64_t restarts_at_start;         /* the joint stamp clock's restarts at START */

    int state;
    char reason[192];
    char load_name[LOADID_LOAD_NAME_MAX];
    int started;
    /* zeroing */
    int64_t zero_end_us;
    /* zeroing samples; those with kinematics (zero_a's). From
     * finish_zeroing on, zero_n counts the samples y0 averages: all, or
     * zero_g_n when the load moved. */
    int64_t zero_n, zero_g_n;
    double zero_sum[6], zero_g_sum[3], zero_a_sum[60];
    double zero_g2_sum, zero_w2_sum; /* sum |g|^2, |omega|^2: did it move? */
    int64_t zero_t_first_us;         /* the zeroing window's first sample */
    double zero_t_sum;               /* and its samples' time after it, summed [us] */
    int64_t zero_t_last_us;          /* its last sample */
    /* the wrench and time sums over the samples zero_a has (kinematics) */
    double zero_kin_sum[6], zero_kin_t_sum;
    double noise_corr[2];   /* the zeroing window's (set_zeroing_noise) */
    double joint_over;      /* levels.joint_position over kalman.meas_sigma; 0 within tolerance */
    int64_t stamp_restarts; /* check_joint_stamps: the window's, when they void phi_std; else 0 */
    double tone_share[2], tone_hz[2]; /* a - g, alpha (measure_tones) */
    /* the notch on the rows against those tones (notch.h; no stages: none),
     * its frequencies per column group (0: none) and the still window's
     * channel levels once the tones are out (0 when not measured) */
    loadid_notch_bank_t notch;
    double notch_hz[2], notch_sigma[LOADID_NOISE_CHANNELS];
    int zeroed; /* y0, g_init and zero_a are valid */
    loadid_real_t y0[6], g_init[3];
    /* eq. (6) averaged over the zeroing window, what y0 holds of the load
     * (loadid_regressor_subtract_zeroing) */
    loadid_real_t zero_a[60];
    /* does the offset drift after zeroing? (drift_check.h) */
    loadid_drift_check_t drift;
    loadid_drift_result_t drift_result;
    int drift_significant;    /* the final estimates are corrected by its pull */
    double drift_iv_pull[10]; /* RIV's pull (the least-squares one without instruments) */
    /* the window's rows as the on-line methods took them, transformed at
     * DONE for phi_std by band (spectrum_rows.h); the bands of one method
     * at a time (REFINED's apart: its job runs beside the loop) */
    loadid_spectrum_rows_t *rows;
    loadid_spectrum_t *bands, *refined_bands;
    /* estimation */
    int64_t est_end_us, last_sample_us, since_publish;
    int64_t start_us;      /* START's utime */
    int rescaled;          /* the rows' check at estimation.rescale_s is done */
    double row_rescale[3]; /* the factors it applied (force, torque, columns), 1 = none */
    loadid_pipeline_estimate_t latest[LOADID_MAX_METHODS];
    int primary;                 /* method used for wrench_t, -1 none */
    loadid_real_t phi_total[16]; /* primary's estimate with the distal part */
    /* loadid_pipeline_trace_rows: the window's newest sample */
    int trace_rows, have_row;
    loadid_real_t row_y[6]; /* as the estimators took it (eq. 7) */
    loadid_regressor_input_t row_motion;

    int64_t frames_bad_extra, samples_used, estimator_errors;
    /* loadid_pipeline_sample (samples decoded outside, the Modbus sensor's) */
    int64_t ft_ok, ft_saturated, ft_faulty, ft_rejected;
    int ft_source_noted; /* the refusal below was logged */
    /* Samples wait here until a joint state at or after their time has
     * arrived, so the joints are interpolated at the sample's time, not
     * extrapolated, and the result does not depend on which of the two
     * streams a process happened to read first (live equals offline). */
    loadid_sensor_sample_t pending[PENDING_MAX];
    int pending_head, pending_count;
    /* With the fixed-lag smoother, commands wait here too, until the joint
     * data cover their utime: the samples before a command must be served
     * (smoothed) before it acts, as they are without the lag. */
    struct {
        int64_t utime;
        int action;
        char load_name[LOADID_LOAD_NAME_MAX];
    } commands[COMMANDS_MAX];
    int commands_head, commands_count;
};

static void flush_pending(loadid_pipeline_t *p, int64_t before, int ready);
static int refined_busy(loadid_pipeline_t *p);
static void refined_take_joints(loadid_pipeline_t *p);
static void restart_rows(loadid_pipeline_t *p);
static void apply_measured_noise(loadid_pipeline_t *p);
static void reset_drift(loadid_pipeline_t *p);

static void note(loadid_pipeline_t *p, const char *fmt, ...) {
    if (!p->sink.log) return;
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    p->sink.log(p->sink.ctx, msg);
}

/* filter_sigma for the joint filters as they run (kalman.joint_period_s
 * auto: again once the stream's period is measured). */
static int filter_noise(loadid_pipeline_t *p) {
    loadid_jf_config_t c;
    const int rc = loadid_signals_filter_config(p->sig, &c);
    if (rc) return rc;
    p->filter_period_us = c.nominal_step_us;
    return loadid_jf_noise_sigma(&c, (double)c.nominal_step_us * 1e-6, p->filter_sigma);
}

static void set_state(loadid_pipeline_t *p, int64_t utime, int state, const char *reason) {
    p->state = state;
    snprintf(p->reason, sizeof p->reason, "%s", reason ? reason : "");
    if (state == LOADID_STATE_FAILED) {
        /* Every failure is of missing data (ZERO, or the data of its
         * window): no complete run. */
        p->complete = 0;
        snprintf(p->incomplete_reason, sizeof p->incomplete_reason, "%s", p->reason);
    }
    if (p->sink.state) p->sink.state(p->sink.ctx, utime, state, p->reason);
}

int loadid_pipeline_create(const loadid_config_t *cfg, const loadid_chain_t *chain,
                           const loadid_pipeline_sink_t *sink, int publish_every,
                           loadid_pipeline_t **out, char *err, size_t errlen) {
    loadid_pipeline_t *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err, errlen, "out of memory");
        return -ENOMEM;
    }
    p->cfg = *cfg;
    if (sink) p->sink = *sink;
    p->publish_every = publish_every < 0 ? 0 : publish_every;
    p->n_params = cfg->offset_model_estimate ? LOADID_NPHI_OFFSET : LOADID_NPHI;
    p->primary = -1;
    p->refined_m = -1;
    p->row_rescale[0] = p->row_rescale[1] = p->row_rescale[2] = 1;
    p->has_accel = cfg->sensor_type == LOADID_SENSOR_JR3;
    p->ft_gap_us = FT_GAP_US;
    if (cfg->sensor_type == LOADID_SENSOR_MODBUS && cfg->modbus_rate_hz > 0 &&
        4e6 / cfg->modbus_rate_hz > FT_GAP_US)
        p->ft_gap_us = (int64_t)llround(4e6 / cfg->modbus_rate_hz);
    for (int i = 0; i < 10; ++i) p->distal[i] = (loadid_real_t)cfg->distal_phi[i];
    loadid_model_config_default(&p->model_cfg);
    p->model_cfg.mass_rel_std = (loadid_real_t)cfg->model_mass_rel_std;
    p->model_cfg.com_std = (loadid_real_t)cfg->model_com_std;
    p->model_cfg.inertia_rel_std = (loadid_real_t)cfg->model_inertia_rel_std;
    p->model_cfg.max_gyration = (loadid_real_t)cfg->model_max_gyration;
    p->model_cfg.fallback_density = (loadid_real_t)cfg->model_fallback_density;
    p->model_cfg.min_snr = (loadid_real_t)cfg->model_min_snr;
    loadid_noise_acc_reset(&p->noise);

    loadid_signals_config_t scfg;
    loadid_setup_signals(cfg, (loadid_signal_source_t)cfg->signals, &scfg);
    int rc = loadid_signals_create(chain, cfg->robot_gravity, &scfg, &p->sig);
    const char *what = "the joint filters and kinematics";
    if (rc == 0) {
        loadid_jr3_config_t j;
        loadid_setup_jr3(cfg, &j);
        rc = loadid_jr3_decoder_create(&j, &p->jr3);
        what = "the JR3 decoder";
    }
    if (rc == 0) {
        rc = loadid_kin_create(chain, cfg->robot_gravity, &p->kin);
        what = "the kinematics";
    }
    if (rc == 0) {
        /* The measurement noise's share of what the joints give the
         * estimators: the on-line filter's, or the fixed-lag smoother's. */
        rc = filter_noise(p);
        what = "the joint filter's noise";
    }
    p->num_methods = cfg->num_methods;
    for (int m = 0; m < p->num_methods; ++m) {
        p->latest[m].method = cfg->methods[m];
        p->has_riv |= cfg->methods[m] == LOADID_METHOD_RIV;
    }
    if (rc == 0) {
        rc = loadid_spectrum_rows_create((int)ceil(cfg->duration_s * 2000) + 100, p->n_params,
                                         p->has_riv, &p->rows);
        p->bands = malloc(sizeof *p->bands);
        p->refined_bands = malloc(sizeof *p->refined_bands);
        if (rc == 0 && !(p->bands && p->refined_bands)) rc = -ENOMEM;
        what = "the window's rows";
    }
    for (int m = 0; m < p->num_methods && rc == 0; ++m) {
        loadid_est_config_t e;
        rc = loadid_est_config_default((loadid_method_t)cfg->methods[m], p->n_params, &e);
        /* The weights follow where a - g and alpha come from (setup.h). */
        if (rc == 0) rc = loadid_setup_weights(cfg, (loadid_signal_source_t)cfg->signals, &e);
        /* Batch references hold the whole window at up to 2 kHz. */
        e.batch_capacity = (int)ceil(cfg->duration_s * 2000) + 100;
        if (rc == 0) rc = loadid_est_create(&e, &p->est[m]);
        what = "an estimator";
        if (rc == 0 && cfg->methods[m] == LOADID_METHOD_REFINED) {
            p->refined_m = m;
            rc = loadid_refined_create(cfg, chain, &p->refined);
            what = "REFINED's stores";
        }
    }
    if (rc != 0) {
        snprintf(err, errlen, "cannot create %s: %s", what, loadid_strerror(rc));
        loadid_pipeline_destroy(p);
        return rc;
    }
    *out = p;
    return 0;
}

void loadid_pipeline_std_always(loadid_pipeline_t *p, int on) {
    if (p) p->std_always = on != 0;
}

void loadid_pipeline_trace_rows(loadid_pipeline_t *p, int on) {
    if (p) p->trace_rows = on != 0;
}

void loadid_pipeline_destroy(loadid_pipeline_t *p) {
    if (!p) return;
    /* First: a running REFINED job (a stop while it runs) uses the
     * estimators and the REFINED state below; this waits for its end. */
    loadid_worker_destroy(p->worker);
    for (int m = 0; m < LOADID_MAX_METHODS; ++m) loadid_est_destroy(p->est[m]);
    loadid_signals_destroy(p->sig);
    loadid_jr3_decoder_destroy(p->jr3);
    loadid_kin_destroy(p->kin);
    loadid_refined_destroy(p->refined);
    loadid_spectrum_rows_destroy(p->rows);
    free(p->bands);
    free(p->refined_bands);
    free(p);
}

/* ------------------------------------------------------------ estimates */

/* Why method m has no estimate, in words: for "not excited", which of the
 * gate's tests failed and which parameters the data determine worst. */
static void explain(loadid_pipeline_t *p, int m, int rc, const loadid_est_info_t *info,
                    int mass_unidentified, char *out, size_t len) {
    if (rc != LOADID_E_NOT_EXCITED) {
        snprintf(out, len, "%s", loadid_strerror(rc));
        return;
    }
    const loadid_est_config_t *c = loadid_est_config(p->est[m]);
    loadid_real_t dir[16];
    const char *group = "?";
    if (loadid_est_weakest_direction(p->est[m], dir, NULL) == 0) {
        static const char *const names[] = {"the mass", "the centre of mass", "the inertia",
                                            "the offset"};
        double share[4] = {0, 0, 0, 0};
        for (int j = 0; j < p->n_params; ++j)
            share[j == 0 ? 0 : j < 4 ? 1 : j < 10 ? 2 : 3] += (double)(dir[j] * dir[j]);
        int best = 0;
        for (int g = 1; g < 4; ++g)
            if (share[g] > share[best]) best = g;
        group = names[best];
    }
    const int64_t k = info->samples;
    if (k * 6 < p->n_params + 1)
        snprintf(out, len, "not excited: %lld samples, too few for %d parameters", (long long)k,
                 p->n_params);
    else if (!(info->condition_number <= c->max_condition))
        snprintf(out, len,
                 "not excited: the motion does not determine %s (condition number %.3g "
                 "over %.3g, %lld samples)",
                 group, (double)info->condition_number, (double)c->max_condition, (long long)k);
    else
        snprintf(out, len,
                 "not excited: the weakest direction of phi, mostly %s, does not stand out "
                 "of the noise%s (noise ratio %.3g, condition number %.3g, %lld samples)",
                 group,
                 mass_unidentified ? ", nor does the mass"
                                   : " (TLS with columns counted noisy has no unique solution)",
                 (double)info->noise_ratio, (double)info->condition_number, (long long)k);
}

/* The final estimate's load model (load_model_t), from its phi_std (std,
 * 10 values) and residual scale. */
static void model_of(loadid_pipeline_t *p, int m, const loadid_real_t *std, loadid_real_t scale,
                     const loadid_real_t load[10], loadid_pipeline_estimate_t *e) {
    /* How far the load's groups stand out of the noise in the data. */
    loadid_real_t load_n[16] = {0}, snr[3];
    for (int i = 0; i < 10; ++i) load_n[i] = load[i];
    const int have_snr = loadid_est_signal_to_noise(p->est[m], load_n, snr) == 0;
    /* Its phi_std does not hold (check_joint_noise; check_joint_stamps for
     * every method): the model as for an unbounded one, saying why; RIV's
     * instruments are not the noisy joints' columns. */
    const int noisy =
        p->joint_over > 0 && m != p->refined_m && p->cfg.methods[m] != LOADID_METHOD_RIV;
    const int unheld = noisy || p->stamp_restarts > 0;
    loadid_real_t unbounded[10];
    for (int i = 0; i < 10; ++i) unbounded[i] = (loadid_real_t)INFINITY;
    loadid_load_model_t lm;
    if (loadid_load_model(load, unheld ? unbounded : std, have_snr ? snr : NULL, &p->model_cfg,
                          &lm) != 0)
        return;
    for (int g = 0; g < 3 && unheld; ++g)
        if (lm.why[g] == LOADID_WHY_STD && p->stamp_restarts > 0)
            lm.why[g] = LOADID_WHY_JOINT_STAMPS, lm.over[g] = (loadid_real_t)p->stamp_restarts;
        else if (lm.why[g] == LOADID_WHY_STD)
            lm.why[g] = LOADID_WHY_JOINT_NOISE, lm.over[g] = (loadid_real_t)p->joint_over;
    for (int i = 0; i < 3; ++i) e->snr[i] = have_snr ? (double)snr[i] : NAN;
    e->has_model = 1;
    e->noise_scale = (double)scale;
    for (int i = 0; i < 10; ++i) e->phi_std[i] = (double)std[i];
    e->identified = lm.identified;
    for (int g = 0; g < 3; ++g) e->ident_why[g] = lm.why[g], e->ident_over[g] = (double)lm.over[g];
    e->projected = lm.projected;
    for (int i = 0; i < 10; ++i) e->model_phi[i] = (double)lm.phi[i];
    e->model_mass = (double)lm.physical.mass;
    for (int i = 0; i < 3; ++i) e->model_com[i] = (double)lm.physical.com[i];
    for (int i = 0; i < 6; ++i) e->model_inertia_com[i] = (double)lm.physical.inertia_com[i];
}

/* e's load fields from method m's phi (load and offset); final (std, its
 * phi_std, and scale from final_phi): with its load model, else phi_std
 * with std_always. */
static void fill_estimate(loadid_pipeline_t *p, int m, const loadid_real_t *phi,
                          loadid_pipeline_estimate_t *e, const loadid_real_t *final_std,
                          loadid_real_t scale) {
    loadid_real_t load[10];
    loadid_phi_subtract(phi, p->distal, load);
    loadid_physical_t ph;
    loadid_phi_to_physical(load, &ph);
    for (int i = 0; i < 10; ++i) e->phi[i] = (double)load[i];
    if (p->n_params == LOADID_NPHI_OFFSET)
        for (int i = 0; i < 6; ++i) e->offset[i] = (double)phi[10 + i];
    e->mass = (double)ph.mass;
    for (int i = 0; i < 3; ++i) e->com[i] = (double)ph.com[i];
    for (int i = 0; i < 6; ++i) e->inertia_com[i] = (double)ph.inertia_com[i];
    e->physically_consistent = ph.violations == 0;
    if (final_std) {
        model_of(p, m, final_std, scale, load, e);
    } else if (p->std_always) {
        loadid_real_t std[16];
        const int ok = loadid_est_uncertainty(p->est[m], phi, std, NULL) == 0;
        for (int i = 0; i < 10; ++i) e->phi_std[i] = ok ? (double)std[i] : INFINITY;
    }
}

/* Method m's std at phi (16 values) and residual scale: by band of
 * frequency from the window's rows (REFINED's own;
 * loadid_est_uncertainty_spectral), else, when the rows are not
 * transformed or do not fit the estimator, with one level per row group. */
static int uncertainty_of(const loadid_pipeline_t *p, int m, const loadid_real_t *phi,
                          loadid_real_t *std, loadid_real_t *scale) {
    const int refined = m == p->refined_m;
    const loadid_spectrum_rows_t *rows = refined ? loadid_refined_rows(p->refined) : p->rows;
    loadid_spectrum_t *sp = refined ? p->refined_bands : p->bands;
    if (loadid_spectrum_rows_bands(rows, loadid_est_config(p->est[m])->row_sigma, sp) == 0 &&
        loadid_est_uncertainty_spectral(p->est[m], phi, sp, std, scale) == 0)
        return 0;
    return loadid_est_uncertainty(p->est[m], phi, std, scale);
}

/* Method m's final phi and its std (16 values) and residual scale, the
 * offset's drift taken out of the wrench: with the offset estimated always
 * (the estimator fits it, loadid_est_drift_fitted), with zeroing when the
 * drift check found one (phi less its pull, the variance plus what
 * fitting it costs); REFINED fits it itself, and a joint delay, and adds
 * what both cost (refined.h). */
static void final_phi(const loadid_pipeline_t *p, int m, loadid_real_t *phi, loadid_real_t *std,
                      loadid_real_t *scale) {
    *scale = 0;
    if (m != p->refined_m && p->n_params == LOADID_NPHI_OFFSET) {
        loadid_real_t fitted[16];
        if (loadid_est_drift_fitted(p->est[m], phi, fitted, std, scale) == 0) {
            memcpy(phi, fitted, sizeof fitted);
            return;
        }
    }
    const int zeroed_drift = m != p->refined_m && p->drift_significant;
    if (zeroed_drift) {
        const double *pull = p->drift_result.pull;
        if (p->cfg.methods[m] == LOADID_METHOD_RIV) pull = p->drift_iv_pull;
        for (int i = 0; i < 10; ++i) phi[i] -= (loadid_real_t)pull[i];
    }
    if (uncertainty_of(p, m, phi, std, scale) != 0)
        for (int i = 0; i < 16; ++i) std[i] = (loadid_real_t)INFINITY;
    const loadid_refined_report_t *ref = &p->refined_rep;
    for (int i = 0; i < 10; ++i) {
        double extra = 0; /* what fitting the drift and a joint delay costs */
        if (zeroed_drift)
            extra = p->drift_result.extra_var[i];
        else if (m == p->refined_m)
            extra = (ref->drift_fitted ? ref->drift_var[i] : 0) + ref->delay_var[i];
        if (extra > 0) std[i] = (loadid_real_t)sqrt((double)std[i] * (double)std[i] + extra);
    }
}

/* At DONE, a method the noise-ratio gate refused whose solution is unique
 * without it (loadid_est_estimate_unique): on slow motion the inertia and
 * the offset do not stand out while the mass does (0.9 % std on a UR5),
 * and "not excited" would withhold it. Its estimate is published when
 * phi_std identifies the mass at least; the groups it does not identify
 * are flagged, as in every estimate. Returns 1 when e took it, -1 when
 * phi_std does not identify the mass, 0 when the solution is not unique. */
static int final_if_determined(loadid_pipeline_t *p, int m, loadid_pipeline_estimate_t *e) {
    loadid_real_t phi[16] = {0};
    loadid_est_info_t info;
    if (loadid_est_estimate_unique(p->est[m], phi, &info) != 0) return 0;
    loadid_real_t std[16], scale;
    final_phi(p, m, phi, std, &scale);
    loadid_pipeline_estimate_t t = *e;
    t.valid = 1;
    t.error = 0;
    t.why[0] = '\0';
    fill_estimate(p, m, phi, &t, std, scale);
    if (!t.has_model || !(t.identified & LOADID_IDENT_MASS)) return -1;
    *e = t;
    if (m != p->refined_m) /* REFINED's job runs on the worker: no log there */
        note(p,
             "%s: its weakest direction does not stand out of the noise (noise ratio %.3g); "
             "published at DONE for the groups phi_std identifies",
             loadid_method_name((loadid_method_t)e->method), (double)info.noise_ratio);
    return 1;
}

/* Fills e with method m's current estimate (load only), stamped utime
 * and state; final: with its uncertainty and load model (not on the
 * per-sample path). Reads nothing else the loop changes while REFINED's
 * job runs, so the job makes REFINED's. */
static void estimate_at(loadid_pipeline_t *p, int m, loadid_pipeline_estimate_t *e, int final,
                        int64_t utime, int state) {
    loadid_real_t phi[16] = {0};
    loadid_est_info_t info;
    memset(&info, 0, sizeof info);
    const int rc = loadid_est_estimate(p->est[m], phi, &info);
    memset(e, 0, sizeof *e);
    for (int i = 0; i < 10; ++i) e->phi_std[i] = NAN; /* not computed */
    e->utime = utime;
    e->samples = info.samples;
    e->method = p->cfg.methods[m];
    e->state = state;
    snprintf(e->load_name, sizeof e->load_name, "%s", p->load_name);
    e->condition_number = (double)info.condition_number;
    e->sigma_min = (double)info.sigma_min;
    e->valid = rc == 0;
    e->error = rc;
    if (!e->valid) {
        if (!final) return;
        const int taken = rc == LOADID_E_NOT_EXCITED ? final_if_determined(p, m, e) : 0;
        if (taken == 1) return;
        explain(p, m, rc, &info, taken == -1, e->why, sizeof e->why);
        return;
    }
    loadid_real_t std[16], scale = 0;
    if (final) final_phi(p, m, phi, std, &scale);
    fill_estimate(p, m, phi, e, final ? std : NULL, scale);
}

static int data_matrix(const loadid_pipeline_t *p, const loadid_regressor_input_t *in,
                       loadid_real_t A[6 * 16]);

/* The window's newest sample and what e leaves unexplained on it, the
 * residual wrench y - A phi_total (loadid_pipeline_trace_rows). */
static void fill_row(const loadid_pipeline_t *p, loadid_pipeline_estimate_t *e) {
    loadid_real_t A[6 * 16], distal[16] = {0}, total[16] = {0}, pd[6], pt[6];
    if (!p->trace_rows || !p->have_row || data_matrix(p, &p->row_motion, A) != 0) return;
    for (int i = 0; i < 10; ++i) distal[i] = p->distal[i];
    loadid_regressor_apply(A, p->n_params, distal, pd);
    const int zeroing = p->n_params == LOADID_NPHI;
    e->has_row = 1;
    for (int i = 0; i < 3; ++i) {
        e->row_motion[i] = (double)p->row_motion.spec[i];
        e->row_motion[3 + i] = (double)p->row_motion.omega[i];
        e->row_motion[6 + i] = (double)p->row_motion.alpha[i];
        e->row_g_init[i] = zeroing ? (double)p->g_init[i] : 0.0;
    }
    for (int i = 0; i < 6; ++i) e->row_wrench[i] = (double)(p->row_y[i] - pd[i]);
    if (!e->valid) {
        for (int i = 0; i < 6; ++i) e->residual[i] = NAN;
        return;
    }
    for (int i = 0; i < 10; ++i) total[i] = (loadid_real_t)e->phi[i] + p->distal[i];
    if (!zeroing)
        for (int i = 0; i < 6; ++i) total[10 + i] = (loadid_real_t)e->offset[i];
    loadid_regressor_apply(A, p->n_params, total, pt);
    for (int i = 0; i < 6; ++i) e->residual[i] = (double)(p->row_y[i] - pt[i]);
}

static void estimate_of(loadid_pipeline_t *p, int m, loadid_pipeline_estimate_t *e, int final) {
    estimate_at(p, m, e, final, p->last_sample_us, p->state);
    fill_row(p, e);
}

/* REFINED's estimate as its job made it, stamped now. */
static void take_refined(loadid_pipeline_t *p) {
    loadid_pipeline_estimate_t *e = &p->latest[p->refined_m];
    *e = p->job_est;
    e->utime = p->last_sample_us;
    e->state = p->state;
    fill_row(p, e);
}

/* What the zeroing window measured of the noise beyond its levels (its
 * lag-1 correlation, a tone in the accelerometer), into a report's l. */
static void zeroing_figures(const loadid_pipeline_t *p, loadid_noise_levels_t *l) {
    for (int c = 0; c < 2; ++c) {
        l->correlation[c] = p->noise_corr[c];
        l->tone_share[c] = p->tone_share[c];
        l->tone_hz[c] = p->tone_hz[c];
        l->notch_hz[c] = p->notch_hz[c];
    }
    l->joint_position = p->levels.joint_position; /* check_joint_noise's */
}

/* A final estimate's groups not identified, and why, in one line. */
static void note_unidentified(loadid_pipeline_t *p, const loadid_pipeline_estimate_t *e) {
    char line[400] = "", why[160];
    size_t used = 0;
    for (int g = 0; g < 3 && used < sizeof line; ++g) {
        if (!loadid_pipeline_why_not(e, g, why, sizeof why)) continue;
        const int n = snprintf(line + used, sizeof line - used, "%s%s (%s)", used ? "; " : "",
                               loadid_ident_name(1 << g), why);
        if (n < 0) return;
        used += (size_t)n;
    }
    if (used)
        note(p, "%s: not identified: %s", loadid_method_name((loadid_method_t)e->method), line);
}

static void publish_all(loadid_pipeline_t *p, int final) {
    for (int m = 0; m < p->num_methods; ++m) {
        /* REFINED has an estimate only once the window has ended (and,
         * on the worker, once its job has been collected). */
        if (m == p->refined_m && (!final || refined_busy(p))) continue;
        if (m == p->refined_m)
            take_refined(p);
        else
            estimate_of(p, m, &p->latest[m], final);
        if (final) note_unidentified(p, &p->latest[m]);
        if (p->sink.estimate) p->sink.estimate(p->sink.ctx, &p->latest[m]);
    }
}

static int popcount3(int bits) {
    return (bits & 1) + ((bits >> 1) & 1) + ((bits >> 2) & 1);
}

/* The primary method: the most identified groups; ties go to REFINED, then
 * to the configuration's order. -1 when no method has an estimate. */
static int best_method(const loadid_pipeline_t *p) {
    int best = -1, best_score = -1;
    for (int m = 0; m < p->num_methods; ++m) {
        const loadid_pipeline_estimate_t *e = &p->latest[m];
        if (!e->valid || !e->has_model) continue;
        const int score = 2 * popcount3(e->identified) + (m == p->refined_m);
        if (score > best_score) best = m, best_score = score;
    }
    return best;
}

/* Why the run that just ended at utime (by its window's end or STOP, or
 * because the input ended) is not complete ("" when it is): in this order,
 * no ZERO, the recording ending inside the window, time without F/T
 * samples or samples without joint data beyond estimation.max_missing_share,
 * refused F/T samples beyond estimation.max_refused_share. */
static void check_complete(loadid_pipeline_t *p, int64_t utime, int by_stop) {
    char why[sizeof p->incomplete_reason] = "";
    loadid_signals_stats_t s;
    loadid_signals_stats(p->sig, &s);
    loadid_jr3_stats_t j;
    loadid_jr3_decoder_stats(p->jr3, &j);
    const int64_t stale = s.samples_stale + s.samples_no_joints - p->stale_at_start;
    /* The window as it ran: to its end, to STOP, or to the input's end. */
    const int64_t end = utime < p->est_end_us ? utime : p->est_end_us;
    const double window_s = (double)(end - p->start_us) / 1e6;
    int64_t missing = p->missing_us;
    const int64_t tail = end - p->cover_prev_us;
    if (tail > p->ft_gap_us) missing += tail;
    const int64_t incomplete = j.samples_incomplete - p->incomplete_at_start;
    const int64_t refused = p->win_saturated + p->win_faulty + incomplete;
    const int64_t joints_end = loadid_signals_newest_joint_time(p->sig);
    int n = 0;
    if (p->n_params == LOADID_NPHI && !p->zero_seen) {
        n = snprintf(why, sizeof why, "no ZERO before START");
    } else if (!by_stop && utime < p->est_end_us) {
        n = snprintf(why, sizeof why,
                     "the recording ends %.3f s after START, %.3f s before the estimation window "
                     "does",
                     window_s, (double)(p->est_end_us - utime) / 1e6);
    } else if ((double)missing > p->cfg.max_missing_share * (double)(end - p->start_us)) {
        n = snprintf(why, sizeof why, "no F/T sample for %.3f s of the %.3f s window",
                     (double)missing / 1e6, window_s);
        if (tail > p->ft_gap_us && n > 0 && (size_t)n < sizeof why)
            n += snprintf(why + n, sizeof why - (size_t)n, " (the last %.3f s of it)",
                          (double)tail / 1e6);
        if (n > 0 && (size_t)n < sizeof why)
            snprintf(why + n, sizeof why - (size_t)n,
                     ", more than %.3g %% (estimation.max_missing_share)",
                     p->cfg.max_missing_share * 100);
    } else if ((double)stale > p->cfg.max_missing_share * (double)(stale + p->samples_used)) {
        n = snprintf(why, sizeof why,
                     "joint data missing for %lld of the window's %lld samples (more than %.3g %%, "
                     "estimation.max_missing_share)",
                     (long long)stale, (long long)(stale + p->samples_used),
                     p->cfg.max_missing_share * 100);
        if (joints_end != INT64_MIN && end - joints_end > p->ft_gap_us && n > 0 &&
            (size_t)n < sizeof why)
            snprintf(why + n, sizeof why - (size_t)n,
                     "; the joint states end %.3f s before the window does",
                     (double)(end - joints_end) / 1e6);
    } else if ((double)refused > p->cfg.max_refused_share * (double)(p->win_samples + incomplete)) {
        snprintf(why, sizeof why,
                 "%lld of the window's %lld F/T samples refused (saturated %lld, faulty %lld, "
                 "incomplete %lld), more than %.3g %% (estimation.max_refused_share)",
                 (long long)refused, (long long)(p->win_samples + incomplete),
                 (long long)p->win_saturated, (long long)p->win_faulty, (long long)incomplete,
                 p->cfg.max_refused_share * 100);
    }
    p->complete = why[0] == 0;
    snprintf(p->incomplete_reason, sizeof p->incomplete_reason, "%s", why);
}

static int refined_busy(loadid_pipeline_t *p) {
    return p->worker && loadid_worker_busy(p->worker);
}

/* REFINED's batch over the window (on the worker, or in line offline),
 * and its estimate: the batch TLS's SVD, uncertainty and load model cost
 * 1.4 ms for 1500 samples, too long for the loop's 1 ms (bench_soak.py). */
static void refined_job(void *ctx) {
    loadid_pipeline_t *p = ctx;
    p->job_rc = loadid_refined_run(
        p->refined, &p->cfg, p->has_accel, p->job_channel, p->job_src, p->zero_a, p->n_params,
        p->drift_significant ? p->drift.t0_us : INT64_MIN, p->est[p->refined_m], &p->refined_rep);
    zeroing_figures(p, &p->refined_rep.levels); /* its phi_std's too */
    estimate_at(p, p->refined_m, &p->job_est, 1, 0, LOADID_STATE_DONE);
}

static void warn_moving_tones(loadid_pipeline_t *p);
static void refined_noted(loadid_pipeline_t *p) {
    p->refined_ran = 1;
    if (p->job_rc != 0) {
        note(p, "REFINED: %s", loadid_strerror(p->job_rc));
        return;
    }
    const loadid_noise_levels_t *l = &p->refined_rep.levels;
    note(p,
         "REFINED: %lld samples on the smoothed joints (jerk PSD %.3g; the accelerometer "
         "differs from them by %.3g m/s^2, %.3g rad/s^2 RMS); rows f %.3g N, tau %.3g N m (of "
         "which unexplained %.3g, %.3g); joint stamps %.2f ms behind the wrench's (fitted, "
         "std %.2f ms%s)",
         (long long)p->refined_rep.samples, p->refined_rep.jerk_psd,
         p->refined_rep.sensor_spec_error, p->refined_rep.sensor_alpha_error, l->force, l->torque,
         p->refined_rep.unexplained[0], p->refined_rep.unexplained[1],
         (double)p->refined_rep.joint_delay_us / 1e3, p->refined_rep.joint_delay_std_us / 1e3,
         p->refined_rep.joint_delay_used ? ", used" : "");
    if (p->refined_rep.drift_fitted)
        note(p,
             "REFINED: the offset drifts %.3g %.3g %.3g N/s, %.3g %.3g %.3g N m/s (fitted, taken "
             "out)",
             p->refined_rep.drift[0], p->refined_rep.drift[1], p->refined_rep.drift[2],
             p->refined_rep.drift[3], p->refined_rep.drift[4], p->refined_rep.drift[5]);
    if (p->refined_rep.joint_delay_used)
        note(p,
             "warning: joints: their stamps are %.2f ms behind the wrench's (REFINED's fit, "
             "std %.2f ms, which used it); the on-line methods carry that as misfit: "
             "kalman.joint_delay_s: %.4f (with what is set now) corrects them",
             (double)p->refined_rep.joint_delay_us / 1e3, p->refined_rep.joint_delay_std_us / 1e3,
             p->cfg.kalman_joint_delay_s + (double)p->refined_rep.joint_delay_us * 1e-6);
    warn_moving_tones(p);
}

/* REFINED at DONE: in line, or handed to the worker (its estimate is then
 * published when the loop collects it). */
static void run_refined(loadid_pipeline_t *p) {
    /* Its smoother weighs the encoders by what they showed when that is
     * clearly more than the configuration says (check_joint_noise; within
     * twice, the configuration fits): with 2^14 counts on filters set for
     * 2^20 REFINED was 2.5 phi_std off in mass, 0.6 with the measured. */
    const double measured = p->levels.joint_position;
    loadid_refined_set_meas_sigma(
        p->refined, measured > 2 * p->cfg.kalman_meas_sigma ? measured : p->cfg.kalman_meas_sigma);
    p->job_src = loadid_noise_acc_sigma(&p->noise, MIN_ZEROING_SAMPLES, p->job_channel);
    memset(&p->latest[p->refined_m], 0, sizeof p->latest[p->refined_m]);
    if (p->worker && loadid_worker_submit(p->worker) == 0) return;
    refined_job(p);
    refined_noted(p);
}

/* wrench_t and the final estimate: the primary method's physically
 * consistent model. */
static void choose_primary(loadid_pipeline_t *p) {
    p->primary = best_method(p);
    if (p->primary < 0) return;
    const loadid_pipeline_estimate_t *e = &p->latest[p->primary];
    /* The offset (16 parameters) as e has it: estimating again solved a
     * batch method's SVD once more in the loop (1.3 ms for REFINED's 1500
     * samples, bench_soak.py). */
    for (int i = 0; i < 10; ++i) p->phi_total[i] = (loadid_real_t)e->model_phi[i] + p->distal[i];
    for (int i = 0; i < 6; ++i) p->phi_total[10 + i] = (loadid_real_t)e->offset[i];
}

/* With zeroing: does the offset drift after it? (drift_check.h) When it
 * does, every on-line method's final estimate is taken as if the fitted
 * drift had been out of the wrench (phi less the drift's pull: exact for
 * least squares, and for RIV its IV counterpart), phi_std gains what
 * fitting it costs, and REFINED fits it itself. */
static void check_drift(loadid_pipeline_t *p) {
    if (p->n_params != LOADID_NPHI) return;
    loadid_drift_result_t *r = &p->drift_result;
    loadid_drift_check_result(&p->drift, r);
    p->drift_significant = r->tested && r->p_value < DRIFT_P;
    if (loadid_drift_check_iv_pull(&p->drift, r, p->drift_iv_pull) != 0)
        memcpy(p->drift_iv_pull, r->pull, sizeof p->drift_iv_pull);
    if (p->drift_significant)
        note(p,
             "the F/T offset drifts since zeroing: %.3g %.3g %.3g N/s, %.3g %.3g %.3g N m/s "
             "(p %.2g over %d blocks); the estimates are corrected by its pull (mass %.3g kg) "
             "and phi_std counts fitting it",
             r->rate[0], r->rate[1], r->rate[2], r->rate[3], r->rate[4], r->rate[5], r->p_value,
             r->blocks, r->pull[0]);
}

/* The joint positions' own noise over the window against the joint
 * filters' meas_sigma (kalman.meas_sigma, or the measured one
 * retune_joint_filters gave them early in the window; a robot still at
 * first, or a configured level): beyond this factor the filters passed noise
 * into a - g, omega and alpha (kf; omega and alpha for mixed) that the
 * weights and phi_std of RLS, RTLS, LS_BATCH and TLS_BATCH do not count (RIV's
 * instruments are not those columns: 0.2 % off at 64). On the simulated
 * RX60 (2 kg box, paper noise, filters set for 2^20 counts): at 4 (2^18
 * counts) RTLS stayed within its phi_std; at 16 (2^16) it was 4 phi_std
 * off in mass; at 64 (2^14) 15 % off, the mass claimed at 2.9 %. REFINED's
 * smoother takes the measured noise (run_refined; 0.5 % off at 64). */
#define JOINT_NOISE_TOLERANCE 5.0

static void check_joint_noise(loadid_pipeline_t *p) {
    const double measured = p->levels.joint_position = loadid_signals_position_noise(p->sig);
    p->joint_over = 0;
    loadid_jf_config_t c; /* kalman.meas_sigma, or what retune_joint_filters set */
    if (loadid_signals_filter_config(p->sig, &c) != 0) return;
    const double over = measured / (double)c.meas_sigma;
    if (!(over > JOINT_NOISE_TOLERANCE) ||
        !(p->cfg.signals == LOADID_SIGNALS_KF || p->cfg.signals == LOADID_SIGNALS_MIXED))
        return;
    p->joint_over = over;
    note(p,
         "warning: joints: their positions are %.3g times noisier than the joint filters assume "
         "(%.3g against %.3g, from their fourth differences over the window; "
         "a coarser encoder): the filters passed it into %s uncounted, so the methods on "
         "them but RIV (its instruments) and REFINED (its smoother) claim nothing; "
         "kalman.meas_sigma: %.3g fits these joints",
         over, measured, (double)c.meas_sigma,
         p->cfg.signals == LOADID_SIGNALS_KF ? "a - g, omega and alpha" : "omega and alpha",
         measured);
}

/* The joint stamps' clock (src/stamp_clock.hpp) started again this many
 * times in the window (or before START and not locked again by then):
 * each time the stamps fitted the stream's rate no more (three early ones
 * in a row, held ones no count fits: jitter of half a period or more, a
 * stream that moved), the line it starts again from is as jittered as
 * they are, and the joint states around it were taken at wrong times,
 * which no phi_std counts. On the RX60 at 1 kHz, before the clock looked
 * ahead, exponential transport delays on the joint stamps restarted it:
 * 150 us mean, 2 in the window, RTLS 39 % off (not claimed: its misfit);
 * 300 us, 20, REFINED 2.7 % off in mass at 3.6 phi_std, claimed until
 * this check (with the look-ahead: none at either). Uniform jitter of 450
 * and 500 us: 1 in 3 of 6 draws (one had RTLS 3.8 % off, claimed); 600
 * us, 15 to 30. So one is enough. */

static void check_joint_stamps(loadid_pipeline_t *p) {
    loadid_signals_stats_t s;
    loadid_signals_stats(p->sig, &s);
    const int64_t r = s.stamp_restarts - p->restarts_at_start;
    p->stamp_restarts = r > 0 ? r : 0;
    if (!p->stamp_restarts) return;
    note(p,
         "warning: joints: their stamps lost the stream's rate %lld times in the window (the "
         "stamp clock started again from them; %lld joint states refused in all): stamped on "
         "arrival, delayed or bunched in transport? (joint_state_t.utime is the sample time) "
         "The joint states around them were taken at wrong times, which no phi_std counts: no "
         "method claims anything",
         (long long)r, (long long)s.joint_msgs_bad);
}

static void finish_estimation(loadid_pipeline_t *p, int64_t utime, int by_stop) {
    check_complete(p, utime, by_stop);
    if (!p->complete) note(p, "incomplete: %s", p->incomplete_reason);
    check_drift(p);
    check_joint_noise(p);
    check_joint_stamps(p);
    if (p->refined_m >= 0) run_refined(p);
    loadid_spectrum_rows_transform(p->rows); /* else phi_std has one level per row group */
    set_state(p, utime, LOADID_STATE_DONE, "");
    publish_all(p, 1);
    choose_primary(p);
}

/* ------------------------------------------------------------- zeroing */

/* What the zeroing window measures for each estimator's phi_std
 * (loadid_est_config_t): y0's error, shared by every row of the
 * estimation (offset_cov, with the zeroing term only), and how alike
 * successive samples' noise is (noise_corr: the force and the torque
 * channels' mean lag-1 correlation). */
static void set_zeroing_noise(loadid_pipeline_t *p) {
    double cov[36], rho[6];
    if (loadid_noise_offset_cov(&p->noise, p->zero_n, cov, rho) != 0) return;
    loadid_real_t c[36];
    for (int i = 0; i < 36; ++i) c[i] = (loadid_real_t)cov[i];
    const loadid_real_t r[2] = {(loadid_real_t)((rho[0] + rho[1] + rho[2]) / 3),
                                (loadid_real_t)((rho[3] + rho[4] + rho[5]) / 3)};
    /* The noise's own level: the window's spread, sqrt(n var(y0)) without
     * the long-run factor. */
    double var[2] = {0, 0};
    for (int i = 0; i < 6; ++i)
        var[i / 3] += cov[7 * i] * (double)p->zero_n * (1 - rho[i]) / (1 + rho[i]) / 3;
    const loadid_real_t sigma[2] = {(loadid_real_t)sqrt(var[0]), (loadid_real_t)sqrt(var[1])};
    for (int m = 0; m < p->num_methods; ++m) {
        if (p->n_params == LOADID_NPHI) loadid_est_set_offset_cov(p->est[m], c);
        loadid_est_set_noise_corr(p->est[m], sigma, r);
    }
    p->noise_corr[0] = (double)r[0], p->noise_corr[1] = (double)r[1];
    note(p,
         "zeroing: offset from %lld samples, its error %.3g %.3g %.3g N, %.3g %.3g %.3g N m; "
         "lag-1 correlation of the noise %.2f (force), %.2f (torque)",
         (long long)p->zero_n, sqrt(cov[0]), sqrt(cov[7]), sqrt(cov[14]), sqrt(cov[21]),
         sqrt(cov[28]), sqrt(cov[35]), (double)r[0], (double)r[1]);
}

/* The load counts as moving while zeroed beyond these (gravity in S's
 * RMS spread over the window: 0.03 degrees of turn; omega's RMS). */
#define ZERO_MOVED_G 5e-3
#define ZERO_MOVED_W 5e-3

/* A vibration in the accelerometer's noise (loadid_noise_tone), over the
 * zeroing window's samples (period_s apart), is reported; when the signals
 * take the accelerometer's columns, whose TLS weights count their noise as
 * white, a notch on every row and the wrench takes it out (notch.h). With
 * signals sensor in the study a 28 Hz tone of 1 m/s^2 and 15 rad/s^2 had
 * left RTLS 23 % off in mass (median), notched 1.2 %; the simulator's
 * default one (9 % of the noise) 1.4 %, notched 1.1 %, its COM 4.0 mm,
 * notched 1.4; a 7 Hz one (signals sensor, RX60) RTLS 13-36 % off in
 * mass unnotched (3 seeds), 0.01-1.4 % notched (5). Filtering both sides keeps
 * A phi = y exact even within the motion's band; under NOTCH_MIN_HZ the
 * window holds under a cycle and the notch would take the motion's main
 * band, and such a tone is only said. */
#define TONE_SHARE 0.08  /* white noise's best sinusoid about 0.04 at n = 256 */
#define TONE_BINS 10.0   /* and about 6 / n at other n: TONE_BINS / n at least */
#define NOTCH_MIN_HZ 4.0 /* 0.8 cycles in 0.2 s; the trajectories' power is mostly under 2 Hz */
#define NOTCH_Q 2.0      /* -3 dB band f0 / 2: a tone's frequency 2 % off loses 99 % of its power */
static const char *const kAccelGroup[2] = {"a - g", "alpha"};

/* Two tones one notch takes out: within a tenth of the notch's frequency. */
static int same_tone(double hz, double notch_hz) {
    return notch_hz > 0 && fabs(hz - notch_hz) < 0.1 * notch_hz;
}

/* Which column groups the signals take from the accelerometer: a - g
 * (sensor, mixed), alpha (sensor). */
static void accel_columns_used(const loadid_pipeline_t *p, int used[2]) {
    used[0] = p->cfg.signals == LOADID_SIGNALS_SENSOR || p->cfg.signals == LOADID_SIGNALS_MIXED;
    used[1] = p->cfg.signals == LOADID_SIGNALS_SENSOR;
}

static void measure_tones(loadid_pipeline_t *p, double period_s) {
    int used[2];
    accel_columns_used(p, used);
    double hz[LOADID_NOISE_TONES_MAX];
    int n_hz = 0;
    for (int c = 0; c < 2; ++c) {
        loadid_noise_tone(&p->noise, 2 + c, period_s, &p->tone_share[c], &p->tone_hz[c]);
        const int n =
            p->noise.still_n < LOADID_NOISE_TONE_N ? p->noise.still_n : LOADID_NOISE_TONE_N;
        if (!used[c] || n < 1 || p->tone_share[c] < fmax(TONE_SHARE, TONE_BINS / n)) continue;
        loadid_biquad_t bq;
        const double f = p->tone_hz[c];
        if (f < NOTCH_MIN_HZ || loadid_notch_design(f, period_s, NOTCH_Q, &bq) != 0) {
            note(p,
                 "warning: zeroing: %.0f %% of the accelerometer's %s noise is one tone at "
                 "%.3g Hz (a vibration), too near the motion's band to take out: the weights "
                 "take it for white noise, and RTLS and TLS_BATCH on these columns may be "
                 "biased by it (RIV and REFINED are not)",
                 100 * p->tone_share[c], kAccelGroup[c], f);
            continue;
        }
        /* a - g's and alpha's tone within a tenth of each other: one notch */
        const int same = c == 1 && same_tone(f, p->notch_hz[0]);
        if (!same) {
            loadid_notch_bank_add(&p->notch, &bq);
            hz[n_hz++] = f;
        }
        p->notch_hz[c] = same ? p->notch_hz[0] : f;
        note(p,
             "zeroing: %.0f %% of the accelerometer's %s noise is one tone at %.3g Hz (a "
             "vibration): a notch there on the rows and the wrench takes it out",
             100 * p->tone_share[c], kAccelGroup[c], p->notch_hz[c]);
    }
    if (n_hz > 0 &&
        loadid_noise_still_sigma_without(&p->noise, hz, n_hz, period_s, p->notch_sigma) != 0)
        memset(p->notch_sigma, 0, sizeof p->notch_sigma);
}

/* A vibration the zeroing window did not have (one the motion excites):
 * REFINED's tone of the accelerometer less the smoothed joints, at DONE,
 * on the columns the signals take from the accelerometer and not notched
 * there. Said, not taken out: the on-line methods have used the rows. */
static void warn_moving_tones(loadid_pipeline_t *p) {
    int used[2];
    accel_columns_used(p, used);
    for (int c = 0; c < 2; ++c) {
        const double share = p->refined_rep.sensor_tone_share[c];
        const double f = p->refined_rep.sensor_tone_hz[c];
        if (!used[c] || share < TONE_SHARE || f < NOTCH_MIN_HZ || same_tone(f, p->notch_hz[c]))
            continue;
        note(p,
             "warning: %.0f %% of the accelerometer's %s difference to the smoothed joints was "
             "one tone at %.3g Hz while estimating (a vibration the zeroing window did not show, "
             "so not notched): RLS, RTLS and TLS_BATCH took it for white noise on "
             "those columns (their phi_std is wider for it; RIV and REFINED are not biased by it)",
             100 * share, kAccelGroup[c], f);
    }
}

static void finish_zeroing(loadid_pipeline_t *p, int64_t utime) {
    /* The samples' spacing, before zero_n may become the kinematics' count. */
    const double period_s = p->zero_n > 1 ? (double)(p->zero_t_last_us - p->zero_t_first_us) *
                                                1e-6 / (double)(p->zero_n - 1)
                                          : 0.0;
    if (p->zero_n < MIN_ZEROING_SAMPLES) {
        char why[160];
        snprintf(why, sizeof why, "zeroing: %lld usable samples in the window (at least %d needed)",
                 (long long)p->zero_n, MIN_ZEROING_SAMPLES);
        set_state(p, utime, LOADID_STATE_FAILED, why);
        return;
    }
    if (p->zero_g_n == 0) {
        set_state(p, utime, LOADID_STATE_FAILED,
                  "zeroing: no joint state near the samples (g_init needs the kinematics)");
        return;
    }
    /* Did the load turn while it was zeroed? Gravity in S comes from the
     * encoders' positions alone (a count's dither moves it by some 1e-5
     * m/s^2), omega from their rates. */
    const double n = (double)p->zero_g_n;
    double g2 = 0;
    for (int i = 0; i < 3; ++i) g2 += p->zero_g_sum[i] * p->zero_g_sum[i] / (n * n);
    const double g_spread = sqrt(fmax(p->zero_g2_sum / n - g2, 0.0)),
                 w_rms = sqrt(p->zero_w2_sum / n);
    const int moved = g_spread > ZERO_MOVED_G || w_rms > ZERO_MOVED_W;
    if (moved && p->zero_g_n < p->zero_n) {
        /* y0 holds eq. (6) averaged over its samples, zero_a over those
         * with kinematics: moving, the two must be the same samples. On
         * slow motion the estimate rests on gravity turning by a few
         * hundredths of a m/s^2 in S, and 10 samples of 200 without joint
         * data (a stall before ZERO) moved zero_a by 9e-4 m/s^2 and the
         * mass of every method by 3 %, claimed at 0.6 % phi_std. */
        if (p->zero_g_n < MIN_ZEROING_SAMPLES) {
            char why[160];
            snprintf(why, sizeof why,
                     "zeroing: the load moved and %lld samples of the window had joint data (at "
                     "least %d needed)",
                     (long long)p->zero_g_n, MIN_ZEROING_SAMPLES);
            set_state(p, utime, LOADID_STATE_FAILED, why);
            return;
        }
        memcpy(p->zero_sum, p->zero_kin_sum, sizeof p->zero_sum);
        p->zero_t_sum = p->zero_kin_t_sum;
        p->zero_n = p->zero_g_n;
    }
    for (int i = 0; i < 6; ++i) p->y0[i] = (loadid_real_t)(p->zero_sum[i] / (double)p->zero_n);
    for (int i = 0; i < 3; ++i)
        p->g_init[i] = (loadid_real_t)(p->zero_g_sum[i] / (double)p->zero_g_n);
    for (int i = 0; i < 60; ++i)
        p->zero_a[i] = (loadid_real_t)(p->zero_a_sum[i] / (double)p->zero_g_n);
    if (moved) {
        loadid_noise_acc_moved(&p->noise);
        note(p,
             "zeroing: the load moved (gravity in S spread %.3g m/s^2, omega %.3g rad/s RMS): "
             "the offset's and the noise's figures come from what a cubic in time leaves",
             g_spread, w_rms);
    }
    p->zeroed = 1;
    set_zeroing_noise(p);
    measure_tones(p, period_s);
    set_state(p, utime, LOADID_STATE_IDLE, "");
}

/* Windows that end by time, before anything at utime is handled. */
static void advance(loadid_pipeline_t *p, int64_t utime) {
    if (p->state == LOADID_STATE_ZEROING && utime >= p->zero_end_us) finish_zeroing(p, utime);
    if (p->state == LOADID_STATE_ESTIMATING && utime >= p->est_end_us)
        finish_estimation(p, utime, 1);
}

/* The clock ends a window only TICK_GRACE_US (plus the smoother's lag)
 * after its end, so that a window normally ends by its samples' own times
 * (as offline) and by the clock only when samples stop coming. */
#define TICK_GRACE_US 50000

/* Joint states stopped coming TICK_GRACE_US before now_us (the clock's, or
 * a sample's own time): the smoother serves what it has, before the queue
 * fills and serves samples it could have smoothed. */
static void end_stalled_piece(loadid_pipeline_t *p, int64_t now_us) {
    const int64_t newest = loadid_signals_newest_joint_time(p->sig);
    if (newest != INT64_MIN && newest < now_us - TICK_GRACE_US) {
        loadid_signals_end_piece(p->sig);
        refined_take_joints(p);
        flush_pending(p, INT64_MIN, 1);
    }
}

void loadid_pipeline_tick(loadid_pipeline_t *p, int64_t now_us) {
    /* the fixed-lag smoother's lag as it runs (kalman.lag_s in joint
     * periods; retune_joint_filters may lengthen it) */
    loadid_jf_config_t c;
    loadid_signals_filter_config(p->sig, &c);
    const int64_t grace = TICK_GRACE_US + (int64_t)c.lag_steps * c.nominal_step_us;
    end_stalled_piece(p, now_us);
    flush_pending(p, now_us - grace, 0); /* joints stopped: serve (or refuse) them */
    advance(p, now_us - grace);
}

void loadid_pipeline_finish(loadid_pipeline_t *p, int64_t now_us) {
    loadid_signals_end_piece(p->sig); /* nothing more comes: serve what there is */
    refined_take_joints(p);
    flush_pending(p, INT64_MAX, 0);
    advance(p, now_us);
    if (p->state == LOADID_STATE_ZEROING) finish_zeroing(p, now_us);
    if (p->state == LOADID_STATE_ESTIMATING) finish_estimation(p, now_us, 0);
}

/* ------------------------------------------------------------- inputs */

/* The joint period the filters run at, once: measured (auto), or a given
 * one the stream's own (its stamps' loop, after JOINT_PERIOD_CHECK
 * states) contradicts by more than a quarter. */
#define JOINT_PERIOD_CHECK 20
static void note_joint_period(loadid_pipeline_t *p) {
    loadid_jf_config_t c;
    loadid_signals_filter_config(p->sig, &c);
    const double ms = (double)c.nominal_step_us / 1e3;
    if (p->cfg.kalman_joint_period_s <= 0) {
        p->period_noted = 1;
        note(p,
             "joints: period %.3f ms, measured from the stream (kalman.joint_period_s auto); "
             "fixed-lag smoother %d steps (%.1f ms)",
             ms, c.lag_steps, (double)c.lag_steps * ms);
        return;
    }
    loadid_signals_stats_t st;
    loadid_signals_stats(p->sig, &st);
    if (st.joint_msgs_ok < JOINT_PERIOD_CHECK) return;
    p->period_noted = 1;
    const double stream = loadid_signals_stream_period_us(p->sig) / 1e3;
    if (fabs(stream - ms) > 0.25 * ms)
        note(p,
             "warning: joints: the stream's period is %.3f ms, kalman.joint_period_s says %.3f ms: "
             "the filters' gains are for the wrong step (auto measures it)",
             stream, ms);
}

/* Early in the window the joint positions' own noise (their fourth
 * differences since START) against what the measured-position filters
 * assume: over JOINT_RETUNE_FACTOR times (a coarser encoder than
 * kalman.meas_sigma's default of 2^20 counts) and with kalman.meas_sigma
 * auto, the filters take the measured noise, run again over the joint
 * states they kept (loadid_jf_retune: the last 0.4 s at 1 kHz), and the
 * on-line estimators start again from the next sample, their weights the
 * filters' new levels. Their state kept instead, the filters carried the
 * old gains' noise for some 0.3 s: RTLS's inertia error 1.7 times REF's on
 * the RX60 with the hollow load at 2^14 counts (20 seeds), 1.0 run again.
 * The smoother's bandwidth falls as the noise's cube root, its time constant
 * grows so, and so does its lag (to at most JOINT_RETUNE_MAX_LAG_S): on the
 * RX60 with 2^14 counts (88 times) RTLS was 14 % off in mass with the
 * filters left at 2^20 (refused at DONE, check_joint_noise); retuned with
 * the 50 ms lag its COM was 3.5 times REF's error, with 150 ms 0.9 times.
 * Tried from JOINT_RETUNE_DIFFS differences (about 30 % error in the
 * noise: a factor of 3 is not mistaken) to JOINT_RETUNE_S after START, as
 * long as a restart leaves most of the window: a robot starting from rest
 * shows its encoder steps only once it moves through them. A configured
 * kalman.meas_sigma is kept (and check_joint_noise judges the run by it). */
#define JOINT_RETUNE_FACTOR 3.0
#define JOINT_RETUNE_DIFFS 32
#define JOINT_RETUNE_S 0.4
#define JOINT_RETUNE_MAX_LAG_S 0.2

/* REFINED keeps the joint states on the filters' (regularised) clock, as
 * they reach the filters (the signals hold some: the period probe, the
 * stamp clock's look-ahead). */
static void refined_take_joints(loadid_pipeline_t *p) {
    loadid_real_t q[LOADID_MAX_JOINTS];
    if (!p->refined || refined_busy(p)) return;
    for (int i = 0; i < loadid_signals_fed_count(p->sig); ++i)
        loadid_refined_joint(p->refined, loadid_signals_fed_state(p->sig, i, q), q);
}

static void retune_joint_filters(loadid_pipeline_t *p) {
    if (p->state != LOADID_STATE_ESTIMATING || (p->cfg.noise_given & LOADID_NOISE_GIVEN_KF_MEAS) ||
        p->cfg.signals == LOADID_SIGNALS_SETPOINT ||
        loadid_signals_position_noise_count(p->sig) < JOINT_RETUNE_DIFFS)
        return;
    const int64_t now = loadid_signals_newest_joint_time(p->sig);
    loadid_jf_config_t c, n;
    if (now - p->start_us > (int64_t)llround(JOINT_RETUNE_S * 1e6) ||
        loadid_signals_filter_config(p->sig, &c) != 0)
        return;
    const double measured = loadid_signals_position_noise(p->sig);
    const double over = measured / (double)c.meas_sigma;
    if (!(over > JOINT_RETUNE_FACTOR)) return;
    double lag_us = (double)c.lag_steps * (double)c.nominal_step_us * cbrt(over);
    if (lag_us > JOINT_RETUNE_MAX_LAG_S * 1e6) lag_us = JOINT_RETUNE_MAX_LAG_S * 1e6;
    if (loadid_signals_retune(p->sig, measured, llround(lag_us)) < 0 ||
        loadid_signals_filter_config(p->sig, &n) != 0)
        return;
    restart_rows(p);
    filter_noise(p);
    apply_measured_noise(p);
    reset_drift(p);
    note(p,
         "joints: their positions are %.3g times noisier than the joint filters assumed (%.3g "
         "against %.3g, from %lld fourth differences since START; a coarser encoder): the "
         "filters take %.3g from here on (kalman.meas_sigma auto) and run again over the joint "
         "states they kept, the fixed-lag smoother %d steps (was %d), and the on-line estimators "
         "start again from the next sample",
         over, measured, (double)c.meas_sigma,
         (long long)loadid_signals_position_noise_count(p->sig), measured, n.lag_steps,
         c.lag_steps);
}

void loadid_pipeline_joint_state(loadid_pipeline_t *p, int64_t utime, int num_joints,
                                 const double *position, const double *setpoint) {
    loadid_real_t pos[LOADID_MAX_JOINTS], set[LOADID_MAX_JOINTS];
    if (num_joints < 1 || num_joints > LOADID_MAX_JOINTS || !position) {
        loadid_signals_push_joints(p->sig, utime, -1, NULL, NULL); /* counted there */
        return;
    }
    for (int i = 0; i < num_joints; ++i) {
        pos[i] = (loadid_real_t)position[i];
        if (setpoint) set[i] = (loadid_real_t)setpoint[i];
    }
    /* kalman.joint_delay_s: the joint stamps on the wrench's clock. */
    utime -= llround(p->cfg.kalman_joint_delay_s * 1e6);
    if (loadid_signals_push_joints(p->sig, utime, num_joints, pos, setpoint ? set : NULL) == 0) {
        memcpy(p->last_q, pos, (size_t)num_joints * sizeof pos[0]);
        p->have_q = 1;
        const int64_t newest = loadid_signals_newest_joint_time(p->sig);
        if (!p->period_noted && newest != INT64_MIN) note_joint_period(p);
        refined_take_joints(p);
        retune_joint_filters(p);
        flush_pending(p, INT64_MIN, 1);
    }
}

/* The worker's REFINED is in: publish it, and let it be the primary when
 * it is the best. */
static void collect_refined(loadid_pipeline_t *p) {
    refined_noted(p);
    if (p->state != LOADID_STATE_DONE) return;
    take_refined(p);
    note_unidentified(p, &p->latest[p->refined_m]);
    if (p->sink.estimate) p->sink.estimate(p->sink.ctx, &p->latest[p->refined_m]);
    choose_primary(p);
}

int loadid_pipeline_refined_async(loadid_pipeline_t *p) {
    if (p->refined_m < 0) return -ENOENT;
    if (!p->worker) {
        const int rc = loadid_worker_create(refined_job, p, &p->worker);
        if (rc != 0) return rc;
    }
    return loadid_worker_fd(p->worker);
}

int loadid_pipeline_refined_collect(loadid_pipeline_t *p) {
    if (!p->worker || !loadid_worker_collect(p->worker)) return 0;
    collect_refined(p);
    return 1;
}

int loadid_pipeline_refined_pending(loadid_pipeline_t *p) {
    return refined_busy(p);
}

/* The on-line estimators and what they are fed start from no rows. */
static void restart_rows(loadid_pipeline_t *p) {
    p->rescaled = 0;
    p->row_rescale[0] = p->row_rescale[1] = p->row_rescale[2] = 1;
    for (int m = 0; m < p->num_methods; ++m) loadid_est_reset(p->est[m]);
    p->samples_used = 0;
    p->since_publish = 0;
    p->have_row = 0;
    p->primary = -1;
    p->drift_significant = 0;
    loadid_spectrum_rows_reset(p->rows);
    loadid_notch_bank_restart(&p->notch);
}

static void reset_run(loadid_pipeline_t *p) {
    /* A new run waits for the last one's REFINED (and publishes it). */
    if (p->worker && loadid_worker_wait(p->worker)) collect_refined(p);
    restart_rows(p);
    p->refined_ran = 0;
    if (p->refined) loadid_refined_start(p->refined);
}

static void reset_drift(loadid_pipeline_t *p) {
    if (p->n_params == LOADID_NPHI)
        loadid_drift_check_reset(&p->drift,
                                 p->zero_t_first_us + llround(p->zero_t_sum / (double)p->zero_n),
                                 p->levels.force, p->levels.torque);
}

/* START: the noise levels measured so far (the zeroing window, else the
 * third differences; the joint filter's covariance at the pose) become the
 * on-line estimators' weights, unless the configuration gives them. */
static void apply_measured_noise(loadid_pipeline_t *p) {
    double channel[LOADID_NOISE_CHANNELS];
    const int src = loadid_noise_acc_sigma(&p->noise, MIN_ZEROING_SAMPLES, channel);
    if (src == LOADID_NOISE_STILL && p->notch.stages > 0 && p->notch_sigma[0] > 0) {
        /* The rows are notched: their noise is the window's without its
         * tones, times the notch's gain on white noise. */
        const double gain = sqrt(loadid_notch_bank_noise_gain(&p->notch));
        for (int i = 0; i < LOADID_NOISE_CHANNELS; ++i) channel[i] = p->notch_sigma[i] * gain;
    }
    double js = 0, ja = 0, jw = 0;
    const int64_t period = loadid_signals_joint_period_us(p->sig);
    if (period > 0 && period != p->filter_period_us) filter_noise(p);
    if (p->have_q)
        loadid_noise_joint_levels(p->kin, p->last_q, p->filter_sigma[1], p->filter_sigma[2], &js,
                                  &ja, &jw);
    const int source = p->cfg.signals;
    const int jr3_spec = source == LOADID_SIGNALS_SENSOR || source == LOADID_SIGNALS_MIXED;
    const int jr3_alpha = source == LOADID_SIGNALS_SENSOR;
    loadid_noise_combine(&p->cfg, jr3_spec, jr3_alpha, channel, src, js, ja, jw, &p->levels);
    zeroing_figures(p, &p->levels);
    for (int m = 0; m < p->num_methods; ++m) {
        if (m == p->refined_m) continue; /* weighted by its own run */
        loadid_est_config_t e = *loadid_est_config(p->est[m]);
        if (loadid_noise_weights(&p->levels, p->cfg.omega_typical, &e) == 0 &&
            loadid_est_set_weights(p->est[m], e.row_sigma, e.col_weight) == 0 &&
            loadid_est_set_exact(p->est[m], e.col_exact) == 0)
            loadid_est_set_measured(p->est[m], e.col_measured);
    }
    /* With the offset estimated no zeroing window sets the wrench noise
     * measured apart (set_zeroing_noise); the channels' levels are that
     * noise all the same, for phi_std's floor and the bias noisy columns
     * leave in least squares (loadid_est_config_t's noise_sigma). */
    if (p->n_params == LOADID_NPHI_OFFSET && src != LOADID_NOISE_FALLBACK) {
        const loadid_real_t sigma[2] = {(loadid_real_t)loadid_noise_rms3(channel),
                                        (loadid_real_t)loadid_noise_rms3(channel + 3)},
                            r[2] = {0, 0};
        for (int m = 0; m < p->num_methods; ++m)
            if (m != p->refined_m) loadid_est_set_noise_corr(p->est[m], sigma, r);
    }
    /* A configured level the data contradict (by more than 2 either way)
     * is still used, as configured, but said: weights off by a factor
     * cost RTLS up to 20 % of the mass in the study's wrong3x cells. */
    if (src != LOADID_NOISE_FALLBACK) {
        static const char *const keys[4] = {"noise.force", "noise.torque", "noise.linear",
                                            "noise.angular"};
        static const int bits[4] = {LOADID_NOISE_GIVEN_FORCE, LOADID_NOISE_GIVEN_TORQUE,
                                    LOADID_NOISE_GIVEN_LINEAR, LOADID_NOISE_GIVEN_ANGULAR};
        const double used[4] = {p->levels.force, p->levels.torque, p->cfg.noise_linear,
                                p->cfg.noise_angular};
        const int applies[4] = {1, 1, jr3_spec, jr3_alpha};
        for (int k = 0; k < 4; ++k) {
            const double *c = channel + 3 * k;
            const double measured = sqrt((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / 3.0);
            if (!applies[k] || !(p->cfg.noise_given & bits[k]) || !(measured > 0)) continue;
            if (used[k] > 2 * measured || used[k] < 0.5 * measured)
                note(p,
                     "warning: %s is %.3g but the data measure %.3g (%s); the configured level "
                     "is used",
                     keys[k], used[k], measured, loadid_noise_source_name(src));
        }
    }
    const loadid_noise_levels_t *l = &p->levels;
    note(p,
         "noise (%s): f %.3g N (%s), tau %.3g N m (%s), a - g %.3g m/s^2 (%s), alpha %.3g "
         "rad/s^2 (%s), omega %.3g rad/s (%s)",
         loadid_noise_source_name(src), l->force, loadid_noise_source_name(l->source[0]), l->torque,
         loadid_noise_source_name(l->source[1]), l->spec, loadid_noise_source_name(l->source[2]),
         l->alpha, loadid_noise_source_name(l->source[3]), l->omega,
         loadid_noise_source_name(l->source[4]));
}

static void run_command(loadid_pipeline_t *p, int64_t utime, int action, const char *load_name);

void loadid_pipeline_command(loadid_pipeline_t *p, int64_t utime, int action,
                             const char *load_name) {
    if (p->cfg.kalman_lag_s > 0) {
        /* Acts once the joint data cover its utime (flush_pending). A full
         * queue (commands faster than the lag) serves the oldest now. */
        if (p->commands_count == COMMANDS_MAX)
            flush_pending(p, p->commands[p->commands_head].utime + 1, 0);
        const int slot = (p->commands_head + p->commands_count) % COMMANDS_MAX;
        p->commands[slot].utime = utime;
        p->commands[slot].action = action;
        snprintf(p->commands[slot].load_name, sizeof p->commands[slot].load_name, "%s",
                 load_name ? load_name : "");
        p->commands_count++;
        flush_pending(p, INT64_MIN, 1);
        return;
    }
    flush_pending(p, utime, 0); /* what came before the command goes first */
    run_command(p, utime, action, load_name);
}

static void run_command(loadid_pipeline_t *p, int64_t utime, int action, const char *load_name) {
    advance(p, utime);
    switch (action) {
        case LOADID_CMD_ZERO:
            if (p->state == LOADID_STATE_ESTIMATING) {
                note(p, "ZERO ignored while estimating");
                return;
            }
            p->zero_n = p->zero_g_n = 0;
            memset(p->tone_share, 0, sizeof p->tone_share);
            memset(p->tone_hz, 0, sizeof p->tone_hz);
            memset(p->notch_hz, 0, sizeof p->notch_hz);
            memset(p->notch_sigma, 0, sizeof p->notch_sigma);
            loadid_notch_bank_clear(&p->notch);
            memset(p->zero_sum, 0, sizeof p->zero_sum);
            memset(p->zero_g_sum, 0, sizeof p->zero_g_sum);
            memset(p->zero_a_sum, 0, sizeof p->zero_a_sum);
            memset(p->zero_kin_sum, 0, sizeof p->zero_kin_sum);
            p->zero_g2_sum = p->zero_w2_sum = p->zero_t_sum = p->zero_kin_t_sum = 0;
            p->zeroed = 0;
            p->zero_seen = 1;
            loadid_noise_acc_reset_still(&p->noise);
            p->zero_end_us = utime + (int64_t)llround(p->cfg.zeroing_window_s * 1e6);
            set_state(p, utime, LOADID_STATE_ZEROING, "");
            return;
        case LOADID_CMD_START:
            if (p->state == LOADID_STATE_ESTIMATING) {
                note(p, "START ignored: already estimating");
                return;
            }
            if (p->state == LOADID_STATE_ZEROING) finish_zeroing(p, utime);
            if (p->state == LOADID_STATE_FAILED) return;
            if (p->n_params == LOADID_NPHI && !p->zeroed) {
                set_state(p, utime, LOADID_STATE_FAILED,
                          "START before a completed ZERO (estimation.offset_model is zeroing)");
                return;
            }
            reset_run(p);
            loadid_signals_position_noise_reset(p->sig);
            p->joint_over = 0;
            p->stamp_restarts = 0;
            apply_measured_noise(p); /* levels.joint_position 0 until DONE */
            reset_drift(p);
            {
                loadid_signals_stats_t s;
                loadid_signals_stats(p->sig, &s);
                p->stale_at_start = s.samples_stale + s.samples_no_joints;
                /* A restart before START whose line is still acquiring
                 * gives the window's first stamps: one of the window's. */
                p->restarts_at_start =
                    s.stamp_restarts - (s.stamp_acquiring && s.stamp_restarts > 0);
                loadid_jr3_stats_t j;
                loadid_jr3_decoder_stats(p->jr3, &j);
                p->incomplete_at_start = j.samples_incomplete;
                p->cover_prev_us = utime;
                p->missing_us = p->win_samples = p->win_saturated = p->win_faulty = 0;
            }
            snprintf(p->load_name, sizeof p->load_name, "%s", load_name ? load_name : "");
            p->started = 1;
            p->est_end_us = utime + (int64_t)llround(p->cfg.duration_s * 1e6);
            p->start_us = utime;
            set_state(p, utime, LOADID_STATE_ESTIMATING, "");
            return;
        case LOADID_CMD_STOP:
            if (p->state == LOADID_STATE_ESTIMATING)
                finish_estimation(p, utime, 1);
            else
                note(p, "STOP ignored: not estimating");
            return;
        case LOADID_CMD_RESET:
            reset_run(p);
            p->zeroed = 0;
            p->zero_seen = 0;
            p->complete = 0;
            p->incomplete_reason[0] = 0;
            p->started = 0;
            p->load_name[0] = 0;
            for (int m = 0; m < p->num_methods; ++m) {
                memset(&p->latest[m], 0, sizeof p->latest[m]);
                p->latest[m].method = p->cfg.methods[m];
            }
            set_state(p, utime, LOADID_STATE_IDLE, "");
            return;
        default:
            note(p, "unknown command action %d ignored", action);
            return;
    }
}

/* estimation.rescale_s after START: the TLS methods weigh rows and
 * columns again by what the measured noise does not explain. TLS splits
 * the misfit between rows and columns by the noise levels; a residual far
 * above them (backlash between the motor-side encoders and the load,
 * elasticity, a noise level configured wrong) is then blamed on the
 * columns, and TLS "corrects" them: 1 % of the mass in the study's
 * low-noise cells, where RLS was right. Whether the levels explain the
 * data is TLS's own misfit (sigma_min over the root of the rows: 1 when
 * they do); which rows carry the excess, the residual of the
 * least-squares fit of the same data, force and torque rows apart
 * (loadid_est_residual_scales). The least-squares residual alone is not
 * enough: with noisy columns (the accelerometer as the source) LS is
 * biased and its residual grows while TLS's misfit stays 1, and weighing
 * by it there cost 14 % of the mass. When TLS's misfit and a group's LS
 * residual exceed 1.2, that group's rows' noise is multiplied by it, and the
 * regressor columns' weights by the smaller of the two, so the columns
 * stay no noisier, relative to the rows, than the levels said: TLS then
 * corrects them no more than their measured noise allows (REFINED treats
 * its smoothed columns as exact outright). On the study's low-noise box
 * load RTLS's mass error went from 0.96 % to 0.08 % (RLS 0.10 %). Retried
 * every 50 samples while the data allow no LS fit yet. */
static void check_row_scales(loadid_pipeline_t *p, int64_t t_us) {
    if (p->rescaled || !(p->cfg.rescale_s > 0) ||
        t_us - p->start_us < (int64_t)llround(p->cfg.rescale_s * 1e6) || p->samples_used % 50 != 0)
        return;
    int first = -1;
    for (int m = 0; m < p->num_methods && first < 0; ++m)
        if (p->cfg.methods[m] == LOADID_METHOD_RTLS || p->cfg.methods[m] == LOADID_METHOD_TLS_BATCH)
            first = m;
    if (first < 0) {
        p->rescaled = 1;
        return;
    }
    loadid_real_t sc[2], phi[16];
    loadid_est_info_t info;
    if (loadid_est_estimate(p->est[first], phi, &info) != 0 ||
        loadid_est_residual_scales(p->est[first], NULL, sc) != 0)
        return;
    p->rescaled = 1;
    /* TLS's own misfit: sigma_min^2 is the weighted residual over all 6 k
     * rows, about 6 k when the levels explain the data. */
    const double tls = (double)info.sigma_min / sqrt(6.0 * (double)info.samples);
    const double f = sc[0] > 1 ? (double)sc[0] : 1, t = sc[1] > 1 ? (double)sc[1] : 1;
    const double c = f < t ? f : t;
    if (!(tls > 1.2) || !(f > 1.2 || t > 1.2)) {
        note(p,
             "rows: the misfit after %.3g s is what the noise levels say (TLS %.2f of them; "
             "least squares: force %.2f, torque %.2f)",
             p->cfg.rescale_s, tls, (double)sc[0], (double)sc[1]);
        return;
    }
    for (int m = 0; m < p->num_methods; ++m) {
        if (p->cfg.methods[m] != LOADID_METHOD_RTLS && p->cfg.methods[m] != LOADID_METHOD_TLS_BATCH)
            continue;
        const int rc =
            loadid_est_rescale(p->est[m], (loadid_real_t)f, (loadid_real_t)t, (loadid_real_t)c);
        if (rc != 0)
            note(p, "%s: rows not weighed again: %s", loadid_method_name(p->cfg.methods[m]),
                 loadid_strerror(rc));
    }
    p->row_rescale[0] = f, p->row_rescale[1] = t, p->row_rescale[2] = c;
    note(p,
         "rows: the misfit after %.3g s is %.2f times what the noise levels explain (TLS), "
         "%.2f in the force and %.2f in the torque rows (least squares); RTLS and TLS_BATCH "
         "weigh those rows by it, and the columns by %.2f, from here on and back to the first "
         "sample",
         p->cfg.rescale_s, tls, (double)sc[0], (double)sc[1], c);
}

/* The regressor the estimators use for one motion: eq. (6) less its mean
 * over the zeroing window (eqs. 7-9, for a load still or moving while
 * zeroed), or [A E6]. */
static int data_matrix(const loadid_pipeline_t *p, const loadid_regressor_input_t *in,
                       loadid_real_t A[6 * 16]) {
    return loadid_regressor_model_zeroed(in->spec, in->omega, in->alpha, p->n_params, p->zero_a, A);
}

/* Completeness: the window's F/T samples, usable or refused, and the time
 * between them. */
static void cover(loadid_pipeline_t *p, const loadid_sensor_sample_t *s) {
    if (p->state != LOADID_STATE_ESTIMATING) return;
    if (s->t_us - p->cover_prev_us > p->ft_gap_us) p->missing_us += s->t_us - p->cover_prev_us;
    if (s->t_us > p->cover_prev_us) p->cover_prev_us = s->t_us;
    p->win_samples++;
    p->win_saturated += s->saturated && !s->faulty;
    p->win_faulty += s->faulty;
}

static void on_sample(loadid_pipeline_t *p, const loadid_sensor_sample_t *s) {
    cover(p, s);
    if (s->saturated || s->faulty) return; /* queued for cover() only: never fed */
    loadid_real_t y[6], lin[3], ang[3];
    for (int i = 0; i < 3; ++i) {
        y[i] = (loadid_real_t)s->force[i];
        y[3 + i] = (loadid_real_t)s->torque[i];
        lin[i] = (loadid_real_t)s->spec[i];
        ang[i] = (loadid_real_t)s->alpha[i];
    }
    double x[LOADID_NOISE_CHANNELS];
    for (int i = 0; i < 6; ++i) x[i] = (double)y[i];
    for (int i = 0; i < 3; ++i) x[6 + i] = (double)lin[i], x[9 + i] = (double)ang[i];
    loadid_noise_acc_moving(&p->noise, s->t_us, NOISE_MAX_GAP_US / 3, x);
    if (p->state == LOADID_STATE_ZEROING) {
        loadid_noise_acc_still(&p->noise, x);
        for (int i = 0; i < 6; ++i) p->zero_sum[i] += (double)y[i];
        if (p->zero_n == 0) p->zero_t_first_us = s->t_us;
        p->zero_t_last_us = s->t_us;
        p->zero_t_sum += (double)(s->t_us - p->zero_t_first_us);
        p->zero_n++;
        loadid_kin_state_t k;
        loadid_real_t a[60];
        if (loadid_signals_kinematics_at(p->sig, s->t_us, &k) == 0 &&
            loadid_regressor(k.spec, k.omega, k.alpha, a) == 0) {
            for (int i = 0; i < 3; ++i) {
                p->zero_g_sum[i] += (double)k.gravity[i];
                p->zero_g2_sum += (double)k.gravity[i] * (double)k.gravity[i];
                p->zero_w2_sum += (double)k.omega[i] * (double)k.omega[i];
            }
            for (int i = 0; i < 60; ++i) p->zero_a_sum[i] += (double)a[i];
            for (int i = 0; i < 6; ++i) p->zero_kin_sum[i] += (double)y[i];
            p->zero_kin_t_sum += (double)(s->t_us - p->zero_t_first_us);
            p->zero_g_n++;
        }
        return;
    }
    if (p->state != LOADID_STATE_ESTIMATING && !(p->state == LOADID_STATE_DONE && p->primary >= 0))
        return;
    loadid_regressor_input_t motion, instr;
    const int riv = p->has_riv && p->state == LOADID_STATE_ESTIMATING;
    if (loadid_signals_at(p->sig, s->t_us, lin, ang, NULL, &motion, riv ? &instr : NULL) != 0)
        return; /* counted by the signals (stale, no data) */
    loadid_real_t A[6 * 16], C[6 * 16];
    if (data_matrix(p, &motion, A) != 0) return;
    if (p->n_params == LOADID_NPHI)
        for (int i = 0; i < 6; ++i) y[i] -= p->y0[i]; /* eq. (7): the zeroed wrench */
    if (p->state == LOADID_STATE_DONE) {
        /* wrench_t: measured minus what the estimate predicts. */
        loadid_real_t pred[6];
        loadid_regressor_apply(A, p->n_params, p->phi_total, pred);
        double f[3], t[3];
        for (int i = 0; i < 3; ++i)
            f[i] = (double)(y[i] - pred[i]), t[i] = (double)(y[3 + i] - pred[3 + i]);
        if (p->sink.wrench) p->sink.wrench(p->sink.ctx, s->t_us, f, t);
        return;
    }
    const int have_c = riv && data_matrix(p, &instr, C) == 0;
    /* REFINED pairs the wrench with its own smoothed kinematics, and the
     * trace the wrench with the motion: both take it as measured. */
    if (p->refined) loadid_refined_sample(p->refined, s->t_us, y, lin, ang);
    if (p->trace_rows) memcpy(p->row_y, y, sizeof p->row_y);
    if (p->notch.stages > 0) { /* the same filter on both sides: A phi = y still */
        loadid_notch_bank_apply(&p->notch, LOADID_NOTCH_A, 6 * p->n_params, A);
        if (have_c) loadid_notch_bank_apply(&p->notch, LOADID_NOTCH_C, 6 * p->n_params, C);
        loadid_notch_bank_apply(&p->notch, LOADID_NOTCH_Y, 6, y);
    }
    if (p->n_params == LOADID_NPHI) {
        loadid_drift_check_add(&p->drift, s->t_us, A, y);
        if (have_c) loadid_drift_check_add_instruments(&p->drift, s->t_us, A, C);
    }
    loadid_spectrum_rows_add(p->rows, s->t_us, A, have_c ? C : NULL, y);
    for (int m = 0; m < p->num_methods; ++m) {
        const int is_riv = p->cfg.methods[m] == LOADID_METHOD_RIV;
        if ((is_riv && !have_c) || m == p->refined_m) continue;
        if (loadid_est_update(p->est[m], A, is_riv ? C : NULL, y) != 0) p->estimator_errors++;
    }
    if (p->trace_rows) {
        p->row_motion = motion;
        p->have_row = 1;
    }
    p->samples_used++;
    p->last_sample_us = s->t_us;
    check_row_scales(p, s->t_us);
    if (p->publish_every > 0 && ++p->since_publish >= p->publish_every) {
        p->since_publish = 0;
        publish_all(p, 0);
    }
}

/* Processes the oldest waiting sample: windows end by its time first. */
static void pop_pending(loadid_pipeline_t *p) {
    const loadid_sensor_sample_t *s = &p->pending[p->pending_head];
    advance(p, s->t_us);
    on_sample(p, s);
    p->pending_head = (p->pending_head + 1) % PENDING_MAX;
    p->pending_count--;
}

/* Processes waiting samples with a time before `before`, or (ready) those
 * that joint data now covers. */
static void flush_pending(loadid_pipeline_t *p, int64_t before, int ready) {
    const int64_t joints = loadid_signals_last_joint_time(p->sig);
    for (;;) {
        /* The earlier of the next sample and the next waiting command; a
         * sample at a command's utime after it, as without the lag. */
        if (!p->pending_count && !p->commands_count) return;
        const int64_t ts = p->pending_count ? p->pending[p->pending_head].t_us : INT64_MAX;
        const int64_t tc = p->commands_count ? p->commands[p->commands_head].utime : INT64_MAX;
        const int sample = p->pending_count && (!p->commands_count || ts < tc);
        const int64_t t = sample ? ts : tc;
        if (!(t < before || (ready && t <= joints))) return;
        if (sample) {
            pop_pending(p);
        } else {
            const int h = p->commands_head;
            p->commands_head = (h + 1) % COMMANDS_MAX;
            p->commands_count--;
            run_command(p, p->commands[h].utime, p->commands[h].action, p->commands[h].load_name);
        }
    }
}

static void enqueue(loadid_pipeline_t *p, const loadid_sensor_sample_t *s);

/* A decoded JR3 sample as the pipeline's sensor sample: its four groups
 * in SI (jr3.h), the accelerometer's among them. */
static void from_jr3(const loadid_jr3_sample_t *j, loadid_sensor_sample_t *s) {
    s->t_us = j->t_us;
    for (int i = 0; i < 3; ++i) {
        s->force[i] = j->value[LOADID_JR3_FORCE][i];
        s->torque[i] = j->value[LOADID_JR3_MOMENT][i];
        s->spec[i] = j->value[LOADID_JR3_LINEAR][i];
        s->alpha[i] = j->value[LOADID_JR3_ANGULAR][i];
    }
    s->has_accel = 1;
    s->saturated = j->saturated;
    s->faulty = j->faulty;
}

int loadid_pipeline_can_frame(loadid_pipeline_t *p, const loadid_can_frame_t *frame) {
    loadid_jr3_output_t out;
    const int rc = loadid_jr3_decoder_feed(p->jr3, frame, &out);
    if (rc == LOADID_JR3_SAMPLE || rc == LOADID_JR3_E_SATURATED || rc == LOADID_JR3_E_FAULT) {
        /* A refused one (counted by the decoder) takes its place in the
         * queue too: the window's completeness counts it, in time order. */
        loadid_sensor_sample_t s;
        from_jr3(&out.sample, &s);
        s.saturated = s.saturated || rc == LOADID_JR3_E_SATURATED;
        s.faulty = s.faulty || rc == LOADID_JR3_E_FAULT;
        enqueue(p, &s);
        return 1;
    } else if (rc == LOADID_JR3_FULL_SCALE) {
        const loadid_jr3_full_scale_change_t *c = &out.full_scale;
        note(p, "JR3 %s full scale now %g %g %g (was %g %g %g)", loadid_jr3_group_name(c->group),
             c->current[0], c->current[1], c->current[2], c->previous[0], c->previous[1],
             c->previous[2]);
    }
    return 0;
}

/* A sample's queue slot, whichever sensor it came from. */
static void enqueue(loadid_pipeline_t *p, const loadid_sensor_sample_t *s) {
    end_stalled_piece(p, s->t_us); /* by the samples' own clock: offline as live */
    if (p->pending_count == PENDING_MAX) pop_pending(p); /* joints this late: serve it now */
    p->pending[(p->pending_head + p->pending_count) % PENDING_MAX] = *s;
    p->pending_count++;
    flush_pending(p, INT64_MIN, 1);
}

void loadid_pipeline_sample(loadid_pipeline_t *p, const loadid_sensor_sample_t *s) {
    if (!p) return;
    if (!s) {
        p->frames_bad_extra++;
        return;
    }
    if (s->faulty || s->saturated) {
        /* Never fed (as the JR3's E_SATURATED / E_FAULT); queued for the
         * window's completeness only. */
        p->ft_saturated += s->saturated != 0;
        p->ft_faulty += s->faulty != 0;
        p->ft_rejected++;
        loadid_sensor_sample_t r;
        memset(&r, 0, sizeof r);
        r.t_us = s->t_us;
        r.saturated = s->saturated != 0;
        r.faulty = s->faulty != 0;
        enqueue(p, &r);
        return;
    }
    if (!s->has_accel &&
        (p->cfg.signals == LOADID_SIGNALS_SENSOR || p->cfg.signals == LOADID_SIGNALS_MIXED)) {
        /* The source wants an accelerometer, which this sample does not
         * have (config.c refuses sensor.type modbus with these). */
        p->frames_bad_extra++;
        if (!p->ft_source_noted)
            note(p, "F/T sample without accelerometer refused: estimation.signals needs one");
        p->ft_source_noted = 1;
        return;
    }
    loadid_sensor_sample_t c = *s;
    for (int i = 0; i < 3; ++i) {
        if (!isfinite(s->force[i]) || !isfinite(s->torque[i]) ||
            (s->has_accel && (!isfinite(s->spec[i]) || !isfinite(s->alpha[i])))) {
            p->frames_bad_extra++;
            return;
        }
        /* Without an accelerometer, spec and alpha are 0 and the signal
         * source (kf, setpoint) takes them from the joints. */
        if (!s->has_accel) c.spec[i] = c.alpha[i] = 0;
    }
    p->ft_ok++;
    enqueue(p, &c);
}

void loadid_pipeline_bad_frame(loadid_pipeline_t *p) {
    p->frames_bad_extra++;
}

void loadid_pipeline_status(const loadid_pipeline_t *p, loadid_pipeline_status_t *st) {
    memset(st, 0, sizeof *st);
    st->state = p->state;
    snprintf(st->reason, sizeof st->reason, "%s", p->reason);
    loadid_jr3_stats_t j;
    loadid_jr3_decoder_stats(p->jr3, &j);
    loadid_signals_stats_t s;
    loadid_signals_stats(p->sig, &s);
    st->samples_ok = j.samples_ok + p->ft_ok;
    st->samples_used = p->samples_used;
    st->frames_bad = j.frames_bad + p->frames_bad_extra;
    st->samples_incomplete = j.samples_incomplete;
    st->samples_saturated = j.samples_saturated + p->ft_saturated;
    st->samples_faulty = j.samples_faulty + p->ft_faulty;
    st->samples_rejected = j.samples_rejected + p->ft_rejected;
    st->sequence_gaps = j.sequence_gaps;
    st->joint_msgs_bad = s.joint_msgs_bad;
    st->joint_stamp_restarts = s.stamp_restarts;
    st->samples_stale = s.samples_stale + s.samples_no_joints;
    st->estimator_errors = p->estimator_errors;
    st->complete = p->complete;
    snprintf(st->incomplete_reason, sizeof st->incomplete_reason, "%s", p->incomplete_reason);
    st->noise = p->levels;
    for (int i = 0; i < 3; ++i) st->rescale[i] = p->row_rescale[i];
}

int loadid_pipeline_refined_report(const loadid_pipeline_t *p, loadid_refined_report_t *out) {
    if (p->refined_m < 0 || !p->refined_ran) return -ENODATA;
    *out = p->refined_rep;
    return 0;
}

int loadid_pipeline_estimates(const loadid_pipeline_t *p, loadid_pipeline_estimate_t *out,
                              int max) {
    int n = p->num_methods < max ? p->num_methods : max;
    for (int m = 0; m < n; ++m) out[m] = p->latest[m];
    return n;
}

int loadid_pipeline_started(const loadid_pipeline_t *p) {
    return p->started;
}

const loadid_config_t *loadid_pipeline_config(const loadid_pipeline_t *p) {
    return &p->cfg;
}

int loadid_pipeline_final(const loadid_pipeline_t *p, loadid_pipeline_estimate_t *est,
                          loadid_pipeline_compensation_t *comp) {
    if (p->state != LOADID_STATE_DONE || p->primary < 0) return -ENODATA;
    *est = p->latest[p->primary];
    memset(comp, 0, sizeof *comp);
    comp->n_params = p->n_params;
    for (int i = 0; i < p->n_params; ++i) comp->phi_total[i] = (double)p->phi_total[i];
    comp->zeroed = p->zeroed;
    for (int i = 0; i < 6; ++i) comp->y0[i] = (double)p->y0[i];
    for (int i = 0; i < 3; ++i) comp->g_init[i] = (double)p->g_init[i];
    for (int i = 0; i < 60; ++i) comp->zero_a[i] = (double)p->zero_a[i];
    return 0;
}

int loadid_pipeline_restore(loadid_pipeline_t *p, const loadid_pipeline_estimate_t *est,
                            const loadid_pipeline_compensation_t *comp) {
    if (comp->n_params != p->n_params) return -EINVAL;
    if (p->n_params == LOADID_NPHI && !comp->zeroed) return -EINVAL;
    int m = -1;
    for (int i = 0; i < p->num_methods && m < 0; ++i)
        if (p->cfg.methods[i] == est->method) m = i;
    if (m < 0) return -EINVAL;
    for (int i = 0; i < comp->n_params; ++i)
        if (!isfinite(comp->phi_total[i])) return -EINVAL;
    for (int i = 0; i < 6; ++i)
        if (!isfinite(comp->y0[i])) return -EINVAL;
    for (int i = 0; i < 3; ++i)
        if (!isfinite(comp->g_init[i])) return -EINVAL;
    for (int i = 0; i < 60; ++i)
        if (!isfinite(comp->zero_a[i])) return -EINVAL;
    for (int i = 0; i < comp->n_params; ++i) p->phi_total[i] = (loadid_real_t)comp->phi_total[i];
    for (int i = 0; i < 6; ++i) p->y0[i] = (loadid_real_t)comp->y0[i];
    for (int i = 0; i < 3; ++i) p->g_init[i] = (loadid_real_t)comp->g_init[i];
    for (int i = 0; i < 60; ++i) p->zero_a[i] = (loadid_real_t)comp->zero_a[i];
    p->zeroed = comp->zeroed;
    p->latest[m] = *est;
    p->latest[m].state = LOADID_STATE_DONE;
    snprintf(p->load_name, sizeof p->load_name, "%s", est->load_name);
    p->primary = m;
    p->state = LOADID_STATE_DONE;
    return 0;
}
