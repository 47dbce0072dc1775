/*
 * Allocation counting for the unit tests that prove a path allocates
 * nothing: alloc_counter.c interposes malloc, calloc, realloc, free and the
 * aligned allocators, and counts each call made while alloc_counting is
 * set; likewise the pthread mutex and rwlock lock calls (an uncontended
 * lock makes no system call, so seccomp cannot see it). Not for the
 * sanitizer builds, which own malloc.
 */
#ifndef LOADID_TEST_ALLOC_COUNTER_H
#define LOADID_TEST_ALLOC_COUNTER_H

extern volatile int alloc_counting; /* count while non-zero */
extern volatile long alloc_count;   /* allocator calls counted */
extern volatile long lock_count;    /* lock calls counted */

#endif
