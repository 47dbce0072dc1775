/* The daemon's log line (log.h). */
#include "log.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void loadidd_log(const char *fmt, ...) {
    /* The whole line in one write, so that lines of two threads do not
     * interleave; a longer one is cut. */
    char line[8192] = "loadidd: ";
    const size_t prefix = strlen(line);
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line + prefix, sizeof line - prefix - 1, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    size_t len = prefix + (size_t)n;
    if (len > sizeof line - 2) len = sizeof line - 2;
    line[len] = '\n';
    fwrite(line, 1, len + 1, stderr);
}
