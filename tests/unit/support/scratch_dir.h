/*
 * A test's scratch folder in /tmp: made fresh (mkdtemp) at setup, removed
 * with all it holds at teardown.
 */
#ifndef LOADID_TEST_SCRATCH_DIR_H
#define LOADID_TEST_SCRATCH_DIR_H

#include <stddef.h>

/* Makes /tmp/loadid-TAG-<6 random characters> and writes its path into
 * dir (cap bytes). Returns 0, or -1 (too long, or mkdtemp failed). */
int scratch_dir_make(char *dir, size_t cap, const char *tag);

/* Removes dir and everything in it, depth first. Returns 0 or -1. */
int scratch_dir_remove(const char *dir);

#endif /* LOADID_TEST_SCRATCH_DIR_H */
