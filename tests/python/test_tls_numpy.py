"""Independent batch checks of the estimators with numpy.linalg.

Data: a realistic load (1.4 kg, a few cm of COM offset, inertia of a small
tool) moved through random states; the TRUE wrench comes from Pinocchio's
Newton-Euler evaluation of the true states (pin_model.wrench), the data
matrix from the library's regressor of the NOISY states (Gaussian noise on
spec = a - g, w and alpha), and Gaussian noise is added to the wrench: the
errors-in-variables situation TLS is made for. Row weights D = diag(1/row_sigma)
and column weights T come from loadid_est_weights_from_noise.

Every expected value is computed here with numpy from the stacked data:
  TLS (paper eqs. 24, 36): C = D [A y] T stacked over all samples, SVD,
      v = last right singular vector, phi_i = -t_i v_i / (t_{n+1} v_{n+1});
  LS: numpy.linalg.lstsq(D A, D y);
  sigma_min: the smallest singular value of C;
  condition_number: numpy.linalg.cond(D A T1), T1 = the first n_params
      column weights (estimator.h: "kappa of D A_Xi T (columns of A only)").
"""

from __future__ import annotations

import functools

import numpy as np
import pinocchio as pin
import pytest

from conftest import (
    LOADID_E_NONFINITE,
    LOADID_E_NOT_EXCITED,
    METHOD_LS_BATCH,
    METHOD_NAMES,
    METHOD_RIV,
    METHOD_RLS,
    METHOD_RTLS,
    METHOD_TLS_BATCH,
    Estimator,
    col_weights,
    config_default,
    regressor,
    row_weights,
    strerror,
    weights_from_noise,
    with_offset,
)
from pin_model import phi_loadid, random_rotation, wrench

EPS = np.finfo(np.float64).eps
G = 9.81

# Noise levels of the simulated sensors (a JR3-class F/T sensor and a
# MEMS accelerometer / gyro pair), used both to make the data and, through
# loadid_est_weights_from_noise, to weight it.
NOISE = dict(sigma_f=0.05, sigma_tau=0.004, sigma_spec=0.05, sigma_alpha=0.5,
             sigma_omega=0.01, omega_typ=1.5)
SAMPLE_COUNTS = [10, 100, 1000]


def true_load() -> pin.Inertia:
    R = random_rotation(np.random.default_rng(5))
    return pin.Inertia(1.4, np.array([0.01, -0.015, 0.06]),
                       R @ np.diag([0.004, 0.005, 0.007]) @ R.T)


@functools.lru_cache(maxsize=None)
def dataset(n_samples: int, n_params: int, seed: int, noise: bool = True):
    """(As, ys, phi_true): As (K, 6, n_params) from the library's regressor of
    noisy states, ys (K, 6) Pinocchio wrenches of the true states plus noise
    (plus a constant sensor offset for the 16-parameter model), phi_true in
    loadid's order ([phi; offset] for 16)."""
    rng = np.random.default_rng(seed)
    load = true_load()
    offset = rng.normal(scale=[2.0, 2.0, 2.0, 0.1, 0.1, 0.1])
    s = NOISE if noise else {k: 0.0 for k in NOISE}
    As, ys = [], []
    for _ in range(n_samples):
        spec = G * random_rotation(rng)[:, 2] + rng.normal(scale=3.0, size=3)
        w = rng.normal(scale=1.5, size=3)
        alpha = rng.normal(scale=8.0, size=3)
        v_lin = rng.normal(scale=0.5, size=3)  # only Pinocchio needs it
        y = wrench(load, spec, w, alpha, v_lin)
        y = y + rng.normal(size=6) * np.repeat([s["sigma_f"], s["sigma_tau"]], 3)
        A = regressor(spec + s["sigma_spec"] * rng.normal(size=3),
                      w + s["sigma_omega"] * rng.normal(size=3),
                      alpha + s["sigma_alpha"] * rng.normal(size=3))
        if n_params == 16:
            A = with_offset(A)
            y = y + offset
        As.append(A)
        ys.append(y)
    phi = phi_loadid(load)
    if n_params == 16:
        phi = np.concatenate([phi, offset])
    As, ys = np.array(As), np.array(ys)
    As.setflags(write=False)
    ys.setflags(write=False)
    return As, ys, phi


def make_config(method: int, n_params: int, **changes):
    cfg = config_default(method, n_params)
    weights_from_noise(cfg, **NOISE)
    for k, v in changes.items():
        setattr(cfg, k, v)
    return cfg


def run(cfg, As, ys, Cs=None):
    with Estimator(cfg) as est:
        est.feed(As, ys, Cs)
        rc, phi, info = est.estimate()
    assert rc == 0, f"{METHOD_NAMES[cfg.method]}: estimate returned {rc} ({strerror(rc)})"
    assert info.samples == len(As)
    return phi, info


# ---------------------------------------------------------------------------
# numpy references
# ---------------------------------------------------------------------------
def stacked(cfg, As, ys):
    """D A (6K x n), D y (6K), C = D [A y] T (6K x n+1)."""
    D, T = row_weights(cfg), col_weights(cfg)
    DA = (D[None, :, None] * As).reshape(-1, As.shape[2])
    Dy = (D[None, :] * ys).reshape(-1)
    C = np.hstack([DA, Dy[:, None]]) * T[None, :]
    return DA, Dy, C


def numpy_tls(cfg, As, ys):
    """Eq. (36) from numpy's SVD; also the singular values."""
    T = col_weights(cfg)
    n = As.shape[2]
    _, _, C = stacked(cfg, As, ys)
    _, s, Vt = np.linalg.svd(C, full_matrices=False)
    # The reference is well defined only for a simple smallest singular value.
    assert s[-2] - s[-1] > 1e-6 * s[0]
    v = Vt[-1]
    return -T[:n] * v[:n] / (T[n] * v[n]), s


def numpy_ls(cfg, As, ys):
    DA, Dy, _ = stacked(cfg, As, ys)
    return np.linalg.lstsq(DA, Dy, rcond=None)[0]


def numpy_rls(As, ys, lam, p0):
    """Eqs. (17)-(19) in numpy: plain covariance update (re-symmetrised), LU solve of S."""
    n = As.shape[2]
    P, phi = np.eye(n) * p0, np.zeros(n)
    for A, y in zip(As, ys):
        S = A @ P @ A.T + np.diag(lam)
        K = np.linalg.solve(S, A @ P).T  # P A^T S^-1 (P and S symmetric)
        phi = phi + K @ (y - A @ phi)
        P = P - K @ A @ P
        P = 0.5 * (P + P.T)
    return phi


def numpy_cond(cfg, As):
    """kappa(D A T1), T1 = the column weights of A's columns (not of y)."""
    DA, _, _ = stacked(cfg, As, np.zeros((len(As), 6)))
    return np.linalg.cond(DA * col_weights(cfg)[None, : As.shape[2]])


def numpy_noise_ratio(cfg, As, ys):
    """sigma_{n+1} / sigma_n of C = D [A y] T, and sigma_max / sigma_{n+1}."""
    _, _, C = stacked(cfg, As, ys)
    s = np.linalg.svd(C, compute_uv=False)
    return s[-1] / s[-2], s[0] / max(s[-1], 1e-300)


def assert_noise_ratio(info_ratio, cfg, As, ys, what):
    ref, spread = numpy_noise_ratio(cfg, As, ys)
    # Formed from the eigenvalues of the augmented Gram matrix: the smallest
    # one carries ~eps * sigma_max^2 absolutely.
    rtol = 1e-10 + 10 * EPS * spread * spread
    assert info_ratio == pytest.approx(ref, rel=rtol), f"{what}: noise ratio"
    return abs(info_ratio / ref - 1)


def assert_close_params(phi, ref, rtol, what):
    """Element-wise relative agreement (atol only guards exact zeros)."""
    err = np.abs(phi - ref)
    bound = rtol * np.abs(ref) + 1e-3 * rtol * np.linalg.norm(ref)
    worst = float(np.max(err / np.maximum(np.abs(ref), 1e-300)))
    assert np.all(err <= bound), (f"{what}: worst element-wise relative error {worst:.3e} > {rtol}"
                                  f"\nlib   {phi}\nnumpy {ref}")
    return worst


def assert_condition(info_kappa, cfg, As, what):
    ref = numpy_cond(cfg, As)
    # The library forms kappa from the eigenvalues of the Gram matrix
    # (D A T1)^T (D A T1), which costs relative accuracy ~ eps kappa^2.
    rtol = 1e-10 + 10 * EPS * ref * ref
    assert info_kappa == pytest.approx(ref, rel=rtol), f"{what}: condition number"
    return abs(info_kappa / ref - 1)


# ---------------------------------------------------------------------------
# TLS: TLS_BATCH and RTLS against numpy's SVD
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("n_params", [10, 16])
@pytest.mark.parametrize("n_samples", SAMPLE_COUNTS)
@pytest.mark.parametrize("method", [METHOD_TLS_BATCH, METHOD_RTLS], ids=["TLS_BATCH", "RTLS"])
def test_tls_equals_numpy_svd(method, n_samples, n_params):
    As, ys, phi_true = dataset(n_samples, n_params, seed=1000 + n_samples)
    cfg = make_config(method, n_params)
    phi, info = run(cfg, As, ys)
    ref, s = numpy_tls(cfg, As, ys)
    what = f"{METHOD_NAMES[method]} n={n_params} K={n_samples}"
    e_phi = assert_close_params(phi, ref, 1e-8, what)
    # info.sigma_min: the smallest singular value of D [A y] T (absolute
    # accuracy of an SVD ~ eps * sigma_max), unique.
    assert info.sigma_min == pytest.approx(s[-1], rel=1e-9, abs=1e2 * EPS * s[0]), what
    assert info.sigma_min_multiplicity == 1
    e_kappa = assert_condition(info.condition_number, cfg, As, what)
    e_ratio = assert_noise_ratio(info.noise_ratio, cfg, As, ys, what)
    # Sanity of the data (not of the library): TLS lands near the truth.
    assert np.linalg.norm(ref[:10] - phi_true[:10]) < 0.05 * np.linalg.norm(phi_true[:10])
    print(f"\n{what}: phi {e_phi:.1e}, sigma_min {abs(info.sigma_min / s[-1] - 1):.1e}, "
          f"kappa {e_kappa:.1e} (kappa={info.condition_number:.3g}), "
          f"noise ratio {e_ratio:.1e} (ratio={info.noise_ratio:.3g})")


def test_condition_number_is_of_D_A_T1_only():
    """The definition, pinned down: kappa of D A T1 with the column weights of
    A's columns, neither of D A (no T) nor of the augmented D [A y] T."""
    As, ys, _ = dataset(100, 10, seed=1100)
    cfg = make_config(METHOD_TLS_BATCH, 10)
    _, info = run(cfg, As, ys)
    DA, _, C = stacked(cfg, As, ys)
    k_ref = numpy_cond(cfg, As)
    assert info.condition_number == pytest.approx(k_ref, rel=1e-9)
    # The alternatives differ from it by far more than the tolerance.
    assert abs(np.linalg.cond(DA) / k_ref - 1) > 0.1
    assert abs(np.linalg.cond(C) / k_ref - 1) > 0.1


# ---------------------------------------------------------------------------
# LS: LS_BATCH, RLS and RIV against numpy.linalg.lstsq
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("n_params", [10, 16])
@pytest.mark.parametrize("n_samples", SAMPLE_COUNTS)
def test_ls_batch_equals_lstsq(n_samples, n_params):
    As, ys, _ = dataset(n_samples, n_params, seed=1000 + n_samples)
    cfg = make_config(METHOD_LS_BATCH, n_params)
    phi, info = run(cfg, As, ys)
    ref = numpy_ls(cfg, As, ys)
    e = assert_close_params(phi, ref, 1e-8, f"LS_BATCH n={n_params} K={n_samples}")
    assert info.sigma_min == 0 and info.sigma_min_multiplicity == 0  # not a TLS method
    assert_condition(info.condition_number, cfg, As, "LS_BATCH")
    assert_noise_ratio(info.noise_ratio, cfg, As, ys, "LS_BATCH")
    print(f"\nLS_BATCH n={n_params} K={n_samples}: {e:.1e}")


def _rls_rel_error(p0, n_samples, method=METHOD_RLS):
    As, ys, _ = dataset(n_samples, 10, seed=1000 + n_samples)
    cfg = make_config(method, 10, p0=p0)
    phi, info = run(cfg, As, ys, As if method == METHOD_RIV else None)
    ref = numpy_ls(cfg, As, ys)
    assert_condition(info.condition_number, cfg, As, METHOD_NAMES[method])
    assert_noise_ratio(info.noise_ratio, cfg, As, ys, METHOD_NAMES[method])
    assert info.sigma_min == 0
    return float(np.linalg.norm(phi - ref) / np.linalg.norm(ref))


@pytest.mark.parametrize("n_samples", SAMPLE_COUNTS)
@pytest.mark.parametrize("method", [METHOD_RLS, METHOD_RIV], ids=["RLS", "RIV"])
def test_recursive_ls_equals_lstsq(method, n_samples):
    """RLS (and RIV with the regressor itself as instruments, which is RLS)
    converge to the weighted LS solution. p0 = 1e4 keeps the ridge p0^-1
    negligible (~1e-10 relative here) while the covariance update still has
    digits to spare: with these weights the posterior covariance is ~2e-6 .. 2e-8,
    and eq. (18) loses ~eps * p0 absolutely (see the p0 = 1e8 test)."""
    e = _rls_rel_error(1e4, n_samples, method)
    print(f"\n{METHOD_NAMES[method]} p0=1e4 K={n_samples}: {e:.1e}")
    assert e <= 1e-7


P0_1E8_REASON = (
    "not a library defect: started from Sigma_0 = 1e8 I, the recursion carries ~eps*p0 = 2e-8 "
    "absolute rounding in Sigma and in S = A Sigma A^T + Lambda, more than the posterior "
    "covariance here (1/lambda_min(Gram) ~ 2e-6 .. 2e-8), so RLS with p0 = 1e8 sits "
    "~2e-5 (10 samples) .. ~2e-6 (1000 samples) away from lstsq; eqs. (17)-(19) evaluated "
    "in numpy are as far off (test_rls_p0_1e8_as_accurate_as_the_recursion_in_numpy)")


@pytest.mark.xfail(strict=True, reason=P0_1E8_REASON)
@pytest.mark.parametrize("n_samples", SAMPLE_COUNTS)
def test_rls_p0_1e8_equals_lstsq(n_samples):
    """The check as first specified: RLS with p0 = 1e8 equals lstsq to 1e-7
    (norm-wise). It cannot hold with realistic row weights; kept strict so
    that a change of the recursion (e.g. a square-root form) shows up."""
    e = _rls_rel_error(1e8, n_samples)
    print(f"\nRLS p0=1e8 K={n_samples}: {e:.1e}")
    assert e <= 1e-7


@pytest.mark.parametrize("n_samples", SAMPLE_COUNTS)
def test_rls_p0_1e8_as_accurate_as_the_recursion_in_numpy(n_samples):
    """With p0 = 1e8 the library's RLS is as close to lstsq as eqs. (17)-(19)
    evaluated in numpy (float64, LU solve) are: within 10x of the numpy
    recursion's own distance to lstsq, and both within 1e-3."""
    As, ys, _ = dataset(n_samples, 10, seed=1000 + n_samples)
    cfg = make_config(METHOD_RLS, 10, p0=1e8)
    ref = numpy_ls(cfg, As, ys)
    e_np = np.linalg.norm(numpy_rls(As, ys, np.array(cfg.row_sigma[:6]) ** 2, 1e8) - ref) \
        / np.linalg.norm(ref)
    e = _rls_rel_error(1e8, n_samples)
    print(f"\nRLS p0=1e8 K={n_samples}: library {e:.1e}, numpy recursion {e_np:.1e}")
    assert e_np <= 1e-3
    assert e <= max(10 * e_np, 1e-7)


@pytest.mark.xfail(strict=True, reason=(
    "library bug (firmware/src/rls.hpp, RecursiveLs::update): with p0 = 1e10 phi explodes "
    "(relative error ~2e4 vs lstsq here) while estimate() still returns 0. S = A Sigma A^T + "
    "Lambda of eq. (17) is numerically indefinite (p0 |A|^2 / Lambda > 1/eps) and is solved by "
    "an unchecked Cholesky (S.llt()), and the Joseph-form update of eq. (18) no longer "
    "re-symmetrises Sigma; eqs. (17)-(19) in numpy (LU solve, Sigma symmetrised) stay within "
    "1e-3, as does the library rebuilt with both changes"))
def test_rls_large_p0_stays_bounded():
    """A large p0 only loses digits in the recursion; it must not blow up:
    the numpy recursion with the same p0 stays within 1e-2 of lstsq, and so
    must the library (a loose bound, far above the expected round-off)."""
    As, ys, _ = dataset(100, 10, seed=1100)
    cfg = make_config(METHOD_RLS, 10, p0=1e10)
    ref = numpy_ls(cfg, As, ys)
    lam = np.array(cfg.row_sigma[:6]) ** 2
    e_np = np.linalg.norm(numpy_rls(As, ys, lam, 1e10) - ref) / np.linalg.norm(ref)
    assert e_np <= 1e-2  # the algorithm itself copes
    with Estimator(cfg) as est:
        est.feed(As, ys)
        rc, phi, _ = est.estimate()
    e = np.linalg.norm(phi - ref) / np.linalg.norm(ref)
    assert rc == 0 and e <= 1e-2, f"library RLS p0=1e10: relative error {e:.3e} (numpy: {e_np:.1e})"


# ---------------------------------------------------------------------------
# Noise-free data, and the NaN path, against the truth / numpy
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("n_params", [10, 16])
@pytest.mark.parametrize("method", [METHOD_TLS_BATCH, METHOD_RTLS, METHOD_LS_BATCH],
                         ids=["TLS_BATCH", "RTLS", "LS_BATCH"])
def test_noise_free_data_recover_pinocchio_parameters(method, n_params):
    """Exact data (library regressor, Pinocchio wrench of the same states):
    every method returns Pinocchio's parameters of the load, which ties the
    sign and order conventions of the estimators to Pinocchio's."""
    As, ys, phi_true = dataset(50, n_params, seed=77, noise=False)
    phi, _ = run(make_config(method, n_params), As, ys)
    np.testing.assert_allclose(phi, phi_true, rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("method", [METHOD_TLS_BATCH, METHOD_RTLS, METHOD_LS_BATCH, METHOD_RLS],
                         ids=["TLS_BATCH", "RTLS", "LS_BATCH", "RLS"])
def test_nonfinite_sample_is_ignored(method):
    """An update holding NaN/Inf returns LOADID_E_NONFINITE and changes
    nothing: the result equals numpy's over the finite samples only."""
    As, ys, _ = dataset(100, 10, seed=1100)
    cfg = make_config(method, 10, p0=1e4)
    with Estimator(cfg) as est:
        for k in range(len(As)):
            if k in (1, 40):  # one during RTLS's initial stacking, one later
                bad_y = np.array(ys[k])
                bad_y[3] = np.nan
                assert est.update(As[k], bad_y) == LOADID_E_NONFINITE
                bad_A = np.array(As[k])
                bad_A[2, 5] = np.inf
                assert est.update(bad_A, ys[k]) == LOADID_E_NONFINITE
            assert est.update(As[k], ys[k]) == 0
        rc, phi, info = est.estimate()
    assert rc == 0 and info.samples == len(As)
    if method in (METHOD_TLS_BATCH, METHOD_RTLS):
        ref, _ = numpy_tls(cfg, As, ys)
        assert_close_params(phi, ref, 1e-8, "TLS with NaN samples")
    else:
        ref = numpy_ls(cfg, As, ys)
        assert np.linalg.norm(phi - ref) <= 1e-7 * np.linalg.norm(ref)


# ---------------------------------------------------------------------------
# The excitation gate on the noise ratio, decided against numpy
# ---------------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def still_dataset(n_samples: int, seed: int):
    """The load held still (one pose, w = alpha = 0): only the sensor noise
    varies, so D A T is well conditioned but nothing stands out of the noise."""
    rng = np.random.default_rng(seed)
    load = true_load()
    spec = G * random_rotation(rng)[:, 2]
    zero = np.zeros(3)
    y_true = wrench(load, spec, zero, zero, zero)
    As, ys = [], []
    for _ in range(n_samples):
        ys.append(y_true + rng.normal(size=6) * np.repeat([NOISE["sigma_f"], NOISE["sigma_tau"]], 3))
        As.append(regressor(spec + NOISE["sigma_spec"] * rng.normal(size=3),
                            NOISE["sigma_omega"] * rng.normal(size=3),
                            NOISE["sigma_alpha"] * rng.normal(size=3)))
    return np.array(As), np.array(ys)


@pytest.mark.parametrize("method", [METHOD_TLS_BATCH, METHOD_RTLS, METHOD_LS_BATCH, METHOD_RLS],
                         ids=["TLS_BATCH", "RTLS", "LS_BATCH", "RLS"])
def test_noise_ratio_gate_follows_numpy(method):
    """estimate() reports LOADID_E_NOT_EXCITED exactly when numpy's
    sigma_{n+1} / sigma_n of D [A y] T exceeds max_noise_ratio (the
    condition-number gate is opened wide so that only this one acts)."""
    As, ys = still_dataset(200, seed=4)
    base = make_config(method, 10, max_condition=1e300)
    ratio, _ = numpy_noise_ratio(base, As, ys)
    assert ratio > 0.5, "a still pose should look unexcited (data sanity)"
    for factor, expect in ((1 - 1e-6, LOADID_E_NOT_EXCITED), (1 + 1e-6, 0)):
        cfg = make_config(method, 10, max_condition=1e300, max_noise_ratio=min(ratio * factor, 1.0))
        with Estimator(cfg) as est:
            est.feed(As, ys)
            rc, phi, info = est.estimate()
        assert rc == expect, f"max_noise_ratio = {factor} x numpy's {ratio}: rc {rc} ({strerror(rc)})"
        assert info.noise_ratio == pytest.approx(ratio, rel=1e-8)
        if rc:
            assert not np.any(phi), "phi must be all zeros when not excited"
    # The default (0.5) refuses this data.
    with Estimator(make_config(method, 10, max_condition=1e300)) as est:
        est.feed(As, ys)
        assert est.estimate()[0] == LOADID_E_NOT_EXCITED
