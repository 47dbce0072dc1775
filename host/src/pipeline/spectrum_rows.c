/* The window's rows, summed in blocks, and their bands of frequency
 * (spectrum_rows.h). */
#include "spectrum_rows.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define ROWS LOADID_NROWS
#define MIN_SAMPLES 100
/* Samples summed into one block before the DFT: the phase moves by
 * 2 pi j BLOCK / K across one at bin j, which puts a share
 * (2 pi j / K)^2 (BLOCK^2 - 1) / 12 of any power into the error: 0.6 % at
 * the last bin of 1500 samples, 2e-5 at the first, where the regressor's
 * power is. */
#define BLOCK 4
#define MAX_VALUES (ROWS * (2 * LOADID_MAX_PARAMS + 1))

static const int kFirstBin[] = {0, 1, 2, 3, 4, 5, 7, 9, 13, 17};
#define N_BANDS ((int)(sizeof kFirstBin / sizeof kFirstBin[0]) - 1)
#define N_BINS 17 /* kFirstBin[N_BANDS] */

struct loadid_spectrum_rows {
    int capacity, n, instruments, nv; /* nv: values a sample has (values()) */
    int64_t count, lost, without_c, t0;
    int blocks, in_block, block_cap;
    double *block_t; /* per block: its samples' mean time after t0 [us] */
    double *block;   /* per block: nv sums, [A y] row by row, then C */
    double *ctot;    /* 6 x n x n: each row's C^T C over the samples (upper) */
    double *dft;     /* N_BINS x 2 (re, im) x nv (transform) */
    int64_t t_last;
    int transformed;
};

int loadid_spectrum_rows_create(int capacity, int n_params, int instruments,
                                loadid_spectrum_rows_t **out) {
    if (!out || capacity < 1 || (n_params != LOADID_NPHI && n_params != LOADID_NPHI_OFFSET))
        return -EINVAL;
    _Static_assert(N_BANDS == LOADID_SPECTRUM_BANDS, "bands of estimator.h");
    _Static_assert(N_BINS == LOADID_SPECTRUM_BINS, "bins of estimator.h");
    loadid_spectrum_rows_t *r = calloc(1, sizeof *r);
    if (!r) return -ENOMEM;
    r->capacity = capacity, r->n = n_params, r->instruments = instruments != 0;
    r->nv = ROWS * (n_params + 1) + (instruments ? ROWS * n_params : 0);
    r->block_cap = capacity / BLOCK + 1;
    r->block_t = malloc((size_t)r->block_cap * sizeof *r->block_t);
    r->block = malloc((size_t)r->block_cap * (size_t)r->nv * sizeof *r->block);
    r->ctot = malloc(ROWS * (size_t)n_params * (size_t)n_params * sizeof *r->ctot);
    r->dft = malloc((size_t)N_BINS * 2 * (size_t)r->nv * sizeof *r->dft);
    if (!r->block_t || !r->block || !r->ctot || !r->dft) {
        loadid_spectrum_rows_destroy(r);
        return -ENOMEM;
    }
    loadid_spectrum_rows_reset(r);
    *out = r;
    return 0;
}

void loadid_spectrum_rows_destroy(loadid_spectrum_rows_t *r) {
    if (!r) return;
    free(r->block_t), free(r->block), free(r->ctot), free(r->dft);
    free(r);
}

void loadid_spectrum_rows_reset(loadid_spectrum_rows_t *r) {
    if (!r) return;
    r->count = r->lost = r->without_c = 0;
    r->blocks = r->in_block = r->transformed = 0;
    memset(r->ctot, 0, ROWS * (size_t)r->n * (size_t)r->n * sizeof *r->ctot);
}

static int finite(const loadid_real_t *x, int n) {
    for (int i = 0; i < n; ++i)
        if (!isfinite((double)x[i])) return 0;
    return 1;
}

void loadid_spectrum_rows_add(loadid_spectrum_rows_t *r, int64_t t_us, const loadid_real_t *A,
                              const loadid_real_t *C, const loadid_real_t y[6]) {
    if (!r || !A || !y) return;
    const int n = r->n, an = ROWS * n;
    if (!finite(A, an) || !finite(y, ROWS)) return; /* no estimator takes it either */
    if (r->count >= r->capacity) {
        r->lost++;
        return;
    }
    if (r->count == 0) r->t0 = t_us;
    r->count++, r->t_last = t_us, r->transformed = 0;
    if (r->in_block == 0) {
        r->block_t[r->blocks] = 0;
        memset(r->block + (size_t)r->blocks * (size_t)r->nv, 0, (size_t)r->nv * sizeof *r->block);
    }
    double *x = r->block + (size_t)r->blocks * (size_t)r->nv;
    r->block_t[r->blocks] += (double)(t_us - r->t0);
    for (int row = 0; row < ROWS; ++row) {
        for (int j = 0; j < n; ++j) x[row * (n + 1) + j] += (double)A[row * n + j];
        x[row * (n + 1) + n] += (double)y[row];
    }
    if (r->instruments) {
        const int have = C && finite(C, an);
        r->without_c += !have;
        if (have) {
            double *xc = x + ROWS * (n + 1);
            for (int i = 0; i < an; ++i) xc[i] += (double)C[i];
            for (int row = 0; row < ROWS; ++row) {
                double *m = r->ctot + (size_t)row * (size_t)(n * n);
                const loadid_real_t *cr = C + row * n;
                for (int b = 0; b < n; ++b) {
                    if (cr[b] == 0) continue; /* the regressor's structural zeros (eq. 6) */
                    for (int a = b; a < n; ++a) m[b * n + a] += (double)cr[a] * (double)cr[b];
                }
            }
        }
    }
    if (++r->in_block == BLOCK) {
        r->block_t[r->blocks++] /= BLOCK;
        r->in_block = 0;
    }
}

int64_t loadid_spectrum_rows_count(const loadid_spectrum_rows_t *r) {
    return r ? r->count : 0;
}

/* X_j += x exp(i j th) for j < N_BINS over the na values of x: out holds
 * per bin na real parts, then na imaginary ones. */
static void add_phased(double *restrict out, const double *restrict x, int na, double th) {
    const double c1 = cos(th), s1 = sin(th);
    double cj = 1, sj = 0; /* exp(i j th) by recurrence */
    for (int j = 0; j < N_BINS; ++j) {
        double *restrict re = out + (size_t)j * 2 * (size_t)na, *restrict im = re + na;
        for (int i = 0; i < na; ++i) re[i] += cj * x[i], im[i] += sj * x[i];
        const double c = cj * c1 - sj * s1;
        sj = sj * c1 + cj * s1, cj = c;
    }
}

int loadid_spectrum_rows_transform(loadid_spectrum_rows_t *r) {
    if (!r) return -EINVAL;
    if (r->lost) return -ENOSPC;
    if (r->count < MIN_SAMPLES || r->t_last <= r->t0) return LOADID_E_NOT_EXCITED;
    const int nv = r->nv;
    const int blocks = r->blocks + (r->in_block > 0);
    const double *last_t = r->block_t + r->blocks;
    /* The values some block has nonzero (the regressor's structural zeros
     * cost nothing below). */
    int active[MAX_VALUES], na = 0;
    for (int i = 0; i < nv; ++i)
        for (int b = 0; b < blocks; ++b)
            if (r->block[(size_t)b * (size_t)nv + (size_t)i] != 0) {
                active[na++] = i;
                break;
            }
    /* X_j = sum_k x_k exp(-2 pi i j (t_k - t_0) / T), T the samples' mean
     * period times their count; a block's sum at its mean time. */
    const double span_us = (double)(r->t_last - r->t0) * (double)r->count / (double)(r->count - 1);
    double *packed = r->dft; /* the active values' first, spread below */
    memset(packed, 0, (size_t)N_BINS * 2 * (size_t)nv * sizeof *packed);
    for (int b = 0; b < blocks; ++b) {
        const double *x = r->block + (size_t)b * (size_t)nv;
        double xa[MAX_VALUES];
        for (int i = 0; i < na; ++i) xa[i] = x[active[i]];
        const double t = b < r->blocks ? r->block_t[b] : *last_t / r->in_block;
        add_phased(packed, xa, na, -6.283185307179586 * t / span_us);
    }
    /* Spread in place from the last bin down: each packed block lies at or
     * before its full one, and after the packed ones still to spread. */
    for (int q = N_BINS * 2 - 1; q >= 0; --q) {
        double tmp[MAX_VALUES];
        memcpy(tmp, packed + (size_t)q * (size_t)na, (size_t)na * sizeof *tmp);
        double *to = r->dft + (size_t)q * (size_t)nv;
        memset(to, 0, (size_t)nv * sizeof *to);
        for (int i = 0; i < na; ++i) to[active[i]] = tmp[i];
    }
    r->transformed = 1;
    return 0;
}

/* out += w d_row^2 Re(X^H X) of the values first.. (stride per row, m per
 * row) over rows row0..row0+2 at bin j. */
static void add_gram(const loadid_spectrum_rows_t *r, int j, int first, int stride, int m, int row0,
                     const double d[ROWS], double w, double *out) {
    const int nv = r->nv;
    const double *re = r->dft + (size_t)j * 2 * (size_t)nv, *im = re + nv;
    for (int row = row0; row < row0 + 3; ++row) {
        const double *xr = re + first + row * stride, *xi = im + first + row * stride;
        const double wr = w * d[row] * d[row];
        for (int b = 0; b < m; ++b)
            for (int a = 0; a < m; ++a) out[b * m + a] += wr * (xr[a] * xr[b] + xi[a] * xi[b]);
    }
}

/* out's rows apart (estimator.h): each bin's weighted rows. */
static void rows_apart(const loadid_spectrum_rows_t *r, const double d[ROWS],
                       loadid_spectrum_t *out) {
    const int n = r->n, n1 = n + 1, nv = r->nv;
    const double K = (double)r->count;
    for (int j = 0; j < N_BINS; ++j) {
        const double w = sqrt((j == 0 ? 1.0 : 2.0) / K);
        for (int part = 0; part < 2; ++part) {
            const double *x = r->dft + ((size_t)j * 2 + (size_t)part) * (size_t)nv;
            for (int row = 0; row < ROWS; ++row) {
                for (int i = 0; i < n1; ++i)
                    out->row_dft[j][part][row * n1 + i] = w * d[row] * x[row * n1 + i];
                if (out->has_iv)
                    for (int i = 0; i < n; ++i)
                        out->iv_dft[j][part][row * n + i] = w * d[row] * x[ROWS * n1 + row * n + i];
            }
        }
    }
    out->has_rows = 1;
}

int loadid_spectrum_rows_bands(const loadid_spectrum_rows_t *r, const loadid_real_t row_sigma[6],
                               loadid_spectrum_t *out) {
    if (!r || !row_sigma || !out || !r->transformed) return -EINVAL;
    double d[ROWS];
    for (int i = 0; i < ROWS; ++i) {
        if (!(row_sigma[i] > 0) || !isfinite((double)row_sigma[i])) return -EINVAL;
        d[i] = 1.0 / (double)row_sigma[i];
    }
    const int n = r->n, n1 = n + 1;
    memset(out, 0, sizeof *out);
    out->n_bands = N_BANDS;
    memcpy(out->first_bin, kFirstBin, sizeof kFirstBin);
    out->samples = r->count;
    out->has_iv = r->instruments && r->without_c == 0;
    const double K = (double)r->count;
    for (int b = 0; b < N_BANDS; ++b)
        for (int j = kFirstBin[b]; j < kFirstBin[b + 1]; ++j) {
            const double w = (j == 0 ? 1.0 : 2.0) / K; /* the bin and its mirror */
            for (int g = 0; g < 2; ++g) {
                add_gram(r, j, 0, n1, n1, 3 * g, d, w, out->gram[b][g]);
                if (out->has_iv) add_gram(r, j, ROWS * n1, n, n, 3 * g, d, w, out->iv_gram[b][g]);
            }
        }
    rows_apart(r, d, out);
    if (!out->has_iv) return 0;
    for (int row = 0; row < ROWS; ++row) { /* C^T W C of each row group, both triangles */
        const double *m = r->ctot + (size_t)row * (size_t)(n * n);
        double *to = out->iv_total[row / 3];
        for (int b = 0; b < n; ++b)
            for (int a = b; a < n; ++a) {
                const double v = d[row] * d[row] * m[b * n + a];
                to[b * n + a] += v;
                if (a != b) to[a * n + b] += v;
            }
    }
    return 0;
}
