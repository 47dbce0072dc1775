/*
 * liballoc_count.so: an LD_PRELOAD library that counts the heap
 * allocations of a process, in all its threads, inside its event loop
 * (tests/python/test_live_no_alloc.py runs loadidd under it).
 *
 * Interposed: malloc, calloc, realloc, free (of a non-NULL pointer),
 * posix_memalign, aligned_alloc, memalign, valloc, pvalloc; each forwards to
 * glibc's __libc_* entry points, so no dlsym is needed and nothing
 * allocates while the interposer bootstraps. glibc routes its own internal
 * allocations (strdup, fopen, asprintf, ...) through these symbols too, and
 * C++'s operator new ends in malloc.
 *
 * The loop's window is marked by epoll_wait, also interposed: it opens at
 * the first call of epoll_wait (start-up is over: the daemon waits for its
 * first event) and closes when the last call returns (what follows is the
 * shutdown, and the handling of the events of that last wait: SIGTERM).
 * Allocations are kept in a pending count that each later entry into
 * epoll_wait commits to the loop's count, so allocations after the last
 * epoll_wait are reported as "shutdown" instead.
 *
 * At exit the counts and the allocating call sites (a short backtrace per
 * distinct site, resolved with dladdr to object+offset and symbol) are
 * written to the file named by LOADID_ALLOC_REPORT (nothing when unset):
 *   loop_allocations N
 *   shutdown_allocations N
 *   epoll_waits N
 *   site loop N shutdown M: FRAME; FRAME; ...   (FRAME: object+offset(symbol))
 * Optional: LOADID_ALLOC_START_AFTER=K opens the window at the K-th
 * epoll_wait instead of the first (not used by the test).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <execinfo.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <unistd.h>

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);

enum { SITE_MAX = 64, SITE_DEPTH = 6, SKIP = 2 /* backtrace itself, the hook */ };

typedef struct {
    void *pc[SITE_DEPTH];
    int depth;
    long count;
    long committed; /* of count, those inside the loop's window */
} site_t;

static volatile int window_open; /* between the first epoll_wait and exit */
static long pending, loop_count, waits, start_after = 1;
static site_t sites[SITE_MAX];
static int nsites;
static volatile char lock;
static __thread int in_hook;
static int (*real_epoll_wait)(int, struct epoll_event *, int, int);

static void site_note(void) {
    void *pc[SITE_DEPTH + SKIP];
    in_hook = 1;
    int n = backtrace(pc, SITE_DEPTH + SKIP); /* primed in the constructor */
    in_hook = 0;
    n = n > SKIP ? n - SKIP : 0;
    while (__atomic_test_and_set(&lock, __ATOMIC_ACQUIRE)) {}
    ++pending;
    int i;
    for (i = 0; i < nsites; ++i)
        if (sites[i].depth == n && !memcmp(sites[i].pc, pc + SKIP, sizeof(void *) * (size_t)n))
            break;
    if (i == nsites && nsites < SITE_MAX) {
        memcpy(sites[i].pc, pc + SKIP, sizeof(void *) * (size_t)n);
        sites[i].depth = n;
        ++nsites;
    }
    if (i < nsites) sites[i].count++;
    __atomic_clear(&lock, __ATOMIC_RELEASE);
}

static inline void note(void) {
    if (window_open && !in_hook) site_note();
}

void *malloc(size_t n) {
    note();
    return __libc_malloc(n);
}
void *calloc(size_t n, size_t s) {
    note();
    return __libc_calloc(n, s);
}
void *realloc(void *p, size_t n) {
    note();
    return __libc_realloc(p, n);
}
void free(void *p) {
    if (p) note();
    __libc_free(p);
}
void *aligned_alloc(size_t a, size_t n) {
    note();
    return __libc_memalign(a, n);
}
void *memalign(size_t a, size_t n) {
    note();
    return __libc_memalign(a, n);
}
void *valloc(size_t n) {
    note();
    return __libc_memalign((size_t)sysconf(_SC_PAGESIZE), n);
}
void *pvalloc(size_t n) {
    note();
    const size_t pg = (size_t)sysconf(_SC_PAGESIZE);
    return __libc_memalign(pg, (n + pg - 1) / pg * pg);
}
int posix_memalign(void **out, size_t a, size_t n) {
    note();
    if (a < sizeof(void *) || (a & (a - 1))) return EINVAL;
    *out = __libc_memalign(a, n);
    return *out ? 0 : ENOMEM;
}

/* Entering a wait commits what the previous iteration allocated to the
 * loop's count. */
int epoll_wait(int ep, struct epoll_event *ev, int max, int timeout) {
    while (__atomic_test_and_set(&lock, __ATOMIC_ACQUIRE)) {}
    if (++waits >= start_after) {
        loop_count += pending;
        pending = 0;
        for (int i = 0; i < nsites; ++i) sites[i].committed = sites[i].count;
        window_open = 1;
    }
    __atomic_clear(&lock, __ATOMIC_RELEASE);
    return real_epoll_wait(ep, ev, max, timeout);
}

__attribute__((constructor)) static void init(void) {
    const char *k = getenv("LOADID_ALLOC_START_AFTER");
    if (k && atol(k) > 0) start_after = atol(k);
    real_epoll_wait = (int (*)(int, struct epoll_event *, int, int))dlsym(RTLD_NEXT, "epoll_wait");
    void *pc[4];
    backtrace(pc, 4); /* loads libgcc_s now, not inside the window */
}

static void put(int fd, const char *s) {
    size_t n = strlen(s);
    while (n) {
        ssize_t w = write(fd, s, n);
        if (w <= 0) return;
        s += w, n -= (size_t)w;
    }
}

__attribute__((destructor)) static void report(void) {
    window_open = 0;
    const char *path = getenv("LOADID_ALLOC_REPORT");
    if (!path) return;
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return;
    char line[512];
    snprintf(line, sizeof line, "loop_allocations %ld\nshutdown_allocations %ld\nepoll_waits %ld\n",
             loop_count, pending, waits);
    put(fd, line);
    for (int i = 0; i < nsites; ++i) {
        const site_t *s = &sites[i];
        snprintf(line, sizeof line, "site loop %ld shutdown %ld:", s->committed,
                 s->count - s->committed);
        put(fd, line);
        for (int d = 0; d < s->depth; ++d) {
            Dl_info info;
            const void *pc = s->pc[d];
            if (dladdr(pc, &info) && info.dli_fname) {
                const char *base = strrchr(info.dli_fname, '/');
                snprintf(line, sizeof line, "%s %s+0x%lx(%s)", d ? ";" : "",
                         base ? base + 1 : info.dli_fname,
                         (unsigned long)((uintptr_t)pc - (uintptr_t)info.dli_fbase),
                         info.dli_sname ? info.dli_sname : "?");
            } else {
                snprintf(line, sizeof line, "%s %p", d ? ";" : "", pc);
            }
            put(fd, line);
        }
        put(fd, "\n");
    }
    close(fd);
}
