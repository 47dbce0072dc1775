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
"""

from __future__ import annotations

import csv
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
    return {int(r[0]): (int(r[1]), np.array([float(x) for x in r[2:]])) for r in rows}


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
    plain = float(re.search(r"^kappa_set_plain: (\S+)$", traj_text, re.M).group(1))
    design = float(re.search(r"^kappa_set: (\S+)$", traj_text, re.M).group(1))
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
