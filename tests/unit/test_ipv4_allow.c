/*
 * Unit tests of loadid/ipv4_allow.h, the matching behind
 * lcm.command_sources: addresses and CIDR blocks parsed from text, and
 * source addresses matched against them. The expected blocks are written
 * out in hex by hand; the matching is cross-checked against an
 * independent rule (the first n bits of the two addresses compared one by
 * one) over random addresses and prefixes.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "loadid/ipv4_allow.h"

static void parses_addresses_and_blocks(void **state) {
    (void)state;
    static const struct {
        const char *text;
        uint32_t net, mask;
    } ok[] = {
        {"127.0.0.1", 0x7F000001u, 0xFFFFFFFFu},
        {"192.168.10.7/32", 0xC0A80A07u, 0xFFFFFFFFu},
        {"10.0.0.0/8", 0x0A000000u, 0xFF000000u},
        {"172.16.0.0/12", 0xAC100000u, 0xFFF00000u},
        {"192.168.1.128/25", 0xC0A80180u, 0xFFFFFF80u},
        {"0.0.0.0/0", 0u, 0u},
        {"255.255.255.255", 0xFFFFFFFFu, 0xFFFFFFFFu},
    };
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; ++i) {
        loadid_ipv4_net_t n = {1, 1};
        if (loadid_ipv4_net_parse(ok[i].text, &n) != 0) fail_msg("refused %s", ok[i].text);
        assert_int_equal(n.net, ok[i].net);
        assert_int_equal(n.mask, ok[i].mask);
        char buf[20];
        /* Formatting gives the text back (a /32 as the bare address). */
        const char *want = strcmp(ok[i].text, "192.168.10.7/32") == 0 ? "192.168.10.7" : ok[i].text;
        assert_string_equal(loadid_ipv4_net_format(&n, buf, sizeof buf), want);
    }
}

static void refuses_malformed_text(void **state) {
    (void)state;
    static const char *const bad[] = {
        "",
        "/8",
        "10.0.0",
        "10.0.0.0.1",
        "10.0.0.256",
        "10.0.0.1/",
        "10.0.0.1/33",
        "10.0.0.1/-1",
        "10.0.0.1/+8",
        "10.0.0.1/ 8",
        "10.0.0.1/8x",
        "10.0.0.1/008",
        "10.0.0.1 ",
        " 10.0.0.1",
        "10.0.0.1/8/8",
        "robot-pc",
        "::1",
        "0x7f.0.0.1",
        "1234567890123456789",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        loadid_ipv4_net_t n;
        if (loadid_ipv4_net_parse(bad[i], &n) != -EINVAL) fail_msg("took '%s'", bad[i]);
    }
    loadid_ipv4_net_t n;
    assert_int_equal(loadid_ipv4_net_parse(NULL, &n), -EINVAL);
    /* Bits after the prefix: refused, with the block the prefix means. */
    assert_int_equal(loadid_ipv4_net_parse("10.0.0.5/24", &n), -ERANGE);
    assert_int_equal(n.net, 0x0A000000u);
    assert_int_equal(n.mask, 0xFFFFFF00u);
    assert_int_equal(loadid_ipv4_net_parse("127.0.0.1/0", &n), -ERANGE);
}

static void matches_the_listed_senders_only(void **state) {
    (void)state;
    loadid_ipv4_net_t list[2];
    assert_int_equal(loadid_ipv4_net_parse("127.0.0.1", &list[0]), 0);
    assert_int_equal(loadid_ipv4_net_parse("192.168.1.128/25", &list[1]), 0);
    assert_int_equal(loadid_ipv4_allow_match(list, 2, 0x7F000001u), 1); /* 127.0.0.1 */
    assert_int_equal(loadid_ipv4_allow_match(list, 2, 0x7F000002u), 0); /* 127.0.0.2 */
    assert_int_equal(loadid_ipv4_allow_match(list, 2, 0xC0A80180u), 1); /* .128: first */
    assert_int_equal(loadid_ipv4_allow_match(list, 2, 0xC0A801FFu), 1); /* .255: last */
    assert_int_equal(loadid_ipv4_allow_match(list, 2, 0xC0A8017Fu), 0); /* .127: below */
    assert_int_equal(loadid_ipv4_allow_match(list, 2, 0xC0A80280u), 0); /* next /24 */
    assert_int_equal(loadid_ipv4_allow_match(list, 1, 0xC0A80180u), 0); /* only the first */
    /* No list: every sender (the default). */
    assert_int_equal(loadid_ipv4_allow_match(NULL, 0, 0x08080808u), 1);
    /* 0.0.0.0/0 in a list: every sender too. */
    assert_int_equal(loadid_ipv4_net_parse("0.0.0.0/0", &list[0]), 0);
    assert_int_equal(loadid_ipv4_allow_match(list, 1, 0xDEADBEEFu), 1);
}

/* splitmix64: the test's own generator. */
static uint64_t mix_state = 12;
static uint64_t next_u64(void) {
    uint64_t z = (mix_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static void matching_agrees_with_comparing_bit_by_bit(void **state) {
    (void)state;
    for (int trial = 0; trial < 100000; ++trial) {
        const uint32_t base = (uint32_t)next_u64();
        const unsigned bits = (unsigned)(next_u64() % 33);
        /* The block as text, its host bits cleared through the text. */
        char text[24];
        uint32_t net = base;
        for (unsigned b = bits; b < 32; ++b) net &= ~(0x80000000u >> b);
        snprintf(text, sizeof text, "%u.%u.%u.%u/%u", net >> 24, (net >> 16) & 255,
                 (net >> 8) & 255, net & 255, bits);
        loadid_ipv4_net_t n;
        assert_int_equal(loadid_ipv4_net_parse(text, &n), 0);
        /* Half the addresses near the block (a few low bits flipped), half anywhere. */
        const uint32_t addr =
            trial % 2 ? net ^ (uint32_t)(next_u64() & 0x3FF) : (uint32_t)next_u64();
        int same = 1;
        for (unsigned b = 0; b < bits; ++b)
            if (((addr ^ net) & (0x80000000u >> b)) != 0) same = 0;
        if (loadid_ipv4_allow_match(&n, 1, addr) != same)
            fail_msg("%s and %08x: expected %d", text, addr, same);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(parses_addresses_and_blocks),
        cmocka_unit_test(refuses_malformed_text),
        cmocka_unit_test(matches_the_listed_senders_only),
        cmocka_unit_test(matching_agrees_with_comparing_bit_by_bit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
