/*
 * The estimation pipeline of loadidd, the same for the live service and
 * --offline: sensor samples (or the JR3's CAN frames), joint states and
 * commands in, in time order; estimates, compensated wrenches and state
 * changes out through callbacks.
 *
 *   frames  -> JR3 decoder (drivers/jr3.h) -> a sensor sample; incomplete
 *              samples and bad frames are counted
 *   samples -> one type for every sensor (loadid_sensor_sample_t): only
 *              unsaturated, fault-free ones go on; the others are counted
 *   joints  -> joint filters (firmware signals.h): wrong count, NaN, time
 *              going backwards refused and counted
 *   sample  -> by state:
 *     ZEROING     wrench averaged over zeroing.window_s; g_init, gravity in
 *                 S from the forward kinematics of the measured joints
 *                 (eqs. 7-9)
 *     ESTIMATING  signal source -> regressor of eq. (6) with the zeroing
 *                 term (or [A E6]) -> every configured estimator; RIV's
 *                 instruments from the setpoints; estimation.duration_s
 *                 after START (or STOP) -> DONE
 *     DONE        wrench_t: measured wrench minus what the final estimate
 *                 (load and distal part, and offset) predicts
 *   commands ZERO, START, STOP, RESET drive IDLE -> ZEROING -> ESTIMATING
 *   -> DONE, or FAILED with a reason.
 * The distal sensor part (distal.phi) is estimated with the load and
 * subtracted from what is reported. After create nothing here allocates.
 */
#ifndef LOADID_PIPELINE_H
#define LOADID_PIPELINE_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/can_frame.h"
#include "loadid/chain.h"
#include "loadid/config.h"
#include "loadid/noise_model.h"
#include "loadid/refined.h"

#ifdef __cplusplus
extern "C" {
#endif

/* States, the values of estimate_t's constants (docs/INTERFACE.md). */
enum {
    LOADID_STATE_IDLE = 0,
    LOADID_STATE_ZEROING = 1,
    LOADID_STATE_ESTIMATING = 2,
    LOADID_STATE_DONE = 3,
    LOADID_STATE_FAILED = 4
};

/* Commands, command_t's constants. */
enum { LOADID_CMD_ZERO = 1, LOADID_CMD_START = 2, LOADID_CMD_STOP = 3, LOADID_CMD_RESET = 4 };

#define LOADID_LOAD_NAME_MAX 128

/* One method's estimate, the fields of estimate_t. */
typedef struct {
    int64_t utime; /* newest sample used */
    int64_t samples;
    int method; /* loadid_method_t */
    int state;
    char load_name[LOADID_LOAD_NAME_MAX];
    double phi[10];   /* the load: distal part removed */
    double offset[6]; /* estimated F/T offset ([A E6]), else 0 */
    double mass, com[3], inertia_com[6];
    double condition_number;
    double sigma_min;
    int physically_consistent;
    int valid;     /* 0: no estimate yet (error says why) */
    int error;     /* the core's code when !valid */
    char why[256]; /* when !valid: what is missing, in words */
    /* Filled in the final estimate (DONE) only, load_model_t's fields
     * (phi_std also in every valid estimate after
     * loadid_pipeline_std_always): */
    int has_model;        /* 1 when the fields below are set */
    double phi_std[10];   /* one standard deviation of each element
                                     (+Inf: not determined by the data) */
    double noise_scale;   /* a-posteriori noise scale s (1: the
                                     weights' noise levels fit the data) */
    int identified;       /* LOADID_IDENT_* bits (load_model.h) */
    int ident_why[3];     /* mass, COM, inertia: why not identified
                                     (loadid_ident_why_t; loadid_pipeline_why_not) */
    double ident_over[3]; /* how far its failed test is over the bound */
    int projected;        /* model_phi differs from phi */
    double model_phi[10]; /* physically consistent (load_model.h) */
    double snr[3];        /* mass, m c, inertia: how far each stands out
                                     of the noise (loadid_est_signal_to_noise) */
    double model_mass, model_com[3], model_inertia_com[6];
    /* After loadid_pipeline_trace_rows, in every estimate published while
     * ESTIMATING and in the final ones: the window's newest sample so far
     * (the trace's columns, trace_csv.h). */
    int has_row;          /* 1 when the fields below are set */
    double row_wrench[6]; /* its wrench as the estimators take it, less
                                     the distal part's: measured minus the
                                     zeroing average (eq. 7) when zeroing,
                                     minus A phi_distal [N, N m] */
    double row_motion[9]; /* the signal source's a - g [m/s^2], omega
                                     [rad/s], alpha [rad/s^2] of its regressor */
    double row_g_init[3]; /* gravity in S at zeroing (the zeroing term of
                                     eqs. 7-9: A is eq. (6) at a - g + g_init);
                                     0 with the offset model */
    double residual[6];   /* row_wrench - A phi - offset: what this
                                     estimate leaves unexplained [N, N m];
                                     NaN when !valid */
} loadid_pipeline_estimate_t;

/* One force-torque sample, whichever sensor it came from (the JR3's four
 * CAN frames decoded by loadid_pipeline_can_frame, the Modbus sensor's
 * registers by its poller): the one type the pipeline's queue, zeroing,
 * estimators and wrench_t take. In S, SI. */
typedef struct {
    int64_t t_us;      /* its time [us], the joint states' clock */
    double force[3];   /* f [N] */
    double torque[3];  /* tau [N m] */
    double spec[3];    /* the accelerometer's a - g [m/s^2] */
    double alpha[3];   /* its angular acceleration [rad/s^2] */
    uint8_t has_accel; /* spec and alpha measured (the JR3); else
                                     they are 0 and the signal source (kf,
                                     setpoint) takes them from the joints */
    uint8_t saturated; /* refused: counted, never fed */
    uint8_t faulty;    /* refused: counted, never fed */
} loadid_sensor_sample_t;

/* Counters (status_t's and more). */
typedef struct {
    int state;
    char reason[192];     /* why FAILED, else "" */
    int64_t samples_ok;   /* complete usable JR3 samples, and usable
                                     loadid_pipeline_sample ones */
    int64_t samples_used; /* fed to the estimators this run */
    int64_t frames_bad;   /* unknown id, wrong DLC, malformed, bad log line */
    int64_t samples_incomplete;
    int64_t samples_saturated;
    int64_t samples_faulty;
    int64_t samples_rejected; /* saturated or faulty or both, each once
                                     (status_t.samples_saturated) */
    int64_t sequence_gaps;
    int64_t joint_msgs_bad;
    int64_t joint_stamp_restarts; /* loadid_signals_stats_t's stamp_restarts */
    int64_t samples_stale;        /* no joint state close enough */
    int64_t estimator_errors;     /* updates refused (non-finite input, full) */
    /* The last estimation run, once it ended: */
    int complete;                /* 1: ZERO (when zeroing) and START seen, the
                                     window ran to its end (or STOP), F/T
                                     samples and joint data for nearly all
                                     of it (estimation.max_missing_share),
                                     few F/T samples refused
                                     (estimation.max_refused_share); 0 also
                                     after FAILED */
    char incomplete_reason[256]; /* why not, else "" */
    loadid_noise_levels_t noise; /* the on-line estimators' noise levels */
    double rescale[3];           /* what RTLS and TLS_BATCH multiplied the force
                                     rows', torque rows' noise and the columns'
                                     weights by (estimation.rescale_s); 1 = kept */
} loadid_pipeline_status_t;

typedef struct {
    void *ctx;
    /* Every method's estimate: after each sample while ESTIMATING (every
     * publish_every-th; may be NULL), and the final one at DONE. */
    void (*estimate)(void *ctx, const loadid_pipeline_estimate_t *e);
    /* The compensated wrench of each usable sample once DONE. */
    void (*wrench)(void *ctx, int64_t utime, const double force[3], const double torque[3]);
    /* A state change (reason: why FAILED, else ""). */
    void (*state)(void *ctx, int64_t utime, int state, const char *reason);
    /* Something worth a log line (a full-scale change, an ignored command). */
    void (*log)(void *ctx, const char *msg);
} loadid_pipeline_sink_t;

typedef struct loadid_pipeline loadid_pipeline_t; /* opaque */

/* publish_every: estimates during ESTIMATING go out after every n-th
 * sample (1: every sample; 0: only the final one). Returns 0, or a
 * negative code with a one-line reason in err. */
int loadid_pipeline_create(const loadid_config_t *cfg, const loadid_chain_t *chain,
                           const loadid_pipeline_sink_t *sink, int publish_every,
                           loadid_pipeline_t **out, char *err, size_t errlen);

void loadid_pipeline_destroy(loadid_pipeline_t *p);

/* Every valid estimate published while ESTIMATING carries phi_std too
 * (loadid_est_uncertainty, a few microseconds each; allocates nothing),
 * not only the final one: loadidd --offline --trace, for the error band
 * of an estimate's evolution. Off by default. */
void loadid_pipeline_std_always(loadid_pipeline_t *p, int on);

/* Every published estimate carries the window's newest sample (its wrench,
 * motion and zeroing gravity) and the residual wrench the estimate leaves
 * on it (has_row, row_*, residual): the trace's residual. The loop keeps
 * one sample's row (15 numbers) per sample; each publication computes the
 * sample's regressor once and a 6 x 16 product per method. Allocates
 * nothing. Off by default. */
void loadid_pipeline_trace_rows(loadid_pipeline_t *p, int on);

/* Inputs, in time order. */
void loadid_pipeline_joint_state(loadid_pipeline_t *p, int64_t utime, int num_joints,
                                 const double *position, const double *setpoint);
void loadid_pipeline_command(loadid_pipeline_t *p, int64_t utime, int action,
                             const char *load_name);
/* Returns 1 when the frame completed a JR3 sample (usable or refused as
 * saturated or faulty), else 0: the live loop times a sample from it. */
int loadid_pipeline_can_frame(loadid_pipeline_t *p, const loadid_can_frame_t *frame);
/* One sample decoded outside the pipeline (the Modbus F/T of
 * drivers/modbus_ft.h, which has no accelerometer). It takes the JR3
 * sample's path (the pending queue, zeroing, estimation, wrench_t); one
 * without an accelerometer is refused when estimation.signals needs one
 * (sensor, mixed: counted in frames_bad and logged once). A saturated or
 * faulty sample is counted in samples_saturated / samples_faulty and never
 * fed; a non-finite value, or s NULL (a read that gave no sample), is
 * counted in frames_bad. */
void loadid_pipeline_sample(loadid_pipeline_t *p, const loadid_sensor_sample_t *s);
/* A can.log line or socket read that was not a frame. */
void loadid_pipeline_bad_frame(loadid_pipeline_t *p);
/* Time passes without input: ends zeroing and estimation windows that
 * ended more than 50 ms before now_us (a window ends by its samples' times
 * first; the clock only when samples stop). */
void loadid_pipeline_tick(loadid_pipeline_t *p, int64_t now_us);
/* The input ended (offline): an estimation under way ends as by STOP. */
void loadid_pipeline_finish(loadid_pipeline_t *p, int64_t now_us);

void loadid_pipeline_status(const loadid_pipeline_t *p, loadid_pipeline_status_t *st);

/* The latest estimate of every configured method (in configuration order);
 * returns how many (<= max). */
int loadid_pipeline_estimates(const loadid_pipeline_t *p, loadid_pipeline_estimate_t *out, int max);

/* What compensating the wrench takes, besides the estimate: phi of load
 * and distal part together (and the offset, for 16 parameters), and the
 * zeroing (y0: the wrench averaged at zeroing, g_init: gravity in S then,
 * zero_a: eq. (6) averaged then, loadid_regressor_subtract_zeroing). */
typedef struct {
    int n_params; /* 10 (zeroing) or 16 ([A E6]) */
    double phi_total[16];
    int zeroed;
    double y0[6], g_init[3], zero_a[60];
} loadid_pipeline_compensation_t;

/* The primary estimate and its compensation, once DONE: the method whose
 * load model has the most identified groups (ties: REFINED, then the
 * configuration's order); phi_total is its physically consistent model
 * with the distal part. Returns 0, or -ENODATA (no estimate). */
int loadid_pipeline_final(const loadid_pipeline_t *p, loadid_pipeline_estimate_t *est,
                          loadid_pipeline_compensation_t *comp);

/* Starts from a saved estimate: state DONE, wrench_t flowing. Returns 0,
 * or -EINVAL (n_params or the method not this configuration's, a value
 * not finite, zeroing data missing for 10 parameters). */
int loadid_pipeline_restore(loadid_pipeline_t *p, const loadid_pipeline_estimate_t *est,
                            const loadid_pipeline_compensation_t *comp);

/* Live: REFINED (about 14 ms at DONE) on a worker thread instead of in
 * the caller's loop. Returns a file descriptor that becomes readable when
 * a run has ended; the loop then calls loadid_pipeline_refined_collect.
 * Until then the on-line methods' finals are out, wrench_t uses the best
 * of them, and loadid_pipeline_final gives that one; REFINED's estimate
 * comes out when collected, and becomes the primary when it is the best.
 * A START before that waits for the run. -ENOENT when REFINED is not
 * configured, or -errno. Call at most once, before the first input. */
int loadid_pipeline_refined_async(loadid_pipeline_t *p);
/* 1 when the worker's REFINED run had ended and is now published, else 0. */
int loadid_pipeline_refined_collect(loadid_pipeline_t *p);
/* 1 while a REFINED run is on the worker and not yet collected. */
int loadid_pipeline_refined_pending(loadid_pipeline_t *p);

/* The REFINED run's report (refined.h); -ENODATA when REFINED is not
 * configured or has not run. */
int loadid_pipeline_refined_report(const loadid_pipeline_t *p, loadid_refined_report_t *out);

/* The configuration the pipeline was created with. */
const loadid_config_t *loadid_pipeline_config(const loadid_pipeline_t *p);

/* Whether START was ever seen since create or RESET. */
int loadid_pipeline_started(const loadid_pipeline_t *p);

/* Why a final estimate's group (0 mass, 1 COM, 2 inertia) is not
 * identified, in words, into out (at most len bytes): "no estimate" when
 * e is not valid (e->why says why), "" when the group is identified
 * (e->identified) or a valid e has no load model (not final); a group
 * without a reason kept (a restored result) says so. Returns 1 when it
 * wrote a reason, else 0. */
int loadid_pipeline_why_not(const loadid_pipeline_estimate_t *e, int group, char *out, size_t len);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_PIPELINE_H */
