/* JSON result of loadidd --offline (result_json.h). */
#include "result_json.h"

#include <errno.h>
#include <math.h>

#include "loadid/core.h"

static void number(FILE *out, double v) {
    if (isfinite(v))
        fprintf(out, "%.17g", v);
    else
        fputs("null", out);
}

static void array(FILE *out, const double *v, int n) {
    fputc('[', out);
    for (int i = 0; i < n; ++i) {
        if (i) fputs(", ", out);
        number(out, v[i]);
    }
    fputc(']', out);
}

/* A JSON string: quotes, backslashes and control characters escaped. */
static void string(FILE *out, const char *s) {
    fputc('"', out);
    for (const unsigned char *c = (const unsigned char *)s; *c; ++c) {
        if (*c == '"' || *c == '\\')
            fprintf(out, "\\%c", *c);
        else if (*c < 0x20)
            fprintf(out, "\\u%04x", *c);
        else
            fputc(*c, out);
    }
    fputc('"', out);
}

static void levels(FILE *out, const loadid_noise_levels_t *l) {
    static const char *const names[5] = {"force", "torque", "spec", "alpha", "omega"};
    const double v[5] = {l->force, l->torque, l->spec, l->alpha, l->omega};
    fputc('{', out);
    for (int i = 0; i < 5; ++i) {
        fprintf(out, "%s\"%s\": ", i ? ", " : "", names[i]);
        number(out, v[i]);
    }
    fputs(", \"source\": {", out);
    for (int i = 0; i < 5; ++i) {
        fprintf(out, "%s\"%s\": ", i ? ", " : "", names[i]);
        string(out, loadid_noise_source_name(l->source[i]));
    }
    fputs("}, \"channels\": ", out);
    array(out, l->channel, LOADID_NOISE_CHANNELS);
    fputs(", \"channels_from\": ", out);
    string(out, loadid_noise_source_name(l->channel_source));
    fputs(", \"joint\": ", out);
    const double j[3] = {l->joint_spec, l->joint_alpha, l->joint_omega};
    array(out, j, 3);
    fputs(", \"joint_position\": ", out);
    number(out, l->joint_position);
    fputs(", \"correlation\": ", out);
    array(out, l->correlation, 2);
    fputs(", \"tone\": {\"share\": ", out);
    array(out, l->tone_share, 2);
    fputs(", \"hz\": ", out);
    array(out, l->tone_hz, 2);
    fputs(", \"notch_hz\": ", out);
    array(out, l->notch_hz, 2);
    fputc('}', out);
    fputc('}', out);
}

/* {group: why} for each group e does not identify. */
static void not_identified(FILE *out, const loadid_pipeline_estimate_t *e) {
    fputc('{', out);
    const char *sep = "";
    for (int g = 0; g < 3; ++g) {
        char why[160];
        if (!loadid_pipeline_why_not(e, g, why, sizeof why)) continue;
        fputs(sep, out);
        string(out, loadid_ident_name(1 << g));
        fputs(": ", out);
        string(out, why);
        sep = ", ";
    }
    fputc('}', out);
}

int loadid_result_json_write(FILE *out, const loadid_pipeline_estimate_t *est, int n,
                             const loadid_pipeline_status_t *st,
                             const loadid_refined_report_t *ref) {
    fputs("[\n", out);
    for (int i = 0; i < n; ++i) {
        const loadid_pipeline_estimate_t *e = &est[i];
        fputs("  {\"method\": ", out);
        string(out, loadid_method_name((loadid_method_t)e->method));
        fputs(", \"load_name\": ", out);
        string(out, e->load_name);
        fprintf(out, ", \"samples\": %lld,\n   \"phi\": ", (long long)e->samples);
        array(out, e->phi, 10);
        fputs(",\n   \"offset\": ", out);
        array(out, e->offset, 6);
        fputs(",\n   \"mass\": ", out);
        number(out, e->mass);
        fputs(", \"com\": ", out);
        array(out, e->com, 3);
        fputs(",\n   \"inertia_com\": ", out);
        array(out, e->inertia_com, 6);
        fputs(",\n   \"condition_number\": ", out);
        number(out, e->condition_number);
        fprintf(out, ", \"physically_consistent\": %s",
                e->physically_consistent ? "true" : "false");
        const int model = e->valid && e->has_model;
        fputs(",\n   \"phi_std\": ", out);
        if (model) {
            array(out, e->phi_std, 10);
        } else {
            const double none[10] = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
            array(out, none, 10);
        }
        fputs(",\n   \"identified\": [", out);
        int first = 1;
        for (int bit = LOADID_IDENT_MASS; bit <= LOADID_IDENT_INERTIA && model; bit <<= 1) {
            if (!(e->identified & bit)) continue;
            fputs(first ? "" : ", ", out);
            string(out, loadid_ident_name(bit));
            first = 0;
        }
        fputs("],\n   \"model_phi\": ", out);
        array(out, e->model_phi, 10);
        fprintf(out, ", \"projected\": %s", model && e->projected ? "true" : "false");
        fprintf(out, ", \"complete\": %s", st->complete ? "true" : "false");
        fputs(",\n   \"noise_scale\": ", out);
        number(out, model ? e->noise_scale : NAN);
        fputs(", \"snr\": ", out);
        const double none3[3] = {NAN, NAN, NAN};
        array(out, model ? e->snr : none3, 3);
        fputs(",\n   \"not_identified\": ", out);
        not_identified(out, e);
        fputs(", \"model\": {\"mass\": ", out);
        number(out, e->model_mass);
        fputs(", \"com\": ", out);
        array(out, e->model_com, 3);
        fputs(", \"inertia_com\": ", out);
        array(out, e->model_inertia_com, 6);
        fputs("},\n   \"noise\": ", out);
        levels(out, &st->noise);
        if (e->method == LOADID_METHOD_RTLS || e->method == LOADID_METHOD_TLS_BATCH) {
            fputs(",\n   \"rescale\": ", out);
            array(out, st->rescale, 3);
        }
        if (ref && e->method == LOADID_METHOD_REFINED) {
            fprintf(out, ",\n   \"refined\": {\"samples\": %lld, \"sensor_spec_error\": ",
                    (long long)ref->samples);
            number(out, ref->sensor_spec_error);
            fputs(", \"sensor_alpha_error\": ", out);
            number(out, ref->sensor_alpha_error);
            fputs(", \"sensor_tone\": {\"share\": ", out);
            array(out, ref->sensor_tone_share, 2);
            fputs(", \"hz\": ", out);
            array(out, ref->sensor_tone_hz, 2);
            fputc('}', out);
            fputs(", \"unexplained\": ", out);
            array(out, ref->unexplained, 2);
            fputs(", \"jerk_psd\": ", out);
            number(out, ref->jerk_psd);
            fputs(", \"omega_rms\": ", out);
            number(out, ref->omega_rms);
            fputs(", \"joint_delay_s\": ", out);
            number(out, (double)ref->joint_delay_us * 1e-6);
            fputs(", \"joint_delay_std_s\": ", out);
            number(out, ref->joint_delay_std_us * 1e-6);
            fprintf(out, ", \"joint_delay_used\": %s", ref->joint_delay_used ? "true" : "false");
            if (ref->drift_fitted) {
                fputs(", \"drift\": ", out);
                array(out, ref->drift, 6);
            }
            fputs(", \"levels\": ", out);
            levels(out, &ref->levels);
            fputc('}', out);
        }
        if (!e->valid) {
            fputs(", \"error\": ", out);
            string(out, e->why[0] ? e->why : loadid_strerror(e->error));
        }
        fprintf(out, "}%s\n", i + 1 < n ? "," : "");
    }
    fputs("]\n", out);
    return ferror(out) ? -EIO : 0;
}
