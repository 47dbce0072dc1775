/*
 * Allocation counting for the unit tests that prove a path allocates
 * nothing: alloc_counter.c interposes malloc, calloc, realloc, free and the
 * aligned allocators, and counts each call made while alloc_counting is
 * set. Not for the sanitizer builds, which own malloc.
 */
#ifndef LOADID_TEST_ALLOC_COUNTER_H
#define LOADID_TEST_ALLOC_COUNTER_H

extern volatile int alloc_counting; /* count while non-zero */
extern volatile long alloc_count;   /* calls counted */

#endif
