/*
 * The shortcut RTLS is measured against in bench_core (not part of the
 * product): keep the 11 x 11 Gram matrix of the weighted data D [A y] T and
 * solve its symmetric eigenproblem again after every sample; the TLS
 * estimate is eq. (36) on its smallest eigenvector. It costs an
 * eigen-solve a sample and works on the Gram matrix, whose condition
 * number is the square of the data's, where Brand's update (RTLS) keeps
 * the singular values themselves.
 */
#ifndef LOADID_BENCH_GRAM_TLS_H
#define LOADID_BENCH_GRAM_TLS_H

#include "loadid/estimator.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct loadid_gram_tls loadid_gram_tls_t;

/* 10-parameter model only; the weights and gate settings of cfg (its
 * method is ignored). Returns 0, -EINVAL or -ENOMEM. */
int loadid_gram_tls_create(const loadid_est_config_t *cfg, loadid_gram_tls_t **out);
void loadid_gram_tls_destroy(loadid_gram_tls_t *g);
void loadid_gram_tls_reset(loadid_gram_tls_t *g);
/* A: 6 x 10 row-major, y: 6. */
void loadid_gram_tls_update(loadid_gram_tls_t *g, const loadid_real_t *A, const loadid_real_t *y);
/* phi (10) and the same figures as loadid_est_estimate's gate (condition
 * number, noise ratio); returns 0 or a LOADID_E_* code. */
int loadid_gram_tls_estimate(const loadid_gram_tls_t *g, loadid_real_t *phi,
                             loadid_est_info_t *info);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_BENCH_GRAM_TLS_H */
