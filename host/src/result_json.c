/* JSON result of loadidd --offline (result_json.h). */
#include "result_json.h"

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

int loadid_result_json_write(FILE *out, const loadid_pipeline_estimate_t *est, int n) {
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
        fprintf(out, ", \"physically_consistent\": %s", e->physically_consistent ? "true" : "false");
        if (!e->valid) {
            fputs(", \"error\": ", out);
            string(out, loadid_strerror(e->error));
        }
        fprintf(out, "}%s\n", i + 1 < n ? "," : "");
    }
    fputs("]\n", out);
    return ferror(out) ? -1 : 0;
}
