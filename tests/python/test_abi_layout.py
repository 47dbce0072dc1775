"""The ctypes mirrors of loadid_est_config_t and loadid_est_info_t match the C
header byte for byte: checked against offsetof() from a C compiler when one is
available, and against the documented defaults of loadid_est_config_default()
(which would land in the wrong fields if the layout were off)."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from conftest import (
    LIB,
    LOADID_MAX_PARAMS,
    METHOD_NAMES,
    METHOD_RTLS,
    METHOD_TLS_BATCH,
    Estimator,
    LoadidEstConfig,
    LoadidEstInfo,
    assert_layout_matches_c,
    config_default,
)

CFG_FIELDS = [name for name, _ in LoadidEstConfig._fields_]
INFO_FIELDS = [name for name, _ in LoadidEstInfo._fields_]


def test_struct_layout_matches_c_compiler(tmp_path):
    assert_layout_matches_c(tmp_path, "loadid/estimator.h",
                            [("loadid_est_config_t", LoadidEstConfig),
                             ("loadid_est_info_t", LoadidEstInfo)])


@pytest.mark.parametrize("n_params", [10, 16])
def test_config_default_lands_in_the_documented_fields(n_params):
    cfg = config_default(METHOD_RTLS, n_params)
    assert cfg.method == METHOD_RTLS and cfg.n_params == n_params
    assert list(cfg.row_sigma) == [1.0] * 6
    w = np.array(cfg.col_weight)
    assert w.shape == (LOADID_MAX_PARAMS + 1,)
    np.testing.assert_array_equal(w[: n_params + 1], 1.0)
    assert cfg.p0 == 1e6 and cfg.forgetting == 1.0
    assert cfg.rtls_init_samples == 2
    # The values of loadid_est_config_default() (estimator.cpp) in the double
    # build, as estimator.h documents them.
    eps = np.finfo(np.float64).eps
    assert cfg.rtls_eps == pytest.approx(64 * eps, rel=1e-12)
    assert cfg.rtls_ortho_tol == 1e-10
    assert cfg.batch_capacity == 4000
    assert cfg.max_condition == 1e6
    assert cfg.max_noise_ratio == 0.95
    np.testing.assert_array_equal(np.array(cfg.col_exact), 1.0)
    np.testing.assert_array_equal(np.array(cfg.col_measured), 0.0)
    np.testing.assert_array_equal(np.array(cfg.offset_cov), 0.0)
    np.testing.assert_array_equal(np.array(cfg.noise_sigma), 0.0)
    np.testing.assert_array_equal(np.array(cfg.noise_corr), 0.0)
    # The estimator keeps a copy that reads back identically through ctypes.
    cfg.p0 = 123.5
    cfg.batch_capacity = 77
    with Estimator(cfg) as est:
        back = est.config()
        for f in CFG_FIELDS:
            a, b = getattr(back, f), getattr(cfg, f)
            if isinstance(a, ctypes.Array):
                a, b = list(a), list(b)
            assert a == b, f
        assert back.p0 == 123.5 and back.batch_capacity == 77


def test_method_names_roundtrip():
    for m, name in METHOD_NAMES.items():
        assert LIB.loadid_method_name(m).decode() == name
        assert LIB.loadid_method_from_name(name.encode()) == m
    assert LIB.loadid_method_from_name(b"nope") < 0
    assert config_default(METHOD_TLS_BATCH, 16).n_params == 16
