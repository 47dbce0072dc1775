// Covariance of an estimate from the information matrix (uncertainty.hpp).
// Computed in double whatever the core's scalar: the information matrix
// squares the condition number.
#include "uncertainty.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace loadid {
namespace {

// The parameters, the drift's six columns when it is fitted, and y.
constexpr int kMax = LOADID_MAX_PARAMS + LOADID_NROWS + 1;
using Md = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMax, kMax>;
using Vd = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMax, 1>;

// The symmetric matrix from its lower triangle.
Md symmetric(const Real *lower, int n1) {
    Md g(n1, n1);
    for (int j = 0; j < n1; ++j)
        for (int i = j; i < n1; ++i) g(i, j) = g(j, i) = static_cast<double>(lower[j * n1 + i]);
    return g;
}

// Inverse of a symmetric positive definite S through its eigen-decomposition;
// false when an eigenvalue is not clearly positive.
bool spd_inverse(const Md &S, Md &inv) {
    Eigen::SelfAdjointEigenSolver<Md> es(S);
    const Vd l = es.eigenvalues();
    const double lmax = l.cwiseAbs().maxCoeff();
    if (!(l.minCoeff() > lmax * 1e-14 * S.rows())) return false;
    inv = es.eigenvectors() * l.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    return true;
}

// A full matrix from a column-major block of n x n values (the core's
// scalar or double).
template <class T>
Md full(const T *m, int n) {
    return Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>>(m, n, n)
        .template cast<double>();
}

// Row r's m values at r * stride (the spectrum's rows apart, estimator.h).
using RowsMap = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic,
                                               Eigen::RowMajor, LOADID_NROWS, kMax + 1>,
                           0, Eigen::OuterStride<>>;
RowsMap rows_of(const double *x, int rows, int m, int stride) {
    return RowsMap(x, rows, m, Eigen::OuterStride<>(stride));
}

// The wrench noise measured apart, row group grp's, in units of the row
// weights D (1 when the weights are that noise); 0 without a measurement.
double measured_noise(const CovInput &in, int grp) {
    if (!in.noise_sigma || !in.row_weight) return 0;
    const double d =
        static_cast<double>(in.noise_sigma[grp]) * static_cast<double>(in.row_weight[3 * grp]);
    return d > 0 && std::isfinite(d) ? d : 0;
}

// J Sigma_y0 J^T, J = inv sum_k A_k^T W: the estimate's covariance from the
// zeroing offset's error (uncertainty.hpp); zero without one.
Md offset_share(const CovInput &in, const Vd &t, const Md &inv) {
    const int n = in.n;
    Md out = Md::Zero(n, n);
    if (!in.offset_cov || !in.row_sum || !in.row_weight) return out;
    Md cov0(LOADID_NROWS, LOADID_NROWS), s(n, LOADID_NROWS);
    for (int r = 0; r < LOADID_NROWS; ++r)
        for (int c = 0; c < LOADID_NROWS; ++c)
            cov0(r, c) = static_cast<double>(in.offset_cov[LOADID_NROWS * r + c]);
    if (!(cov0.cwiseAbs().maxCoeff() > 0)) return out;
    // sum_k A_k^T D^2 = T1^-1 (sum_k D A_k T1)^T D.
    for (int j = 0; j < n; ++j)
        for (int r = 0; r < LOADID_NROWS; ++r)
            s(j, r) = static_cast<double>(in.row_sum[LOADID_NROWS * j + r]) / t(j) *
                      static_cast<double>(in.row_weight[r]);
    const Md jac = inv * s;
    return jac * cov0 * jac.transpose();
}

// b b^T, the bias the columns' noise may leave in phi (uncertainty.hpp).
// h: sum A^T W A (n x n, without the column weights). Columns counted
// exact (a joint filter's) pull by h^-1 C phi, but for least squares the
// share of their noise that is a measurement's (col_measured) counts as a
// noisy column's. For least squares
// (least_squares) the noisy ones too: their error is a measurement's, so
// E[h] = H0 + C and phi_LS = (H0 + C)^-1 H0 phi, i.e. phi - phi_LS =
// (h - C)^-1 C phi_LS. The column weights give C in units of the row
// weights, so it is scaled by the measured wrench noise in those units
// (noise_sigma, the larger row group's); without that measurement the
// weights may be defaults, not noise levels, and no such bias is counted.
// Not finite when h - C is not positive definite: the columns' noise is
// all their signal in some direction.
Md attenuation_share(const CovInput &in, const Vd &t, const Vd &phi, const Md &h,
                     bool least_squares) {
    const int n = static_cast<int>(h.rows());
    if (!in.col_exact) return Md::Zero(n, n);
    const double kappa = std::pow(std::max(measured_noise(in, 0), measured_noise(in, 1)), 2);
    least_squares = least_squares && kappa > 0;
    Vd c = Vd::Zero(n), noisy = Vd::Zero(n);
    const double rows = 6.0 * static_cast<double>(in.samples);
    for (int j = 0; j < std::min(n, LOADID_NPHI); ++j) { // the offset columns are exact
        const double exact = static_cast<double>(in.col_exact[j]);
        if (exact != 1.0) {
            const double t_noise = t(j) / exact, all = rows / (t_noise * t_noise);
            const double measured =
                least_squares && in.col_measured ? static_cast<double>(in.col_measured[j]) : 0;
            c(j) = (1 - measured) * all;
            noisy(j) = kappa * measured * all;
        } else if (least_squares) {
            noisy(j) = kappa * rows / (t(j) * t(j));
        }
    }
    if (!(c.maxCoeff() > 0) && !(noisy.maxCoeff() > 0)) return Md::Zero(n, n);
    Md hc = h;
    hc.diagonal() -= noisy;
    const Eigen::LDLT<Md> f(hc);
    if (noisy.maxCoeff() > 0 && !(f.info() == Eigen::Success && (f.vectorD().array() > 0).all()))
        return Md::Constant(n, n, std::numeric_limits<double>::quiet_NaN());
    const Vd b = f.solve((c + noisy).cwiseProduct(phi));
    if (!b.allFinite()) return Md::Zero(n, n);
    return b * b.transpose();
}

// d d^T delta^2: TLS takes the columns' noise share K = lmin T^-2 off the
// Gram (Van Huffel & Vandewalle 1991), so its estimate moves by
// d = (h - K)^-1 K phi per unit of relative error in that share; its
// relative error is taken as |1 - s^2|, s TLS's own misfit (1 when the row
// and column weights fit the data). With columns counted exact K is
// nothing; with the accelerometer's columns (sensor, mixed) the share
// corrected 24-71 % of the mass, and a vibration the weights did not
// describe (coherent across the axes) left RTLS 8-10 % off in mass at
// 3 % phi_std.
Md weights_share(const Vd &t, const Vd &phi, const Md &hi, double lmin, int noisy_to, double s2) {
    const int n = static_cast<int>(hi.rows());
    Vd k = Vd::Zero(n);
    for (int j = 0; j < noisy_to; ++j) k(j) = lmin / (t(j) * t(j)) * phi(j);
    const Vd d = hi * k;
    const double delta = 1 - s2;
    return delta * delta * d * d.transpose();
}

// What covariance_std works on: the weighted Gram of [A y] with column
// weights t (gs, and gts over the torque rows), np columns estimated at
// phi (np values), IV's M and C^T W C (unweighted). The columns from
// exact_from on are exact (the drift's): TLS takes no noise off them.
struct Problem {
    int np = 0, exact_from = 0;
    Md gs, gts, m, cc, cct; // cct: cc over the torque rows (empty: not kept)
    Vd t, phi;
    bool witness = true; // add the zeroing offset's share and the drift witness
    Md out;              // in.n x np: what is reported of phi (empty: its first in.n)
};

// The estimate's problem as the estimator keeps it.
Problem plain(const CovInput &in) {
    Problem p;
    const int n = in.n, n1 = n + 1;
    p.np = p.exact_from = n;
    p.gs = symmetric(in.gram, n1);
    p.gts = symmetric(in.gram_torque, n1);
    p.t.resize(n1);
    for (int j = 0; j < n1; ++j) p.t(j) = static_cast<double>(in.t[j]);
    p.phi.resize(n);
    for (int j = 0; j < n; ++j) p.phi(j) = static_cast<double>(in.phi[j]);
    if (in.kind == CovKind::IV) {
        p.m = full(in.iv_m, n);
        p.cc = full(in.iv_cc, n);
        if (in.iv_cc_torque) p.cct = full(in.iv_cc_torque, n);
    }
    return p;
}

// q (plain) with the offset's linear drift fitted too (uncertainty.hpp):
// six exact columns tau_k E6 after the n parameters (column weight 1), at
// phi less the drift's pull and the drift's fitted rate; pull (n values):
// the least-squares estimate (IV's for IV) with a constant offset less the
// one with the drift. False without the drift sums (IV: its own too) or
// when a fit is singular.
bool with_drift(const CovInput &in, const Problem &q, Problem &p, Vd &pull) {
    const int n = in.n, nd = LOADID_NROWS, n2 = n + nd;
    if (!in.drift_cross || !in.drift_y || !in.row_weight || n != LOADID_NPHI_OFFSET) return false;
    p = q;
    p.np = n2;
    p.witness = false;
    p.gs = Md::Zero(n2 + 1, n2 + 1);
    p.gts = Md::Zero(n2 + 1, n2 + 1);
    // Parameters 0..n-1, drift n..n2-1, y at n2.
    auto place = [&](const Md &from, Md &to) {
        to.topLeftCorner(n, n) = from.topLeftCorner(n, n);
        to.block(n2, 0, 1, n) = from.block(n, 0, 1, n);
        to.block(0, n2, n, 1) = from.block(0, n, n, 1);
        to(n2, n2) = from(n, n);
    };
    place(q.gs, p.gs);
    place(q.gts, p.gts);
    for (int r = 0; r < nd; ++r) {
        const double d = static_cast<double>(in.row_weight[r]);
        for (Md *g : {&p.gs, &p.gts}) {
            if (g == &p.gts && r < 3) continue; // a drift column reaches its own row only
            for (int j = 0; j < n; ++j)
                (*g)(n + r, j) = (*g)(j, n + r) = d * in.drift_cross[j * 6 + r];
            (*g)(n + r, n2) = (*g)(n2, n + r) = d * in.drift_y[r];
            (*g)(n + r, n + r) = d * d * in.drift_tt;
        }
    }
    p.t.resize(n2 + 1);
    p.t.head(n) = q.t.head(n);
    p.t.segment(n, nd).setOnes();
    p.t(n2) = q.t(n);
    Vd x16, x22;
    if (in.kind == CovKind::IV && in.iv_drift && in.iv_b) {
        // [C t E6]^T W [A t E6] [phi; rate] = [C t E6]^T W y, W = D^2; the
        // drift columns are their own instruments.
        p.m = Md::Zero(n2, n2);
        p.cc = Md::Zero(n2, n2);
        p.m.topLeftCorner(n, n) = q.m;
        p.cc.topLeftCorner(n, n) = q.cc;
        if (q.cct.size() != 0) {
            p.cct = Md::Zero(n2, n2);
            p.cct.topLeftCorner(n, n) = q.cct;
        }
        Vd b(n2);
        for (int j = 0; j < n; ++j) b(j) = static_cast<double>(in.iv_b[j]);
        for (int r = 0; r < nd; ++r) {
            const double d = static_cast<double>(in.row_weight[r]);
            for (int j = 0; j < n; ++j) {
                p.m(j, n + r) = p.cc(j, n + r) = p.cc(n + r, j) = in.iv_drift[r * n + j];
                p.m(n + r, j) = d * in.drift_cross[j * 6 + r] / q.t(j);
            }
            p.m(n + r, n + r) = p.cc(n + r, n + r) = d * d * in.drift_tt;
            if (p.cct.size() != 0 && r >= 3) { // a drift column reaches its own row only
                p.cct.col(n + r) = p.cc.col(n + r);
                p.cct.row(n + r) = p.cc.row(n + r);
            }
            b(n + r) = d * in.drift_y[r] / q.t(n);
        }
        x16 = Eigen::PartialPivLU<Md>(q.m).solve(Vd(b.head(n)));
        x22 = Eigen::PartialPivLU<Md>(p.m).solve(b);
    } else {
        if (in.kind == CovKind::IV) return false;
        // Least squares in the unweighted columns.
        const Md g = p.t.cwiseInverse().asDiagonal() * p.gs * p.t.cwiseInverse().asDiagonal();
        Eigen::LDLT<Md> full(Md(g.topLeftCorner(n2, n2)));
        Eigen::LDLT<Md> part(Md(g.topLeftCorner(n, n)));
        if (full.info() != Eigen::Success || part.info() != Eigen::Success) return false;
        x22 = full.solve(Vd(g.col(n2).head(n2)));
        x16 = part.solve(Vd(g.col(n2).head(n)));
    }
    if (!x16.allFinite() || !x22.allFinite()) return false;
    pull = x16 - x22.head(n);
    p.phi.resize(n2);
    p.phi.head(n) = q.phi - pull;
    p.phi.tail(nd) = x22.tail(nd);
    // The offset reported is the line's at the window's (weighted) mean
    // time, where a constant offset's fit would put it and its error is
    // least: offset + tau_mid rate. tau_mid = sum w tau / sum w from the
    // first offset column (its entry is 1 in its row).
    const int off = LOADID_NPHI;
    const double w_sum = q.gs(off, off),
                 tau_mid = in.drift_cross[off * 6] * in.row_weight[0] * q.t(off) / w_sum;
    if (!(w_sum > 0) || !std::isfinite(tau_mid)) return false;
    p.out = Md::Identity(n, n2);
    for (int r = 0; r < nd; ++r) p.out(off + r, n + r) = tau_mid;
    return true;
}

// d d^T, d = phi_16 - phi_22, the drift's pull (with_drift): the
// witness of a drift the estimate has not fitted (uncertainty.hpp).
Md drift_share(const CovInput &in, const Problem &q) {
    Problem p;
    Vd pull;
    if (!with_drift(in, q, p, pull)) return Md::Zero(in.n, in.n);
    return pull * pull.transpose();
}

// The residual's covariance between a sample's rows, each row group's
// mean variance 1 (uncertainty.hpp), over the bands' bins but the mean
// (where the regressor has its power); false without the rows apart or
// where a group has no residual.
bool row_shape(const loadid_spectrum_t &sp, const Vd &v, Eigen::Matrix<double, 6, 6> &shape) {
    if (!sp.has_rows) return false;
    const int n1 = static_cast<int>(v.size());
    shape.setZero();
    for (int j = 1; j < sp.first_bin[sp.n_bands]; ++j)
        for (int part = 0; part < 2; ++part) {
            const Eigen::Matrix<double, 6, 1> e =
                rows_of(sp.row_dft[j][part], LOADID_NROWS, n1, n1) * v;
            shape += e * e.transpose();
        }
    double scale[2];
    for (int g = 0; g < 2; ++g) {
        const double mean = shape.diagonal().segment<3>(3 * g).mean();
        if (!(mean > 0) || !std::isfinite(mean)) return false;
        scale[g] = 1 / std::sqrt(mean);
    }
    for (int r = 0; r < LOADID_NROWS; ++r)
        for (int s = 0; s < LOADID_NROWS; ++s) shape(r, s) *= scale[r / 3] * scale[s / 3];
    return true;
}

// Whether a parameter's column carries a measurement's noise (col_exact
// 1: the accelerometer's, signals sensor or mixed), which a sample's rows
// share.
bool measured_columns(const CovInput &in) {
    if (!in.col_exact) return true;
    for (int j = 0; j < std::min(in.n, LOADID_NPHI); ++j)
        if (in.col_exact[j] == Real(1)) return true;
    return false;
}

// sum over bin j's rows of Re(X^H S X), X = re + i im (6 x m, row r's m
// values at r * m): the meat of a residual of covariance S between rows.
Md bin_meat(const double *re, const double *im, int m, const Eigen::Matrix<double, 6, 6> &S) {
    const RowsMap xr = rows_of(re, LOADID_NROWS, m, m), xi = rows_of(im, LOADID_NROWS, m, m);
    return xr.transpose() * S * xr + xi.transpose() * S * xi;
}

// sum over bin j's rows row0..row0+2 of Re(C^H A): the instruments' and
// the data's product (rows as bin_meat's; A has n1 values a row).
Md bin_cross(const loadid_spectrum_t &sp, int j, int n, int row0) {
    Md x = Md::Zero(n, n);
    for (int part = 0; part < 2; ++part)
        x += rows_of(sp.iv_dft[j][part] + row0 * n, 3, n, n).transpose() *
             rows_of(sp.row_dft[j][part] + row0 * (n + 1), 3, n, n + 1);
    return x;
}

// The sandwich's meat from the residual's level per band of frequency
// (uncertainty.hpp): for each row group g (gf, gt: the force and torque
// rows' Gram of [A y], columns unweighted) and band, S_gb = v^T G v over
// the band's values less the fit's leverage tr(H^-1 G_AA) there, at least
// the wrench noise measured apart; a band with too few values left joins
// the next. IV's fit is oblique, P = A M^-1 C^T W: with the rows apart its
// leverage in a band is 2 tr(M^-1 C_b^T W A_b) - tr(G_b M^-1 C^T W C M^-T)
// (tr(H^-1 G_b) for least squares): a regressor whose noise inflates
// A^T W A would have the least-squares figure take too little off (the
// sensor's alpha: the torque rows' level 19 % low). With the rows apart a
// band's meat is sum_j Re(X_j^H S_b X_j) (IV: the instruments' X), S_b the
// rows' shape scaled to the band's levels; else, and for the rest above
// the bands, sum S_gb G_AA (IV: the instruments' Gram). False without a
// spectrum or for another problem than the estimate's own (the drift's).
bool spectral_meat(const CovInput &in, const Problem &p, const Md &gf, const Md &gt, const Vd &v,
                   Md &meat) {
    constexpr double kMinDof = 12; // a band with fewer joins the next
    const loadid_spectrum_t *sp = in.spectrum;
    const int n = p.np, n1 = n + 1;
    if (!sp || n != in.n) return false;
    const bool iv = in.kind == CovKind::IV;
    const int nb = sp->n_bands;
    Md hi, mi;
    if (!spd_inverse(Md((gf + gt).topLeftCorner(n, n)), hi)) return false;
    const bool oblique = iv && sp->has_rows;
    if (oblique) {
        mi = Eigen::PartialPivLU<Md>(p.m).inverse();
        if (!mi.allFinite()) return false;
    }
    // Each band's level per row group (nb: the rest), and the rest's Gram.
    double level[LOADID_SPECTRUM_BANDS + 1][2];
    Md rest[2];
    for (int grp = 0; grp < 2; ++grp) {
        const double floor = std::pow(measured_noise(in, grp), 2);
        rest[grp] = iv ? full(sp->iv_total[grp], n) : Md((grp == 0 ? gf : gt).topLeftCorner(n, n));
        double pend_rr = 0, pend_dof = 0, pend_lev = 0, used = 0;
        int first = 0;
        Md left = grp == 0 ? gf : gt;
        for (int b = 0; b <= nb; ++b) {
            double dof = 0, rr = 0, lev = 0;
            if (b < nb) {
                const Md band = full(sp->gram[b][grp], n1);
                left -= band;
                rest[grp] -= iv ? full(sp->iv_gram[b][grp], n) : Md(band.topLeftCorner(n, n));
                // Three channels, two real values a bin (one for the mean).
                const double values = b == 0 ? 3 : 6.0 * (sp->first_bin[b + 1] - sp->first_bin[b]);
                used += values;
                if (b > 0) { // band 0's residual holds the zeroing offset's error
                    dof = values;
                    rr = v.dot(band * v);
                    lev = (hi * band.topLeftCorner(n, n)).trace();
                    if (oblique) {
                        Md x = Md::Zero(n, n);
                        for (int j = sp->first_bin[b]; j < sp->first_bin[b + 1]; ++j)
                            x += bin_cross(*sp, j, n, 3 * grp);
                        lev = 2 * (mi * x).trace() -
                              (band.topLeftCorner(n, n) * mi * p.cc * mi.transpose()).trace();
                    }
                }
            } else {
                dof = 3.0 * static_cast<double>(in.samples) - used;
                rr = v.dot(left * v);
                lev = (hi * left.topLeftCorner(n, n)).trace();
            }
            pend_rr += rr, pend_dof += dof, pend_lev += lev;
            if (b < nb && pend_dof - pend_lev < kMinDof) continue;
            const double l =
                std::max(std::max(pend_rr, 0.0) / std::max(pend_dof - pend_lev, 1.0), floor);
            for (; first <= b; ++first) level[first][grp] = l;
            pend_rr = pend_dof = pend_lev = 0;
        }
    }
    meat = level[nb][0] * rest[0] + level[nb][1] * rest[1];
    Eigen::Matrix<double, 6, 6> shape;
    const bool apart = measured_columns(in) && row_shape(*sp, v, shape);
    for (int b = 0; b < nb; ++b) {
        if (!apart) {
            for (int grp = 0; grp < 2; ++grp)
                meat += level[b][grp] * (iv ? full(sp->iv_gram[b][grp], n)
                                            : Md(full(sp->gram[b][grp], n1).topLeftCorner(n, n)));
            continue;
        }
        Eigen::Matrix<double, 6, 6> s;
        for (int r = 0; r < LOADID_NROWS; ++r)
            for (int c = 0; c < LOADID_NROWS; ++c)
                s(r, c) = shape(r, c) * std::sqrt(level[b][r / 3] * level[b][c / 3]);
        for (int j = sp->first_bin[b]; j < sp->first_bin[b + 1]; ++j) {
            if (iv) {
                meat += bin_meat(sp->iv_dft[j][0], sp->iv_dft[j][1], n, s);
            } else {
                const Md m = bin_meat(sp->row_dft[j][0], sp->row_dft[j][1], n1, s);
                meat += m.topLeftCorner(n, n);
            }
        }
    }
    return meat.allFinite();
}

int covariance_of(const CovInput &in, const Problem &p, Real *std, Real *scale) {
    const int n = p.np, n1 = n + 1;
    for (int i = 0; i < in.n; ++i) std[i] = std::numeric_limits<Real>::infinity();
    *scale = std::numeric_limits<Real>::quiet_NaN();
    const double rows = 6.0 * static_cast<double>(in.samples), dof = rows - n;
    if (!(dof >= 2)) return LOADID_E_NOT_EXCITED;
    const Vd &t = p.t, &phi = p.phi;
    // Without the column weights: sum [A y]^T D^2 [A y], all rows and the
    // torque rows.
    const Md &gs = p.gs;
    const Md g = t.cwiseInverse().asDiagonal() * gs * t.cwiseInverse().asDiagonal();
    const Md gt = t.cwiseInverse().asDiagonal() * p.gts * t.cwiseInverse().asDiagonal();
    const Md gf = g - gt;
    // The residual's variance per row group, and overall.
    Vd v(n1);
    v.head(n) = phi;
    v(n) = -1;
    const double half = dof / 2;
    double sf2 = std::max(v.dot(gf * v), 0.0) / half;
    double st2 = std::max(v.dot(gt * v), 0.0) / half;
    double s2 = (sf2 + st2) / 2; // the scale reported: of the residual itself
    if (in.noise_corr) {
        double *group[2] = {&sf2, &st2};
        for (int k = 0; k < 2; ++k) {
            const double r = static_cast<double>(in.noise_corr[k]);
            *group[k] += std::pow(measured_noise(in, k), 2) * ((1 + r) / (1 - r) - 1);
        }
    }
    const double s2_iv = (sf2 + st2) / 2;
    Md smeat;
    const bool spectral = spectral_meat(in, p, gf, gt, v, smeat);
    Md cov(n, n);
    if (in.kind == CovKind::IV) {
        Eigen::PartialPivLU<Md> lu(p.m);
        const Md mi = lu.inverse();
        if (!mi.allFinite()) return LOADID_E_NOT_EXCITED;
        // One level per row group as least squares' where the torque rows'
        // part is kept, else the rows' mean.
        const Md meat = spectral            ? smeat
                        : p.cct.size() != 0 ? Md(sf2 * (p.cc - p.cct) + st2 * p.cct)
                                            : Md(s2_iv * p.cc);
        if (p.witness)
            cov = mi * meat * mi.transpose() + offset_share(in, t, mi) + drift_share(in, p);
        else
            cov = mi * meat * mi.transpose();
    } else {
        Md h = g.topLeftCorner(n, n);
        double lmin = 0;
        if (in.kind == CovKind::TLS) {
            // A0^T W A0 of the noise-free data: the noise's share, the
            // smallest eigenvalue of the scaled Gram per unit column weight,
            // comes off (Van Huffel & Vandewalle 1991, sec. 8.2); exact
            // columns are eliminated first (mixed LS-TLS) and keep theirs.
            const int ne = n - p.exact_from;
            Md noisy = gs;
            if (ne > 0) {
                const int k = p.exact_from;
                Md s(n1 - ne, n1 - ne);
                s << gs.topLeftCorner(k, k), gs.block(0, n, k, 1), gs.block(n, 0, 1, k), gs(n, n);
                Md x(ne, n1 - ne);
                x << gs.block(k, 0, ne, k), gs.block(k, n, ne, 1);
                noisy = s - x.transpose() * Md(gs.block(k, k, ne, ne)).ldlt().solve(x);
            }
            Eigen::SelfAdjointEigenSolver<Md> es(noisy, Eigen::EigenvaluesOnly);
            lmin = std::max(es.eigenvalues()(0), 0.0);
            h.diagonal().head(p.exact_from).array() -=
                lmin * t.head(p.exact_from).array().square().inverse();
            // TLS's own scale: the orthogonal residual per entry of the
            // weighted data, 1 when the row and column weights fit.
            s2 = lmin / dof;
        }
        Md hi;
        if (!spd_inverse(h, hi)) return LOADID_E_NOT_EXCITED;
        const Md meat =
            spectral ? smeat : Md(sf2 * gf.topLeftCorner(n, n) + st2 * gt.topLeftCorner(n, n));
        const bool ls = in.kind != CovKind::TLS;
        cov = hi * meat * hi + attenuation_share(in, t, phi, g.topLeftCorner(n, n), ls);
        if (!ls) cov += weights_share(t, phi, hi, lmin, p.exact_from, s2);
        if (p.witness) cov += offset_share(in, t, hi) + drift_share(in, p);
    }
    if (!cov.allFinite()) return LOADID_E_NOT_EXCITED;
    if (p.out.size() != 0) cov = p.out * cov * p.out.transpose();
    for (int i = 0; i < in.n; ++i) std[i] = static_cast<Real>(std::sqrt(std::max(cov(i, i), 0.0)));
    *scale = static_cast<Real>(std::sqrt(s2));
    return 0;
}

} // namespace

int covariance_std(const CovInput &in, Real *std, Real *scale) {
    if (!in.phi_fitted) return covariance_of(in, plain(in), std, scale);
    Problem p;
    Vd pull;
    for (int i = 0; i < in.n; ++i) std[i] = std::numeric_limits<Real>::infinity();
    *scale = std::numeric_limits<Real>::quiet_NaN();
    if (!with_drift(in, plain(in), p, pull)) return LOADID_E_NOT_EXCITED;
    const Vd reported = p.out * p.phi;
    for (int i = 0; i < in.n; ++i) in.phi_fitted[i] = static_cast<Real>(reported(i));
    return covariance_of(in, p, std, scale);
}

int weakest_direction(const CovInput &in, Real *dir, Real *ratio) {
    const int n = in.n, n1 = n + 1;
    if (in.samples <= 0) return LOADID_E_NOT_EXCITED;
    const Md gs = symmetric(in.gram, n1);
    Eigen::SelfAdjointEigenSolver<Md> es(gs.topLeftCorner(n, n));
    const Vd l = es.eigenvalues();
    // In the scaled coordinates x = T^-1 phi: phi = T x.
    Vd v(n);
    double big = 0;
    for (int j = 0; j < n; ++j) {
        v(j) = es.eigenvectors()(j, 0) * static_cast<double>(in.t[j]);
        big = std::max(big, std::abs(v(j)));
    }
    for (int j = 0; j < n; ++j) dir[j] = static_cast<Real>(big > 0 ? v(j) / big : 0);
    if (ratio)
        *ratio = static_cast<Real>(l(n - 1) > 0 ? std::sqrt(std::max(l(0), 0.0) / l(n - 1)) : 0);
    return 0;
}

int group_snr(const CovInput &in, Real snr[3]) {
    const int n = in.n, n1 = n + 1;
    snr[0] = snr[1] = snr[2] = 0;
    const double rows = 6.0 * static_cast<double>(in.samples);
    if (!(rows > 0)) return LOADID_E_NOT_EXCITED;
    Vd t(n1);
    for (int j = 0; j < n1; ++j) t(j) = static_cast<double>(in.t[j]);
    const Md g =
        t.cwiseInverse().asDiagonal() * symmetric(in.gram, n1) * t.cwiseInverse().asDiagonal();
    const int first[3] = {0, 1, 4}, count[3] = {1, 3, 6};
    const double share[3] = {1.0, 1.0, 0.5}; // the inertia reaches the torque rows only
    for (int grp = 0; grp < 3; ++grp) {
        double e = 0;
        for (int i = 0; i < count[grp]; ++i)
            for (int j = 0; j < count[grp]; ++j)
                e += static_cast<double>(in.phi[first[grp] + i]) *
                     g(first[grp] + i, first[grp] + j) *
                     static_cast<double>(in.phi[first[grp] + j]);
        snr[grp] = static_cast<Real>(std::sqrt(std::max(e, 0.0) / (rows * share[grp])));
    }
    return 0;
}

} // namespace loadid
