// One instantiation of each decomposition (linalg.hpp).
#include "linalg.hpp"

namespace loadid {
namespace linalg {

void svd_left(const Work &M, Square &U, Values &s) {
    const Eigen::JacobiSVD<Work> svd(M, Eigen::ComputeFullU);
    U = svd.matrixU();
    s = svd.singularValues();
}

void sym_eigenvalues(const Square &G, Values &lambda) {
    const Eigen::SelfAdjointEigenSolver<Square> es(G, Eigen::EigenvaluesOnly);
    lambda = es.eigenvalues();
}

void householder_q(const Square &A, Square &Q, Values &r_diag) {
    const Eigen::HouseholderQR<Square> qr(A);
    Q = qr.householderQ();
    r_diag = qr.matrixQR().diagonal();
}

void colpiv_qr(const Tall &H, Square &Q, Tall &R, Eigen::Matrix<int, LOADID_NROWS, 1> &perm) {
    const Eigen::ColPivHouseholderQR<Tall> qr(H);
    Q = qr.householderQ();
    R = qr.matrixQR().triangularView<Eigen::Upper>();
    perm = qr.colsPermutation().indices();
}

}  // namespace linalg
}  // namespace loadid
