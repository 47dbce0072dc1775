"""Cross-check of the URDF loader (loadid/urdf.h) and the forward kinematics of
the sensor frame S (loadid/kinematics.h) against Pinocchio, which reads the
same URDF file on its own (pin.buildModelFromUrdf), and against the URDF text
parsed independently with xml.etree.

Conventions mapped here, each explicitly:

* Joint order. loadid's chain lists the movable joints from base_link to the
  sensor link; Pinocchio numbers the joints of the whole tree depth-first
  (side branches included). Every value goes through the joint's name:
  model.getJointId(name), then joints[id].idx_q / idx_v.
* Continuous joints have nq = 2 in Pinocchio (q = [cos, sin]) and nv = 1.
* Frames. loadid gives everything relative to base_link; Pinocchio relative to
  its universe, the URDF root (track7's root is `world`, above a tilted
  base_link). Orientation and position: bMs = oMb^-1 oMs. Velocities and
  accelerations: base_link is fixed in Pinocchio's universe (checked below),
  so motion relative to it is motion relative to the universe.
* pin.LOCAL gives a frame's velocity and acceleration in the frame's own axes;
  getFrameClassicalAcceleration's linear part is the classical acceleration
  of the frame origin (d2p/dt2), its angular part alpha = d(omega)/dt.
* Gravity is given in base_link's frame ([0, 0, -9.81], docs/INTERFACE.md), so in S
  it is R_bs^T g -- for track7 that is not the world's z.

The negative controls at the end show that the 1e-9 comparison is sensitive:
a 1e-6 perturbation of one joint origin, or a plausible wrong convention on
the Pinocchio side, fails it by orders of magnitude.
"""

from __future__ import annotations

import ctypes
import errno
import math
import os
import re
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from conftest import (
    SANITIZER_PRELOAD,
    LOADID_E_MODEL,
    LOADID_E_NONFINITE,
    LOADID_JOINT_PRISMATIC,
    LOADID_JOINT_REVOLUTE,
    LoadidChain,
    LoadidJointDesc,
    LoadidKinState,
    assert_layout_matches_c,
    Kinematics,
    REPO_ROOT,
    chain_check,
    kin_state_dict,
    load_urdf,
    urdf_library_path,
)

RX60 = REPO_ROOT / "host" / "config" / "robots" / "rx60.urdf"
URDF_DATA = REPO_ROOT / "tests" / "data" / "urdf"
TRACK7 = URDF_DATA / "track7.urdf"
UR5 = URDF_DATA / "ur5_jr3.urdf"
ROBOTS = {"rx60": RX60, "track7": TRACK7, "ur5": UR5}
BASE, SENSOR = "base_link", "ft_sensor"

N_SAMPLES = 1000
TOL = 1e-9
G_BASE = np.array([0.0, 0.0, -9.81])
QUANTITIES = ("rotation", "position", "omega", "alpha", "accel", "gravity", "spec")

# Typical robot motion: |qd| <= 3 rad/s, |qdd| <= 20 rad/s^2; prismatic
# joints 1.5 m/s and 10 m/s^2.
QD_MAX = {LOADID_JOINT_REVOLUTE: 3.0, LOADID_JOINT_PRISMATIC: 1.5}
QDD_MAX = {LOADID_JOINT_REVOLUTE: 20.0, LOADID_JOINT_PRISMATIC: 10.0}


# --------------------------------------------------------------------------
# The URDF read independently (xml.etree), for limits and expected chains
# --------------------------------------------------------------------------
def _floats(text, default):
    return np.array([float(x) for x in text.split()]) if text else np.array(default, float)


def rpy_matrix(rpy) -> np.ndarray:
    """URDF's fixed-axis roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), \
        math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def xml_chain(path, base=BASE, sensor=SENSOR):
    """The joints on the path base -> sensor, base first, as dicts with name,
    type, xyz, rot (4x4 origin), axis, lower, upper, velocity."""
    root = ET.parse(path).getroot()
    by_child = {}
    for j in root.findall("joint"):
        origin = j.find("origin")
        xyz = _floats(origin.get("xyz") if origin is not None else None, [0, 0, 0])
        rpy = _floats(origin.get("rpy") if origin is not None else None, [0, 0, 0])
        axis_el = j.find("axis")
        axis = _floats(axis_el.get("xyz") if axis_el is not None else None, [1, 0, 0])
        lim = j.find("limit")
        get = (lambda k, d: float(lim.get(k)) if lim is not None and lim.get(k) else d)
        jtype = j.get("type")
        if jtype == "continuous":
            lower, upper = -math.inf, math.inf
        else:
            lower, upper = get("lower", -math.inf), get("upper", math.inf)
        by_child[j.find("child").get("link")] = dict(
            name=j.get("name"), type=jtype, parent=j.find("parent").get("link"),
            xyz=xyz, rot=rpy_matrix(rpy), axis=axis / np.linalg.norm(axis),
            lower=lower, upper=upper, velocity=get("velocity", math.inf))
    path_joints, link = [], sensor
    while link != base:
        j = by_child[link]
        path_joints.append(j)
        link = j["parent"]
    return path_joints[::-1]


def expected_folded(path):
    """Movable joints of xml_chain with the fixed joints folded into the next
    transform (chain.h), plus the tip transform: [(joint, xyz, rot)], tip."""
    out = []
    T = np.eye(4)
    for j in xml_chain(path):
        M = np.eye(4)
        M[:3, :3], M[:3, 3] = j["rot"], j["xyz"]
        T = T @ M
        if j["type"] == "fixed":
            continue
        out.append((j, T[:3, 3].copy(), T[:3, :3].copy()))
        T = np.eye(4)
    return out, (T[:3, 3].copy(), T[:3, :3].copy())


def joint_type(urdf_type: str) -> int:
    return {"revolute": LOADID_JOINT_REVOLUTE, "continuous": LOADID_JOINT_REVOLUTE,
            "prismatic": LOADID_JOINT_PRISMATIC}[urdf_type]


# --------------------------------------------------------------------------
# Pinocchio side
# --------------------------------------------------------------------------
class PinReference:
    """The same URDF through Pinocchio; states of S relative to base_link."""

    def __init__(self, path, base=BASE, sensor=SENSOR):
        self.model = pin.buildModelFromUrdf(str(path))
        self.data = self.model.createData()
        for name in (base, sensor):
            assert self.model.existFrame(name), f"Pinocchio has no frame {name!r}"
        self.base_id = self.model.getFrameId(base)
        self.s_id = self.model.getFrameId(sensor)

    def configuration(self, names, q, qd, qdd, rng=None):
        """Pinocchio's (Q, V, A) with loadid's chain values put in by joint
        name; joints off the chain get random values (they must not matter)."""
        m = self.model
        Q, V, A = pin.neutral(m), np.zeros(m.nv), np.zeros(m.nv)
        if rng is not None:
            V[:] = rng.uniform(-1, 1, m.nv)
            A[:] = rng.uniform(-5, 5, m.nv)
            for jid in range(1, m.njoints):
                jm = m.joints[jid]
                if jm.nq == 1:
                    Q[jm.idx_q] = rng.uniform(-0.5, 0.5)
        for i, name in enumerate(names):
            assert m.existJointName(name), f"Pinocchio has no joint {name!r}"
            jid = m.getJointId(name)
            jm = m.joints[jid]
            assert jm.nv == 1, f"{name}: nv = {jm.nv}"
            if jm.nq == 1:
                Q[jm.idx_q] = q[i]
            elif jm.nq == 2:  # continuous: (cos q, sin q)
                Q[jm.idx_q], Q[jm.idx_q + 1] = math.cos(q[i]), math.sin(q[i])
            else:
                raise AssertionError(f"{name}: nq = {jm.nq}")
            V[jm.idx_v], A[jm.idx_v] = qd[i], qdd[i]
        return Q, V, A

    def state(self, names, q, qd, qdd, rng=None, *, frame=pin.LOCAL, classical=True,
              gravity_in_world=False) -> dict:
        m, d = self.model, self.data
        Q, V, A = self.configuration(names, q, qd, qdd, rng)
        pin.forwardKinematics(m, d, Q, V, A)
        pin.updateFramePlacements(m, d)
        oMb, oMs = d.oMf[self.base_id], d.oMf[self.s_id]
        bMs = oMb.actInv(oMs)
        R = np.array(bMs.rotation)
        v = pin.getFrameVelocity(m, d, self.s_id, frame)
        if classical:
            a = pin.getFrameClassicalAcceleration(m, d, self.s_id, frame)
        else:
            a = pin.getFrameAcceleration(m, d, self.s_id, frame)
        # Gravity: G_BASE is given in base_link's frame. (The wrong variant
        # takes the same numbers as world coordinates.)
        g_s = (np.array(oMs.rotation).T @ G_BASE) if gravity_in_world else R.T @ G_BASE
        accel = np.array(a.linear)
        return dict(rotation=R, position=np.array(bMs.translation), omega=np.array(v.angular),
                    alpha=np.array(a.angular), accel=accel, gravity=g_s, spec=accel - g_s)

    def base_motion(self, names, q, qd, qdd, rng=None):
        m, d = self.model, self.data
        Q, V, A = self.configuration(names, q, qd, qdd, rng)
        pin.forwardKinematics(m, d, Q, V, A)
        return (np.array(pin.getFrameVelocity(m, d, self.base_id, pin.LOCAL).vector),
                np.array(pin.getFrameClassicalAcceleration(m, d, self.base_id,
                                                           pin.LOCAL).vector))


# --------------------------------------------------------------------------
# Samples
# --------------------------------------------------------------------------
def chain_names(chain: LoadidChain):
    return [chain.joints[i].name.decode() for i in range(chain.num_joints)]


def random_samples(path, n, seed):
    """n random (q, qd, qdd) within the URDF's position limits (continuous
    joints anywhere in [-pi, pi]), from the URDF text, not from the loader."""
    rng = np.random.default_rng(seed)
    movable = [j for j in xml_chain(path) if j["type"] != "fixed"]
    lo = np.array([-math.pi if j["type"] == "continuous" else j["lower"] for j in movable])
    hi = np.array([math.pi if j["type"] == "continuous" else j["upper"] for j in movable])
    vmax = np.array([QD_MAX[joint_type(j["type"])] for j in movable])
    amax = np.array([QDD_MAX[joint_type(j["type"])] for j in movable])
    for _ in range(n):
        yield (rng.uniform(lo, hi), rng.uniform(-vmax, vmax), rng.uniform(-amax, amax), rng)


def max_errors(chain, ref: PinReference, samples, **ref_kwargs) -> dict:
    names = chain_names(chain)
    worst = {k: 0.0 for k in QUANTITIES}
    with Kinematics(chain, G_BASE) as kin:
        for q, qd, qdd, rng in samples:
            c = kin.eval(q, qd, qdd)
            p = ref.state(names, q, qd, qdd, rng, **ref_kwargs)
            for k in QUANTITIES:
                worst[k] = max(worst[k], float(np.max(np.abs(c[k] - p[k]))))
    return worst


@pytest.fixture(scope="module")
def loaded(urdf_lib):
    """Both shipped robots through the C loader: {name: LoadidChain}."""
    out = {}
    for name, path in ROBOTS.items():
        rc, chain, msg = load_urdf(urdf_lib, path, BASE, SENSOR)
        assert rc == 0, f"{path}: rc {rc}: {msg}"
        out[name] = chain
    return out


# --------------------------------------------------------------------------
# ABI: the ctypes mirrors match the headers
# --------------------------------------------------------------------------
def test_struct_layout_matches_c_compiler(tmp_path):
    assert_layout_matches_c(tmp_path, "loadid/kinematics.h",
                            [("loadid_joint_desc_t", LoadidJointDesc),
                             ("loadid_chain_t", LoadidChain),
                             ("loadid_kin_state_t", LoadidKinState)])


# --------------------------------------------------------------------------
# The loader against the URDF text
# --------------------------------------------------------------------------
@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_loader_chain_matches_urdf_text(loaded, robot):
    chain = loaded[robot]
    assert chain.base_link.decode() == BASE and chain.sensor_link.decode() == SENSOR
    assert chain_check(chain) == 0
    folded, (tip_xyz, tip_rot) = expected_folded(ROBOTS[robot])
    assert chain.num_joints == len(folded) == {"rx60": 6, "track7": 7, "ur5": 6}[robot]
    for i, (j, xyz, rot) in enumerate(folded):
        d = chain.joints[i]
        assert d.name.decode() == j["name"], i
        assert d.type == joint_type(j["type"]), j["name"]
        assert d.lower == j["lower"] and d.upper == j["upper"], j["name"]
        assert d.velocity == j["velocity"], j["name"]
        np.testing.assert_allclose(d.axis[:], j["axis"], rtol=0, atol=1e-15, err_msg=j["name"])
        # Folded fixed transforms: origin of this joint in the previous
        # movable joint's child frame (rpy converted here, independently).
        np.testing.assert_allclose(d.origin_xyz[:], xyz, rtol=0, atol=1e-14, err_msg=j["name"])
        np.testing.assert_allclose(np.reshape(d.origin_rot[:], (3, 3)), rot, rtol=0, atol=1e-14,
                                   err_msg=j["name"])
    np.testing.assert_allclose(chain.tip_xyz[:], tip_xyz, rtol=0, atol=1e-14)
    np.testing.assert_allclose(np.reshape(chain.tip_rot[:], (3, 3)), tip_rot, rtol=0, atol=1e-14)


def test_track7_has_the_awkward_features(loaded):
    """The test robot really has what it is meant to exercise."""
    root = ET.parse(TRACK7).getroot()
    children = {j.find("child").get("link") for j in root.findall("joint")}
    roots = [l.get("name") for l in root.findall("link") if l.get("name") not in children]
    assert roots == ["world"]  # base_link is not the root
    types = [j["type"] for j in xml_chain(TRACK7)]
    assert types[0] == "fixed" and types[-2:] == ["fixed", "fixed"]
    assert "continuous" in types and "prismatic" in types
    i4 = [j["name"] for j in xml_chain(TRACK7)].index("joint_4")
    assert xml_chain(TRACK7)[i4 - 1]["type"] == "fixed"  # folded in the middle
    ref = PinReference(TRACK7)
    # Pinocchio numbers the branch joint camera_pan between joint_3 and joint_4.
    assert list(ref.model.names)[1:6] == ["joint_1", "joint_2", "joint_3", "camera_pan",
                                          "joint_4"]
    assert ref.model.joints[ref.model.getJointId("joint_5")].nq == 2  # continuous


# --------------------------------------------------------------------------
# Kinematics against Pinocchio
# --------------------------------------------------------------------------
@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_pinocchio_base_link_is_fixed(loaded, robot):
    ref = PinReference(ROBOTS[robot])
    names = chain_names(loaded[robot])
    for q, qd, qdd, rng in random_samples(ROBOTS[robot], 20, seed=3):
        v, a = ref.base_motion(names, q, qd, qdd, rng)
        assert np.all(v == 0) and np.all(a == 0)


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_kinematics_match_pinocchio(loaded, robot):
    chain = loaded[robot]
    with Kinematics(chain, G_BASE) as kin:
        assert kin.n == chain.num_joints
    worst = max_errors(chain, PinReference(ROBOTS[robot]),
                       random_samples(ROBOTS[robot], N_SAMPLES, seed=2024))
    summary = ", ".join(f"{k} {v:.1e}" for k, v in worst.items())
    print(f"\n{robot}: max abs error over {N_SAMPLES} states: {summary}")
    assert all(v <= TOL for v in worst.values()), f"{robot}: {summary}"


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_null_rates_mean_rest(loaded, robot):
    """qd = qdd = NULL is the robot at rest: omega = alpha = accel = 0 and the
    specific force is -g (in S), as Pinocchio has it for zero rates."""
    chain = loaded[robot]
    ref = PinReference(ROBOTS[robot])
    names = chain_names(chain)
    zero = np.zeros(chain.num_joints)
    with Kinematics(chain, G_BASE) as kin:
        for q, _, _, _ in random_samples(ROBOTS[robot], 50, seed=7):
            c = kin.eval(q)
            p = ref.state(names, q, zero, zero)
            for k in QUANTITIES:
                np.testing.assert_allclose(c[k], p[k], rtol=0, atol=TOL, err_msg=k)
            assert np.all(c["omega"] == 0) and np.all(c["alpha"] == 0)
            assert np.all(c["accel"] == 0)
            np.testing.assert_allclose(np.linalg.norm(c["spec"]), 9.81, rtol=1e-14)


def test_rx60_zero_pose():
    """At q = 0 the RX60 stands straight up: S 0.341 + 0.290 + 0.310 + 0.065
    + 0.035 m above the base, 0.049 m to the side, axes parallel to the base."""
    p = PinReference(RX60).state([f"joint_{i}" for i in range(1, 7)], np.zeros(6), np.zeros(6),
                                 np.zeros(6))
    np.testing.assert_allclose(p["position"], [0, 0.049, 1.041], atol=1e-15)
    np.testing.assert_allclose(p["rotation"], np.eye(3), atol=1e-15)


def test_nonfinite_input_is_rejected_and_leaves_output(loaded):
    chain = loaded["track7"]
    with Kinematics(chain, G_BASE) as kin:
        q = np.linspace(0.1, 0.7, chain.num_joints)
        rc, st = kin.eval_raw(q, q, q)
        assert rc == 0
        before = kin_state_dict(st)
        for which in range(3):
            args = [q.copy(), q.copy(), q.copy()]
            args[which][2] = np.nan
            rc, st = kin.eval_raw(*args, out=st)
            assert rc == LOADID_E_NONFINITE, which
            after = kin_state_dict(st)
            for k in QUANTITIES:
                np.testing.assert_array_equal(after[k], before[k])


def test_chain_check_rejects_a_broken_chain(loaded):
    chain = LoadidChain.from_buffer_copy(loaded["rx60"])
    assert chain_check(chain) == 0
    chain.joints[2].axis[0] = 1e-3  # no longer a unit axis
    assert chain_check(chain) == -errno.EINVAL
    chain = LoadidChain.from_buffer_copy(loaded["rx60"])
    chain.num_joints = 0
    assert chain_check(chain) == -errno.EINVAL


# --------------------------------------------------------------------------
# Rejections
# --------------------------------------------------------------------------
_ISOLATED = r"""
import ctypes, sys
lib = ctypes.CDLL(sys.argv[1])
f = lib.loadid_urdf_load_file
f.restype = ctypes.c_int
f.argtypes = [ctypes.c_char_p] * 3 + [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t]
chain = ctypes.create_string_buffer(int(sys.argv[5]))
err = ctypes.create_string_buffer(512)
rc = f(sys.argv[2].encode(), sys.argv[3].encode(), sys.argv[4].encode(), chain, err, 512)
print(rc)
print(err.value.decode(errors="replace"))
"""


def _rss_bytes(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def load_isolated(path, base=BASE, sensor=SENSOR, timeout=20.0, max_rss=1 << 30):
    """loadid_urdf_load_file in a child process, so that a loader that hangs
    (walking up a loop forever, growing memory as it goes) or crashes fails
    this test instead of blocking, starving or killing the whole run. The
    child is killed after `timeout` seconds or once it holds `max_rss` bytes
    (polled; an address-space rlimit would break sanitizer builds).
    Returns (rc, message)."""
    args = [sys.executable, "-c", _ISOLATED, urdf_library_path(), str(path), base, sensor,
            str(ctypes.sizeof(LoadidChain))]
    with subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          env=dict(os.environ, **SANITIZER_PRELOAD)) as proc:
        t_end = time.monotonic() + timeout
        why = None
        while proc.poll() is None:
            if time.monotonic() > t_end:
                why = f"did not return within {timeout} s"
            elif _rss_bytes(proc.pid) > max_rss:
                why = f"grew beyond {max_rss >> 20} MiB"
            if why:
                proc.kill()
                proc.communicate()
                pytest.fail(f"loadid_urdf_load_file({path.name}) {why} (walking up a "
                            "kinematic loop forever?)")
            time.sleep(0.02)
        out, err = proc.communicate()
    assert proc.returncode == 0, f"{path.name}: loader process died: {proc.returncode} " \
                                 f"{err[-2000:]}"
    lines = out.splitlines()
    return int(lines[0]), "\n".join(lines[1:])


# file -> what the message must mention (case-insensitive regex)
BAD_FILES = {
    "bad_no_sensor.urdf": r"'ft_sensor'",
    "bad_loop.urdf": r"loop|cycl|parent",
    "bad_loop_no_root.urdf": r"loop|cycl|parent|root",
    "bad_no_movable.urdf": r"movable",
    "bad_floating.urdf": r"floating",
    "bad_xml.urdf": r"pars|xml|not a valid urdf",
}


def test_every_bad_file_has_an_expectation():
    assert sorted(p.name for p in URDF_DATA.glob("bad_*.urdf")) == sorted(BAD_FILES)


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_urdf_is_rejected_with_its_cause(urdf_lib, name):
    path = URDF_DATA / name
    rc, msg = load_isolated(path)
    assert rc == LOADID_E_MODEL, f"{name}: rc {rc}, message {msg!r}"
    assert str(path) in msg, f"{name}: the message does not name the file: {msg!r}"
    assert re.search(BAD_FILES[name], msg, re.IGNORECASE), f"{name}: {msg!r}"
    assert "\n" not in msg.strip(), f"{name}: not one line: {msg!r}"


def test_missing_file_is_enoent(urdf_lib, tmp_path):
    path = tmp_path / "no_such_robot.urdf"
    rc, _, msg = load_urdf(urdf_lib, path)
    assert rc == -errno.ENOENT, msg
    assert str(path) in msg


def test_base_not_an_ancestor_of_sensor(urdf_lib):
    rc, _, msg = load_urdf(urdf_lib, RX60, base_link=SENSOR, sensor_link=BASE)
    assert rc == LOADID_E_MODEL, msg
    assert re.search(r"ancestor", msg, re.IGNORECASE), msg
    # A base on a side branch is not an ancestor either.
    rc, _, msg = load_urdf(urdf_lib, TRACK7, base_link="camera_link", sensor_link=SENSOR)
    assert rc == LOADID_E_MODEL and "ancestor" in msg, msg


def test_unknown_link_names_are_named(urdf_lib):
    rc, _, msg = load_urdf(urdf_lib, RX60, base_link="no_base")
    assert rc == LOADID_E_MODEL and "no_base" in msg, msg
    rc, _, msg = load_urdf(urdf_lib, RX60, sensor_link="no_sensor")
    assert rc == LOADID_E_MODEL and "no_sensor" in msg, msg


def test_base_below_the_root_and_sensor_mid_chain(urdf_lib):
    """Any base/sensor pair along a path works: here world -> link_5."""
    rc, chain, msg = load_urdf(urdf_lib, TRACK7, base_link="world", sensor_link="link_5")
    assert rc == 0, msg
    assert chain_names(chain) == [f"joint_{i}" for i in range(1, 6)]


# --------------------------------------------------------------------------
# Negative controls: the comparison above can fail
# --------------------------------------------------------------------------
def _perturbed(tmp_path, src, old, new):
    text = src.read_text()
    assert text.count(old) == 1, old
    out = tmp_path / src.name
    out.write_text(text.replace(old, new))
    return out


@pytest.mark.parametrize("robot,old,new,must_fail", [
    ("rx60", 'xyz="0 0.049 0.290"', 'xyz="0 0.049 0.290001"', True),      # 1e-6 m
    ("track7", 'rpy="0.4 0.5 -0.6"', 'rpy="0.4 0.500001 -0.6"', True),    # 1e-6 rad
    # Above base_link (world -> base_link): nothing relative to base_link
    # may depend on it, so the comparison must still pass.
    ("track7", 'rpy="0.1 -0.2 0.3"', 'rpy="0.1 -0.200001 0.3"', False),
])
def test_a_micro_perturbed_model_fails_the_comparison(urdf_lib, tmp_path, robot, old, new,
                                                      must_fail):
    """The C side reads a copy with one origin moved by 1e-6; Pinocchio reads
    the original. The 1e-9 comparison must fail by a wide margin."""
    path = _perturbed(tmp_path, ROBOTS[robot], old, new)
    rc, chain, msg = load_urdf(urdf_lib, path)
    assert rc == 0, msg
    worst = max_errors(chain, PinReference(ROBOTS[robot]),
                       random_samples(ROBOTS[robot], 100, seed=5))
    if must_fail:
        assert max(worst.values()) > 100 * TOL, worst
    else:
        assert max(worst.values()) <= TOL, worst


@pytest.mark.parametrize("robot,wrong,quantity", [
    ("rx60", dict(frame=pin.WORLD), "omega"),                     # world axes, not S
    ("rx60", dict(frame=pin.LOCAL_WORLD_ALIGNED), "alpha"),
    ("rx60", dict(classical=False), "accel"),                     # spatial, not classical
    ("track7", dict(classical=False), "spec"),
    ("track7", dict(gravity_in_world=True), "gravity"),           # g in world, not base
])
def test_a_wrong_convention_fails_the_comparison(loaded, robot, wrong, quantity):
    worst = max_errors(loaded[robot], PinReference(ROBOTS[robot]),
                       random_samples(ROBOTS[robot], 100, seed=9), **wrong)
    assert worst[quantity] > 1e-3, worst
