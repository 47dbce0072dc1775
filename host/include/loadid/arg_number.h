/*
 * Whole decimal numbers from the command line (--publish-every,
 * --can-file-epoch): the whole text or nothing, so "10ms", "", "1e3" or a
 * value past the range is refused instead of read as a prefix or 0.
 */
#ifndef LOADID_ARG_NUMBER_H
#define LOADID_ARG_NUMBER_H

#ifdef __cplusplus
extern "C" {
#endif

/* *out = text as a base-10 integer in [lo, hi]. Returns 0, or -EINVAL
 * (empty, other characters, outside [lo, hi] or long long; *out unchanged). */
int loadid_arg_integer(const char *text, long long lo, long long hi, long long *out);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_ARG_NUMBER_H */
