"""The LCM types of docs/INTERFACE.md (proto/*.lcm) through lcm-gen's C and Python
output.

* C and Python agree byte for byte: tests/tools/lcm_encode_samples (the
  lcm-gen C code, path in LOADID_LCM_ENCODE) encodes one instance of each
  type; the same instances are built here with the lcm-gen Python package
  (LOADID_LCM_PYTHON_DIR) and must encode to the same bytes, fingerprint
  included, and decode the C bytes back to the same fields; the constants
  agree too.
* The .lcm files say what the interface document says: the LCM block of
  docs/INTERFACE.md (the one fenced block that starts with
  "package loadid;") goes through lcm-gen (LOADID_LCM_GEN) here and every
  type must have the fingerprint, fields and constants of the build's
  types. The document is part of the repository, so it is never skipped.
* An event log written and read with the `lcm` package carries a
  joint_state_t, as lcm.log in a recording does.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import pathlib
import re
import shutil
import subprocess

import pytest

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
TYPES = ["joint_state_t", "command_t", "estimate_t", "wrench_t", "status_t", "load_model_t"]


@pytest.fixture(scope="module")
def c_output():
    """{type: (fingerprint bytes, message bytes)}, {(type, NAME): value}."""
    exe = os.environ.get("LOADID_LCM_ENCODE")
    if not exe or not os.path.isfile(exe):
        pytest.fail("LOADID_LCM_ENCODE must name the lcm_encode_samples program (ctest sets it)")
    out = subprocess.run([exe], capture_output=True, text=True, check=True, timeout=60).stdout
    msgs, consts = {}, {}
    for line in out.splitlines():
        f = line.split()
        if f[0] == "const":
            consts[(f[1], f[2])] = int(f[3])
        else:
            msgs[f[0]] = (bytes.fromhex(f[1]), bytes.fromhex(f[2]))
    assert sorted(msgs) == sorted(TYPES)
    return msgs, consts


def python_instances(t):
    """The instances of lcm_encode_samples.c, field for field."""
    js = t.joint_state_t()
    js.utime = 1700000000123456
    js.num_joints = 3
    js.position = [0.1, -0.2, 0.3]
    js.setpoint = [0.11, -0.21, 0.31]

    cmd = t.command_t()
    cmd.utime = 42
    cmd.action = t.command_t.START
    cmd.load_name = "o1 gripper"

    est = t.estimate_t()
    est.utime = 7
    est.samples = 1500
    est.method = t.estimate_t.RTLS
    est.state = t.estimate_t.DONE
    est.load_name = "o1"
    est.phi = [i + 0.5 for i in range(10)]
    est.offset = [-0.25 * i for i in range(6)]
    est.mass = 1.25
    est.com = [0.01, -0.02, 0.03]
    est.inertia_com = [0.001 * (i + 1) for i in range(6)]
    est.condition_number = 12.5
    est.sigma_min = 0.0625
    est.physically_consistent = True

    w = t.wrench_t()
    w.utime = -1
    w.force = [1.0, 2.0, 3.0]
    w.torque = [-0.5, 0.25, 0.125]

    st = t.status_t()
    st.utime = 99
    st.state = 2
    st.samples_ok = 1000
    st.frames_bad = 3
    st.samples_incomplete = 4
    st.samples_saturated = 5
    st.sequence_gaps = 6
    st.joint_msgs_bad = 7
    st.loop_us_p50 = 12.5
    st.loop_us_p99 = 40.25
    st.loop_us_max = 99.75

    lm = t.load_model_t()
    lm.utime = 8
    lm.method = t.estimate_t.REFINED
    lm.load_name = "o1 model"
    lm.identified = t.load_model_t.MASS | t.load_model_t.COM
    lm.projected = True
    lm.phi = [0.75 - i for i in range(10)]
    lm.phi_std = [0.015625 * (i + 1) for i in range(10)]
    lm.mass = 0.75
    lm.com = [-0.125, 0.25, 0.5]
    lm.inertia_com = [0.002 * (6 - i) for i in range(6)]
    return {"joint_state_t": js, "command_t": cmd, "estimate_t": est, "wrench_t": w,
            "status_t": st, "load_model_t": lm}


def fields(msg) -> dict:
    out = {}
    for name in msg.__slots__:
        v = getattr(msg, name)
        out[name] = list(v) if isinstance(v, (list, tuple)) else v
    return out


@pytest.mark.parametrize("type_name", TYPES)
def test_c_and_python_bytes_match(lcmtypes, c_output, type_name):
    msgs, _ = c_output
    fingerprint, c_bytes = msgs[type_name]
    cls = getattr(lcmtypes, type_name)
    # LCM's fingerprint: the first 8 bytes of every message, the same hash in
    # C and Python.
    assert cls._get_packed_fingerprint() == fingerprint
    assert c_bytes[:8] == fingerprint
    py_msg = python_instances(lcmtypes)[type_name]
    assert py_msg.encode() == c_bytes
    decoded = cls.decode(c_bytes)
    want = fields(py_msg)
    got = fields(decoded)
    if type_name == "estimate_t":
        got["physically_consistent"] = bool(got["physically_consistent"])
    if type_name == "load_model_t":
        got["projected"] = bool(got["projected"])
    assert got == want
    # A message of another type is refused, not misread.
    other = msgs["wrench_t" if type_name != "wrench_t" else "status_t"][1]
    with pytest.raises(ValueError):
        cls.decode(other)


def test_constants_match(lcmtypes, c_output):
    _, consts = c_output
    assert len(consts) == 18
    for (type_name, name), value in consts.items():
        assert getattr(getattr(lcmtypes, type_name), name) == value


@pytest.mark.parametrize("n", [0, 1, 6, 7, 16])
def test_joint_state_round_trip(lcmtypes, n):
    js = lcmtypes.joint_state_t()
    js.utime = 1_700_000_000_000_000 + n
    js.num_joints = n
    js.position = [0.1 * i - 0.3 for i in range(n)]
    js.setpoint = [-0.05 * i + 1e-9 for i in range(n)]
    data = js.encode()
    assert len(data) == 8 + 8 + 4 + 2 * 8 * n  # fingerprint, utime, num_joints, arrays
    back = lcmtypes.joint_state_t.decode(data)
    assert back.utime == js.utime and back.num_joints == n
    assert list(back.position) == js.position and list(back.setpoint) == js.setpoint


def test_event_log_round_trip(lcmtypes, tmp_path):
    lcm = pytest.importorskip("lcm")
    path = str(tmp_path / "lcm.log")
    log = lcm.EventLog(path, "w", overwrite=True)
    for k in range(3):
        js = lcmtypes.joint_state_t()
        js.utime = 1_700_000_000_000_000 + 1000 * k
        js.num_joints = 6
        js.position = [0.01 * k] * 6
        js.setpoint = [0.02 * k] * 6
        log.write_event(js.utime, "LOADID_JOINTS", js.encode())
    cmd = lcmtypes.command_t()
    cmd.utime = 1_700_000_000_002_500
    cmd.action = lcmtypes.command_t.ZERO
    cmd.load_name = ""
    log.write_event(cmd.utime, "LOADID_COMMAND", cmd.encode())
    log.close()

    log = lcm.EventLog(path, "r")
    events = list(log)
    log.close()
    assert [e.channel for e in events] == ["LOADID_JOINTS"] * 3 + ["LOADID_COMMAND"]
    for k, e in enumerate(events[:3]):
        js = lcmtypes.joint_state_t.decode(e.data)
        assert e.timestamp == js.utime == 1_700_000_000_000_000 + 1000 * k
        assert list(js.position) == [0.01 * k] * 6
    assert lcmtypes.command_t.decode(events[3].data).action == 1


INTERFACE_MD = REPO_ROOT / "docs" / "INTERFACE.md"


def test_lcm_files_match_interface(lcmtypes, tmp_path):
    assert INTERFACE_MD.is_file(), f"{INTERFACE_MD} is missing"
    text = INTERFACE_MD.read_text()
    blocks = re.findall(r"^```[^\n]*\n(package loadid;\n.*?)^```", text, flags=re.S | re.M)
    assert len(blocks) == 1, (
        f"{INTERFACE_MD} must hold exactly one fenced block starting with 'package loadid;', "
        f"found {len(blocks)}")
    lcm_gen = os.environ.get("LOADID_LCM_GEN") or shutil.which("lcm-gen")
    if not lcm_gen:
        pytest.fail("lcm-gen not found (LOADID_LCM_GEN)")
    src = tmp_path / "interface.lcm"
    src.write_text(blocks[0])
    out = tmp_path / "py"
    subprocess.run([lcm_gen, "--python", "--ppath", str(out), str(src)], check=True, timeout=60)
    generated = sorted(p.stem for p in (out / "loadid").glob("*_t.py"))
    assert generated == sorted(TYPES)
    for type_name in TYPES:
        spec = importlib.util.spec_from_file_location(f"interface_{type_name}",
                                                      out / "loadid" / f"{type_name}.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        want = getattr(mod, type_name)
        got = getattr(lcmtypes, type_name)
        assert got.__slots__ == want.__slots__, type_name
        assert got._get_packed_fingerprint() == want._get_packed_fingerprint(), type_name
        consts = {k: v for k, v in vars(want).items() if k.isupper()}
        assert {k: v for k, v in vars(got).items() if k.isupper()} == consts, type_name
