/* A test's scratch folder (scratch_dir.h). */
#define _XOPEN_SOURCE 700 /* mkdtemp, nftw */
#include "scratch_dir.h"

#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>

int scratch_dir_make(char *dir, size_t cap, const char *tag) {
    const int n = snprintf(dir, cap, "/tmp/loadid-%s-XXXXXX", tag); /* mkdtemp's template */
    if (n < 0 || (size_t)n >= cap) return -1;
    return mkdtemp(dir) ? 0 : -1;
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
    (void)st, (void)flag, (void)ftw;
    return remove(path);
}

int scratch_dir_remove(const char *dir) {
    return nftw(dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS) == 0 ? 0 : -1;
}
