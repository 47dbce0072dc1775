/* Allocation counting by interposition (alloc_counter.h). */
#include "alloc_counter.h"

#include <errno.h>
#include <stddef.h>

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);

volatile int alloc_counting;
volatile long alloc_count;

void *malloc(size_t n) {
    if (alloc_counting) ++alloc_count;
    return __libc_malloc(n);
}
void *calloc(size_t n, size_t s) {
    if (alloc_counting) ++alloc_count;
    return __libc_calloc(n, s);
}
void *realloc(void *p, size_t n) {
    if (alloc_counting) ++alloc_count;
    return __libc_realloc(p, n);
}
void free(void *p) {
    if (alloc_counting && p) ++alloc_count;
    __libc_free(p);
}
void *aligned_alloc(size_t a, size_t n) {
    if (alloc_counting) ++alloc_count;
    return __libc_memalign(a, n);
}
void *memalign(size_t a, size_t n) {
    if (alloc_counting) ++alloc_count;
    return __libc_memalign(a, n);
}
int posix_memalign(void **out, size_t a, size_t n) {
    if (alloc_counting) ++alloc_count;
    *out = __libc_memalign(a, n);
    return *out ? 0 : ENOMEM;
}
