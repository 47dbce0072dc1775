"""The simulator's recordings (tools/sim, loadid-sim) read back through
independent readers, and the condition-number tool (loadid-kappa):

* can.log: every sample's frames decode, through the project's decoder
  (tests/tools/jr3_decode_log) and through `cantools` reading proto/jr3.dbc,
  to the SI values the simulator encoded (its --values file) within one
  count; the base+4 frames carry the configured full scales; can-utils'
  log2asc converts every line (canplayer's syntax).
* lcm.log: read with the `lcm` package's EventLog and decoded with lcm-gen's
  Python types: 1 kHz joint states whose setpoints are loadid-traj's
  setpoints, quantised encoder positions that differ from them by a
  servo's tracking error, and ZERO then START at the times of truth.yaml.
* The same seed gives byte-identical files; another seed does not.
* Damaged recordings: what the decoder counts equals what truth.yaml says
  was done.
* loadid-kappa: the structure of the paper's Table I.
* Real-data-like settings (simulation.*), each against a computation here
  from the recording's bytes: zero: false leaves START alone in lcm.log;
  drift moves the decoded force/torque at rest by drift x elapsed time;
  accel_bias/alpha_bias shift the decoded accelerometer at rest from -g in S
  (Pinocchio) and 0; jitter_us moves only the time stamps (uniform, within
  +-N, streams in order, contents unchanged) and 0 changes no byte;
  trajectory_scale scales s_i(t) of the setpoints and so the peak velocity.
"""

from __future__ import annotations

import csv
import json
import math
import pathlib
import re
import shutil
import subprocess

import numpy as np
import pytest

from recordings import damage_count, program, read_truth, run_tool, simulate

REPO_ROOT = pathlib.Path(__file__).resolve().parents[2]
FULL_SCALE = {0: [200.0] * 3, 1: [12.0] * 3, 2: [98.1] * 3, 3: [1000.0] * 3}
CANDUMP = re.compile(r"^\((\d+)\.(\d{6})\) (\S+) ([0-9A-F]{3})#([0-9A-F]*)$")


def read_values(rec):
    with open(rec / "values.csv") as f:
        rows = list(csv.reader(f))[1:]
    return {int(r[0]): (int(r[1]), np.array([float(x) for x in r[2:14]])) for r in rows}


def decode_project(rec):
    out = run_tool([program("LOADID_JR3_DECODE_LOG"), rec / "can.log"]).stdout
    samples, stats, bad = {}, {}, 0
    for line in out.splitlines():
        f = line.split()
        if f[0] == "S":
            samples[int(f[2])] = (int(f[1]), int(f[3]), np.array([float(x) for x in f[4:]]))
        elif f[0] == "T":
            stats[f[1]] = int(f[2])
        elif f[0] == "B":
            bad += 1
    return samples, stats, bad


def one_count():
    return np.array([FULL_SCALE[g][i] / 16384 for g in range(4) for i in range(3)])


# ------------------------------------------------------------------ can.log
def test_project_decoder_reads_back_every_sample(recording):
    values = read_values(recording)
    samples, stats, bad = decode_project(recording)
    assert bad == 0 and stats["frames_bad"] == 0 and stats["sequence_gaps"] == 0
    assert stats["samples_incomplete"] == 0 and stats["samples_rejected"] == 0
    assert len(samples) == len(values) == stats["samples_ok"]
    tol = one_count()
    worst = 0.0
    for t, (seq, v) in values.items():
        rc, dseq, dv = samples[t]
        assert rc == 1 and dseq == seq
        worst = max(worst, float(np.max(np.abs(dv - v) / tol)))
    assert worst <= 1.0, f"worst error {worst:.3f} counts"
    # base+4 once a second, all four groups.
    assert stats["full_scale_frames"] == 4 * math.ceil(len(values) / 1000 - 0.5)


def test_cantools_with_the_dbc_reads_back_every_frame(recording):
    cantools = pytest.importorskip("cantools")
    db = cantools.database.load_file(str(REPO_ROOT / "proto" / "jr3.dbc"))
    values = read_values(recording)
    names = ["X", "Y", "Z"]
    tol = one_count()
    frames = full_scale = 0
    sample_t = None
    for line in (recording / "can.log").read_text().splitlines():
        m = CANDUMP.match(line)
        assert m, f"not a candump line: {line!r}"
        t = int(m.group(1)) * 1_000_000 + int(m.group(2))
        can_id, data = int(m.group(4), 16), bytes.fromhex(m.group(5))
        msg = db.get_message_by_frame_id(can_id)
        decoded = msg.decode(data, decode_choices=False)
        group = can_id - 0x1A0
        if group == 0:
            sample_t = t
        if group < 4:
            seq, v = values[sample_t]
            sig = [s.name for s in msg.signals]
            xyz = [decoded[next(n for n in sig if n.endswith(a) or n.endswith("_" + a))]
                   for a in names]
            err = np.abs(np.array(xyz) - v[3 * group:3 * group + 3]) / tol[3 * group:3 * group + 3]
            assert np.all(err <= 1.0), (line, xyz, v[3 * group:3 * group + 3])
            frames += 1
        else:
            full = [v for k, v in decoded.items() if k.startswith("FullScale_")]
            g = data[0]
            assert sorted(round(x, 6) for x in full) == sorted(FULL_SCALE[g]), (line, decoded)
            full_scale += 1
    assert frames == 4 * len(values) and full_scale > 0


def test_log2asc_accepts_every_line(recording, tmp_path):
    log2asc = shutil.which("log2asc")
    if log2asc is None:
        pytest.fail("log2asc (Debian can-utils) is missing: tools/setup.sh installs it")
    run_tool([log2asc, "-I", recording / "can.log", "-O", tmp_path / "out.asc", "vcan0"])
    asc = (tmp_path / "out.asc").read_text().splitlines()
    rx = [line for line in asc if " Rx " in line]
    assert len(rx) == len((recording / "can.log").read_text().splitlines())


# ------------------------------------------------------------------ lcm.log
def test_lcm_log_reads_back_with_eventlog(recording, trajectory, lcmtypes):
    lcm = pytest.importorskip("lcm")
    truth = read_truth(recording)
    log = lcm.EventLog(str(recording / "lcm.log"), "r")
    joints, commands = [], []
    for ev in log:
        if ev.channel == "LOADID_JOINTS":
            joints.append((ev.timestamp, lcmtypes.joint_state_t.decode(ev.data)))
        elif ev.channel == "LOADID_COMMAND":
            commands.append((ev.timestamp, lcmtypes.command_t.decode(ev.data)))
        else:
            pytest.fail(f"unexpected channel {ev.channel}")
    assert [c.action for _, c in commands] == [lcmtypes.command_t.ZERO, lcmtypes.command_t.START]
    assert [t for t, _ in commands] == [int(truth["times.zero"]), int(truth["times.start"])]
    assert all(c.load_name == "o1" for _, c in commands)
    assert len(joints) == int(truth["counts.joint_msgs"])
    times = np.array([t for t, _ in joints])
    assert np.all(np.diff(times) == 1000) and all(m.utime == t for t, m in joints)
    assert all(m.num_joints == 6 for _, m in joints)

    # Setpoints: loadid-traj's own samples, shifted by the still phase.
    sp = np.loadtxt(trajectory / "setpoints.csv", delimiter=",", skiprows=1)
    begin, traj0 = int(truth["times.begin"]), int(truth["times.trajectory"])
    step = 2 * math.pi / 2 ** 20
    tracking = 0.0
    for t, m in joints:
        k = (t - traj0) // 1000
        want = sp[k, 1:7] if 0 <= k < len(sp) else sp[0 if k < 0 else -1, 1:7]
        np.testing.assert_allclose(m.setpoint, want, rtol=0, atol=1e-9)
        pos = np.array(m.position)
        np.testing.assert_allclose(pos / step, np.round(pos / step), rtol=0, atol=1e-6)
        tracking = max(tracking, float(np.max(np.abs(pos - np.array(m.setpoint)))))
        assert t >= begin
    # The servo lags: measured positions are not the setpoints, but close.
    assert 1e-4 < tracking < 0.1, tracking


def test_same_seed_same_bytes(recording, trajectory, tmp_path):
    again = simulate(tmp_path / "again", trajectory)
    other = simulate(tmp_path / "other", trajectory, "--seed", "2")
    for name in ["can.log", "lcm.log", "truth.yaml", "values.csv"]:
        assert (again / name).read_bytes() == (recording / name).read_bytes(), name
    assert (other / "can.log").read_bytes() != (recording / "can.log").read_bytes()


# ------------------------------------------------------------------ damage
@pytest.mark.parametrize("kind,stat", [
    ("skip-samples", "sequence_gaps"),
    ("saturate", "samples_saturated"),
    ("fault", "samples_faulty"),
    ("bad-frames", "frames_bad"),
])
def test_damage_is_counted_by_the_decoder(trajectory, tmp_path, kind, stat):
    rec = simulate(tmp_path / kind, trajectory, "--damage", f"{kind}=0.01")
    truth = read_truth(rec)
    done = damage_count(truth, kind)
    assert done > 10
    _, stats, bad = decode_project(rec)
    assert bad == 0
    if kind == "skip-samples":
        # A skipped last sample leaves no later one to reveal the gap.
        assert done - 1 <= stats[stat] <= done
        assert stats["samples_ok"] == int(truth["counts.samples"]) - done
    else:
        assert stats[stat] == done
        others = {"samples_saturated", "samples_faulty", "frames_bad"} - {stat}
        assert all(stats[o] == 0 for o in others)


def test_dropped_frames_leave_incomplete_samples(trajectory, tmp_path):
    rec = simulate(tmp_path / "drop", trajectory, "--damage", "drop-frames=0.01")
    truth = read_truth(rec)
    dropped = damage_count(truth, "drop-frames")
    samples, stats, _ = decode_project(rec)
    values = read_values(rec)
    lost = len(values) - stats["samples_ok"]
    # Each damaged sample lost one to four frames.
    assert math.ceil(dropped / 4) <= lost <= dropped
    assert stats["frames_bad"] == 0
    # What did arrive complete is untouched.
    for t, (rc, _, v) in samples.items():
        assert np.all(np.abs(v - values[t][1]) <= one_count())


def test_bit_errors_never_stop_the_decoder(trajectory, tmp_path):
    rec = simulate(tmp_path / "bits", trajectory, "--damage", "bit-errors=0.02")
    truth = read_truth(rec)
    assert damage_count(truth, "bit-errors") > 100
    _, stats, bad = decode_project(rec)
    assert bad == 0
    assert stats["frames_total"] == len((rec / "can.log").read_text().splitlines())
    assert stats["samples_ok"] < int(truth["counts.samples"])
    assert stats["frames_bad"] > 0  # flipped reserved status bits are caught


def test_joint_stream_damage(trajectory, tmp_path, lcmtypes):
    lcm = pytest.importorskip("lcm")
    rec = simulate(tmp_path / "joints", trajectory, "--damage", "nan-joints=0.01",
                   "--damage", "stall-joints=1.2:1.5")
    truth = read_truth(rec)
    nans = damage_count(truth, "nan-joints")
    stalled = damage_count(truth, "stall-joints")
    assert stalled == 300
    begin = int(truth["times.begin"])
    seen_nan, times = 0, []
    for ev in lcm.EventLog(str(rec / "lcm.log"), "r"):
        if ev.channel == "LOADID_JOINTS":
            m = lcmtypes.joint_state_t.decode(ev.data)
            seen_nan += any(math.isnan(x) for x in m.position)
            times.append(m.utime - begin)
    assert seen_nan == nans > 0
    assert not any(1_200_000 <= t < 1_500_000 for t in times)
    assert len(times) == int(truth["counts.samples"]) - stalled


# ------------------------------------------------------------------ kappa
def test_kappa_table_structure(recording, trajectory, tmp_path):
    noisy_cfg = tmp_path / "noisy.yaml"
    noisy_cfg.write_text("noise:\n  linear: 3.0\n  angular: 40.0\n"
                         "simulation:\n  vibration_linear: 2.0\n  vibration_angular: 20.0\n")
    noisy = tmp_path / "noisy"
    run_tool([program("LOADID_SIM_EXE"), "--config", noisy_cfg, "--trajectory",
          trajectory / "traj.yaml", "--out", noisy])
    out = run_tool([program("LOADID_KAPPA_EXE"), recording, noisy]).stdout.splitlines()
    weighted = run_tool([program("LOADID_KAPPA_EXE"), "--weighted", recording]).stdout.splitlines()
    assert out[0].split() == ["recording", "load", "samples", "kappa_set", "kappa_sens",
                              "kappa_kf"]
    rows = [line.split() for line in out[1:]]
    assert [r[1] for r in rows] == ["o1", "o1"] and all(r[2] == "1500" for r in rows)
    clean, loud = ([float(x) for x in r[3:]] for r in rows)
    # The same commanded trajectory: the same kappa_set, close to the
    # designer's (exact setpoint derivatives there, filtered ones here),
    # without weights and with the estimator's.
    assert clean[0] == loud[0]
    traj_text = (trajectory / "traj.yaml").read_text()
    plain = float(re.search(r"^kappa_set: (\S+)$", traj_text, re.M).group(1))
    design = float(re.search(r"^kappa_design: (\S+)$", traj_text, re.M).group(1))
    assert abs(clean[0] - plain) <= 0.03 * plain
    assert abs(float(weighted[1].split()[3]) - design) <= 0.03 * design
    # Noisy accelerometers (Table I): kappa_sens clearly above kappa_set,
    # and above the quieter recording's.
    assert loud[1] >= 1.15 * loud[0], (clean, loud)
    assert loud[1] > clean[1]


def test_kappa_refuses_a_missing_recording(tmp_path):
    r = subprocess.run([program("LOADID_KAPPA_EXE"), tmp_path / "nothing"], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode != 0 and "cannot read" in r.stderr


# ------------------------------------------------------------------ real-data-like settings
# simulation.zero, drift, accel_bias, alpha_bias, jitter_us, trajectory_scale:
# each checked against what the recording's own bytes say, computed here.
G_BASE = np.array([0.0, 0.0, -9.81])
RX60 = REPO_ROOT / "host" / "config" / "robots" / "rx60.urdf"


def simulate_with(path, trajectory, config_text, *extra):
    """A recording made with a configuration file holding config_text."""
    path.mkdir(parents=True, exist_ok=True)
    cfg = path / "config.yaml"
    cfg.write_text(config_text)
    return simulate(path / "rec", trajectory, "--config", cfg, *extra)


def read_lcm(rec, lcmtypes):
    """Every event of lcm.log in file order: (timestamp, channel, message)."""
    lcm = pytest.importorskip("lcm")
    events = []
    for ev in lcm.EventLog(str(rec / "lcm.log"), "r"):
        if ev.channel == "LOADID_JOINTS":
            events.append((ev.timestamp, ev.channel, lcmtypes.joint_state_t.decode(ev.data)))
        elif ev.channel == "LOADID_COMMAND":
            events.append((ev.timestamp, ev.channel, lcmtypes.command_t.decode(ev.data)))
        else:
            pytest.fail(f"unexpected channel {ev.channel}")
    return events


def can_frame_times(rec):
    times = []
    for line in (rec / "can.log").read_text().splitlines():
        m = CANDUMP.match(line)
        assert m, line
        times.append(int(m.group(1)) * 1_000_000 + int(m.group(2)))
    return np.array(times)


def traj_value(trajectory, key):
    text = (trajectory / "traj.yaml").read_text()
    return re.search(rf"^{key}: (.+)$", text, re.M).group(1)


def window_means(rec, truth, seconds=0.2):
    """Mean decoded JR3 values (12 channels) and mean time [s after the
    start] over the recording's first and last `seconds` (both at rest at q_0)."""
    samples, _, _ = decode_project(rec)
    t = np.array(sorted(samples))
    v = np.array([samples[k][2] for k in t])
    begin, end = int(truth["times.begin"]), int(truth["times.end"])
    first = t < begin + seconds * 1e6
    last = t >= end - seconds * 1e6
    assert first.sum() >= 190 and last.sum() >= 190
    t = (t - begin) * 1e-6
    return (v[first].mean(axis=0), t[first].mean()), (v[last].mean(axis=0), t[last].mean())


def rx60_sensor(q, qd=None):
    """Pinocchio from the URDF at the RX60's joint positions q (joint_1..6)
    and velocities qd: g in the sensor frame S, and S's angular velocity in S."""
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(str(RX60))
    data = model.createData()
    Q, V = pin.neutral(model), np.zeros(model.nv)
    for i, name in enumerate(f"joint_{k}" for k in range(1, 7)):
        joint = model.joints[model.getJointId(name)]
        assert joint.nq == 1
        Q[joint.idx_q] = q[i]
        V[joint.idx_v] = 0.0 if qd is None else qd[i]
    pin.forwardKinematics(model, data, Q, V)
    pin.updateFramePlacements(model, data)
    s_id = model.getFrameId("ft_sensor")
    R_ob = data.oMf[model.getFrameId("base_link")].rotation
    R_os = data.oMf[s_id].rotation
    omega = np.asarray(pin.getFrameVelocity(model, data, s_id, pin.LOCAL).angular)
    return (R_ob.T @ R_os).T @ G_BASE, omega


def test_zero_false_no_still_phase(trajectory, tmp_path, lcmtypes):
    rec = simulate_with(tmp_path, trajectory, "simulation:\n  zero: false\n  still_s: 0\n")
    truth = read_truth(rec)
    assert truth["simulation.zero"] == "false" and float(truth["simulation.still_s"]) == 0
    assert int(truth["times.zero"]) == -1
    begin = int(truth["times.begin"])
    assert int(truth["times.trajectory"]) == begin
    events = read_lcm(rec, lcmtypes)
    commands = [(t, m) for t, ch, m in events if ch == "LOADID_COMMAND"]
    # No ZERO: START alone, when the active part begins (fade_s after the
    # trajectory's start, which is the recording's start).
    assert [m.action for _, m in commands] == [lcmtypes.command_t.START]
    fade_us = round(float(traj_value(trajectory, "fade_s")) * 1e6)
    assert commands[0][0] == int(truth["times.start"]) == begin + fade_us
    assert int(truth["counts.commands"]) == 1
    # The trajectory starts at once: setpoints are loadid-traj's from the first one on.
    sp = np.loadtxt(trajectory / "setpoints.csv", delimiter=",", skiprows=1)
    joints = [(t, m) for t, ch, m in events if ch == "LOADID_JOINTS"]
    for t, m in joints[:len(sp)]:
        np.testing.assert_allclose(m.setpoint, sp[(t - begin) // 1000, 1:7], rtol=0, atol=1e-9)
    samples, stats, _ = decode_project(rec)
    assert len(samples) == stats["samples_ok"] == len(joints) == int(truth["counts.samples"])


def test_drift_moves_the_offset_linearly(trajectory, tmp_path):
    drift = np.array([0.05, -0.04, 0.03, 0.004, -0.003, 0.002])  # N/s, N m/s
    quiet = "simulation:\n  noise:\n    force: 0\n    torque: 0\n"
    rec = simulate_with(tmp_path / "drift", trajectory,
                        quiet + f"  drift: [{', '.join(map(str, drift))}]\n")
    still = simulate_with(tmp_path / "still", trajectory, quiet)
    truth = read_truth(rec)
    np.testing.assert_array_equal(json.loads(truth["simulation.drift"]), drift)
    (v0, t0), (v1, t1) = window_means(rec, truth)
    elapsed = t1 - t0
    assert elapsed > 2.5, elapsed
    change = (v1 - v0)[:6]
    tol = one_count()[:6]
    # Without drift the load reads the same at the start and in the tail.
    (s0, _), (s1, _) = window_means(still, read_truth(still))
    assert np.all(np.abs((s1 - s0)[:6]) <= tol), (s1 - s0)[:6] / tol
    err = (change - drift * elapsed) / tol
    print(f"drift: elapsed {elapsed:.4f} s, change {change}, expected {drift * elapsed}, "
          f"error {err} counts")
    assert np.all(np.abs(err) <= 1.0), err
    assert np.all(np.abs(drift * elapsed) >= 5 * tol)  # well above the tolerance


def test_accelerometer_biases(trajectory, tmp_path, lcmtypes):
    accel_bias, alpha_bias = np.array([0.3, -0.2, 0.15]), np.array([0.5, -0.4, 0.3])
    rec = simulate_with(
        tmp_path, trajectory,
        "simulation:\n  vibration_linear: 0\n  vibration_angular: 0\n"
        "  noise:\n    linear: 0\n    angular: 0\n"
        f"  accel_bias: [{', '.join(map(str, accel_bias))}]\n"
        f"  alpha_bias: [{', '.join(map(str, alpha_bias))}]\n")
    truth = read_truth(rec)
    np.testing.assert_array_equal(json.loads(truth["simulation.accel_bias"]), accel_bias)
    np.testing.assert_array_equal(json.loads(truth["simulation.alpha_bias"]), alpha_bias)
    (v0, _), (v1, _) = window_means(rec, truth)
    # At rest a = 0, so the accelerometer's a - g is -g in S, at the
    # encoders' positions of the first joint state.
    first = next(m for _, ch, m in read_lcm(rec, lcmtypes) if ch == "LOADID_JOINTS")
    spec = -rx60_sensor(np.array(first.position))[0]
    tol = one_count()
    for v in (v0, v1):
        lin_err = (v[6:9] - (spec + accel_bias)) / tol[6:9]
        ang_err = (v[9:12] - alpha_bias) / tol[9:12]
        print(f"accel bias: linear {v[6:9]} vs {spec + accel_bias} ({lin_err} counts), "
              f"angular {v[9:12]} ({ang_err} counts)")
        assert np.all(np.abs(lin_err) <= 1.0) and np.all(np.abs(ang_err) <= 1.0)
    # The biases are well above the tolerance: without them the test would fail.
    assert np.all(np.abs(accel_bias) >= 20 * tol[6:9]) and np.all(np.abs(alpha_bias) >= 4 * tol[9:12])


def test_jitter_moves_only_the_stamps(recording, trajectory, tmp_path, lcmtypes):
    n = 200
    rec = simulate_with(tmp_path, trajectory, f"simulation:\n  jitter_us: {n}\n")
    truth, clean = read_truth(rec), read_truth(recording)
    assert int(truth["simulation.jitter_us"]) == n
    begin = int(truth["times.begin"])
    # lcm.log: in time order; joint states strictly increasing, each within
    # +-n of its 1 kHz tick; commands at their nominal times.
    events = read_lcm(rec, lcmtypes)
    stamps = np.array([t for t, _, _ in events])
    assert np.all(np.diff(stamps) >= 0)
    joints = [(t, m) for t, ch, m in events if ch == "LOADID_JOINTS"]
    commands = [(t, m.action) for t, ch, m in events if ch == "LOADID_COMMAND"]
    assert commands == [(int(clean["times.zero"]), lcmtypes.command_t.ZERO),
                        (int(clean["times.start"]), lcmtypes.command_t.START)]
    tj = np.array([t for t, _ in joints])
    assert all(m.utime == t for t, m in joints)
    dev_j = tj - (begin + 1000 * np.arange(len(tj)))
    d = np.diff(tj)
    assert np.all(d > 0)
    assert np.all(np.abs(dev_j) <= n) and np.all(np.abs(d - 1000) <= 2 * n)
    # Uniform on [-n, n]: spread over the whole range, std (2n+1)/sqrt(12).
    std = math.sqrt(((2 * n + 1) ** 2 - 1) / 12)
    assert dev_j.max() >= 0.95 * n and dev_j.min() <= -0.95 * n
    assert (d - 1000).max() >= 1.5 * n and (d - 1000).min() <= -1.5 * n
    assert abs(dev_j.mean()) <= 10 and abs(dev_j.std() / std - 1) <= 0.08, (dev_j.mean(), dev_j.std())
    # The joint messages' contents are those of the recording without jitter.
    clean_joints = [m for _, ch, m in read_lcm(recording, lcmtypes) if ch == "LOADID_JOINTS"]
    assert len(clean_joints) == len(joints)
    for (_, m), c in zip(joints, clean_joints):
        assert list(m.position) == list(c.position) and list(m.setpoint) == list(c.setpoint)
    # can.log: frames strictly increasing in time; each sample within +-n
    # of its nominal time (370 us after its tick), decoded to the values the
    # clean recording's sample of the same tick carries.
    assert np.all(np.diff(can_frame_times(rec)) > 0)
    samples, stats, bad = decode_project(rec)
    assert bad == 0 and stats["sequence_gaps"] == 0 and stats["samples_incomplete"] == 0
    clean_samples, _, _ = decode_project(recording)
    tc, tc_clean = sorted(samples), sorted(clean_samples)
    assert len(tc) == len(tc_clean)
    dev_c = np.array(tc) - np.array(tc_clean)
    assert np.all(np.abs(dev_c) <= n)
    assert dev_c.max() >= 0.95 * n and dev_c.min() <= -0.95 * n
    assert abs(dev_c.std() / std - 1) <= 0.08
    dc = np.diff(tc)
    assert np.all(dc > 0) and np.all(np.abs(dc - 1000) <= 2 * n)
    for a, b in zip(tc, tc_clean):
        assert samples[a][1] == clean_samples[b][1]
        np.testing.assert_array_equal(samples[a][2], clean_samples[b][2])
    # Independent streams: joint and CAN jitter uncorrelated.
    r = np.corrcoef(dev_j, dev_c)[0, 1]
    assert abs(r) < 0.1, r
    # The physics at the nominal times: values.csv differs in t_us only.
    rows = (rec / "values.csv").read_text().splitlines()
    clean_rows = (recording / "values.csv").read_text().splitlines()
    assert [r.split(",", 1)[1] for r in rows] == [r.split(",", 1)[1] for r in clean_rows]
    clipped = int(truth["simulation.jitter_clipped"])
    print(f"jitter {n} us: joint dev mean {dev_j.mean():.2f} std {dev_j.std():.1f} "
          f"(uniform {std:.1f}), CAN dev std {dev_c.std():.1f}, corr {r:.3f}, "
          f"clipped {clipped}, joint diffs {d.min()}..{d.max()} us")
    # The recording reader (drivers/recording.h) takes it: loadid-kappa runs.
    out = run_tool([program("LOADID_KAPPA_EXE"), rec]).stdout.splitlines()
    assert out[1].split()[1:3] == ["o1", "1500"], out


def test_jitter_zero_is_byte_identical(recording, trajectory, tmp_path):
    rec = simulate_with(tmp_path, trajectory, "simulation:\n  jitter_us: 0\n")
    for name in ["can.log", "lcm.log", "truth.yaml", "values.csv"]:
        assert (rec / name).read_bytes() == (recording / name).read_bytes(), name


def test_trajectory_scale_scales_the_motion(recording, trajectory, tmp_path, lcmtypes):
    s = 0.05
    rec = simulate_with(tmp_path, trajectory, f"simulation:\n  trajectory_scale: {s}\n")
    truth = read_truth(rec)
    assert float(truth["simulation.trajectory_scale"]) == s

    def setpoints(r):
        return np.array([m.setpoint for _, ch, m in read_lcm(r, lcmtypes)
                         if ch == "LOADID_JOINTS"])

    full, slow = setpoints(recording), setpoints(rec)
    q0 = np.array(json.loads(traj_value(trajectory, "q0")))
    assert full.shape == slow.shape
    # s_i(t) = q(t) - q_0, scaled by s at every instant.
    np.testing.assert_allclose(slow - q0, s * (full - q0), rtol=0, atol=1e-12)
    v_full = np.abs(np.diff(full, axis=0)).max(axis=0) / 1e-3
    v_slow = np.abs(np.diff(slow, axis=0)).max(axis=0) / 1e-3
    np.testing.assert_allclose(v_slow / v_full, s, rtol=1e-6)
    a_slow = np.abs(np.diff(slow, 2, axis=0)).max() / 1e-6
    print(f"trajectory_scale {s}: peak joint velocity {v_full.max():.3f} -> {v_slow.max():.4f} "
          f"rad/s, peak joint acceleration {a_slow:.3f} rad/s^2")
    # The real-data-like target for the sensor: |omega| <= 0.4 rad/s (from
    # the setpoints by Pinocchio) and |alpha| <= 2 rad/s^2, read off the JR3
    # angular channel (noise and vibration off).
    qd = np.gradient(slow, 1e-3, axis=0)
    peak_omega = max(float(np.linalg.norm(rx60_sensor(q, v)[1]))
                     for q, v in zip(slow[::10], qd[::10]))
    print(f"trajectory_scale {s}: peak |omega| of S {peak_omega:.3f} rad/s")
    assert peak_omega <= 0.4
    quiet = simulate_with(tmp_path / "quiet", trajectory,
                          f"simulation:\n  trajectory_scale: {s}\n  vibration_angular: 0\n"
                          "  noise:\n    angular: 0\n")
    samples, _, _ = decode_project(quiet)
    alpha = np.array([v[2][9:12] for v in samples.values()])
    peak_alpha = float(np.linalg.norm(alpha, axis=1).max())
    print(f"trajectory_scale {s}: peak |alpha| of S {peak_alpha:.3f} rad/s^2")
    assert peak_alpha <= 2.0
