/*
 * loadid core: scalar type, sizes and error codes shared by every module of
 * the estimation core. Plain C, usable from C11 and C++17.
 */
#ifndef LOADID_TYPES_H
#define LOADID_TYPES_H

#ifdef __cplusplus
extern "C" {
#endif

/* The scalar of the whole core. The CMake option LOADID_SCALAR picks it;
 * each core library target defines LOADID_SCALAR_FLOAT publicly (1 or 0). */
#if defined(LOADID_SCALAR_FLOAT) && LOADID_SCALAR_FLOAT
typedef float loadid_real_t;
#else
typedef double loadid_real_t;
#endif

/* Sizes of the paper's model. */
#define LOADID_NROWS 6        /* rows of one regressor: f (3), tau (3) */
#define LOADID_NPHI 10        /* eq. (5): m, m*c (3), I_S (6) */
#define LOADID_NPHI_OFFSET 16 /* [phi; o_f; o_tau]: regressor [A E6] */
#define LOADID_MAX_PARAMS 16

/*
 * Errors. Every function returns 0 (or a non-negative count) on success and
 * a negative code on failure: a negated errno from <errno.h> for argument
 * and resource errors, or one of the private codes below (all below -1000 so
 * they never collide with errno values). loadid_strerror() names each.
 */
enum loadid_error {
    LOADID_E_NONFINITE = -1001,   /* an input holds NaN or Inf; state unchanged */
    LOADID_E_NOT_EXCITED = -1002, /* too few samples or rank-deficient data */
    LOADID_E_NO_SOLUTION = -1003, /* TLS: last component of the TLS vector is 0 (eq. 36) */
    LOADID_E_FULL = -1004,        /* batch estimator: its row store is full */
    LOADID_E_STALE = -1005,       /* joint data too far from the sample time */
    LOADID_E_NO_DATA = -1006,     /* no joint state (or setpoint) received yet */
    LOADID_E_TIME_ORDER = -1007,  /* a time stamp not after the previous one */
    LOADID_E_MODEL = -1008        /* the robot model is not a usable chain */
};

/* Returns a static, human-readable text for any return code of the core
 * (0, a negated errno, or a loadid_error). Never NULL. */
const char *loadid_strerror(int code);

/* Returns 1 when the library was built with float as loadid_real_t, else 0. */
int loadid_scalar_is_float(void);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_TYPES_H */
