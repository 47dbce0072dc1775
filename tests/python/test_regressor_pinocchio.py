"""Cross-check of loadid's regressor (eq. 6) and zeroing term (eqs. 7-9)
against Pinocchio's rigid-body regressor and Newton-Euler wrench.

See pin_model.py for the two convention mappings, (a) parameter order and
(b) spatial versus classical acceleration; the first tests below verify
those mappings from Pinocchio itself before they are used.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from conftest import add_zeroing, apply, regressor, with_offset
from pin_model import (
    PIN_TO_LOADID,
    body_regressor_loadid,
    phi_loadid,
    random_load,
    random_rotation,
    wrench,
)

N_STATES = 2500
TOL = 1e-12  # relative to max(norm, 1)
G = 9.81


def rel_err(x, ref) -> float:
    return float(np.linalg.norm(np.asarray(x) - np.asarray(ref)) / max(np.linalg.norm(ref), 1.0))


def random_state(rng):
    """A random state of the sensor frame: spec = a - g (gravity of 9.81 in a
    random direction plus a motion), w, alpha, and a nonzero linear velocity
    of the origin, which only Pinocchio needs (the wrench does not depend on it
    once the acceleration is converted)."""
    g_dir = random_rotation(rng)[:, 2]
    spec = G * g_dir + rng.normal(scale=5.0, size=3)
    w = rng.normal(scale=2.0, size=3)
    alpha = rng.normal(scale=15.0, size=3)
    v_lin = rng.normal(scale=1.5, size=3)
    return spec, w, alpha, v_lin


# --------------------------------------------------------------------------
# The mappings, verified from Pinocchio itself
# --------------------------------------------------------------------------
def test_pinocchio_parameter_order():
    """(a) toDynamicParameters is [m, mc, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] with the
    inertia about the frame origin; PIN_TO_LOADID gives eq. (5)'s order."""
    m = 2.0
    c = np.array([0.1, -0.2, 0.3])
    I_C = np.array([[1.0, 0.01, 0.02],
                    [0.01, 2.0, 0.03],
                    [0.02, 0.03, 3.0]])
    # Parallel-axis theorem (docs/INTERFACE.md): I_S = I_C + m (c.c E - c c^T).
    I_S = I_C + m * (c @ c * np.eye(3) - np.outer(c, c))
    pin_params = np.asarray(pin.Inertia(m, c, I_C).toDynamicParameters())
    expected_pin = [m, *(m * c), I_S[0, 0], I_S[0, 1], I_S[1, 1], I_S[0, 2], I_S[1, 2], I_S[2, 2]]
    np.testing.assert_allclose(pin_params, expected_pin, rtol=0, atol=1e-15)
    # loadid's eq. (5): [m, mcx, mcy, mcz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz].
    expected_loadid = [m, *(m * c), I_S[0, 0], I_S[0, 1], I_S[0, 2], I_S[1, 1], I_S[1, 2], I_S[2, 2]]
    np.testing.assert_allclose(pin_params[PIN_TO_LOADID], expected_loadid, rtol=0, atol=1e-15)
    # And the regressor is linear in exactly these parameters.
    rng = np.random.default_rng(11)
    v = pin.Motion(rng.normal(size=3), rng.normal(size=3))
    a = pin.Motion(rng.normal(size=3), rng.normal(size=3))
    I = pin.Inertia(m, c, I_C)
    np.testing.assert_allclose(np.asarray(pin.bodyRegressor(v, a)) @ pin_params,
                               (I * a + v.cross(I * v)).vector, rtol=1e-13, atol=1e-13)


def test_pinocchio_spatial_acceleration_convention():
    """(b) For a point mass at the origin, the force Pinocchio returns is
    m (a_lin + w x v_lin): its spatial linear acceleration is not the
    classical acceleration of the origin."""
    rng = np.random.default_rng(12)
    I = pin.Inertia(3.0, np.zeros(3), np.zeros((3, 3)))
    w, v_lin, a_lin = rng.normal(size=(3, 3))
    f = (I * pin.Motion(a_lin, np.zeros(3)) + pin.Motion(v_lin, w).cross(I * pin.Motion(v_lin, w)))
    np.testing.assert_allclose(f.linear, 3.0 * (a_lin + np.cross(w, v_lin)), rtol=1e-14, atol=1e-14)


# --------------------------------------------------------------------------
# Eq. (6) against Pinocchio
# --------------------------------------------------------------------------
def test_regressor_matches_pinocchio_body_regressor():
    rng = np.random.default_rng(20240601)
    worst_matrix = worst_wrench = worst_ne = 0.0
    for _ in range(N_STATES):
        spec, w, alpha, v_lin = random_state(rng)
        load = random_load(rng)
        A = regressor(spec, w, alpha)
        Y = body_regressor_loadid(spec, w, alpha, v_lin)  # columns in loadid order
        # The matrices themselves, column by column in eq. (5)'s order.
        e = rel_err(A, Y)
        worst_matrix = max(worst_matrix, e)
        assert e <= TOL, f"regressor differs from pinocchio by {e:.3e}\nA=\n{A}\nY=\n{Y}"
        # The wrench of a random load: loadid's A phi against Pinocchio's
        # Newton-Euler I a + v x* I v (independent of the regressor).
        phi = phi_loadid(load)
        y_ref = wrench(load, spec, w, alpha, v_lin)
        e = rel_err(A @ phi, y_ref)
        worst_wrench = max(worst_wrench, e)
        assert e <= TOL, f"A phi differs from pinocchio's wrench by {e:.3e}"
        # loadid_regressor_apply is the same product.
        e = rel_err(apply(A, phi), y_ref)
        worst_ne = max(worst_ne, e)
        assert e <= TOL
    print(f"\nworst relative error over {N_STATES} states: regressor {worst_matrix:.2e}, "
          f"A phi {worst_wrench:.2e}, apply {worst_ne:.2e}")


def test_skipping_the_acceleration_conversion_mismatches():
    """The mapping (b) is really exercised: feeding spec as Pinocchio's spatial
    linear acceleration (no w x v_lin correction) disagrees with loadid, by
    m (w x v_lin) in the force, whenever w x v_lin != 0; with v_lin = 0 the
    two accelerations coincide and the unconverted call agrees."""
    rng = np.random.default_rng(7)
    for _ in range(50):
        spec, w, alpha, v_lin = random_state(rng)
        load = random_load(rng)
        phi = phi_loadid(load)
        A = regressor(spec, w, alpha)
        y_lib = A @ phi
        y_wrong = wrench(load, spec, w, alpha, v_lin, convert=False)
        assert rel_err(y_lib, y_wrong) > 1e-3
        # The difference is exactly the term the conversion removes: Pinocchio
        # adds m (w x v_lin) to f and (m c) x (w x v_lin) to tau.
        wxv = np.cross(w, v_lin)
        np.testing.assert_allclose(y_wrong[:3] - y_lib[:3], phi[0] * wxv, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(y_wrong[3:] - y_lib[3:], np.cross(phi[1:4], wxv),
                                   rtol=1e-10, atol=1e-10)
        assert rel_err(A, body_regressor_loadid(spec, w, alpha, v_lin, convert=False)) > 1e-3
        # v_lin = 0: spatial and classical accelerations are equal.
        zero = np.zeros(3)
        assert rel_err(y_lib, wrench(load, spec, w, alpha, zero, convert=False)) <= TOL
        assert rel_err(A, body_regressor_loadid(spec, w, alpha, zero, convert=False)) <= TOL


def test_regressor_at_rest_reads_weight_upwards():
    """docs/INTERFACE.md: a load hanging still with z of S up reads f_z = +m 9.81;
    Pinocchio agrees when its acceleration is spec = a - g = [0 0 +9.81]."""
    load = pin.Inertia(1.7, np.array([0.02, -0.01, 0.05]), np.diag([0.01, 0.02, 0.03]))
    spec = np.array([0.0, 0.0, G])
    A = regressor(spec, np.zeros(3), np.zeros(3))
    y = A @ phi_loadid(load)
    y_ref = wrench(load, spec, np.zeros(3), np.zeros(3), np.zeros(3))
    np.testing.assert_allclose(y, y_ref, rtol=1e-14, atol=1e-14)
    assert y[2] == pytest.approx(1.7 * G, rel=1e-14)


# --------------------------------------------------------------------------
# Zeroing, eqs. (7)-(9)
# --------------------------------------------------------------------------
def test_zeroing_matches_pinocchio_zeroed_wrench():
    """y_zeroed = wrench(state) - wrench(still at the zeroing pose), where at
    the zeroing pose the load is at rest and its accelerometer reads
    spec = -g_init. loadid_regressor_add_zeroing(g_init, A(state)) must map
    phi onto exactly that, both as a matrix and as a wrench."""
    rng = np.random.default_rng(99)
    worst = 0.0
    for _ in range(N_STATES):
        spec, w, alpha, v_lin = random_state(rng)
        load = random_load(rng)
        g_init = G * random_rotation(rng)[:, 0]  # gravity in S at the zeroing pose
        phi = phi_loadid(load)
        A_offs = add_zeroing(regressor(spec, w, alpha), g_init)
        zero = np.zeros(3)
        # Pinocchio: moving state minus the still reading (v = 0, a = -g_init).
        y_ref = wrench(load, spec, w, alpha, v_lin) - wrench(load, -g_init, zero, zero, zero)
        e = rel_err(A_offs @ phi, y_ref)
        worst = max(worst, e)
        assert e <= TOL, f"zeroed wrench differs by {e:.3e}"
        Y_ref = (body_regressor_loadid(spec, w, alpha, v_lin)
                 - body_regressor_loadid(-g_init, zero, zero, zero))
        e = rel_err(A_offs, Y_ref)
        worst = max(worst, e)
        assert e <= TOL, f"zeroed regressor differs by {e:.3e}"
        # Eq. (8): the zeroing term touches only m and m c.
        np.testing.assert_array_equal(A_offs[:, 4:], regressor(spec, w, alpha)[:, 4:])
    print(f"\nworst relative error of the zeroed regressor/wrench: {worst:.2e}")


def test_with_offset_is_A_E6():
    rng = np.random.default_rng(3)
    spec, w, alpha, v_lin = random_state(rng)
    load = random_load(rng)
    A = regressor(spec, w, alpha)
    A16 = with_offset(A)
    np.testing.assert_array_equal(A16, np.hstack([A, np.eye(6)]))
    o = rng.normal(size=6)
    y_ref = wrench(load, spec, w, alpha, v_lin) + o
    phi16 = np.concatenate([phi_loadid(load), o])
    assert rel_err(apply(A16, phi16), y_ref) <= TOL
