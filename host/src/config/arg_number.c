/* Whole decimal numbers from the command line (arg_number.h). */
#include "loadid/arg_number.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>

int loadid_arg_integer(const char *text, long long lo, long long hi, long long *out) {
    /* strtoll skips leading space and takes a prefix: neither is a number here. */
    if (!text || !out || !*text || isspace((unsigned char)*text)) return -EINVAL;
    char *end;
    errno = 0;
    const long long v = strtoll(text, &end, 10);
    if (errno == ERANGE || *end || v < lo || v > hi) return -EINVAL;
    *out = v;
    return 0;
}
