/*
 * Writes the binary seeds of tests/fuzz/corpus (and the candump text ones)
 * with the project's own encoders, so that every seed is a valid input of
 * today's formats or a named edge case of them:
 *   fuzz_make_seeds CORPUS_DIR
 * (the target is built on demand: ninja -C build/release fuzz_make_seeds).
 * The YAML and URDF seeds are copies of the repository's files, committed
 * as they are. Deterministic: the same bytes on every run.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "loadid/candump.h"
#include "loadid/jr3.h"
#include "loadid/lcm_wire.h"
#include "loadid/modbus_ft.h"

static const char *root;

/* A growing byte buffer, written out as one seed. */
typedef struct {
    uint8_t b[8192];
    size_t n;
} buf_t;

static void put(buf_t *s, const void *p, size_t n) {
    if (s->n + n > sizeof s->b) {
        fprintf(stderr, "make_seeds: seed too large\n");
        exit(1);
    }
    memcpy(s->b + s->n, p, n);
    s->n += n;
}

static void write_seed(const char *target, const char *name, const buf_t *s) {
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", root, target);
    if (mkdir(path, 0777) != 0 && errno != EEXIST) {
        perror(path);
        exit(1);
    }
    snprintf(path, sizeof path, "%s/%s/%s", root, target, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(s->b, 1, s->n, f) != s->n || fclose(f) != 0) {
        perror(path);
        exit(1);
    }
    printf("%s (%zu bytes)\n", path, s->n);
}

/* ---- jr3: frames as fuzz_jr3.c reads them (id LE16 | bit 15 extended,
 * dlc, 8 data bytes) ---- */

static void put_frame(buf_t *s, const loadid_can_frame_t *f) {
    const uint16_t id = (uint16_t)((f->id & 0x7FFF) | (f->extended ? 0x8000u : 0));
    const uint8_t head[3] = {(uint8_t)id, (uint8_t)(id >> 8), f->dlc};
    put(s, head, 3);
    put(s, f->data, 8);
}

static void put_raw(buf_t *s, uint16_t id, uint8_t dlc, const uint8_t data[8]) {
    const uint8_t head[3] = {(uint8_t)id, (uint8_t)(id >> 8), dlc};
    put(s, head, 3);
    put(s, data, 8);
}

/* A hanging load of 1.2 kg with its COM off the axis, swinging a little. */
static void sample_values(int i, double v[LOADID_JR3_NUM_GROUPS][3]) {
    const double a = 0.3 * sin(0.05 * i);
    const double f[3] = {1.2 * 9.81 * sin(a), 0.4 * cos(a), 1.2 * 9.81 * cos(a)};
    const double m[3] = {0.06 * cos(a), -0.09, 0.01 * sin(a)};
    const double lin[3] = {9.81 * sin(a), 0.02, 9.81 * cos(a)};
    const double ang[3] = {1.5 * cos(0.05 * i), 0.0, -0.7};
    memcpy(v[0], f, sizeof f);
    memcpy(v[1], m, sizeof m);
    memcpy(v[2], lin, sizeof lin);
    memcpy(v[3], ang, sizeof ang);
}

static void put_sample(buf_t *s, const loadid_jr3_config_t *cfg, int i, uint8_t seq,
                       unsigned faults, const int order[4]) {
    double v[LOADID_JR3_NUM_GROUPS][3];
    sample_values(i, v);
    loadid_can_frame_t fr[LOADID_JR3_NUM_GROUPS];
    if (loadid_jr3_encode(cfg, (const double(*)[3])v, seq, faults, 1000 * i, fr) < 0) {
        fprintf(stderr, "make_seeds: jr3 encode failed\n");
        exit(1);
    }
    for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) put_frame(s, &fr[order ? order[g] : g]);
}

static void jr3_seeds(void) {
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    buf_t s = {.n = 0};

    /* Five good samples, then each group's full-scale frame (the periodic
     * repetition of the configured one, then a change of the force group's). */
    for (int i = 0; i < 5; ++i) put_sample(&s, &cfg, i, (uint8_t)i, 0, NULL);
    for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
        loadid_can_frame_t f;
        loadid_jr3_encode_full_scale(cfg.base_id, g, cfg.full_scale[g], 5000, &f, NULL);
        put_frame(&s, &f);
    }
    const double fs100[3] = {100.0, 100.0, 150.0};
    loadid_can_frame_t f;
    loadid_jr3_encode_full_scale(cfg.base_id, 0, fs100, 5000, &f, NULL);
    put_frame(&s, &f);
    put_sample(&s, &cfg, 5, 5, 0, NULL);
    write_seed("jr3", "samples_and_full_scale", &s);

    /* Groups out of order, a sequence gap, the wrap 255 -> 0, a duplicate
     * group (sample abandoned) and a frame after a complete sample. */
    s.n = 0;
    static const int shuffled[4] = {3, 1, 0, 2};
    put_sample(&s, &cfg, 0, 250, 0, shuffled);
    put_sample(&s, &cfg, 1, 253, 0, NULL);
    put_sample(&s, &cfg, 2, 255, 0, NULL);
    put_sample(&s, &cfg, 3, 0, 0, NULL);
    double v[LOADID_JR3_NUM_GROUPS][3];
    sample_values(4, v);
    loadid_can_frame_t fr[LOADID_JR3_NUM_GROUPS];
    loadid_jr3_encode(&cfg, (const double(*)[3])v, 1, 0, 4000, fr);
    put_frame(&s, &fr[0]);
    put_frame(&s, &fr[1]);
    put_frame(&s, &fr[1]); /* duplicate: the sample goes */
    put_frame(&s, &fr[2]);
    put_frame(&s, &fr[3]);
    put_sample(&s, &cfg, 5, 2, 0, NULL);
    put_frame(&s, &fr[0]); /* sequence 1 again after 2: a new, incomplete sample */
    write_seed("jr3", "order_gap_wrap_duplicate", &s);

    /* Saturated (a force beyond full scale), faulty, both. */
    s.n = 0;
    sample_values(0, v);
    v[0][2] = 500.0;
    loadid_jr3_encode(&cfg, (const double(*)[3])v, 10, 0, 0, fr);
    for (int g = 0; g < 4; ++g) put_frame(&s, &fr[g]);
    put_sample(&s, &cfg, 1, 11, LOADID_JR3_ALL_GROUPS, NULL);
    loadid_jr3_encode(&cfg, (const double(*)[3])v, 12, 1u << 3, 2000, fr);
    for (int g = 0; g < 4; ++g) put_frame(&s, &fr[g]);
    put_sample(&s, &cfg, 3, 13, 0, NULL);
    write_seed("jr3", "saturated_faulty", &s);

    /* Bad frames between good ones: DLC 7 and 9, an extended id, ids just
     * outside base..base+4, reserved status bits, malformed full-scale
     * frames (group 4, byte 1 set, a zero full scale), then a reset. */
    s.n = 0;
    put_sample(&s, &cfg, 0, 0, 0, NULL);
    const uint8_t d[8] = {1, 2, 3, 4, 5, 6, 1, 0};
    put_raw(&s, 0x1A0, 7, d);
    put_raw(&s, 0x1A1, 9, d);
    put_raw(&s, 0x8000 | 0x1A0, 8, d);
    put_raw(&s, 0x19F, 8, d);
    put_raw(&s, 0x1A5, 8, d);
    const uint8_t reserved[8] = {1, 2, 3, 4, 5, 6, 1, 0x04};
    put_raw(&s, 0x1A2, 8, reserved);
    const uint8_t fs_group4[8] = {4, 0, 0xD0, 0x07, 0xD0, 0x07, 0xD0, 0x07};
    const uint8_t fs_byte1[8] = {0, 1, 0xD0, 0x07, 0xD0, 0x07, 0xD0, 0x07};
    const uint8_t fs_zero[8] = {1, 0, 0xB0, 0x04, 0x00, 0x00, 0xB0, 0x04};
    put_raw(&s, 0x1A4, 8, fs_group4);
    put_raw(&s, 0x1A4, 8, fs_byte1);
    put_raw(&s, 0x1A4, 8, fs_zero);
    put_sample(&s, &cfg, 1, 1, 0, NULL);
    put_raw(&s, 0xFFFF, 0, d); /* the harness's reset */
    put_sample(&s, &cfg, 2, 2, 0, NULL);
    write_seed("jr3", "bad_frames_reset", &s);
}

/* ---- candump: log lines as candump -l writes them, and edge cases ---- */

static void put_text(buf_t *s, const char *t) {
    put(s, t, strlen(t));
}

static void candump_seeds(void) {
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    buf_t s = {.n = 0};
    for (int i = 0; i < 3; ++i) {
        double v[LOADID_JR3_NUM_GROUPS][3];
        sample_values(i, v);
        loadid_can_frame_t fr[LOADID_JR3_NUM_GROUPS];
        loadid_jr3_encode(&cfg, (const double(*)[3])v, (uint8_t)i, 0, 1700000000123456 + 1000 * i,
                          fr);
        for (int g = 0; g < LOADID_JR3_NUM_GROUPS; ++g) {
            char line[LOADID_CANDUMP_LINE_MAX];
            loadid_candump_format(&fr[g], "vcan0", line, sizeof line);
            put_text(&s, line);
        }
    }
    write_seed("candump", "jr3_samples.log", &s);

    s.n = 0;
    put_text(&s, "(0000000000.000000) can0 123#\n");              /* no data */
    put_text(&s, "(1700000000.000001) can0 1FFFFFFF#DEADBEEF\n"); /* extended */
    put_text(&s, "(1700000000.000002)   vcan10  1A0#01.02.03.04.05.06.07.08\r\n");
    put_text(&s, "\n \t\r\n");                                            /* blank lines */
    put_text(&s, "(1700000000.000003) can0 7FF#0102 \t\n");               /* trailing blanks */
    put_text(&s, "(1700000000.000004) can0 123##1DEAD\n");                /* CAN FD */
    put_text(&s, "(1700000000.000005) can0 123#R\n");                     /* remote */
    put_text(&s, "(1700000000.000006) can0 20000080#0000000000000000\n"); /* error frame */
    put_text(&s, "(9223372036854.775807) can0 000#00\n");                 /* the largest time */
    put_text(&s, "(9223372036854.775808) can0 000#00\n");                 /* one past it */
    put_text(&s, "(1700000000.12345) can0 123#00\n");                     /* 5 fraction digits */
    put_text(&s, "(1700000000.000007) averyveryverylongname 123#00\n");
    put_text(&s, "(1700000000.000008) can0 800#00\n");                 /* 11 bits exceeded */
    put_text(&s, "(1700000000.000009) can0 123#0.1\n");                /* misplaced '.' */
    put_text(&s, "(1700000000.000010) can0 123#010203040506070809\n"); /* 9 bytes */
    put_text(&s, "(1700000000.000011) can0 1A0#");
    for (int i = 0; i < 60; ++i) put_text(&s, "00");                 /* longer than a line may be */
    put_text(&s, "\n(1700000000.000012) can0 1A0#0102030405060708"); /* no final newline */
    write_seed("candump", "edge_cases.log", &s);
}

/* ---- lcm_wire and lcm_udpm: messages from the encoders ---- */

static void lcm_seed(const char *target, const char *name, const uint8_t *msg, int n,
                     const char *channel) {
    if (n <= 0) {
        fprintf(stderr, "make_seeds: LCM encode failed for %s\n", name);
        exit(1);
    }
    buf_t s = {.n = 0};
    if (channel) { /* LCM's short message: "LC02", sequence number, channel, NUL */
        static const uint8_t head[8] = {'L', 'C', '0', '2', 0, 0, 0, 42};
        put(&s, head, sizeof head);
        put(&s, channel, strlen(channel) + 1);
    }
    put(&s, msg, (size_t)n);
    write_seed(target, name, &s);
}

static void lcm_seeds(void) {
    uint8_t b[1024];
    loadid_lcm_joint_state_t js;
    memset(&js, 0, sizeof js);
    js.utime = 1700000000000000;
    js.num_joints = 6;
    for (int i = 0; i < 6; ++i) js.position[i] = js.setpoint[i] = 0.1 * i - 0.25;
    js.setpoint[2] += 1e-4;
    int n = loadid_lcm_encode_joint_state(&js, b, sizeof b);
    lcm_seed("lcm_wire", "joint_state_6", b, n, NULL);
    lcm_seed("lcm_udpm", "joints_datagram", b, n, "LOADID_JOINTS");
    js.num_joints = LOADID_LCM_MAX_JOINTS;
    for (int i = 6; i < LOADID_LCM_MAX_JOINTS; ++i) js.position[i] = js.setpoint[i] = 0.01 * i;
    js.position[3] = NAN;
    n = loadid_lcm_encode_joint_state(&js, b, sizeof b);
    lcm_seed("lcm_wire", "joint_state_16_nan", b, n, NULL);

    loadid_lcm_command_t cmd;
    memset(&cmd, 0, sizeof cmd);
    cmd.utime = 1700000000500000;
    cmd.action = 2; /* START */
    snprintf(cmd.load_name, sizeof cmd.load_name, "o1");
    n = loadid_lcm_encode_command(&cmd, b, sizeof b);
    lcm_seed("lcm_wire", "command_start", b, n, NULL);
    lcm_seed("lcm_udpm", "command_datagram", b, n, "R2_LOADID_COMMAND");
    cmd.action = 1; /* ZERO, the longest name */
    memset(cmd.load_name, 'x', LOADID_LCM_NAME_MAX - 1);
    cmd.load_name[LOADID_LCM_NAME_MAX - 1] = '\0';
    n = loadid_lcm_encode_command(&cmd, b, sizeof b);
    lcm_seed("lcm_wire", "command_zero_long_name", b, n, NULL);

    loadid_lcm_estimate_t est;
    memset(&est, 0, sizeof est);
    est.utime = 1700000001500000;
    est.samples = 1500;
    est.method = 3;
    est.state = 3;
    snprintf(est.load_name, sizeof est.load_name, "o1");
    const double phi[10] = {1.2, 0.06, -0.09, 0.012, 0.01, 0, 0, 0.012, 0.001, 0.008};
    memcpy(est.phi, phi, sizeof phi);
    est.mass = 1.2;
    est.com[0] = 0.05;
    est.condition_number = 42.5;
    est.sigma_min = 0.01;
    est.physically_consistent = 1;
    n = loadid_lcm_encode_estimate(&est, b, sizeof b);
    lcm_seed("lcm_wire", "estimate_rtls", b, n, NULL);

    loadid_lcm_wrench_t w = {1700000000001000, {0.1, -0.2, 11.77}, {0.01, 0.02, -0.03}};
    n = loadid_lcm_encode_wrench(&w, b, sizeof b);
    lcm_seed("lcm_wire", "wrench", b, n, NULL);

    loadid_lcm_status_t st;
    memset(&st, 0, sizeof st);
    st.utime = 1700000002000000;
    st.state = 2;
    st.samples_ok = 1500;
    st.sequence_gaps = 3;
    st.loop_us_p50 = 12.5;
    st.loop_us_p99 = 40.0;
    st.loop_us_max = INFINITY;
    n = loadid_lcm_encode_status(&st, b, sizeof b);
    lcm_seed("lcm_wire", "status_inf", b, n, NULL);

    loadid_lcm_load_model_t lm;
    memset(&lm, 0, sizeof lm);
    lm.utime = 1700000001500000;
    lm.method = 6;
    snprintf(lm.load_name, sizeof lm.load_name, "gripper");
    lm.identified = 7;
    lm.projected = 1;
    memcpy(lm.phi, phi, sizeof phi);
    for (int i = 0; i < 10; ++i) lm.phi_std[i] = 1e-3 * (i + 1);
    lm.mass = 1.2;
    n = loadid_lcm_encode_load_model(&lm, b, sizeof b);
    lcm_seed("lcm_wire", "load_model_refined", b, n, NULL);

    /* udpm: a fragment of a long message, and two URLs (the same bytes are
     * tried as an lcm.url). */
    static const uint8_t frag[24] = {'L', 'C', '0', '3', 0, 0, 0,   7,   0, 0, 0x10, 0,
                                     0,   0,   0,   0,   0, 2, 'C', 'H', 0, 1, 2,    3};
    lcm_seed("lcm_udpm", "fragment", frag, sizeof frag, NULL);
    static const char url1[] = "udpm://239.255.76.67:7667?ttl=0";
    static const char url2[] = "udpm://224.0.0.251:1?recv_buf_size=2097152&ttl=255&other=1";
    lcm_seed("lcm_udpm", "url_default", (const uint8_t *)url1, (int)strlen(url1), NULL);
    lcm_seed("lcm_udpm", "url_options", (const uint8_t *)url2, (int)strlen(url2), NULL);
}

/* ---- modbus_ft: operations as fuzz_modbus_ft.c reads them ---- */

static void put_regs(buf_t *s, uint8_t op, const uint16_t *r, int n) {
    put(s, &op, 1);
    for (int k = 0; k < n; ++k) {
        const uint8_t be[2] = {(uint8_t)(r[k] >> 8), (uint8_t)r[k]};
        put(s, be, 2);
    }
}

static void modbus_seeds(void) {
    const double fsf[3] = {200, 200, 200}, fsm[3] = {12, 12, 12};
    buf_t s = {.n = 0};
    uint16_t h[LOADID_MODBUS_FT_HOLDING_COUNT];
    const double sf[3] = {150, 150, 300}, sm[3] = {10, 10, 12.34};
    loadid_modbus_ft_encode_full_scale(sf, sm, h);
    put_regs(&s, 2, h, LOADID_MODBUS_FT_HOLDING_COUNT); /* read at open */
    uint16_t r[LOADID_MODBUS_FT_INPUT_COUNT];
    for (int i = 0; i < 6; ++i) {
        const double a = 0.3 * sin(0.05 * i);
        const double f[3] = {11.77 * sin(a), 0.4, 11.77 * cos(a)};
        const double m[3] = {0.06 * cos(a), -0.09, 0.01};
        loadid_modbus_ft_encode(sf, sm, f, m, false, (uint16_t)(65533 + i), r);
        put_regs(&s, 0, r, LOADID_MODBUS_FT_INPUT_COUNT);
        if (i == 2) put_regs(&s, 1, r, LOADID_MODBUS_FT_INPUT_COUNT); /* stale */
    }
    write_seed("modbus_ft", "samples_counter_wrap", &s);

    s.n = 0;
    const double big[3] = {500, 0, -500}, zero[3] = {0, 0, 0};
    loadid_modbus_ft_encode(fsf, fsm, big, zero, false, 1, r);
    put_regs(&s, 0, r, LOADID_MODBUS_FT_INPUT_COUNT); /* saturated */
    loadid_modbus_ft_encode(fsf, fsm, zero, zero, true, 2, r);
    put_regs(&s, 0, r, LOADID_MODBUS_FT_INPUT_COUNT); /* fault */
    loadid_modbus_ft_encode(fsf, fsm, zero, zero, false, 9, r);
    put_regs(&s, 0, r, LOADID_MODBUS_FT_INPUT_COUNT); /* a gap of 6 */
    r[LOADID_MODBUS_FT_REG_STATUS] = 0x0100;          /* reserved bits */
    put_regs(&s, 0, r, LOADID_MODBUS_FT_INPUT_COUNT);
    const uint16_t hz[6] = {2000, 2000, 0, 1200, 1200, 1200}; /* a zero full scale */
    put_regs(&s, 2, hz, LOADID_MODBUS_FT_HOLDING_COUNT);
    const uint8_t reopen = 3;
    put(&s, &reopen, 1);
    loadid_modbus_ft_encode(fsf, fsm, zero, zero, false, 9, r);
    put_regs(&s, 0, r, LOADID_MODBUS_FT_INPUT_COUNT); /* same counter after a reopen: new */
    write_seed("modbus_ft", "saturated_fault_gap_reopen", &s);
}

int main(int argc, char **argv) {
    if (argc == 2 && (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0)) {
        printf(
            "usage: fuzz_make_seeds CORPUS_DIR\n"
            "Writes the binary seeds of the fuzz corpora (JR3, candump, LCM, Modbus) into\n"
            "CORPUS_DIR/<target>/, byte-identical on every run.\n");
        return 0;
    }
    if (argc != 2) {
        fprintf(stderr, "usage: fuzz_make_seeds CORPUS_DIR\n");
        return 2;
    }
    root = argv[1];
    if (mkdir(root, 0777) != 0 && errno != EEXIST) {
        perror(root);
        return 1;
    }
    jr3_seeds();
    candump_seeds();
    lcm_seeds();
    modbus_seeds();
    return 0;
}
