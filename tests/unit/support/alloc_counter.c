/* Allocation and lock counting by interposition (alloc_counter.h). */
#define _GNU_SOURCE /* RTLD_NEXT */
#include "alloc_counter.h"

#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <stddef.h>

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);

volatile int alloc_counting;
volatile long alloc_count;
volatile long lock_count;

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

/* Locks: the next definitions (libc's), looked up once at load, before
 * anything is counted (dlsym may allocate). */
typedef int (*mutex_fn)(pthread_mutex_t *);
typedef int (*rwlock_fn)(pthread_rwlock_t *);
static mutex_fn next_mutex_lock, next_mutex_trylock;
static rwlock_fn next_rdlock, next_wrlock, next_tryrdlock, next_trywrlock;

__attribute__((constructor)) static void find_locks(void) {
    next_mutex_lock = (mutex_fn)dlsym(RTLD_NEXT, "pthread_mutex_lock");
    next_mutex_trylock = (mutex_fn)dlsym(RTLD_NEXT, "pthread_mutex_trylock");
    next_rdlock = (rwlock_fn)dlsym(RTLD_NEXT, "pthread_rwlock_rdlock");
    next_wrlock = (rwlock_fn)dlsym(RTLD_NEXT, "pthread_rwlock_wrlock");
    next_tryrdlock = (rwlock_fn)dlsym(RTLD_NEXT, "pthread_rwlock_tryrdlock");
    next_trywrlock = (rwlock_fn)dlsym(RTLD_NEXT, "pthread_rwlock_trywrlock");
}

int pthread_mutex_lock(pthread_mutex_t *m) {
    if (alloc_counting) ++lock_count;
    return next_mutex_lock(m);
}
int pthread_mutex_trylock(pthread_mutex_t *m) {
    if (alloc_counting) ++lock_count;
    return next_mutex_trylock(m);
}
int pthread_rwlock_rdlock(pthread_rwlock_t *l) {
    if (alloc_counting) ++lock_count;
    return next_rdlock(l);
}
int pthread_rwlock_wrlock(pthread_rwlock_t *l) {
    if (alloc_counting) ++lock_count;
    return next_wrlock(l);
}
int pthread_rwlock_tryrdlock(pthread_rwlock_t *l) {
    if (alloc_counting) ++lock_count;
    return next_tryrdlock(l);
}
int pthread_rwlock_trywrlock(pthread_rwlock_t *l) {
    if (alloc_counting) ++lock_count;
    return next_trywrlock(l);
}
