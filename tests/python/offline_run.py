"""Running loadidd --offline from the tests (docs/INTERFACE.md), and the
recordings they make for it: slow and real-data-like motion, lcm.log's
events. Shared by test_offline.py and test_joint_stamps.py.
"""

from __future__ import annotations

import json
from pathlib import Path
import subprocess

import numpy as np

from accuracy import BOUNDS, assert_accuracy
from recordings import program, read_truth, simulate


def write_config(path, text="estimation:\n  duration_s: 1.5\n"):
    path.write_text(text)
    return path


def offline(config, rec, *extra, check=True):
    r = subprocess.run([program("LOADIDD_EXE"), "--config", str(config), "--offline", str(rec),
                        *[str(e) for e in extra]], capture_output=True, text=True, timeout=300)
    if check:
        assert r.returncode == 0, r.stderr
        return (json.loads(r.stdout) if r.stdout else None), r.stderr
    return r


def truth_phi(rec):
    truth = read_truth(rec)
    return np.array(json.loads(truth["load.phi"])), truth


def physical(phi):
    """Mass, COM and inertia about the COM, computed here (parallel axes)."""
    m, c = phi[0], phi[1:4] / phi[0]
    I = np.array([[phi[4], phi[5], phi[6]], [phi[5], phi[7], phi[8]], [phi[6], phi[8], phi[9]]])
    Ic = I - m * (c @ c * np.eye(3) - np.outer(c, c))
    return m, c, Ic[np.triu_indices(3)]


def assert_close_to_truth(est, phi, bounds="default"):
    assert_accuracy(est, phi, **BOUNDS[bounds])
    # The reported physical values are those of the reported phi.
    em, ec, eic = physical(np.array(est["phi"]))
    assert abs(em - est["mass"]) <= 1e-12 and np.allclose(ec, est["com"], atol=1e-12)
    assert np.allclose(eic, est["inertia_com"], atol=1e-12)


SLOW = "trajectory:\n  base_frequency: 0.1\n  harmonics: 4\n  max_frequency: 0.4\n"
UR5 = Path(__file__).resolve().parents[1] / "data" / "urdf" / "ur5_jr3.urdf"


def slow_recording(tmp_path, robot, seed, simulation, *extra):
    """A recording of slow motion: a trajectory of 0.1-0.4 Hz designed for
    the robot section robot ("" the RX60) and seed, simulated with the
    simulation section given (and loadid-sim's extra arguments)."""
    slow = robot + SLOW
    traj_cfg = write_config(tmp_path / "traj.yaml", slow + f"  seed: {seed}\n")
    (tmp_path / "traj").mkdir()
    subprocess.run([program("LOADID_TRAJ_EXE"), "--config", str(traj_cfg), "--monte-carlo", "300",
                    "--candidates", "1", "--max-evals", "800", "--quiet",
                    "--out", str(tmp_path / "traj" / "traj.yaml")], check=True, timeout=300)
    sim = write_config(tmp_path / "sim.yaml", slow + simulation)
    return simulate(tmp_path / "rec", tmp_path / "traj", "--config", sim, "--seed", str(seed),
                    *extra)


DRIFT = "[0.05, -0.04, 0.03, 0.002, -0.002, 0.001]"


def real_data_like(tmp_path, robot="", seed=1, drift=DRIFT):
    """A recording like a slow real robot's and the four methods' results
    on it (the offset estimated): a trajectory of 0.1-0.4 Hz at 30 % of
    its amplitude, no still phase and no ZERO, a drifting F/T bias (drift:
    loadid-sim's per-second rates), 1 m/s^2 of accelerometer bias and 200
    us of time-stamp jitter on both streams. robot: the configuration's
    robot section ("" the RX60)."""
    rec = slow_recording(tmp_path, robot, seed,
                         "simulation:\n  zero: false\n  still_s: 0.3\n"
                         f"  drift: {drift}\n"
                         "  accel_bias: [1.0, 0.0, 0.0]\n  jitter_us: 200\n"
                         "  trajectory_scale: 0.3\n  vibration_angular: 0.0\n"
                         "  noise:\n    angular: 0.0\n", "--values", tmp_path / "values.csv")
    cfg = write_config(tmp_path / "c.yaml", robot + SLOW + "estimation:\n  offset_model: estimate\n"
                       "  methods: [RTLS, RIV, RLS, REFINED]\n")
    result, _ = offline(cfg, rec)
    return rec, result


# lcm.log is parsed here with struct, from LCM's format (sync word, event
# number, time, channel length, data length, channel, data; big-endian),
# independently of the service's reader.

def lcm_events(path):
    """(offset, time, channel, data offset, data length) of every event."""
    import struct
    b = path.read_bytes()
    out, off = [], 0
    while off < len(b):
        sync, _, t, cl, dl = struct.unpack(">IqqII", b[off:off + 28])
        assert sync == 0xEDA1DA01
        out.append((off, t, b[off + 28:off + 28 + cl].decode(), off + 28 + cl, dl))
        off += 28 + cl + dl
    return out
