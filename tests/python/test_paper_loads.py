"""The paper's test loads o2 and o3 of loadid-study (tools/study/loadid_study.py,
BLOCKS: steel blocks on the sensor's mounting face, off its axis) against an
independent computation: Pinocchio's Inertia.FromBox of each block (mass from
the density and the edges, computed here), moved into S by an SE3 placement
(Pinocchio's se3 action on the spatial inertia), summed; phi read with
toDynamicParameters through pin_model's explicit permutation. Also what the
paper says of them (sec. V.A, Fig. 5): steel, 1 to 1.6 kg; o2 two identical
blocks stacked; mounted off-centre."""

from __future__ import annotations

import math
import pathlib
import sys

import numpy as np
import pinocchio as pin

from pin_model import phi_loadid

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "tools" / "study"))
import loadid_study  # noqa: E402

STEEL = 7850.0  # kg/m^3


def rotation(rpy):
    """URDF's fixed-axis roll-pitch-yaw, by Pinocchio's own conversion."""
    return pin.rpy.rpyToMatrix(*rpy)


def phi_pinocchio(blocks) -> np.ndarray:
    total = pin.Inertia.Zero()
    for (a, b, c), centre, rpy in blocks:
        body = pin.Inertia.FromBox(STEEL * a * b * c, a, b, c)   # about its centre, own axes
        total += pin.SE3(rotation(rpy), np.array(centre, float)).act(body)
    return phi_loadid(total)


def test_blocks_match_pinocchio():
    assert set(loadid_study.BLOCKS) == {"o2", "o3"}
    for name, (_, blocks) in loadid_study.BLOCKS.items():
        want = phi_pinocchio(blocks)
        got = loadid_study.load_phi(name)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15, err_msg=name)


def test_blocks_are_what_the_paper_describes():
    o2 = loadid_study.BLOCKS["o2"][1]
    # o2: two identical blocks, stacked (one on the other along z, touching).
    assert len(o2) == 2 and o2[0][0] == o2[1][0] and o2[0][2] == o2[1][2]
    (_, _, h), lower, upper = o2[0][0], np.array(o2[0][1]), np.array(o2[1][1])
    np.testing.assert_allclose(upper - lower, [0, 0, h], atol=1e-15)
    for name, (_, blocks) in loadid_study.BLOCKS.items():
        phi = loadid_study.load_phi(name)
        m, c = phi[0], phi[1:4] / phi[0]
        assert 1.0 <= m <= 1.6, (name, m)
        assert math.hypot(c[0], c[1]) > 0.02, (name, c)          # off the sensor's axis
        # On the mounting face: the lowest corner of every block at z = 0 or
        # above, and the lowest of all exactly at 0.
        lows = []
        for dims, centre, rpy in blocks:
            corners = np.array([[sx * dims[0], sy * dims[1], sz * dims[2]]
                                for sx in (-.5, .5) for sy in (-.5, .5) for sz in (-.5, .5)])
            lows.append((corners @ rotation(rpy).T + centre)[:, 2].min())
        assert min(lows) == 0.0 or abs(min(lows)) < 1e-15, (name, lows)
        # Every element of phi is far from 0, so eq. (37)'s relative error
        # is meaningful for each.
        assert np.all(np.abs(phi[4:]) > 1e-4) and np.all(np.abs(phi[1:4]) > 1e-2), (name, phi)
