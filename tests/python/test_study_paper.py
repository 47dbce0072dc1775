"""loadid-study --paper end to end, with 2 seeds (tools/study/paper_study.py):
the programs of this build tree design tr1 and tr2, simulate o1, o2 and o3 on
both, estimate with every signal source and method; the files must all be
there, the PNGs real images, and every number of report.json finite and the
one runs.csv gives: the test recomputes the medians and 90th percentiles of
eq. (37) from runs.csv's phi columns and the loads' true phi (o1 the paper's
numbers, written here; o2, o3 checked against Pinocchio in
test_paper_loads.py), and Table I's kappas from its kappa columns. About
25 s on an idle 2-core machine."""

from __future__ import annotations

import csv
import json
import math
import os
import pathlib
import struct
import subprocess
import sys

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tools" / "study"))
import loadid_study  # noqa: E402

SEEDS = 2
O1 = np.array([1.00, -43.5e-3, 28.5e-3, 22.5e-3, 2.21e-3, 1.22e-3, 0.96e-3, 3.74e-3, -0.63e-3,
               4.95e-3])                    # the paper's sec. V.A
PARAMS = ["m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"]
SOURCES = ["sensor", "mixed", "kf", "setpoint"]
METHODS = ["RTLS", "RIV", "RLS", "TLS_BATCH", "REFINED"]
FILES = ["runs.csv", "summary.json", "report.md", "report.json", "table1.txt", "table1.png",
         "fig6_o1_tr2_sensor.png", "fig7_o1_tr2_mixed.png", "fig8_o2_tr2_sensor.png",
         "fig9_o1_tr2_sources.png", "rtls_ratios.png"]


@pytest.fixture(scope="module")
def paper(tmp_path_factory):
    build = pathlib.Path(os.environ["LOADIDD_EXE"]).resolve().parents[1]
    out = tmp_path_factory.mktemp("paper")
    r = subprocess.run([str(REPO / "tools" / "study" / "loadid-study"), "--paper", "--seeds",
                        str(SEEDS), "--jobs", "2", "--build", str(build), "--workdir",
                        str(out / "work"), "--out", str(out)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    return out, r.stdout


def truth(load):
    return O1 if load == "o1" else loadid_study.load_phi(load)


def read_runs(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def eq37(rows, load, traj, sig, method):
    """eq. (37) per parameter over the seeds, (seeds, 10), from phi."""
    sel = [r for r in rows if (r["load"], r["trajectory"], r["signals"], r["method"])
           == (load, traj, sig, method) and r["ok"] == "True"]
    phi = np.array([[float(r[f"phi{i}"]) for i in range(10)] for r in sel])
    return 100 * np.abs((phi - truth(load)) / truth(load))


def png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    return struct.unpack(">II", data[16:24])


def test_every_file_and_run(paper):
    out, stdout = paper
    for f in FILES:
        assert (out / f).is_file() and (out / f).stat().st_size > 0, f
        if f.endswith(".png"):
            w, h = png_size(out / f)
            assert w >= 600 and h >= 200, (f, w, h)
    assert "report: " in stdout and "Table I" in stdout
    rows = read_runs(out / "runs.csv")
    keys = {(r["load"], r["trajectory"], r["signals"], r["method"], int(r["seed"])) for r in rows}
    want = {(l, t, s, m, k) for l in ("o1", "o2", "o3") for t in ("tr1", "tr2")
            for k in range(1, SEEDS + 1)
            for s, m in [(s, m) for s in SOURCES for m in METHODS] + [("", "REF"), ("", "REF_ACC")]}
    assert keys == want and len(rows) == len(want)
    assert all(r["ok"] == "True" for r in rows), [r["error"] for r in rows if r["ok"] != "True"]
    # The Fig. 8 run's traces, every source, with phi_std.
    for s in SOURCES:
        head = (out / "traces" / f"o2-tr2-s1-{s}.csv").read_text().splitlines()[0]
        assert ",phi_std0," in head and ",phi_std9," in head, head


def test_report_numbers_are_runs_csv(paper):
    out, _ = paper
    rows = read_runs(out / "runs.csv")
    rep = json.loads((out / "report.json").read_text())
    md = (out / "report.md").read_text()
    assert rep["seeds"] == SEEDS
    checked = 0
    for key, sig in (("fig6", "sensor"), ("fig7", "mixed")):
        for m in ("RLS", "RIV", "RTLS", "TLS_BATCH", "REFINED", "REF", "REF_ACC"):
            e = eq37(rows, "o1", "tr2", "" if m.startswith("REF") and m != "REFINED" else sig, m)
            assert e.shape == (SEEDS, 10), (key, m, e.shape)
            for i, p in enumerate(PARAMS):
                got = rep[key][m][p]
                assert math.isfinite(got["median"]) and math.isfinite(got["p90"])
                assert math.isclose(got["median"], float(np.median(e[:, i])), rel_tol=1e-9)
                assert math.isclose(got["p90"], float(np.percentile(e[:, i], 90)), rel_tol=1e-9)
                checked += 1
    for s in SOURCES:
        e = eq37(rows, "o1", "tr2", s, "RTLS")
        for i, p in enumerate(PARAMS):
            assert math.isclose(rep["fig9"][s][p]["median"], float(np.median(e[:, i])),
                                rel_tol=1e-9)
            checked += 1
    assert checked == 2 * 7 * 10 + 4 * 10
    h = rep["headline"]
    assert h["rtls_mass_fig6"] == rep["fig6"]["RTLS"]["m"]["median"]
    assert h["rls_ixx_fig7"] == rep["fig7"]["RLS"]["Ixx"]["median"]
    # The headline as report.md prints it (3 significant digits).
    for k in ("rtls_mass_fig6", "rtls_mass_fig7"):
        assert f"| {h[k]:.3g} % |" in md, k
    assert f"{h['rtls_ixx_fig6']:.3g} % / {h['rls_ixx_fig6']:.3g} % / {h['riv_ixx_fig6']:.3g} %" in md
    # No format field left unformatted (one sentence had lost its f prefix).
    assert "{" not in md and "}" not in md, [l for l in md.splitlines() if "{" in l or "}" in l]
    o1 = {t["trajectory"]: t for t in rep["table1"] if t["load"] == "o1"}
    assert f"Here, on o1: kappa_set {o1['tr1']['kappa_set']:.3g} (tr1)" in md
    # Table I: kappa_set the same in every seed (the setpoints), kappa_sens
    # the median of the seeds'.
    for t in rep["table1"]:
        sel = {int(r["seed"]): r for r in rows if (r["trajectory"], r["load"])
               == (t["trajectory"], t["load"])}
        assert len(sel) == SEEDS
        ks = np.array([float(r["kappa_set"]) for r in sel.values()])
        assert np.ptp(ks) == 0 and math.isclose(t["kappa_set"], ks[0], rel_tol=1e-12)
        sens = [float(r["kappa_sens"]) for r in sel.values()]
        assert math.isclose(t["kappa_sens"], float(np.median(sens)), rel_tol=1e-12)
        assert 1 < t["kappa_set"] < 100 and 1 < t["kappa_sens"] < 100
    # RTLS beats RLS, or not, as the medians say: recount one source.
    w = rep["wins"]["sensor"]
    n = beats = 0
    for load in ("o1", "o2", "o3"):
        for traj in ("tr1", "tr2"):
            a = np.median(eq37(rows, load, traj, "sensor", "RTLS"), axis=0)
            b = np.median(eq37(rows, load, traj, "sensor", "RLS"), axis=0)
            n += 10
            beats += int(np.sum(a < b))
    assert (w["cells"], w["beats_rls"]) == (n, beats)
    # Fig. 8's numbers: the last on-line row of the RTLS trace.
    last = [r for r in csv.DictReader(open(out / "traces" / "o2-tr2-s1-sensor.csv"))
            if r["method"] == "RTLS"][-2]
    f8 = rep["fig8"]["methods"]["RTLS"]
    assert f8["phi"] == [float(last[f"phi{i}"]) for i in range(10)]
    assert f8["std"] == [float(last[f"phi_std{i}"]) for i in range(10)]
