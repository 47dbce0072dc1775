"""The committed golden recording (tests/data/golden: a simulated o1 on the
RX60, seed 7) through loadidd --offline gives the committed result,
expected.json, to 1e-9: any change of an estimate, an uncertainty, a
model, a count or a key shows here. When a change is meant to alter the
result, tests/tools/update_golden.sh rewrites expected.json; the commit
says why."""

from __future__ import annotations

import gzip
import json
import math
import pathlib
import shutil
import subprocess

import numpy as np

from accuracy import BOUNDS, assert_accuracy
from recordings import program, read_truth

GOLDEN = pathlib.Path(__file__).resolve().parents[1] / "data" / "golden"
RTOL = 1e-9


def compare(got, want, path="result"):
    """Same structure, keys in the same order, equal strings, ints and
    booleans, and numbers within RTOL (relative to the larger, or 1e-15
    absolute for numbers near zero)."""
    assert type(got) is type(want) or {type(got), type(want)} <= {int, float}, \
        (path, got, want)
    if isinstance(want, dict):
        assert list(got) == list(want), (path, list(got), list(want))
        for k in want:
            compare(got[k], want[k], f"{path}.{k}")
    elif isinstance(want, list):
        assert len(got) == len(want), (path, len(got), len(want))
        for i, (g, w) in enumerate(zip(got, want)):
            compare(g, w, f"{path}[{i}]")
    elif isinstance(want, float) or isinstance(got, float):
        ok = (math.isnan(got) and math.isnan(want)) or \
            abs(got - want) <= RTOL * max(abs(got), abs(want)) + 1e-15
        assert ok, (path, got, want)
    else:
        assert got == want, (path, got, want)


def test_golden_recording_gives_the_committed_result(tmp_path):
    rec = tmp_path / "rec"
    rec.mkdir()
    for name in ("can.log", "lcm.log"):
        with gzip.open(GOLDEN / f"{name}.gz", "rb") as src, open(rec / name, "wb") as dst:
            shutil.copyfileobj(src, dst)
    r = subprocess.run([program("LOADIDD_EXE"), "--config", str(GOLDEN / "loadid.yaml"),
                        "--offline", str(rec)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    got, want = json.loads(r.stdout), json.loads((GOLDEN / "expected.json").read_text())
    assert [g["method"] for g in got] == ["RTLS", "RIV", "RLS", "TLS_BATCH", "REFINED"]
    compare(got, want)
    # And the committed result itself is a good one (so that a wrong
    # update_golden.sh run cannot bless a broken estimate).
    truth = np.array(json.loads(read_truth(GOLDEN)["load.phi"]))
    for e in want:
        assert e["complete"] is True and e["samples"] == 1500
        assert_accuracy(e, truth, **BOUNDS["default"])
