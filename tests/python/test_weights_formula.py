"""loadid_est_weights_from_noise (estimator.h) against its formula, built
here from Pinocchio's regressor rather than from the library's code.

The formula (estimator.h, estimator.cpp): rows D = 1/sigma_f (force) and
1/sigma_tau (torque); column j's weight t_j = sqrt(6 / v_j), where v_j is
the summed noise variance of column j after D: each entry made of alpha
adds sigma_alpha^2, each of a - g sigma_spec^2, and each product of two
angular velocities q = 2 omega_typ^2 sigma_omega^2 (a first-order bound).

Which entries of a column hold alpha, a - g or omega products is counted
here numerically from pinocchio.bodyRegressor (pin_model.py), not from the
library. A Monte Carlo over noisy alpha and a - g then checks the premise
itself: the summed variance of D dA_j is 6 / t_j^2.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import METHOD_RTLS, config_default, weights_from_noise
from pin_model import body_regressor_loadid

NOISES = [  # sigma_f, sigma_tau, sigma_spec, sigma_alpha, sigma_omega, omega_typ
    (0.1, 0.005, 0.5, 5.0, 0.02, 2.0),
    (0.03, 0.0015, 0.15, 1.5, 0.001, 0.4),
    (1.0, 0.2, 0.05, 20.0, 0.1, 0.0),
]


def entry_counts():
    """(6, 10, 3) counts: whether regressor entry (row, column) changes with
    alpha, a - g or omega, by finite differences at random states."""
    rng = np.random.default_rng(7)
    dep = np.zeros((6, 10, 3), bool)
    for _ in range(5):
        spec, w, al = rng.normal(size=3) * 5, rng.normal(size=3), rng.normal(size=3) * 3
        base = body_regressor_loadid(spec, w, al, np.zeros(3))
        for k, (s, ww, a) in enumerate([(0, 0, 1), (1, 0, 0), (0, 1, 0)]):
            for i in range(3):
                e = np.eye(3)[i] * 1e-3
                d = body_regressor_loadid(spec + s * e, w + ww * e, al + a * e, np.zeros(3)) - base
                dep[:, :, k] |= np.abs(d) > 1e-9
    return dep


def formula_weights(counts, sf, st, ss, sa, sw, wt):
    q = 2.0 * wt ** 2 * sw ** 2
    per_entry = np.array([sa ** 2, ss ** 2, q])          # alpha, a - g, omega products
    row_var = np.array([sf] * 3 + [st] * 3) ** 2
    v = (counts * per_entry[None, None, :]).sum(2) / row_var[:, None]
    return np.sqrt(6.0 / v.sum(0))


def test_entry_counts_are_those_of_eq_6():
    dep = entry_counts()
    f, t = dep[:3].sum(0), dep[3:].sum(0)                 # (10, 3)
    # Force rows: m has a - g in all three; m c has alpha in two and omega
    # products in three; the inertia never reaches them.
    np.testing.assert_array_equal(f[0], [0, 3, 0])
    np.testing.assert_array_equal(f[1:4], [[2, 0, 3]] * 3)
    np.testing.assert_array_equal(f[4:], np.zeros((6, 3)))
    # Torque rows: m c has a - g in two; I_xx, I_yy, I_zz alpha in one and
    # omega in two; the products of inertia alpha in two and omega in three.
    np.testing.assert_array_equal(t[0], [0, 0, 0])
    np.testing.assert_array_equal(t[1:4], [[0, 2, 0]] * 3)
    for j in (4, 7, 9):
        np.testing.assert_array_equal(t[j], [1, 0, 2])
    for j in (5, 6, 8):
        np.testing.assert_array_equal(t[j], [2, 0, 3])


@pytest.mark.parametrize("noise", NOISES)
def test_weights_equal_the_formula(noise):
    cfg = weights_from_noise(config_default(METHOD_RTLS), *noise)
    want = formula_weights(entry_counts(), *noise)
    np.testing.assert_allclose(np.array(cfg.col_weight[:10]), want, rtol=1e-12)
    assert cfg.col_weight[10] == 1.0
    np.testing.assert_array_equal(np.array(cfg.row_sigma[:]), [noise[0]] * 3 + [noise[1]] * 3)


def test_weighted_columns_carry_the_wrench_column_noise():
    """Monte Carlo: noisy alpha and a - g (omega exact: the formula's omega
    term is a first-order bound, not an expectation) give every column of
    D dA a summed variance of 6 / t_j^2, the wrench column's 6 unit rows."""
    sf, st, ss, sa = 0.1, 0.005, 0.5, 5.0
    cfg = weights_from_noise(config_default(METHOD_RTLS), sf, st, ss, sa, 1e-12, 0.0)
    t = np.array(cfg.col_weight[:10])
    rng = np.random.default_rng(3)
    d = 1.0 / np.array([sf] * 3 + [st] * 3)
    n, acc = 4000, np.zeros(10)
    for _ in range(n):
        spec, w, al = rng.normal(size=3) * 5, rng.normal(size=3), rng.normal(size=3) * 3
        y0 = body_regressor_loadid(spec, w, al, np.zeros(3))
        y1 = body_regressor_loadid(spec + ss * rng.normal(size=3), w,
                                   al + sa * rng.normal(size=3), np.zeros(3))
        acc += (((y1 - y0) * d[:, None]) ** 2).sum(0)
    ratio = t ** 2 * (acc / n) / 6.0
    # Each column's sum is over 1 to 3 chi^2(1) terms: relative standard
    # error at most sqrt(2/4000) = 2.2 %; 7 % is 3 of them (a wrong entry
    # count is 33 % or more).
    print("t_j^2 var_j / 6:", np.round(ratio, 3))
    np.testing.assert_allclose(ratio, 1.0, atol=0.07)
