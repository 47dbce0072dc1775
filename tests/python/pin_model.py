"""Pinocchio side of the cross-checks: random loads and states, the mapping of
Pinocchio's conventions onto loadid's, and the Newton-Euler wrench.

Conventions mapped here (each verified by a test in test_regressor_pinocchio.py):

(a) Parameter order. Pinocchio's ``Inertia.toDynamicParameters()`` returns
        [m, mc_x, mc_y, mc_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]      (pin 4.1.0)
    loadid's phi (eq. 5, docs/INTERFACE.md) is
        [m, mc_x, mc_y, mc_z, Ixx, Ixy, Ixz, Iyy, Iyz, Izz].
    Both hold the inertia about the frame origin (I = I_C + m S(c)^T S(c)),
    so only Iyy and Ixz swap places: loadid index 6 (Ixz) is pin index 7 and
    loadid index 7 (Iyy) is pin index 6. ``PIN_TO_LOADID`` is that
    permutation: phi_loadid = phi_pin[PIN_TO_LOADID], and the columns of
    Pinocchio's regressor reorder the same way, Y_loadid = Y_pin[:, PIN_TO_LOADID].

(b) Acceleration. ``pinocchio.bodyRegressor(v, a)`` gives the body wrench
    I a + v x* (I v) for the spatial velocity v = (v_lin, w) and the
    *spatial* acceleration a = (dv_lin/dt in the body frame, alpha). The
    linear part of a spatial acceleration is not the classical acceleration
    of the frame origin: classical = a_lin + w x v_lin. loadid's input is
    spec = a_classical - g (the accelerometer reading at the origin), so
        a_lin(spatial) = spec - w x v_lin.
    Gravity enters through Pinocchio's usual trick: a body in a gravity
    field g reads the same wrench as a body without gravity accelerated by
    -g, so the (classical) acceleration fed to Pinocchio is spec = a - g.

Both wrenches are [f; tau] with tau about the frame origin, in the body
(sensor) frame: Pinocchio's Force vector is [linear; angular], the same row
order as eq. (6).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

# loadid index j  <-  Pinocchio index PIN_TO_LOADID[j]
PIN_TO_LOADID = np.array([0, 1, 2, 3, 4, 5, 7, 6, 8, 9])


def random_rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    return pin.Quaternion(q[0], q[1], q[2], q[3]).toRotationMatrix()


def random_load(rng, mass_range=(0.2, 20.0), com_box=0.3) -> pin.Inertia:
    """A physically valid rigid body: m > 0, any COM, I_C from a random
    non-negative mass distribution along random principal axes, so it is
    positive definite and satisfies the triangle inequalities."""
    m = rng.uniform(*mass_range)
    c = rng.uniform(-com_box, com_box, size=3)
    # Second moments of the mass along the principal axes (>= 0) -> principal
    # moments [sy+sz, sx+sz, sx+sy]: triangle inequalities hold by construction.
    s = m * rng.uniform(0.0005, 0.02, size=3)
    principal = np.array([s[1] + s[2], s[0] + s[2], s[0] + s[1]])
    R = random_rotation(rng)
    I_C = R @ np.diag(principal) @ R.T
    return pin.Inertia(m, c, I_C)


def phi_loadid(inertia: pin.Inertia) -> np.ndarray:
    """loadid's phi (eq. 5) of a Pinocchio inertia, via the explicit permutation."""
    return np.asarray(inertia.toDynamicParameters())[PIN_TO_LOADID]


def spatial_motion(spec, w, alpha, v_lin, convert=True):
    """Pinocchio's spatial velocity and spatial acceleration for loadid's state.

    convert=False feeds spec as the spatial linear acceleration directly
    (wrong unless v_lin = 0 or w || v_lin); used to show that the mapping matters.
    """
    spec, w, alpha, v_lin = (np.asarray(x, dtype=float) for x in (spec, w, alpha, v_lin))
    v = pin.Motion(v_lin, w)
    a_lin = spec - np.cross(w, v_lin) if convert else spec
    a = pin.Motion(a_lin, alpha)
    return v, a


def body_regressor_loadid(spec, w, alpha, v_lin, convert=True) -> np.ndarray:
    """Pinocchio's bodyRegressor with its columns in loadid's phi order."""
    v, a = spatial_motion(spec, w, alpha, v_lin, convert)
    return np.asarray(pin.bodyRegressor(v, a))[:, PIN_TO_LOADID]


def wrench(inertia: pin.Inertia, spec, w, alpha, v_lin, convert=True) -> np.ndarray:
    """Newton-Euler wrench [f; tau] the load exerts on the sensor (Pinocchio):
    I a + v x* (I v), with the conversions above."""
    v, a = spatial_motion(spec, w, alpha, v_lin, convert)
    f = inertia * a + v.cross(inertia * v)
    return np.asarray(f.vector).copy()
