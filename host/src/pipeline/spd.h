/* Symmetric positive definite systems in double, by Cholesky: the normal
 * equations of the pipeline's batch fits (REFINED, the drift check). */
#ifndef LOADID_PIPELINE_SPD_H
#define LOADID_PIPELINE_SPD_H

/* M = L L^T in place (lower triangle of the row-major n x n M); 0, or -1
 * when M is not positive definite. */
int loadid_chol_factor(double *M, int n);

/* b <- (L L^T)^-1 b for loadid_chol_factor's L. */
void loadid_chol_solve(const double *L, double *b, int n);

/* Solves the n x n symmetric positive definite M x = b in place (M is
 * factored); 0, or -1 when M is not positive definite. */
int loadid_spd_solve(double *M, double *b, int n);

#endif
