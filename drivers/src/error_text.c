/* loadid_error_text: one text for every return code (error_text.h). */
#include "loadid/error_text.h"

#include <string.h>

#include "loadid/candump.h"
#include "loadid/jr3.h"
#include "loadid/lcm_eventlog.h"
#include "loadid/lcm_wire.h"
#include "loadid/modbus_ft.h"
#include "loadid/types.h"

const char *loadid_error_text(int code) {
    if (code == 0) return "success";
    if (code > 0) return "not an error (a count or a notice)";
    if (code > -1000) return strerror(-code);
    switch (-code / 100) {
        case 10:
            return loadid_strerror(code);
        case 11:
            return loadid_jr3_strerror(code);
        case 12:
            return loadid_modbus_ft_strerror(code);
        case 13:
            return loadid_eventlog_strerror(code);
        case 14:
            return loadid_lcm_strerror(code);
        case 15:
            return loadid_candump_strerror(code);
        default:
            return "unknown error code";
    }
}
