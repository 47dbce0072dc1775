"""Helpers of the tests that run the tools on recordings: the programs'
paths (set by ctest), running them, and reading truth.yaml."""

from __future__ import annotations

import os
import re
import subprocess

import pytest


def program(var: str) -> str:
    path = os.environ.get(var)
    if not path or not os.path.isfile(path):
        pytest.fail(f"{var} must name the program (ctest sets it)")
    return path


def run_tool(args, **kw):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, check=True,
                          timeout=300, **kw)


def make_trajectory(d):
    run_tool([program("LOADID_TRAJ_EXE"), "--monte-carlo", "300", "--candidates", "1",
          "--max-evals", "800", "--out", d / "traj.yaml", "--setpoints", d / "setpoints.csv",
          "--quiet"])
    return d


def simulate(out_dir, trajectory, *extra):
    run_tool([program("LOADID_SIM_EXE"), "--trajectory", trajectory / "traj.yaml", "--out", out_dir,
          "--values", out_dir / "values.csv", *extra])
    return out_dir


def read_truth(rec) -> dict:
    """The few keys of truth.yaml the tests need (flat 'key: value' lines
    under their section), without a YAML library."""
    truth, section = {}, None
    for line in (rec / "truth.yaml").read_text().splitlines():
        m = re.match(r"^(\w[\w-]*):\s*(.*)$", line)
        if m:
            section = m.group(1)
            if m.group(2) and not m.group(2).startswith("#"):
                truth[section] = m.group(2)
            continue
        m = re.match(r"^  ([\w-]+):\s*(.*)$", line)
        if m and section:
            truth[f"{section}.{m.group(1)}"] = m.group(2)
    return truth


def damage_count(truth, kind) -> int:
    return int(re.search(r"count: (\d+)", truth[f"damage.{kind}"]).group(1))
