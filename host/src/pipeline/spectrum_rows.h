/* The window's rows as an estimator was fed them, summed in blocks of 4
 * samples, for the final estimate's uncertainty by band of frequency
 * (loadid_spectrum_t, estimator.h): the backlash's and the joint filter's
 * misfit fills the residual at tens of Hz, where the regressor has no
 * power. Storage is allocated at create; add() never allocates. */
#ifndef LOADID_PIPELINE_SPECTRUM_ROWS_H
#define LOADID_PIPELINE_SPECTRUM_ROWS_H

#include <stdint.h>

#include "loadid/estimator.h"

typedef struct loadid_spectrum_rows loadid_spectrum_rows_t;

/* Room for capacity samples of n_params columns (10 or 16), with the
 * instruments' rows too when instruments. 0, -EINVAL or -ENOMEM. */
int loadid_spectrum_rows_create(int capacity, int n_params, int instruments,
                                loadid_spectrum_rows_t **out);
void loadid_spectrum_rows_destroy(loadid_spectrum_rows_t *r);
void loadid_spectrum_rows_reset(loadid_spectrum_rows_t *r);

/* One sample at t_us: A (6 x n_params row-major), C (the instruments',
 * NULL when the sample has none), y (6). A sample past the capacity is
 * counted as lost; so is one that is not finite (no estimator takes it). */
void loadid_spectrum_rows_add(loadid_spectrum_rows_t *r, int64_t t_us, const loadid_real_t *A,
                              const loadid_real_t *C, const loadid_real_t y[6]);

/* The DFT of the rows kept at bins 0..16 of the window's span (at DONE,
 * once; about 2 M multiply-adds for 1500 samples of 10 parameters). 0; -EINVAL;
 * -ENOSPC when samples were lost (the bands would not be the estimator's
 * data); LOADID_E_NOT_EXCITED with fewer than 100 samples. */
int loadid_spectrum_rows_transform(loadid_spectrum_rows_t *r);

/* The bands of the transformed rows weighted by 1 / row_sigma (an
 * estimator's row levels, loadid_est_config): bins 0, 1, 2, 3, 4, 5-6,
 * 7-8, 9-12, 13-16. out->has_iv when every sample had
 * instruments. 0, or -EINVAL (not transformed, a level not positive). */
int loadid_spectrum_rows_bands(const loadid_spectrum_rows_t *r, const loadid_real_t row_sigma[6],
                               loadid_spectrum_t *out);

/* Samples kept. */
int64_t loadid_spectrum_rows_count(const loadid_spectrum_rows_t *r);

#endif
