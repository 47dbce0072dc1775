/*
 * Unit tests of loadid/arg_number.h, the whole-number options of loadid
 * and loadidd (--publish-every, --can-file-epoch): what is taken, what is
 * refused, and that a refusal leaves the value alone.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <limits.h>

#include "loadid/arg_number.h"

static void takes_whole_numbers_in_range(void **state) {
    (void)state;
    static const struct {
        const char *text;
        long long lo, hi, want;
    } ok[] = {
        {"1", 1, 1000000, 1},
        {"1000000", 1, 1000000, 1000000},
        {"+25", 1, 1000000, 25},
        {"007", 1, 1000000, 7},
        {"0", 0, LLONG_MAX, 0},
        {"1764547200000000", 0, LLONG_MAX, 1764547200000000LL},
        {"9223372036854775807", 0, LLONG_MAX, LLONG_MAX},
        {"-3", -5, 5, -3},
    };
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; ++i) {
        long long v = -42;
        if (loadid_arg_integer(ok[i].text, ok[i].lo, ok[i].hi, &v) != 0)
            fail_msg("refused %s", ok[i].text);
        assert_true(v == ok[i].want);
    }
}

static void refuses_the_rest_and_keeps_the_value(void **state) {
    (void)state;
    static const struct {
        const char *text;
        long long lo, hi;
    } bad[] = {
        {"", 1, 1000000},
        {"0", 1, 1000000},
        {"1000001", 1, 1000000},
        {"-1", 0, LLONG_MAX},
        {"10ms", 1, 1000000},
        {"1e3", 1, 1000000},
        {"0x10", 1, 1000000},
        {" 5", 1, 1000000},
        {"5 ", 1, 1000000},
        {"\t5", 1, 1000000},
        {"2.5", 1, 1000000},
        {"abc", 0, LLONG_MAX},
        {"+", 0, LLONG_MAX},
        {"-", -5, 5},
        {"9223372036854775808", 0, LLONG_MAX}, /* past long long: ERANGE */
        {"-9223372036854775809", LLONG_MIN, 0},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        long long v = -42;
        if (loadid_arg_integer(bad[i].text, bad[i].lo, bad[i].hi, &v) != -EINVAL)
            fail_msg("took \"%s\"", bad[i].text);
        assert_true(v == -42);
    }
    long long v = -42;
    assert_int_equal(loadid_arg_integer(NULL, 0, 1, &v), -EINVAL);
    assert_int_equal(loadid_arg_integer("1", 0, 1, NULL), -EINVAL);
    assert_true(v == -42);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(takes_whole_numbers_in_range),
        cmocka_unit_test(refuses_the_rest_and_keeps_the_value),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
