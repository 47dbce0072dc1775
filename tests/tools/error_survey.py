#!/usr/bin/env python3
"""error_survey: where the end-to-end tests' accuracy bounds come from.

Runs each scenario of the offline tests (tests/python/test_offline.py: the
same trajectory, simulator options and daemon configuration) over many
simulator seeds through the shipped loadid-sim and loadidd --offline, and
prints per scenario and method the median, 90th percentile and maximum of
the mass error (%), the COM error (mm) and the worst principal moment of
the inertia about the COM (%), computed by tests/python/accuracy.py. The
tests put their bounds at 2 to 3 times the maximum printed here; rerun it
when the method changes, and move the bounds with it.

    error_survey.py [--build build/release] [--seeds 20] [--scenario NAME]...
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "python"))

from accuracy import VCAN_LAG_US, load_errors  # noqa: E402
from recordings import read_truth  # noqa: E402

ALL = "  methods: [RTLS, RIV, RLS, TLS_BATCH, REFINED]\n"
DISTAL = [0.3, 0.0, 0.0, 0.006, 2e-4, 0.0, 0.0, 2e-4, 0.0, 1e-4]
# name: (daemon configuration, simulator configuration or None, extra simulator args)
SCENARIOS = {
    "default": ("estimation:\n  duration_s: 1.5\n" + ALL, None, []),
    "distal": (f"estimation:\n{ALL}distal:\n  phi: {DISTAL}\n", "same", []),
    "offset": ("estimation:\n  offset_model: estimate\n  methods: [RTLS]\n", None, []),
    **{f"signals-{s}": (f"estimation:\n  signals: {s}\n  methods: [RTLS, TLS_BATCH]\n", None, [])
       for s in ("sensor", "kf", "setpoint", "mixed")},
    **{f"damage-{d}": ("estimation:\n  methods: [RTLS, RIV, RLS]\n", None, ["--damage", f"{d}"])
       for d in ("saturate=0.02", "fault=0.02", "skip-samples=0.02", "drop-frames=0.01",
                 "bad-frames=0.02")},
    "vcan": ("estimation:\n  methods: [RTLS, RIV, RLS, REFINED]\nkalman:\n"
             "  max_joint_age_s: 0.02\n", None, []),
    # test_live_modbus.py's whole live session (its own configuration: the
    # serial sensor polled at 500 Hz, signals kf, the sensor lost and found,
    # reads unanswered and bad CRCs), run live per seed in a network namespace.
    "modbus": (None, None, []),
}
# name: how late the daemon gets the JR3 frames [us] (the vcan VM's live
# daemon: accuracy.py VCAN_LAG_US).
DELAY_CAN_US = {"vcan": VCAN_LAG_US}


def delay_can(rec: pathlib.Path, us: int) -> None:
    """Every can.log line's time stamp US microseconds later."""
    log = rec / "can.log"
    out = []
    for line in log.read_text().splitlines(keepends=True):
        m = re.match(r"\((\d+)\.(\d{6})\)", line)
        t = int(m.group(1)) * 1_000_000 + int(m.group(2)) + us
        out.append(f"({t // 1_000_000}.{t % 1_000_000:06d})" + line[m.end():])
    log.write_text("".join(out))


def run(args, **kw):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, check=True,
                          timeout=600, **kw)


def survey(build: pathlib.Path, name: str, seeds: int, work: pathlib.Path) -> dict:
    cfg_text, sim_cfg, extra = SCENARIOS[name]
    cfg = work / f"{name}.yaml"
    cfg.write_text(cfg_text or "")
    out = {}
    for seed in range(1, seeds + 1):
        rec = work / f"{name}-{seed}"
        args = [build / "tools/loadid-sim", "--trajectory", work / "traj.yaml", "--out", rec,
                "--seed", seed, *extra]
        if sim_cfg == "same":
            args += ["--config", cfg]
        run(args)
        if name in DELAY_CAN_US:
            delay_can(rec, DELAY_CAN_US[name])
        truth = truth_phi(rec)
        if name == "modbus":
            for est in modbus_finals(rec, work / f"{name}-{seed}-session"):
                e = load_errors(est["phi"], truth)
                out.setdefault(METHOD_NAMES[est["method"]], []).append(
                    (e["mass_pct"], e["com_mm"], e["moment_pct"]))
            shutil.rmtree(rec)
            continue
        r = subprocess.run([str(build / "host/loadidd"), "--config", str(cfg), "--offline",
                            str(rec)], capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            raise RuntimeError(f"{name} seed {seed}: {r.stderr.strip()}")
        for est in json.loads(r.stdout):
            phi = est["phi"]
            e = load_errors([np.nan if x is None else x for x in phi], truth)
            out.setdefault(est["method"], []).append((e["mass_pct"], e["com_mm"], e["moment_pct"]))
        for f in rec.iterdir():
            f.unlink()
        rec.rmdir()
    return {m: np.array(v) for m, v in out.items()}


METHOD_NAMES = {1: "RLS", 2: "RIV", 3: "RTLS"}  # estimate_t.method


def modbus_finals(rec: pathlib.Path, d: pathlib.Path) -> list:
    """The final (DONE) estimates of test_live_modbus.py's live session on
    the recording rec, its files in the folder d."""
    from test_live_modbus import DONE, run_modbus_session
    d.mkdir()
    s = run_modbus_session(rec, d)
    shutil.rmtree(d)
    if s["returncode"] != 0:
        raise RuntimeError(f"modbus session on {rec}: {s['stderr']}")
    finals = [e for e in s["estimate"] if e["state"] == DONE]
    if sorted(e["method"] for e in finals) != [1, 2, 3]:
        raise RuntimeError(f"modbus session on {rec}: finals {finals}: {s['stderr']}")
    return finals


def program_environment(build: pathlib.Path) -> None:
    """The programs' paths as ctest gives them to the Python tests (the
    live Modbus session reads them)."""
    for var, rel in (("LOADIDD_EXE", "host/loadidd"),
                     ("LOADID_MODBUS_SIM_EXE", "tools/loadid-modbus-sim"),
                     ("LOADID_LCM_PYTHON_DIR", "proto/python"),
                     ("LOADID_CORE_LIB", "firmware/libloadid_core.so")):
        os.environ.setdefault(var, str(build / rel))


def truth_phi(rec):
    return np.array(json.loads(read_truth(rec)["load.phi"]))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=str(ROOT / "build" / "release"))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--scenario", action="append", choices=sorted(SCENARIOS))
    a = ap.parse_args()
    build = pathlib.Path(a.build).resolve()
    program_environment(build)
    names = a.scenario or list(SCENARIOS)
    with tempfile.TemporaryDirectory(prefix="error_survey.") as d:
        work = pathlib.Path(d)
        # The tests' trajectory (tests/python/recordings.py make_trajectory).
        run([build / "tools/loadid-traj", "--monte-carlo", "300", "--candidates", "1",
             "--max-evals", "800", "--out", work / "traj.yaml", "--setpoints",
             work / "setpoints.csv", "--quiet"])
        print(f"error_survey: {a.seeds} seeds per scenario; figures median / p90 / max; "
              f"suggested bound = 2.5 x max")
        print(f"{'scenario':<26} {'method':<10} {'mass %':>22} {'COM mm':>22} "
              f"{'worst moment %':>22}")
        for name in names:
            res = survey(build, name, a.seeds, work)
            for m, v in res.items():
                cells = []
                for k in range(3):
                    x = v[:, k]
                    cells.append(f"{np.median(x):6.3f} {np.percentile(x, 90):6.3f} "
                                 f"{np.max(x):7.3f}")
                print(f"{name:<26} {m:<10} {cells[0]:>22} {cells[1]:>22} {cells[2]:>22}")
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
