/*
 * Unit tests of loadid/candump.h: the candump log format of can-utils.
 *
 * References: lines written out by hand as `candump -l` writes them
 * ("(%010lu.%06lu) %*s " then "%03X#" or "%08X#" and the data in upper-case
 * hex pairs), times to the microsecond as integers, every refusal with its
 * own code, a format -> parse round trip over random frames, and the reader
 * over a temporary file with good, bad, blank and over-long lines.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "loadid/candump.h"

static uint64_t mix_state;
static uint64_t next_u64(void) /* splitmix64 */
{
    uint64_t z = (mix_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static int parse(const char *line, loadid_can_frame_t *f, char ifname[16]) {
    return loadid_candump_parse(line, f, ifname);
}

static void test_parse_design_example(void **state) {
    (void)state;
    loadid_can_frame_t f;
    char ifname[LOADID_CANDUMP_IFNAME_MAX];
    assert_int_equal(parse("(1700000000.123456) vcan0 1A0#0102030405060708\n", &f, ifname), 0);
    assert_true(f.t_us == INT64_C(1700000000123456));
    assert_string_equal(ifname, "vcan0");
    assert_int_equal(f.id, 0x1A0);
    assert_false(f.extended);
    assert_int_equal(f.dlc, 8);
    const uint8_t want[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    assert_memory_equal(f.data, want, 8);
    /* ifname may be NULL. */
    assert_int_equal(parse("(1700000000.123456) vcan0 1A0#01", &f, NULL), 0);
    assert_int_equal(f.dlc, 1);
}

static void test_parse_time_exact(void **state) {
    (void)state;
    loadid_can_frame_t f;
    struct {
        const char *line;
        int64_t t_us;
    } cases[] = {
        /* As a double, 1700000000.000001 * 1e6 is 1700000000000001.0 only by
         * luck of rounding; 1700000000.000003 is not (it gives ...002.75). */
        {"(1700000000.000001) can0 123#", INT64_C(1700000000000001)},
        {"(1700000000.000003) can0 123#", INT64_C(1700000000000003)},
        {"(1700000000.999999) can0 123#", INT64_C(1700000000999999)},
        {"(0000000000.000000) can0 123#", 0},
        {"(0.000001) can0 123#", 1},
        {"(0000000000000000000000000000001.500000) can0 123#", 1500000},
        {"(4102444800.000000) can0 123#", INT64_C(4102444800000000)}, /* 2100 */
        /* The largest time an int64 holds, and one microsecond more. */
        {"(9223372036854.775807) can0 123#", INT64_MAX},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        assert_int_equal(parse(cases[i].line, &f, NULL), 0);
        if (f.t_us != cases[i].t_us) {
            fail_msg("%s: t_us %lld", cases[i].line, (long long)f.t_us);
        }
    }
    const char *bad[] = {
        "(9223372036854.775808) can0 123#",
        "(9223372036855.000000) can0 123#",
        "(99999999999999999999999.000000) can0 123#",
        "(1.00000) can0 123#",   /* 5 fraction digits */
        "(1.0000000) can0 123#", /* 7 */
        "(1.) can0 123#",
        "(.000000) can0 123#",
        "(1) can0 123#",
        "(-1.000000) can0 123#",
        "(+1.000000) can0 123#",
        "( 1.000000) can0 123#",
        "(1 .000000) can0 123#",
        "(1,000000) can0 123#",
        "(1.00000a) can0 123#",
        "(0x1.000000) can0 123#",
        "(1.000000 can0 123#",
        "(1.000000",
        "(",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc = parse(bad[i], &f, NULL);
        if (rc != LOADID_CANDUMP_E_TIMESTAMP) {
            fail_msg("%s: %d, want LOADID_CANDUMP_E_TIMESTAMP", bad[i], rc);
        }
    }
}

static void test_parse_ids(void **state) {
    (void)state;
    loadid_can_frame_t f;
    assert_int_equal(parse("(1.000000) can0 000#", &f, NULL), 0);
    assert_int_equal(f.id, 0);
    assert_false(f.extended);
    assert_int_equal(parse("(1.000000) can0 7FF#", &f, NULL), 0);
    assert_int_equal(f.id, 0x7FF);
    assert_int_equal(parse("(1.000000) can0 7ff#", &f, NULL), 0);
    assert_int_equal(f.id, 0x7FF);
    /* 8 digits: extended, whatever the value. */
    assert_int_equal(parse("(1.000000) can0 000001A0#11", &f, NULL), 0);
    assert_int_equal(f.id, 0x1A0);
    assert_true(f.extended);
    assert_int_equal(parse("(1.000000) can0 1FFFFFFF#", &f, NULL), 0);
    assert_int_equal(f.id, 0x1FFFFFFF);
    assert_true(f.extended);
    assert_int_equal(parse("(1.000000) can0 1abcdef0#", &f, NULL), 0);
    assert_int_equal(f.id, 0x1ABCDEF0);

    const char
        *
            bad[] =
                {
                    "(1.000000) can0 800#", /* above 11 bits */
                    "(1.000000) can0 FFF#",
                    "(1.000000) can0 20000000#",  /* CAN_ERR_FLAG: an error frame */
                    "(1.000000) can0 80000123#",  /* CAN_EFF_FLAG spelled out */
                    "(1.000000) can0 1A#",        /* 2 digits */
                    "(1.000000) can0 1A0B#",      /* 4 */
                    "(1.000000) can0 1234567#",   /* 7 */
                    "(1.000000) can0 123456789#", /* 9 */
                    "(1.000000) can0 #00",
                    "(1.000000) can0 1G0#",
                    "(1.000000) can0 -12#",
                };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc = parse(bad[i], &f, NULL);
        if (rc != LOADID_CANDUMP_E_ID) {
            fail_msg("%s: %d, want LOADID_CANDUMP_E_ID", bad[i], rc);
        }
    }
}

static void test_parse_data(void **state) {
    (void)state;
    loadid_can_frame_t f;
    assert_int_equal(parse("(1.000000) can0 1A0#", &f, NULL), 0);
    assert_int_equal(f.dlc, 0);
    assert_int_equal(parse("(1.000000) can0 1a0#abCDef", &f, NULL), 0);
    assert_int_equal(f.dlc, 3);
    const uint8_t want3[3] = {0xAB, 0xCD, 0xEF};
    assert_memory_equal(f.data, want3, 3);
    /* can-utils' optional dots between bytes. */
    assert_int_equal(parse("(1.000000) can0 1A0#01.02.0304", &f, NULL), 0);
    const uint8_t want4[4] = {1, 2, 3, 4};
    assert_int_equal(f.dlc, 4);
    assert_memory_equal(f.data, want4, 4);
    assert_int_equal(parse("(1.000000) can0 1A0#FFFFFFFFFFFFFFFF", &f, NULL), 0);
    assert_int_equal(f.dlc, 8);

    const char *bad[] = {
        "(1.000000) can0 1A0#1",
        "(1.000000) can0 1A0#123",
        "(1.000000) can0 1A0#0G",
        "(1.000000) can0 1A0#G0",
        "(1.000000) can0 1A0#010203040506070809", /* 9 bytes */
        "(1.000000) can0 1A0#.01",
        "(1.000000) can0 1A0#01..02",
        "(1.000000) can0 1A0#01.",
        "(1.000000) can0 1A0#0.1",
        "(1.000000) can0 1A0#01#02",
        "(1.000000) can0 1A0#01_8", /* can-utils' len8_dlc suffix */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc = parse(bad[i], &f, NULL);
        if (rc != LOADID_CANDUMP_E_DATA) {
            fail_msg("%s: %d, want LOADID_CANDUMP_E_DATA", bad[i], rc);
        }
    }
}

static void test_parse_fd_and_remote(void **state) {
    (void)state;
    loadid_can_frame_t f;
    assert_int_equal(parse("(1.000000) can0 123##1112233", &f, NULL), LOADID_CANDUMP_E_FD);
    assert_int_equal(parse("(1.000000) can0 123##0", &f, NULL), LOADID_CANDUMP_E_FD);
    assert_int_equal(parse("(1.000000) can0 12345678##1", &f, NULL), LOADID_CANDUMP_E_FD);
    assert_int_equal(parse("(1.000000) can0 123###00", &f, NULL), LOADID_CANDUMP_E_FD);
    assert_int_equal(parse("(1.000000) can0 123#R", &f, NULL), LOADID_CANDUMP_E_REMOTE);
    assert_int_equal(parse("(1.000000) can0 123#R4", &f, NULL), LOADID_CANDUMP_E_REMOTE);
    assert_int_equal(parse("(1.000000) can0 123#r", &f, NULL), LOADID_CANDUMP_E_REMOTE);
    assert_int_equal(parse("(1.000000) can0 12345678#R\n", &f, NULL), LOADID_CANDUMP_E_REMOTE);
}

static void test_parse_syntax_and_endings(void **state) {
    (void)state;
    loadid_can_frame_t f;
    char ifname[LOADID_CANDUMP_IFNAME_MAX];
    const char *good[] = {
        "(1.000000) can0 123#00",
        "(1.000000) can0 123#00\n",
        "(1.000000) can0 123#00\r\n",
        "(1.000000) can0 123#00 \t\n",
        "(1.000000) can0 123#00\r",
        "(1.000000)   can0\t123#00", /* candump pads names of several interfaces */
        "(1.000000) can0 123#00  ",
    };
    for (size_t i = 0; i < sizeof good / sizeof good[0]; ++i) {
        int rc = parse(good[i], &f, ifname);
        if (rc != 0) {
            fail_msg("\"%s\": %d (%s)", good[i], rc, loadid_candump_strerror(rc));
        }
        assert_string_equal(ifname, "can0");
        assert_int_equal(f.id, 0x123);
        assert_int_equal(f.dlc, 1);
    }
    const char *bad[] = {
        "",
        "\n",
        "1.000000 can0 123#00",
        " (1.000000) can0 123#00",
        "(1.000000)can0 123#00",
        "(1.000000) can0",
        "(1.000000) can0\n",
        "(1.000000) can0 \n",
        "(1.000000) can0 123",
        "(1.000000) can0 123#00 extra",
        "(1.000000) can0 123#00 R", /* can-utils' direction flag: not written by candump -l */
        "(1.000000) can0 123#00\n\n",
        "(1.000000) can0 123#00\nmore",
        "(1.000000) 123#00",
        "DROPCOUNT: dropped 3 CAN frames on 'can0' socket (total drops 3)",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc = parse(bad[i], &f, ifname);
        if (rc != LOADID_CANDUMP_E_SYNTAX) {
            fail_msg("\"%s\": %d, want LOADID_CANDUMP_E_SYNTAX", bad[i], rc);
        }
    }
    /* Interface names: 15 characters at most, printable. */
    assert_int_equal(parse("(1.000000) abcdefghijklmno 123#", &f, ifname), 0);
    assert_string_equal(ifname, "abcdefghijklmno");
    assert_int_equal(parse("(1.000000) abcdefghijklmnop 123#", &f, ifname),
                     LOADID_CANDUMP_E_IFNAME);
    assert_int_equal(parse("(1.000000) ca\x01n0 123#", &f, ifname), LOADID_CANDUMP_E_IFNAME);
    assert_int_equal(parse("(1.000000) ca\x7fn0 123#", &f, ifname), LOADID_CANDUMP_E_IFNAME);
    assert_int_equal(parse("(1.000000) ca\xc3\xa9 123#", &f, ifname), LOADID_CANDUMP_E_IFNAME);
    assert_int_equal(parse(NULL, &f, ifname), -EINVAL);
    assert_int_equal(parse("(1.000000) can0 123#", NULL, ifname), -EINVAL);
}

static void test_format(void **state) {
    (void)state;
    char buf[128];
    loadid_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = 0x1A0;
    f.dlc = 8;
    for (int i = 0; i < 8; ++i) {
        f.data[i] = (uint8_t)(i + 1);
    }
    f.t_us = INT64_C(1700000000123456);
    const char *want = "(1700000000.123456) vcan0 1A0#0102030405060708\n";
    assert_int_equal(loadid_candump_format(&f, "vcan0", buf, sizeof buf), (int)strlen(want));
    assert_string_equal(buf, want);

    /* Zero padding of the seconds (%010), of the id, upper-case hex. */
    f.t_us = 1;
    f.id = 0xA;
    f.dlc = 2;
    f.data[0] = 0xAB;
    f.data[1] = 0x0C;
    assert_true(loadid_candump_format(&f, "can0", buf, sizeof buf) > 0);
    assert_string_equal(buf, "(0000000000.000001) can0 00A#AB0C\n");
    f.extended = true;
    f.id = 0x1A0;
    f.dlc = 0;
    f.t_us = INT64_MAX;
    assert_true(loadid_candump_format(&f, "can0", buf, sizeof buf) > 0);
    assert_string_equal(buf, "(9223372036854.775807) can0 000001A0#\n");

    /* Exactly fitting, one byte short. */
    f.t_us = 0;
    const char *w2 = "(0000000000.000000) can0 000001A0#\n";
    size_t len = strlen(w2);
    assert_int_equal(loadid_candump_format(&f, "can0", buf, len + 1), (int)len);
    assert_string_equal(buf, w2);
    assert_int_equal(loadid_candump_format(&f, "can0", buf, len), -ENOSPC);
    assert_string_equal(buf, "");

    /* Refused. */
    loadid_can_frame_t g = f;
    g.dlc = 9;
    assert_int_equal(loadid_candump_format(&g, "can0", buf, sizeof buf), -EINVAL);
    g = f;
    g.extended = false;
    g.id = 0x800;
    assert_int_equal(loadid_candump_format(&g, "can0", buf, sizeof buf), -EINVAL);
    g.extended = true;
    g.id = 0x20000000;
    assert_int_equal(loadid_candump_format(&g, "can0", buf, sizeof buf), -EINVAL);
    g = f;
    g.t_us = -1;
    assert_int_equal(loadid_candump_format(&g, "can0", buf, sizeof buf), -EINVAL);
    assert_int_equal(loadid_candump_format(&f, "", buf, sizeof buf), -EINVAL);
    assert_int_equal(loadid_candump_format(&f, "a b", buf, sizeof buf), -EINVAL);
    assert_int_equal(loadid_candump_format(&f, "abcdefghijklmnop", buf, sizeof buf), -EINVAL);
    assert_int_equal(loadid_candump_format(&f, NULL, buf, sizeof buf), -EINVAL);
    assert_int_equal(loadid_candump_format(NULL, "can0", buf, sizeof buf), -EINVAL);
    assert_int_equal(loadid_candump_format(&f, "can0", NULL, 10), -EINVAL);
    assert_int_equal(loadid_candump_format(&f, "can0", buf, 0), -ENOSPC);
}

static void test_round_trip_random(void **state) {
    (void)state;
    mix_state = 7;
    char buf[LOADID_CANDUMP_LINE_MAX];
    char ifname[LOADID_CANDUMP_IFNAME_MAX];
    for (int i = 0; i < 20000; ++i) {
        loadid_can_frame_t f, g;
        memset(&f, 0, sizeof f);
        f.extended = next_u64() & 1;
        f.id = (uint32_t)next_u64() & (f.extended ? LOADID_CAN_EFF_MASK : LOADID_CAN_SFF_MASK);
        f.dlc = (uint8_t)(next_u64() % 9);
        for (int k = 0; k < f.dlc; ++k) {
            f.data[k] = (uint8_t)next_u64();
        }
        f.t_us = (int64_t)(next_u64() >> 1);
        const char *name = (i & 1) ? "vcan0" : "abcdefghijklmno";
        int n = loadid_candump_format(&f, name, buf, sizeof buf);
        assert_true(n > 0 && n < (int)sizeof buf);
        assert_int_equal(loadid_candump_parse(buf, &g, ifname), 0);
        assert_string_equal(ifname, name);
        assert_true(g.t_us == f.t_us);
        assert_int_equal(g.id, f.id);
        assert_int_equal(g.extended, f.extended);
        assert_int_equal(g.dlc, f.dlc);
        assert_memory_equal(g.data, f.data, f.dlc);
    }
}

static void test_reader(void **state) {
    (void)state;
    FILE *fp = tmpfile();
    assert_non_null(fp);
    char long_line[300];
    memset(long_line, 'A', sizeof long_line - 1);
    long_line[sizeof long_line - 1] = '\0';
    /* line 1 good, 2 empty, 3 good CRLF, 4 bad (FD), 5 blanks only,
     * 6 too long, 7 good, 8 with a NUL, 9 good without a final newline. */
    fputs("(1700000000.000001) vcan0 1A0#0102030405060708\n", fp);
    fputs("\n", fp);
    fputs("(1700000000.000002) can1 12345678#FF\r\n", fp);
    fputs("(1700000000.000003) vcan0 123##100\n", fp);
    fputs("  \t\r\n", fp);
    fputs(long_line, fp);
    fputs("\n", fp);
    fputs("(1700000000.000004) vcan0 1A1#\n", fp);
    fputs("(1700000000.000005) vcan0 1A1#00", fp);
    fputc('\0', fp);
    fputs("11\n", fp);
    fputs("(1700000000.000006) vcan0 1A2#AA", fp);
    rewind(fp);

    loadid_candump_reader_t *r = NULL;
    assert_int_equal(loadid_candump_reader_open(fp, &r), 0);
    assert_int_equal(loadid_candump_reader_line(r), 0);
    loadid_can_frame_t f;
    char ifname[LOADID_CANDUMP_IFNAME_MAX];

    assert_int_equal(loadid_candump_read(r, &f, ifname), 1);
    assert_int_equal(loadid_candump_reader_line(r), 1);
    assert_true(f.t_us == INT64_C(1700000000000001));
    assert_int_equal(f.id, 0x1A0);

    assert_int_equal(loadid_candump_read(r, &f, ifname), 1);
    assert_int_equal(loadid_candump_reader_line(r), 3);
    assert_string_equal(ifname, "can1");
    assert_true(f.extended);
    assert_int_equal(f.id, 0x12345678);
    assert_int_equal(f.dlc, 1);

    assert_int_equal(loadid_candump_read(r, &f, ifname), LOADID_CANDUMP_E_FD);
    assert_int_equal(loadid_candump_reader_line(r), 4);

    assert_int_equal(loadid_candump_read(r, &f, ifname), LOADID_CANDUMP_E_LONG_LINE);
    assert_int_equal(loadid_candump_reader_line(r), 6);

    assert_int_equal(loadid_candump_read(r, &f, NULL), 1);
    assert_int_equal(loadid_candump_reader_line(r), 7);
    assert_int_equal(f.id, 0x1A1);
    assert_int_equal(f.dlc, 0);

    assert_int_equal(loadid_candump_read(r, &f, ifname), LOADID_CANDUMP_E_LONG_LINE);
    assert_int_equal(loadid_candump_reader_line(r), 8);

    assert_int_equal(loadid_candump_read(r, &f, ifname), 1);
    assert_int_equal(loadid_candump_reader_line(r), 9);
    assert_true(f.t_us == INT64_C(1700000000000006));
    assert_int_equal(f.data[0], 0xAA);

    assert_int_equal(loadid_candump_read(r, &f, ifname), 0);
    assert_int_equal(loadid_candump_read(r, &f, ifname), 0);
    assert_int_equal(loadid_candump_reader_line(r), 9);

    assert_int_equal(loadid_candump_read(NULL, &f, ifname), -EINVAL);
    assert_int_equal(loadid_candump_read(r, NULL, ifname), -EINVAL);
    loadid_candump_reader_close(r);
    loadid_candump_reader_close(NULL);
    fclose(fp);

    /* An empty file. */
    fp = tmpfile();
    assert_non_null(fp);
    assert_int_equal(loadid_candump_reader_open(fp, &r), 0);
    assert_int_equal(loadid_candump_read(r, &f, ifname), 0);
    assert_int_equal(loadid_candump_reader_line(r), 0);
    loadid_candump_reader_close(r);
    fclose(fp);

    /* A line of exactly LOADID_CANDUMP_LINE_MAX with its newline is read;
     * one more character is too long. */
    fp = tmpfile();
    assert_non_null(fp);
    char line[LOADID_CANDUMP_LINE_MAX + 8];
    const char *head = "(1.000000) vcan0 123#00";
    for (int extra = 0; extra < 2; ++extra) {
        size_t n = LOADID_CANDUMP_LINE_MAX - 1 + (size_t)extra; /* without '\n' */
        memset(line, ' ', n);
        memcpy(line, head, strlen(head));
        line[n] = '\n';
        line[n + 1] = '\0';
        fputs(line, fp);
    }
    rewind(fp);
    assert_int_equal(loadid_candump_reader_open(fp, &r), 0);
    assert_int_equal(loadid_candump_read(r, &f, ifname), 1);
    assert_int_equal(loadid_candump_read(r, &f, ifname), LOADID_CANDUMP_E_LONG_LINE);
    assert_int_equal(loadid_candump_reader_line(r), 2);
    assert_int_equal(loadid_candump_read(r, &f, ifname), 0);
    loadid_candump_reader_close(r);
    fclose(fp);

    assert_int_equal(loadid_candump_reader_open(NULL, &r), -EINVAL);
    assert_null(r);
    assert_int_equal(loadid_candump_reader_open(stdin, NULL), -EINVAL);
    assert_int_equal(loadid_candump_reader_line(NULL), 0);
}

static void test_strerror(void **state) {
    (void)state;
    const int codes[] = {0,
                         LOADID_CANDUMP_E_SYNTAX,
                         LOADID_CANDUMP_E_TIMESTAMP,
                         LOADID_CANDUMP_E_IFNAME,
                         LOADID_CANDUMP_E_ID,
                         LOADID_CANDUMP_E_DATA,
                         LOADID_CANDUMP_E_FD,
                         LOADID_CANDUMP_E_REMOTE,
                         LOADID_CANDUMP_E_LONG_LINE,
                         -EINVAL,
                         -ENOSPC,
                         -ENOMEM,
                         -EIO};
    const size_t n = sizeof codes / sizeof codes[0];
    for (size_t i = 0; i < n; ++i) {
        const char *a = loadid_candump_strerror(codes[i]);
        assert_non_null(a);
        assert_string_not_equal(a, "unknown error");
        for (size_t j = 0; j < i; ++j) {
            assert_string_not_equal(a, loadid_candump_strerror(codes[j]));
        }
    }
    assert_string_equal(loadid_candump_strerror(-424242), "unknown error");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_design_example),
        cmocka_unit_test(test_parse_time_exact),
        cmocka_unit_test(test_parse_ids),
        cmocka_unit_test(test_parse_data),
        cmocka_unit_test(test_parse_fd_and_remote),
        cmocka_unit_test(test_parse_syntax_and_endings),
        cmocka_unit_test(test_format),
        cmocka_unit_test(test_round_trip_random),
        cmocka_unit_test(test_reader),
        cmocka_unit_test(test_strerror),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
