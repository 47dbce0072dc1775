// The Gram-eigenproblem shortcut (gram_tls.h), for bench_core only. It
// shares the excitation gate with the estimators, so that the benchmark
// compares the TLS solutions alone.
#include "gram_tls.h"

#include <cerrno>
#include <new>

#include "eigen_types.hpp"
#include "excitation.hpp"
#include "tls_solution.hpp"

namespace {

using loadid::Real;
constexpr int N = LOADID_NPHI;
constexpr int N1 = N + 1;

} // namespace

struct loadid_gram_tls {
    explicit loadid_gram_tls(const loadid_est_config_t &c)
        : cfg(c), t(loadid::col_weights<N>(c)), excitation(loadid::row_weights(c), t) {}
    loadid_est_config_t cfg;
    loadid::Vec<N1> t;
    loadid::Excitation<N> excitation; // its Gram matrix is the shortcut's
    int64_t samples = 0;
};

extern "C" int loadid_gram_tls_create(const loadid_est_config_t *cfg, loadid_gram_tls_t **out) {
    if (!cfg || !out || cfg->n_params != N) return -EINVAL;
    *out = new (std::nothrow) loadid_gram_tls(*cfg);
    return *out ? 0 : -ENOMEM;
}

extern "C" void loadid_gram_tls_destroy(loadid_gram_tls_t *g) {
    delete g;
}

extern "C" void loadid_gram_tls_reset(loadid_gram_tls_t *g) {
    g->excitation.reset();
    g->samples = 0;
}

extern "C" void loadid_gram_tls_update(loadid_gram_tls_t *g, const loadid_real_t *A,
                                       const loadid_real_t *y) {
    g->excitation.add(loadid::Regressor<N>(loadid::ConstRegressorMap<N>(A)),
                      Eigen::Map<const loadid::Vec6>(y));
    ++g->samples;
}

extern "C" int loadid_gram_tls_estimate(const loadid_gram_tls_t *g, loadid_real_t *phi,
                                        loadid_est_info_t *info) {
    using Mat = Eigen::Matrix<Real, N1, N1>;
    const Mat gram = g->excitation.gram().selfadjointView<Eigen::Lower>();
    const Eigen::SelfAdjointEigenSolver<Mat> es(gram);
    // Eigenvalues ascending: singular values (their roots) descending, as
    // tls_solution wants them.
    Mat W;
    loadid::Vec<N1> s;
    for (int j = 0; j < N1; ++j) {
        W.col(j) = es.eigenvectors().col(N - j);
        s(j) = std::sqrt(std::max(es.eigenvalues()(N - j), Real(0)));
    }
    const Real ratio = s(N - 1) > 0 ? s(N) / s(N - 1) : Real(1);
    Eigen::Map<loadid::Vec<N>> out(phi);
    out.setZero();
    const int gate = loadid::excitation_gate(g->excitation, ratio, g->cfg, g->samples, info, true);
    if (info) info->sigma_min = s(N);
    if (gate) return gate;
    const loadid::TlsSolution<N> sol = loadid::tls_solution<N>(W, s, g->t, g->cfg.rtls_eps);
    if (sol.status) return sol.status;
    out = sol.phi;
    return 0;
}
