/*
 * What every harness of tests/fuzz shares: the libFuzzer entry point's
 * prototype, and FUZZ_CHECK, the oracle beyond the sanitizers: a broken
 * promise of a header (a counter invariant, a return code outside the
 * documented set, a round trip that does not give the input back) prints
 * where and aborts, which libFuzzer reports as a crash with its input.
 */
#ifndef LOADID_FUZZ_CHECK_H
#define LOADID_FUZZ_CHECK_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#ifdef __cplusplus
extern "C" {
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#ifdef __cplusplus
}
#endif

#define FUZZ_CHECK(cond)                                                                  \
    do {                                                                                  \
        if (!(cond)) {                                                                    \
            fprintf(stderr, "%s:%d: FUZZ_CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
            abort();                                                                      \
        }                                                                                 \
    } while (0)

#endif /* LOADID_FUZZ_CHECK_H */
