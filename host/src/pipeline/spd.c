/* Cholesky for the pipeline's normal equations (spd.h). */
#include "spd.h"

#include <math.h>

int loadid_chol_factor(double *M, int n) {
    for (int j = 0; j < n; ++j) {
        double d = M[j * n + j];
        for (int k = 0; k < j; ++k) d -= M[j * n + k] * M[j * n + k];
        if (!(d > 0)) return -1;
        M[j * n + j] = sqrt(d);
        for (int i = j + 1; i < n; ++i) {
            double v = M[i * n + j];
            for (int k = 0; k < j; ++k) v -= M[i * n + k] * M[j * n + k];
            M[i * n + j] = v / M[j * n + j];
        }
    }
    return 0;
}

void loadid_chol_solve(const double *L, double *b, int n) {
    for (int i = 0; i < n; ++i) { /* L z = b, then L^T x = z */
        for (int k = 0; k < i; ++k) b[i] -= L[i * n + k] * b[k];
        b[i] /= L[i * n + i];
    }
    for (int i = n - 1; i >= 0; --i) {
        for (int k = i + 1; k < n; ++k) b[i] -= L[k * n + i] * b[k];
        b[i] /= L[i * n + i];
    }
}

int loadid_spd_solve(double *M, double *b, int n) {
    if (loadid_chol_factor(M, n)) return -1;
    loadid_chol_solve(M, b, n);
    return 0;
}
