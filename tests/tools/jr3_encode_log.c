/*
 * jr3_encode_log: the JR3 encoder and the candump formatter of drivers/ as a
 * filter, for the Python cross-check against proto/jr3.dbc
 * (tests/python/test_jr3_dbc.py). Default configuration (base 0x1A0,
 * default full scales), interface vcan0. One command a line on stdin:
 *
 *   S t_us seq fault_groups v0 .. v11
 *       one sample, values [SI] in the order force XYZ, moment XYZ,
 *       linear XYZ, angular XYZ -> four candump lines
 *   F t_us group fs0 fs1 fs2
 *       the base+4 frame of a group -> one candump line
 *
 * Numbers as strtod/strtoll read them. Exit 0, or 1 with a one-line reason
 * on stderr for a line it cannot read or encode.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "loadid/candump.h"
#include "loadid/jr3.h"

static int die(long line, const char *why) {
    fprintf(stderr, "jr3_encode_log: line %ld: %s\n", line, why);
    return 1;
}

/* Reads one number token; returns 0 or -1. */
static int next_double(char **p, double *out) {
    char *end;
    errno = 0;
    *out = strtod(*p, &end);
    if (end == *p || errno == ERANGE) {
        return -1;
    }
    *p = end;
    return 0;
}

static int next_ll(char **p, long long *out) {
    char *end;
    errno = 0;
    *out = strtoll(*p, &end, 0);
    if (end == *p || errno == ERANGE) {
        return -1;
    }
    *p = end;
    return 0;
}

static int print_frame(const loadid_can_frame_t *f) {
    char buf[LOADID_CANDUMP_LINE_MAX];
    int n = loadid_candump_format(f, "vcan0", buf, sizeof buf);
    if (n < 0) {
        return n;
    }
    fputs(buf, stdout);
    return 0;
}

int main(int argc, char **argv) {
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printf(
            "usage: jr3_encode_log < COMMANDS\n"
            "Encodes JR3 frames as candump lines (base 0x1A0, default full scales,\n"
            "vcan0), one command a line on stdin:\n"
            "  S t_us seq fault_groups v0 .. v11   a sample (SI) -> four lines\n"
            "  F t_us group fs0 fs1 fs2            a full-scale frame -> one line\n");
        return 0;
    }
    if (argc > 1) {
        fprintf(stderr, "usage: jr3_encode_log < COMMANDS (see --help)\n");
        return 2;
    }
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    char line[1024];
    long lineno = 0;
    while (fgets(line, sizeof line, stdin)) {
        ++lineno;
        char *p = line;
        while (*p == ' ' || *p == '\t') {
            ++p;
        }
        if (*p == '\n' || *p == '\0') {
            continue;
        }
        char cmd = *p++;
        long long t_us, a;
        if (next_ll(&p, &t_us) != 0 || next_ll(&p, &a) != 0) {
            return die(lineno, "expected t_us and a number");
        }
        if (cmd == 'S') {
            long long fault;
            double v[LOADID_JR3_NUM_GROUPS][3];
            if (a < 0 || a > 255 || next_ll(&p, &fault) != 0 || fault < 0 || fault > 15) {
                return die(lineno, "bad sequence or fault_groups");
            }
            for (int i = 0; i < 12; ++i) {
                if (next_double(&p, &v[i / 3][i % 3]) != 0) {
                    return die(lineno, "expected 12 values");
                }
            }
            loadid_can_frame_t fr[LOADID_JR3_NUM_GROUPS];
            int rc = loadid_jr3_encode(&cfg, (const double(*)[3])v, (uint8_t)a, (unsigned)fault,
                                       t_us, fr);
            if (rc < 0) {
                return die(lineno, loadid_jr3_strerror(rc));
            }
            for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
                if ((rc = print_frame(&fr[g])) != 0) {
                    return die(lineno, loadid_candump_strerror(rc));
                }
            }
        } else if (cmd == 'F') {
            double fs[3];
            for (int k = 0; k < 3; ++k) {
                if (next_double(&p, &fs[k]) != 0) {
                    return die(lineno, "expected 3 full scales");
                }
            }
            loadid_can_frame_t f;
            int rc = loadid_jr3_encode_full_scale(cfg.base_id, (int)a, fs, t_us, &f, NULL);
            if (rc < 0) {
                return die(lineno, loadid_jr3_strerror(rc));
            }
            if ((rc = print_frame(&f)) != 0) {
                return die(lineno, loadid_candump_strerror(rc));
            }
        } else {
            return die(lineno, "expected S or F");
        }
    }
    if (ferror(stdin)) {
        return die(lineno, "read error");
    }
    return fflush(stdout) == 0 ? 0 : 1;
}
