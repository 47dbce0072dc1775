/*
 * One space of return codes (loadid/error_text.h): every private code of
 * every module is distinct, lies in its module's range, and
 * loadid_error_text() names it as the module itself does.
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "loadid/candump.h"
#include "loadid/error_text.h"
#include "loadid/jr3.h"
#include "loadid/lcm_eventlog.h"
#include "loadid/lcm_wire.h"
#include "loadid/modbus_ft.h"
#include "loadid/types.h"

typedef struct {
    int code, lo, hi; /* the module's range [lo, hi] (negative) */
    const char *(*own)(int);
    const char *name;
} code_t;

#define C(code, lo, own) \
    { code, lo - 98, lo, own, #code }
static const code_t kCodes[] = {
    C(LOADID_E_NONFINITE, -1001, loadid_strerror),
    C(LOADID_E_NOT_EXCITED, -1001, loadid_strerror),
    C(LOADID_E_NO_SOLUTION, -1001, loadid_strerror),
    C(LOADID_E_FULL, -1001, loadid_strerror),
    C(LOADID_E_STALE, -1001, loadid_strerror),
    C(LOADID_E_NO_DATA, -1001, loadid_strerror),
    C(LOADID_E_TIME_ORDER, -1001, loadid_strerror),
    C(LOADID_E_MODEL, -1001, loadid_strerror),
    C(LOADID_JR3_E_SATURATED, -1101, loadid_jr3_strerror),
    C(LOADID_JR3_E_FAULT, -1101, loadid_jr3_strerror),
    C(LOADID_JR3_E_UNKNOWN_ID, -1101, loadid_jr3_strerror),
    C(LOADID_JR3_E_DLC, -1101, loadid_jr3_strerror),
    C(LOADID_JR3_E_MALFORMED, -1101, loadid_jr3_strerror),
    C(LOADID_JR3_E_RESERVED, -1101, loadid_jr3_strerror),
    C(LOADID_JR3_E_DUPLICATE, -1101, loadid_jr3_strerror),
    C(LOADID_JR3_E_RANGE, -1101, loadid_jr3_strerror),
    C(LOADID_MODBUS_FT_E_SATURATED, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_FAULT, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_STALE, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_MALFORMED, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_TIMEOUT, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_BAD_FRAME, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_EXCEPTION, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_GONE, -1201, loadid_modbus_ft_strerror),
    C(LOADID_MODBUS_FT_E_CLOSED, -1201, loadid_modbus_ft_strerror),
    C(LOADID_EVENTLOG_E_NOT_LOG, -1301, loadid_eventlog_strerror),
    C(LOADID_EVENTLOG_E_SEEK, -1301, loadid_eventlog_strerror),
    C(LOADID_LCM_ESHORT, -1401, loadid_lcm_strerror),
    C(LOADID_LCM_ELONG, -1401, loadid_lcm_strerror),
    C(LOADID_LCM_EFINGERPRINT, -1401, loadid_lcm_strerror),
    C(LOADID_LCM_ECOUNT, -1401, loadid_lcm_strerror),
    C(LOADID_LCM_ESTRING, -1401, loadid_lcm_strerror),
    C(LOADID_LCM_ENOSPC, -1401, loadid_lcm_strerror),
    C(LOADID_LCM_EINVAL, -1401, loadid_lcm_strerror),
    C(LOADID_CANDUMP_E_SYNTAX, -1501, loadid_candump_strerror),
    C(LOADID_CANDUMP_E_TIMESTAMP, -1501, loadid_candump_strerror),
    C(LOADID_CANDUMP_E_IFNAME, -1501, loadid_candump_strerror),
    C(LOADID_CANDUMP_E_ID, -1501, loadid_candump_strerror),
    C(LOADID_CANDUMP_E_DATA, -1501, loadid_candump_strerror),
    C(LOADID_CANDUMP_E_FD, -1501, loadid_candump_strerror),
    C(LOADID_CANDUMP_E_REMOTE, -1501, loadid_candump_strerror),
    C(LOADID_CANDUMP_E_LONG_LINE, -1501, loadid_candump_strerror),
};
#define N (sizeof kCodes / sizeof kCodes[0])

static void codes_are_distinct_and_in_their_ranges(void **state) {
    (void)state;
    for (size_t i = 0; i < N; ++i) {
        if (kCodes[i].code < kCodes[i].lo || kCodes[i].code > kCodes[i].hi)
            fail_msg("%s = %d outside [%d, %d]", kCodes[i].name, kCodes[i].code, kCodes[i].lo,
                     kCodes[i].hi);
        for (size_t j = 0; j < i; ++j)
            if (kCodes[i].code == kCodes[j].code)
                fail_msg("%s and %s are both %d", kCodes[i].name, kCodes[j].name, kCodes[i].code);
    }
}

static void every_code_has_its_modules_text(void **state) {
    (void)state;
    for (size_t i = 0; i < N; ++i) {
        const char *text = loadid_error_text(kCodes[i].code);
        assert_non_null(text);
        assert_string_equal(text, kCodes[i].own(kCodes[i].code));
        assert_null(strstr(text, "unknown"));
    }
}

static void errno_zero_and_unknown(void **state) {
    (void)state;
    assert_string_equal(loadid_error_text(0), "success");
    assert_string_equal(loadid_error_text(-ENODEV), strerror(ENODEV));
    assert_string_equal(loadid_error_text(-EINVAL), strerror(EINVAL));
    assert_string_equal(loadid_error_text(-1099), loadid_strerror(-1099));
    assert_string_equal(loadid_error_text(-1650), "unknown error code");
    assert_string_equal(loadid_error_text(-99999), "unknown error code");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(codes_are_distinct_and_in_their_ranges),
        cmocka_unit_test(every_code_has_its_modules_text),
        cmocka_unit_test(errno_zero_and_unknown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
