"""loadid plot (docs/INTERFACE.md): a recording estimated by loadidd
--offline --trace and drawn; the figures are PNG files of a sane size, and
the residual wrench's RMS it writes and prints are numpy's from the trace
(the on-line rows' res_* columns, and every traced sample's wrench less
eqs. (1)-(2) of the final estimate, written out here); the final
estimate's residual is about what the true load leaves, which only the
noise and the joint signals' errors should."""

from __future__ import annotations

import csv
import json
import re
import shutil
import struct
import subprocess

import numpy as np
import pytest

from recordings import program, read_truth

WRENCH = ["fx", "fy", "fz", "tx", "ty", "tz"]
AXES = ["spec_x", "spec_y", "spec_z"], ["omega_x", "omega_y", "omega_z"], \
    ["alpha_x", "alpha_y", "alpha_z"]


def loadid(*args, check=True):
    r = subprocess.run([program("LOADID_CLI_EXE"), *[str(a) for a in args]], capture_output=True,
                       text=True, timeout=120)
    if check:
        assert r.returncode == 0, f"{r.stdout}\n{r.stderr}"
    return r


def wrench_of(phi, spec, omega, alpha):
    """Eqs. (1)-(2) for one row of motion, vector by vector."""
    m, mc = phi[0], np.asarray(phi[1:4])
    i = phi[4:10]
    inertia = np.array([[i[0], i[1], i[2]], [i[1], i[3], i[4]], [i[2], i[4], i[5]]])
    f = m * spec + np.cross(alpha, mc) + np.cross(omega, np.cross(omega, mc))
    tau = inertia @ alpha + np.cross(omega, inertia @ omega) + np.cross(mc, spec)
    return np.concatenate([f, tau])


def read_rows(path):
    with open(path, newline="") as f:
        return [{k: (v if k == "method" else float(v)) for k, v in r.items()}
                for r in csv.DictReader(f)]


def png_size(path):
    """Width and height from a PNG's IHDR; fails on anything else."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    assert data[12:16] == b"IHDR" and data[-8:-4] == b"IEND", f"{path}: no IHDR/IEND"
    return struct.unpack(">II", data[16:24]), len(data)


@pytest.fixture(scope="module")
def plotted(recording, tmp_path_factory):
    d = tmp_path_factory.mktemp("plot")
    cfg = d / "c.yaml"
    cfg.write_text("estimation:\n  methods: [RTLS, RIV, RLS, REFINED]\n")
    r = loadid("plot", "--config", cfg, recording, "--out", d / "out")
    return d, cfg, r.stdout


def test_plot_of_a_recording_draws_and_its_residual_is_numpy_s(plotted, recording):
    d, cfg, out = plotted
    o = d / "out"
    for name in ("trace-estimates.png", "trace-residual.png"):
        (w, h), size = png_size(o / name)
        assert 800 <= w <= 4000 and 400 <= h <= 3000, (name, w, h)
        assert 20_000 < size < 3_000_000, (name, size)
    # The estimates are loadidd's: the result it wrote beside the trace.
    result = json.loads((o / "result.json").read_text())
    assert [e["method"] for e in result] == ["RTLS", "RIV", "RLS", "REFINED"]
    rows = read_rows(o / "trace.csv")
    by = {}
    for r in rows:
        by.setdefault(r["method"], []).append(r)
    samples = {}
    for r in rows:
        samples.setdefault(r["t_s"], r)
    ss = [samples[t] for t in sorted(samples)]
    truth = read_truth(recording)
    true_phi = np.array(json.loads(truth["load.phi"]))

    def residual_rms(phi, offset):
        left = [np.array([s[k] for k in WRENCH]) - offset - wrench_of(
            phi, np.array([s[k] for k in AXES[0]]) + np.array([s[f"g_init_{a}"] for a in "xyz"]),
            np.array([s[k] for k in AXES[1]]), np.array([s[k] for k in AXES[2]])) for s in ss]
        return np.sqrt(np.mean(np.array(left) ** 2, axis=0))

    truth_rms = residual_rms(true_phi, np.zeros(6))
    written = {(r["method"], r["kind"]): r for r in csv.DictReader(open(o / "trace-residual.csv"))}
    for m, rs in by.items():
        final = rs[-1]
        phi = np.array([final[f"phi{i}"] for i in range(10)])
        np.testing.assert_allclose(phi, next(e["phi"] for e in result if e["method"] == m),
                                   rtol=1e-8)
        want_final = residual_rms(phi, np.array([final[f"offset{i}"] for i in range(6)]))
        got = written[(m, "final")]
        assert int(got["samples"]) == len(ss) == 150
        np.testing.assert_allclose([float(got[f"rms_{k}"]) for k in WRENCH], want_final,
                                   rtol=1e-7, err_msg=m)
        # Fitted to these data, the final estimate explains them about as
        # well as the true load does (at most 5 % worse, axis by axis).
        assert np.all(want_final <= 1.05 * truth_rms), (m, want_final, truth_rms)
        # The printed line says the same, to its 3 digits.
        line = next(l for l in out.splitlines() if l.split()[:1] == [m])
        f = re.search(r"final f \[([^\]]+)\] N, tau \[([^\]]+)\] N m", line)
        printed = [float(x) for x in (f.group(1) + " " + f.group(2)).split()]
        np.testing.assert_allclose(printed, want_final, rtol=5e-3, err_msg=line)
        if m != "REFINED":
            online = [r for r in rs[:-1] if r["valid"] == 1]
            want = np.sqrt(np.mean(np.array([[r[f"res_{k}"] for k in WRENCH] for r in online]) ** 2,
                                   axis=0))
            got = written[(m, "online")]
            assert int(got["samples"]) == len(online) > 100
            np.testing.assert_allclose([float(got[f"rms_{k}"]) for k in WRENCH], want, rtol=1e-7)
    print("final residual RMS (RTLS):", written[("RTLS", "final")], "truth's:", truth_rms)


def test_plot_draws_a_trace_folder_and_refuses_what_it_cannot(plotted, recording, tmp_path):
    d, _, _ = plotted
    # A folder holding a trace: drawn beside it (truth.yaml there gives the truth).
    shutil.copy(d / "out" / "trace.csv", tmp_path / "run7.csv")
    shutil.copy(recording / "truth.yaml", tmp_path / "truth.yaml")
    r = loadid("plot", tmp_path)
    for name in ("run7-estimates.png", "run7-residual.png", "run7-residual.csv"):
        assert f"wrote {tmp_path / name}" in r.stdout and (tmp_path / name).is_file(), name
    assert "the simulated noise: f 0.1 N, tau 0.005 N m" in r.stdout
    # A recording needs the configuration it is to be estimated with.
    r = loadid("plot", recording, check=False)
    assert r.returncode == 2 and "is a recording: give the configuration" in r.stderr, r.stderr
    (tmp_path / "notes.txt").write_text("x\n")
    r = loadid("plot", tmp_path / "notes.txt", check=False)
    assert r.returncode == 1 and "not a trace CSV" in r.stderr, r.stderr
    r = loadid("plot", tmp_path / "missing", check=False)
    assert r.returncode == 1 and "No such file or directory" in r.stderr, r.stderr
    r = loadid("plot", check=False)
    assert r.returncode == 2, r.stderr
    r = loadid("status", "--out", tmp_path, check=False)
    assert r.returncode == 2 and "--out and --publish-every are for plot" in r.stderr
    r = loadid("plot", "--publish-every", "1.5", tmp_path, check=False)
    assert r.returncode == 2 and "--publish-every: a count in 1..1000000, not 1.5" in r.stderr
